"""Modal integrals against independent quadrature, and the geometric stiffness of a cubic
bending field against the paper's element matrix (8)."""
from functools import lru_cache

import mpmath
import numpy as np
import pytest
import sympy as sp
from scipy import integrate

from flexsym.physics.energy import ENERGY_TERMS, A, E, L, build_fields
from flexsym.physics.integrals import REL_TOL, IntegralTable
from flexsym.model.modes import Mode, ModeRef, s

from conftest import BUILTIN_NAMES

# scipy warns that double precision limits its own accuracy on the cancelling sinh/cosh terms.
pytestmark = pytest.mark.filterwarnings("ignore::scipy.integrate.IntegrationWarning")


def _numpy_factor(table, factor):
    """An independent evaluation of one factor: lambdified numpy, nested scipy.quad for H."""
    if factor.kind == "mode":
        fn = sp.lambdify(s, table.modes[factor.a].derivative(factor.order), "numpy")
        return lambda x: float(fn(x))
    da = sp.lambdify(s, sp.diff(table.modes[factor.a].expr, s), "numpy")
    db = sp.lambdify(s, sp.diff(table.modes[factor.b].expr, s), "numpy")
    return lru_cache(maxsize=None)(
        lambda x: integrate.quad(lambda y: da(y) * db(y), 0.0, x, epsabs=1e-15, epsrel=1e-14)[0])


@pytest.mark.parametrize("name", BUILTIN_NAMES)
def test_modal_integrals_match_scipy_quad(derivation, name):
    der = derivation(name)
    table = der.table
    assert table.symbols, "a variant has modal integrals"
    for sym in table.symbols:
        v = table.value(sym)
        assert v.rel_error <= REL_TOL
        a, b, s_pow, factors = table.monomial(sym)
        fns = [_numpy_factor(table, f) for f in factors]
        integrand = lambda x: x**s_pow * np.prod([f(x) for f in fns])
        ref = integrate.quad(integrand, float(a), float(b), epsabs=1e-14, epsrel=1e-13, limit=200)[0]
        scale = integrate.quad(lambda x: abs(integrand(x)), float(a), float(b), epsabs=1e-14, limit=200)[0]
        # scipy works in double precision on modes whose sinh/cosh terms cancel to ~1e-13.
        assert abs(float(v.value) - ref) <= 1e-11 * max(scale, 1e-300), (sym, float(v.value), ref)


def test_gauss_path_agrees_with_exact_path():
    """Integrals that sympy does in closed form, redone by the quadrature path, agree to 25 digits."""
    from flexsym.model.modes import mode

    modes = {m.name: m for m in (mode(ModeRef("axial", "static")), mode(ModeRef("axial", "sine", 2)),
                                 mode(ModeRef("bending", "static")))}
    table = IntegralTable(modes)
    f = table.mode_value
    expr = table.integrate(f("u_sin2", 1) * f("v_static", 1)**2 + s**2 * f("u_static") * f("v_static")
                           + table.fs_value("v_static", "v_static") * f("u_sin2"))
    for sym in table.symbols:
        exact = table.value(sym)
        assert exact.method == "exact"
        gauss = table._gauss(*table.monomial(sym))
        assert abs(gauss.value - exact.value) <= mpmath.mpf("1e-25") * max(1, abs(exact.value)), sym
    assert expr.free_symbols == set(table.symbols)


def test_pinned_mode_integrals_match_quadrature():
    """pp (closed form) and pf (Gauss, transcendental) modes beside cf and ff in one table: the
    products the energies take, against scipy's quadrature; pp's closed forms against the
    Gauss path to 25 digits."""
    from flexsym.model.modes import mode

    refs = [ModeRef("bending", "pinned_pinned", 2), ModeRef("bending", "pinned_pinned", 3),
            ModeRef("bending", "pinned_free", 2), ModeRef("bending", "clamped_free", 1),
            ModeRef("axial", "fixed_free", 1)]
    table = IntegralTable({m.name: m for m in (mode(r) for r in refs)})
    f = table.mode_value
    table.integrate(f("v_pp2", 2) ** 2 + f("v_pp2", 2) * f("v_pp3", 2) + f("v_pf2", 2) * f("v_pp3", 2)
                    + f("v_cf1", 1) * f("v_pp2", 1) + s * f("v_pf2") + s * f("v_pp3")
                    + table.fs_value("v_pp2", "v_pf2") * f("u_ff1") + f("u_ff1", 1) * f("v_pp2", 1) ** 2)
    methods = set()
    for sym in table.symbols:
        v = table.value(sym)
        methods.add(v.method)
        a, b, s_pow, factors = table.monomial(sym)
        fns = [_numpy_factor(table, fa) for fa in factors]
        integrand = lambda x: x**s_pow * np.prod([fn(x) for fn in fns])
        ref = integrate.quad(integrand, float(a), float(b), epsabs=1e-14, epsrel=1e-13, limit=200)[0]
        scale = integrate.quad(lambda x: abs(integrand(x)), float(a), float(b), epsabs=1e-14, limit=200)[0]
        assert abs(float(v.value) - ref) <= 1e-11 * max(scale, 1e-300), (sym, float(v.value), ref)
        if all(table.modes[fa.a].exact and (fa.kind == "mode" or table.modes[fa.b].exact) for fa in factors):
            assert v.method == "exact", sym
            gauss = table._gauss(a, b, s_pow, factors)
            assert abs(gauss.value - v.value) <= mpmath.mpf("1e-25") * max(1, abs(v.value)), sym
    assert methods == {"exact", "gauss"}


