"""Equations of motion of a System in relative coordinates on its spanning tree (sympy).

Unknowns q: the coordinates of the tree joints that are not guided (in tree order), then each
flexible body's elastic coordinates. A guided joint k contributes the drive entries
d = [t, theta_k, theta_k', theta_k''] (known functions of time, not unknowns).

Each body's frame pose (angle phi, origin R) is an expression of its parent's pose and its tree
joint's coordinate; a flexible beam's frame is its root's tangent frame. Energies:
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
motion through T. `prestress` keeps N(x) = rho A phi'^2 (L^2 - x^2)/2 with phi' the frame's
actual rate (a velocity-dependent stiffness on the bending coordinates, a force term, not
part of the Lagrangian); the frame's translational acceleration and gravity are NOT in this
N(x): use #1-#3 when they matter (S2, S3).
Outputs of q, q', q'', the drive and lambda: joint reactions (joint_reaction: a cut joint's
from lambda, a tree joint's from the momentum balance of the subtree beyond it), N and M from
equilibrium (_equilibrium_stress: the part of the beam beyond the station with the frame's
actual motion, gravity and the loads on its markers), the violation.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from types import SimpleNamespace

import sympy as sp

from flexsym.model.exact_numbers import exact
from flexsym.physics.energy import (BEAM_PARAMS, ENERGY_TERMS, FrameMotion, build_fields,
                     gravity_density, kinetic_density, momentum_density, w)
from flexsym.physics.efbody import EfPart, ef_part
from flexsym.physics.exact_kinematics import ExactKinematics, Quadrature
from flexsym.physics.exact_body import EXACT_VG, body_quadrature, inertial_section_load, position_symbols
from flexsym.core.errors import SpecError
from flexsym.physics.integrals import BodyIntegralTable, IntegralTable
from flexsym.physics.lagrange import equations_of_motion, generalized_force, jacobi_integral
from flexsym.model.joint_kinds import KINDS, planar_cut_rows, planar_frame
from flexsym.model.maneuver import Param, maneuver_of, parse_expression, parse_theta, t
from flexsym.model.modes import s
from flexsym.physics.outputs import field_at, output_expression
from flexsym.model.strain_models import STRAIN_MODELS
from flexsym.model.system import (GROUND, FlexibleBeam, Gravity, PointForce, SpringDamper, System, Torque,
                     beam_station, length_scale, parse_output, section_at,
                     section_point)

SECTION_PARAMS = ("rho", "E", "A", "I", "L")  # per flexible body, the order of BEAM_PARAMS


def _rot(phi) -> sp.Matrix:
    return sp.Matrix([[sp.cos(phi), -sp.sin(phi)], [sp.sin(phi), sp.cos(phi)]])


def _axis_direction(joint, angle, across: bool = False) -> sp.Matrix:
    """A planar joint's unit axis (or its normal, turned +90 degrees), in ground, its parent
    turned by angle."""
    ax = sp.Matrix([exact(a) for a in joint.axis])
    return _rot(angle) * (sp.Matrix([-ax[1], ax[0]]) if across else ax) / sp.sqrt(ax.dot(ax))


def _cross(a, b) -> sp.Expr:
    return a[0] * b[1] - a[1] * b[0]


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


@dataclass
class FlexPart:
    """A flexible body's deformation: its table, fields (in this body's symbols), modes."""

    beam: FlexibleBeam
    table: IntegralTable
    fields: object
    modes: dict
    groups: dict  # mode name -> 'axial' | 'bending'
    coords: list  # mode names in order
    psyms: dict  # global beam parameter symbol -> this body's symbol

    def view(self):
        """What outputs.field_at / output_expression read (a derivation-like object)."""
        return SimpleNamespace(spec=self.beam.model, table=self.table, modes=self.modes,
                               fields=self.fields)


@dataclass
class ExactPart(FlexPart, ExactKinematics):
    """A beam with exact kinematics (physics/exact_body.py): its V is the modal beam's (the
    FlexPart's fields), its T, gravity and positions are casadi quadratures."""

    quad: Quadrature = None
    frame: tuple = ()  # (omega, V_x, V_y, g_x, g_y, R_x, R_y) in frame components, sympy
    index: list = field(default_factory=list)  # its coordinates' places in q, in mode order

    @property
    def fe_body(self):
        return self.beam.model.body


