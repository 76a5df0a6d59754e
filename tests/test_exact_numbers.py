"""Every constant of a model enters the equations exactly (flexsym/model/exact_numbers.py): a
station such as 0.301, for which sympy's nsimplify returns a product of irrational powers,
used to stop the derivation of section forces there."""
import random

import sympy as sp

from flexsym.model.exact_numbers import exact
from flexsym.scenes.system_scene import system_from_dict
from test_spatial_damping import A, L, RHO, cantilever


def test_exact_is_rational_and_the_float_itself():
    """Three- and four-digit decimals (about 1 % of which nsimplify turns irrational, as the
    first three here): each a rational whose float is the input; the rationals nsimplify finds
    are kept (1/3 stays 1/3, so generated code does not change)."""
    rng = random.Random(1)
    values = [0.301, 2.3464, 0.2037] + [round(rng.uniform(0, 10), 4) for _ in range(40)]
    assert not any(sp.nsimplify(v).is_Rational for v in values[:3])  # the case exists
    for v in values:
        assert exact(v).is_Rational and float(exact(v)) == v, v
    assert exact(0.301) == sp.Rational(301, 1000) and exact(1 / 3) == sp.Rational(1, 3)
    assert exact(sp.Rational(2, 7)) == sp.Rational(2, 7) and exact(2.5) == sp.Rational(5, 2)


def test_section_forces_at_a_station_nsimplify_cannot_make_rational():
    """The spatial cantilever at rest and undeformed: from equilibrium Qz(x) = rho A g_z (L - x)
    and N = 0 at x = 0.301 and 0.2037 (derivation only, exactly to round-off)."""
    from flexsym.physics.spatial import derive_spatial

    g_z = -9.81
    data = cantilever({"zeta": 0.0}, g=(0.0, 0.0, g_z),
                      columns={"Q1": "Qz(beam, 0.301)", "Q2": "Qz(beam, 0.2037)", "N1": "N(beam, 0.301)"})
    der = derive_spatial(system_from_dict(data, name="c3"))
    rest = {sym: v for _, sym, v in der.params} | {x: 0 for x in [*der.q, *der.qd, *der.qdd]}
    for col, x in (("Q1", 0.301), ("Q2", 0.2037)):
        value = float(der.outputs[col].xreplace(rest))
        want = RHO * A * g_z * (L - x)
        assert abs(value - want) < 1e-12 * abs(want), (col, value, want)
    assert abs(float(der.outputs["N1"].xreplace(rest))) < 1e-12
