"""Equations of motion of a spatial System (dimension = 3) in relative coordinates on its
spanning tree (sympy): the 3D sibling of assemble.py, producing the same SystemDerivation, so
that sysgen.py, the templates and the runtime take it unchanged.

What is derived so far: rigid bodies, modal beams (uniform, or from finite-element data:
fedata.BeamBody, below) and the geometrically exact `ef` (spatial_ef.py), each through its kind
(physics/body_kinds/spatial/: the loop over the bodies asks the kind, never the body), joined
in a tree by revolute, prismatic, cylindrical and universal joints (turns and slides in series
about axes fixed in the frame they move; axis_motion), spherical joints (Euler parameters on
|e| = 1, a constraint row) and clamps, with loops closed by spherical, universal, revolute,
prismatic, cylindrical joints and clamps (_cut_rows: one mechanism, the kinds as data,
SPATIAL_CUT_ROWS), guided or motor-driven, under gravity, point forces, torques and
spring-dampers, beams with structural damping; a body may hang from a rigid body, from a
modal beam's marker or from an ef beam's node (the deformed section's frame: the kind's hang).
What is not (an ef beam's mass-proportional damping, ...) is refused up front by System.validate.

Each body's kinetic energy is written in placeholders of its frame's motion (omega, V) and
left to casadi (der.frame_T, sysgen.frame_kinetic_energy), which substitutes the actual motion
and forms Lagrange's equations by AD: expanding a ball joint's quartic frame motion times the
modal fields in sympy makes kernels too large to compile. Strain energies, gravity and the
generalised forces stay in sympy.

Kinematics, composed joint by joint in each body's own frame components (no trigonometric
identity ever has to be simplified): with a the joint's unit axis, Q = Rot(a, theta) its
rotation (Rodrigues) and s its slide along a, m_p and m_c the joint's marker on parent and
child, m = m_p + a s,
    omega_c = Q^T omega_p + a theta',    V_c = Q^T (V_p + omega_p x m) + a s' - omega_c x m_c,
    g_c = Q^T g_p,   A_c = A_p Q,   R_c = R_p + A_p m - A_c m_c
(revolute: s = 0; prismatic: theta = 0; cylindrical: both; a clamp: Q = I, s = 0; Q a = a). A
universal joint in the tree turns twice, by theta1 about a1 (parent_axis, parent's frame), then
by theta2 about a2 (axis, the child's frame): Q = Rot(a1, theta1) Rot(a2, theta2), omega_c =
Q^T omega_p + Rot(a2, theta2)^T a1 theta1' + a2 theta2', s = 0.
A beam's floating frame is its root section's; on it the beam carries, per unit s = x/L,
    r = (L s + u, v, vz),   u = axial modes (+ u_fs = -1/2 int (v_x^2 + vz_x^2) for #3),
    v, vz = the model's bending modes in the frame's x-y (I = I_z) and x-z (I_y) planes,
    phi = torsion: the model's torsion modes, the bar's shapes (variant.TORSION_MODES, the
          first fixed-free sin(pi s / 2), unless the scene gives others or none).
Energies (uniform beam; Euler-Bernoulli, St Venant torsion, rotary inertia of bending left
out, as the spatial benchmarks define it):
    T = 1/2 int rho A |V + r' + omega x r|^2 dx + 1/2 int rho (I_y + I_z) (phi' + omega.t)^2 dx,
        t = (1, v_x, vz_x) the tangent to first order;
    V_g = -m g.R - int rho A g_c.r dx;  strain terms of the variant's strain model, generalised:
    axial EA/2 int u_x^2, bending EI_z/2 int v_xx^2 + EI_y/2 int vz_xx^2, torsion GJ/2 int
    phi_x^2 (always, on the torsion coordinate), cubic EA/2 int u_x (v_x^2 + vz_x^2) (#1/#2:
    K_G in both planes from the axial modes), prestress 1/2 int N(x) (v_x^2 + vz_x^2) with
    N = rho A (omega_y^2 + omega_z^2)(L^2 - x^2)/2 (the centrifugal load of the frame's actual
    rotation about the axes across the beam; on a frame that joints spin, -V_p is in T, as in
    the plane: body_kinds/spatial/modal.py) and the load rho A (g_x - a_0x)(L - x) of the
    frame origin's acceleration and gravity along the beam (in T and V, as m3 holds it).
A beam from finite-element data: each term carries its section distribution (the table's
weights: rho A with the point masses, EA, EI_z, EI_y, GJ, rho (I_y + I_z)), each plane and the
torsion have their own modes from the mesh (modal._beam_modes), and prestress is the geometric
stiffness of the twelve unit inertial load cases projected on the modes times the frame's
actual omega_i omega_j, alpha_i and a_i (modal._load_case_energy: on a frame that joints spin
the omega_i omega_j cases' energy joins T, as the analytic V_p does; the alpha_i and a_i cases
are written into T and V as m3 holds them, so no force reads q'' and M stays symmetric).
What the generalisation keeps and drops: the bending planes couple only through the frame's
motion, the foreshortening and the cubic term (both planes in one stretch); torsion is
linear and couples to bending only through omega.t in T (the propeller moment of a section
needs its bending rotary inertia, left out by definition); the section's twist does not turn
the bending planes (second order).
Outputs: angle/rate of a joint (slide/slide_rate, angle2/rate2: its second coordinate),
x/y/z of a marker, u/v/vz and w (distance from the chord) at a station, N, Mx (torsion), My,
Mz at a station, constitutive or from equilibrium of the part beyond the station (the
variant's axial_force / moment), in the beam frame's components, the moments turned into the
deformed section's axes to first order; the shear forces Qy, Qz (always from equilibrium,
turned likewise); sigma(beam, x, y, z) = N/A - Mz y/I_z + My z/I_y; T, V, violation,
Hx/Hy/Hz (angular momentum about the origin), joint reactions (joint_reaction: a cut joint's
from its multipliers, a tree joint's from the momentum balance of the bodies beyond it).
Section moments: Mz = EI_z v_xx, My = -EI_y vz_xx, Mx = GJ phi_x (the loads of the part
beyond the station on the part before it).
"""
from __future__ import annotations

