"""The modal beam with exact kinematics (strain model `exact`).

The deformation is carried by two modal fields along the beam (s = x/L):

    section rotation  phi(s) = sum_k xi_k Phi_k'(s) / L     (bending modes: their slopes)
    axial stretch     eps(s) = sum_j eta_j Phi_j'(s) / L    (axial modes: their strains;
                                                             none = inextensible, eps = 0)

and positions in the moving frame follow without approximation,

    r(s) = L int_0^s (1 + eps) (cos phi, sin phi) ds',

so at small deflection v = int phi dx reproduces the bending modes (the coordinates keep
their meaning: xi_k is the amplitude of mode k in metres) and adding modes converges to
the geometrically exact (Kirchhoff) rod. Energies:

    T = 1/2 rho A L int_0^1 |r' + w z x r|^2 ds        (r' the velocity in the moving frame)
    V = 1/2 int (EA eps^2 + EI (dphi/dx)^2) dx          (material curvature per reference length)

V is quadratic in the coordinates: it is the linear model's strain energy, so sympy derives it
with the modal integrals (energy.py terms 'stretch' and 'curvature'). T has trigonometric
functions of the fields inside cumulative integrals: it is built here as a casadi expression
over composite Gauss-Legendre points (n_seg segments of M_POINTS points; on each segment a
spectral integration matrix gives int from the segment start to each point of the
polynomial through the point values, and segment ends accumulate). M = d2T/dq'2 and
f = dT/dq - (d2T/dq'dq) q' - (d2T/dq'dw) alpha - dV/dq follow by casadi AD.

The number of segments is chosen at generation time by doubling until M, f and the energies
at a large-deflection test state (section rotation up to 1.5 rad, mode k carrying a share
~ 1/k^2) change by less than QUAD_RTOL relative (the finer rule being the judge); it is
recorded in the manifest. `exact_study` re-checks the chosen rule against a 4x finer one at
the states of every run.
"""
from __future__ import annotations

import casadi as ca
import numpy as np
import sympy as sp

from flexsym.physics.energy import ENERGY_TERMS, alpha, build_fields, w
from flexsym.core.errors import FlexsymError
from flexsym.physics.integrals import IntegralTable
from flexsym.physics.exact_kinematics import (M_POINTS, MAX_SEGMENTS, QUAD_RTOL, ExactKinematics,
                                             Quadrature, _test_state)
from flexsym.emit.kernels import translator
from flexsym.physics.lagrange import equations_of_motion_sx, generalized_force
from flexsym.model.maneuver import maneuver_of
from flexsym.physics.modal import Derivation, DerivedTerm
from flexsym.model.output_names import point_of
from flexsym.physics.outputs import output_expression
from flexsym.model.strain_models import STRAIN_MODELS


