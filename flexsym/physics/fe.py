"""The finite-element reference `ef`: a geometrically exact planar beam (ANCF cable element).

Each element carries, at its two nodes, the position r and the slope r_x = dr/dx of the
beam axis in the moving frame (8 coordinates), interpolated by cubic Hermite functions.
No rotation is linearised and no strain term is truncated:

    axial strain  eps   = (r_x . r_x - 1) / 2          (Green-Lagrange)
    curvature     kappa = (r_x x r_xx) / |r_x|^2       (material: d(phi)/dx per reference length)
    V^e = int_0^l [EA eps^2 / 2 + EI kappa^2 / 2] dx   (Gauss-Legendre, QUAD_POINTS per element)
    T^e = 1/2 int_0^l rho A |r' + w z x r|^2 dx        (exact: a polynomial in xi)

so the mass matrix is constant and the inertial terms are those of the modal variants.
Euler-Bernoulli kinematics: no shear, no rotary inertia. The root node is clamped to the
rotating frame (r = 0, and r_x along x: its length, the root stretch, stays free); the
unknowns are the displacements q = e - e_ref from the straight beam. sympy derives T^e and V^e
for one element (its inertial M^e, f^e by lagrange.equations_of_motion); casadi differentiates
V^e (AD) and emits element kernels; generated C assembles them.
"""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from flexsym.physics.energy import A, E, I, alpha, rho, w
from flexsym.physics.integrals import gauss_legendre
from flexsym.physics.lagrange import equations_of_motion
from flexsym.model.maneuver import Maneuver, maneuver_of
from flexsym.model.variant import QUAD_POINTS, FESpec

xi = sp.Symbol("xi", real=True)
le = sp.Symbol("l", positive=True)  # element length, p[L] / elements at run time


def hermite(l):
    return [1 - 3 * xi**2 + 2 * xi**3, l * (xi - 2 * xi**2 + xi**3), 3 * xi**2 - 2 * xi**3,
            l * (-xi**2 + xi**3)]


@dataclass
class ElementDerivation:
    spec: FESpec
    maneuver: Maneuver
    e: sp.Matrix  # absolute nodal coordinates (x1, y1, x1', y1', x2, y2, x2', y2')
    ed: sp.Matrix
    edd: sp.Matrix
    T: sp.Expr
    M: sp.Matrix
    f_inertial: sp.Matrix
    V: sp.Expr  # elastic energy by Gauss quadrature
    strain: sp.Expr  # eps(xi)
    stretch: sp.Expr  # |r_x|(xi)
    curvature: sp.Expr  # kappa(xi)

    @property
    def params(self) -> list[sp.Symbol]:
        """Element parameter vector pe = [rho, E, A, I, l]."""
        return [rho, E, A, I, le]


def derive_element(spec: FESpec) -> ElementDerivation:
    spec.validate()
    e = sp.Matrix(sp.symbols("x1 y1 dx1 dy1 x2 y2 dx2 dy2", real=True))
    ed = sp.Matrix([sp.Symbol(str(c) + "_d", real=True) for c in e])
    edd = sp.Matrix([sp.Symbol(str(c) + "_dd", real=True) for c in e])
    N = hermite(le)
    rx = sum(Ni * e[j] for Ni, j in zip(N, (0, 2, 4, 6)))
    ry = sum(Ni * e[j] for Ni, j in zip(N, (1, 3, 5, 7)))
    vx = sum(Ni * ed[j] for Ni, j in zip(N, (0, 2, 4, 6)))
    vy = sum(Ni * ed[j] for Ni, j in zip(N, (1, 3, 5, 7)))
    density = rho * A / 2 * ((vx - w * ry)**2 + (vy + w * rx)**2)
    T = sp.expand(le * sp.integrate(sp.expand(density), (xi, 0, 1)))
    M, f_in = equations_of_motion(T, sp.zeros(8, 1), e, ed, [(None, w, alpha)])  # inertial part

    eps, kappa, stretch, V = elastic_element(rx, ry)
    maneuver = maneuver_of(spec.maneuver)
    if not maneuver.accelerates:
        f_in = f_in.xreplace({alpha: 0})
    return ElementDerivation(spec, maneuver, e, ed, edd, T, M, f_in, V, eps, stretch, kappa)


def elastic_element(rx, ry):
    """(eps, kappa, |r_x|, V^e) of an element whose axis is (rx, ry)(xi): the one place of the
    strain measures (the one-beam `ef` and efbody.py's `ef` bodies in systems)."""
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


