"""Equations of motion of a System in relative coordinates on its spanning tree (sympy).

Unknowns q: the coordinates of the tree joints that are not guided (in tree order), then each
flexible body's elastic coordinates. A guided joint k contributes the drive entries
d = [t, theta_k, theta_k', theta_k''] (known functions of time, not unknowns).

Each body's frame pose (angle phi, origin R) is an expression of its parent's pose and its tree
joint's coordinate; a flexible beam's frame is its root's tangent frame. A body is reached only
through its kind (physics/body_kinds/: rigid, modal, exact, ef), which adds its coordinates,
its deformation part and its share of the energies and forces below, and gives the fields and
marker poses on it. Energies:
  rigid body   T = 1/2 m |v_G|^2 + 1/2 J phi'^2,  V_g = -m g.r_G
  modal beam   T = int 1/2 rho A |V + r' + phi' k x r|^2 dx in frame components (energy.py's
               kinetic_density with the frame's actual motion), V_g = -m g.R - int rho A g.A r dx,
               strain terms and their `wrt` groups exactly as the variant's strain model.
  ef beam      the same per ANCF element (efbody.py); its kinetic and elastic energies are
               differentiated by casadi AD in sysgen.py (der.T, M and f here leave them out;
               outputs read them through the placeholders EF_T and ef_guided_force).
Structural damping of a beam (system.Damping; none: nothing added): a dissipation function D
in the elastic rates relative to the frame, Q -= dD/dq' (rigid-body motion is not damped):
  modal beam   D = beta/2 int (EA u_x'^2 + EI v_xx'^2) dx  (the strain rate of the axial modes'
               stretch and the curvature: beta K q') + alpha/2 q'^T M_ee q' + sum_i c_i q_i'^2/2,
               c_i = 2 zeta_i sqrt(K_ii M_ii) (K, M_ee: undeformed, of the elastic coordinates)
  ef beam      efbody.generic_dissipation per element (Kelvin-Voigt on the Green strain and the
               material curvature; alpha on the element mass matrix), summed in casadi by
               sysgen (der.ef_damping); a body's point masses' alpha part here
The output `dissipation` is the power 2 D = q'^T dD/dq' (W) of every damped body.
Loads: gravity, motors, point forces, torques, spring-dampers. Cut joints give constraint rows
Phi(q, theta) (cut_joint_rows); sysgen.py differentiates them.
Lagrange with guided coordinates theta_k (p = dT/dq'), by lagrange.equations_of_motion:
  M = dp/dq',  f = dT/dq - (dp/dq) q' - sum_k (dp/dtheta_k theta_k' + dp/dtheta_k' theta_k'') + Q
Q: strain terms (their groups only), gravity, motors, point forces and torques.

Geometric stiffening per strain model in a system: #1/#2 (geometric_stiffness) and #3
(foreshortening) need nothing: the axial coordinates, or u_fs, respond to the frame's actual
motion through T. `prestress` keeps V_p = 1/2 int N(x) v_x^2, N(x) = rho A phi'^2 (L^2 - x^2)/2
with phi' the frame's actual rate: a potential that varies in time under a guided drive, and
on a frame that joints spin -V_p joins T (it is the part of m3's T linear in the
foreshortening), so the joints' equations take its rate dependence and T + V is conserved;
its sections, momentum and reactions then read the foreshortened fields (FlexPart.
inertial_fields). The axial load of the frame origin's acceleration and of gravity along the
beam, rho A (a_0x - g_x)(L - x), is in T and V as m3 holds it (body_kinds.modal.
root_load_energy). A beam loaded axially beyond its root (S2's coupler) is refused.
Outputs of q, q', q'', the drive and lambda: joint reactions (joint_reaction: a cut joint's
from lambda, a tree joint's from the momentum balance of the subtree beyond it), N and M from
equilibrium (_equilibrium_stress: the part of the beam beyond the station with the frame's
actual motion, gravity and the loads on its markers), the violation.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp
from sympy.core.function import AppliedUndef

from flexsym.model.exact_numbers import exact
from flexsym.physics.body_kinds import kind_of
from flexsym.physics.body_kinds.base import BodyFrame, cross, rot, station
from flexsym.physics.body_kinds.ef import EfKinetic
from flexsym.physics.body_kinds.modal import FlexPart
from flexsym.physics.energy import BEAM_PARAMS
from flexsym.physics.exact_body import EXACT_VG
from flexsym.core.errors import SpecError
from flexsym.physics.lagrange import equations_of_motion, jacobi_integral
from flexsym.model.joint_kinds import KINDS, planar_cut_rows, planar_frame
from flexsym.model.maneuver import Maneuver, Param, maneuver_of, parse_expression, parse_theta, t
from flexsym.model.system import (GROUND, Gravity, PointForce, SpringDamper, System, Torque,
                     beam_station, length_scale, loads_at, output_beam, parse_output,
                     section_at, section_point, station_side)

SECTION_PARAMS = ("rho", "E", "A", "I", "L")  # per flexible body, the order of BEAM_PARAMS


def _axis_direction(joint, angle, across: bool = False) -> sp.Matrix:
    """A planar joint's unit axis (or its normal, turned +90 degrees), in ground, its parent
    turned by angle."""
    ax = sp.Matrix([exact(a) for a in joint.axis])
    return rot(angle) * (sp.Matrix([-ax[1], ax[0]]) if across else ax) / sp.sqrt(ax.dot(ax))


@dataclass
class Coordinate:
    name: str
    group: str  # 'joint' | 'axial' | 'bending' | 'torsion' (spatial)
    body: str
    joint: str = ""
    start: tuple | None = None  # (value, rate) at t = 0 when not the joint's initial / rate


def start_of(system: System, c: Coordinate) -> tuple[float, float]:
    """A coordinate's (value, rate) at t = 0: its own start, else its joint's initial and rate,
    else 0 (an elastic coordinate: undeformed, at rest). The one place this is decided (the
    generated initial state, the spatial loop check)."""
    if c.start is not None:
        return c.start
    if c.group == "joint":  # by its name (Joint.coordinates: a cylindrical joint has two, ...)
        x = next(x for x in system.joint(c.joint).coordinates if x.name == c.name)
        return x.value, x.rate or 0.0
    return 0.0, 0.0


@dataclass
class Guided:
    joint: str
    driver: str
    theta: sp.Expr  # of t and the drive parameters
    params: tuple[Param, ...]
    symbols: tuple[sp.Symbol, sp.Symbol, sp.Symbol]  # theta, theta', theta''


@dataclass
class Pose:
    angle: sp.Expr
    R: sp.Matrix


# Placeholders in output expressions for what sysgen computes in casadi from the ef bodies'
# kinetic energy T_ef: T_ef itself, and per guided joint d/dt dT_ef/dtheta' - dT_ef/dtheta
# (T_ef with the exact beams' T and the T that reads their positions, plus dV_g/dtheta of their
# gravity).
EF_T = sp.Symbol("T_ef_", real=True)


# ... and the ef bodies' element dissipation D_ef (the output `dissipation` reads 2 D)
EF_D = sp.Symbol("D_ef_", real=True)


def ef_guided_force(joint: str) -> sp.Symbol:
    return sp.Symbol(f"Q_ef_{joint}_", real=True)


@dataclass
class SystemDerivation:
    system: System
    tree: object
    coords: list[Coordinate]
    guided: list[Guided]
    q: sp.Matrix
    qd: sp.Matrix
    qdd: sp.Matrix
    params: list[tuple[str, sp.Symbol, float]]  # (name, symbol, default)
    poses: dict[str, Pose] = field(default_factory=dict)
    flex: dict[str, FlexPart] = field(default_factory=dict)
    T: sp.Expr = sp.Integer(0)
    V: sp.Expr = sp.Integer(0)
    momentum: sp.Expr = sp.Integer(0)
    terms: list = field(default_factory=list)  # (body, term, wrt, V, Q)
    Q: sp.Matrix = None
    M: sp.Matrix = None
    f: sp.Matrix = None
    outputs: dict[str, sp.Expr] = field(default_factory=dict)
    constraints: list[tuple[str, sp.Expr]] = field(default_factory=list)  # Phi(q, theta) rows
    lam: sp.Matrix = None  # their multipliers (outputs read them)
    elastic: list = field(default_factory=list)  # ef bodies (EfPart) with elastic energy
                                                 # (sysgen: per element, by casadi AD)
    ef_kinetic: list[EfKinetic] = field(default_factory=list)  # not in T, M, f (sysgen)
    V_grav: sp.Expr = sp.Integer(0)
    # per body, ground frame: mass, first moment m r_G, angular momentum about the origin
    # (reactions of tree joints are the subtree's momentum balance)
    mass: dict = field(default_factory=dict)
    first_moment: dict = field(default_factory=dict)
    body_momentum: dict = field(default_factory=dict)
    dropped: list[dict] = field(default_factory=list)
    # structural damping: per damped body its dissipation function D (sympy, in q'; an ef
    # body's point masses only), and per damped ef body (alpha, beta) of its elements (sysgen)
    dissipation: dict = field(default_factory=dict)
    ef_damping: dict = field(default_factory=dict)
    exact_bodies: list = field(default_factory=list)  # ExactPart: T and V_g in casadi (sysgen)
    casadi_outputs: dict = field(default_factory=dict)  # placeholder -> value(tr, x) (sysgen)
    # applied-function placeholders, name -> value(tr, x): positions on an exact beam that sympy
    # differentiates (a body hangs from it, a load acts on it); sysgen gives their derivatives
    casadi_functions: dict = field(default_factory=dict)
    memo: dict = field(default_factory=dict)  # once(): what several outputs read
    # the terms of the kinetic energy that read them (a hanging body's): not in T, M, f; sysgen
    # translates it and adds its Lagrange terms by casadi AD, as the exact beams' own T
    T_casadi: sp.Expr = sp.Integer(0)

    @property
    def drive_symbols(self) -> list[sp.Symbol]:
        return [t] + [x for g in self.guided for x in g.symbols]

    @property
    def drive_params(self) -> list[Param]:
        return [p for g in self.guided for p in g.params]

    @property
    def outputs_use_acceleration(self) -> bool:
        """The outputs read q'' (reactions, N and M from equilibrium): the runtime computes it."""
        return any(e.has(*self.qdd) for e in self.outputs.values())

    @property
    def outputs_use_drive(self) -> bool:
        """The outputs read t or a guided joint's theta_k, theta_k', theta_k''."""
        return any(e.has(*self.drive_symbols) for e in self.outputs.values())

    def ddt(self, expr, order: int = 1):
        """Total time derivative along the motion (q, q', theta_k and their rates)."""
        if isinstance(expr, sp.MatrixBase):
            return expr.applyfunc(lambda e: self.ddt(e, order))
        rates = [*zip(self.q, self.qd), *zip(self.qd, self.qdd)]
        rates += [r for g in self.guided for r in (g.symbols[:2], g.symbols[1:])]
        expr = sp.sympify(expr)
        for _ in range(order):
            free = expr.free_symbols  # differentiated by what it holds only (a large sum, once)
            expr = sp.Add(*[sp.diff(expr, x) * xd for x, xd in rates if x in free])
        return expr

    def once(self, key, make):
        """make()'s value, made once per derivation (each output column reads one component
        of a joint's reaction, of a section's loads)."""
        if key not in self.memo:
            self.memo[key] = make()
        return self.memo[key]

    def energies(self) -> tuple[sp.Expr, sp.Expr, sp.Expr]:
        """(T, V, h = T2 - T0 + V): h is conserved when nothing is guided or motored and every
        term is conservative (then h = T + V). Without the ef bodies' T (sysgen adds it)."""
        return self.T, self.V, jacobi_integral(self.T, self.M, self.qd, self.V)


def check_derivable(system: System, tree=None) -> None:
    """Refuse, before any work, what the derivation does not support (one line)."""
    tree = tree or system.tree()
    where = f"system '{system.name}'"
    for b in system.bodies:
        kind_of(b).check(system, tree, b)
    for load in system.loads:
        if not isinstance(load, (Gravity, PointForce, Torque, SpringDamper)):
            raise SpecError(f"{where}: load {type(load).__name__} is not derived yet")


def param_layout(system: System) -> tuple[list, dict]:
    """p: [rho, E, A, I, L] of each flexible body (plain names for one body, as a one-beam
    variant's p, so that --param L=... keeps working; else body_rho, ...)."""
    beams = [b for b in system.bodies if b.flexible]
    params, by_body = [], {}
    for b in beams:
        values = {"rho": b.section.rho, "E": b.section.E, "A": b.section.A, "I": b.section.I,
                  "L": b.length}
        mapping = {}
        for gp in BEAM_PARAMS:
            name = system.beam_param(b.name, gp.name)
            sym = gp.symbol if len(beams) == 1 else sp.Symbol(name, positive=True)
            params.append((name, sym, float(values[gp.name])))
            mapping[gp.symbol] = sym
        by_body[b.name] = mapping
    return params, by_body


def _guided(system: System) -> list[Guided]:
    guided = [d for d in system.drivers if d.kind == "guided"]
    out = []
    for d in guided:
        where = f"system '{system.name}': driver '{d.name}'"
        if d.maneuver:
            try:
                man = maneuver_of(d.maneuver)
            except SpecError as exc:
                raise SpecError(f"{where}: {exc}") from None
            given = dict(d.params)
            unknown = set(given) - {p.name for p in man.params}
            if unknown:
                raise SpecError(f"{where}: manoeuvre '{man.name}' has no parameter "
                                f"{', '.join(sorted(unknown))}")
            theta, params = man.theta, []
            for p in man.params:
                name = p.name if len(guided) == 1 else f"{d.name}_{p.name}"
                np_ = Param(name, float(given.get(p.name, p.default)), p.unit, p.description)
                theta = theta.xreplace({p.symbol: np_.symbol})
                params.append(np_)
        else:
            try:
                theta = parse_theta(d.expression)
            except SpecError as exc:
                raise SpecError(f"{where}: {exc}") from None
            params = []
        j = system.driven(d)  # the joint's name, or its second coordinate's (J_slide, J_angle2)
        syms = (sp.Symbol(j, real=True), sp.Symbol(f"{j}_d", real=True),
                sp.Symbol(f"{j}_dd", real=True))
        out.append(Guided(j, d.name, theta, tuple(params), syms))
    return out


def derive_system(system: System, integral_symbols: bool = False) -> SystemDerivation:
    """integral_symbols: keep the modal integrals of T and the energy terms as the table's
    symbols (a one-beam variant's derivation, modal.py, which substitutes them at kernel
    time and lists them in its manifest); valid with one flexible body only."""
    system.validate()
    tree = system.tree()
    check_derivable(system, tree)
    guided = _guided(system)
    guided_by_joint = {g.joint: g for g in guided}
    params, psyms = param_layout(system)

    coords: list[Coordinate] = []
    joint_sym: dict[str, tuple] = {}  # joint -> (coordinate, rate) symbols
    for body in tree.order:
        j = system.joint(tree.joint_of(body))
        if j.has_coordinate and j.name not in guided_by_joint:
            coords.append(Coordinate(j.name, "joint", body, j.name))
    for b in system.bodies:
        coords += [Coordinate(name, group, b.name) for name, group in kind_of(b).coordinates(b)]
    q = sp.Matrix([sp.Symbol(c.name, real=True) for c in coords])
    qd = sp.Matrix([sp.Symbol(c.name + "_d", real=True) for c in coords])
    qdd = sp.Matrix([sp.Symbol(c.name + "_dd", real=True) for c in coords])
    for c, x, xd in zip(coords, q, qd):
        if c.group == "joint":
            joint_sym[c.joint] = (x, xd)
    for g in guided:
        joint_sym[g.joint] = g.symbols[:2]
    der = SystemDerivation(system, tree, coords, guided, q, qd, qdd, params)

    # deformation parts (a flexible body's fields, in its own coordinate symbols), built once
    qnames = [c.name for c in coords]
    for b in system.bodies:
        part = kind_of(b).part(b, psyms.get(b.name), qnames)
        if part is not None:
            der.flex[b.name] = part

    # kinematics: poses in tree order
    for body in tree.order:
        j = system.joint(tree.joint_of(body))
        if j.parent == GROUND:
            P, phiP = sp.Matrix(j.point).applyfunc(exact), sp.Integer(0)
        else:
            P, phiP = marker_pose(der, j.parent)
        c = joint_sym.get(j.name, (sp.Integer(0),))[0]
        off = exact(j.offset)
        P, phi = planar_frame(KINDS[j.kind], P, phiP, off, [c], lambda a: _axis_direction(j, a))
        der.poses[body] = Pose(phi, kind_of(system.body(body)).origin(P, phi, system.marker(j.child)[1]))

    # energies and forces
    g = next((ld.g for ld in system.loads if isinstance(ld, Gravity)), None)
    gvec = sp.Matrix([exact(x) for x in g]) if g is not None else sp.zeros(2, 1)
    der.V_grav, der.Q = sp.Integer(0), sp.zeros(len(coords), 1)  # summed by the bodies' kinds
    for b in system.bodies:
        kind_of(b).contribute(der, b, BodyFrame.of(der, der.poses[b.name], gvec), integral_symbols)
    V_grav, Q = der.V_grav, der.Q
    for D in der.dissipation.values():
        Q -= sp.Matrix([sp.diff(D, xd) for xd in qd])
    der.V += V_grav
    der.V_grav = V_grav
    Q += sp.Matrix([-sp.diff(V_grav, x) for x in q])
    for load in system.loads:
        if isinstance(load, SpringDamper):
            Q += add_spring(der, load, _spring_ends(der, load))
    Q += _applied_forces(der, list(q))
    der.Q = Q.applyfunc(sp.expand)

    if der.casadi_functions:  # the terms of T that read positions on an exact beam: casadi's
        terms = sp.Add.make_args(der.T)
        der.T_casadi = sp.Add(*[e for e in terms if e.has(AppliedUndef)])
        der.T = sp.Add(*[e for e in terms if not e.has(AppliedUndef)])
    der.M, der.f = equations_of_motion(der.T, der.Q, q, qd, [gd.symbols for gd in guided])
    der.constraints = [row for name in tree.cut for row in cut_joint_rows(der, system.joint(name))]
    der.lam = sp.Matrix([sp.Symbol(f"lambda_{k}", real=True) for k in range(len(der.constraints))])
    der.outputs = {o.column: output_of(der, o.quantity) for o in system.outputs}
    for gd in guided:  # at constant speed: the terms in its theta'' are zero, so left out
        if not Maneuver(gd.driver, gd.params, gd.theta, "").accelerates:
            zero = {gd.symbols[2]: 0}
            der.f = der.f.xreplace(zero)
            der.outputs = {k: v.xreplace(zero) for k, v in der.outputs.items()}
            der.dropped.append({"what": f"theta'' terms of guided joint '{gd.joint}'",
                                "why": f"driver '{gd.driver}' has theta'' = 0 identically"})
    return der


def _side(der: SystemDerivation, joint, side: str) -> tuple[sp.Matrix, sp.Expr]:
    ref = getattr(joint, side)
    if ref == GROUND:
        return sp.Matrix([exact(c) for c in joint.point]), sp.Integer(0)
    return marker_pose(der, ref)


def cut_joint_rows(der: SystemDerivation, joint) -> list[tuple[str, sp.Expr]]:
    """Phi = 0 of a cut joint: revolute (pin: the two points coincide), clamp (and the angles
    differ by the offset), prismatic (the child point on the parent's axis line, angles differ
    by the offset). On a beam, a point's angle is its tangent's."""
    rows = planar_cut_rows(KINDS[joint.kind], _side(der, joint, "parent"), _side(der, joint, "child"),
                           exact(joint.offset), lambda a: _axis_direction(joint, a, across=True))
    return [(f"{joint.name}.{suffix}", e) for suffix, e, _ in rows]


def _applied_forces(der: SystemDerivation, wrt) -> sp.Matrix:
    """Generalised forces of the motors, point forces and torques on the coordinates `wrt`
    (symbols: unknowns, or a guided theta_k for the torque it needs)."""
    system = der.system
    Q = sp.zeros(len(wrt), 1)
    env = [("t", t)]
    coordinate_of = {}
    for c, x, xd in zip(der.coords, der.q, der.qd):
        if c.group == "joint":
            env += [(c.joint, x), (f"{c.joint}_rate", xd)]
            coordinate_of[c.joint] = x
    for gd in der.guided:
        env += [(gd.joint, gd.symbols[0]), (f"{gd.joint}_rate", gd.symbols[1])]
    env = tuple(env)
    for d in system.drivers:
        if d.kind == "motor" and coordinate_of[d.joint] in wrt:
            tau = parse_expression(d.expression, env, f"motor '{d.name}' force")
            Q[list(wrt).index(coordinate_of[d.joint])] += tau
    for load in system.loads:
        if isinstance(load, PointForce):
            body, _ = system.marker(load.marker)
            r, _phi = marker_pose(der, load.marker)
            F = sp.Matrix([exact(load.fx), exact(load.fy)])
            if load.frame == "body":
                F = rot(der.poses[body].angle) * F
            Q += sp.Matrix([F.dot(r.diff(x)) for x in wrt])
        elif isinstance(load, Torque):
            tau = parse_expression(load.expression, env, f"torque on '{load.body}'")
            phi = der.poses[load.body].angle
            Q += sp.Matrix([tau * sp.diff(phi, x) for x in wrt])
    return Q


def _spring_ends(der: SystemDerivation, load) -> list[sp.Matrix]:
    return [sp.Matrix([exact(c) for c in point]) if ref == GROUND else marker_pose(der, ref)[0]
            for ref, point in ((load.a, load.point_a), (load.b, load.point_b))]


def spring_force_on_a(der: SystemDerivation, load, ends: list[sp.Matrix]) -> sp.Matrix:
    """The spring-damper's force on its end a (ground frame; on b: the opposite): along the
    line from a to b, k (l - l0) + c l' (l0 = 0: k delta + c delta'), as add_spring's Q."""
    a, b = ends
    delta = b - a
    k, c, l0 = (exact(v) for v in (load.k, load.c, load.l0))
    if l0 == 0:
        return k * delta + c * der.ddt(delta)
    length = sp.sqrt(delta.dot(delta))
    return (k * (length - l0) + c * der.ddt(length)) * delta / length


def spring_energy(der: SystemDerivation, load, ends: list[sp.Matrix], wrt) -> tuple[sp.Expr, sp.Matrix]:
    """A spring-damper between the points `ends` (ground components, planar or spatial): its
    V = k (l - l0)^2 / 2 and its generalised force on the symbols `wrt`, -dV/dx - c l' dl/dx."""
    delta = ends[1] - ends[0]
    k, c, l0 = (exact(v) for v in (load.k, load.c, load.l0))
    if l0 == 0:  # no square root: smooth when the ends meet
        V = k * delta.dot(delta) / 2
        rate = der.ddt(delta)
        damping = sp.Matrix([-c * rate.dot(delta.diff(x)) for x in wrt])
    else:
        length = sp.sqrt(delta.dot(delta))
        V = k * (length - l0)**2 / 2
        damping = sp.Matrix([-c * der.ddt(length) * sp.diff(length, x) for x in wrt])
    return V, sp.Matrix([-sp.diff(V, x) for x in wrt]) + damping


def add_spring(der: SystemDerivation, load, ends: list[sp.Matrix]) -> sp.Matrix:
    """A spring-damper (spring_energy): its V added to der.V and to der.terms, and its Q on the
    unknowns returned."""
    V, Q = spring_energy(der, load, ends, der.q)
    der.V += V
    der.terms.append(("", f"spring {load.name or load.a + '-' + load.b}", ("all",), V, Q))
    return Q


def motor_torque(der: SystemDerivation, driver, applied=None, spring_ends=None) -> sp.Expr:
    """torque(D): a motor's force as given; for a guided joint the generalised force that
    keeps it on theta(t): d/dt dT/dtheta' - dT/dtheta + dV_g/dtheta - Q_theta + Phi_theta^T
    lambda (lambda: the cut joints' multipliers, M q'' = f - Phi_q^T lambda; Q_theta: the
    motors', forces', torques' and spring-dampers'). applied(der, wrt) and spring_ends(der,
    load): the dimension's (the plane's by default; physics/spatial.py passes its own); the part
    of T that casadi differentiates (ef elements, exact beams, a spatial system's bodies in
    their frames' motion) is the placeholder ef_guided_force, given its value by sysgen."""
    applied, spring_ends = applied or _applied_forces, spring_ends or _spring_ends
    coordinate = der.system.driven(driver)  # its joint's, or a second coordinate's (J_slide)
    if driver.kind == "motor":
        k = next(i for i, c in enumerate(der.coords) if c.name == coordinate)
        return applied(der, [der.q[k]])[0]
    th, thd, _ = next(g for g in der.guided if g.joint == coordinate).symbols
    p = sp.diff(der.T, thd)
    tau = der.ddt(p) - sp.diff(der.T, th) + sp.diff(der.V_grav, th) - applied(der, [th])[0]
    for load in der.system.loads:  # a spring-damper pulls on the guided joint too
        if isinstance(load, SpringDamper):
            tau -= spring_energy(der, load, spring_ends(der, load), [th])[1][0]
    if der.ef_kinetic or der.exact_bodies or getattr(der, "frame_T", None):  # what casadi differentiates
        tau += ef_guided_force(coordinate)
    for (_, phi), lam in zip(der.constraints, der.lam):
        tau += sp.diff(phi, th) * lam
    return sp.expand(tau)


def marker_pose(der: SystemDerivation, ref: str) -> tuple[sp.Matrix, sp.Expr]:
    """Ground position and angle of 'body.marker' (on a beam: the deformed axis point and its
    tangent angle phi + v_x, linear in the slope as the modal kinematics)."""
    body, m = der.system.marker(ref)
    return kind_of(der.system.body(body)).marker_pose(der, body, m)


def beam_fields_at(der: SystemDerivation, body: str, x: float):
    """(u, v, v_x) at x on a flexible body, in its frame and coordinate symbols."""
    return kind_of(der.system.body(body)).fields_at(der, body, x)


def joint_coordinate(der: SystemDerivation, joint: str, rate: bool, where: str,
                     coordinate: str | None = None) -> sp.Expr:
    """A joint's coordinate (or its rate), or the one named `coordinate` (a spatial joint's
    second, Joint.coordinates): an unknown of q, or a guided coordinate's theta(t)."""
    name = coordinate or joint
    for c, x, xd in zip(der.coords, der.q, der.qd):
        if (c.name == name) if coordinate else (c.joint == joint):
            return xd if rate else x
    for g in der.guided:
        if g.joint == name:
            return g.symbols[1] if rate else g.symbols[0]
    raise SpecError(f"{where}: joint '{joint}' is a cut joint (no coordinate)")


def output_of(der: SystemDerivation, quantity: str) -> sp.Expr:
    system = der.system
    fn, args = parse_output(system, quantity)
    where = f"system '{system.name}': output '{quantity}'"
    if fn in ("angle", "rate"):
        return joint_coordinate(der, args[0], fn == "rate", where)
    if fn in ("x", "y"):
        return marker_pose(der, args[0])[0][0 if fn == "x" else 1]
    if fn == "T":
        return der.T + (EF_T if der.ef_kinetic or der.exact_bodies else 0)
    if fn == "V":
        return (der.V + sp.Add(*[part.elastic_energy() for part in der.elastic])
                + (EXACT_VG if der.exact_bodies else 0))
    if fn == "momentum":
        return der.momentum
    if fn == "dissipation":
        return 2 * (sp.Add(*der.dissipation.values()) + (EF_D if der.ef_damping else 0))
    if fn == "torque":
        return motor_torque(der, next(d for d in system.drivers if d.name == args[0]))
    if fn == "reaction":
        force, moment, _ = joint_reaction(der, system.joint(args[0]))
        return {"x": force[0], "y": force[1], "moment": moment}[args[1]]
    if fn == "violation":
        return violation(der)
    if fn in ("v", "u", "w", "N", "M"):
        beam = output_beam(system, fn, args)  # N, M: with the output's recovery, if it names one
        x, side = beam_station(system, beam, args[1], where), station_side(args[1])
        u, v, _ = beam_fields_at(der, beam.name, x)
        if fn == "u":
            return u
        if fn == "v":
            return v
        if fn == "w":
            ut, vt, _ = beam_fields_at(der, beam.name, beam.length)
            u0, v0, _ = beam_fields_at(der, beam.name, 0.0)
            p0 = sp.Matrix([u0, v0])
            d = sp.Matrix([station(der, beam.name, beam.length) + ut, vt]) - p0
            r = sp.Matrix([station(der, beam.name, x) + u, v]) - p0
            return cross(d, r) / sp.sqrt(d.dot(d))
        return _stress(der, beam, x, fn, where, side)
    if fn == "sigma":  # sigma = N/A - M y/I (M = EI v'' > 0 shortens the fibres at y > 0)
        beam = system.body(args[0])
        x, side = beam_station(system, beam, args[1], where), station_side(args[1])
        y = exact(section_point(beam, x, args[2:], where, side)[0])
        A_x, I_x, _ = section_at(beam, x, side)  # the section there, as run-time parameters A, I scaled
        A_ = BEAM_PARAMS[2].symbol * exact(A_x / beam.section.A)
        I_ = BEAM_PARAMS[3].symbol * exact(I_x / beam.section.I)
        psyms = der.flex[beam.name].psyms
        N, M = (_stress(der, beam, x, q, where, side) for q in ("N", "M"))
        return N / A_.xreplace(psyms) - M * y / I_.xreplace(psyms)
    raise SpecError(f"{where}: '{fn}' is not derived for systems yet")


def _stress(der, beam, x, fn, where, side=0):
    """N or M at station x: from the equilibrium of the part beyond it, or the kind's own
    (its strain's: EA eps, EI kappa). side: the station's (system.station_side); the kinds
    read it at a node of their elements, and the loads exactly at x (a point mass, a marker's)
    belong to the part beyond for side -1 and at the tip (loads_at)."""
    kind = kind_of(beam)
    if kind.from_equilibrium(beam, fn):
        return _equilibrium_stress(der, beam, x, fn, side)
    return kind.own_stress(der, beam, x, fn, where, side)


def length_param(der: SystemDerivation) -> int:
    """Index in der.params of the parameter that is the length scale, or -1: the L of the one
    flexible body when it sets the scale (then tolerances, blow-up and the violation follow
    `--param L=...`, as for a one-beam variant); the runtime's fsm_system.length_param."""
    scale = length_scale(der.system)
    beams = [b for b in der.system.bodies if b.flexible]
    names = [n for n, _, _ in der.params]
    return names.index("L") if (len(beams) == 1 and beams[0].length == scale and "L" in names) else -1


def violation(der: SystemDerivation) -> sp.Expr:
    """max_i |Phi_i| / length scale (length_param's parameter, else length_scale): the
    runtime's `violation` column as an output (0 with no cut joint). A nest of Piecewise, as
    casadi's fmax takes two arguments."""
    if not der.constraints:
        return sp.Integer(0)
    # The nest is built on placeholders, then the rows put in: sympy folds the conditions of a
    # nested Piecewise through its logic simplification, which on a spatial loop's rows (Euler
    # parameters) took minutes (S7: 207 of a 214 s derivation); on symbols it takes
    # milliseconds and gives the same nest.
    a = sp.symbols(f"_phi0:{len(der.constraints)}")
    rows = [sp.Abs(x) for x in a]
    out = rows[0]
    for r in rows[1:]:
        out = sp.Piecewise((out, out >= r), (r, True))
    out = out.xreplace({x: phi for x, (_, phi) in zip(a, der.constraints)})
    i = length_param(der)
    return out / (der.params[i][1] if i >= 0 else sp.Float(length_scale(der.system)))


def _cut_loads(der: SystemDerivation, joint) -> tuple[sp.Matrix, sp.Expr, sp.Matrix, sp.Matrix]:
    """(F, tau, at_child, at_parent): the force and torque a cut joint's parent side exerts on
    its child side, from M q'' = f - Phi_q^T lambda: a row pc - pp of a pin gives the child
    -lambda, the normal row of a prismatic -lambda n (n the parent's axis normal), an angle
    row a torque -lambda. The parent side gets -F and -tau at `at_parent`."""
    lam = {name: l for (name, _), l in zip(der.constraints, der.lam)}
    (pp, ap), (pc, _) = _side(der, joint, "parent"), _side(der, joint, "child")
    n = joint.name
    tau = -lam.get(f"{n}.angle", sp.Integer(0))
    if f"{n}.normal" in lam:  # the gap across a prismatic joint's axis (planar_cut_rows)
        return -lam[f"{n}.normal"] * _axis_direction(joint, ap, across=True), tau, pc, pc
    return -sp.Matrix([lam[f"{n}.x"], lam[f"{n}.y"]]), tau, pc, pp


def _external_loads(der: SystemDerivation, bodies: set[str]) -> tuple[sp.Matrix, sp.Expr]:
    """Resultant force and moment about the ground origin of the loads on `bodies` from outside
    the set, except the tree joint that carries it: gravity, point forces, torques,
    spring-dampers with one end outside and cut joints with one side outside."""
    system = der.system
    env = [("t", t)] + [(c.joint, x) for c, x in zip(der.coords, der.q) if c.group == "joint"] \
        + [(f"{c.joint}_rate", xd) for c, xd in zip(der.coords, der.qd) if c.group == "joint"] \
        + [(g.joint, g.symbols[0]) for g in der.guided] \
        + [(f"{g.joint}_rate", g.symbols[1]) for g in der.guided]
    F, Mo = sp.zeros(2, 1), sp.Integer(0)

    def add(force, at):
        nonlocal F, Mo
        F += force
        Mo += cross(at, force)

    def inside(ref):
        return ref != GROUND and system.marker(ref)[0] in bodies

    g = next((ld.g for ld in system.loads if isinstance(ld, Gravity)), None)
    if g is not None:
        gvec = sp.Matrix([exact(x) for x in g])
        for b in bodies:
            F += der.mass[b] * gvec
            Mo += cross(der.first_moment[b], gvec)
    for b in sorted(bodies):  # dampers acting on the motion relative to a body's frame
        load = kind_of(system.body(b)).damping_load(der, system.body(b))
        if load is not None:
            pose = der.poses[b]
            force = rot(pose.angle) * load[0]
            add(force, pose.R)
            Mo += load[1]
    for load in system.loads:
        if isinstance(load, PointForce) and inside(load.marker):
            body, _ = system.marker(load.marker)
            force = sp.Matrix([exact(load.fx), exact(load.fy)])
            if load.frame == "body":
                force = rot(der.poses[body].angle) * force
            add(force, marker_pose(der, load.marker)[0])
        elif isinstance(load, Torque) and load.body in bodies:
            Mo += parse_expression(load.expression, tuple(env), f"torque on '{load.body}'")
        elif isinstance(load, SpringDamper) and inside(load.a) != inside(load.b):
            ends = [sp.Matrix([exact(c) for c in pt]) if ref == GROUND
                    else marker_pose(der, ref)[0]
                    for ref, pt in ((load.a, load.point_a), (load.b, load.point_b))]
            delta = ends[1] - ends[0]
            k, c, l0 = (exact(v) for v in (load.k, load.c, load.l0))
            if l0 == 0:
                on_b = -k * delta - c * der.ddt(delta)
            else:
                length = sp.sqrt(delta.dot(delta))
                on_b = -(k * (length - l0) + c * der.ddt(length)) * delta / length
            add(on_b if inside(load.b) else -on_b, ends[1] if inside(load.b) else ends[0])
    for name in der.tree.cut:
        joint = system.joint(name)
        if inside(joint.child) == inside(joint.parent):
            continue
        force, tau, at_c, at_p = _cut_loads(der, joint)
        if inside(joint.child):
            add(force, at_c)
            Mo += tau
        else:
            add(-force, at_p)
            Mo -= tau
    return F, Mo


def joint_reaction(der: SystemDerivation, joint) -> tuple[sp.Matrix, sp.Expr, sp.Matrix]:
    """_joint_reaction, once per derivation."""
    return der.once(("reaction", joint.name), lambda: _joint_reaction(der, joint))


def _joint_reaction(der: SystemDerivation, joint) -> tuple[sp.Matrix, sp.Expr, sp.Matrix]:
    """(F, M, P): the force (ground components) and the moment about P (the joint's child
    point) that the joint's parent side exerts on its child side, constraint and drive loads
    together (a guided or motored joint's moment or axial force is its drive's). A cut joint:
    from its multipliers. A tree joint: the momentum balance of the subtree beyond it,
    F = d^2/dt^2 (sum m r_G) - external forces, M = dH_O/dt - external moments - P x F, an
    expression of q, q', q'', the drive and lambda."""
    if joint.name in der.tree.cut:
        force, tau, at_c, _ = _cut_loads(der, joint)
        return force, tau, at_c
    bodies = der.tree.subtree(der.system, joint.name)
    P = _side(der, joint, "child")[0]
    Fe, Me = _external_loads(der, bodies)
    S = sum((der.first_moment[b] for b in bodies), sp.zeros(2, 1))
    H = sp.Add(*[der.body_momentum[b] for b in bodies])
    F = der.ddt(S, 2) - Fe
    M = der.ddt(H) - Me - cross(P, F)
    return F, M, P


def _loads_beyond(der: SystemDerivation, beam, x: float, side: int = 0) -> list[tuple[sp.Matrix, sp.Expr, sp.Matrix]]:
    """(F, tau, at) of the loads on beam's markers beyond station x (and at x where loads_at):
    joints (a cut joint's multipliers, a child tree joint's reaction, with the sign for the
    side the beam is on), point forces, spring-dampers (ground frame)."""
    system, out = der.system, []
    at_x = loads_at(beam, x, side)

    def beyond(ref):
        if ref == GROUND:
            return False
        body, m = system.marker(ref)
        return body == beam.name and (m.x > x or (at_x and m.x >= x))

    for j in system.joints:
        if j.name != der.tree.joint_of(beam.name) and (beyond(j.parent) or beyond(j.child)):
            F, tau, P = joint_reaction(der, j)
            if beyond(j.parent):  # the beam is the parent side: it gets -F, -tau at P
                out.append((-F, -tau, P))
            if beyond(j.child):
                out.append((F, tau, P))
    for load in system.loads:
        if isinstance(load, PointForce) and beyond(load.marker):
            F = sp.Matrix([exact(load.fx), exact(load.fy)])
            if load.frame == "body":
                F = rot(der.poses[beam.name].angle) * F
            out.append((F, sp.Integer(0), marker_pose(der, load.marker)[0]))
        elif isinstance(load, SpringDamper) and (beyond(load.a) or beyond(load.b)):
            Fa = spring_force_on_a(der, load, _spring_ends(der, load))
            for ref, F in ((load.a, Fa), (load.b, -Fa)):
                if beyond(ref):
                    out.append((F, sp.Integer(0), marker_pose(der, ref)[0]))
    return out


def _equilibrium_stress(der: SystemDerivation, beam, x: float, fn: str, side: int = 0) -> sp.Expr:
    """N or M at station x from the equilibrium of the part of the beam beyond x, with the
    frame's actual motion and gravity: the inertial loads -rho A (a - g) (a in frame
    components: A^T R'' + the relative, Coriolis, angular and centripetal terms, as
    outputs._equilibrium_* for a guided hub) and the loads on its markers beyond x (joint
    reactions, point forces). N: their component along the section's axis (tension > 0), M:
    their moment about the section point (point rotary inertias' couples included). The
    inertial part is the kind's (inertial_stress)."""
    out, section, axis = kind_of(beam).inertial_stress(der, beam, x, fn, loads_at(beam, x, side))
    Arot = rot(der.poses[beam.name].angle)
    for F, tau, P in _loads_beyond(der, beam, x, side):
        out += (Arot.T * F).dot(axis) if fn == "N" else cross(P - section, F) + tau
    return out