class ExactDerivation(ExactKinematics, Derivation):
    """A Derivation whose T, M, f and kinematic outputs live in casadi (quadrature), V in sympy."""

    exact = True
    quadrature: Quadrature = None

    @property
    def mass_constant(self) -> bool:
        return False

    @property
    def outputs_use_acceleration(self) -> bool:
        return any(self._exact_output(n) and n[0] in "NM" for n in self.spec.outputs)

    @property
    def integrals(self) -> list[sp.Symbol]:
        return self.table.symbols  # V's and the sympy outputs' (T, M, f are quadratures)

    @property
    def outputs_use_drive(self) -> bool:
        """Equilibrium N and M read the frame's motion; v_tip, u_tip and EI dphi/dx do not."""
        return any(n[0] in "NM" if e is None else e.has(w, alpha) for n, e in self.outputs.items())

    @property
    def conservative(self) -> bool:
        return True

    def energies(self):
        raise FlexsymError("the exact model's kinetic energy is a quadrature (casadi), not a sympy "
                           "expression: use its energy kernel")

    def stiffness_split(self):
        raise FlexsymError("the exact model's stiffness is not split into K_L and K_G")

    def _exact_output(self, name: str) -> bool:
        """Outputs from the exact kinematics; the others (M = EI dphi/dx, N = EA eps) are sympy."""
        return (name in ("v_tip", "u_tip") or (name[0] == "N" and self.spec.axial_force == "equilibrium")
                or (name[0] == "M" and self.spec.moment == "equilibrium"))

    def kinematics(self, quad: Quadrature, x: dict) -> dict:
        return self.beam_kinematics(quad, x["q"], x["qd"], x["p"][4])

    def _frame_acceleration(self, quad: Quadrature, k: dict, gdd, drive, L):
        """Absolute acceleration in moving-frame components: r'' + 2w z x r' + alpha z x r - w^2 r
        (gdd: the q'' part of the integrand of r'', None to leave it out)."""
        return self.acceleration(quad, k, gdd, drive[0], drive[1] if self.maneuver.accelerates else None, L)

    def mass_matrix(self, quad: Quadrature, k: dict, p):
        n = len(self.coords)
        J, _ = self._cumulative(quad, ca.horzcat(*k["cols"]), k["scale"])  # N x 2n
        W = ca.DM(quad.weights)
        Jx = [J[:, 2 * i] for i in range(n)]
        Jy = [J[:, 2 * i + 1] for i in range(n)]
        M = ca.SX.zeros(n, n)
        for i in range(n):
            for j in range(i + 1):
                M[i, j] = ca.dot(W, Jx[i] * Jx[j] + Jy[i] * Jy[j])
                M[j, i] = M[i, j]
        return p[0] * p[2] * p[4] * M

    def equations(self, quad: Quadrature, x: dict, V):
        """M, f and [T, V, h] by d'Alembert's principle on the quadrature points:
        M q'' = -sum_i m_i J_i^T (J_i' q' + 2w z x r_i' + alpha z x r_i - w^2 r_i) - dV/dq,
        the same equations as Lagrange's (lagrange_equations, the test's cross-check)."""
        q, qd, drive, p = x["q"], x["qd"], x["drive"], x["p"]
        k = self.kinematics(quad, x)
        acc = self._frame_acceleration(quad, k, None, drive, p[4])
        F = p[0] * p[2] * p[4] * acc * ca.repmat(ca.DM(quad.weights), 1, 2)
        Ft = self._cumulative_transpose(quad, F, k["scale"])  # N x 2
        f = -ca.vertcat(*[ca.sum1(ca.sum2(col * Ft)) for col in k["cols"]]) - ca.gradient(V, q)
        M = self.mass_matrix(quad, k, p)
        v = k["rd"] + drive[0] * ca.horzcat(-k["r"][:, 1], k["r"][:, 0])
        W = ca.DM(quad.weights)
        T = 0.5 * p[0] * p[2] * p[4] * ca.dot(W, ca.sum2(v * v))
        T0 = 0.5 * p[0] * p[2] * p[4] * drive[0]**2 * ca.dot(W, ca.sum2(k["r"] * k["r"]))
        h = 0.5 * ca.dot(qd, ca.mtimes(M, qd)) - T0 + V
        return M, f, ca.vertcat(T, V, h)

    def residual(self, quad: Quadrature, x: dict, V):
        """r = M q'' - f in one pass: sum_i m_i J_i^T a_i (with a_i the full acceleration,
        q'' included) + dV/dq. Equal to M q'' - f, without forming M: its Jacobians (the
        Newton matrices) cost half as much as differentiating M q'' - f."""
        q, qdd, drive, p = x["q"], x["qdd"], x["drive"], x["p"]
        k = self.kinematics(quad, x)
        phidd, epsdd = self._fields(quad, qdd, p[4])
        gdd = k["t"] * ca.repmat(epsdd, 1, 2) + k["n"] * ca.repmat(k["a"] * phidd, 1, 2)
        acc = self._frame_acceleration(quad, k, gdd, drive, p[4])
        F = p[0] * p[2] * p[4] * acc * ca.repmat(ca.DM(quad.weights), 1, 2)
        Ft = self._cumulative_transpose(quad, F, k["scale"])
        return ca.vertcat(*[ca.sum1(ca.sum2(col * Ft)) for col in k["cols"]]) + ca.gradient(V, q)

    def lagrange_equations(self, quad: Quadrature, x: dict, V):
        """M = d2T/dq'2 and f from Lagrange's equations (lagrange.py) by casadi AD of T (an
        independent route to the same equations, used by the tests)."""
        q, qd, drive, p = x["q"], x["qd"], x["drive"], x["p"]
        k = self.kinematics(quad, x)
        v = k["rd"] + drive[0] * ca.horzcat(-k["r"][:, 1], k["r"][:, 0])
        T = 0.5 * p[0] * p[2] * p[4] * ca.dot(ca.DM(quad.weights), ca.sum2(v * v))
        M, f = equations_of_motion_sx(T, -ca.gradient(V, q), q, qd, [(None, drive[0], drive[1])])
        if not self.maneuver.accelerates:
            f = ca.substitute(f, drive[1], 0)
        return M, f

    def exact_output(self, quad: Quadrature, name: str, x: dict):
        q, qdd, drive, p = x["q"], x["qdd"], x["drive"], x["p"]
        k = self.kinematics(quad, x)
        if name == "v_tip":
            return k["tip"][1]
        if name == "u_tip":
            return k["tip"][0] - p[4]
        # The part beyond x is moved by the inertial loads alone (a: absolute acceleration in
        # moving-frame components), so the section at x carries
        #   N(x) = -rho A int_x^L a dx . t(x)              (along the axis at x)
        #   M(x) = -rho A int_x^L (r - r(x)) x a dx       (EI kappa sign: tip load +y gives M > 0)
        at = float(point_of(name, self.spec.points)[1])
        phidd, epsdd = self._fields(quad, qdd, p[4])
        gdd = k["t"] * ca.repmat(epsdd, 1, 2) + k["n"] * ca.repmat(k["a"] * phidd, 1, 2)
        acc = self._frame_acceleration(quad, k, gdd, drive, p[4])
        wb = ca.DM(quad.weights_between(at, 1.0))
        if name[0] == "M":
            g = k["t"] * ca.repmat(k["a"], 1, 2)
            r_at = p[4] * ca.mtimes(ca.DM(quad.weights_between(0.0, at)).T, g)  # 1 x 2
            arm = k["r"] - ca.repmat(r_at, quad.size, 1)
            moment = arm[:, 0] * acc[:, 1] - arm[:, 1] * acc[:, 0]
            return -p[0] * p[2] * p[4] * ca.dot(wb, moment)
        phi_at, _ = self._fields(quad, q, p[4], at=[at])
        Fx, Fy = p[4] * ca.dot(wb, acc[:, 0]), p[4] * ca.dot(wb, acc[:, 1])
        return -p[0] * p[2] * (Fx * ca.cos(phi_at[0]) + Fy * ca.sin(phi_at[0]))


