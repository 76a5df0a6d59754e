"""Call the compiled kernels of a built variant from Python (ctypes), on numpy arrays."""
from __future__ import annotations

import ctypes
from pathlib import Path

import numpy as np

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

    def _invoke(self, c_name: str, inputs, out_shapes) -> list[np.ndarray]:
        keep = [np.ascontiguousarray(np.atleast_1d(np.asarray(x, dtype=float)).ravel()) for x in inputs]
        outs = [np.zeros(shape) for shape in out_shapes]
        fn = getattr(self.lib, c_name)
        fn.restype = None
        fn(*[_ptr(a) for a in keep], *[_ptr(o) for o in outs])
        return [o if o.shape[1] > 1 else o[:, 0] for o in outs]

    def call(self, kernel: str, *inputs) -> list[np.ndarray]:
        """A generated kernel by name, with the input sizes checked against the manifest."""
        info = self.kernels[kernel]
        for (name, size), x in zip(info["inputs"].items(), inputs):
            if np.asarray(x).size != size:
                raise ValueError(f"{kernel}: input {name} has {np.asarray(x).size} values, expected {size}")
        return self._invoke(info["c_name"], inputs, [tuple(s) for s in info["outputs"].values()])

    def mass(self, q, p=None):
        return self._invoke("fsm_mass", [q, self._p(p)], [(self.nq, self.nq)])[0]

    def force(self, q, qd, w, alpha=0.0, p=None):
        return self._invoke("fsm_force", [q, qd, [w, alpha], self._p(p)], [(self.nq, 1)])[0]

    def residual_jac(self, q, qd, qdd, w, alpha=0.0, p=None):
        n = self.nq
        return self._invoke("fsm_residual_jac", [q, qd, qdd, [w, alpha], self._p(p)], [(n, n), (n, n)])

    def outputs(self, q, qd=None, qdd=None, w=0.0, alpha=0.0, p=None) -> dict:
        z = np.zeros(self.nq)
        y = self._invoke("fsm_outputs", [q, z if qd is None else qd, z if qdd is None else qdd,
                                         [w, alpha], self._p(p)], [(self.ny, 1)])[0]
        return dict(zip(self.manifest["outputs"], np.atleast_1d(y)))

    def energy(self, q, qd, w, alpha=0.0, p=None):
        return self._invoke("fsm_energy", [q, qd, [w, alpha], self._p(p)], [(3, 1)])[0]

    def maneuver(self, t, mp=None):
        return self._invoke("fsm_maneuver", [[t], self.maneuver_defaults if mp is None else mp], [(3, 1)])[0]

    def _p(self, p):
        return self.param_defaults if p is None else np.asarray(p, dtype=float)