@dataclass
class EfKinetic:
    """An ef body's frame motion in frame components (omega, V = A^T R'), which sysgen feeds
    to the generic element's kinetic energy (efbody.generic_element) per element."""

    body: str
    omega: sp.Expr
    V: tuple[sp.Expr, sp.Expr]


# Placeholders in output expressions for what sysgen computes in casadi from the ef bodies'
# kinetic energy T_ef: T_ef itself, and per guided joint d/dt dT_ef/dtheta' - dT_ef/dtheta.
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
        for _ in range(order):
            out = sp.Integer(0)
            for x, xd in zip(self.q, self.qd):
                out += sp.diff(expr, x) * xd
            for x, xd in zip(self.qd, self.qdd):
                out += sp.diff(expr, x) * xd
            for g in self.guided:
                th, thd, thdd = g.symbols
                out += sp.diff(expr, th) * thd + sp.diff(expr, thd) * thdd
            expr = out
        return expr

    def energies(self) -> tuple[sp.Expr, sp.Expr, sp.Expr]:
        """(T, V, h = T2 - T0 + V): h is conserved when nothing is guided or motored and every
        term is conservative (then h = T + V). Without the ef bodies' T (sysgen adds it)."""
        return self.T, self.V, jacobi_integral(self.T, self.M, self.qd, self.V)


def _beyond_root(ref, beam: str) -> bool:
    return isinstance(ref, str) and ref.partition(".")[0] == beam and ref.partition(".")[2] != "root"


def _loaded_beyond_root(system: System, beam: str) -> str:
    """The first force or spring acting on the beam anywhere but at its root ('' if none)."""
    for load in system.loads:
        if any(_beyond_root(getattr(load, k, ""), beam) for k in ("marker", "a", "b")):
            return f"load '{load.name or type(load).__name__}'"
    return ""


def _held_beyond_root(system: System, beam: str) -> str:
    """The first joint, force or spring acting on the beam anywhere but at its root ('' if none)."""
    for j in system.joints:
        if _beyond_root(j.parent, beam) or _beyond_root(j.child, beam):
            return f"joint '{j.name}'"
    return _loaded_beyond_root(system, beam)


def _check_exact(system: System, tree, b: FlexibleBeam) -> None:
    """What the exact kinematics in a system (physics/exact_body.py) is derived for: a
    planar beam (damped as a modal beam: its strain measures are linear in its coordinates) (uniform, or sections and point masses from finite-element data)
    from which nothing hangs and on which no load acts beyond its root (their equations
    would differentiate its quadrature positions in sympy), N and M its own
    (EA eps, EI dphi/dx), and no output that needs its momentum (momentum, the reaction of a
    tree joint it lies beyond, N or M from equilibrium of a beam it hangs from)."""
    where = f"system '{system.name}': body '{b.name}': the exact kinematics (strain model 'exact')"
    if system.dimension != 2:
        raise SpecError(f"{where} is derived for planar systems only")
    body = b.model.body
    if body is not None and (body.matrices is not None or any(m.rotary for m in body.masses)):
        raise SpecError(f"{where} is derived for a beam from its sections and point masses "
                        "(not from imported matrices, nor with a point mass's rotary inertia)")
    loaded = _loaded_beyond_root(system, b.name)
    for j in system.joints:
        if j.parent.partition(".")[0] == b.name and j.name not in tree.cut:
            raise SpecError(f"{where}: joint '{j.name}' hangs a body from it (a loop may close "
                            "on it; a body hanging from it is not derived yet)")
    if loaded:
        raise SpecError(f"{where}: {loaded} acts on it beyond its root (not derived yet)")
    beyond = {j.name for j in system.joints if j.name not in tree.cut
              and b.name in tree.subtree(system, j.name)}
    for o in system.outputs:
        fn, args = parse_output(system, o.quantity)
        keys = {"M": ("moment",), "N": ("axial_force",), "sigma": ("moment", "axial_force")}.get(fn, ())
        on_beam = keys and args[0] != b.name and any(
            getattr(system.body(args[0]).model, k, "") == "equilibrium" for k in keys) and any(
            j.parent.partition(".")[0] == args[0] for j in system.joints if j.name in beyond)
        if fn == "momentum" or (fn == "reaction" and args[0] in beyond) or on_beam:
            raise SpecError(f"{where}: output '{o.quantity}' needs its momentum, which is not "
                            "derived yet")


