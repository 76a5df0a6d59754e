"""The finite-element reference ef: generated element kernels, frequencies, convergence in
mesh and step, and the modal variants against it at a moderate spin rate."""
from dataclasses import replace

import numpy as np
import scipy.linalg as sl
import sympy as sp

from flexsym.physics.energy import alpha, w
from flexsym.physics.fe import elastic_element, hermite, le, xi
from flexsym.physics.lagrange import equations_of_motion
from flexsym.toolchain.pipeline import compiled, prepare
from flexsym.toolchain.run import run_built
from flexsym.model.variant import builtin

RHO, E, A, I, L = 3000.0, 7.0e10, 4.0e-4, 2.0e-7, 10.0
OMEGA1 = 1.8751040687119611**2 * np.sqrt(E * I / (RHO * A * L**4))
AXIAL1 = np.pi / 2 * np.sqrt(E / RHO) / L


def ef(n):
    return replace(builtin("ef"), name=f"ef_n{n}", elements=n, aliases=())


def _hub_element():
    """One ANCF element on the spinning hub derived here, apart from efbody.py (what the
    one-beam `ef` generated until 2026-12): T^e with the hub's rate w in the moving frame, its
    inertial forces by Lagrange's equations with the drive (w, alpha), V^e of fe.py's strain
    measures. Returns (e, e', the parameter symbols, M^e, inertial f^e, V^e)."""
    from flexsym.physics.energy import A as A_, E as E_, I as I_, rho

    e = sp.Matrix(sp.symbols("x1 y1 dx1 dy1 x2 y2 dx2 dy2", real=True))
    ed = sp.Matrix([sp.Symbol(str(c) + "_d", real=True) for c in e])
    N = hermite(le)
    rx, ry, vx, vy = (sum(Ni * v[j] for Ni, j in zip(N, idx)) for v, idx in
                      ((e, (0, 2, 4, 6)), (e, (1, 3, 5, 7)), (ed, (0, 2, 4, 6)), (ed, (1, 3, 5, 7))))
    T = sp.expand(le * sp.integrate(sp.expand(rho * A_ / 2 * ((vx - w * ry)**2 + (vy + w * rx)**2)), (xi, 0, 1)))
    M, f_in = equations_of_motion(T, sp.zeros(8, 1), e, ed, [(None, w, alpha)])
    return e, ed, [rho, E_, A_, I_, le], M, f_in, elastic_element(rx, ry)[3]


def test_compiled_ef_matches_the_element_derivation(model):
    """The compiled ef variant (its S0's body: efbody's frame terms, the ef_elastic kernel by
    casadi AD, assembled by system.c) against fe.py's element derivation, assembled here: M^e
    and the inertial forces of T^e with the hub's rate w and acceleration alpha (_hub_element),
    the elastic forces -dV^e/de differentiated by sympy, at random deformed states."""
    spec = builtin("ef")
    e_, ed_, pe, M_sym, f_in, V = _hub_element()
    lib = model("ef")
    n, l = spec.elements, L / spec.elements
    symbols = list(e_) + list(ed_) + [w, alpha] + pe
    f_e = sp.lambdify(symbols, f_in - sp.Matrix([sp.diff(V, x) for x in e_]), "numpy")
    M_e = sp.lambdify(symbols, M_sym, "numpy")
    # the variant's coordinates q: dx0, then (ux, uy, dx, dy) of nodes 1..n, displacements
    # from the straight beam (node k at x = k l, slope (1, 0)); the root's x, y, dy are held
    free = [2] + list(range(4, 4 * (n + 1)))
    rng = np.random.default_rng(3)
    for _ in range(3):
        q, qd = rng.uniform(-0.05, 0.05, lib.nq), rng.uniform(-1, 1, lib.nq)
        omega, acc = rng.uniform(0, 6), rng.uniform(-1, 1)
        e, ed = np.zeros(4 * (n + 1)), np.zeros(4 * (n + 1))
        e[free], ed[free] = q, qd
        e += np.concatenate([[k * l, 0.0, 1.0, 0.0] for k in range(n + 1)])
        f, M = np.zeros(4 * (n + 1)), np.zeros((4 * (n + 1),) * 2)
        for k in range(n):
            dofs = slice(4 * k, 4 * k + 8)
            args = [*e[dofs], *ed[dofs], omega, acc, RHO, E, A, I, l]
            f[dofs] += np.ravel(f_e(*args))
            M[dofs, dofs] += np.array(M_e(*args), dtype=float)
        f_ref, M_ref = f[free], M[np.ix_(free, free)]
        assert np.max(np.abs(lib.force(q, qd, omega, acc) - f_ref)) <= 1e-10 * np.max(np.abs(f_ref))
        assert np.max(np.abs(lib.mass(q) - M_ref)) <= 1e-13 * np.max(np.abs(M_ref))


