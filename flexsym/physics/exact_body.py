"""A beam with exact kinematics (strain model `exact`, physics/exact.py) as a body of a planar
system, its floating frame moved by the system (physics/body_kinds/exact.ExactPart).

Its strain energy is the modal beam's (quadratic: sympy, as every modal body's). What the exact
kinematics changes lives in casadi, over the beam's composite Gauss rule (exact.Quadrature):

    r(s) = L int_0^s (1 + eps) (cos phi, sin phi) ds'                 (frame components)
    T    = 1/2 rho A L int_0^1 |r' + omega z x r + V|^2 ds              (omega, V: the frame's)
    V_g  = -rho A L int_0^1 g . (R + r) ds                              (R: the frame's origin)

A beam from finite-element data (ExactKinematics.fe_body) has rho A (s) in place of rho A
(constant on each piece of its rule) and adds sum_k m_k (1/2 |v(s_k)|^2 - g . (R + r(s_k)))
for its point masses, which then take their share of the d'Alembert loads and section loads.

T and V_g join the system's automatic-differentiation path (sysgen.build_system_kernels), and
a position r(x) on the beam (a marker, an output, a cut joint's row) is a placeholder in sympy
whose casadi value sysgen substitutes: a plain symbol, which sympy never differentiates, when
only casadi differentiates r(x) (a cut joint's rows, outputs); an applied function r(q_b) of
the beam's coordinates when sympy does (body_kinds/exact.differentiated: a body hangs from the
beam, a force or a spring acts on it beyond its root). Then sympy's derivatives of it,
Derivative(r(q_b), q_i, ...), are casadi's of the quadrature value (sysgen.placeholder_values),
and the terms of T that read r(x) (the hanging bodies', through their pose) are left to casadi
as the beam's own T (assemble: der.T_casadi): Lagrange on them by AD, their part of the
one-pass residual d/dt dT/dq' - dT/dq by one forward sweep. Generalised forces (a force's
F . dr/dq, a spring's -dV/dq, gravity's on the hanging bodies) and the reactions in the
section loads stay sympy's, with first and second derivatives of r(x) as placeholders.
"""
from __future__ import annotations

import casadi as ca
import numpy as np
import sympy as sp

from flexsym.core.errors import FlexsymError
from flexsym.model.exact_numbers import exact
from flexsym.physics.exact_kinematics import M_POINTS, MAX_SEGMENTS, QUAD_RTOL, Quadrature, _test_state

# Placeholder of the exact beams' gravity potential V_g in the output V (sysgen's casadi value)
EXACT_VG = sp.Symbol("V_exact_", real=True)


def body_quadrature(part) -> Quadrature:
    """The composite rule, segments doubled until the beam's first moment, mass matrix and
    kinetic energy in a spinning, translating frame change by less than QUAD_RTOL at
    exact.py's large-deflection test state (section rotation up to 1.5 rad), the finer rule
    judging: the one-beam rule's test (exact.choose_quadrature) on what a system body uses."""
    q, qd, _, p = _test_state(part)
    L = p[4]
    qs, qds = ca.SX.sym("q", len(q)), ca.SX.sym("qd", len(q))

    def evaluate(quad):
        k = part.beam_kinematics(quad, qs, qds, L)
        W = ca.DM(part.mass_weights(quad))
        v = k["rd"] + 6.0 * ca.horzcat(-k["r"][:, 1], k["r"][:, 0]) + ca.repmat(ca.DM([[0.7, -0.4]]), W.shape[0], 1)
        T = 0.5 * ca.dot(W, ca.sum2(v * v))
        fn = ca.Function("check", [qs, qds], [ca.mtimes(W.T, k["r"]).T, T, ca.vec(ca.hessian(T, qds)[0])])
        return [np.array(v.full()).ravel() for v in fn(q, qd)]

    def change(a, b):  # each quantity against its own size (T would hide M's error)
        return max(np.max(np.abs(x - y)) / np.max(np.abs(y)) for x, y in zip(a, b))

    edges = part.edges()
    n_seg = 2 if len(edges) == 2 else 1  # a uniform beam: B (x = L/2) a segment end
    prev = evaluate(Quadrature(n_seg, M_POINTS, edges))
    while n_seg < MAX_SEGMENTS:
        cur = evaluate(Quadrature(2 * n_seg, M_POINTS, edges))
        if change(prev, cur) < QUAD_RTOL:
            return Quadrature(n_seg, M_POINTS, edges)
        n_seg, prev = 2 * n_seg, cur
    raise FlexsymError(f"body '{part.beam.name}': exact kinematics: the quadrature did not reach "
                       f"{QUAD_RTOL:g} with {MAX_SEGMENTS} segments (too many or too high modes)")


