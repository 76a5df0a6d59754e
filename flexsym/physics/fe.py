"""The ANCF cable element of `ef`, the geometrically exact planar beam: its shape functions and
strain measures, written once for every `ef` beam (efbody.py assembles it in a system; a
one-beam `ef` is its spin-up system S0).

Each element carries, at its two nodes, the position r and the slope r_x = dr/dx of the
beam axis in its frame (8 coordinates), interpolated by cubic Hermite functions.
No rotation is linearised and no strain term is truncated:

    axial strain  eps   = (r_x . r_x - 1) / 2          (Green-Lagrange)
    curvature     kappa = (r_x x r_xx) / |r_x|^2       (material: d(phi)/dx per reference length)
    V^e = int_0^l [EA eps^2 / 2 + EI kappa^2 / 2] dx   (Gauss-Legendre, QUAD_POINTS per element)

Euler-Bernoulli kinematics: no shear, no rotary inertia.
"""
from __future__ import annotations

import sympy as sp

from flexsym.physics.energy import A, E, I
from flexsym.physics.integrals import gauss_legendre
from flexsym.model.variant import QUAD_POINTS

xi = sp.Symbol("xi", real=True)
le = sp.Symbol("l", positive=True)  # element length, p[L] / elements at run time


def hermite(l):
    return [1 - 3 * xi**2 + 2 * xi**3, l * (xi - 2 * xi**2 + xi**3), 3 * xi**2 - 2 * xi**3,
            l * (-xi**2 + xi**3)]


def elastic_element(rx, ry):
    """(eps, kappa, |r_x|, V^e) of an element whose axis is (rx, ry)(xi): the one place of the
    strain measures (efbody.py's `ef` bodies)."""
    # Derivatives along the beam: d/dx = (1/l) d/dxi.
    r1 = sp.Matrix([sp.diff(rx, xi), sp.diff(ry, xi)]) / le
    r2 = sp.Matrix([sp.diff(rx, xi, 2), sp.diff(ry, xi, 2)]) / le**2
    eps = (r1.dot(r1) - 1) / 2
    # material curvature d(phi)/dx per reference length (Kirchhoff rod; the exact modal model's);
    # (r_x x r_xx)/|r_x|^3 would be per deformed length, O(axial strain) different
    kappa = (r1[0] * r2[1] - r1[1] * r2[0]) / r1.dot(r1)
    V = sp.Integer(0)
    for xg, wg in zip(*gauss_legendre(QUAD_POINTS)):
        at = {xi: sp.Float(xg, 30)}
        V += sp.Float(wg, 30) * le * (E * A / 2 * eps.xreplace(at)**2 + E * I / 2 * kappa.xreplace(at)**2)
    return eps, kappa, sp.sqrt(r1.dot(r1)), V