def check_derivable(system: System, tree=None) -> None:
    """Refuse, before any work, what the derivation does not support (one line)."""
    tree = tree or system.tree()
    where = f"system '{system.name}'"
    for b in system.bodies:
        if b.flexible and b.model.kind == "modal" and STRAIN_MODELS[b.model.strain].kinematics == "exact":
            _check_exact(system, tree, b)
        if b.flexible and b.model.kind == "modal" and b.model.strain == "prestress":
            held = _held_beyond_root(system, b.name)
            if held:
                raise SpecError(f"{where}: body '{b.name}': the prestress model's axial force is the "
                                f"beam's own centrifugal load, which holds for a beam free beyond its "
                                f"root; {held} loads it axially: use m2 or m3 (N from equilibrium), "
                                "or ef")
        body = getattr(b.model, "body", None) if b.flexible else None
        if body is not None:  # the body's data are the beam's: markers and p must agree
            ref = body.reference
            given = (b.length, b.section.rho, b.section.E, b.section.A, b.section.I)
            data = (body.length, ref.rho, ref.E, ref.A, ref.I)
            if any(abs(x - y) > 1e-12 * abs(y) for x, y in zip(given, data)):
                raise SpecError(f"{where}: body '{b.name}': length and section (rho, E, A, I) "
                                f"{given} differ from its finite-element data's length and root "
                                f"section {data}")
    for load in system.loads:
        if not isinstance(load, (Gravity, PointForce, Torque, SpringDamper)):
            raise SpecError(f"{where}: load {type(load).__name__} is not derived yet")


