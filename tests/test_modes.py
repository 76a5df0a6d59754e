"""Mode library: eigenvalues solved to full precision and every boundary condition checked."""
import mpmath
import pytest
import sympy as sp

from flexsym.core.errors import SpecError
from flexsym.model.modes import (FAMILIES, ModeRef, clamped_free_beta, clamped_pinned_beta, mode,
                           parse_mode_token, root_slope_free, s)

ALL_MODES = [ModeRef(axis, fam, k) for (axis, fam), f in FAMILIES.items()
             for k in ([1] if f.single else [1, 2, 3, 6])]


@pytest.mark.parametrize("ref", ALL_MODES, ids=lambda r: f"{r.axis}-{r.token}")
def test_boundary_conditions(ref):
    m = mode(ref)
    assert m.ref.family == ref.family and m.ref.axis == ref.axis
    assert m.bcs, "every mode declares its boundary conditions"
    with mpmath.workdps(40):
        for bc in m.bcs:
            value = sp.N(m.derivative(bc.order).subs(s, bc.at), 40)
            # Scale: the size of that derivative over the beam (beam modes grow like beta^order).
            scale = max(abs(sp.N(m.derivative(bc.order).subs(s, x), 30)) for x in (0.25, 0.5, 0.75, 1)) or 1
            assert abs(value - bc.value) <= 1e-25 * max(scale, 1), (ref, bc, value)


def test_paper_eigenvalues_and_precision():
    # The paper prints beta_11 = 3.926602, beta_12 = 7.068583 (eq. 40).
    assert abs(float(clamped_pinned_beta(1)) - 3.926602) < 5e-7
    assert abs(float(clamped_pinned_beta(2)) - 7.068583) < 5e-7
    for k in range(1, 7):
        b = clamped_pinned_beta(k)
        with mpmath.workdps(45):
            assert abs(mpmath.tan(b) - mpmath.tanh(b)) < mpmath.mpf(10) ** -35
        # Consecutive roots approach (k + 1/4) pi.
        assert abs(float(b) - (k + 0.25) * mpmath.pi) < 0.01
    # Clamped-free: 1.8751 (benchmark.md: omega_1 = 1.8751^2 sqrt(EI / rho A L^4)).
    assert abs(float(clamped_free_beta(1)) - 1.8751040687119611) < 1e-15
    for k in range(1, 5):
        with mpmath.workdps(45):
            b = clamped_free_beta(k)
            assert abs(1 + mpmath.cos(b) * mpmath.cosh(b)) < mpmath.mpf(10) ** -25


def test_static_modes_match_paper():
    assert sp.simplify(mode(ModeRef("axial", "static")).expr - s) == 0
    phi2 = mode(ModeRef("bending", "static")).expr
    assert sp.simplify(phi2 - (sp.Rational(3, 2) * s**2 - sp.Rational(1, 2) * s**3)) == 0
    # Clamped-pinned modes vanish at the tip, so v_o(L) = eta_2 (benchmark.md section 3).
    for k in (1, 2):
        assert mode(ModeRef("bending", "clamped_pinned", k)).value_at(0, 1) == 0


def test_exactness_flags():
    assert mode(ModeRef("axial", "sine", 2)).exact
    assert mode(ModeRef("bending", "static")).exact
    assert not mode(ModeRef("bending", "clamped_pinned", 1)).exact


def test_pinned_root_modes():
    """pp: sin(k pi s) exactly (closed-form integrals). pf: the pinned-free beam's modes, beta
    the roots of tan b = tanh b (as clamped-pinned), orthogonal to each other and to the turn
    about the pin (s). Both leave the root slope free; no other family does."""
    for k in (1, 2, 5):
        m = mode(ModeRef("bending", "pinned_pinned", k))
        assert m.exact and sp.simplify(m.expr - sp.sin(k * sp.pi * s)) == 0
    pf = [mode(ModeRef("bending", "pinned_free", k)) for k in (1, 2, 3)]
    assert [m.eigenvalue for m in pf] == [mode(ModeRef("bending", "clamped_pinned", k)).eigenvalue
                                          for k in (1, 2, 3)]
    assert not pf[0].exact
    with mpmath.workdps(40):
        fn = [sp.lambdify(s, m.expr, "mpmath") for m in pf]
        for i, f in enumerate(fn):
            norm = mpmath.quad(lambda x: f(x) ** 2, [0, 1])
            assert abs(mpmath.quad(lambda x: x * f(x), [0, 1])) < 1e-30 * norm
            for g in fn[:i]:
                assert abs(mpmath.quad(lambda x: f(x) * g(x), [0, 1])) < 1e-30 * norm
    free = {(a, f) for (a, f) in FAMILIES if root_slope_free(ModeRef(a, f, 1))}
    assert free == {("bending", "pinned_pinned"), ("bending", "pinned_free")}


@pytest.mark.parametrize("axis,token,expected", [
    ("axial", "static", ModeRef("axial", "static", 1)),
    ("axial", "sin2", ModeRef("axial", "sine", 2)),
    ("bending", "cp3", ModeRef("bending", "clamped_pinned", 3)),
    ("bending", "clamped_free1", ModeRef("bending", "clamped_free", 1)),
    ("bending", "pp2", ModeRef("bending", "pinned_pinned", 2)),
    ("bending", "pinned_free3", ModeRef("bending", "pinned_free", 3)),
])
def test_parse_tokens(axis, token, expected):
    assert parse_mode_token(axis, token) == expected


@pytest.mark.parametrize("axis,token,msg", [
    ("bending", "foo1", "unknown bending mode"),
    ("axial", "cp1", "unknown axial mode"),
    ("bending", "cp", "needs an index"),
    ("bending", "cp0", "index"),
    ("bending", "cp99", "index"),
    ("axial", "static2", "single member"),
    ("bending", "cp-1", "cannot read"),
])
def test_bad_tokens(axis, token, msg):
    with pytest.raises(SpecError, match=msg):
        parse_mode_token(axis, token)
