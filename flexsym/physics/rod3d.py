"""The spatial `ef` reference: a geometrically exact 3D beam element (Simo-Reissner rod).

One uniform two-node element of length le in a body's floating frame. Each node k carries its
position r_k (3) and its section's rotation Lambda_k = exp(psi_k) relative to the frame, psi_k
a rotation vector (3): 12 coordinates per element, e = (r_1, psi_1, r_2, psi_2), all in frame
components. The element is written once as casadi SX expressions of SX symbols (casadi AD gives
gradients, Hessians and mass matrices; sysgen can instantiate it per element like the planar
efbody.generic_element).

Strains (Simo-Reissner, objective; Crisfield-Jelenic interpolation of the rotations):
    Lambda_r = Lambda_1^T Lambda_2 = exp(phi)      relative rotation of the nodes (|phi| < pi,
                                                   the short way, whatever the nodes' psi)
    Lambda_m = Lambda_1 exp(phi / 2)               the section at the midpoint
    K        = phi / le                            curvature and twist (Lambda^T Lambda' of the
                                                   constant-curvature interpolation, exact)
    Gamma    = Lambda_m^T (r_2 - r_1) / le - e_1   axial strain and the two shear strains
    V_e = le/2 [EA G1^2 + GA (G2^2 + G3^2) + GJ K1^2 + EI_y K2^2 + EI_z K3^2]
Positions are linear in x and the strains are taken at the midpoint only (one-point, reduced
integration), which keeps linear elements free of shear locking; Gamma and K are unchanged
when all nodes are moved by one rigid motion (objectivity), so V_e vanishes for every rigid
motion and large displacements and rotations are exact (strains small: linear constitutive).
Curvatures are about the section's own axes: K2 about y (deflection along z, stiffness E I_y,
K2 = -w'' for small slopes), K3 about z (deflection along y, E I_z, K3 = v'').

Deviation from the benchmarks' Euler-Bernoulli beam: the rod keeps shear deformation with the
true shear stiffness G A (no correction factor). For a slender beam it changes deflections and
frequencies by O((r_g/L)^2), r_g the radius of gyration (tip deflection under a tip load:
+ P L / (G A) against P L^3 / (3 E I), i.e. 3 (E/G) (r_g/L)^2 relative). A shear-rigid
(Kirchhoff) element would need C1 interpolation of the positions or constraints; the rod
converges at O(h^2) with plain linear elements, handles unequal I_y, I_z and torsion
exactly, and needs no special treatment of large rotations.

Kinetic energy in the moving frame (angular velocity omega, origin velocity V, both in frame
components): the velocity of an axis point is V + r' + omega x r (r' the rate in the frame),
integrated exactly over the linear element (consistent translational mass rho A); the section's
material angular velocity is W = Lambda^T omega + W_rel, W_rel = 2 vec(q* (x) q') of its
quaternion q(psi), with the rotary inertia rho diag(I_y + I_z, I_y, I_z) per length lumped at
the two nodes (le/2 each). The torsional part rho (I_y + I_z) is the benchmarks'; the bending
rotary inertia rho I_y, rho I_z, which they neglect, is kept (factor `bending_inertia`, 1 by
default) because without it the bending rotations carry no inertia and the mass matrix is
singular; its effect is O((r_g/L)^2) as well. Gravity (g in frame components) enters as
V_g = -int rho A g . r dx (exact for the linear element).

Rotation parametrisation: psi relative to the floating frame. The exponential map is regular
for |psi| < 2 pi; at 2 pi its out-of-plane derivatives vanish (a node turned by a full turn),
yet a bent element's stress keeps the Hessian regular there (the end-moment test rolls a
cantilever into a full circle, tip psi = 2 pi). Nodal rotation vectors on either side of
|psi| = pi are fine: the relative rotation is taken the short way. A frame that follows the
root keeps bending rotations far below these limits. exp(psi) and the log of the relative
rotation are evaluated through quaternions with series expansions near zero, so casadi's
derivatives of any order are exact at the undeformed state (psi = 0, phi = 0).

Stiffness of the equations: the bending rotary inertia is tiny, so each element has a mode of
rotation against shear at about sqrt(2 G A / (rho I)) ~ c_shear / r_g (1e6 rad/s for a 20 x 10
mm steel section), whatever the mesh; the planar ANCF `ef`'s fastest is axial, ~ c / le. An
implicit integrator is needed (or `bending_inertia` > 1 as mass scaling: rho I_eff = rho A
le^2 / 12 brings it down to ~ c / le and changes frequencies by O(h^2)).

Section forces (constitutive, in the deformed section's frame, constant over an element):
    (N, Q_y, Q_z) = (EA G1, GA G2, GA G3),  (M_t, M_y, M_z) = (GJ K1, EI_y K2, EI_z K3).

Clamped root: the body's first node is fixed to the frame (r = 0, psi = 0); its coordinates are
dropped (ClampedBeam). A root node still carries half an element's rotary inertia, which moves
with the frame (its omega terms stay in T).

Wiring into a system (as sysgen.ef_kinetic_energy does for the planar ef): per element, call
element_functions()["kinetic"](e, e', omega, V, le, sec, b) with the element's 12 nodal values
(root entries 0), their rates, and the frame's omega and V in frame components; "elastic" and
"gravity" (g in frame components) likewise; sum, and take Lagrange's equations by casadi AD.
Section forces: "forces" per element (midpoint values) or ClampedBeam.section_forces_at.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from math import factorial

import casadi as ca
import numpy as np

NODE_COORDS = ("rx", "ry", "rz", "px", "py", "pz")  # per node: position, rotation vector
SECTION = ("E", "G", "rho", "A", "Iy", "Iz", "J")  # the order of a section vector `sec`


# --- rotations (casadi SX/MX/DM, or anything casadi accepts) ---

def _smooth(u, threshold, coeffs, closed):
    """f(u) for u >= 0: the series sum c_k u^k below `threshold`, closed(u) above; closed is
    evaluated at max(u, threshold) so that neither branch nor its derivatives are ever NaN."""
    series = sum(c * u**k for k, c in enumerate(coeffs))
    safe = ca.if_else(u < threshold, threshold, u)
    return ca.if_else(u < threshold, series, closed(safe))


def quaternion(psi):
    """Unit quaternion (w, v) of exp(psi): (cos(t/2), sin(t/2) psi / t), t = |psi|."""
    t2 = ca.dot(psi, psi)
    c = _smooth(t2, 1.0, [(-0.25)**k / factorial(2 * k) for k in range(11)],
                lambda u: ca.cos(ca.sqrt(u) / 2))
    s = _smooth(t2, 1.0, [0.5 * (-0.25)**k / factorial(2 * k + 1) for k in range(11)],
                lambda u: ca.sin(ca.sqrt(u) / 2) / ca.sqrt(u))
    return ca.vertcat(c, s * psi)


def qmul(a, b):
    """Hamilton product a (x) b of quaternions (w, x, y, z)."""
    wa, va, wb, vb = a[0], a[1:4], b[0], b[1:4]
    return ca.vertcat(wa * wb - ca.dot(va, vb), wa * vb + wb * va + ca.cross(va, vb))


def qconj(a):
    return ca.vertcat(a[0], -a[1:4])


def qmatrix(a):
    """Rotation matrix of the unit quaternion a: R v = a (x) v (x) a*."""
    w, v = a[0], a[1:4]
    return (w**2 - ca.dot(v, v)) * ca.DM.eye(3) + 2 * v @ v.T + 2 * w * ca.skew(v)


def qlog(a):
    """Rotation vector of the unit quaternion a with a[0] > 0 (rotations below pi):
    2 atan(|v| / w) v / |v| = (2 / w) g(|v|^2 / w^2) v, g(u) = atan(sqrt u) / sqrt u."""
    w, v = a[0], a[1:4]
    u = ca.dot(v, v) / w**2
    g = _smooth(u, 0.01, [(-1)**k / (2 * k + 1) for k in range(9)],
                lambda s: ca.atan(ca.sqrt(s)) / ca.sqrt(s))
    return 2 * g / w * v


# --- one element ---

def _split(e):
    return e[0:3], e[3:6], e[6:9], e[9:12]


def element_kinematics(e, le):
    """(Gamma, K, Lambda_m): strains of the element e = (r1, psi1, r2, psi2) and its midpoint
    section's rotation (frame components)."""
    r1, p1, r2, p2 = _split(e)
    q1, q2 = quaternion(p1), quaternion(p2)
    qr = qmul(qconj(q1), q2)
    # q and -q are one rotation: take the relative rotation's short way (below pi), whatever
    # the signs of the nodal quaternions (nodal rotation vectors on either side of |psi| = pi)
    qr = ca.if_else(qr[0] < 0, -1, 1) * qr
    K = qlog(qr) / le
    half = ca.vertcat(1 + qr[0], qr[1:4]) / ca.sqrt(2 * (1 + qr[0]))
    Lm = qmatrix(qmul(q1, half))
    Gamma = Lm.T @ (r2 - r1) / le - ca.vertcat(1, 0, 0)
    return Gamma, K, Lm


