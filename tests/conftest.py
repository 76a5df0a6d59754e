"""Shared fixtures: an isolated build cache, derivations and compiled models per variant."""
from __future__ import annotations

import json
import os
from pathlib import Path

import pytest


@pytest.fixture(scope="session", autouse=True)
def isolated_cache(tmp_path_factory):
    """Builds and custom variants go to a fresh cache, as on a new machine; pytest-xdist's
    workers share one (its builds are locked per folder), so each system is built once.
    FLEXSYM_TEST_CACHE names that cache instead: .ci/run gives the suite and the documentation's
    commands one fresh cache, so a scene both build is built once (builds are keyed by what
    generates them, so sharing changes no result)."""
    if os.environ.get("FLEXSYM_TEST_CACHE"):
        path = Path(os.environ["FLEXSYM_TEST_CACHE"])
        path.mkdir(parents=True, exist_ok=True)
    elif os.environ.get("PYTEST_XDIST_WORKER"):
        path = tmp_path_factory.getbasetemp().parent / "flexsym-cache"
        path.mkdir(exist_ok=True)
    else:
        path = tmp_path_factory.mktemp("flexsym-cache")
    old = os.environ.get("FLEXSYM_CACHE")
    os.environ["FLEXSYM_CACHE"] = str(path)
    yield path
    if old is None:
        os.environ.pop("FLEXSYM_CACHE", None)
    else:
        os.environ["FLEXSYM_CACHE"] = old


_derivations: dict = {}
_models: dict = {}


@pytest.fixture(scope="session")
def derivation():
    from flexsym.codegen.derive import derive
    from flexsym.model.variant import builtin

    def get(name):
        spec = builtin(name)
        if spec.name not in _derivations:
            _derivations[spec.name] = derive(spec)
        return _derivations[spec.name]

    return get


_s0_kernels: dict = {}


@pytest.fixture(scope="session")
def s0_kernels():
    """s0_kernels(variant name or spec) -> {name: emit.kernels.Kernel}: the casadi kernels of
    the variant's generated folder (its S0's, sysgen.build_system_kernels)."""
    from flexsym.codegen.sysgen import build_system_kernels
    from flexsym.model.library import variant_system
    from flexsym.model.variant import builtin
    from flexsym.physics.assemble import derive_system

    def get(target):
        spec = builtin(target) if isinstance(target, str) else target
        key = json.dumps(spec.to_dict(), sort_keys=True)
        if key not in _s0_kernels:
            _s0_kernels[key] = {k.name: k for k in build_system_kernels(derive_system(variant_system(spec)))}
        return _s0_kernels[key]

    return get


@pytest.fixture(scope="session")
def model(isolated_cache):
    from flexsym.toolchain.pipeline import compiled
    from flexsym.model.variant import builtin

    def get(name):
        spec = builtin(name)
        if spec.name not in _models:
            _models[spec.name] = compiled(spec)
        return _models[spec.name]

    return get


@pytest.fixture(scope="session")
def simulate(isolated_cache):
    """simulate(variant, **run options) -> RunResult (builds once per variant)."""
    from flexsym.toolchain.pipeline import prepare
    from flexsym.toolchain.run import run_built
    from flexsym.model.variant import builtin

    builds = {}

    def run(name, **kw):
        spec = builtin(name)
        if spec.name not in builds:
            builds[spec.name] = prepare(spec)
        return run_built(builds[spec.name], **kw)

    return run


BUILTIN_NAMES = ["linear", "geometric", "geometric_sine", "foreshortening"]


@pytest.fixture(scope="session")
def system_kernels_agree():
    """check(der, built, t, seed): a built system's generated C kernels (mass, force, outputs)
    against their casadi functions against the sympy expressions of its derivation, at a
    random state with no guided joint and no cut joint (d = [t]), to 1e-12 of each result."""
    import ctypes

    import numpy as np
    import sympy as sp

    from flexsym.codegen.sysgen import build_system_kernels

    from flexsym.physics.assemble import EF_T
    from flexsym.physics.lagrange import equations_of_motion

    def check(der, built, t: float, seed: int) -> None:
        kernels = {k.name: k.function for k in build_system_kernels(der)}
        M, f, y = der.M, der.f, sp.Matrix(list(der.outputs.values()))
        frame_T = getattr(der, "frame_T", ())
        if frame_T:  # a spatial system's T, which casadi differentiates: here sympy does
            T = sum((T_b.xreplace(actual) for T_b, actual in frame_T), sp.Integer(0))
            M_, f_ = equations_of_motion(T, sp.zeros(len(der.q), 1), der.q, der.qd,
                                         [g.symbols for g in der.guided])
            M, f, y = M + M_, f + f_, y.xreplace({EF_T: T})
        # time derivatives that casadi takes (body_kinds.spatial.base.along_motion): here sympy does
        y = y.xreplace({s_: der.ddt(e, k) for s_, (e, k) in getattr(der, "along", {}).items()})
        lib = ctypes.CDLL(str(built.library))
        rnd = np.random.default_rng(seed)
        n = len(der.q)
        q, qd, qdd = rnd.uniform(-0.3, 0.3, n), rnd.uniform(-0.5, 0.5, n), rnd.uniform(-1, 1, n)
        d = np.array([t])
        p = np.array([v for _, _, v in der.params])
        sym = dict(zip(der.q, q)) | dict(zip(der.qd, qd)) | dict(zip(der.qdd, qdd))
        sym |= {s_: v for (_, s_, v) in der.params} | {der.drive_symbols[0]: d[0]}
        ptr = ctypes.POINTER(ctypes.c_double)
        for name, args, expr in (("mass", (q, d, p), M), ("force", (q, qd, d, p), f),
                                 ("outputs", (q, qd, qdd, np.zeros(0), d, p), y)):
            ref = np.array(expr.xreplace(sym).evalf(30), dtype=float).reshape(-1)
            cas = np.array(kernels[name](*args)).reshape(-1)  # a dense matrix, row by row
            out = np.zeros(ref.size)
            arrays = [np.ascontiguousarray(a, dtype=float) for a in args]
            fn = getattr(lib, f"fsm_{der.system.name}_{name}")  # named after the system
            fn.restype = None
            fn(*[a.ctypes.data_as(ptr) for a in arrays], out.ctypes.data_as(ptr))
            scale = np.abs(ref).max()
            assert np.abs(cas - ref).max() <= 1e-12 * scale, name
            assert np.abs(out - ref).max() <= 1e-12 * scale, name
    return check
