"""Flexible bodies from beam finite-element data: description, assembly, modes, invariants.

A body is a straight planar beam cut into elements, each with its own section (E, rho, A, I),
with point masses (and rotary inertias) at nodes, clamped at its interface node (the root,
x = 0). It is assembled with the paper's planar beam element (eq. 7-8: linear axial,
Hermite cubic bending, consistent mass; the (th1, th2) entry of K_G is -l/30). Nothing here
knows about the hub: a body is a description plus the matrices and modes derived from it.

Modes (fixed-interface modal synthesis, as the paper; the tip is the interface of the static
modes): the tokens of the analytic families are mapped onto their discrete counterparts, so
that the same variants (m1, m2, m3, prestress) apply to any body:

    axial   static  constraint mode: u_tip = 1, K u = 0 elsewhere       (Phi1 = s for a uniform bar)
    axial   sinK    k-th normal mode with the tip fixed (fixed-interface) (sin(k pi s))
    axial   ffK     k-th clamped-free normal mode                          (sin((2k-1) pi s/2))
    bending static  constraint mode: v_tip = 1, tip rotation free          (3/2 s^2 - 1/2 s^3)
    bending cpK     k-th normal mode with v_tip fixed (fixed-interface)    (clamped-pinned Psi_k)
    bending cfK     k-th clamped-free normal mode                          (Lambda_k)

Static modes have tip value 1 and are computed in exact rational arithmetic (the tip-load
response of the element table, which the element reproduces exactly), rounded once to
double; normal modes are eigenvectors (doubles), mass-normalised (int mu phi^2 ds = 1 with
the point masses) with the sign fixed by their first significant nodal value (positive), so
that generation is deterministic.

Shapes are stored as nodal values in s = x/L (v and dv/ds at every node); between nodes they
are the element's own interpolation, so every invariant is an integral of piecewise
polynomials, evaluated exactly by Gauss-Legendre per element (in double precision: the
eigenvectors are doubles).
"""
from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from flexsym.model.beam_element import numeric_element_matrices
from flexsym.core.errors import SpecError
from flexsym.model.limits import MAX_MAGNITUDE, MIN_POSITIVE

GAUSS_POINTS = 8  # exact for polynomials of degree 15 per element (invariants reach 14)
SIG_DIGITS = 13  # invariants are rounded to this many significant digits (deterministic code)
ORTHO_TOL = 1e-11  # |invariant| below this fraction of its scale is an exact zero


@dataclass(frozen=True)
class Section:
    """An element's section and material. I resists bending along y (the planar I, the spatial
    I_z); a spatial body's sections add Iy (bending along z), J (St Venant torsion) and G."""

    E: float
    rho: float
    A: float
    I: float
    Iy: float | None = None
    J: float | None = None
    G: float | None = None

    SPATIAL = ("Iy", "J", "G")

    @property
    def spatial(self) -> bool:
        return self.Iy is not None


@dataclass(frozen=True)
class PointMass:
    x: float  # position along the axis [m] (must be a node)
    mass: float = 0.0  # [kg]
    rotary: float = 0.0  # rotary inertia about the normal to the plane [kg m^2]