def _stiffness(sec):
    E, G, _, A, Iy, Iz, J = (sec[i] for i in range(7))
    return ca.vertcat(E * A, G * A, G * A), ca.vertcat(G * J, E * Iy, E * Iz)


def elastic_energy(e, le, sec):
    """V_e of one element (sec: E, G, rho, A, Iy, Iz, J)."""
    Gamma, K, _ = element_kinematics(e, le)
    cG, cK = _stiffness(sec)
    return le / 2 * (ca.dot(cG, Gamma**2) + ca.dot(cK, K**2))


def strain_rate_energy(e, ed, le, sec):
    """The elastic energy's quadratic form in the strain rates, le/2 [cG . Gamma'^2 + cK . K'^2]
    (Gamma' = dGamma/de e', K' likewise): beta times it is the element's Kelvin-Voigt
    dissipation, as beta/2 q'^T K q' is a modal beam's. Any expressions for e, e' (casadi's
    directional derivative needs symbols: element_functions' "strain_rate" is built on them)."""
    return element_functions()["strain_rate"](e, ed, le, sec)


def relative_kinetic_energy(e, ed, le, sec, bending_inertia=1.0):
    """kinetic_energy of the rates e' relative to the frame alone (omega = V = 0): alpha times it
    is the element's mass-proportional dissipation, as alpha/2 q'^T M q' is a modal beam's. Any
    expressions for e, e' (element_functions' "kinetic" is built on symbols)."""
    zero = ca.SX.zeros(3)
    return element_functions()["kinetic"](e, ed, zero, zero, le, sec, bending_inertia)


