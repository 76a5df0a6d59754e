"""Stress recovery: resultants at constant rotation, vanishing end values, element method
against continuum, N from axial equilibrium."""
import numpy as np
import pytest

from flexsym.toolchain.pipeline import compiled, prepare
from flexsym.toolchain.run import run_built
from flexsym.model.variant import builtin, customize

RHO, E, A, I, L = 3000.0, 7.0e10, 4.0e-4, 2.0e-7, 10.0
OMEGA = 6.0


def n_hat(s):
    """Centrifugal axial force of the straight beam at constant Omega."""
    return RHO * A * OMEGA**2 * L**2 * (1 - s**2) / 2


def equilibrium(m, omega=OMEGA):
    q = np.zeros(m.nq)
    z = np.zeros(m.nq)
    load = np.max(np.abs(m.force(q, z, omega, 0.0)))  # the centrifugal load on the straight beam
    for _ in range(40):
        f = m.force(q, z, omega, 0.0)
        dq = np.linalg.solve(m.residual_jac(q, z, z, omega, 0.0)[0], f)
        q += dq
        if np.max(np.abs(dq)) < 1e-15:
            break
    assert np.max(np.abs(m.force(q, z, omega, 0.0))) <= 1e-9 * load
    return q, m.outputs(q, z, z, omega, 0.0)


def custom(base, **kw):
    return compiled(customize(builtin(base), **kw), log=lambda s: None)


POINTS = {"A": 0.0, "s0p25": 0.25, "B": 0.5, "s0p75": 0.75, "C": 1.0}
OUTS = ["v_tip", "u_tip"] + [f"{q}_{p}" for q in "NM" for p in POINTS]


def test_constant_rotation_axial_force_ef():
    """The geometrically exact model reproduces N(x) = rho A Omega^2 (L^2 - x^2)/2 up to the
    centrifugal load of the stretch itself (u/L ~ 5e-5): tolerance 1e-3 of N(0)."""
    _, y = equilibrium(custom("ef", outputs=OUTS + ["N_A_clamp", "M_A_clamp"]))
    for p, s in POINTS.items():
        assert abs(y[f"N_{p}"] - n_hat(s)) <= 1e-3 * n_hat(0), (p, y[f"N_{p}"], n_hat(s))
        assert abs(y[f"M_{p}"]) < 1e-6
    # Element resultant and clamp reaction agree at the root.
    assert abs(y["N_A"] - y["N_A_clamp"]) < 1e-2
    assert abs(y["N_C"]) < 1e-2


def test_constant_rotation_axial_force_modal():
    """#1: a constant N, the mean of N(x) (the best constant in L2). #2: N(x) is the L2-best fit
    of N(x) in span{1, cos(pi s)} (the Galerkin property of its axial modes s, sin(pi s)).
    #3 with N from equilibrium: N(x) itself."""
    s = np.linspace(0, 1, 2001)
    _, y1 = equilibrium(custom("m1", outputs=OUTS))
    for p in POINTS:
        assert abs(y1[f"N_{p}"] - RHO * A * OMEGA**2 * L**2 / 3) < 1e-3 * n_hat(0)
    _, y2 = equilibrium(custom("m2", outputs=OUTS))
    basis = np.stack([np.ones_like(s), np.cos(np.pi * s)], axis=1)
    coef = np.linalg.lstsq(basis, n_hat(s), rcond=None)[0]
    for p, sp_ in POINTS.items():
        fit = coef[0] + coef[1] * np.cos(np.pi * sp_)
        assert abs(y2[f"N_{p}"] - fit) < 1e-3 * n_hat(0), (p, y2[f"N_{p}"], fit)
    # So #2 is closer than #1 to N = 0 at the free end, but not zero (566 N against 1441 N).
    assert 0 < y2["N_C"] < 0.5 * y1["N_C"]
    _, y3 = equilibrium(custom("m3", outputs=OUTS, axial_force="equilibrium"))
    for p, sp_ in POINTS.items():
        assert abs(y3[f"N_{p}"] - n_hat(sp_)) < 1e-3 * n_hat(0)


def test_foreshortening_has_no_axial_force_by_default():
    from flexsym.core.errors import SpecError

    assert not any(o.startswith("N_") for o in builtin("m3").outputs)
    with pytest.raises(SpecError, match="N_A is not available.*--axial-force equilibrium"):
        customize(builtin("m3"), outputs="v_tip,N_A")


@pytest.fixture(scope="module")
def spinup_runs():
    out = {}
    for name in ("m1", "m2", "m3", "prestress", "ef"):
        out[name] = run_built(prepare(builtin(name)), dt=1e-3, t_end=20.0)
        assert out[name].ok
    return out


def test_moment_vanishes_at_the_free_end(spinup_runs):
    for name in ("m1", "m2", "m3", "prestress"):
        # v''(L) = 0 is a boundary condition of every bending mode: exactly zero.
        assert np.max(np.abs(spinup_runs[name]["M_C"])) == 0.0, name
    ef = spinup_runs["ef"]
    # The FE model has M(L) = 0 as a natural condition: small, not exact.
    assert np.max(np.abs(ef["M_C"])) < 2e-3 * np.max(np.abs(ef["M_A"]))
    assert np.max(np.abs(ef["N_C"])) < 1e-3 * np.max(np.abs(ef["N_A"]))
    # Root moment from the element resultant and from the clamp reaction agree.
    assert np.max(np.abs(ef["M_A"] - ef["M_A_clamp"])) < 0.01 * np.max(np.abs(ef["M_A"]))


def test_element_method_converges_to_continuum():
    cont = run_built(prepare(builtin("m2")), dt=1e-3, t_end=10.0)
    errors = []
    for n in (8, 16, 32):
        r = run_built(prepare(customize(builtin("m2"), stress=f"element:{n}"), log=lambda s: None),
                      dt=1e-3, t_end=10.0)
        errors.append([np.max(np.abs(r[k] - cont[k])) for k in ("N_A", "M_A", "M_B")])
    errors = np.array(errors)
    rates = np.log2(errors[:-1] / errors[1:])
    # End forces of exact nodal displacements: second order in the element length.
    assert np.all(np.abs(rates - 2) < 0.15), (errors, rates)
    assert errors[-1, 1] < 0.005 * np.max(np.abs(cont["M_A"]))