import math

import numpy as np
import sympy as sp

from flexsym.core.errors import SpecError
from flexsym.model.exact_numbers import exact
from flexsym.model.joint_kinds import KINDS
from flexsym.model.parameters import BEAM_PARAMS, SPATIAL_BEAM_PARAMS
from flexsym.model.system import (GROUND, SECOND, FlexibleBeam, Gravity, PointForce, SpringDamper,
                                  System, Torque, beam_station, length_scale, loads_at, output_beam,
                                  parse_output, section_at, section_point, station_side)
from flexsym.physics.assemble import (EF_T, Coordinate, SystemDerivation, _guided, add_spring,
                                      joint_coordinate, motor_torque, spring_force_on_a, start_of,
                                      violation)
from flexsym.physics.body_kinds.spatial import kind_of
from flexsym.physics.body_kinds.spatial.base import (Frame, Motion, along_motion, cross, euler_G, euler_rotation,
                                                     rotation, vec)
from flexsym.physics.lagrange import equations_of_motion
from flexsym.physics.spatial_ef import ef_elastic_output, ef_kinetic_output, rod_dissipation_output
from flexsym.model.maneuver import parse_expression, t
from flexsym.scenes.assembly import joint_motion


def spatial_params(system: System):
    """p: [rho, E, A, I, L, Iy, J, G] of each flexible body (plain names for one body)."""
    beams = [b for b in system.bodies if b.flexible]
    params, by_body = [], {}
    generic = [(gp.name, gp.symbol) for gp in BEAM_PARAMS + SPATIAL_BEAM_PARAMS]
    for b in beams:
        sec = b.section
        values = {"rho": sec.rho, "E": sec.E, "A": sec.A, "I": sec.I, "L": b.length,
                  "Iy": sec.Iy, "J": sec.J, "G": sec.G}
        mapping = {}
        for name, sym in generic:
            pname = system.beam_param(b.name, name)
            psym = sym if len(beams) == 1 else sp.Symbol(pname, positive=True)
            params.append((pname, psym, float(values[name])))
            mapping[name] = psym
        by_body[b.name] = mapping
    return params, by_body


