"""A number of a model (a float of a scene or of the API) as an exact sympy number: the one rule
for every constant that enters the derived equations.

sympy's nsimplify when it finds a rational (0.15 -> 3/20, 1/3 -> 1/3: the generated code stays
as it was), else the float's shortest decimal, exactly (0.301 -> 301/1000). For about 1 % of
three- and four-digit decimals nsimplify returns a product of irrational powers instead
(0.301 -> 2**(75/247)*3**(593/741)*...), which the integral tables cannot take as a station.
"""
from __future__ import annotations

import sympy as sp


def exact(x) -> sp.Expr:
    """x as an exact number (a sympy expression without floats is returned as nsimplify does)."""
    if isinstance(x, sp.Basic) and not x.is_Float:
        return x if x.is_Rational else sp.nsimplify(x)
    r = sp.nsimplify(x)
    return r if r.is_Rational else sp.Rational(repr(float(x)))