def _body_vectors(part, tr, x):
    """The body's coordinates and rates (SX, in the order of its modes) and its L, rho A."""
    q = ca.vertcat(*[x["q"][i] for i in part.index])
    qd = ca.vertcat(*[x["qd"][i] for i in part.index])
    P = {k.name: tr(v) for k, v in part.psyms.items()}
    return q, qd, P["L"], P["rho"] * P["A"]


def _point_motion(part, tr, x) -> tuple:
    """(r, v, weights, rho A, L) of a beam's quadrature points and point masses: positions in
    frame components and absolute velocities v = r' + omega z x r + V, linear in q'."""
    q, qd, L, rhoA = _body_vectors(part, tr, x)
    k = part.beam_kinematics(part.quad, q, qd, L)
    om, Vx, Vy = (tr(e) for e in part.frame[:3])
    r = k["r"]
    v = k["rd"] + ca.horzcat(-om * r[:, 1] + Vx, om * r[:, 0] + Vy)
    return r, v, part.mass_weights(part.quad), rhoA, L


def exact_energies(bodies, tr, x) -> tuple:
    """(T, V_g) of the exact beams, casadi, in the system's q, q' (see the module doc)."""
    T, Vg = ca.SX(0.0), ca.SX(0.0)
    for part in bodies:
        r, v, w, rhoA, L = _point_motion(part, tr, x)
        gx, gy, Rx, Ry = (tr(e) for e in part.frame[3:])
        W = ca.DM(w)
        T += 0.5 * rhoA * L * ca.dot(W, ca.sum2(v * v))
        gR = gx * Rx + gy * Ry
        if part.fe_body is not None:  # its mass is not rho A L of the root section
            gR = float(np.sum(w)) * gR
        Vg -= rhoA * L * (ca.dot(W, gx * r[:, 0] + gy * r[:, 1]) + gR)
    return T, Vg


def exact_mass(bodies, tr, x) -> ca.SX:
    """The exact beams' part of M, in the system's q': sum_i m_i J_i^T J_i over the quadrature
    points and point masses, J_i = dv_i/dq' (v_i of exact_energies, linear in q'), one
    triangle filled: d2T/dq'2 of exact_energies' T without differentiating it twice (the
    exact variant's mass 9.3 k -> 6.2 k operations; sysgen takes f from exact_residual)."""
    n = x["qd"].shape[0]
    M = ca.SX.zeros(n, n)
    for part in bodies:
        _, v, w, rhoA, L = _point_motion(part, tr, x)
        W = ca.DM(w)
        Jx, Jy = ca.jacobian(v[:, 0], x["qd"]), ca.jacobian(v[:, 1], x["qd"])
        for i in range(n):
            for j in range(i + 1):
                e = rhoA * L * ca.dot(W, Jx[:, i] * Jx[:, j] + Jy[:, i] * Jy[:, j])
                M[i, j] += e
                if i != j:
                    M[j, i] += e
    return M


def position_symbols(part, outputs: dict, x: float, args=None) -> tuple:
    """Placeholders for r(x) on the beam (frame components), registered in `outputs` (the
    derivation's casadi_outputs) with their casadi values. With args (the beam's coordinate
    symbols, for a beam whose positions sympy differentiates: a tree joint hangs a body from it,
    a load acts on it beyond its root), applied functions r_c(q_b) instead, registered in
    `outputs` (then the derivation's casadi_functions) by name: sympy's derivatives of them,
    Derivative(r_c(q_b), q_i, ...), are casadi's of the same value (sysgen.placeholder_values)."""
    at = float(exact(x) / exact(part.beam.length))
    names = [f"r{c}_{part.beam.name}_{at!r}_" for c in "xy"]
    if args is not None:
        syms = tuple(sp.Function(n, real=True)(*args) for n in names)
        keys = names
    else:
        syms = keys = tuple(sp.Symbol(n, real=True) for n in names)
    if keys[0] in outputs:
        return syms
    weights = ca.DM(part.quad.weights_between(0.0, at))

    def value(tr, xx, c):
        q, qd, L, _ = _body_vectors(part, tr, xx)
        k = part.beam_kinematics(part.quad, q, qd, L)
        g = k["t"] * ca.repmat(k["a"], 1, 2)
        return L * ca.mtimes(weights.T, g[:, c])
    outputs[keys[0]] = lambda tr, xx: value(tr, xx, 0)
    outputs[keys[1]] = lambda tr, xx: value(tr, xx, 1)
    return syms


