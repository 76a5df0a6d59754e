"""Call the compiled kernels of a built variant from Python (ctypes), on numpy arrays."""
from __future__ import annotations

import ctypes
from pathlib import Path

import numpy as np

from flexsym.core.errors import SpecError
from flexsym.toolchain.build import Built
from flexsym.codegen.generate import read_manifest

_dptr = ctypes.POINTER(ctypes.c_double)


def _ptr(a: np.ndarray):
    return a.ctypes.data_as(_dptr)


class CompiledModel:
    """A built variant's library: the model interface of flexsym/model.h (fsm_mass, fsm_force,
    ...) for every kind of model, and any generated kernel by name (manifest.json)."""

    def __init__(self, built: Built, gen_dir: Path):
        self.built = built
        self.manifest = read_manifest(gen_dir)
        self.lib = ctypes.CDLL(str(built.library))
        self.kernels = self.manifest["kernels"]
        self.nq = len(self.manifest["coordinates"])
        self.ny = len(self.manifest["outputs"])
        self.param_defaults = np.array([p["default"] for p in self.manifest["params"]])
        self.maneuver_defaults = np.array([p["default"] for p in self.manifest["maneuver"]["params"]])

    def _invoke(self, c_name: str, inputs, out_shapes, sizes) -> list[np.ndarray]:
        """inputs: (name, value) pairs, each checked against its size before C reads it."""
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

    def _state(self, c_name, out_shapes, **given):
        """Calls a model-interface function; given: q, qd, qdd (nq values each), w and alpha
        (one each), p (the parameters), in the C function's order."""
        sizes = {"q": self.nq, "qd": self.nq, "qdd": self.nq, "wa": 2, "p": len(self.param_defaults)}
        if "w" in given:
            _array("w", given.pop("w"), 1, c_name), _array("alpha", given.pop("alpha"), 1, c_name)
        inputs = [(k, v) for k, v in given.items()]
        return self._invoke(c_name, inputs, out_shapes, [sizes[k] for k, _ in inputs])

    def mass(self, q, p=None):
        return self._state("fsm_mass", [(self.nq, self.nq)], q=q, p=self._p(p))[0]

    def force(self, q, qd, w, alpha=0.0, p=None):
        return self._state("fsm_force", [(self.nq, 1)], q=q, qd=qd, w=w, alpha=alpha, wa=[w, alpha],
                           p=self._p(p))[0]

    def residual_jac(self, q, qd, qdd, w, alpha=0.0, p=None):
        n = self.nq
        return self._state("fsm_residual_jac", [(n, n), (n, n)], q=q, qd=qd, qdd=qdd, w=w, alpha=alpha,
                           wa=[w, alpha], p=self._p(p))

    def outputs(self, q, qd=None, qdd=None, w=0.0, alpha=0.0, p=None) -> dict:
        z = np.zeros(self.nq)
        y = self._state("fsm_outputs", [(self.ny, 1)], q=q, qd=z if qd is None else qd,
                        qdd=z if qdd is None else qdd, w=w, alpha=alpha, wa=[w, alpha], p=self._p(p))[0]
        return dict(zip(self.manifest["outputs"], np.atleast_1d(y)))

    def energy(self, q, qd, w, alpha=0.0, p=None):
        return self._state("fsm_energy", [(3, 1)], q=q, qd=qd, w=w, alpha=alpha, wa=[w, alpha],
                           p=self._p(p))[0]

    def maneuver(self, t, mp=None):
        mp = self.maneuver_defaults if mp is None else mp
        return self._invoke("fsm_maneuver", [("t", t), ("mp", mp)], [(3, 1)],
                            [1, len(self.maneuver_defaults)])[0]

    def _p(self, p):
        return self.param_defaults if p is None else p


def _array(name: str, x, size: int, fn: str) -> np.ndarray:
    """x as the contiguous double array C reads: exactly size real, finite values (C reads
    size values whatever it is given: a short array would be read past its end)."""
    try:
        a = np.asarray(x)
    except Exception as exc:  # ragged lists and the like
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
