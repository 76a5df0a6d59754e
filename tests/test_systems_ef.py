"""`ef` bodies in systems: the column-block Jacobian kernels, and the modal variants against
`ef` on the benchmark systems (short runs on coarse meshes; the converged study is README's)."""
from dataclasses import replace

import numpy as np
import pytest

from flexsym import sysgen
from flexsym.spec import builtin, customize
from flexsym.systems_library import pendulum_system
from flexsym.sysgen import run_system


def _ef_pendulum(elements: int):
    return pendulum_system(customize(builtin("ef"), elements=elements))


def test_jacobian_blocks_equal_one_kernel(monkeypatch):
    """residual_jac split into column blocks (one C function each, assembled in system.c) gives
    the rows of the single-kernel Jacobian: the same casadi graph, so equal to round-off
    (measured: identical over S3's 2 s with 4 elements, against the code before the split)."""
    system = _ef_pendulum(4)
    der_blocks = sysgen.residual_jac_blocks(sysgen.derive_system(system))
    assert len(der_blocks) > 1  # 18 coordinates: three blocks
    opts = dict(t_end=0.3, dt=1e-4)
    split = run_system(system, **opts)
    monkeypatch.setattr(sysgen, "JAC_BLOCK", 10**6)
    whole = run_system(replace(system, name="pendulum_one_jac"), **opts)
    assert split.ok and whole.ok
    for c in ("x_tip", "y_tip", "w_mid", "M_mid"):
        assert np.max(np.abs(split[c] - whole[c])) <= 1e-10 * np.max(np.abs(whole[c]))
