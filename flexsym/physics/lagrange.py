"""Lagrange's equations of motion, written once for every model (one-beam variants and systems).

Unknowns q with rates q'; known guided coordinates x_k(t) with their rates and accelerations
(a one-beam variant's hub angle theta, whose rate w and acceleration alpha are inputs; a
system's guided joints theta_k). With p = dT/dq' and the generalised forces Q,

    d/dt dT/dq' - dT/dq = Q   gives   M q'' = f,   M = dp/dq',
    f = dT/dq - (dp/dq) q' - sum_k (dp/dx_k x_k' + dp/dx_k' x_k'') + Q.

M is never inverted symbolically: the C runtime solves with it. `equations_of_motion` works on
sympy expressions (modal beams, rigid bodies); `equations_of_motion_sx` is the same formula on
a casadi T (the exact kinematics' quadrature, where it checks d'Alembert's form).
"""
from __future__ import annotations

import casadi as ca
import sympy as sp


def equations_of_motion(T: sp.Expr, Q: sp.Matrix, q: sp.Matrix, qd: sp.Matrix,
                        guided=()) -> tuple[sp.Matrix, sp.Matrix]:
    """(M, f), expanded. guided: (x, x', x'') symbols of each guided coordinate; x is None
    when T does not read the coordinate itself (a one-beam T reads only the hub rate)."""
    p = sp.Matrix([sp.diff(T, x) for x in qd])
    M = p.jacobian(qd).applyfunc(sp.expand)
    f = sp.Matrix([sp.diff(T, x) for x in q]) - p.jacobian(q) * qd + Q
    for x, xd, xdd in guided:
        if x is not None:
            f -= p.diff(x) * xd
        f -= p.diff(xd) * xdd
    return M, f.applyfunc(sp.expand)


def equations_of_motion_sx(T, Q, q, qd, guided=()):
    """`equations_of_motion` on casadi SX: (M, f) with guided = [(x or None, x', x'')]."""
    M, p = ca.hessian(T, qd)
    f = ca.gradient(T, q) - ca.jtimes(p, q, qd) + Q
    for x, xd, xdd in guided:
        if x is not None:
            f -= ca.jacobian(p, x) * xd
        f -= ca.jacobian(p, xd) * xdd
    return M, f


def generalized_force(V: sp.Expr, q: sp.Matrix, acts) -> sp.Matrix:
    """Q_i = -dV/dq_i on the coordinates where acts[i] (a strain model's `wrt` groups), else 0."""
    return sp.Matrix([-sp.diff(V, x) if a else 0 for x, a in zip(q, acts)])


def jacobi_integral(T: sp.Expr, M: sp.Matrix, qd: sp.Matrix, V: sp.Expr) -> sp.Expr:
    """h = T2 - T0 + V (T2 = q'^T M q' / 2, T0 = T at q' = 0): conserved when the guided
    coordinates move at constant rate (or nothing is guided) and every force derives from V."""
    T0 = T.xreplace({x: 0 for x in qd})
    T2 = sp.expand((qd.T * M * qd)[0, 0] / 2)
    return T2 - T0 + V