def _param_layout(system: System) -> tuple[list, dict]:
    """p: [rho, E, A, I, L] of each flexible body (plain names for one body, as a one-beam
    variant's p, so that --param L=... keeps working; else body_rho, ...)."""
    beams = [b for b in system.bodies if b.flexible]
    params, by_body = [], {}
    for b in beams:
        values = {"rho": b.section.rho, "E": b.section.E, "A": b.section.A, "I": b.section.I,
                  "L": b.length}
        mapping = {}
        for gp in BEAM_PARAMS:
            name = gp.name if len(beams) == 1 else f"{b.name}_{gp.name}"
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
    params, psyms = _param_layout(system)

    coords: list[Coordinate] = []
    joint_sym: dict[str, tuple] = {}  # joint -> (coordinate, rate) symbols
    for body in tree.order:
        j = system.joint(tree.joint_of(body))
        if j.has_coordinate and j.name not in guided_by_joint:
            coords.append(Coordinate(j.name, "joint", body, j.name))
    for b in system.bodies:
        if b.flexible and b.model.kind == "fe":
            coords += [Coordinate(f"{b.name}_{c}", "node", b.name) for c in b.model.coordinates]
        elif b.flexible:
            refs = b.model.modes
            for r in refs:
                coords.append(Coordinate(f"{b.name}_{r.coordinate}", r.axis, b.name))
    q = sp.Matrix([sp.Symbol(c.name, real=True) for c in coords])
    qd = sp.Matrix([sp.Symbol(c.name + "_d", real=True) for c in coords])
    qdd = sp.Matrix([sp.Symbol(c.name + "_dd", real=True) for c in coords])
    for c, x, xd in zip(coords, q, qd):
        if c.group == "joint":
            joint_sym[c.joint] = (x, xd)
    for g in guided:
        joint_sym[g.joint] = g.symbols[:2]
    der = SystemDerivation(system, tree, coords, guided, q, qd, qdd, params)

    # deformation fields of each flexible body, in its own coordinate symbols
    for b in system.bodies:
        if not b.flexible:
            continue
        if b.model.kind == "fe":
            der.flex[b.name] = ef_part(b, psyms[b.name])
            continue
        spec = b.model.validate()
        modes = {r.coordinate: spec.mode(r) for r in spec.modes}
        names = list(modes)
        sym = {n: sp.Symbol(f"{b.name}_{n}", real=True) for n in names}
        symd = {n: sp.Symbol(f"{b.name}_{n}_d", real=True) for n in names}
        symdd = {n: sp.Symbol(f"{b.name}_{n}_dd", real=True) for n in names}
        table = IntegralTable(modes) if spec.body is None else BodyIntegralTable(spec.body, modes)
        strain = STRAIN_MODELS[spec.strain]
        fields = build_fields([modes[r.coordinate] for r in spec.axial],
                              [modes[r.coordinate] for r in spec.bending], sym, symd, table,
                              strain.foreshortening, symdd)
        args = (b, table, fields, modes, {r.coordinate: r.axis for r in spec.modes}, names,
                psyms[b.name])
        if strain.kinematics == "exact":
            part = ExactPart(*args, index=[[c.name for c in coords].index(f"{b.name}_{n}") for n in names])
            part.quad = body_quadrature(part)
            der.flex[b.name] = part
        else:
            der.flex[b.name] = FlexPart(*args)

    # kinematics: poses in tree order
    for body in tree.order:
        j = system.joint(tree.joint_of(body))
        if j.parent == GROUND:
            P, phiP = sp.Matrix(j.point).applyfunc(exact), sp.Integer(0)
        else:
            P, phiP = marker_pose(der, j.parent)
        c = joint_sym.get(j.name, (sp.Integer(0),))[0]
        off = exact(j.offset)
        b = system.body(body)
        mc = system.marker(j.child)[1]
        mloc = sp.Matrix([exact(mc.x), exact(mc.y)])
        P, phi = planar_frame(KINDS[j.kind], P, phiP, off, [c], lambda a: _axis_direction(j, a))
        R = P - (_rot(phi) * mloc if not b.flexible else sp.zeros(2, 1))
        der.poses[body] = Pose(phi, R)

    # energies and forces
    g = next((ld.g for ld in system.loads if isinstance(ld, Gravity)), None)
    gvec = sp.Matrix([exact(x) for x in g]) if g is not None else sp.zeros(2, 1)
    V_grav = sp.Integer(0)
    Q = sp.zeros(len(coords), 1)
    for b in system.bodies:
        pose = der.poses[b.name]
        A_ = _rot(pose.angle)
        omega = der.ddt(pose.angle)
        Rdot = der.ddt(pose.R)
        if not b.flexible:
            G = pose.R + A_ * sp.Matrix([exact(x) for x in b.com])
            vG = der.ddt(G)
            m, J = exact(b.mass), exact(b.inertia)
            der.T += m * vG.dot(vG) / 2 + J * omega**2 / 2
            V_grav += -m * gvec.dot(G)
            der.momentum += m * _cross(G, vG) + J * omega
            der.mass[b.name], der.first_moment[b.name] = m, m * G
            der.body_momentum[b.name] = m * _cross(G, vG) + J * omega
            continue
        part = der.flex[b.name]
        ph = sp.symbols("Om_ Vx_ Vy_ Rx_ Ry_ gx_ gy_", real=True)
        Vloc, Rloc, gloc = A_.T * Rdot, A_.T * pose.R, A_.T * gvec
        actual = {ph[0]: omega, ph[1]: Vloc[0], ph[2]: Vloc[1], ph[3]: Rloc[0], ph[4]: Rloc[1],
                  ph[5]: gloc[0], ph[6]: gloc[1]}
        mass = BEAM_PARAMS[0].symbol * BEAM_PARAMS[2].symbol * BEAM_PARAMS[4].symbol
        if isinstance(part, EfPart):
            Vg_, H_ = part.energies()
            der.ef_kinetic.append(EfKinetic(b.name, omega, (Vloc[0], Vloc[1])))
            der.T += part.point_mass_kinetic().xreplace(actual)  # elements' T: sysgen, by AD
            V_grav += Vg_.xreplace(actual) - part.mass * gvec.dot(pose.R)
            der.momentum += H_.xreplace(actual)
            _record_body(der, b.name, part.mass, pose, A_,
                         [-sp.diff(Vg_, gk).xreplace(actual) for gk in ph[5:]],
                         H_.xreplace(actual))
            der.elastic.append(part)
            der.terms.append((b.name, "ancf_elastic", ("node",), None, None))
            if b.damped:
                alpha, beta = (_exact_number(getattr(b.damping, k)) for k in ("alpha", "beta"))
                der.ef_damping[b.name] = (alpha, beta)
                der.dissipation[b.name] = part.point_mass_dissipation(alpha)
            continue
        frame = FrameMotion(ph[0], ph[1], ph[2])
        tab, fl = part.table, part.fields

        def body_expr(expr, tab=tab, part=part, actual=actual):
            values = {} if integral_symbols else tab.substitutions()
            return expr.xreplace(values).xreplace(part.psyms).xreplace(actual)

        mass = mass * tab.integrate(fl.weights["mu"])  # 1 for a uniform beam; a body's own
        if isinstance(part, ExactPart):  # T and the deformation's gravity: exact_body (casadi)
            part.frame = (omega, Vloc[0], Vloc[1], gloc[0], gloc[1], Rloc[0], Rloc[1])
            der.exact_bodies.append(part)
        else:
            der.T += body_expr(tab.integrate(kinetic_density(fl, frame)))
            V_grav += body_expr(tab.integrate(gravity_density(fl, ph[5], ph[6]))) \
                - body_expr(mass) * gvec.dot(pose.R)
            H_ = body_expr(tab.integrate(momentum_density(fl, frame, ph[3], ph[4])))
            der.momentum += H_
            Ig = tab.integrate(gravity_density(fl, ph[5], ph[6]))  # linear in g: -g.(first moment)
            _record_body(der, b.name, body_expr(mass), pose, A_,
                         [body_expr(-sp.diff(Ig, gk)) for gk in ph[5:]], H_)
        strain = STRAIN_MODELS[b.model.strain]
        for term_name, wrt in strain.terms:
            term = ENERGY_TERMS[term_name]
            V = body_expr(tab.integrate(term.density(fl)).xreplace({w: ph[0]}))
            Qk = generalized_force(V, q, [c.body == b.name and c.group in wrt for c in coords])
            der.terms.append((b.name, term_name, wrt, V, Qk))
            der.V += V
            Q += Qk
        if b.damped:
            der.dissipation[b.name] = _modal_dissipation(b, part, body_expr)
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

    der.M, der.f = equations_of_motion(der.T, der.Q, q, qd, [gd.symbols for gd in guided])
    der.constraints = [row for name in tree.cut for row in cut_joint_rows(der, system.joint(name))]
    der.lam = sp.Matrix([sp.Symbol(f"lambda_{k}", real=True) for k in range(len(der.constraints))])
    der.outputs = {o.column: output_of(der, o.quantity) for o in system.outputs}
    return der