def test_foreshortening_kernel_from_its_chebyshev_series():
    """H_ab(x) = int_0^x b_a' b_b' (m3's foreshortening) is read from the antiderivative of a
    Chebyshev series of b_a' b_b': at Gauss nodes of a station's part [0.3, 1] it equals
    mpmath's own quadrature at 45 digits to 1e-36 of its scale, for clamped-free modes 1-4 and
    a pinned-free one (up to e^(2 beta_4 s)). A series is refused (None: the inner rule takes
    over) where the integrand is not resolved, a kink; and int_0^x cos 5t = sin(5x)/5."""
    from flexsym.model.modes import mode
    from flexsym.physics.integrals import Factor, _nodes, chebyshev_antiderivative, clenshaw

    refs = [ModeRef("bending", "clamped_free", k) for k in (1, 2, 3, 4)] + [ModeRef("bending", "pinned_free", 2)]
    table = IntegralTable({m.name: m for m in (mode(r) for r in refs)})
    xs, _ = _nodes(24, sp.Rational(3, 10), 1)
    names = list(table.modes)
    for a, b in [(names[0], names[0]), (names[1], names[3]), (names[3], names[3]), (names[2], names[4])]:
        got = table._fs_samples(Factor("fs", a, b), xs)
        da, db = (sp.lambdify(s, sp.diff(table.modes[m].expr, s), "mpmath") for m in (a, b))
        with mpmath.workdps(45):
            ref = [mpmath.quad(lambda y: da(y) * db(y), [0, x]) for x in xs]
            scale = max(abs(r) for r in ref)
            assert max(abs(g - r) for g, r in zip(got, ref)) <= mpmath.mpf("1e-36") * scale, (a, b)
    with mpmath.workdps(44):
        assert chebyshev_antiderivative(lambda x: abs(x - mpmath.mpf("0.3")), 256) is None
        series = chebyshev_antiderivative(lambda x: mpmath.cos(5 * x), 64)
        x = mpmath.mpf("0.7")
        assert abs(clenshaw(series, 2 * x - 1) - mpmath.sin(5 * x) / 5) < mpmath.mpf("1e-40")


def _hermite_modes():
    shapes = [1 - 3 * s**2 + 2 * s**3, s - 2 * s**2 + s**3, 3 * s**2 - 2 * s**3, -s**2 + s**3]
    return [Mode(ModeRef("bending", "hermite", i + 1), e, True, (), f"N_{i + 1}", f"Hermite shape {i + 1}")
            for i, e in enumerate(shapes)]


def test_geometric_stiffness_of_cubic_field_matches_paper_element_matrix():
    """One beam element: u = s * eta (linear axial field), v = Hermite cubic with nodal dofs
    d = (v1, L th1, v2, L th2). The cubic energy term EA/2 int u_x v_x^2 dx must equal
    1/2 P q^T K_GL q with P = EA (u2 - u1)/L and K_GL of the paper's eq. (8)."""
    from flexsym.model.modes import mode

    axial = mode(ModeRef("axial", "static"))
    bending = _hermite_modes()
    table = IntegralTable({m.name: m for m in [axial] + bending})
    eta = sp.Symbol("eta")
    d = sp.symbols("d1:5")
    q = {axial.name: eta} | {m.name: di for m, di in zip(bending, d)}
    fields = build_fields([axial], bending, q, {k: 0 for k in q}, table, False)
    V = table.integrate(ENERGY_TERMS["cubic"].density(fields)).xreplace(table.substitutions())
    G = sp.hessian(V, d) / eta  # V = 1/2 eta d^T G d
    # Convert to physical dofs (v1, th1, v2, th2): v = ... + N2 * (L th1) + ...
    T = sp.diag(1, L, 1, L)
    K_ours = sp.simplify(T * G * T / (E * A / L))  # divide by P / eta = EA / L
    Le = L
    K_paper = sp.Matrix([
        [sp.Rational(6, 5) / Le, sp.Rational(1, 10), -sp.Rational(6, 5) / Le, sp.Rational(1, 10)],
        [sp.Rational(1, 10), 2 * Le / 15, -sp.Rational(1, 10), -Le / 30],
        [-sp.Rational(6, 5) / Le, -sp.Rational(1, 10), sp.Rational(6, 5) / Le, -sp.Rational(1, 10)],
        [sp.Rational(1, 10), -Le / 30, -sp.Rational(1, 10), 2 * Le / 15],
    ])
    diff = (K_ours - K_paper).applyfunc(lambda e: sp.nsimplify(sp.N(e.subs(L, 7.0), 30), tolerance=1e-25))
    assert diff == sp.zeros(4, 4), K_ours
    # The paper prints +L/30 for the (theta1, theta2) entry of (8); the integral gives -L/30
    # (the standard geometric stiffness): a sign misprint, recorded here so it is not copied.
    assert sp.simplify(K_ours[1, 3] + L / 30) == 0