def _strain_rate_energy(e, ed, le, sec):
    Gamma, K, _ = element_kinematics(e, le)
    cG, cK = _stiffness(sec)
    Gd, Kd = ca.jtimes(Gamma, e, ed), ca.jtimes(K, e, ed)
    return le / 2 * (ca.dot(cG, Gd**2) + ca.dot(cK, Kd**2))


def section_forces(e, le, sec):
    """(N, Q_y, Q_z, M_t, M_y, M_z) of the element, in its midpoint section's frame."""
    Gamma, K, _ = element_kinematics(e, le)
    cG, cK = _stiffness(sec)
    return ca.vertcat(cG * Gamma, cK * K)


def angular_velocity(psi, psid):
    """Material angular velocity of exp(psi) relative to the frame: 2 vec(q* (x) q')."""
    q = quaternion(psi)
    qd = ca.jtimes(q, psi, psid)
    return 2 * qmul(qconj(q), qd)[1:4]


def kinetic_energy(e, ed, omega, V, le, sec, bending_inertia=1.0):
    """T_e of one element in a frame moving with (omega, V) (frame components); ed = de/dt
    relative to the frame. Translational: exact integral of rho A/2 |V + r' + omega x r|^2 over
    the linear element; rotational: 1/2 W^T J_rho W at each node with le/2, W = Lambda^T omega
    + W_rel, J_rho = rho diag(I_y + I_z, b I_y, b I_z), b = bending_inertia."""
    r1, p1, r2, p2 = _split(e)
    v1, w1, v2, w2 = _split(ed)
    rho, A, Iy, Iz = sec[2], sec[3], sec[4], sec[5]
    a = V + v1 + ca.cross(omega, r1)
    b = V + v2 + ca.cross(omega, r2)
    T = rho * A * le / 6 * (ca.dot(a, a) + ca.dot(a, b) + ca.dot(b, b))
    Jr = rho * ca.vertcat(Iy + Iz, bending_inertia * Iy, bending_inertia * Iz)
    for p, w in ((p1, w1), (p2, w2)):
        W = qmatrix(quaternion(p)).T @ omega + angular_velocity(p, w)
        T += le / 4 * ca.dot(Jr, W**2)
    return T


def gravity_potential(e, g, le, sec):
    """V_g = -int rho A g . r dx of the element (g in frame components)."""
    r1, _, r2, _ = _split(e)
    return -sec[2] * sec[3] * le / 2 * ca.dot(g, r1 + r2)