def derive_spatial(system: System, ef_free_ad: bool = False) -> SystemDerivation:
    """ef_free_ad: spatial ef beams on a free frame get their elements' kinetic energy through the
    whole-system AD path (der.casadi_T) instead of the per-element C kernels (a check)."""
    system.validate()
    tree = system.tree()
    guided = _guided(system)
    guided_by_joint = {g.joint: g for g in guided}  # by the guided coordinate's name
    params, psyms = spatial_params(system)

    coords: list[Coordinate] = []
    for body in tree.order:
        j = system.joint(tree.joint_of(body))
        if j.has_coordinate:  # a cylindrical joint's two, ..., but a guided one's
            coords += [Coordinate(c.name, "joint", body, j.name) for c in j.coordinates
                       if c.name not in guided_by_joint]
        elif KINDS[j.kind].euler:  # Euler parameters: e(0) turns x to direction, e' = G^T omega/2
            e0, ed0 = initial_euler(j.direction, j.rate)
            coords += [Coordinate(f"{j.name}_e{k}", "joint", body, j.name, (e0[k], ed0[k]))
                       for k in range(4)]
    body_kind = {b.name: kind_of(b) for b in system.bodies}  # body_kinds/spatial
    for b in system.bodies:
        coords += body_kind[b.name].coordinates(b)
    q = sp.Matrix([sp.Symbol(c.name, real=True) for c in coords])
    qd = sp.Matrix([sp.Symbol(c.name + "_d", real=True) for c in coords])
    qdd = sp.Matrix([sp.Symbol(c.name + "_dd", real=True) for c in coords])
    joint_sym: dict = {}
    for c, x, xd in zip(coords, q, qd):
        if c.group == "joint":
            joint_sym.setdefault(c.joint, []).append((x, xd))
    by_name = {c.name: (x, xd) for c, x, xd in zip(coords, q, qd)} | {g.joint: g.symbols[:2] for g in guided}
    for body in tree.order:  # each tree joint's coordinates in order, unknowns or guided
        j = system.joint(tree.joint_of(body))
        if j.coordinates:
            joint_sym[j.name] = [by_name[c.name] for c in j.coordinates]
    der = SystemDerivation(system, tree, coords, guided, q, qd, qdd, params)
    der.ef_free_ad = ef_free_ad
    der.spatial = {}
    der.rod_bodies, der.casadi_T, der.casadi_outputs = [], [], {}  # spatial ef beams (casadi)
    der.along = {}  # placeholder -> (expression, order) of along_motion
    der.casadi_T_out = []

    for b in system.bodies:  # what the kinds build once (a body may hang from a beam's marker)
        body_kind[b.name].part(der, b, psyms.get(b.name))

    grav = next((ld.g for ld in system.loads if isinstance(ld, Gravity)), (0, 0, 0))
    frames = {GROUND: Frame(sp.eye(3), sp.zeros(3, 1), sp.zeros(3, 1), sp.zeros(3, 1), vec(grav))}
    for body in tree.order:
        j = system.joint(tree.joint_of(body))
        if j.parent == GROUND:
            fp, m_p = frames[GROUND], vec(j.point)
        else:
            pbody, pm = system.marker(j.parent)
            fp, m_p = body_kind[pbody].hang(der, frames[pbody], pbody, pm)  # a beam's: its section's frame
        cm = system.marker(j.child)[1]
        m_c = vec((cm.x, cm.y, cm.z))
        if j.kind == "spherical":
            e = sp.Matrix([x for x, _ in joint_sym[j.name]])
            ed = sp.Matrix([xd for _, xd in joint_sym[j.name]])
            Q, rel = euler_rotation(e), 2 * euler_G(e) * ed
            # e.e = 1 as a constraint row scaled to a length (the runtime's tolerances are
            # lengths); (e.e')^2 k/2 in T makes M regular and vanishes with its forces on it
            scale = exact(length_scale(system))
            der.constraints.append((f"{j.name}.norm", scale * (e.dot(e) - 1) / 2))
            der.T += 2 * body_kind[body].spin_inertia(system.body(body), psyms.get(body)) * e.dot(ed)**2
            slide, v_rel = sp.zeros(3, 1), sp.zeros(3, 1)
        else:
            Q, rel, slide, v_rel = axis_motion(j, joint_sym.get(j.name, ()))
        m_p = m_p + slide
        omega = Q.T * fp.omega + rel
        # v_rel = a s' needs no Q^T: Q turns about a itself (a cylindrical joint), or is I
        V = Q.T * (fp.V + cross(fp.omega, m_p)) - cross(omega, m_c) + v_rel
        A_ = fp.A * Q
        R = fp.R + fp.A * m_p - A_ * m_c
        frames[body] = Frame(A_, R, omega, V, Q.T * fp.g)
    der.spatial["frames"] = frames
    _cut_rows(der)  # the loops' rows and their checks before the costly work

    der.V_grav, der.Q = sp.Integer(0), sp.zeros(len(coords), 1)  # the kinds add to them
    gvec = vec(grav)
    der.frame_T = []  # (T in the frame-motion placeholders, their actual values): sysgen, by AD
    for b in system.bodies:
        fr = frames[b.name]
        body_kind[b.name].contribute(der, b, psyms.get(b.name), fr, Motion.of(b.name, fr), gvec)
    V_grav, Q_ = der.V_grav, der.Q
    der.V += V_grav
    Q_ += sp.Matrix([-sp.diff(V_grav, x) for x in q])
    for load in system.loads:
        if isinstance(load, SpringDamper):
            Q_ += add_spring(der, load, _spring_ends(der, load))
    Q_ += _applied(der)
    der.Q = Q_.applyfunc(sp.expand)
    der.M, der.f = equations_of_motion(der.T, der.Q, q, qd, [gd.symbols for gd in guided])
    der.lam = sp.Matrix([sp.Symbol(f"lambda_{k}", real=True) for k in range(len(der.constraints))])
    der.outputs = {o.column: _output(der, o.quantity) for o in system.outputs}
    return der


def axis_motion(j, coordinates) -> tuple[sp.Matrix, sp.Matrix, sp.Matrix, sp.Matrix]:
    """A joint's motion from its coordinates' symbols (x, x') (Joint.coordinates: turns about and
    slides along their axes, in series): (Q, the parent marker's shift, the child's angular
    velocity relative to the parent, the shifted marker's velocity relative to the parent), the
    last two in the child's components, composed by assembly.joint_motion (the start's poses
    compose them the same way, with numbers) with exact axes."""
    return joint_motion(j, coordinates, rotation, _unit_vec)