def _loads(part, tr, x, ddot):
    """The beam's kinematics at its quadrature points and m_i (a_i - g) per unit weight (N x 2,
    frame components): a_i the absolute acceleration, a_O + alpha z x r_i - omega^2 r_i +
    2 omega z x r_i' + r_i'' (a_O = V' + omega z x V), q'' included; and the frame's omega
    and V (SX)."""
    q, qd, qdd, d = x["q"], x["qd"], x["qdd"], x["d"]
    qb, qbd, L, rhoA = _body_vectors(part, tr, x)
    qbdd = ca.vertcat(*[qdd[i] for i in part.index])
    quad = part.quad
    k = part.beam_kinematics(quad, qb, qbd, L)
    om, Vx, Vy, gx, gy = (tr(e) for e in part.frame[:5])
    V = ca.vertcat(Vx, Vy)

    def rate(e):  # d/dt along the motion, q'' included
        return ca.mtimes(ca.jacobian(e, q), qd) + ca.mtimes(ca.jacobian(e, qd), qdd) \
            + ca.mtimes(ca.jacobian(e, d), ddot)
    alpha, Vd = rate(om), rate(V)
    aO = Vd + om * ca.vertcat(-Vy, Vx)
    phidd, epsdd = part._fields(quad, qbdd, L)
    gdd = k["t"] * ca.repmat(epsdd, 1, 2) + k["n"] * ca.repmat(k["a"] * phidd, 1, 2)
    acc = part.acceleration(quad, k, gdd, om, alpha, L)
    acc = acc + ca.repmat(ca.horzcat(aO[0] - gx, aO[1] - gy), acc.shape[0], 1)
    return k, rhoA * L * acc, om, V, L


def exact_residual(bodies, tr, x, ddot):
    """The exact beams' part of r = M q'' - f by d'Alembert's principle on the quadrature
    points, in the system's q, q', q'': sum_i m_i (a_i - g) . dp_i/dq (_loads), with
    dp_i/dq = J_V + z x r_i J_omega + dr_i/dq (J_V = dV/dq', J_omega = domega/dq': the
    frame's virtual motion). Equal to the Lagrange terms of exact_energies (the tests compare
    their derivatives), at a fraction of the cost of differentiating those: sysgen takes the
    Newton Jacobians from this one, as exact.py does for the guided hub."""
    q, qd = x["q"], x["qd"]
    r_all = ca.SX.zeros(q.shape[0])
    for part in bodies:
        k, mA, om, V, L = _loads(part, tr, x, ddot)
        F = mA * ca.repmat(ca.DM(part.mass_weights(part.quad)), 1, 2)  # N x 2 (and the point masses)
        Ft = part._transpose_with_points(part.quad, F, k["scale"], L)
        elastic = ca.vertcat(*[ca.sum1(ca.sum2(col * Ft)) for col in k["cols"]])
        # sum_i r_i x F_i with r = C g (C: the cumulative integral and its rows at the point
        # masses) is sum_j g_j x (C^T F)_j: the positions r_i are not needed
        g = k["g"]
        moment = ca.sum1(g[:, 0] * Ft[:, 1] - g[:, 1] * Ft[:, 0])
        r_b = ca.mtimes(ca.jacobian(V, qd).T, ca.sum1(F).T) + ca.jacobian(om, qd).T * moment
        for j, i in enumerate(part.index):
            r_b[i] += elastic[j]
        r_all += r_b
    return r_all


def inertial_section_load(part, outputs: dict, x: float, fn: str, closed: bool = False) -> sp.Symbol:
    """A placeholder for what the inertial loads beyond station x give the section there:
    N = -sum m_i (a_i - g) . t(x) (tension > 0), M = -sum (r_i - r(x)) x m_i (a_i - g) (the
    modal beam's signs), over the quadrature weights from x to the tip (a point mass at x with
    them if closed: system.loads_at); the loads on the beam's markers beyond x are added in
    sympy (assemble._equilibrium_stress)."""
    at = float(exact(x) / exact(part.beam.length))
    side = "_left" if closed and at < 1.0 else ""  # (at the tip the only side)
    sym = sp.Symbol(f"{fn}_inertial_{part.beam.name}_{at!r}{side}_", real=True)
    if sym in outputs:
        return sym
    wb = ca.DM(part.mass_weights(part.quad, at, 1.0, closed))
    w0 = ca.DM(part.quad.weights_between(0.0, at))

    def value(tr, xx):
        k, mA, _, _, L = _loads(part, tr, xx, xx["ddot"])
        g = k["t"] * ca.repmat(k["a"], 1, 2)
        r_x = L * ca.mtimes(w0.T, g)  # 1 x 2
        if fn == "N":
            qb = ca.vertcat(*[xx["q"][i] for i in part.index])
            phi, _ = part._fields(part.quad, qb, L, at=[at])
            force = ca.mtimes(wb.T, mA)
            return -(force[0] * ca.cos(phi[0]) + force[1] * ca.sin(phi[0]))
        arm = k["r"] - ca.repmat(r_x, k["r"].shape[0], 1)
        return -ca.dot(wb, arm[:, 0] * mA[:, 1] - arm[:, 1] * mA[:, 0])
    outputs[sym] = value
    return sym
