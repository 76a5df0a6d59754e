"""Assembly at t = 0: position and velocity analysis on the joint coordinates, as multibody
codes do it, before anything is generated or run.

Every flexible body is undeformed (its elastic coordinates and their rates are 0); the cut
joints' constraints Phi(q, t) = 0 are solved for the *free* joint coordinates only: those of
the tree joints that are not guided and not `fixed`, starting from their `initial` values
(guesses; 0 when not given). A guided joint's coordinate and rate are its driver's theta(0),
theta'(0); a fixed coordinate never moves; a given `rate` never changes. In a spatial system
a ball joint's coordinates are two tilts of its `direction` across it (poses3), and its rate
in the velocity analysis is the child's angular velocity relative to the parent (three
components, the parent's axes: rates3).

Positions: Gauss-Newton with minimum-norm steps (numpy's least squares) on Phi scaled by the
mechanism's size, coordinates scaled likewise (a prismatic one by the size), each step halved
until |Phi| decreases. When it stalls from the guesses (a start with the bodies in line is
singular: the loop cannot be closed by first-order moves), it is retried with every free
coordinate turned by +NUDGE (rad, or NUDGE x the size for a prismatic joint), then by -NUDGE.
Refused: a loop that stays open (max |Phi| above CLOSE_TOL x the size), and a closed loop whose
Jacobian w.r.t. the free coordinates has lower rank there than at a generic configuration (a
dead point, or dependent joints). Velocities: the minimum-norm change of the free rates with
Phi_q q' + Phi_t = 0 (in 3D on the assembled positions, with a universal joint's cross axis
kept perpendicular: rates3).

Why: the runtime's consistent start (runtime_c/src/constrained.c cs_consistent_start) is a
Newton on *all* coordinates; given a loop that does not close, it closes it with the elastic
coordinates too, that is by deforming the bodies, and releases that strain at t = 0. Closed
here to rounding, the loop leaves it nothing to correct (its tolerance is newton_tol x the
length scale, 1e-12 by default), so a run starts with zero strain energy.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import sympy as sp

from flexsym.core.errors import SpecError
from flexsym.model.joint_kinds import KINDS, planar_cut_rows, planar_frame
from flexsym.model.maneuver import maneuver_of, parse_theta, t
from flexsym.model.system import GROUND, System

CLOSE_TOL = 1e-12  # a loop is closed when max |Phi| <= this x the size (the runtime's default)
RANK_TOL = 1e-8    # singular values below this x the largest one count as zero
NUDGE = 0.5        # rad (or x the size): the restart of a coordinate from a stalled start
MAX_ITER = 60
REACH_STEP = 0.1  # rad (x the size for a slide): a guided coordinate's largest change between
                  # two positions of the reach check (follow); Newton closes from there
RECENTRE = 0.3  # a ball joint's turn in follow (its Gibbs vector: tan of half its angle, about
                # 33 degrees) beyond which it is turned from where it is
REACH_TOL = 1e-9   # x the size: a loop the rigid linkage closes along the drives' motion


@dataclass(frozen=True)
class Assembly:
    """What the assembly did: per joint (name, unit, before, after) of the coordinates and of the
    rates that changed, the loop residual after it (m), and the size it is relative to."""

    moved: tuple = ()
    rates: tuple = ()
    residual: float = 0.0
    scale: float = 1.0
    loops: bool = False

    def line(self, newton_tol: float = CLOSE_TOL) -> str | None:
        """One line for stderr and the CSV header (None when nothing was moved); newton_tol: the
        run's, whose multiple of the size is what the runtime's consistent start leaves alone."""
        if not (self.moved or self.rates):
            return None
        parts = [f"joint {n} turned {b:.3g} {u} to [{', '.join(f'{c:.10g}' for c in m[0])}]" if m else
                 f"joint {n} moved {b - a:+.3g} {u} to {b:.10g}" for n, u, a, b, *m in self.moved]
        parts += [f"joint {n} rate set to [{', '.join(f'{c:.10g}' for c in m[0])}] {u}/s" if m else
                  f"joint {n} rate set to {b:.10g} {u}/s (from {a:g})" for n, u, a, b, *m in self.rates]
        tol = newton_tol * self.scale
        strain = ("below the runtime's tolerance {:.2g} m: elastic coordinates 0 at t = 0, no "
                  "initial strain energy" if self.residual <= tol else "ABOVE the runtime's "
                  "tolerance {:.2g} m (--newton-tol): its consistent start corrects it with every "
                  "coordinate, deforming the bodies, or refuses").format(tol)
        return f"assembly: {', '.join(parts)} (loop residual {self.residual:.2g} m, {strain})"


def guided_laws(system: System) -> dict:
    """theta(t) of each guided coordinate (sympy, in t), by its name (System.driven: a joint's
    own name, or J_slide, J_angle2)."""
    out = {}
    for d in system.drivers:
        if d.kind != "guided":
            continue
        if d.maneuver:
            expr = maneuver_of(d.maneuver).theta.subs(
                {sp.Symbol(k, positive=True): v for k, v in d.params})
        else:
            expr = parse_theta(d.expression)
        out[system.driven(d)] = expr
    return out


def theta0(system: System) -> dict:
    """(theta(0), theta'(0)) of each guided coordinate, by its name."""
    return {c: (float(e.subs(t, 0)), float(sp.diff(e, t).subs(t, 0))) for c, e in guided_laws(system).items()}


def _rot(phi, v):
    c, s = sp.cos(phi), sp.sin(phi)
    return (c * v[0] - s * v[1], s * v[0] + c * v[1])


def poses(system: System, q: dict) -> dict:
    """Each body's frame (X, Y, angle) with the tree joints' coordinates q[joint] (numbers or
    sympy expressions) and undeformed beams."""
    out = {GROUND: (0, 0, 0)}
    tree = system.tree()
    for body in tree.order:
        j = system.joint(tree.joint_of(body))
        phi_p = out[j.parent.partition(".")[0]][2] if j.parent != GROUND else 0
        p, phi = planar_frame(KINDS[j.kind], sp.Matrix(_world(system, out, j.parent, j.point)), phi_p,
                              j.offset, [q.get(j.name, 0)], lambda a: sp.Matrix(_axis(j, a)))
        m = _rot(phi, _local(system, j.child))
        out[body] = (p[0] - m[0], p[1] - m[1], phi)
    return out


def rotations3(system: System) -> dict:
    """Each body's frame of a spatial system at t = 0 (ground <- frame, numpy): the start
    geometry checks' numbers, before anything is derived."""
    return {b: np.array(A.evalf(), dtype=float) for b, (A, _) in poses3(system, start3(system)).items()}


def start3(system: System) -> dict:
    """Every joint coordinate's value at t = 0 by its name (Joint.coordinates; a guided joint's
    theta(0)): poses3's q."""
    return ({c.name: c.value for j in system.joints for c in j.coordinates}
            | {k: v[0] for k, v in theta0(system).items()})


def poses3(system: System, q: dict) -> dict:
    """Each body's frame of a spatial system (A: ground <- frame, R: its origin), composed as
    physics/spatial.py does (A_c = A_p Q, R_c = R_p + A_p m_p - A_c m_c) with undeformed beams:
    the coordinates of a revolute, prismatic, cylindrical or universal joint in the tree (q by
    their names, Joint.coordinates) turn the child about or slide it along their axes in series
    (joint_motion), a spherical joint by the shortest turn of x to its direction, tilted by
    q[joint] = (a, b) along two directions across it (the assembly's coordinates; absent: not
    tilted)."""
    out = {GROUND: (sp.eye(3), sp.zeros(3, 1))}
    tree = system.tree()
    for body in tree.order:
        j = system.joint(tree.joint_of(body))
        A_p, R_p = out[j.parent.partition(".")[0]] if j.parent != GROUND else out[GROUND]
        m_p = sp.Matrix(j.point) if j.parent == GROUND else _local3(system, j.parent)
        c = q.get(j.name, 0)
        Q, _, shift, _ = joint_motion(j, [(q.get(x.name, 0), 0) for x in j.coordinates], _turn3, _unit3)
        m_p = m_p + shift
        if j.kind == "spherical" and isinstance(c, tuple) and len(c) == 3:  # follow's turn of its base
            Q = _gibbs_turn(sp.Matrix(c)) * q[(j.name, "base")]
        elif j.kind == "spherical" and isinstance(c, tuple):  # the assembly's tilts
            d = sp.Matrix(_tilted(j.direction or (1.0, 0.0, 0.0), *c))
            v, cos = sp.Matrix([0, -d[2], d[1]]), d[0]  # x cross d, x . d (d a unit vector)
            K = sp.Matrix([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
            Q = sp.eye(3) + K + K * K / (1 + cos)  # the shortest turn of x to d (_Loops: d.x > -0.9)
        elif j.kind == "spherical" and j.direction is not None:
            Q = sp.Matrix(_turn(*shortest_turn(j.direction)))
        if (j.name, "turn") in q:  # rates3: (I + [w]x) Q turns by w (parent's axes) to first order
            w = q[(j.name, "turn")]
            Q = sp.Matrix([[1, -w[2], w[1]], [w[2], 1, -w[0]], [-w[1], w[0], 1]]) * Q
        A = A_p * Q
        out[body] = (A, R_p + A_p * m_p - A * _local3(system, j.child))
    return out


def _gibbs_turn(c):
    """The rotation of Gibbs vector c = tan(angle / 2) axis, I + 2 ([c]x + [c]x^2) / (1 + c.c):
    exact, rational, regular up to a half turn (symbols or numbers)."""
    K = sp.Matrix([[0, -c[2], c[1]], [c[2], 0, -c[0]], [-c[1], c[0], 0]])
    return sp.eye(3) + 2 * (K + K * K) / (1 + c.dot(c))


def joint_motion(j, coordinates, turn, unit) -> tuple[sp.Matrix, sp.Matrix, sp.Matrix, sp.Matrix]:
    """A joint's motion composed of its coordinates in series (Joint.coordinates, each a turn
    about or a slide along its axis; coordinates: their (x, x') in that order), the one
    composition of the derivation (physics/spatial.axis_motion: exact, symbolic) and of the
    start (poses3: numbers, x' = 0): (Q, the parent marker's shift in the parent's frame, the
    child's angular velocity relative to the parent and the shifted marker's velocity relative
    to it, both in the child's components). A turn by theta about a: Q <- Q Rot(a, theta) and
    the relative angular velocity turned into the new frame plus a theta' (a universal joint:
    Rot(a1, t1) Rot(a2, t2), Rot(a2, t2)^T a1 t1' + a2 t2'); a slide by s along a: a s and
    a s' (a cylindrical joint slides along the axis it turned about, Q a = a, so a is its
    direction in both frames); a clamp: Q = I. turn(axis, angle): the rotation; unit(axis):
    the unit vector."""
    Q, rel, shift, v_rel = sp.eye(3), sp.zeros(3, 1), sp.zeros(3, 1), sp.zeros(3, 1)
    for c, (x, xd) in zip(j.coordinates, coordinates):
        a = unit(c.axis)
        if c.motion == "turn":
            R = turn(c.axis, x)
            Q, rel = Q * R, R.T * rel + a * xd
        else:
            shift, v_rel = shift + a * x, v_rel + a * xd
    return Q, rel, shift, v_rel


def _unit3(axis) -> sp.Matrix:
    a = sp.Matrix(axis)
    return a / sp.sqrt(a.dot(a))


def _tilted(direction, a, b) -> list:
    """The unit direction d0 + a t1 + b t2, normalised (t1, t2: unit, across d0 and each other)."""
    d0 = np.asarray(direction, float) / np.linalg.norm(direction)
    t1 = np.cross(d0, np.eye(3)[int(np.argmin(np.abs(d0)))])
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(d0, t1)
    d = [d0[k] + a * t1[k] + b * t2[k] for k in range(3)]
    n2 = sum(x * x for x in d)
    n = sp.sqrt(n2) if isinstance(n2, sp.Basic) else math.sqrt(n2)  # symbols (_Loops) or numbers
    return [x / n for x in d]


def _turn3(axis, angle) -> sp.Matrix:
    a = _unit3(axis)
    K = sp.Matrix([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return sp.eye(3) + sp.sin(angle) * K + (1 - sp.cos(angle)) * K * K


def _local3(system, ref) -> sp.Matrix:
    m = system.marker(ref)[1]
    return sp.Matrix([m.x, m.y, m.z])


def across(axis) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(a, n1, n2): the unit axis and two unit directions across it and each other, a right-handed
    triad by one rule (n1 = a x e_k / |.|, e_k the coordinate axis least along a; n2 = a x n1):
    the directions a closing revolute, cylindrical or prismatic joint's rows are taken along."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    n1 = np.cross(a, np.eye(3)[int(np.argmin(np.abs(a)))])
    n1 /= np.linalg.norm(n1)
    return a, n1, np.cross(a, n1)


def cut_axes(j, A_p0: np.ndarray, A_c0: np.ndarray) -> tuple[list | None, list]:
    """A spatial joint closing a loop as data (SPATIAL_CUT_ROWS), from the two sides' axes at the
    assembled t = 0 (A_p0, A_c0: ground <- the parent's and the child's section, numpy; ground: I):
    (gap, pairs). gap: None (the two points coincide: three rows along ground's axes) or the
    parent-frame directions the gap is measured along ("across": n1, n2 of the axis, `across`);
    pairs: (label, u, w) of the rotation rows u_c . w_p = 0, u fixed in the child's section, w in
    the parent's (their frames' components): "axis": the parent's axis a carried into the child
    at t = 0 (u = A_c0^T A_p0 a) across n1 and across n2; "lock": the parent's triad f = (a, n1,
    n2) (a clamp: its section's axes) carried likewise, g_i . f_j for (i, j) = (2, 3), (3, 1),
    (1, 2), to first order the relative rotation's components along f_1, f_2, f_3 (each row's
    gradient at t = 0 a unit turn: well conditioned). All rows vanish at t = 0 by construction
    but the gap's, which the assembly closes. A universal joint's cross row is
    physics/spatial._cut_rows' own (as it was first written)."""
    gap_kind, turn = KINDS[j.kind].cut_rows
    if gap_kind == "point" and turn in ("", "cross"):
        return None, []
    if KINDS[j.kind].welds:  # its section's axes
        f = list(np.eye(3))
    else:
        f = list(across(j.axis))
    carry = A_c0.T @ A_p0  # child <- parent at t = 0
    g = [carry @ v for v in f]
    if turn == "axis":
        pairs = [("a1", g[0], f[1]), ("a2", g[0], f[2])]
    else:
        pairs = [("r1", g[1], f[2]), ("r2", g[2], f[0]), ("r3", g[0], f[1])]
    return (None if gap_kind == "point" else [f[1], f[2]]), pairs


def _end3(system, frames, j, side: str):
    """(A, the point) of a joint's side: a body's marker, or ground's point."""
    ref = getattr(j, side)
    if ref == GROUND:
        return sp.eye(3), sp.Matrix(j.point)
    A, R = frames[ref.partition(".")[0]]
    return A, R + A * _local3(system, ref)


def cut_rows3(system: System, frames: dict) -> list[tuple[str, object, bool]]:
    """(cut joint, Phi row, is a length) of a spatial system's loops with undeformed bodies: the
    two points coincide, or (prismatic, cylindrical: cut_axes) their gap has no component
    across the axis fixed in the parent; the rotation rows vanish at t = 0 by their definition
    (cut_axes; a universal joint's cross axis: physics/spatial.py), rates3 holds their rates."""
    rows = []
    for name in system.tree().cut:
        j = system.joint(name)
        (A_p, p), (_, c) = _end3(system, frames, j, "parent"), _end3(system, frames, j, "child")
        if KINDS[j.kind].cut_rows[0] == "across":
            rows += [(name, (p - c).dot(A_p * sp.Matrix(n)), True) for n in across(j.axis)[1:]]
        else:
            rows += [(name, p[k] - c[k], True) for k in range(3)]
    return rows


def shortest_turn(direction) -> tuple[np.ndarray, float]:
    """(unit axis, angle) of the rotation that turns x to `direction` about x cross direction
    (a half turn about z for -x): a ball joint's start, here and in its Euler parameters
    (physics/spatial.initial_euler)."""
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    axis = np.cross([1.0, 0.0, 0.0], d)
    n = np.linalg.norm(axis)
    return (axis / n if n > 0 else np.array([0.0, 0.0, 1.0])), math.atan2(n, d[0])


def _turn(axis, angle) -> np.ndarray:
    """Rodrigues: the rotation by angle about axis (normalised here)."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def _axis(j, angle, across: bool = False):
    """A planar joint's unit axis (or its normal) in ground, its parent turned by angle."""
    n = math.hypot(*j.axis)
    return _rot(angle, (-j.axis[1] / n, j.axis[0] / n) if across else (j.axis[0] / n, j.axis[1] / n))


def _local(system, ref):
    m = system.marker(ref)[1]
    return (m.x, m.y)


def _world(system, frames, ref, point=(0.0, 0.0)):
    if ref == GROUND:
        return point
    X, Y, phi = frames[ref.partition(".")[0]]
    m = _rot(phi, _local(system, ref))
    return (X + m[0], Y + m[1])


def cut_rows(system: System, frames: dict) -> list[tuple[str, object, bool]]:
    """(cut joint, Phi row, is a length) as assemble.cut_joint_rows with undeformed bodies:
    a pin's two points coincide; a clamp's angles too; a prismatic joint's child point lies on
    the parent's axis line and the angles agree."""
    rows = []
    for name in system.tree().cut:
        j = system.joint(name)
        sides = [(_world(system, frames, ref, point), frames[ref.partition(".")[0]][2] if ref != GROUND else 0)
                 for ref, point in ((j.parent, j.point), (j.child, (0.0, 0.0)))]
        rows += [(name, e, length) for _, e, length in
                 planar_cut_rows(KINDS[j.kind], *sides, j.offset, lambda a: _axis(j, a, across=True))]
    return rows


class _Loops:
    """Phi and Phi_q of the cut joints as numeric functions of all tree joint coordinates,
    dimensionless: lengths / size, a prismatic coordinate x size."""

    def __init__(self, system: System, scale: float, turned: bool = False):
        tree = system.tree()
        self.order = [j.name for j in system.joints]
        tree_joints = [system.joint(tree.joint_of(b)) for b in tree.order]
        # a spherical joint's two coordinates tilt its direction (poses3), unless it points
        # within 25 degrees of -x, where the shortest turn from x is near its singularity (it
        # stays as given); the others' are their own. turned (follow): each spherical joint's
        # three coordinates are a turn (a Gibbs vector) of its orientation self.base[name]
        balls = [j for j in tree_joints if j.kind == "spherical"] if turned else []
        tilted = balls or [j for j in tree_joints if j.kind == "spherical"
                           and (j.direction is None or j.direction[0] / math.hypot(*j.direction) > -0.9)]
        # per coordinate: its joint, its name (Joint.coordinates; None: a tilt or turn), its unit
        entries = []
        for j in tree_joints:
            entries += ([(j, None, 1.0)] * (3 if turned else 2) if j in tilted else
                        [(j, c.name, scale if c.motion == "slide" else 1.0) for c in j.coordinates])
        self.joints = [j for j, _, _ in entries]
        self.coords = [c for _, c, _ in entries]
        self.unit = np.array([u for _, _, u in entries])
        x = sp.symbols(f"x0:{len(self.joints)}", real=True)
        q = {}
        for j, c, xi, u in zip(self.joints, self.coords, x, self.unit):
            if c is None:
                q[j.name] = q.get(j.name, ()) + (xi,)
            else:
                q[c] = xi * u
        base = {j.name: sp.Matrix(3, 3, sp.symbols(f"b{k}_0:9", real=True)) for k, j in enumerate(balls)}
        q |= {(name, "base"): B for name, B in base.items()}
        if system.dimension == 3:
            rows = cut_rows3(system, poses3(system, q))
        else:
            rows = cut_rows(system, poses(system, q))
        self.names = [n for n, _, _ in rows]
        self.lengths = [length for _, _, length in rows]
        phi = sp.Matrix([e / scale if length else e for _, e, length in rows])
        args = [x, [b for B in base.values() for b in B]] if base else [x]
        self.base = {name: np.eye(3) for name in base}  # follow sets them
        # the bases' products repeat: printed once (S7: half the time to make, a quarter to evaluate)
        cse = bool(base)
        self._phi = sp.lambdify(args, phi, "numpy", cse=cse)
        self._jac = sp.lambdify(args, phi.jacobian(x), "numpy", cse=cse) if x else None

    def _args(self, x) -> list:
        return [x, np.concatenate([B.ravel() for B in self.base.values()])] if self.base else [x]

    def phi(self, x):
        return np.asarray(self._phi(*self._args(x)), dtype=float).reshape(-1)

    def jac(self, x):
        """(rows x coordinates); no coordinates (a loop through clamps only): rows x 0."""
        if self._jac is None:
            return np.zeros((len(self.names), 0))
        return np.asarray(self._jac(*self._args(x)), dtype=float).reshape(len(self.names), len(x))


def _newton(loops: _Loops, x0: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Gauss-Newton on the free entries from x0, minimum-norm steps, halved until |Phi|
    decreases; returns the best iterate."""
    x = x0.copy()
    r = loops.phi(x)
    for _ in range(MAX_ITER):
        if np.max(np.abs(r), initial=0.0) <= 1e-3 * CLOSE_TOL:
            break
        step = np.linalg.lstsq(loops.jac(x)[:, free], -r, rcond=None)[0]
        for _ in range(30):
            trial = x.copy()
            trial[free] += step
            rt = loops.phi(trial)
            if np.linalg.norm(rt) < np.linalg.norm(r):
                break
            step = step / 2
        else:
            break  # no decrease along the step: stalled
        x, r = trial, rt
    return x


def numeric_rank(a: np.ndarray) -> int:
    """The rank of a, singular values below RANK_TOL x the largest counting as zero."""
    if a.size == 0:
        return 0
    s = np.linalg.svd(a, compute_uv=False)
    return int(np.sum(s > RANK_TOL * s[0])) if s[0] > 0 else 0


def assemble(system: System, scale: float, t_end: float | None = None) -> tuple[System, Assembly]:
    """The system with its free joint coordinates and rates at t = 0 solved (see the module
    doc), and what moved; scale: the mechanism's size (m). SpecError when a loop cannot close
    or is singular at t = 0, or (t_end given) when the guided drives take it beyond its reach
    before t_end (follow)."""
    if not system.tree().cut:
        return system, Assembly(scale=scale)
    loops = _Loops(system, scale)
    guided = theta0(system)
    starts = {c.name: (c.value, c.rate) for j in loops.joints for c in j.coordinates}  # (value, rate)
    fixed = np.array([c in guided or j.fixed for j, c in zip(loops.joints, loops.coords)], dtype=bool)
    free = ~fixed
    x0 = np.array([guided[c][0] if c in guided else 0.0 if c is None else starts[c][0]
                   for j, c in zip(loops.joints, loops.coords)]) / loops.unit
    x, res = x0, np.max(np.abs(loops.phi(x0)), initial=0.0)
    if res > CLOSE_TOL:
        for nudge in (0.0, NUDGE, -NUDGE):
            start = x0.copy()
            start[free] += nudge
            x = _newton(loops, start, free)
            res = np.max(np.abs(loops.phi(x)), initial=0.0)
            if res <= CLOSE_TOL:
                break
        else:
            _cannot_close(system, loops, x, fixed, scale)
    jac = loops.jac(x)
    rank = numeric_rank(jac[:, free])
    generic = max(numeric_rank(loops.jac(_random(loops, k))[:, free]) for k in range(4))
    if rank < generic:
        _singular(system, loops, jac, free, rank)
    if t_end is not None:
        follow(system, loops, x, free, t_end, scale)

    moved, rates, joints = [], [], dict((j.name, j) for j in system.joints)
    for name, k in _ball_entries(loops).items():
        j, (a, b) = joints[name], x[k]
        if a or b:  # its direction tilted: reported as the angle turned
            d0 = np.asarray(j.direction or (1.0, 0.0, 0.0), float)
            d = np.array(_tilted(d0, a, b), dtype=float) * np.linalg.norm(d0)
            turn = math.atan2(np.linalg.norm(np.cross(d0, d)), float(d0 @ d))
            moved.append((f"{j.name} direction", "rad", 0.0, turn, [float(c) for c in d]))
            joints[j.name] = replace(j, direction=tuple(float(c) for c in d))
    for j, c, u, a, b in zip(loops.joints, loops.coords, loops.unit, x0, x):
        if c is not None and b != a:
            moved.append((_label(j, c), _unit(j, c), float(a * u), float(b * u)))
            joints[j.name] = replace(joints[j.name], **{_key(j, c, 0): float(b * u)})
    placed = replace(system, joints=tuple(joints[j.name] for j in system.joints))
    if system.dimension == 3:  # at the assembled positions
        J, slots, names = rates3(placed, guided, scale)
        _redundant(placed, J, slots, names, guided)
    else:
        J, slots = jac, list(zip(loops.joints, loops.coords, loops.unit))
    for (j, c), rate in _rates(placed, J, slots, guided).items():
        if c is None:  # a ball joint's turn rates
            rates.append((j.name, "rad", 0.0, float(np.linalg.norm(rate)), [float(w) for w in rate]))
            joints[j.name] = replace(joints[j.name], rate=tuple(float(w) for w in rate))
        else:
            rates.append((_label(j, c), _unit(j, c), 0.0, float(rate)))
            joints[j.name] = replace(joints[j.name], **{_key(j, c, 1): float(rate)})
    order = [j.name for j in system.joints]
    moved.sort(key=lambda m: order.index(m[0].split()[0]))
    rates.sort(key=lambda m: order.index(m[0].split()[0]))
    report = Assembly(tuple(moved), tuple(rates), float(res * scale), scale, True)
    return replace(system, joints=tuple(joints[j.name] for j in system.joints)), report


def _label(j, c: str) -> str:
    """A coordinate in the report: its joint, and a second one's field (J slide, J angle2)."""
    return j.name if c == j.name else f"{j.name} {j.fields_of(c)[0]}"


def _unit(j, c: str) -> str:
    return "m" if next(x.motion for x in j.coordinates if x.name == c) == "slide" else "rad"


def _key(j, c: str, rate: int) -> str:
    """The Joint field of coordinate c's value (rate 0) or rate (1) (Joint.coordinates)."""
    return j.fields_of(c)[rate]


def _rates(system: System, J: np.ndarray, slots: list, guided: dict) -> dict:
    """Velocity analysis at the assembled t = 0: {(joint, coordinate name or None for a ball
    joint's turn): its new rate} of the free rates, the minimum-norm change that makes
    Phi_q q' + Phi_t = 0 (refused when it cannot); J: Phi_q (dimensionless) over the rate
    slots (joint, coordinate name or a ball joint's component 0-2, unit)."""
    def given_rate(j, c):
        if c in guided:
            return guided[c][1]
        if isinstance(c, int):
            return None if j.rate is None else j.rate[c]
        return next(x.rate for x in j.coordinates if x.name == c)

    given = np.array([given_rate(j, c) or 0.0 for j, c, _ in slots]) / np.array([u for _, _, u in slots])
    free = np.array([c not in guided and given_rate(j, c) is None for j, c, _ in slots], dtype=bool)
    rhs = -J @ given
    if not np.max(np.abs(rhs), initial=0.0) > 0:
        return {}
    v = given.copy()
    v[free] += np.linalg.lstsq(J[:, free], rhs, rcond=None)[0]
    left = np.max(np.abs(J @ v))
    if left > 1e-9 * np.max(np.abs(J)) * np.max(np.abs(given)):  # round-off: consistent
        names = {j.name for (j, _, _), f in zip(slots, free) if not f}
        raise SpecError(f"system '{system.name}': the joints' rates at t = 0 cannot satisfy the "
                        f"loops: {', '.join(j.name for j in system.joints if j.name in names)} are "
                        "given (drivers' theta'(0), rate = ...) and the free rates cannot close the "
                        f"loops' velocities (residual {left:.3g}); give fewer rates")
    out = {}
    for (j, c, u), f, vi in zip(slots, free, v):
        if f:
            out.setdefault((j, None if isinstance(c, int) else c), []).append(vi * u)
    return {k: np.array(r) if k[1] is None else r[0] for k, r in out.items() if any(r)}


def _rate_slots(system: System, scale: float) -> list:
    """(joint, coordinate name or component, unit) of every tree joint rate: each coordinate's
    (Joint.coordinates; a slide's unit is the size), a ball joint's three turn rates (parent's
    axes)."""
    tree = system.tree()
    slots = []
    for j in (system.joint(tree.joint_of(b)) for b in tree.order):
        if j.kind == "spherical":
            slots += [(j, k, 1.0) for k in range(3)]
        slots += [(j, c.name, scale if c.motion == "slide" else 1.0) for c in j.coordinates]
    return slots


def rates3(system: System, guided: dict, scale: float):
    """(Phi_q, slots) of a spatial system's loops at its assembled coordinates: the derivative
    of the cut rows (poses3, points / size) w.r.t. each rate slot's small move, a ball joint's
    as the small turn (I + [w]x) of its child; a universal joint adds d/dt (e1 . e2) with e2
    fixed in the parent's section, perpendicular to e1 and the parent's x at t = 0 (as
    physics/spatial.py's row), so the cross's spin is set too."""
    slots = _rate_slots(system, scale)
    h = sp.symbols(f"h0:{len(slots)}", real=True)
    q = start3(system)
    for (j, c, u), hk in zip(slots, h):
        if isinstance(c, int):
            q[(j.name, "turn")] = q.get((j.name, "turn"), (0, 0, 0))[:c] + (hk,) + (0,) * (2 - c)
        else:
            q[c] = q[c] + hk * u
    frames = poses3(system, q)
    gaps = cut_rows3(system, frames)
    rows, names = [e / scale for _, e, _ in gaps], [n for n, _, _ in gaps]
    at0 = {hk: 0 for hk in h}
    for name in system.tree().cut:
        j = system.joint(name)
        if j.kind != "universal":
            A = [_end3(system, frames, j, side)[0] for side in ("parent", "child")]
            _, pairs = cut_axes(j, *(np.array(a.xreplace(at0), dtype=float) for a in A))
            rows += [(A[1] * sp.Matrix(u)).dot(A[0] * sp.Matrix(w)) for _, u, w in pairs]
            names += [name] * len(pairs)
            continue
        e1 = frames[j.child.partition(".")[0]][0] * sp.Matrix(j.axis) / math.sqrt(sum(c * c for c in j.axis))
        A_p = frames[j.parent.partition(".")[0]][0]  # an undeformed beam's section: its frame
        e1_0, A_p0 = np.array(e1.xreplace(at0), dtype=float).ravel(), np.array(A_p.xreplace(at0), dtype=float)
        e2_0 = np.cross(e1_0, A_p0[:, 0])
        rows.append(e1.dot(A_p * sp.Matrix(A_p0.T @ (e2_0 / np.linalg.norm(e2_0)))))
        names.append(name)
    J = sp.Matrix(rows).jacobian(h).xreplace(at0) if h else sp.zeros(len(rows), 0)
    return np.array(J.evalf(), dtype=float).reshape(len(rows), len(h)), slots, names


def _redundant(system: System, J: np.ndarray, slots: list, names: list, guided: dict) -> None:
    """A spatial loop's rows at the assembled t = 0 (rates3's Phi_q over the tree's rates that
    are not guided): rows that no rate moves (a planar loop's out-of-plane rows, run in 3D) are
    left out; if the others are dependent (a redundant loop), the motion runs (the runtime's
    block solve drops dependent rows: runtime_c/src/constrained.c cs_kkt) but the multipliers
    are one solution of many, so a reaction output is refused here, before any work."""
    reactions = [o.quantity for o in system.outputs if o.quantity.replace(" ", "").startswith("reaction(")]
    if not reactions or J.size == 0:
        return
    free = np.array([c not in guided for _, c, _ in slots], dtype=bool)
    Jf = J[:, free]
    big = np.max(np.abs(Jf), initial=0.0)
    moved = [i for i in range(len(Jf)) if np.max(np.abs(Jf[i]), initial=0.0) > 1e-12 * big]
    rank = numeric_rank(Jf[moved])
    if rank < len(moved):
        u = np.linalg.svd(Jf[moved])[0]
        null = u[:, rank:]  # the rows' dependent combinations
        joints = [n for n in system.tree().cut if any(names[moved[i]] == n for i in range(len(moved))
                                                      if np.max(np.abs(null[i]), initial=0.0) > 1e-6)]
        raise SpecError(f"system '{system.name}': joint(s) {', '.join(joints)}: the loops' constraints are "
                        f"redundant at t = 0 ({len(moved)} rows of rank {rank}): the reactions are "
                        f"statically indeterminate, output '{reactions[0]}' is refused (the motion runs "
                        "without it; or close the loop with a joint that leaves the redundant freedom)")


def _random(loops: _Loops, k: int) -> np.ndarray:
    return np.random.default_rng(k).uniform(-math.pi, math.pi, len(loops.joints))


def _names(loops: _Loops, mask) -> str:
    """The joints of the masked coordinates, in the file's order."""
    names = {j.name for j, m in zip(loops.joints, mask) if m}
    return ", ".join(n for n in loops.order if n in names) or "none"


def follow(system, loops, x0, free, t_end: float, scale: float) -> None:
    """Follow the rigid linkage (bodies undeformed) along its guided coordinates' motion on
    [0, t_end], from the assembled x0 by the assembly's Newton, in steps that move no guided
    coordinate by more than REACH_STEP; refuse a time where no free coordinates close the
    loop: the drives would take the mechanism beyond its reach, and its flexible bodies be
    stretched to follow them (what validity's strain gauge would flag after the run). A
    spherical joint turns freely there: three coordinates turning its orientation, started
    again from where it is whenever it has turned by RECENTRE (_turnable)."""
    laws = guided_laws(system)
    if not any(c in laws for c in loops.coords) or not loops.names:
        return
    if any(j.kind == "spherical" for j in loops.joints):
        loops, x0, free = _turnable(system, loops, x0, free, scale)
    turns = _ball_entries(loops)
    slots = [k for k, c in enumerate(loops.coords) if c in laws]
    fns = [sp.lambdify(t, laws[loops.coords[k]], "numpy") for k in slots]

    def at(time):
        return np.array([float(f(time)) for f in fns]) / loops.unit[slots]

    # one guided turn: its angle mod 2 pi is all the closure depends on, so a full turn covers
    # every later position
    turn = len(slots) == 1 and _unit(loops.joints[slots[0]], loops.coords[slots[0]]) == "rad"
    x, time, h = x0.copy(), 0.0, t_end / 200
    low = high = x0[slots[0]]
    while time < t_end and not (turn and high - low >= 2 * math.pi):
        h = min(h, t_end - time)
        target = at(time + h)
        if np.max(np.abs(target - x[slots])) > REACH_STEP and h > t_end * 1e-7:
            h /= 2
            continue
        trial = x.copy()
        trial[slots] = target
        trial = _newton(loops, trial, free)
        gap = np.max(np.abs(loops.phi(trial)), initial=0.0)
        if gap > REACH_TOL:
            if h > t_end * 1e-7:  # a smaller step first: Newton may have left the branch
                h /= 2
                continue
            probe = min(time + t_end / 100, t_end)  # how far open it is a little later
            later = x.copy()
            later[slots] = at(probe)
            rows = np.abs(loops.phi(_newton(loops, later, free)))
            k = int(np.argmax(rows))
            apart = f"{rows[k] * scale:.3g} m" if loops.lengths[k] else f"{rows[k]:.3g} rad"
            where = ", ".join(f"{_label(loops.joints[j], loops.coords[j])} {target[i] * loops.unit[j]:.4g} "
                              f"{_unit(loops.joints[j], loops.coords[j])}" for i, j in enumerate(slots))
            raise SpecError(f"system '{system.name}': the guided drives take the mechanism beyond its "
                            f"reach at t = {time + h:.4g} s ({where}): joint '{loops.names[k]}' (cut "
                            f"joint) cannot close with undeformed bodies (at t = {probe:.4g} s it stays "
                            f"{apart} open at best); its flexible bodies would be stretched to follow. "
                            "Fix the lengths or the drives, or end the run before (t_end)")
        x, time, h = trial, time + h, min(2 * h, t_end / 200)
        low, high = min(low, x[slots[0]]), max(high, x[slots[0]])
        for name, k in turns.items():  # its turn kept small: turned from where it is
            if np.linalg.norm(x[k]) > RECENTRE:
                loops.base[name] = np.asarray(_gibbs_turn(sp.Matrix(x[k])), dtype=float) @ loops.base[name]
                x[k] = 0.0


def _ball_entries(loops) -> dict:
    """Each spherical joint's entries of x (its tilts, or follow's turn)."""
    out: dict = {}
    for k, (j, c) in enumerate(zip(loops.joints, loops.coords)):
        if c is None:
            out.setdefault(j.name, []).append(k)
    return out


def _turnable(system, loops, x, free, scale):
    """The assembled position in follow's coordinates: each spherical joint's orientation (the
    shortest turn of x to its direction, tilted as x has it: poses3) as its base, its turn 0;
    a ball joint turns freely along a motion (its spin included) and its direction in its
    parent's frame may sweep a full turn, which the tilts d0 + a t1 + b t2 cannot follow."""
    turned = _Loops(system, scale, turned=True)
    tilts = _ball_entries(loops)
    value = {(j.name, c): v for j, c, v in zip(loops.joints, loops.coords, x) if c is not None}
    is_free = {(j.name, c): f for j, c, f in zip(loops.joints, loops.coords, free) if c is not None}
    for j in {j.name: j for j in turned.joints if j.kind == "spherical"}.values():
        d = j.direction or (1.0, 0.0, 0.0)
        if j.name in tilts:
            d = _tilted(d, *x[tilts[j.name]])
        turned.base[j.name] = _turn(*shortest_turn(d))
    new_x = np.array([0.0 if c is None else value[(j.name, c)] for j, c in zip(turned.joints, turned.coords)])
    new_free = np.array([c is None or is_free[(j.name, c)] for j, c in zip(turned.joints, turned.coords)])
    return turned, new_x, new_free


def _cannot_close(system, loops, x, fixed, scale):
    r = loops.phi(x)
    worst = int(np.argmax(np.abs(r)))
    name = loops.names[worst]
    j = system.joint(name)
    what = f"{abs(r[worst]) * scale:.4g} m" if loops.lengths[worst] else f"{abs(r[worst]):.4g} rad"
    how = (f"moving the free joint coordinates ({_names(loops, ~fixed)}; fixed: {_names(loops, fixed)})"
           if loops.joints else "with no joint coordinate to move")
    raise SpecError(f"system '{system.name}': joint '{name}' (cut joint, closes a loop): cannot close "
                    f"at t = 0: '{j.parent}' and '{j.child}' stay {what} apart at best, {how} with "
                    "undeformed bodies; fix the geometry, the fixed values, or give initial guesses "
                    "nearer the closed position")


def _singular(system, loops, jac, free, rank):
    u, s, _ = np.linalg.svd(jac[:, free])
    null = u[:, rank:]  # rows' combinations the free coordinates cannot move
    cut = sorted({loops.names[i] for i in range(len(loops.names))
                  if np.max(np.abs(null[i]), initial=0.0) > 1e-6})
    raise SpecError(f"system '{system.name}': joint{'s' if len(cut) > 1 else ''} "
                    f"{', '.join(repr(c) for c in cut)} (cut joint, closes a loop): singular at "
                    f"t = 0: the loop's constraint Jacobian w.r.t. the free joint coordinates "
                    f"({_names(loops, free)}) has rank {rank} < {len(loops.names)} rows there (a "
                    "dead point, bodies in line, or dependent joints); start the mechanism away "
                    "from it")