def _unit_vec(axis) -> sp.Matrix:
    a = vec(axis)
    return a / sp.sqrt(a.dot(a))


def initial_euler(direction, rate) -> tuple[list[float], list[float]]:
    """A spherical joint's Euler parameters at t = 0: the shortest rotation turning the parent's
    x axis to `direction` (none: the identity), and their rates for the child's angular velocity
    `rate` relative to the parent (parent's frame): e' = G(e)^T A(e)^T omega / 2."""
    from flexsym.scenes.assembly import shortest_turn

    e = np.array([1.0, 0.0, 0.0, 0.0])
    if direction is not None:
        axis, angle = shortest_turn(direction)
        e = np.concatenate([[math.cos(angle / 2)], math.sin(angle / 2) * axis])
    w = np.asarray(rate if rate is not None else (0.0, 0.0, 0.0), float)
    A = np.array(euler_rotation(sp.Matrix(e)).evalf(), dtype=float)
    G = np.array(euler_G(sp.Matrix(e)).evalf(), dtype=float)
    return [float(v) for v in e], [float(v) for v in G.T @ (A.T @ w) / 2]


def _start_values(der) -> dict:
    """Every symbol's value at t = 0: the coordinates' starts (elastic 0: undeformed) and the
    guided joints' theta(0), theta'(0) (for checks and the universal joints' fixed axes)."""
    from flexsym.scenes.assembly import theta0

    vals = {}
    for c, x, xd in zip(der.coords, der.q, der.qd):
        vals[x], vals[xd] = start_of(der.system, c)
    drive0 = theta0(der.system)
    for g in der.guided:
        th, thd = drive0[g.joint]
        vals[g.symbols[0]], vals[g.symbols[1]] = th, thd
    return vals | {sym: v for _, sym, v in der.params}


def _section_rotation(der, ref: str) -> sp.Matrix:
    """Ground <- section axes at 'body.marker' (its kind's: a beam's section's)."""
    body, m = der.system.marker(ref)
    return kind_of(der.system.body(body)).section_rotation(der, body, m)


def _cut_point(der, ref: str, point) -> sp.Matrix:
    """A cut joint's side's point (ground's: the joint's point)."""
    return vec(point) if ref == GROUND else _marker_point(der, ref)


def _cut_axes_of(der, ref: str) -> sp.Matrix:
    """Ground <- a cut joint's side's section axes (ground's: I)."""
    return sp.eye(3) if ref == GROUND else _section_rotation(der, ref)


