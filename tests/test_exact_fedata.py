"""The exact kinematics of a beam from finite-element data (physics/exact_kinematics.py,
exact_body.py): a rule broken into pieces is the same rule as one piece with the same nodes;
rho A per section and a point mass enter T as a hand computation says; the point mass sits at
the beam's integrated tip; d'Alembert's residual of a stepped body with a tip mass is the
derivative of Lagrange's equations."""
from __future__ import annotations

import casadi as ca
import numpy as np
import sympy as sp

from flexsym.model.fedata import BeamBody, PointMass, Section, body_mode
from flexsym.model.modes import parse_mode_token
from flexsym.physics.exact_body import exact_energies
from flexsym.physics.exact_kinematics import ExactKinematics, Quadrature

INNER, OUTER = Section(7.0e10, 3000.0, 4.0e-4, 2.0e-7), Section(7.0e10, 3000.0, 2.0e-4, 5.0e-8)
TOKENS = ("cf1", "cf2", "cf3")


class Part(ExactKinematics):
    """What exact_energies reads of a system's body (body_kinds.exact.ExactPart), numbers for symbols."""

    def __init__(self, body: BeamBody, quad: Quadrature | None = None):
        self.fe_body = body
        refs = [parse_mode_token("bending", t) for t in TOKENS]
        self.modes = {r.coordinate: body_mode(body, r) for r in refs}
        self.coords = list(self.modes)
        self.groups = {c: "bending" for c in self.coords}
        self.index = list(range(len(self.coords)))
        ref = body.reference
        self.psyms = {sp.Symbol(k): v for k, v in (("L", body.length), ("rho", ref.rho), ("A", ref.A))}
        self.quad = quad or Quadrature(4, 6, self.edges())

    def energies(self, q, qd, frame):
        """(T, V_g) at q, q' with the frame's (omega, V_x, V_y, g_x, g_y, R_x, R_y)."""
        self.frame = frame
        x = {"q": ca.DM(q), "qd": ca.DM(qd)}
        T, V = exact_energies([self], lambda e: ca.DM(float(e)), x)
        return float(T), float(V)


STATE = (np.array([0.8, -0.05, 0.01]), np.array([0.3, -0.2, 0.1]), (2.0, 0.7, -0.4, 1.5, -9.81, 0.3, 0.2))


def test_a_rule_in_pieces_is_the_rule_with_the_same_nodes():
    """A uniform beam integrated over two pieces of n segments (the edges of a stepped beam)
    or one of 2n: the same nodes, so T, V_g and a point's position agree to round-off."""
    body = BeamBody.from_segments([(10.0, INNER)], 20)
    one, two = Quadrature(8, 6), Quadrature(4, 6, (0.0, 0.5, 1.0))
    assert np.abs(one.nodes - two.nodes).max() < 1e-15 and np.abs(one.weights - two.weights).max() < 1e-16
    a, b = Part(body, one).energies(*STATE), Part(body, two).energies(*STATE)
    assert abs(a[0] - b[0]) <= 1e-13 * abs(a[0]) and abs(a[1] - b[1]) <= 1e-13 * abs(a[1])
    for at in (0.3, 0.5, 0.77):
        assert np.abs(one.weights_between(0.0, at) - two.weights_between(0.0, at)).max() < 1e-15


def test_sections_and_a_point_mass_in_the_kinetic_energy():
    """Undeformed (q = 0) in a frame turning at omega with origin velocity V: T is
    1/2 int rho A(x) |V + omega z x x|^2 dx + 1/2 m |V + omega z x L|^2, by hand, and V_g
    is -g.(m_total R + first moment); the stepped body's rule breaks at its nodes (its step
    among them: the modes are polynomials per element)."""
    body = BeamBody.from_segments([(5.0, INNER), (5.0, OUTER)], 10, (PointMass(10.0, 0.5),))
    part = Part(body)
    assert part.edges() == tuple(k / 10 for k in range(11)) and part.point_masses() == [(1.0, 0.5 / (3000.0 * 4e-4 * 10.0))]
    om, Vx, Vy, gx, gy, Rx, Ry = STATE[2]
    T, V = part.energies(np.zeros(3), np.zeros(3), STATE[2])

    def seg(mu, a, b):  # int_a^b mu ((Vx)^2 + (Vy + om x)^2) dx and int_a^b mu x dx
        F = lambda x: Vx**2 * x + (Vy + om * x)**3 / (3 * om)  # noqa: E731
        return mu * (F(b) - F(a)), mu * (b * b - a * a) / 2
    (e1, m1), (e2, m2) = seg(1.2, 0.0, 5.0), seg(0.6, 5.0, 10.0)
    T_hand = 0.5 * (e1 + e2 + 0.5 * (Vx**2 + (Vy + om * 10.0)**2))
    V_hand = -(gx * Rx + gy * Ry) * (1.2 * 5 + 0.6 * 5 + 0.5) - gx * (m1 + m2 + 0.5 * 10.0)
    assert abs(T - T_hand) <= 1e-13 * T_hand and abs(V - V_hand) <= 1e-13 * abs(V_hand)


def test_the_point_mass_is_at_the_integrated_tip():
    """Deformed, the point mass's row of the positions (the integral of the unit tangent to
    s = 1 by the per-segment weights) is the beam's tip from the cumulative rule."""
    body = BeamBody.from_segments([(5.0, INNER), (5.0, OUTER)], 10, (PointMass(10.0, 0.5),))
    part = Part(body)
    q = ca.DM([2.0, -0.3, 0.1])
    k = part.beam_kinematics(part.quad, q, ca.DM([0.1, 0.2, 0.3]), 10.0)
    tip, point = np.array(ca.evalf(k["tip"])).ravel(), np.array(ca.evalf(k["r"][-1, :])).ravel()
    assert k["r"].shape[0] == part.quad.size + 1
    assert np.abs(tip - point).max() <= 1e-13 * 10.0 and tip[1] > 1.0  # it deflects, a lot


def test_at_rest_the_mass_matrix_is_the_modes_mass_normalisation():
    """Undeformed and at rest, the exact body's mass matrix d2T/dq'2 is rho A L of the root
    section times the modes' Gram matrix in the finite-element data's consistent mass, which
    holds the sections and the tip mass (fedata: mass-normalised modes, so the identity): an
    independent route to the same numbers. A segment per element (10 per piece) integrates the
    piecewise polynomials exactly, so they agree to round-off."""
    body = BeamBody.from_segments([(5.0, INNER), (5.0, OUTER)], 20, (PointMass(10.0, 0.5),))
    part = Part(body, Quadrature(10, 6, (0.0, 0.5, 1.0)))
    qd = ca.SX.sym("qd", 3)
    part.frame = (0.0,) * 7
    T, _ = exact_energies([part], lambda e: ca.DM(float(e)), {"q": ca.DM.zeros(3), "qd": qd})
    M = np.array(ca.evalf(ca.hessian(T, qd)[0]))
    assert np.abs(M / (3000.0 * 4e-4 * 10.0) - np.eye(3)).max() < 1e-11
