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

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import mpmath
import numpy as np
import sympy as sp

from flexsym.physics.energy import ENERGY_TERMS, alpha, build_fields, w
from flexsym.core.errors import FlexsymError
from flexsym.physics.integrals import IntegralTable, gauss_legendre
from flexsym.emit.kernels import make_kernels, maneuver_sx, translator
from flexsym.physics.lagrange import equations_of_motion_sx, generalized_force
from flexsym.model.maneuver import maneuver_of
from flexsym.physics.modal import Derivation, DerivedTerm
from flexsym.model.modes import s
from flexsym.model.output_names import point_of
from flexsym.physics.outputs import output_expression
from flexsym.model.strain_models import STRAIN_MODELS

M_POINTS = 6  # Gauss points per segment (cumulative integrals cost m^2 per segment)
QUAD_RTOL = 1e-6  # accuracy check of the quadrature (relative; see choose_quadrature)
MAX_SEGMENTS = 256
TEST_TIP_SLOPE = 1.5  # rad: the test state's largest section rotation (a tip thrown sideways)


@dataclass(frozen=True)
class Quadrature:
    """Composite Gauss-Legendre rule on [0, 1]: n_seg segments of m points."""

    n_seg: int
    m: int

    @property
    def size(self) -> int:
        return self.n_seg * self.m

    @property
    def local(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return _local_rule(self.m)

    @property
    def nodes(self) -> np.ndarray:
        tau = self.local[0]
        return np.concatenate([(k + tau) / self.n_seg for k in range(self.n_seg)])

    @property
    def weights(self) -> np.ndarray:
        return np.tile(self.local[1], self.n_seg) / self.n_seg

    def weights_between(self, a: float, b: float) -> np.ndarray:
        """Weights over all nodes of int_a^b g ds for g interpolated per segment (degree m - 1)."""
        out = np.zeros(self.size)
        tau, _, _ = self.local
        for k in range(self.n_seg):
            lo, hi = max(a * self.n_seg - k, 0.0), min(b * self.n_seg - k, 1.0)
            if hi > lo:
                out[k * self.m:(k + 1) * self.m] = (_lagrange_integrals(tau, hi)
                                                    - _lagrange_integrals(tau, lo)) / self.n_seg
        return out

    def describe(self) -> dict:
        return {"segments": self.n_seg, "points_per_segment": self.m, "points": self.size,
                "rule": "composite Gauss-Legendre with a spectral integration matrix per segment",
                "check": f"M, f and [T, V, h] change by < {QUAD_RTOL:g} relative when the number "
                         f"of segments is doubled, at a test state with section rotation up to "
                         f"{TEST_TIP_SLOPE} rad (mode k's share ~ 1/k^2)"}


@lru_cache(maxsize=None)
def _local_rule(m: int):
    """Nodes, weights and cumulative integration matrix S[a, b] = int_0^tau_a l_b on [0, 1]."""
    xs, ws = gauss_legendre(m)
    tau = np.array([float(x) for x in xs])
    S = np.array([_lagrange_integrals(tau, t) for t in tau])
    return tau, np.array([float(x) for x in ws]), S


def _lagrange_integrals(tau: np.ndarray, t: float) -> np.ndarray:
    """int_0^t l_b(x) dx for the Lagrange basis on the nodes tau (exact polynomial integration)."""
    with mpmath.workdps(40):
        out = []
        for b in range(len(tau)):
            poly = [mpmath.mpf(1)]  # coefficients, lowest degree first
            denom = mpmath.mpf(1)
            for c in range(len(tau)):
                if c != b:
                    poly = [(poly[i - 1] if i else 0) - tau[c] * (poly[i] if i < len(poly) else 0)
                            for i in range(len(poly) + 1)]
                    denom *= tau[b] - tau[c]
            out.append(float(sum(cf * mpmath.mpf(t)**(i + 1) / (i + 1)
                                 for i, cf in enumerate(poly)) / denom))
    return np.array(out)


def _shape_derivative(mode, order: int, at: np.ndarray) -> np.ndarray:
    fn = sp.lambdify(s, sp.diff(mode.expr, s, order), "mpmath")
    with mpmath.workdps(30):
        return np.array([float(fn(mpmath.mpf(float(x)))) for x in at])


class ExactDerivation(Derivation):
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

    # ----- casadi ------------------------------------------------------------------------
    def _fields(self, quad: Quadrature, vec, p, at=None):
        """(phi-like, eps-like) fields of the coordinate vector `vec` (q, q' or q'') at the
        quadrature nodes (or at the points `at`), as SX."""
        at = quad.nodes if at is None else np.asarray(at, dtype=float)
        phi, eps = ca.SX.zeros(len(at)), ca.SX.zeros(len(at))
        for i, name in enumerate(self.coords):
            d = ca.DM(_shape_derivative(self.modes[name], 1, at)) * vec[i]
            if self.groups[name] == "bending":
                phi += d
            else:
                eps += d
        return phi / p[4], eps / p[4]

    @staticmethod
    def _cumulative(quad: Quadrature, g, scale):
        """int_0^s g at every node (N x c) and over the whole beam (1 x c)."""
        _, wts, S = quad.local
        start, rows = ca.SX.zeros(1, g.shape[1]), []
        for k in range(quad.n_seg):
            gk = g[k * quad.m:(k + 1) * quad.m, :]
            rows.append(ca.repmat(start, quad.m, 1) + scale * ca.mtimes(ca.DM(S), gk))
            start = start + scale * ca.mtimes(ca.DM(wts).T, gk)
        return ca.vertcat(*rows), start

    @staticmethod
    def _cumulative_transpose(quad: Quadrature, F, scale):
        """The transpose of _cumulative: sum_i C_ij F_i, the load at and beyond node j."""
        _, wts, S = quad.local
        beyond, rows = ca.SX.zeros(1, F.shape[1]), []
        for k in reversed(range(quad.n_seg)):
            Fk = F[k * quad.m:(k + 1) * quad.m, :]
            rows.insert(0, scale * (ca.mtimes(ca.DM(S).T, Fk) + ca.mtimes(ca.DM(wts), beyond)))
            beyond = beyond + ca.sum1(Fk)
        return ca.vertcat(*rows)

    def kinematics(self, quad: Quadrature, x: dict) -> dict:
        """Positions, velocities and the velocity part of the accelerations at the nodes
        (N x 2, moving frame), and the Jacobian columns dg/dq of the integrand g = (1+eps) t."""
        q, qd, p = x["q"], x["qd"], x["p"]
        phi, eps = self._fields(quad, q, p)
        phid, epsd = self._fields(quad, qd, p)
        c, sn = ca.cos(phi), ca.sin(phi)
        a = 1 + eps
        t, n = ca.horzcat(c, sn), ca.horzcat(-sn, c)
        scale = p[4] / quad.n_seg
        cols = []  # dg_j/dq_i as N x 2 blocks
        for i, name in enumerate(self.coords):
            shape = ca.DM(_shape_derivative(self.modes[name], 1, quad.nodes)) / p[4]
            base = n * ca.repmat(a, 1, 2) if self.groups[name] == "bending" else t
            cols.append(base * ca.repmat(shape, 1, 2))
        r, tip = self._cumulative(quad, t * ca.repmat(a, 1, 2), scale)
        gd = t * ca.repmat(epsd, 1, 2) + n * ca.repmat(a * phid, 1, 2)
        rd, _ = self._cumulative(quad, gd, scale)
        gamma = n * ca.repmat(2 * epsd * phid, 1, 2) - t * ca.repmat(a * phid * phid, 1, 2)
        rdd_v, _ = self._cumulative(quad, gamma, scale)
        return {"r": r, "tip": tip, "rd": rd, "rdd_v": rdd_v, "cols": cols, "scale": scale,
                "t": t, "n": n, "a": a}

    @staticmethod
    def _frame_acceleration(k: dict, rdd, drive, accelerates: bool):
        """Absolute acceleration in moving-frame components: r'' + 2w z x r' + alpha z x r - w^2 r."""
        r, rd, wz = k["r"], k["rd"], drive[0]
        zx = lambda v: ca.horzcat(-v[:, 1], v[:, 0])  # noqa: E731
        acc = rdd + 2 * wz * zx(rd) - wz * wz * r
        return acc + drive[1] * zx(r) if accelerates else acc

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
        acc = self._frame_acceleration(k, k["rdd_v"], drive, self.maneuver.accelerates)
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
        phidd, epsdd = self._fields(quad, qdd, p)
        gdd = k["t"] * ca.repmat(epsdd, 1, 2) + k["n"] * ca.repmat(k["a"] * phidd, 1, 2)
        rdd_a, _ = self._cumulative(quad, gdd, k["scale"])
        acc = self._frame_acceleration(k, k["rdd_v"] + rdd_a, drive, self.maneuver.accelerates)
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
        phidd, epsdd = self._fields(quad, qdd, p)
        gdd = k["t"] * ca.repmat(epsdd, 1, 2) + k["n"] * ca.repmat(k["a"] * phidd, 1, 2)
        rdd_a, _ = self._cumulative(quad, gdd, k["scale"])
        acc = self._frame_acceleration(k, k["rdd_v"] + rdd_a, drive, self.maneuver.accelerates)
        wb = ca.DM(quad.weights_between(at, 1.0))
        if name[0] == "M":
            g = k["t"] * ca.repmat(k["a"], 1, 2)
            r_at = p[4] * ca.mtimes(ca.DM(quad.weights_between(0.0, at)).T, g)  # 1 x 2
            arm = k["r"] - ca.repmat(r_at, quad.size, 1)
            moment = arm[:, 0] * acc[:, 1] - arm[:, 1] * acc[:, 0]
            return -p[0] * p[2] * p[4] * ca.dot(wb, moment)
        phi_at, _ = self._fields(quad, q, p, at=[at])
        Fx, Fy = p[4] * ca.dot(wb, acc[:, 0]), p[4] * ca.dot(wb, acc[:, 1])
        return -p[0] * p[2] * (Fx * ca.cos(phi_at[0]) + Fy * ca.sin(phi_at[0]))


def _prepare(spec) -> "ExactDerivation":
    """Modes, fields and the energy terms (sympy, quadratic: the linear model's strain energy)
    with their generalised forces Q. `spec` is validated (derive.derive)."""
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


def _test_state(der):
    """Bending mode k carries a share ~ 1/k^2 of a 1.5 rad rotation (alternating signs: the
    harder case; a smooth deformation's modal content decays at least that fast), moderate
    velocities. The study (exact_study.py) checks the rule on the states the runs visit."""
    n = len(der.coords)
    bend = [i for i, c in enumerate(der.coords) if der.groups[c] == "bending"]
    q = np.zeros(n)
    Lval = 10.0
    shares = np.array([1.0 / (j + 1)**2 for j in range(len(bend))])
    for j, i in enumerate(bend):
        slope = _shape_derivative(der.modes[der.coords[i]], 1, np.linspace(0, 1, 201))
        q[i] = (-1)**j * TEST_TIP_SLOPE * Lval * shares[j] / (shares.sum() * np.max(np.abs(slope)))
    for i, c in enumerate(der.coords):
        if der.groups[c] == "axial":
            q[i] = 1e-3
    qd = np.array([0.3 * (-1)**i * (i + 1) for i in range(n)])
    return q, qd, np.array([6.0, 0.5]), np.array([3000.0, 7.0e10, 4.0e-4, 2.0e-7, Lval])


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


def build_exact_kernels(der: ExactDerivation) -> list:
    tr, x = _symbolic_inputs(der)
    q, qd, qdd, drive, p = x["q"], x["qd"], x["qdd"], x["drive"], x["p"]
    quad = der.quadrature
    V = _potential(der, tr)
    M, f, en = der.equations(quad, x, V)
    r = der.residual(quad, x, V)
    ys = []
    for name in der.spec.outputs:
        expr = der.outputs[name]
        ys.append(der.exact_output(quad, name, x) if expr is None else tr(der.numeric(expr)))
    return make_kernels([
        ("mass", "mass matrix M(q) = d2T/dq'2 (exact kinematics, quadrature)",
         [("q", q), ("p", p)], [("M", M)]),
        ("force", "right-hand side f of M q'' = f", [("q", q), ("qd", qd), ("drive", drive), ("p", p)],
         [("f", f)]),
        ("residual_jac", "Jacobians of r = M(q) q'' - f", [("q", q), ("qd", qd), ("qdd", qdd),
                                                          ("drive", drive), ("p", p)],
         [("dr_dq", ca.jacobian(r, q)), ("dr_dqd", ca.jacobian(r, qd))]),
        ("outputs", "output quantities " + ", ".join(der.spec.outputs),
         [("q", q), ("qd", qd), ("qdd", qdd), ("drive", drive), ("p", p)], [("y", ca.vertcat(*ys))]),
        ("energy", "[T, V, h]: kinetic, potential energy and Jacobi integral",
         [("q", q), ("qd", qd), ("drive", drive), ("p", p)], [("e", en)]),
        ("maneuver", f"[theta, w, alpha] of manoeuvre '{der.maneuver.name}'",
         [("t", x["t"]), ("mp", x["mp"])], [("drive3", maneuver_sx(tr, der.maneuver))]),
    ])