@dataclass(frozen=True)
class BeamBody:
    """Nodes x_0 = 0 < x_1 < ... < x_n along the axis, element e joins nodes e and e+1 and has
    sections[e]; point masses at nodes; the root node (x = 0) is the clamped interface."""

    nodes: tuple[float, ...]
    sections: tuple[Section, ...]
    masses: tuple[PointMass, ...] = ()
    matrices: object = field(default=None, compare=False, repr=False)  # imported (M, K, KG)

    # ----- construction ---------------------------------------------------------------
    @staticmethod
    def from_segments(segments, elements: int, masses=()) -> "BeamBody":
        """segments: [(length, Section)], meshed with about `elements` equal-ish elements in
        total (each segment gets a share proportional to its length, at least one)."""
        total = sum(l for l, _ in segments)
        nodes, sections = [0.0], []
        for length, sec in segments:
            k = max(1, round(elements * length / total))
            x0 = nodes[-1]
            nodes += [x0 + length * (i + 1) / k for i in range(k)]
            sections += [sec] * k
        return BeamBody(tuple(nodes), tuple(sections), tuple(masses)).validate()

    def segments(self) -> list[tuple[float, Section]]:
        """Runs of equal sections, also cut at point masses: what a remeshing must keep."""
        cuts = {self.node_index(m.x) for m in self.masses}
        segs, start = [], 0
        for e in range(1, self.elements + 1):
            if e == self.elements or self.sections[e] != self.sections[e - 1] or e in cuts:
                segs.append((self.nodes[e] - self.nodes[start], self.sections[start]))
                start = e
        return segs

    def remeshed(self, elements: int) -> "BeamBody":
        """The same beam (sections, steps, point masses) on about `elements` elements."""
        if elements == self.elements:
            return self
        return BeamBody.from_segments(self.segments(), elements, self.masses)

    def validate(self, where: str = "body") -> "BeamBody":
        n = len(self.sections)
        if n < 1 or len(self.nodes) != n + 1:
            raise SpecError(f"{where}: {len(self.nodes)} nodes for {n} elements (need elements + 1)")
        if self.nodes[0] != 0.0:
            raise SpecError(f"{where}: the first node (the clamped root) must be at x = 0")
        for i, (a, b) in enumerate(zip(self.nodes, self.nodes[1:])):
            if not (math.isfinite(b) and b > a):
                raise SpecError(f"{where}: node {i + 1} at x = {b!r} does not follow node {i} "
                                f"at x = {a!r} (nodes must increase along the axis)")
        spatial = self.sections[0].spatial
        for e, sec in enumerate(self.sections):
            for k in ("E", "rho", "A", "I") + (Section.SPATIAL if spatial else ()):
                v = getattr(sec, k)
                if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                    raise SpecError(f"{where}: element {e}: {k} = {v!r} must be a positive number")
            given = [k for k in Section.SPATIAL if getattr(sec, k) is not None]
            if given and len(given) < 3 or bool(given) != spatial:
                raise SpecError(f"{where}: element {e}: give Iy, J and G on every element of a "
                                "spatial body, and on none of a planar one")
        if spatial and any(m.rotary for m in self.masses):
            raise SpecError(f"{where}: a point mass's rotary inertia is planar only (a spatial "
                            "body's point masses are on its axis, mass only)")
        for pm in self.masses:
            if self.node_index(pm.x) is None:
                raise SpecError(f"{where}: point mass at x = {pm.x!r} is not at a node")
            if not (math.isfinite(pm.mass) and pm.mass >= 0 and math.isfinite(pm.rotary)
                    and pm.rotary >= 0 and (pm.mass > 0 or pm.rotary > 0)):
                raise SpecError(f"{where}: point mass at x = {pm.x!r}: mass and rotary inertia "
                                "must be >= 0 and not both zero")
        return self

    def node_index(self, x: float) -> int | None:
        for i, xn in enumerate(self.nodes):
            if abs(xn - x) <= 1e-12 * self.length:
                return i
        return None

    # ----- properties -----------------------------------------------------------------
    @property
    def elements(self) -> int:
        return len(self.sections)

    @property
    def length(self) -> float:
        return self.nodes[-1]

    @property
    def reference(self) -> Section:
        """The section the run-time parameters (rho, E, A, I) scale: the root element's."""
        return self.sections[0]

    @property
    def s_nodes(self) -> np.ndarray:
        return np.array(self.nodes) / self.length

    @property
    def spatial(self) -> bool:
        return self.reference.spatial

    def ratios(self) -> dict[str, np.ndarray]:
        """Per element: rho A, E A, E I relative to the reference section; a spatial body's
        also E I_y, G J and rho (I_y + I_z), the sections' spin inertia."""
        r = self.reference
        out = {"mu": np.array([s.rho * s.A for s in self.sections]) / (r.rho * r.A),
               "ea": np.array([s.E * s.A for s in self.sections]) / (r.E * r.A),
               "ei": np.array([s.E * s.I for s in self.sections]) / (r.E * r.I)}
        if self.spatial:
            out |= {"eiy": np.array([s.E * s.Iy for s in self.sections]) / (r.E * r.Iy),
                    "gj": np.array([s.G * s.J for s in self.sections]) / (r.G * r.J),
                    "ip": np.array([s.rho * (s.Iy + s.I) for s in self.sections]) / (r.rho * (r.Iy + r.I))}
        return out

    def view(self, plane: str) -> "BeamBody":
        """A spatial body's other equations as a planar body's, so that the same assembly and
        modes serve: "z", bending along z (I = I_y); "torsion", St Venant torsion as the bar's
        axial equation (E A -> G J, rho A -> rho (I_y + I_z); point masses on the axis have no
        spin inertia)."""
        if plane == "z":
            secs = tuple(Section(s.E, s.rho, s.A, s.Iy) for s in self.sections)
            return BeamBody(self.nodes, secs, tuple(PointMass(m.x, m.mass) for m in self.masses))
        ip = [s.Iy + s.I for s in self.sections]
        secs = tuple(Section(s.G * s.J / p, s.rho, p, s.I) for s, p in zip(self.sections, ip))
        return BeamBody(self.nodes, secs)

    def to_dict(self) -> dict:
        """Canonical content (repr of every double): what generated code depends on."""
        keys = ("E", "rho", "A", "I") + (Section.SPATIAL if self.spatial else ())
        d = {"nodes": [repr(float(x)) for x in self.nodes],
             "sections": [[repr(float(getattr(s, k))) for k in keys] for s in self.sections],
             "masses": [[repr(float(m.x)), repr(float(m.mass)), repr(float(m.rotary))]
                        for m in self.masses]}
        if self.matrices is not None:
            h = hashlib.sha256()
            for mat in self.matrices:
                h.update(np.ascontiguousarray(mat, dtype=np.float64).tobytes())
            d["imported_matrices"] = h.hexdigest()
        return d

    @cached_property
    def digest(self) -> str:
        return hashlib.sha256(json.dumps(self.to_dict(), sort_keys=True).encode()).hexdigest()[:10]

    def summary(self) -> str:
        pm = ", ".join(f"{m.mass:g} kg at x = {m.x:g} m" for m in self.masses) or "none"
        return (f"beam body: {self.elements} elements, L = {self.length:g} m, point masses: {pm}")

    # ----- assembly (SI units, free dofs u, v, theta of nodes 1..n) ----------------------
    @cached_property
    def assembled(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(M, K, KG): consistent mass with point masses, linear stiffness (7), geometric
        stiffness for a unit axial load in every element (8); root dofs removed."""
        if self.matrices is not None:
            return self.matrices
        n = self.elements
        nd = 3 * (n + 1)
        M, K, KG = (np.zeros((nd, nd)) for _ in range(3))
        for e, sec in enumerate(self.sections):
            l = self.nodes[e + 1] - self.nodes[e]
            me, ke, kge = element_matrices(sec, l)
            idx = np.arange(3 * e, 3 * e + 6)
            for big, small in ((M, me), (K, ke), (KG, kge)):
                big[np.ix_(idx, idx)] += small
        for pm in self.masses:
            i = self.node_index(pm.x)
            M[3 * i, 3 * i] += pm.mass
            M[3 * i + 1, 3 * i + 1] += pm.mass
            M[3 * i + 2, 3 * i + 2] += pm.rotary
        return M[3:, 3:], K[3:, 3:], KG[3:, 3:]

    # ----- modes ----------------------------------------------------------------------
    def mode_shape(self, axis: str, family: str, index: int) -> "ShapeData":
        if family not in FE_FAMILIES:  # pp: the root node is clamped here (its rotation held)
            raise SpecError(f"{axis} mode family '{family}' is not derived for a body from "
                            f"finite-element data (its root node is clamped; derived: "
                            f"{', '.join(FE_FAMILIES)})")
        return _mode_cache(self, axis, family, index)


FE_FAMILIES = ("static", "sine", "clamped_pinned", "fixed_free", "clamped_free")


def element_matrices(sec: Section, l: float):
    """Mass, stiffness (eq. 7) and unit-load geometric stiffness (eq. 8, (th1, th2) = -l/30)
    of the planar beam element, dofs (u1, v1, th1, u2, v2, th2) (beam_element.py)."""
    M, K, KG = numeric_element_matrices()(l, sec.E * sec.A, sec.E * sec.I, sec.rho * sec.A)
    return np.asarray(M, dtype=float), np.asarray(K, dtype=float), np.asarray(KG, dtype=float)


@dataclass(frozen=True)
class ShapeData:
    """A mode of a body as nodal values in s = x/L: axial (u) or bending (v, dv/ds)."""

    axis: str
    values: tuple[float, ...]  # u or v at every node (root included)
    slopes: tuple[float, ...] = ()  # dv/ds at every node (bending)
    frequency: float | None = None  # rad/s, for normal modes


def _axis_dofs(body: BeamBody, axis: str) -> np.ndarray:
    n = body.elements
    if axis == "axial":
        return np.array([3 * i for i in range(n)])
    return np.array([3 * i + c for i in range(n) for c in (1, 2)])


def _eig(K: np.ndarray, M: np.ndarray):
    from scipy.linalg import eigh

    w2, X = eigh(K, M)
    return w2, X


def _mode_cache(body: BeamBody, axis: str, family: str, index: int) -> ShapeData:
    key = (body.digest, axis, family, index)
    hit = _SHAPES.get(key)
    if hit is None:
        hit = _SHAPES[key] = _compute_mode(body, axis, family, index)
    return hit


_SHAPES: dict = {}


def _static_mode(body: BeamBody, axis: str) -> ShapeData:
    """The constraint mode in exact rational arithmetic (every double is a rational): the
    response to a tip load, u' = c / EA or v'' = c (L - x) / EI per element, normalised to a
    unit tip value, rounded once to double. The element reproduces it exactly (nodal loads,
    piecewise constant sections), so this is the finite-element solution without its solve."""
    from fractions import Fraction as F

    x = [F(v) for v in body.nodes]
    L = x[-1]
    if axis == "axial":
        u = [F(0)]
        for e, sec in enumerate(body.sections):
            u.append(u[-1] + (x[e + 1] - x[e]) / (F(sec.E) * F(sec.A)))
        return ShapeData(axis, tuple(float(v / u[-1]) for v in u))
    v, th = [F(0)], [F(0)]
    for e, sec in enumerate(body.sections):
        l, c, ei = x[e + 1] - x[e], L - x[e], F(sec.E) * F(sec.I)
        v.append(v[-1] + th[-1] * l + (c * l**2 / 2 - l**3 / 6) / ei)
        th.append(th[-1] + (c * l - l**2 / 2) / ei)
    return ShapeData(axis, tuple(float(a / v[-1]) for a in v),
                     tuple(float(b * L / v[-1]) for b in th))


def _compute_mode(body: BeamBody, axis: str, family: str, index: int) -> ShapeData:
    if family == "static":
        return _static_mode(body, axis)
    M, K, _ = body.assembled
    dofs = _axis_dofs(body, axis)
    Ka, Ma = K[np.ix_(dofs, dofs)], M[np.ix_(dofs, dofs)]
    nd = len(dofs)
    tip = nd - 1 if axis == "axial" else nd - 2  # u_n, or v_n (the tip rotation stays free)
    inner = np.array([i for i in range(nd) if i != tip])
    x = np.zeros(nd)
    keep = inner if family in ("sine", "clamped_pinned") else np.arange(nd)
    if index > len(keep):
        raise SpecError(f"{axis} mode {family}{index}: the body's {body.elements} elements "
                        f"have only {len(keep)} such modes")
    w2, X = _eig(Ka[np.ix_(keep, keep)], Ma[np.ix_(keep, keep)])
    x[keep] = X[:, index - 1]
    freq = math.sqrt(max(w2[index - 1], 0.0))
    norm = math.sqrt(x @ Ma @ x / (body.reference.rho * body.reference.A * body.length))
    x /= norm
    big = np.abs(x).max()
    vals = x if axis == "axial" else x[0::2]
    first = next(v for v in vals if abs(v) > 1e-8 * big)
    if first < 0:
        x = -x
    L = body.length
    if axis == "axial":
        return ShapeData(axis, (0.0,) + tuple(float(v) for v in x), (), freq)
    return ShapeData(axis, (0.0,) + tuple(float(v) for v in x[0::2]),
                     (0.0,) + tuple(float(v) * L for v in x[1::2]), freq)


# ----- geometric stiffness from unit inertial loads (spatial bodies) ----------------------
# A frame's motion loads its undeformed body, per unit mass at r, with -(a + alpha x r +
# omega x (omega x r)), a = the frame origin's acceleration minus gravity (all in the frame's
# components): linear in twelve unit cases, as the SID standard input data hold them, the six
# products omega_i omega_j, the three alpha_i and the three a_i. Each case's axial forces N_e
# (a static solve of the clamped body) give its geometric stiffness sum_e N_e K_G,e (the
# element's, eq. 8, in both bending planes), projected on the modes.
AXES = "xyz"
LOAD_CASES = (tuple(f"ww_{AXES[i]}{AXES[j]}" for i in range(3) for j in range(i, 3))
              + tuple(f"al_{c}" for c in AXES) + tuple(f"a_{c}" for c in AXES))


def load_case_field(case: str) -> tuple[np.ndarray, np.ndarray]:
    """(C, d): the case's load per unit mass at r is -(C r + d)."""
    C, d = np.zeros((3, 3)), np.zeros(3)
    kind, axes = case.split("_")
    k = [AXES.index(c) for c in axes]
    if kind == "ww":  # omega x (omega x r) = (omega omega^T - |omega|^2 I) r
        i, j = k
        C[i, j] += 1.0
        C[j, i] += 1.0 if i != j else 0.0
        if i == j:
            C -= np.eye(3)
    elif kind == "al":  # alpha x r
        e = np.eye(3)[k[0]]
        C = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
    else:
        d[k[0]] = 1.0
    return C, d


def load_case_scale(case: str) -> int:
    """N of a unit case is rho A L^m times a number: m = 1 for a_i, 2 for the others."""
    return 1 if case.startswith("a_") else 2


def load_case_forces(body: BeamBody) -> dict[str, np.ndarray]:
    """Per case, the axial force N_e of every element [N per unit case] of the clamped body:
    K u = F on the axial dofs with the consistent nodal loads of the case's axial load
    -(C r + d)_x rho A on the undeformed axis r = (x, 0, 0) and at the point masses, N_e =
    E A (u_e+1 - u_e) / l. (Its transverse load bends the body and adds no axial force.)"""
    M, K, _ = body.assembled
    ax = np.arange(0, K.shape[0], 3)
    Ka = K[np.ix_(ax, ax)]
    gx, gw = gauss()
    x = np.array(body.nodes)
    out = {}
    for case in LOAD_CASES:
        C, d = load_case_field(case)
        F = np.zeros(body.elements + 1)
        for e, sec in enumerate(body.sections):
            l = x[e + 1] - x[e]
            xs = x[e] + l * gx
            q = -(C[0, 0] * xs + d[0]) * sec.rho * sec.A * gw * l
            F[e] += (q * (1 - gx)).sum()
            F[e + 1] += (q * gx).sum()
        for pm in body.masses:
            F[body.node_index(pm.x)] += -(C[0, 0] * pm.x + d[0]) * pm.mass
        u = np.concatenate([[0.0], np.linalg.solve(Ka, F[1:])])
        out[case] = np.array([s.E * s.A for s in body.sections]) * np.diff(u) / np.diff(x)
    return out


def load_case_stiffness(body: BeamBody, shapes: list[ShapeData]) -> dict[str, np.ndarray]:
    """The cases' geometric stiffness projected on bending modes (shapes, in one plane: the
    element's K_G does not depend on I), over rho_ref A_ref L^(m-1) (load_case_scale): the
    numbers D with V = 1/2 sum_c f_c rho A L^(m_c - 1) q^T D_c q; cases without axial force
    left out."""
    n, L, r = body.elements, body.length, body.reference
    bend = np.array([3 * i + c for i in range(n) for c in (1, 2)])
    Phi = np.zeros((2 * n, len(shapes)))
    for k, sh in enumerate(shapes):
        Phi[0::2, k] = sh.values[1:]
        Phi[1::2, k] = np.array(sh.slopes[1:]) / L
    out = {}
    for case, KG in load_case_geometric(body).items():
        scale = r.rho * r.A * L**load_case_scale(case)
        D = Phi.T @ KG[np.ix_(bend, bend)] @ Phi / (scale / L)
        out[case] = np.vectorize(round_sig)(D)
    return out


def load_case_geometric(body: BeamBody) -> dict[str, np.ndarray]:
    """Per case with an axial force, its geometric stiffness sum_e N_e K_G,e [N/m per unit
    case] over the free dofs (u, v, theta of nodes 1..n; K_G,e does not depend on I, so it is
    either bending plane's)."""
    n, r = body.elements, body.reference
    out = {}
    for case, N in load_case_forces(body).items():
        if np.abs(N).max() <= ORTHO_TOL * r.rho * r.A * body.length**load_case_scale(case):
            continue
        KG = np.zeros((3 * (n + 1), 3 * (n + 1)))
        for e, sec in enumerate(body.sections):
            _, _, kge = element_matrices(sec, body.nodes[e + 1] - body.nodes[e])
            idx = np.arange(3 * e, 3 * e + 6)
            KG[np.ix_(idx, idx)] += N[e] * kge
        out[case] = KG[3:, 3:]
    return out


# ----- a spatial body's matrices (the folder format's, feimport.py) -----------------------
# Six dofs per free node, as finite-element programs write them: u axial, v and w the
# deflections along y and z, phi the twist, theta_y = -dw/dx and theta_z = dv/dx (rotations
# about the axes, right-hand rule). The equations decouple: the planar body's (u; v, theta_z),
# the view "z"'s bending (w, -theta_y) and the view "torsion"'s bar (phi).
SPATIAL_DOFS = ("u", "v", "w", "phi", "theta_y", "theta_z")
_PLANES = {"y": ((0, 0, 1.0), (1, 1, 1.0), (2, 5, 1.0)),  # (planar dof, spatial dof, sign)
           "z": ((1, 2, 1.0), (2, 4, -1.0)),  # bending only: u is the y plane's
           "torsion": ((0, 3, 1.0),)}


def _to_spatial(n: int, planes: dict[str, np.ndarray]) -> np.ndarray:
    """Planar matrices over the free dofs (u, v, theta of nodes 1..n) placed in the spatial
    layout (SPATIAL_DOFS of nodes 1..n), each plane's dofs as _PLANES maps them."""
    out = np.zeros((6 * n, 6 * n))
    for plane, mat in planes.items():
        src = np.array([3 * i + a for i in range(n) for a, _, _ in _PLANES[plane]])
        dst = np.array([6 * i + b for i in range(n) for _, b, _ in _PLANES[plane]])
        sign = np.array([c for _ in range(n) for _, _, c in _PLANES[plane]])
        out[np.ix_(dst, dst)] += sign[:, None] * mat[np.ix_(src, src)] * sign[None, :]
    return out


def spatial_matrices(body: BeamBody) -> tuple[np.ndarray, np.ndarray]:
    """(M, K) of a spatial body over the free dofs SPATIAL_DOFS of nodes 1..n: consistent mass
    with the point masses (on u, v, w), linear stiffness; per element the 12-dof spatial
    element (axial bar, Hermite bending in both planes, torsion bar: G J / l [1 -1; -1 1],
    rho I_p l / 6 [2 1; 1 2])."""
    views = {"y": body.assembled, "z": body.view("z").assembled,
             "torsion": body.view("torsion").assembled}
    return tuple(_to_spatial(body.elements, {p: m[k] for p, m in views.items()}) for k in (0, 1))


def spatial_load_case_geometric(body: BeamBody) -> dict[str, np.ndarray]:
    """load_case_geometric in the spatial layout: the bending blocks of both planes."""
    return {case: _to_spatial(body.elements, {"y": KG, "z": KG})
            for case, KG in load_case_geometric(body).items()}


# ----- piecewise evaluation ------------------------------------------------------------

def locate(body: BeamBody, s: np.ndarray, side: int = -1) -> np.ndarray:
    """Element index of each s; a node belongs to the element on its left (side=-1) or right."""
    sn = body.s_nodes
    if side < 0:
        e = np.searchsorted(sn, s, side="left") - 1
    else:
        e = np.searchsorted(sn, s, side="right") - 1
    return np.clip(e, 0, body.elements - 1)


def evaluate(body: BeamBody, shape: ShapeData, order: int, s, elem=None) -> np.ndarray:
    """d^order/ds^order of a shape at points s (inside element elem when given)."""
    s = np.atleast_1d(np.asarray(s, dtype=float))
    e = locate(body, s) if elem is None else np.full(s.shape, elem)
    sn = body.s_nodes
    h = sn[e + 1] - sn[e]
    t = (s - sn[e]) / h
    vals = np.array(shape.values)
    if shape.axis == "axial":
        u1, u2 = vals[e], vals[e + 1]
        if order == 0:
            return (1 - t) * u1 + t * u2
        if order == 1:
            return (u2 - u1) / h
        return np.zeros_like(s)
    d = np.array(shape.slopes)
    v1, d1, v2, d2 = vals[e], d[e] * h, vals[e + 1], d[e + 1] * h
    if order == 0:
        N = (1 - 3 * t**2 + 2 * t**3, t - 2 * t**2 + t**3, 3 * t**2 - 2 * t**3, -t**2 + t**3)
    elif order == 1:
        N = tuple(n / h for n in (-6 * t + 6 * t**2, 1 - 4 * t + 3 * t**2, 6 * t - 6 * t**2,
                                  -2 * t + 3 * t**2))
    elif order == 2:
        N = tuple(n / h**2 for n in (-6 + 12 * t, -4 + 6 * t, 6 - 12 * t, -2 + 6 * t))
    elif order == 3:
        N = tuple(n / h**3 + 0 * t for n in (12.0, 6.0, -12.0, 6.0))
    else:
        return np.zeros_like(s)
    return N[0] * v1 + N[1] * d1 + N[2] * v2 + N[3] * d2


def nhat(body: BeamBody, s, elem=None) -> np.ndarray:
    """Centrifugal prestress N(x) / (rho_ref A_ref w^2 L^2 / 2): 1 - s^2 for a uniform beam
    without masses. N(x) = w^2 [int_x^L rho A xb dxb + sum of m_k x_k beyond x]."""
    s = np.atleast_1d(np.asarray(s, dtype=float))
    e = locate(body, s) if elem is None else np.full(s.shape, elem)
    mu = body.ratios()["mu"]
    sn = body.s_nodes
    # int_{s_e+1}^1 mu s ds for each element's right end
    seg = mu * (sn[1:]**2 - sn[:-1]**2) / 2
    beyond = np.concatenate([np.cumsum(seg[::-1])[::-1][1:], [0.0]])
    out = beyond[e] + mu[e] * (sn[e + 1]**2 - s**2) / 2
    r = body.reference
    for pm in body.masses:
        sk = pm.x / body.length
        out = out + np.where(sk >= s - 1e-15, pm.mass / (r.rho * r.A * body.length) * sk, 0.0)
    return 2 * out


def gauss(n: int = GAUSS_POINTS):
    x, w = np.polynomial.legendre.leggauss(n)
    return (x + 1) / 2, w / 2


# ----- modes as the derivation sees them ---------------------------------------------------

@dataclass(frozen=True)
class BodyMode:
    """A numerically computed mode of a body, with the interface of modes.Mode."""

    ref: object  # modes.ModeRef
    body: BeamBody = field(repr=False)
    shape: ShapeData = field(repr=False)
    exact = False
    eigenvalue = None

    @property
    def name(self) -> str:
        return self.ref.coordinate

    @property
    def latex(self) -> str:
        return rf"\hat{{\phi}}_{{{self.ref.token}}}"

    @property
    def expr(self):
        return f"<{self.body.elements}-element {self.ref.axis} shape {self.ref.token}>"

    @property
    def description(self) -> str:
        kind = {"static": "static constraint mode (unit tip displacement)",
                "sine": "fixed-interface normal mode (tip fixed)",
                "clamped_pinned": "fixed-interface normal mode (tip deflection fixed)",
                "fixed_free": "clamped-free normal mode",
                "clamped_free": "clamped-free normal mode"}[self.ref.family]
        f = f", {self.shape.frequency:.6g} rad/s" if self.shape.frequency is not None else ""
        idx = "" if self.ref.family == "static" else f" {self.ref.index}"
        return f"{self.ref.axis} {kind}{idx} of the {self.body.elements}-element body{f}"

    @property
    def bcs(self):
        from flexsym.model.modes import BoundaryCondition as B

        bc = [B(0, 0, 0)] if self.ref.axis == "axial" else [B(0, 0, 0), B(1, 0, 0)]
        if self.ref.family == "static":
            bc.append(B(0, 1, 1))
        elif self.ref.family in ("sine", "clamped_pinned"):
            bc.append(B(0, 1, 0))
        return tuple(bc)

    def numeric(self, order: int, at: float, side: int = 0) -> float:
        """The value at s = at; at a node, derivatives that jump are averaged over both sides
        (side 0), or the element's before (-1) or beyond (+1)."""
        ends = [evaluate(self.body, self.shape, order, at, locate(self.body, np.array([at]), k)[0])[0]
                for k in ((-1, 1) if side == 0 else (side,))]
        return float(sum(ends) / len(ends))

    def value_at(self, order: int, at, side: int = 0):
        import sympy as sp

        for bc in self.bcs:
            if bc.order == order and bc.at == at:
                return sp.Integer(bc.value)
        return sp.Float(repr(round_sig(self.numeric(order, float(at), side))), 17)


def body_mode(body: BeamBody, ref) -> BodyMode:
    return BodyMode(ref, body, body.mode_shape(ref.axis, ref.family, ref.index))


def round_sig(x: float, digits: int = SIG_DIGITS) -> float:
    return float(f"{x:.{digits - 1}e}") if x else 0.0


# ----- scene files ------------------------------------------------------------------------

SEGMENT_KEYS = {"length": "length", "density": "rho", "youngs_modulus": "E", "area": "A",
                "inertia": "I"}
SEGMENT_KEYS_3D = {"length": "length", "density": "rho", "youngs_modulus": "E", "area": "A",
                   "inertia_z": "I", "inertia_y": "Iy", "torsion_constant": "J", "shear_modulus": "G"}
DEFAULT_ELEMENTS = 100


def check_mesh_keys(r) -> None:
    """[body] elements / ef_elements of a scene (r: scene._Reader)."""
    tab = r.data["body"]
    for key in ("elements", "ef_elements"):
        v = tab.get(key)
        if v is not None and (isinstance(v, bool) or not isinstance(v, int) or not 1 <= v <= 2000):
            r.fail(f"[body] {key}", f"must be an integer in 1..2000 (got {v!r})")


def scene_body(r, spatial: bool = False) -> BeamBody:
    """The [body] table of a scene (r: scene._Reader): segments meshed with `elements` elements
    (for the modes) and point masses; a spatial beam's segments have the spatial section's keys
    (SEGMENT_KEYS_3D). An imported folder is read by feimport.scene_folder."""
    tab = r.data["body"]
    check_mesh_keys(r)
    keys = SEGMENT_KEYS_3D if spatial else SEGMENT_KEYS
    segs = tab.get("segments")
    if not isinstance(segs, list) or not segs or not all(isinstance(s, dict) for s in segs):
        r.fail("[body] segments", f"must be a non-empty list of tables {{{', '.join(keys)}}}")
    segments = []
    for i, seg in enumerate(segs):
        where = f"[body] segments[{i}]"
        unknown = sorted(set(seg) - set(keys))
        if unknown:
            r.fail(f"{where} {unknown[0]}", f"unknown key (known: {', '.join(keys)})")
        vals = {}
        for key, short in keys.items():
            v = seg.get(key)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
                    or not MIN_POSITIVE <= v <= MAX_MAGNITUDE:
                r.fail(f"{where} {key}", f"must be a positive number, {MIN_POSITIVE:g} <= x <= "
                       f"{MAX_MAGNITUDE:g} (got {v!r})")
            vals[short] = float(v)
        segments.append((vals.pop("length"), Section(**vals)))
    masses = []
    pms = tab.get("point_masses", [])
    if not isinstance(pms, list) or not all(isinstance(m, dict) for m in pms):
        r.fail("[body] point_masses", "must be a list of tables {x, mass, rotary}")
    for i, pm in enumerate(pms):
        where = f"[body] point_masses[{i}]"
        unknown = sorted(set(pm) - {"x", "mass", "rotary"})
        if unknown:
            r.fail(f"{where} {unknown[0]}", "unknown key (known: x, mass, rotary)")
        vals = {}
        for key in ("x", "mass", "rotary"):
            v = pm.get(key, 0.0)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0 \
                    or v > MAX_MAGNITUDE:
                r.fail(f"{where} {key}", f"must be a number >= 0 and <= {MAX_MAGNITUDE:g} (got {v!r})")
            vals[key] = float(v)
        masses.append(PointMass(**vals))
    total = sum(length for length, _ in segments)
    cuts = [0.0]
    for length, _ in segments:
        cuts.append(cuts[-1] + length)
    for i, m in enumerate(masses):
        if not any(abs(m.x - c) <= 1e-12 * total for c in cuts):
            r.fail(f"[body] point_masses[{i}] x", f"x = {m.x:g} m must be a segment end "
                   f"(one of {', '.join(f'{c:g}' for c in cuts)})")
    masses = [PointMass(next(c for c in cuts if abs(m.x - c) <= 1e-12 * total), m.mass, m.rotary)
              for m in masses]
    try:
        return BeamBody.from_segments(segments, tab.get("elements", DEFAULT_ELEMENTS), masses)
    except SpecError as exc:
        r.fail("[body]", str(exc))