def _exact_number(x) -> sp.Rational:
    """A damping value as the exact rational of its decimal representation."""
    return sp.Rational(repr(float(x)))


def _modal_dissipation(b: FlexibleBeam, part: FlexPart, body_expr) -> sp.Expr:
    """D of a damped modal beam (module doc): the strain-rate and relative kinetic energies of
    the undeformed beam's elastic rates (the fields linear in the rates: no foreshortening)."""
    spec, tab = b.model, part.table
    rate = {n: sp.Symbol(f"{b.name}_{n}_d", real=True) for n in part.coords}
    rf = build_fields([part.modes[r.coordinate] for r in spec.axial],
                      [part.modes[r.coordinate] for r in spec.bending], rate, rate, tab, False)
    K2 = body_expr(tab.integrate(ENERGY_TERMS["axial"].density(rf) + ENERGY_TERMS["bending"].density(rf)))
    M2 = body_expr(tab.integrate(kinetic_density(rf, FrameMotion(sp.Integer(0)))))
    return damping_dissipation(b.damping, K2, M2, [rate[n] for n in part.coords])


def damping_dissipation(d, K2: sp.Expr, M2: sp.Expr, rates: list) -> sp.Expr:
    """D of a damped modal beam in both dimensions (module doc) from its strain-rate and
    relative kinetic energies K2, M2 (the undeformed beam's, quadratic in its elastic rates):
    beta K2 + alpha M2 + a dashpot 2 zeta_i omega_i m_i on each rate."""
    D = _exact_number(d.beta) * K2 + _exact_number(d.alpha) * M2
    for qd, z in zip(rates, d.zetas(len(rates))):
        if z:
            c = 2 * _exact_number(z) * sp.sqrt(sp.diff(K2, qd, 2) * sp.diff(M2, qd, 2))
            D += c * qd**2 / 2
    return sp.expand(D)