def _cut_rows(der) -> None:
    """Constraint rows of the joints that close loops, by kind as data (SPATIAL_CUT_ROWS,
    assembly.cut_axes), every row scaled to a length:
     * gap rows: the parent's point minus the child's, ground components (spherical, universal,
       revolute, clamp: .x, .y, .z), or along n1, n2 across the axis a, fixed in the parent's
       section (prismatic, cylindrical: .n1, .n2; the slide along a is free);
     * rotation rows u_c . w_p (u fixed in the child's section, w in the parent's), from the
       assembled start (cut_axes): a universal joint's one (.cross: its child's axis e1 stays
       perpendicular to e2, fixed in the parent's section, e2 at t = 0 perpendicular to e1 and to
       the parent's x axis); revolute, cylindrical: the child's copy of a across n1 and n2 (.a1,
       .a2: the axes stay parallel); prismatic, clamp: the relative rotation locked (.r1, .r2,
       .r3: the child's copy of the parent's triad f against the parent's, g2.f3, g3.f1, g1.f2).
    der.spatial["cuts"][name] = (first row, the rows' loads: ("gap", n, parent-fixed) per gap
    row, ("turn", u, w) per rotation row) for cut_load. Refused when a loop does not close at
    t = 0 (the scene reader assembles it first)."""
    from flexsym.scenes.assembly import cut_axes

    system = der.system
    scale = exact(length_scale(system))
    der.spatial["cuts"] = {}
    base = _start_values(der) if der.tree.cut else {}

    def at_start() -> dict:  # with the ef nodes' quaternions the rows have registered so far
        return base | getattr(der, "ef_start", {})

    for name in der.tree.cut:
        j = system.joint(name)
        first = len(der.constraints)
        loads = []
        turn_rows = KINDS[j.kind].cut_rows[1]
        if turn_rows in ("", "cross"):  # a ball's and a universal joint's, written first: their rows as they were
            gap = _cut_point(der, j.parent, j.point) - _marker_point(der, j.child)
            der.constraints += [(f"{name}.{c}", gap[k]) for k, c in enumerate("xyz")]
            loads += [("gap", None, False)] * 3
        if turn_rows == "cross":
            e1 = der.spatial["frames"][system.marker(j.child)[0]].A * vec(j.axis)
            e1 = e1 / sp.sqrt(vec(j.axis).dot(vec(j.axis)))
            Rp = _section_rotation(der, j.parent)
            start = at_start()  # after the rotations: an ef node's are registered then
            e1_0 = [float(v) for v in e1.xreplace(start).evalf()]
            x_0 = [float(v) for v in (Rp * sp.Matrix([1, 0, 0])).xreplace(start).evalf()]
            e2_0 = vec(_unit(np.cross(e1_0, x_0)))
            e2_local = sp.Matrix([exact(float(v)) for v in (Rp.xreplace(start).evalf().T * e2_0)])
            e2 = Rp * e2_local
            der.constraints.append((f"{name}.cross", scale * e1.dot(e2)))
            loads.append(("turn", e1, e2))
        elif turn_rows:
            Ap, Ac = _cut_axes_of(der, j.parent), _cut_axes_of(der, j.child)
            p, c = _cut_point(der, j.parent, j.point), _marker_point(der, j.child)
            start = at_start()
            A0 = [np.array(A.xreplace(start).evalf(), dtype=float) for A in (Ap, Ac)]
            across, pairs = cut_axes(j, *A0)
            if across is None:
                der.constraints += [(f"{name}.{k}", p[i] - c[i]) for i, k in enumerate("xyz")]
                loads += [("gap", None, False)] * 3
            else:
                for k, n in enumerate(across):
                    n = Ap * sp.Matrix([exact(float(v)) for v in n])
                    der.constraints.append((f"{name}.n{k + 1}", (p - c).dot(n)))
                    loads.append(("gap", n, True))
            for label, u, w in pairs:
                u, w = (A * sp.Matrix([exact(float(v)) for v in x]) for A, x in ((Ac, u), (Ap, w)))
                der.constraints.append((f"{name}.{label}", scale * u.dot(w)))
                loads.append(("turn", u, w))
        der.spatial["cuts"][name] = (first, loads, scale)
    if der.tree.cut:
        start = at_start()
        for row, phi in der.constraints:
            if row.endswith(".norm"):
                continue
            gap = float(sp.sympify(phi.xreplace(start)).evalf())  # a bare coordinate's row: a float
            if abs(gap) > 1e-9 * float(scale):
                raise SpecError(f"system '{system.name}': joint '{row.split('.')[0]}' does not close "
                                f"at t = 0 ({row}: {gap:.3g} m): assemble the system first "
                                "(scenes.system_scene.checked_system; the scene reader does)")


def _unit(v):
    """v normalised (not 0: check_assembly refused an axis along the parent's x at t = 0)."""
    n = math.sqrt(sum(c * c for c in v))
    return [c / n for c in v]


def cut_loads(der, beam: str) -> list[tuple[sp.Matrix, sp.Matrix, str]]:
    """(force, torque) in ground components that each cut joint exerts on `beam`, and the
    marker (cut_load, per side)."""
    out = []
    for name in der.spatial.get("cuts", {}):
        j = der.system.joint(name)
        for side, ref in (("parent", j.parent), ("child", j.child)):
            if ref != GROUND and der.system.marker(ref)[0] == beam:
                out.append((*cut_load(der, name, side), ref))
    return out


def cut_load(der, name: str, side: str) -> tuple[sp.Matrix, sp.Matrix]:
    """(force, torque about the side's point) in ground components that cut joint `name` exerts
    on its `side`: minus Phi_q^T lambda split by side, row by row (cut_rows' loads). A gap row
    n . (p - c): -lambda n on the parent, +lambda n on the child, and where n turns with the
    parent (across an axis) the parent's torque -lambda n x (p - c) (the force acts where the
    child's point is); a rotation row s u . w (u the child's, w the parent's): the torques
    -lambda s u x w on the child and -lambda s w x u on the parent."""
    first, loads, scale = der.spatial["cuts"][name]
    force, torque = sp.zeros(3, 1), sp.zeros(3, 1)
    parent = side == "parent"
    gap = None
    for k, load in enumerate(loads):
        lam = der.lam[first + k, 0]
        if load[0] == "gap":
            n, turns = load[1], load[2]
            if n is None:  # along ground's axis k (the rows .x, .y, .z)
                force[k % 3] += -lam if parent else lam
                continue
            force += -lam * n if parent else lam * n
            if parent and turns:
                if gap is None:
                    j = der.system.joint(name)
                    gap = _cut_point(der, j.parent, j.point) - _marker_point(der, j.child)
                torque += -lam * cross(n, gap)
        else:
            u, w = load[1], load[2]
            mu = lam * scale
            torque += -mu * (cross(w, u) if parent else cross(u, w))
    return force, torque


