"""Kinematics of the beam in the moving frame and energy densities.

Densities are written per unit s = x/L (so an energy is int_0^1 density ds), in terms of
factor placeholders from the IntegralTable; derivatives along the beam are d/dx = (1/L) d/ds.
Which term is differentiated with respect to which coordinate group is the strain model's
choice (strain_models.py).
"""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from flexsym.physics.integrals import IntegralTable
from flexsym.model.modes import Mode, s
from flexsym.model.parameters import BEAM_PARAMS

rho, E, A, I, L = (p.symbol for p in BEAM_PARAMS)
w, alpha = sp.symbols("w alpha", real=True)  # theta' and theta'' (known inputs)


@dataclass
class Fields:
    """Displacement fields along the beam as polynomials in placeholders and coordinates."""

    u: sp.Expr  # axial displacement u_o(s)
    u_dot: sp.Expr
    u_ddot: sp.Expr
    u_stretch: sp.Expr  # the axial-mode part of u (the stretch: the strain-energy field)
    u_stretch_s: sp.Expr  # its d/ds
    v: sp.Expr  # transverse displacement v_o(s)
    v_dot: sp.Expr
    v_s: sp.Expr
    v_ss: sp.Expr
    v_dot_s: sp.Expr = sp.Integer(0)  # d/ds of the transverse velocity (rotary inertia)
    v_ddot: sp.Expr = sp.Integer(0)  # transverse acceleration (moment from equilibrium)
    v_ddot_s: sp.Expr = sp.Integer(0)
    weights: dict = None  # section distributions mu, ea, ei, nhat, rot (IntegralTable.weight)


def build_fields(axial: list[Mode], bending: list[Mode], q: dict, qd: dict,
                 table: IntegralTable, foreshortening: bool, qdd: dict | None = None) -> Fields:
    mv = table.mode_value
    qdd = qdd or {k: 0 for k in q}
    u = sum((mv(m.name) * q[m.name] for m in axial), sp.Integer(0))
    u_stretch = u
    u_dot = sum((mv(m.name) * qd[m.name] for m in axial), sp.Integer(0))
    u_ddot = sum((mv(m.name) * qdd[m.name] for m in axial), sp.Integer(0))
    u_s = sum((mv(m.name, 1) * q[m.name] for m in axial), sp.Integer(0))
    v = sum((mv(m.name) * q[m.name] for m in bending), sp.Integer(0))
    v_dot = sum((mv(m.name) * qd[m.name] for m in bending), sp.Integer(0))
    v_s = sum((mv(m.name, 1) * q[m.name] for m in bending), sp.Integer(0))
    v_ss = sum((mv(m.name, 2) * q[m.name] for m in bending), sp.Integer(0))
    if foreshortening:
        # eq. (30): u_fs(x) = -1/2 int_0^x (v_x)^2 dx = -1/(2L) sum_ij H_ij(s) q_i q_j
        for mi in bending:
            for mj in bending:
                h = table.fs_value(mi.name, mj.name)
                u += -h * q[mi.name] * q[mj.name] / (2 * L)
                u_dot += -h * q[mi.name] * qd[mj.name] / L
                u_ddot += -h * (qd[mi.name] * qd[mj.name] + q[mi.name] * qdd[mj.name]) / L
    v_dot_s = sum((mv(m.name, 1) * qd[m.name] for m in bending), sp.Integer(0))
    weights = {k: table.weight(k) for k in ("mu", "ea", "ei", "nhat", "rot")}
    v_ddot = sum((mv(m.name) * qdd[m.name] for m in bending), sp.Integer(0))
    v_ddot_s = sum((mv(m.name, 1) * qdd[m.name] for m in bending), sp.Integer(0))
    return Fields(u, u_dot, u_ddot, u_stretch, u_s, v, v_dot, v_s, v_ss, v_dot_s, v_ddot, v_ddot_s,
                  weights)


@dataclass(frozen=True)
class FrameMotion:
    """The floating frame's motion, in the frame's own components: rate omega = phi' and the
    velocity (Vx, Vy) = A(phi)^T R' of its origin. The guided hub of a one-beam variant is
    FrameMotion(w): a frame turning about a fixed point."""

    omega: sp.Expr
    Vx: sp.Expr = sp.Integer(0)
    Vy: sp.Expr = sp.Integer(0)