def _record_body(der, name, mass, pose, A_, local_moment, H) -> None:
    der.mass[name] = mass
    der.first_moment[name] = mass * pose.R + A_ * sp.Matrix(local_moment)
    der.body_momentum[name] = H


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
                F = _rot(der.poses[body].angle) * F
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


def add_spring(der: SystemDerivation, load, ends: list[sp.Matrix]) -> sp.Matrix:
    """A spring-damper between the points `ends` (ground components, planar or spatial): its
    V = k (l - l0)^2 / 2 added to der.V and to der.terms, and its Q = -dV/dq - c l' dl/dq
    returned."""
    delta = ends[1] - ends[0]
    k, c, l0 = (exact(v) for v in (load.k, load.c, load.l0))
    if l0 == 0:  # no square root: smooth when the ends meet
        V = k * delta.dot(delta) / 2
        rate = der.ddt(delta)
        damping = sp.Matrix([-c * rate.dot(delta.diff(x)) for x in der.q])
    else:
        length = sp.sqrt(delta.dot(delta))
        V = k * (length - l0)**2 / 2
        damping = sp.Matrix([-c * der.ddt(length) * sp.diff(length, x) for x in der.q])
    Q = sp.Matrix([-sp.diff(V, x) for x in der.q]) + damping
    der.V += V
    der.terms.append(("", f"spring {load.name or load.a + '-' + load.b}", ("all",), V, Q))
    return Q


def motor_torque(der: SystemDerivation, driver) -> sp.Expr:
    """torque(D): a motor's force as given; for a guided joint the generalised force that
    keeps it on theta(t): d/dt dT/dtheta' - dT/dtheta + dV_g/dtheta - Q_theta + Phi_theta^T
    lambda (lambda: the cut joints' multipliers, M q'' = f - Phi_q^T lambda)."""
    if driver.kind == "motor":
        j = next(c for c in der.coords if c.joint == driver.joint)
        return _applied_forces(der, [der.q[der.coords.index(j)]])[0]
    th, thd, _ = next(g for g in der.guided if g.joint == driver.joint).symbols
    p = sp.diff(der.T, thd)
    tau = der.ddt(p) - sp.diff(der.T, th) + sp.diff(der.V_grav, th) - _applied_forces(der, [th])[0]
    if der.ef_kinetic:
        tau += ef_guided_force(driver.joint)
    for (_, phi), lam in zip(der.constraints, der.lam):
        tau += sp.diff(phi, th) * lam
    return sp.expand(tau)


def marker_pose(der: SystemDerivation, ref: str) -> tuple[sp.Matrix, sp.Expr]:
    """Ground position and angle of 'body.marker' (on a beam: the deformed axis point and its
    tangent angle phi + v_x, linear in the slope as the modal kinematics)."""
    body, m = der.system.marker(ref)
    pose = der.poses[body]
    b = der.system.body(body)
    if not b.flexible:
        return pose.R + _rot(pose.angle) * sp.Matrix([exact(m.x), exact(m.y)]), pose.angle
    u, v, slope = beam_fields_at(der, body, m.x)
    return pose.R + _rot(pose.angle) * sp.Matrix([_x(der, body, m.x) + u, v]), pose.angle + slope


def _x(der, body, x):
    part = der.flex[body]
    return exact(x) / exact(part.beam.length) * part.psyms[BEAM_PARAMS[4].symbol]