def _momentum(der, bodies=None) -> sp.Matrix:
    """Angular momentum about the ground origin of `bodies` (None: all), ground components:
    per rigid body m G x v_G + A (I omega); per beam A [int rho A (A^T R + r) x v dx + int rho
    (I_y + I_z) spin t dx] (the momentum conjugate to this T's rotation: conserved about an
    axis about which nothing acts)."""
    H = sp.zeros(3, 1)
    for b in der.system.bodies:
        if bodies is not None and b.name not in bodies:
            continue
        H += kind_of(b).momentum(der, b, der.spatial["frames"][b.name])
    return H


def _drive_load(der, driver) -> sp.Expr:
    """What a guided coordinate's drive applies, from its joint's reaction (joint_reaction: the
    momentum balance of the bodies beyond it): an ideal joint's constraint loads do no work
    along its own motions, so the reaction's moment along a turn's axis (its force along a
    slide's) is the drive's. The axis in ground components: the first coordinate's in the
    parent marker's axes, the second's (a universal joint's, the child's; a cylindrical joint's
    slide, the same axis) in the child's. For systems whose kinetic energy casadi does not hold
    whole (spatial ef beams: per-element kernels); equal to motor_torque's Lagrange equation
    where both apply."""
    system = der.system
    j = system.joint(driver.joint)
    F, M = joint_reaction(der, j)
    k = [c.name for c in j.coordinates].index(system.driven(driver))
    c = j.coordinates[k]
    A = _cut_axes_of(der, j.parent) if k == 0 else der.spatial["frames"][system.marker(j.child)[0]].A
    a = A * _unit_vec(c.axis)
    return (M if c.motion == "turn" else F).dot(a)


def _first_moment(der, bodies) -> tuple[sp.Expr, sp.Matrix]:
    """(mass, first moment about the ground origin, ground components) of `bodies`: per rigid
    body m (R + A c), per modal beam m R + A int rho A r dx."""
    mass, S = sp.Integer(0), sp.zeros(3, 1)
    for name in sorted(bodies):
        b = der.system.body(name)
        m, Sb = kind_of(b).first_moment(der, b, der.spatial["frames"][name])
        mass, S = mass + m, S + Sb
    return mass, S


def joint_reaction(der, joint) -> tuple[sp.Matrix, sp.Matrix]:
    """_joint_reaction, once per derivation."""
    return der.once(("reaction", joint.name), lambda: _joint_reaction(der, joint))


def _joint_reaction(der, joint) -> tuple[sp.Matrix, sp.Matrix]:
    """(F, M): the force and the moment about the joint's child point P (ground components)
    that the joint's parent side exerts on its child side, constraint and drive loads together
    (as assemble.joint_reaction in the plane). A cut joint: its multipliers (cut_load). A tree
    joint: the momentum balance of the subtree beyond it, F = d^2/dt^2 (first moment) -
    external forces, M = dH_O/dt - external moments about O - P x F; a motor or guide on a
    joint inside the subtree is internal, on this joint it is part of the reaction."""
    if joint.name in der.tree.cut:
        return cut_load(der, joint.name, "child")
    system = der.system
    bodies = der.tree.subtree(system, joint.name)
    mass, S = _first_moment(der, bodies)
    F, Mo = sp.zeros(3, 1), sp.zeros(3, 1)  # external loads, moment about O

    def add(force, at):
        nonlocal F, Mo
        F, Mo = F + force, Mo + cross(at, force)

    def inside(ref):
        return ref != GROUND and system.marker(ref)[0] in bodies

    gvec = vec(next((ld.g for ld in system.loads if isinstance(ld, Gravity)), (0, 0, 0)))
    F, Mo = F + mass * gvec, Mo + cross(S, gvec)
    for b in sorted(bodies):  # dampers acting on the motion relative to a beam's frame
        load = kind_of(system.body(b)).damping_load(der, system.body(b))
        if load is not None:
            F, Mo = F + load[0], Mo + load[1]
    for load in system.loads:
        if isinstance(load, PointForce) and inside(load.marker):
            add(_point_force(der, load), _marker_point(der, load.marker))
        elif isinstance(load, Torque) and load.body in bodies:
            tau = _torque(der, load)
            Mo += der.spatial["frames"][load.body].A * tau if load.frame == "body" else tau
        elif isinstance(load, SpringDamper) and inside(load.a) != inside(load.b):
            ends = _spring_ends(der, load)
            Fa = spring_force_on_a(der, load, ends)
            if inside(load.a):
                add(Fa, ends[0])
            else:
                add(-Fa, ends[1])
    for name in der.tree.cut:
        j = system.joint(name)
        if inside(j.child) != inside(j.parent):
            side, ref = ("child", j.child) if inside(j.child) else ("parent", j.parent)
            Fc, tc = cut_load(der, name, side)
            add(Fc, _marker_point(der, ref))
            Mo += tc
    P = _marker_point(der, joint.child)
    Fr = along_motion(der, S, 2) - F
    return Fr, along_motion(der, _momentum(der, bodies), 1) - Mo - cross(P, Fr)