def kinetic_density(f: Fields, frame: FrameMotion = FrameMotion(w)) -> sp.Expr:
    """T per unit s: 1/2 rho A L mu [(Vx + u' - omega v)^2 + (Vy + v' + omega (x + u))^2],
    velocities in the moving frame (mu = 1 for the uniform beam), plus 1/2 J (omega + v'_x)^2
    of point rotary inertias."""
    mu, rot, om = f.weights["mu"], f.weights["rot"], frame.omega
    T = rho * A * L / 2 * mu * ((frame.Vx + f.u_dot - om * f.v)**2
                                + (frame.Vy + f.v_dot + om * (L * s + f.u))**2)
    if rot != 0:
        T += rho * A * L**3 / 2 * rot * (om + f.v_dot_s / L)**2
    return T


def gravity_density(f: Fields, gx: sp.Expr, gy: sp.Expr) -> sp.Expr:
    """-rho A L mu g.r per unit s for the part of r in the frame, (x + u, v); (gx, gy) = A^T g
    (the frame origin's part, -m g.R, is added by the caller)."""
    return -rho * A * L * f.weights["mu"] * (gx * (L * s + f.u) + gy * f.v)


def momentum_density(f: Fields, frame: FrameMotion, Rx: sp.Expr, Ry: sp.Expr) -> sp.Expr:
    """Angular momentum about the ground origin per unit s, in frame components (a rotation
    keeps the planar cross product): (R + r) x (V + r' + omega k x r), R = (Rx, Ry) = A^T R,
    plus the point rotary inertias' J (omega + v'_x)."""
    om = frame.omega
    px, py = Rx + L * s + f.u, Ry + f.v
    vx, vy = frame.Vx + f.u_dot - om * f.v, frame.Vy + f.v_dot + om * (L * s + f.u)
    h = rho * A * L * f.weights["mu"] * (px * vy - py * vx)
    rot = f.weights["rot"]
    if rot != 0:
        h += rho * A * L**3 * rot * (om + f.v_dot_s / L)
    return h


@dataclass(frozen=True)
class EnergyTerm:
    name: str
    formula: str  # the term as written in the paper / benchmark note
    density: object  # Fields -> sp.Expr, per unit s


ENERGY_TERMS: dict[str, EnergyTerm] = {t.name: t for t in (
    EnergyTerm("axial", "EA/2 int (u_x)^2 dx",
               lambda f: E * A / (2 * L) * f.weights["ea"] * f.u_stretch_s**2),
    EnergyTerm("bending", "EI/2 int (v_xx)^2 dx",
               lambda f: E * I / (2 * L**3) * f.weights["ei"] * f.v_ss**2),
    EnergyTerm("cubic", "EA/2 int u_x (v_x)^2 dx",
               lambda f: E * A / (2 * L**2) * f.weights["ea"] * f.u_stretch_s * f.v_s**2),
    EnergyTerm("quartic", "EA/8 int (v_x)^4 dx",
               lambda f: E * A / (8 * L**3) * f.weights["ea"] * f.v_s**4),
    EnergyTerm("prestress", "1/2 int N(x) (v_x)^2 dx, N = rho A w^2 (L^2 - x^2)/2 (a body: "
               "N = w^2 [int_x^L rho A x dx + m_tip L])",
               lambda f: rho * A * w**2 * L / 4 * f.weights["nhat"] * f.v_s**2),
    # exact kinematics (exact.py, uniform beams only): the same quadratic forms, read as
    # eps = u_x, dphi/dx = v_xx
    EnergyTerm("stretch", "EA/2 int eps^2 dx, eps = sum eta_j Phi_j'/L (exact)",
               lambda f: E * A / (2 * L) * f.weights["ea"] * f.u_stretch_s**2),
    EnergyTerm("curvature", "EI/2 int (dphi/dx)^2 dx, phi = sum xi_k Phi_k'/L (exact)",
               lambda f: E * I / (2 * L**3) * f.weights["ei"] * f.v_ss**2),
)}