def beam_fields_at(der: SystemDerivation, body: str, x: float):
    """(u, v, v_x) at x on a flexible body, in its frame and coordinate symbols."""
    part = der.flex[body]
    if isinstance(part, EfPart):
        rx, ry, slope = part.position(x)
        return rx - _x(der, body, x), ry, slope
    at = exact(x) / exact(part.beam.length)
    view = part.view()
    L_ = part.psyms[BEAM_PARAMS[4].symbol]

    def fa(e):
        return field_at(view, e, at).xreplace(part.table.substitutions()).xreplace(part.psyms)
    if isinstance(part, ExactPart):  # the section angle is the slope field, exactly
        rx, ry = position_symbols(part, der.casadi_outputs, x)
        return rx - _x(der, body, x), ry, fa(part.fields.v_s) / L_
    return fa(part.fields.u), fa(part.fields.v), fa(part.fields.v_s) / L_


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
        beam = system.body(args[0])
        x = beam_station(system, beam, args[1], where)
        u, v, _ = beam_fields_at(der, beam.name, x)
        if fn == "u":
            return u
        if fn == "v":
            return v
        if fn == "w":
            ut, vt, _ = beam_fields_at(der, beam.name, beam.length)
            u0, v0, _ = beam_fields_at(der, beam.name, 0.0)
            p0 = sp.Matrix([u0, v0])
            d = sp.Matrix([_x(der, beam.name, beam.length) + ut, vt]) - p0
            r = sp.Matrix([_x(der, beam.name, x) + u, v]) - p0
            return _cross(d, r) / sp.sqrt(d.dot(d))
        return _stress(der, beam, x, fn, where)
    if fn == "sigma":  # sigma = N/A - M y/I (M = EI v'' > 0 shortens the fibres at y > 0)
        beam = system.body(args[0])
        x = beam_station(system, beam, args[1], where)
        y = exact(section_point(beam, x, args[2:], where)[0])
        A_x, I_x, _ = section_at(beam, x)  # the section there, as run-time parameters A, I scaled
        A_ = BEAM_PARAMS[2].symbol * exact(A_x / beam.section.A)
        I_ = BEAM_PARAMS[3].symbol * exact(I_x / beam.section.I)
        psyms = der.flex[beam.name].psyms
        N, M = (_stress(der, beam, x, q, where) for q in ("N", "M"))
        return N / A_.xreplace(psyms) - M * y / I_.xreplace(psyms)
    raise SpecError(f"{where}: '{fn}' is not derived for systems yet")


def _stress(der, beam, x, fn, where):
    part = der.flex[beam.name]
    if isinstance(part, EfPart):
        return part.stress(fn, x)
    frac = exact(x) / exact(beam.length)
    spec = replace(beam.model, points=(("o", str(frac)),))
    if (beam.model.axial_force if fn == "N" else beam.model.moment) == "equilibrium":
        return _equilibrium_stress(der, beam, x, fn)
    if fn == "N" and not spec.axial and spec.strain != "prestress":
        raise SpecError(f"{where}: strain model '{spec.strain}' has no axial coordinate to carry "
                        "an axial force")
    view = SimpleNamespace(spec=spec, table=part.table, modes=part.modes, fields=part.fields)
    expr = output_expression(view, f"{fn}_o")
    omega = der.ddt(der.poses[beam.name].angle)
    return expr.xreplace(part.table.substitutions()).xreplace(part.psyms).xreplace({w: omega})


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
    rows = [sp.Abs(phi) for _, phi in der.constraints]
    if not rows:
        return sp.Integer(0)
    out = rows[0]
    for r in rows[1:]:
        out = sp.Piecewise((out, out >= r), (r, True))
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
        Mo += _cross(at, force)

    def inside(ref):
        return ref != GROUND and system.marker(ref)[0] in bodies

    g = next((ld.g for ld in system.loads if isinstance(ld, Gravity)), None)
    if g is not None:
        gvec = sp.Matrix([exact(x) for x in g])
        for b in bodies:
            F += der.mass[b] * gvec
            Mo += _cross(der.first_moment[b], gvec)
    for load in system.loads:
        if isinstance(load, PointForce) and inside(load.marker):
            body, _ = system.marker(load.marker)
            force = sp.Matrix([exact(load.fx), exact(load.fy)])
            if load.frame == "body":
                force = _rot(der.poses[body].angle) * force
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
    M = der.ddt(H) - Me - _cross(P, F)
    return F, M, P