def _prepare(spec) -> "ExactDerivation":
    """Modes, fields and the energy terms (sympy, quadratic: the linear model's strain energy)
    with their generalised forces Q. `spec` is validated (derive.derive)."""
    if spec.body is not None:  # scene._spec refuses it; its sections would be taken as uniform
        raise FlexsymError("the exact kinematics on the guided hub integrates a uniform beam")
    strain = STRAIN_MODELS[spec.strain]
    maneuver = maneuver_of(spec.maneuver)
    modes = {r.coordinate: spec.mode(r) for r in spec.modes}
    groups = {r.coordinate: r.axis for r in spec.modes}
    names = list(modes)
    q = sp.Matrix([sp.Symbol(n, real=True) for n in names])
    qd = sp.Matrix([sp.Symbol(n + "_d", real=True) for n in names])
    qdd = sp.Matrix([sp.Symbol(n + "_dd", real=True) for n in names])
    qmap, qdmap, qddmap = dict(zip(names, q)), dict(zip(names, qd)), dict(zip(names, qdd))

    table = IntegralTable(modes)  # a uniform beam (spec.validate refuses a [body])
    axial = [modes[r.coordinate] for r in spec.axial]
    bending = [modes[r.coordinate] for r in spec.bending]
    fields = build_fields(axial, bending, qmap, qdmap, table, strain.foreshortening, qddmap)
    der = ExactDerivation(spec, strain, maneuver, modes, groups, q, qd, qdd, table, fields)

    Q = sp.zeros(len(names), 1)
    for term_name, wrt in strain.terms:
        term = ENERGY_TERMS[term_name]
        V = table.integrate(term.density(fields))
        Qk = generalized_force(V, q, [groups[n] in wrt for n in names]).applyfunc(sp.expand)
        der.terms.append(DerivedTerm(term_name, term.formula, wrt, V, Qk))
        Q += Qk
    der.Q = Q
    return der


