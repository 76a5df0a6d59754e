"""Analytic limits from the generated, compiled kernels: frequencies, centrifugal elongation,
positive definite mass."""
import numpy as np
import pytest
import scipy.linalg as sl

from conftest import BUILTIN_NAMES

RHO, E, A, I, L = 3000.0, 7.0e10, 4.0e-4, 2.0e-7, 10.0
OMEGA1 = 1.8751040687119611**2 * np.sqrt(E * I / (RHO * A * L**4))  # 3.7977 rad/s
C = np.sqrt(E / RHO)  # bar wave speed


def _frequencies(m):
    z = np.zeros(m.nq)
    M = m.mass(z)
    K = m.residual_jac(z, z, z, 0.0)[0]  # dr/dq at rest, no rotation: K_L
    return np.sqrt(sl.eigh(K, M, eigvals_only=True))


@pytest.mark.parametrize("name", BUILTIN_NAMES)
def test_first_bending_frequency(model, name):
    assert abs(OMEGA1 - 3.798) < 1e-3
    omega = _frequencies(model(name))[0]
    assert abs(omega - OMEGA1) / OMEGA1 < 0.005, omega
    # A Rayleigh-Ritz bound: from above.
    assert omega >= OMEGA1 * (1 - 1e-12)




def test_axial_frequencies(model):
    exact = np.pi / 2 * C / L  # 758.8 rad/s, fixed-free bar
    # #1: a single linear axial mode; its Rayleigh quotient is exactly sqrt(3) c / L = 836.7 rad/s,
    # 10 % above the exact value: the linear mode is the bar's static shape, not its mode.
    f1 = _frequencies(model("m1"))
    assert np.isclose(f1[-1], np.sqrt(3) * C / L, rtol=1e-10)
    # #2 adds sin(pi s): the first axial frequency comes within 0.5 % of 759 rad/s.
    f2 = _frequencies(model("m2"))
    axial = f2[f2 > 300][0]
    assert abs(axial - exact) / exact < 0.005, axial
    assert axial >= exact
    # Explicit stability: RK4 needs dt < 2.785 / omega_max (about 3.3 ms for #1).
    assert 2.785 / f1[-1] < 3.4e-3


def _equilibrium(m, omega, iters=30):
    q = np.zeros(m.nq)
    z = np.zeros(m.nq)
    for _ in range(iters):
        f = m.force(q, z, omega, 0.0)
        J = m.residual_jac(q, z, z, omega, 0.0)[0]  # d(M 0 - f)/dq = -df/dq
        dq = np.linalg.solve(J, f)
        q = q + dq
        if np.max(np.abs(dq)) < 1e-16:
            break
    assert np.max(np.abs(m.force(q, z, omega, 0.0))) < 1e-9
    return q


def test_centrifugal_elongation_at_constant_speed(model):
    """At constant Omega = 6 rad/s the equilibrium of #1 (f = 0, q' = 0) has the axial tip
    elongation rho Omega^2 L^3 / (3E) = 5.14e-4 m (benchmark.md section 5)."""
    m = model("m1")
    q = _equilibrium(m, 6.0)
    u_tip = m.outputs(q)["u_tip"]
    expected = RHO * 6.0**2 * L**3 / (3 * E)
    assert abs(expected - 5.14e-4) < 1e-6
    assert abs(u_tip - expected) / expected < 0.01, u_tip
    # The linear axial mode has the exact one-mode answer (centrifugal softening of the bar).
    assert np.isclose(u_tip, expected / (1 - RHO * 36 * L**2 / (3 * E)), rtol=1e-12)
    # No bending at equilibrium.
    assert np.max(np.abs(q[1:])) < 1e-14


@pytest.mark.parametrize("name", BUILTIN_NAMES)
def test_mass_symmetric_positive_definite(model, name):
    m = model(name)
    rng = np.random.default_rng(7)
    masses = []
    for _ in range(10):
        q = rng.uniform(-1.0, 1.0, m.nq)
        M = m.mass(q)
        assert np.allclose(M, M.T, rtol=0, atol=1e-14 * np.max(np.abs(M)))
        assert np.min(np.linalg.eigvalsh(M)) > 0
        masses.append(M)
    constant = all(np.array_equal(masses[0], M) for M in masses)
    # #0-#2 have a constant mass matrix; foreshortening makes it depend on q.
    assert constant == (name != "foreshortening")
    assert bool(m.manifest["mass_constant"]) == constant