@lru_cache(maxsize=None)
def element_functions() -> dict[str, ca.Function]:
    """The element as casadi Functions of SX symbols, for instantiation per element:
    elastic(e, le, sec) -> V_e; kinetic(e, ed, omega, V, le, sec, bending_inertia) -> T_e;
    gravity(e, g, le, sec) -> V_g; strains(e, le) -> (Gamma, K); forces(e, le, sec) ->
    (N, Q_y, Q_z, M_t, M_y, M_z); midframe(e, le) -> Lambda_m; strain_rate(e, ed, le, sec) ->
    the elastic energy's form in the strain rates (strain_rate_energy)."""
    e, ed = ca.SX.sym("e", 12), ca.SX.sym("ed", 12)
    om, V, g = ca.SX.sym("omega", 3), ca.SX.sym("V", 3), ca.SX.sym("g", 3)
    le, sec, b = ca.SX.sym("le"), ca.SX.sym("sec", 7), ca.SX.sym("bending_inertia")
    Gamma, K, Lm = element_kinematics(e, le)
    return {
        "elastic": ca.Function("rod3d_elastic", [e, le, sec], [elastic_energy(e, le, sec)]),
        "kinetic": ca.Function("rod3d_kinetic", [e, ed, om, V, le, sec, b],
                               [kinetic_energy(e, ed, om, V, le, sec, b)]),
        "gravity": ca.Function("rod3d_gravity", [e, g, le, sec], [gravity_potential(e, g, le, sec)]),
        "strains": ca.Function("rod3d_strains", [e, le], [Gamma, K]),
        "strain_rate": ca.Function("rod3d_strain_rate", [e, ed, le, sec], [_strain_rate_energy(e, ed, le, sec)]),
        "forces": ca.Function("rod3d_forces", [e, le, sec], [section_forces(e, le, sec)]),
        "midframe": ca.Function("rod3d_midframe", [e, le], [Lm]),
    }


# --- a uniform clamped-free beam ---

@dataclass(frozen=True)
class Section:
    E: float
    G: float
    rho: float
    A: float
    Iy: float
    Iz: float
    J: float

    @property
    def vector(self) -> np.ndarray:
        return np.array([getattr(self, k) for k in SECTION], dtype=float)


@dataclass(frozen=True)
class ClampedBeam:
    """A uniform beam of length L along the frame's x axis, n elements, root node clamped to
    the frame (r = 0, psi = 0: its coordinates are dropped). Coordinates q: per free node
    k = 1..n, (rx_k, ry_k, rz_k, px_k, py_k, pz_k), absolute in the frame."""
    n: int
    L: float

    @property
    def le(self) -> float:
        return self.L / self.n

    @property
    def names(self) -> list[str]:
        return [f"{c}{k}" for k in range(1, self.n + 1) for c in NODE_COORDS]

    @property
    def q0(self) -> np.ndarray:
        """The undeformed beam: node k at (k L / n, 0, 0), psi = 0."""
        q = np.zeros(6 * self.n)
        q[0::6] = np.arange(1, self.n + 1) * self.le
        return q

    def index(self, node: int, coord: str) -> int:
        """Position in q of a free node's coordinate (node 1..n)."""
        return 6 * (node - 1) + NODE_COORDS.index(coord)

    def elements(self, q):
        """The elements' nodal vectors (12 each), the clamped root's entries zero."""
        zero = ca.DM.zeros(6) if isinstance(q, (np.ndarray, ca.DM)) else type(q).zeros(6)
        q = ca.DM(q) if isinstance(q, np.ndarray) else q
        nodes = [zero] + [q[6 * k:6 * k + 6] for k in range(self.n)]
        return [ca.vertcat(nodes[k], nodes[k + 1]) for k in range(self.n)]

    def energies(self, q, qd, omega, V, g, sec, bending_inertia=1.0):
        """(T, V_elastic, V_gravity) of the beam, summed over its elements."""
        f = element_functions()
        es, eds = self.elements(q), self.elements(qd)
        T = sum(f["kinetic"](e, ed, omega, V, self.le, sec, bending_inertia) for e, ed in zip(es, eds))
        Ve = sum(f["elastic"](e, self.le, sec) for e in es)
        Vg = sum(f["gravity"](e, g, self.le, sec) for e in es)
        return T, Ve, Vg

    def element_forces(self, q, sec) -> np.ndarray:
        """(n, 6) section forces (N, Q_y, Q_z, M_t, M_y, M_z) at the element midpoints."""
        f = element_functions()["forces"]
        return np.array([np.array(f(e, self.le, ca.DM(sec))).ravel() for e in self.elements(np.asarray(q, float))])

    def section_forces_at(self, q, x: float, sec) -> np.ndarray:
        """Section forces at station x (0 <= x <= L): linear in x between the element midpoints
        (where the one-point element's strains are sampled, O(h^2) there), extrapolated over
        the end half-elements (exact at the root for forces linear in x, as under tip loads).
        Components in the local section frames (which differ by O(h) between midpoints)."""
        F = self.element_forces(q, sec)
        if self.n == 1:
            return F[0]
        xm = (np.arange(self.n) + 0.5) * self.le
        k = int(np.clip(np.searchsorted(xm, x) - 1, 0, self.n - 2))
        t = (x - xm[k]) / self.le
        return (1 - t) * F[k] + t * F[k + 1]
