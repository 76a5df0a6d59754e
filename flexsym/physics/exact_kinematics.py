"""The exact kinematics of one planar beam in casadi (physics/exact.py explains the model):
the composite Gauss rule, the fields at its points and their cumulative integrals, shared by
the one-beam derivation (exact.ExactDerivation) and a system's body (exact_body.py)."""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import mpmath
import numpy as np
import sympy as sp

from flexsym.physics.integrals import gauss_legendre
from flexsym.model.fedata import BodyMode, evaluate, locate
from flexsym.model.modes import s

M_POINTS = 6  # Gauss points per segment (cumulative integrals cost m^2 per segment)
QUAD_RTOL = 1e-6  # accuracy check of the quadrature (relative; see choose_quadrature)
MAX_SEGMENTS = 256
TEST_TIP_SLOPE = 1.5  # rad: the test state's largest section rotation (a tip thrown sideways)


@dataclass(frozen=True)
class Quadrature:
    """Composite Gauss-Legendre rule on [0, 1]: each piece between consecutive `edges` cut into
    n_seg equal segments of m points. A uniform beam has one piece; a beam of several sections
    one per section (and point mass), so that no segment straddles a jump of rho A or EI."""

    n_seg: int
    m: int
    edges: tuple = (0.0, 1.0)

    @property
    def pieces(self) -> list[tuple[float, float]]:
        return list(zip(self.edges, self.edges[1:]))

    @property
    def size(self) -> int:
        return self.n_seg * self.m * len(self.pieces)

    @property
    def local(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return _local_rule(self.m)

    def width(self, segment: int) -> float:
        """The width of the piece that holds a segment (its segments' width times n_seg)."""
        a, b = self.pieces[segment // self.n_seg]
        return b - a

    @property
    def nodes(self) -> np.ndarray:
        tau = self.local[0]
        return np.concatenate([a + (b - a) * ((k + tau) / self.n_seg)
                               for a, b in self.pieces for k in range(self.n_seg)])

    @property
    def weights(self) -> np.ndarray:
        return np.concatenate([np.tile(self.local[1], self.n_seg) / self.n_seg * (b - a)
                               for a, b in self.pieces])

    def weights_between(self, a: float, b: float) -> np.ndarray:
        """Weights over all nodes of int_a^b g ds for g interpolated per segment (degree m - 1)."""
        out = np.zeros(self.size)
        tau, _, _ = self.local
        for p, (e0, e1) in enumerate(self.pieces):
            h = e1 - e0
            for k in range(self.n_seg):
                lo = max((a - e0) / h * self.n_seg - k, 0.0)
                hi = min((b - e0) / h * self.n_seg - k, 1.0)
                if hi > lo:
                    j = p * self.n_seg + k
                    out[j * self.m:(j + 1) * self.m] = (_lagrange_integrals(tau, hi)
                                                        - _lagrange_integrals(tau, lo)) / self.n_seg * h
        return out

    def describe(self) -> dict:
        return {"segments": self.n_seg * len(self.pieces), "points_per_segment": self.m, "points": self.size,
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


@lru_cache(maxsize=None)
def _point_matrix(quad: Quadrature, points: tuple) -> np.ndarray:
    """Row k: the weights of int_0^s_k over the nodes (a point mass's position from g)."""
    return np.array([quad.weights_between(0.0, sk) for sk in points])


def _segment_scale(quad: Quadrature, k: int, scale):
    """Segment k's length: `scale` (L / n_seg) times its piece's width; one piece of width 1
    (a uniform beam) keeps `scale` itself, so that its kernels stay as they were."""
    w = quad.width(k)
    return scale if w == 1.0 else scale * w


def _shape_derivative(mode, order: int, at: np.ndarray) -> np.ndarray:
    if isinstance(mode, BodyMode):  # from finite-element data: the element's own interpolation
        return evaluate(mode.body, mode.shape, order, np.asarray(at, dtype=float))
    fn = sp.lambdify(s, sp.diff(mode.expr, s, order), "mpmath")
    with mpmath.workdps(30):
        return np.array([float(fn(mpmath.mpf(float(x)))) for x in at])


class ExactKinematics:
    """The exact kinematics of one beam in casadi, from its coordinate names (`coords`, in the
    order of its coordinate vector), their mode shapes (`modes`) and groups (`groups`: axial or
    bending): the one-beam derivation's and a system body's (physics/body_kinds/exact.ExactPart).
    A beam from finite-element data (`fe_body`) has sections that change along it and point
    masses: its rule is broken at both (edges), its mass per point scaled by rho A (mass_weights),
    and its fields carry rows for the point masses after the quadrature nodes."""

    fe_body = None  # fedata.BeamBody (a system body from finite-element data) or None: uniform

    def edges(self) -> tuple:
        """The quadrature's piece edges in s: a body from finite-element data's nodes (its
        sections change there, its point masses sit there, and its modes, polynomials per
        element, have a kink in curvature and a jump in axial strain there, which a Gauss
        segment straddling them integrates to O(h) only)."""
        body = self.fe_body
        if body is None:
            return (0.0, 1.0)
        return tuple(float(v) for v in body.s_nodes)

    def point_masses(self) -> list[tuple[float, float]]:
        """(s, m / (rho A L) of the root section) of each point mass."""
        body = self.fe_body
        if body is None:
            return []
        r = body.reference
        return [(pm.x / body.length, pm.mass / (r.rho * r.A * body.length)) for pm in body.masses]

    def mass_weights(self, quad: Quadrature, a: float = 0.0, b: float = 1.0, closed: bool = True) -> np.ndarray:
        """Mass per rho A L of the root section of the nodes, then of the point masses, between
        a and b (a point mass at b included, at a if closed): the rule's weights times the
        section's rho A relative to the root's (constant on each piece), and m / (rho A L)."""
        w = quad.weights if (a, b) == (0.0, 1.0) else quad.weights_between(a, b)
        body = self.fe_body
        if body is None:
            return w
        mu = body.ratios()["mu"][locate(body, quad.nodes)]
        return np.concatenate([w * mu, [c if a < sk <= b or (closed and sk == a) else 0.0
                                        for sk, c in self.point_masses()]])

    def _with_points(self, quad: Quadrature, cum, g, L):
        """A cumulative field at the nodes (N x c), the integral of g (N x c) at the point
        masses appended."""
        points = tuple(sk for sk, _ in self.point_masses())
        if not points:
            return cum
        return ca.vertcat(cum, L * ca.mtimes(ca.DM(_point_matrix(quad, points)), g))

    def _transpose_with_points(self, quad: Quadrature, F, scale, L):
        """The transpose of _cumulative with _with_points: the load at and beyond node j from
        F (one row per node, then per point mass)."""
        points = tuple(sk for sk, _ in self.point_masses())
        if not points:
            return self._cumulative_transpose(quad, F, scale)
        return (self._cumulative_transpose(quad, F[:quad.size, :], scale)
                + L * ca.mtimes(ca.DM(_point_matrix(quad, points)).T, F[quad.size:, :]))

    def _fields(self, quad: Quadrature, vec, L, at=None):
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
        return phi / L, eps / L

    @staticmethod
    def _cumulative(quad: Quadrature, g, scale):
        """int_0^s g at every node (N x c) and over the whole beam (1 x c)."""
        _, wts, S = quad.local
        start, rows = ca.SX.zeros(1, g.shape[1]), []
        for k in range(quad.size // quad.m):
            gk = g[k * quad.m:(k + 1) * quad.m, :]
            sc = _segment_scale(quad, k, scale)
            rows.append(ca.repmat(start, quad.m, 1) + sc * ca.mtimes(ca.DM(S), gk))
            start = start + sc * ca.mtimes(ca.DM(wts).T, gk)
        return ca.vertcat(*rows), start

    @staticmethod
    def _cumulative_transpose(quad: Quadrature, F, scale):
        """The transpose of _cumulative: sum_i C_ij F_i, the load at and beyond node j."""
        _, wts, S = quad.local
        beyond, rows = ca.SX.zeros(1, F.shape[1]), []
        for k in reversed(range(quad.size // quad.m)):
            Fk = F[k * quad.m:(k + 1) * quad.m, :]
            rows.insert(0, _segment_scale(quad, k, scale) * (ca.mtimes(ca.DM(S).T, Fk)
                                                             + ca.mtimes(ca.DM(wts), beyond)))
            beyond = beyond + ca.sum1(Fk)
        return ca.vertcat(*rows)

    def beam_kinematics(self, quad: Quadrature, q, qd, L) -> dict:
        """Positions, velocities and the velocity part of the accelerations at the nodes
        (N x 2, moving frame; then a row per point mass), and the Jacobian columns dg/dq of
        the integrand g = (1+eps) t at the nodes;
        q, qd: the beam's coordinates and rates (SX), L its length."""
        phi, eps = self._fields(quad, q, L)
        phid, epsd = self._fields(quad, qd, L)
        c, sn = ca.cos(phi), ca.sin(phi)
        a = 1 + eps
        t, n = ca.horzcat(c, sn), ca.horzcat(-sn, c)
        scale = L / quad.n_seg
        cols = []  # dg_j/dq_i as N x 2 blocks
        for i, name in enumerate(self.coords):
            shape = ca.DM(_shape_derivative(self.modes[name], 1, quad.nodes)) / L
            base = n * ca.repmat(a, 1, 2) if self.groups[name] == "bending" else t
            cols.append(base * ca.repmat(shape, 1, 2))
        g = t * ca.repmat(a, 1, 2)
        r, tip = self._cumulative(quad, g, scale)
        gd = t * ca.repmat(epsd, 1, 2) + n * ca.repmat(a * phid, 1, 2)
        rd, _ = self._cumulative(quad, gd, scale)
        gamma = n * ca.repmat(2 * epsd * phid, 1, 2) - t * ca.repmat(a * phid * phid, 1, 2)
        rdd_v, _ = self._cumulative(quad, gamma, scale)
        r, rd, rdd_v = (self._with_points(quad, c, h, L) for c, h in ((r, g), (rd, gd), (rdd_v, gamma)))
        return {"r": r, "tip": tip, "rd": rd, "rdd_v": rdd_v, "cols": cols, "scale": scale,
                "t": t, "n": n, "a": a, "g": g, "gd": gd, "gamma": gamma}

    def acceleration(self, quad: Quadrature, k: dict, gdd, omega, alpha, L):
        """r'' + 2 omega z x r' + alpha z x r - omega^2 r at the nodes (N x 2, then a row per
        point mass; moving-frame components): the acceleration relative to the frame's origin
        of beam_kinematics' k, gdd being the q'' part of the integrand of r'' (None: left out),
        alpha None when the frame does not accelerate. One cumulative integral of the sum of
        the integrands: integrating along the beam is linear and omega, alpha are uniform on
        it, so the four integrals r, r', r''_v, r''_a of the sum's parts are not needed."""
        zx = lambda v: ca.horzcat(-v[:, 1], v[:, 0])  # noqa: E731
        h = k["gamma"] + 2 * omega * zx(k["gd"]) - omega * omega * k["g"]
        if gdd is not None:
            h = h + gdd
        if alpha is not None:
            h = h + alpha * zx(k["g"])
        acc, _ = self._cumulative(quad, h, k["scale"])
        return self._with_points(quad, acc, h, L)


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