def _marker_point(der, ref: str) -> sp.Matrix:
    """Ground position of 'body.marker' (on a beam: the deformed axis point)."""
    body, m = der.system.marker(ref)
    return kind_of(der.system.body(body)).marker_point(der, body, m)


def _spring_ends(der, load: SpringDamper) -> list[sp.Matrix]:
    return [vec(pt) if ref == GROUND else _marker_point(der, ref)
            for ref, pt in ((load.a, load.point_a), (load.b, load.point_b))]


def _applied(der, wrt=None) -> sp.Matrix:
    """Generalised forces of point forces, motors and torques (virtual power: F . dr/dx,
    tau . d omega / dx') on the coordinates wrt (symbols: the unknowns by default, or a guided
    coordinate's theta for the torque it needs)."""
    system = der.system
    wrt = list(der.q) if wrt is None else list(wrt)
    rate = dict(zip(der.q, der.qd)) | {g.symbols[0]: g.symbols[1] for g in der.guided}
    Q = sp.zeros(len(wrt), 1)
    names = _names(der)
    for load in system.loads:
        if isinstance(load, PointForce):
            F = _point_force(der, load)
            p = _marker_point(der, load.marker)
            Q += sp.Matrix([F.dot(sp.diff(p, x)) for x in wrt])
        elif isinstance(load, Torque):  # virtual power tau . omega, omega in the body's axes
            fr = der.spatial["frames"][load.body]
            tau = _torque(der, load, names)
            if load.frame == "ground":
                tau = fr.A.T * tau
            Q += sp.Matrix([tau.dot(sp.diff(fr.omega, rate[x])) for x in wrt])
    for d in system.drivers:
        if d.kind == "motor":
            k = next(i for i, c in enumerate(der.coords) if c.name == system.driven(d))
            if der.q[k] in wrt:
                Q[wrt.index(der.q[k])] += parse_expression(d.expression, tuple(names.items()),
                                                           f"system '{system.name}': driver '{d.name}'")
    return Q


def _names(der) -> dict:
    """What a load's expression may name: t, each joint coordinate and its rate."""
    names = {"t": t}
    for c, x, xd in zip(der.coords, der.q, der.qd):
        if c.group == "joint":  # its name: the joint's, or J_slide, J_angle2 (Joint.coordinates)
            names[c.name], names[f"{c.name}_rate"] = x, xd
    return names


def _point_force(der, load: PointForce) -> sp.Matrix:
    """A point force's vector in ground components (given in the ground's or its body's axes)."""
    F = vec((load.fx, load.fy, load.fz))
    return der.spatial["frames"][der.system.marker(load.marker)[0]].A * F if load.frame == "body" else F


def _torque(der, load: Torque, names=None) -> sp.Matrix:
    """A torque load's vector, in its frame's components."""
    return sp.Matrix([parse_expression(e, tuple((names or _names(der)).items()),
                                       f"system '{der.system.name}': torque '{load.name or load.body}'")
                      for e in load.expression])


def _output(der, quantity: str) -> sp.Expr:
    system = der.system
    fn, args = parse_output(system, quantity)
    where = f"system '{system.name}': output '{quantity}'"
    second = any(fn in v[2:] for v in SECOND.values())  # a joint's second coordinate (slide, angle2)
    if fn in ("angle", "rate") or second:  # an unknown of q, or a guided coordinate's theta(t)
        j = system.joint(args[0])
        name = j.coordinates[1].name if second else j.name
        rate = fn == "rate" or fn in (v[3] for v in SECOND.values())
        return joint_coordinate(der, args[0], rate, where, coordinate=name)  # a cut joint: refused
    if fn == "R":  # ground <- the marker's axes (a beam's: its section's, to first order)
        return _section_rotation(der, args[0])["xyz".index(args[1]), "xyz".index(args[2])]
    if fn in ("x", "y", "z"):
        return _marker_point(der, args[0])["xyz".index(fn)]
    if fn == "torque":  # a motor's as given; a guided coordinate's by Lagrange's equation of it
        driver = next(d for d in system.drivers if d.name == args[0])
        if driver.kind == "guided" and getattr(der, "rod_bodies", None):
            return _drive_load(der, driver)  # ef beams' T is per-element C: not in Lagrange's here
        return motor_torque(der, driver, _applied, _spring_ends)
    if fn == "T":  # EF_T: what casadi adds (the bodies' T in their frame's motion)
        return der.T + EF_T + (ef_kinetic_output(der) if der.casadi_T_out else 0)
    ef = getattr(der, "rod_bodies", [])
    if fn == "V":
        return der.V + (ef_elastic_output(der) if ef else 0)
    if fn == "violation":
        return violation(der)
    if fn == "dissipation":  # 2 D: the power of the damped beams (an ef beam's: casadi)
        damped_rods = any(r["damped"] for r in getattr(der, "rod_bodies", ()))
        return 2 * (sp.Add(*der.dissipation.values()) + (rod_dissipation_output(der) if damped_rods else 0))
    if fn in ("Hx", "Hy", "Hz"):  # modal beams only (System.validate)
        return _momentum(der)["xyz".index(fn[1])]
    if fn == "reaction":  # x, y, z: the force; mx, my, mz: the moment (REACTION_COMPONENTS)
        F, M = joint_reaction(der, system.joint(args[0]))
        return (F if len(args[1]) == 1 else M)["xyz".index(args[1][-1])]
    beam = output_beam(system, fn, args)  # N and the moments: with the output's recovery, if named
    x, side = beam_station(system, beam, args[1], where), station_side(args[1])
    if fn == "sigma":
        return _sigma(der, beam, x, args[2:], where, side)
    kind = kind_of(beam)
    if fn in ("u", "v", "vz"):
        return kind.displacement(der, beam, x, fn)
    if fn == "w":  # distance from the chord root-tip
        p0, p1, px = (kind.axis_point(der, beam.name, xx) for xx in (0.0, beam.length, x))
        d = p1 - p0
        c = cross(d, px - p0)
        return sp.sqrt(c.dot(c) / d.dot(d))
    return _section(der, beam, x, fn, side)