def _frequencies(n):
    m = compiled(ef(n), log=lambda s: None)
    z = np.zeros(m.nq)
    w2, V = sl.eigh(m.residual_jac(z, z, z, 0.0)[0], m.mass(z))
    ux = [1 + 4 * k for k in range(n)]  # x displacements of the nodes
    axial = [i for i in range(len(w2)) if np.sum(V[ux, i]**2) > 0.5 * np.sum(V[:, i]**2)]
    return np.sqrt(w2[0]), np.sqrt(w2[axial[0]])


def test_frequencies_converge_with_the_mesh():
    errs = []
    for n in (2, 4, 8):
        bend, axial = _frequencies(n)
        assert bend >= OMEGA1 * (1 - 1e-12) and axial >= AXIAL1 * (1 - 1e-12)  # Rayleigh-Ritz
        errs.append((bend - OMEGA1) / OMEGA1)
    rates = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    # Cubic Hermite elements, energy with second derivatives: eigenvalue errors O(h^(2(p+1-m)))
    # = O(h^4) with p = 3, m = 2 (Strang & Fix).
    assert np.all(np.abs(rates - 4) < 0.3), (errs, rates)
    assert errs[-1] < 5e-6
    assert abs(_frequencies(8)[1] - AXIAL1) / AXIAL1 < 1e-6


def _max_diff(a, b):
    n = min(len(a.t), len(b.t))
    assert np.allclose(a.t[:n], b.t[:n])
    return np.max(np.abs(a["v_tip"][:n] - b["v_tip"][:n]))


def test_spinup_converges_in_mesh():
    kw = dict(dt=1e-3, t_end=8.0)
    ref = run_built(prepare(ef(32), log=lambda s: None), **kw)
    errs = [_max_diff(run_built(prepare(ef(n), log=lambda s: None), **kw), ref) for n in (2, 4, 8)]
    rates = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(rates > 3.5), (errs, rates)
    assert errs[-1] < 5e-5


def test_spinup_converges_in_time():
    b = prepare(ef(4), log=lambda s: None)
    ref = run_built(b, dt=1.25e-4, t_end=8.0, out_every=80)
    errs = [_max_diff(run_built(b, dt=dt, t_end=8.0, out_every=int(round(0.01 / dt))), ref)
            for dt in (5e-3, 2.5e-3, 1.25e-3)]
    rates = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(np.abs(rates - 2) < 0.3), (errs, rates)  # generalized-alpha: second order


def test_modal_variants_near_ef_at_2_rad_s():
    """At omega_s = 2 rad/s stiffening is mild. #2, #3 and the prestress variant stay within
    1 mm of ef; #1 does not: its constant axial force (the mean rho A Omega^2 L^2 / 3) stiffens
    the static bending shape 38 % too much (int N Phi2'^2: 0.400 against 0.289 rho A Omega^2 L^2),
    which costs it about 1 cm, always on the stiff side."""
    kw = dict(dt=1e-3, t_end=20.0, params={"ws": 2.0, "ts": 15.0})
    ref = run_built(prepare(builtin("ef")), **kw)
    for name, tol in (("m2", 1e-3), ("m3", 1e-3), ("prestress", 1e-3), ("m1", 1.2e-2)):
        r = run_built(prepare(builtin(name)), **kw)
        assert _max_diff(r, ref) < tol, name
    m1 = run_built(prepare(builtin("m1")), **kw)
    assert np.min(m1["v_tip"]) > np.min(ref["v_tip"]) + 3e-3  # less deflection: too stiff
    s = sp.Symbol("s")
    phi2_s = sp.diff(sp.Rational(3, 2) * s**2 - s**3 / 2, s)
    mean = sp.integrate(phi2_s**2 / 3, (s, 0, 1))
    true = sp.integrate((1 - s**2) / 2 * phi2_s**2, (s, 0, 1))
    assert abs(float(mean / true) - 1.38) < 0.01