def _loads_beyond(der: SystemDerivation, beam, x: float) -> list[tuple[sp.Matrix, sp.Expr, sp.Matrix]]:
    """(F, tau, at) of the loads on beam's markers beyond station x (at the tip, x = L, those
    at the tip): joints (a cut joint's multipliers, a child tree joint's reaction, with the
    sign for the side the beam is on), point forces, spring-dampers (ground frame)."""
    system, out = der.system, []
    L = beam.length

    def beyond(ref):
        if ref == GROUND:
            return False
        body, m = system.marker(ref)
        return body == beam.name and (m.x > x or (x >= L and m.x >= L))

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
                F = _rot(der.poses[beam.name].angle) * F
            out.append((F, sp.Integer(0), marker_pose(der, load.marker)[0]))
        elif isinstance(load, SpringDamper) and (beyond(load.a) or beyond(load.b)):
            Fa = spring_force_on_a(der, load, _spring_ends(der, load))
            for ref, F in ((load.a, Fa), (load.b, -Fa)):
                if beyond(ref):
                    out.append((F, sp.Integer(0), marker_pose(der, ref)[0]))
    return out


def _equilibrium_stress(der: SystemDerivation, beam, x: float, fn: str) -> sp.Expr:
    """N or M at station x from the equilibrium of the part of the beam beyond x, with the
    frame's actual motion and gravity: the inertial loads -rho A (a - g) (a in frame
    components: A^T R'' + the relative, Coriolis, angular and centripetal terms, as
    outputs._equilibrium_* for a guided hub) and the loads on its markers beyond x (joint
    reactions, point forces). N: their frame-x component (tension > 0), M: their moment about
    the section point (point rotary inertias' couples included)."""
    part = der.flex[beam.name]
    if isinstance(part, ExactPart):  # the inertial loads over its quadrature (casadi)
        pose = der.poses[beam.name]
        Arot = _rot(pose.angle)
        u, v, slope = beam_fields_at(der, beam.name, x)
        tangent = sp.Matrix([sp.cos(slope), sp.sin(slope)])  # the section's axis, frame components
        section = pose.R + Arot * sp.Matrix([_x(der, beam.name, x) + u, v])
        out = inertial_section_load(part, der.casadi_outputs, x, fn)
        for F, tau, P in _loads_beyond(der, beam, x):
            out += (Arot.T * F).dot(tangent) if fn == "N" else _cross(P - section, F) + tau
        return out
    rho_, A_, L_ = (BEAM_PARAMS[k].symbol for k in (0, 2, 4))
    f, tab = part.fields, part.table
    om, al, a0x, a0y, gx, gy = sp.symbols("Om_ Al_ A0x_ A0y_ gx_ gy_", real=True)
    at = exact(x) / exact(beam.length)
    X = L_ * s + f.u
    ax = a0x - gx + f.u_ddot - 2 * om * f.v_dot - al * f.v - om**2 * X
    ay = a0y - gy + f.v_ddot + 2 * om * f.u_dot + al * X - om**2 * f.v
    view = part.view()
    if fn == "N":
        out = -rho_ * A_ * L_ * tab.integrate(f.weights["mu"] * ax, at, 1)
    else:
        dx = X - L_ * at - field_at(view, f.u, at)
        dy = f.v - field_at(view, f.v, at)
        out = -rho_ * A_ * L_ * tab.integrate(f.weights["mu"] * (dx * ay - dy * ax), at, 1)
        if f.weights["rot"] != 0:
            out -= rho_ * A_ * L_**3 * tab.integrate(f.weights["rot"] * (al + f.v_ddot_s / L_), at, 1)
    pose = der.poses[beam.name]
    Arot = _rot(pose.angle)
    omega = der.ddt(pose.angle)
    a0 = Arot.T * der.ddt(pose.R, 2)
    g = next((ld.g for ld in der.system.loads if isinstance(ld, Gravity)), (0, 0))
    gl = Arot.T * sp.Matrix([exact(c) for c in g])
    actual = {om: omega, al: der.ddt(omega), a0x: a0[0], a0y: a0[1], gx: gl[0], gy: gl[1]}
    out = out.xreplace(tab.substitutions()).xreplace(part.psyms).xreplace(actual)
    u, v, _ = beam_fields_at(der, beam.name, x)
    section = pose.R + Arot * sp.Matrix([_x(der, beam.name, x) + u, v])
    for F, tau, P in _loads_beyond(der, beam, x):
        out += (Arot.T * F)[0] if fn == "N" else _cross(P - section, F) + tau
    return out
