"""Call the compiled kernels of a built variant from Python (ctypes), on numpy arrays."""
from __future__ import annotations

import ctypes
from pathlib import Path

import numpy as np

from flexsym.core.errors import SpecError
from flexsym.toolchain.build import Built
from flexsym.codegen.generate import c_prefix, read_manifest

_dptr = ctypes.POINTER(ctypes.c_double)


def _ptr(a: np.ndarray):
    return a.ctypes.data_as(_dptr)


class CompiledModel:
    """A built variant's library: the one-beam model interface (fsm_<name>_mass, fsm_<name>_force,
    ..., its generated header) for every kind of model, and any generated kernel by name
    (manifest.json)."""

    def __init__(self, built: Built, gen_dir: Path):
        self.built = built
        self.manifest = read_manifest(gen_dir)
        self.lib = ctypes.CDLL(str(built.library))
        self.kernels = self.manifest["kernels"]
        self.prefix = c_prefix(self.manifest["spec"]["name"])
        self.nq = len(self.manifest["coordinates"])
        self.ny = len(self.manifest["outputs"])
        self.param_defaults = np.array([p["default"] for p in self.manifest["params"]])
        self.maneuver_defaults = np.array([p["default"] for p in self.manifest["maneuver"]["params"]])

    def _invoke(self, c_name: str, inputs, out_shapes, sizes=None) -> list[np.ndarray]:
        """inputs: (name, value) pairs; each is checked against its size (sizes, or the model
        interface's by name) before C reads it."""
        if sizes is None:
            known = {"q": self.nq, "qd": self.nq, "qdd": self.nq, "[w, alpha]": 2,
                     "p": len(self.param_defaults), "t": 1, "mp": len(self.maneuver_defaults)}
            sizes = [known[name] for name, _ in inputs]
        keep = [_array(name, x, n, c_name) for (name, x), n in zip(inputs, sizes)]
        outs = [np.zeros(shape) for shape in out_shapes]
        fn = getattr(self.lib, c_name)
        fn.restype = None
        fn(*[_ptr(a) for a in keep], *[_ptr(o) for o in outs])
        return [o if o.shape[1] > 1 else o[:, 0] for o in outs]

    def call(self, kernel: str, *inputs) -> list[np.ndarray]:
        """A generated kernel by name, with the input sizes checked against the manifest."""
        info = self.kernels[kernel]
        if len(inputs) != len(info["inputs"]):
            raise SpecError(f"{kernel}: {len(inputs)} inputs given, expected {len(info['inputs'])} "
                            f"({', '.join(info['inputs'])})")
        return self._invoke(info["c_name"], list(zip(info["inputs"], inputs)),
                            [tuple(s) for s in info["outputs"].values()], list(info["inputs"].values()))

    def mass(self, q, p=None):
        return self._invoke(self.prefix + "mass", [("q", q), ("p", self._p(p))], [(self.nq, self.nq)])[0]

    def force(self, q, qd, w, alpha=0.0, p=None):
        return self._invoke(self.prefix + "force", [("q", q), ("qd", qd), ("[w, alpha]", _wa(w, alpha)), ("p", self._p(p))],
                            [(self.nq, 1)])[0]

    def residual_jac(self, q, qd, qdd, w, alpha=0.0, p=None):
        n = self.nq
        return self._invoke(self.prefix + "residual_jac", [("q", q), ("qd", qd), ("qdd", qdd), ("[w, alpha]", _wa(w, alpha)),
                                                 ("p", self._p(p))], [(n, n), (n, n)])

    def outputs(self, q, qd=None, qdd=None, w=0.0, alpha=0.0, p=None) -> dict:
        z = np.zeros(self.nq)
        y = self._invoke(self.prefix + "outputs", [("q", q), ("qd", z if qd is None else qd), ("qdd", z if qdd is None else qdd),
                                         ("[w, alpha]", _wa(w, alpha)), ("p", self._p(p))], [(self.ny, 1)])[0]
        return dict(zip(self.manifest["outputs"], np.atleast_1d(y)))

    def energy(self, q, qd, w, alpha=0.0, p=None):
        return self._invoke(self.prefix + "energy", [("q", q), ("qd", qd), ("[w, alpha]", _wa(w, alpha)), ("p", self._p(p))],
                            [(3, 1)])[0]

    def maneuver(self, t, mp=None):
        return self._invoke(self.prefix + "maneuver", [("t", t), ("mp", self.maneuver_defaults if mp is None else mp)],
                            [(3, 1)])[0]

    def _p(self, p):
        return self.param_defaults if p is None else p


def _wa(w, alpha) -> np.ndarray:
    """The drive [w, alpha]: two real numbers (each checked alone: [True, 0.0] would otherwise
    become [1.0, 0.0])."""
    return np.concatenate([_array(name, v, 1, "drive") for name, v in (("w", w), ("alpha", alpha))])


def _array(name: str, x, size: int, fn: str) -> np.ndarray:
    """x as the contiguous double array C reads: exactly size real, finite values (C reads
    size values whatever it is given: a short array would be read past its end)."""
    try:
        a = np.asarray(x)
    except ValueError as exc:  # ragged lists
        raise SpecError(f"{fn}: {name} is not an array of numbers ({exc})") from None
    if a.dtype.kind not in "iuf":
        raise SpecError(f"{fn}: {name} must hold real numbers (got dtype {a.dtype}: "
                        f"{'bool' if a.dtype.kind == 'b' else 'complex' if a.dtype.kind == 'c' else 'not numbers'})")
    a = np.ascontiguousarray(np.atleast_1d(a), dtype=float).ravel()
    if a.size != size:
        raise SpecError(f"{fn}: {name} has {a.size} values, expected {size}")
    if not np.all(np.isfinite(a)):
        raise SpecError(f"{fn}: {name} has a value that is not finite ({a[~np.isfinite(a)][0]})")
    return a