def _sigma(der, beam: FlexibleBeam, x: float, point, where: str, side: int = 0) -> sp.Expr:
    """The normal stress at the section point (y, z): E eps with eps = u' - y v'' - z vz'',
    and Mz = E I_z v'', My = -E I_y vz'' (a fibre at y > 0 shortens under Mz > 0, as in the
    plane; one at z > 0 stretches under My > 0), so sigma = N/A - Mz y/I_z + My z/I_y, with the
    beam's N, My and Mz (constitutive or from equilibrium, modal or ef)."""
    y, z = (exact(c) for c in section_point(beam, x, point, where, side))
    P = der.spatial[beam.name]["P"]
    N, My, Mz = (_section(der, beam, x, f, side) for f in ("N", "My", "Mz"))
    sec = beam.section  # the section at x, as the run-time parameters scaled (section_at)
    A, Iz, Iy = (P[k] * exact(v / getattr(sec, k)) for k, v in zip(("A", "I", "Iy"), section_at(beam, x, side)))
    return N / A - Mz * y / Iz + My * z / Iy


def _section(der, beam: FlexibleBeam, x: float, fn: str, side: int = 0) -> sp.Expr:
    """N, Qy, Qz, Mx, My, Mz at station x in the deformed section's axes (its kind's: from its
    elements, constitutive or from the equilibrium of the part beyond x with _loads_beyond),
    on the station's side (system.station_side; the planar assemble._stress's)."""
    return kind_of(beam).section(der, beam, x, fn, _loads_beyond, side)


def _loads_beyond(der, beam: FlexibleBeam, x: float, fn: str, out: sp.Expr, section: sp.Matrix,
                  side: int = 0) -> sp.Expr:
    """out plus the loads on the part of `beam` beyond station x (frame components): the force
    Sx, Sy, Sz or the moment Mx, My, Mz about the section point (frame components) of the
    cut joints', the hung bodies', the point forces' and the spring ends' loads there (and at
    x where system.loads_at)."""
    at_x = loads_at(beam, x, side)
    fr = der.spatial["frames"][beam.name]
    kind = kind_of(beam)
    force, k = fn[0] == "S", "xyz".index(fn[1])

    def beyond(ref):  # a marker of this beam on the part beyond x
        if ref == GROUND:
            return None
        body, m = der.system.marker(ref)
        on = body == beam.name and (m.x > x or (at_x and m.x >= x))
        return m if on else None

    hung = [(-F, -M, j.parent) for j in der.system.joints  # bodies hung from markers beyond x
            if j.name not in der.tree.cut and beyond(j.parent)
            for F, M in [joint_reaction(der, j)]]  # (F, M: on the hung body, about the marker)
    for F, tau, ref in cut_loads(der, beam.name) + hung:
        m = beyond(ref)
        if m is None:
            continue
        Floc, tloc = fr.A.T * F, fr.A.T * tau
        if force:
            out += Floc[k]
        else:
            out += cross(kind.axis_point(der, beam.name, m.x) - section, Floc)[k] + tloc[k]
    for ld in der.system.loads:  # point forces and spring ends on the part beyond x
        if isinstance(ld, PointForce):
            acting = [(beyond(ld.marker), vec((ld.fx, ld.fy, ld.fz)), ld.frame == "body")]
        elif isinstance(ld, SpringDamper) and (beyond(ld.a) or beyond(ld.b)):
            Fa = spring_force_on_a(der, ld, _spring_ends(der, ld))
            acting = [(beyond(ld.a), Fa, False), (beyond(ld.b), -Fa, False)]
        else:
            continue
        for m, Fv, local in acting:
            if m is None:
                continue
            Floc = Fv if local else fr.A.T * Fv
            if force:
                out += Floc[k]
            else:
                out += cross(kind.axis_point(der, beam.name, m.x) - section, Floc)[k]
    return out
