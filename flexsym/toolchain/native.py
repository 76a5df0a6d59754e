"""Call the compiled kernels of a built variant from Python (ctypes), on numpy arrays."""
from __future__ import annotations

import ctypes
from pathlib import Path

import numpy as np

from flexsym.core.errors import SpecError
from flexsym.toolchain.build import Built
from flexsym.codegen.folder import c_prefix, read_manifest

_dptr = ctypes.POINTER(ctypes.c_double)


def _ptr(a: np.ndarray):
    return a.ctypes.data_as(_dptr)


class SystemStruct(ctypes.Structure):
    """runtime_c/include/flexsym/system.h's fsm_system, field by field (the one mirror of it
    in Python: keep in step); pointers as void*."""
    _fields_ = ([(k, ctypes.c_char_p) for k in ("name", "fingerprint", "generator")]
                + [(k, ctypes.c_int) for k in ("nq", "nd", "nc", "ny", "np", "nmp")]
                + [("length_scale", ctypes.c_double)]
                + [(k, ctypes.c_int) for k in ("length_param", "mass_constant", "bandwidth",
                                               "outputs_use_acceleration", "outputs_use_drive")]
                + [(k, ctypes.c_void_p) for k in (
                    "coord_names", "constraint_names", "output_names", "param_names",
                    "param_defaults", "drive_param_names", "drive_param_defaults",
                    "drive", "mass", "force", "residual_jac", "constraints", "constraint_jac",
                    "constraint_rate", "constraint_acc", "outputs", "energy", "initial_state",
                    "constraint_hess", "coord_unbounded", "residual")]
                + [("band_first", ctypes.c_int), ("band_end", ctypes.c_int),
                   ("coord_held", ctypes.c_void_p)])


class CompiledModel:
    """A built variant's model (the struct of system.h its accessor returns: its S0's, with
    the ef elements assembled), called in the one-beam variables: the hub's rate and
    acceleration w, alpha as the drive d = [t, theta, w, alpha] (a guided root without
    gravity: t and theta enter no equation); and any generated kernel by name (manifest.json)."""

    def __init__(self, built: Built, gen_dir: Path):
        self.built = built
        self.manifest = read_manifest(gen_dir)
        self.lib = ctypes.CDLL(str(built.library))
        self.kernels = self.manifest["kernels"]
        self.prefix = c_prefix(self.manifest["spec"]["name"])
        accessor = getattr(self.lib, self.manifest["model"])
        accessor.restype = ctypes.POINTER(SystemStruct)
        self.model = accessor().contents
        self.nq, self.ny = self.model.nq, self.model.ny
        self.param_defaults = np.array([p["default"] for p in self.manifest["params"]])
        self.maneuver_defaults = np.array([p["default"] for p in self.manifest["drive_params"]])

    def _run(self, fn: str, inputs, out_shapes) -> list[np.ndarray]:
        """The model's function fn (a field of its struct) on inputs: (name, value, size)."""
        c_fn = ctypes.CFUNCTYPE(None, *[_dptr] * (len(inputs) + len(out_shapes)))(getattr(self.model, fn))
        return _invoke(c_fn, self.prefix + fn, inputs, out_shapes)

    def call(self, kernel: str, *inputs) -> list[np.ndarray]:
        """A generated kernel by name, with the input sizes checked against the manifest."""
        info = self.kernels[kernel]
        if len(inputs) != len(info["inputs"]):
            raise SpecError(f"{kernel}: {len(inputs)} inputs given, expected {len(info['inputs'])} "
                            f"({', '.join(info['inputs'])})")
        fn = getattr(self.lib, info["c_name"])
        fn.restype = None
        return _invoke(fn, info["c_name"], [(name, x, n) for (name, n), x in
                                                      zip(info["inputs"].items(), inputs)],
                       [tuple(s) for s in info["outputs"].values()])

    def _state(self, **given) -> list:
        sizes = {"q": self.nq, "qd": self.nq, "qdd": self.nq}
        return [(name, x, sizes[name]) for name, x in given.items()]

    def _d(self, w=0.0, alpha=0.0) -> tuple:
        return "d", np.concatenate([[0.0, 0.0], _wa(w, alpha)]), self.model.nd

    def _p(self, p) -> tuple:
        return "p", self.param_defaults if p is None else p, self.model.np

    def mass(self, q, p=None):
        return self._run("mass", [*self._state(q=q), self._d(), self._p(p)], [(self.nq, self.nq)])[0]

    def force(self, q, qd, w, alpha=0.0, p=None):
        return self._run("force", [*self._state(q=q, qd=qd), self._d(w, alpha), self._p(p)], [(self.nq,)])[0]

    def residual_jac(self, q, qd, qdd, w, alpha=0.0, p=None):
        n = self.nq
        return self._run("residual_jac", [*self._state(q=q, qd=qd, qdd=qdd), self._d(w, alpha), self._p(p)],
                         [(n, n), (n, n)])

    def outputs(self, q, qd=None, qdd=None, w=0.0, alpha=0.0, p=None) -> dict:
        z = np.zeros(self.nq)
        y = self._run("outputs", [*self._state(q=q, qd=z if qd is None else qd, qdd=z if qdd is None else qdd),
                                  ("lambda", np.zeros(self.model.nc), self.model.nc), self._d(w, alpha),
                                  self._p(p)], [(self.ny,)])[0]
        return dict(zip(self.manifest["outputs"], np.atleast_1d(y)))

    def energy(self, q, qd, w, alpha=0.0, p=None):
        return self._run("energy", [*self._state(q=q, qd=qd), self._d(w, alpha), self._p(p)], [(3,)])[0]

    def maneuver(self, t, mp=None):
        """[theta, w, alpha] of the guided root at time t."""
        mp = self.maneuver_defaults if mp is None else mp
        return self._run("drive", [("t", t, 1), ("mp", mp, self.model.nmp)], [(self.model.nd,)])[0][1:]


def _invoke(c_fn, label: str, inputs, out_shapes) -> list[np.ndarray]:
    """A C function of double pointers on inputs ((name, value, size), each checked before C
    reads it), then outputs of out_shapes; a column is returned as a vector."""
    keep = [_array(name, x, n, label) for name, x, n in inputs]
    outs = [np.zeros(shape) for shape in out_shapes]
    c_fn(*[_ptr(a) for a in keep], *[_ptr(o) for o in outs])
    return [o if o.ndim > 1 and o.shape[1] > 1 else o.ravel() for o in outs]


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
