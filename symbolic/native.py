"""Call the compiled kernels of a built variant from Python (ctypes), on numpy arrays."""
from __future__ import annotations

import ctypes
import json
from pathlib import Path

import numpy as np

from .build import Built
from .generate import read_manifest

_dptr = ctypes.POINTER(ctypes.c_double)


def _ptr(a: np.ndarray):
    return a.ctypes.data_as(_dptr)


class CompiledModel:
    """The kernels of libflexsym_<name>.so with the shapes recorded in manifest.json."""

    def __init__(self, built: Built, gen_dir: Path):
        self.built = built
        self.manifest = read_manifest(gen_dir)
        self.lib = ctypes.CDLL(str(built.library))
        self.kernels = self.manifest["kernels"]
        self.nq = len(self.manifest["coordinates"])
        self.param_defaults = np.array([p["default"] for p in self.manifest["params"]])
        self.maneuver_defaults = np.array([p["default"] for p in self.manifest["maneuver"]["params"]])

    def call(self, kernel: str, *inputs) -> list[np.ndarray]:
        info = self.kernels[kernel]
        args, keep = [], []
        for (name, size), x in zip(info["inputs"].items(), inputs):
            a = np.ascontiguousarray(np.atleast_1d(np.asarray(x, dtype=float)).ravel())
            if a.size != size:
                raise ValueError(f"{kernel}: input {name} has {a.size} values, expected {size}")
            keep.append(a)
            args.append(_ptr(a))
        outs = [np.zeros((r, c)) for r, c in info["outputs"].values()]
        fn = getattr(self.lib, info["c_name"])
        fn.restype = None
        fn(*args, *[_ptr(o) for o in outs])
        return [o if o.shape[1] > 1 else o[:, 0] for o in outs]

    def mass(self, q, p=None):
        return self.call("mass", q, self._p(p))[0]

    def force(self, q, qd, w, alpha=0.0, p=None):
        return self.call("force", q, qd, [w, alpha], self._p(p))[0]

    def residual_jac(self, q, qd, qdd, w, alpha=0.0, p=None):
        return self.call("residual_jac", q, qd, qdd, [w, alpha], self._p(p))

    def outputs(self, q, qd=None, p=None):
        y = self.call("outputs", q, np.zeros(self.nq) if qd is None else qd, self._p(p))[0]
        return dict(zip(self.manifest["outputs"], y))

    def energy(self, q, qd, w, alpha=0.0, p=None):
        return self.call("energy", q, qd, [w, alpha], self._p(p))[0]

    def maneuver(self, t, mp=None):
        return self.call("maneuver", [t], self.maneuver_defaults if mp is None else mp)[0]

    def _p(self, p):
        return self.param_defaults if p is None else np.asarray(p, dtype=float)

    def info(self) -> dict:
        import subprocess

        out = subprocess.run([str(self.built.executable), "--info"], capture_output=True, text=True,
                             check=True).stdout
        return json.loads(out)