def derive_exact(spec) -> ExactDerivation:
    """Modes, fields and V (_prepare); then the sympy outputs, the quadrature choice, and T as
    a placeholder (T, M, f live in casadi: equations())."""
    der = _prepare(spec)
    der.T = sp.Symbol("T_quadrature")
    der.outputs = {n: (None if der._exact_output(n) else output_expression(der, n))
                   for n in der.spec.outputs}
    der.quadrature = choose_quadrature(der)
    if not der.maneuver.accelerates:
        der.dropped.append({"what": "theta'' (alpha) terms",
                            "why": f"manoeuvre '{der.maneuver.name}' has theta'' = 0 identically"})
    return der


def continuous_formulas() -> dict[str, str]:
    return {
        "section rotation": "phi(s) = sum_k xi_k Phi_k'(s) / L   (bending modes)",
        "axial stretch": "eps(s) = sum_j eta_j Phi_j'(s) / L   (axial modes; none: inextensible)",
        "position": "r(s) = L int_0^s (1 + eps) (cos phi, sin phi) ds'   (moving frame, exact)",
        "kinetic energy": "T = 1/2 rho A L int_0^1 |r' + w z x r|^2 ds",
        "strain energy": "V = 1/2 int (EA eps^2 + EI (dphi/dx)^2) dx",
        "stresses": "N = EA eps or, from equilibrium, -rho A int_x^L a dx . t(x);  M = EI dphi/dx "
                    "or, from equilibrium, -rho A int_x^L (r - r(x)) x a dx",
    }


def _symbolic_inputs(der):
    return translator(der.q, der.qd, der.qdd, der.params, der.maneuver, (w, alpha))


def _potential(der, tr):
    V = sp.Add(*[t.V for t in der.terms])
    return tr(der.numeric(sp.expand(V)))


def choose_quadrature(der) -> Quadrature:
    tr, x = _symbolic_inputs(der)
    V = _potential(der, tr)
    q, qd, drive, p = _test_state(der)

    def evaluate(quad):
        M, f, en = der.equations(quad, x, V)
        fn = ca.Function("check", [x["q"], x["qd"], x["drive"], x["p"]], [M, f, en])
        return [np.array(v.full()).ravel() for v in fn(q, qd, drive, p)]

    n_seg = 2  # B (x = L/2) is a segment end
    prev = evaluate(Quadrature(n_seg, M_POINTS))
    while n_seg < MAX_SEGMENTS:
        cur = evaluate(Quadrature(2 * n_seg, M_POINTS))
        change = max(np.max(np.abs(a - b)) / np.max(np.abs(b)) for a, b in zip(prev, cur))
        if change < QUAD_RTOL:
            return Quadrature(n_seg, M_POINTS)
        n_seg, prev = 2 * n_seg, cur
    raise FlexsymError(f"exact kinematics: the quadrature did not reach {QUAD_RTOL:g} with "
                       f"{MAX_SEGMENTS} segments (too many or too high modes)")


def quadrature_error(der: ExactDerivation, q_rows, qd_rows, drive_rows, p, finer: int = 4) -> float:
    """Largest relative change of M and of the inertial part of f (what the quadrature
    computes; the elastic part is exact) at the given states when the rule is `finer` times
    finer: the quadrature's error on the states a run visited."""
    _, x = _symbolic_inputs(der)
    V = ca.SX(0)
    fns = []
    for quad in (der.quadrature, Quadrature(der.quadrature.n_seg * finer, der.quadrature.m)):
        M, f, _ = der.equations(quad, x, V)
        fns.append(ca.Function("mf", [x["q"], x["qd"], x["drive"], x["p"]], [M, f]))
    worst = 0.0
    for q, qd, dr in zip(q_rows, qd_rows, drive_rows):
        a = [np.array(v.full()) for v in fns[0](q, qd, dr, p)]
        b = [np.array(v.full()) for v in fns[1](q, qd, dr, p)]
        worst = max(worst, *(np.max(np.abs(u - v)) / np.max(np.abs(v)) for u, v in zip(a, b)
                             if np.max(np.abs(v)) > 0))
    return worst


