"""Equations of motion of a spatial System (dimension = 3) in relative coordinates on its
spanning tree (sympy): the 3D sibling of assemble.py, producing the same SystemDerivation, so
that sysgen.py, the templates and the runtime take it unchanged.

What is derived so far: rigid bodies, modal beams (uniform, or from finite-element data:
fedata.BeamBody, below) and the geometrically exact `ef` (spatial_ef.py) joined in a tree by
revolute, prismatic, cylindrical and universal joints (turns and slides in series about axes
fixed in the frame they move; axis_motion), spherical joints (Euler parameters on |e| = 1, a
constraint row) and clamps, with loops closed by spherical, universal, revolute, prismatic,
cylindrical joints and clamps (_cut_rows: one mechanism, the kinds as data, SPATIAL_CUT_ROWS),
guided or
motor-driven, under gravity, point forces, torques and spring-dampers, modal beams with
structural damping; a body may hang from a rigid body or from a modal beam's marker (the
deformed section's frame, _section_frame). What is not (an ef beam's damping, ...) is refused
up front by System.validate.

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
    phi = torsion: the first fixed-free torsion mode sin(pi s / 2) (TORSION_MODES).
Energies (uniform beam; Euler-Bernoulli, St Venant torsion, rotary inertia of bending left
out, as the spatial benchmarks define it):
    T = 1/2 int rho A |V + r' + omega x r|^2 dx + 1/2 int rho (I_y + I_z) (phi' + omega.t)^2 dx,
        t = (1, v_x, vz_x) the tangent to first order;
    V_g = -m g.R - int rho A g_c.r dx;  strain terms of the variant's strain model, generalised:
    axial EA/2 int u_x^2, bending EI_z/2 int v_xx^2 + EI_y/2 int vz_xx^2, torsion GJ/2 int
    phi_x^2 (always, on the torsion coordinate), cubic EA/2 int u_x (v_x^2 + vz_x^2) (#1/#2:
    K_G in both planes from the axial modes), prestress 1/2 int N(x) (v_x^2 + vz_x^2) with
    N = rho A (omega_y^2 + omega_z^2)(L^2 - x^2)/2 (the centrifugal load of the frame's actual
    rotation about the axes across the beam).
A beam from finite-element data: each term carries its section distribution (the table's
weights: rho A with the point masses, EA, EI_z, EI_y, GJ, rho (I_y + I_z)), each plane and the
torsion have their own modes from the mesh (_beam_modes), and prestress is the geometric
stiffness of the twelve unit inertial load cases projected on the modes times the frame's
actual omega_i omega_j, alpha_i and a_i (_load_case_energy); where a_i reads a free frame's
q'', that part of the force joins M (not symmetric then: the runtime factors it by LU).
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
from dataclasses import dataclass

import numpy as np
import sympy as sp

from flexsym.core.errors import SpecError
from flexsym.model.exact_numbers import exact
from flexsym.model.modes import mode, s
from flexsym.model.joint_kinds import KINDS
from flexsym.model.parameters import BEAM_PARAMS, SPATIAL_BEAM_PARAMS
from flexsym.model.strain_models import STRAIN_MODELS
from flexsym.model.system import (GROUND, SECOND, FlexibleBeam, Gravity, PointForce, SpringDamper,
                                  System, Torque, beam_coordinates, beam_station, length_scale, parse_output,
                                  section_at, section_point)
from flexsym.physics.assemble import (EF_T, Coordinate, SystemDerivation, _guided, add_spring,
                                      joint_coordinate, spring_force_on_a, start_of, violation)
from flexsym.physics.body_kinds.modal import damping_dissipation
from flexsym.model.fedata import (body_mode, load_case_forces, load_case_scale, load_case_stiffness, locate,
                                  round_sig)
from flexsym.physics.integrals import BodyIntegralTable, IntegralTable
from flexsym.physics.lagrange import equations_of_motion, generalized_force
from flexsym.physics.outputs import field_at
from flexsym.physics.spatial_ef import (ef_at, ef_body, ef_coordinates, ef_elastic_output,
                                        ef_kinetic_output, ef_rotation, ef_section, is_ef)
from flexsym.model.maneuver import parse_expression, t
from flexsym.scenes.assembly import joint_motion



def _skew(a: sp.Matrix) -> sp.Matrix:
    return sp.Matrix([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])


def _cross(a: sp.Matrix, b: sp.Matrix) -> sp.Matrix:
    return sp.Matrix([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _vec(v) -> sp.Matrix:
    return sp.Matrix([exact(c) for c in v])


def rotation(axis, angle) -> sp.Matrix:
    """Rodrigues: the rotation by angle about the unit axis (a number tuple, normalised here)."""
    a = _vec(axis)
    a = a / sp.sqrt(a.dot(a))
    K = _skew(a)
    return sp.eye(3) + sp.sin(angle) * K + (1 - sp.cos(angle)) * K * K


@dataclass
class Frame:
    """A body frame: A (ground <- frame), origin R (ground), and in the frame's own components
    its angular velocity omega, origin velocity V and the gravity g."""

    A: sp.Matrix
    R: sp.Matrix
    omega: sp.Matrix
    V: sp.Matrix
    g: sp.Matrix


def _params(system: System):
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
            pname = name if len(beams) == 1 else f"{b.name}_{name}"
            psym = sym if len(beams) == 1 else sp.Symbol(pname, positive=True)
            params.append((pname, psym, float(values[name])))
            mapping[name] = psym
        by_body[b.name] = mapping
    return params, by_body


def _beam_modes(b: FlexibleBeam) -> tuple[dict, dict]:
    """(coordinate -> the key of its mode in the beam's table, key -> mode). A uniform beam's
    two bending planes share its bending shapes and its torsion takes the bar's (the key is the
    mode's own coordinate); a body from finite-element data has its own shapes per plane and
    for torsion (fedata.BeamBody.view), keyed by the coordinate."""
    body = b.model.body
    names = beam_coordinates(b)
    if body is None:
        return {n: r.coordinate for n, _, r in names}, {r.coordinate: mode(r) for _, _, r in names}
    views = {"u": body, "v": body, "vz": body.view("z"), "phi": body.view("torsion")}
    return ({n: n for n, _, _ in names},
            {n: body_mode(views[n.split("_")[0]], r) for n, _, r in names})


def _fields(b: FlexibleBeam, sym: dict, symd: dict, symdd: dict, table: IntegralTable, fs: bool,
            keys: dict):
    """(position r, velocity r', acceleration r'' in the frame, per unit s; and the strain
    fields) as polynomials in the table's placeholders (keys: _beam_modes)."""
    L = BEAM_PARAMS[4].symbol
    mv = table.mode_value
    groups = {"u": [], "v": [], "vz": [], "phi": []}
    for n, _, _ in beam_coordinates(b):
        groups[n.split("_")[0]].append(n)

    def field(group, sy, order=0):
        return sum((mv(keys[n], order) * sy[n] for n in groups[group]), sp.Integer(0))

    F = {}
    for key, sy in (("", sym), ("_d", symd), ("_dd", symdd)):
        for g in groups:
            F[g + key] = field(g, sy)
    F["u_stretch_s"] = field("u", sym, 1)
    F["v_s"], F["v_ss"] = field("v", sym, 1), field("v", sym, 2)
    F["vz_s"], F["vz_ss"] = field("vz", sym, 1), field("vz", sym, 2)
    F["phi_s"] = field("phi", sym, 1)
    F["v_d_s"], F["vz_d_s"] = field("v", symd, 1), field("vz", symd, 1)
    if fs:  # u_fs = -1/(2L) sum_ij H_ij(s) (v_i v_j + vz_i vz_j)
        for plane in ("v", "vz"):
            for ni in groups[plane]:
                for nj in groups[plane]:
                    h = table.fs_value(keys[ni], keys[nj])
                    F["u"] += -h * sym[ni] * sym[nj] / (2 * L)
                    F["u_d"] += -h * sym[ni] * symd[nj] / L
                    F["u_dd"] += -h * (symd[ni] * symd[nj] + sym[ni] * symdd[nj]) / L
    return F


def _strain_density(term: str, F: dict, P: dict, omega: sp.Matrix, w) -> sp.Expr:
    """A strain-energy term per unit s (P: this body's parameter symbols, w: its table's
    section distributions, IntegralTable.weight)."""
    L, E, A, Iz, Iy, G, J, rho = (P[k] for k in ("L", "E", "A", "I", "Iy", "G", "J", "rho"))
    slope2 = F["v_s"]**2 + F["vz_s"]**2
    if term == "axial":
        return E * A * w("ea") / (2 * L) * F["u_stretch_s"]**2
    if term == "bending":
        return (E * Iz * w("ei") * F["v_ss"]**2 + E * Iy * w("eiy") * F["vz_ss"]**2) / (2 * L**3)
    if term == "torsion":
        return G * J * w("gj") / (2 * L) * F["phi_s"]**2
    if term == "cubic":
        return E * A * w("ea") / (2 * L**2) * F["u_stretch_s"] * slope2
    if term == "prestress":
        return rho * A * (omega[1]**2 + omega[2]**2) * L / 4 * (1 - s**2) * slope2
    raise SpecError(f"strain term '{term}' is not derived in 3D")


def _load_case_factors(der, fr: Frame, cases) -> dict:
    """The frame's actual value of each unit load case (fedata.LOAD_CASES): omega_i omega_j,
    alpha_i = omega_i', and a_i, its origin's acceleration minus gravity (V' + omega x V - g),
    in the frame's components (q'' appears where the frame moves freely)."""
    om, out, acc = fr.omega, {}, None
    for case in cases:
        kind, axes = case.split("_")
        k = ["xyz".index(c) for c in axes]
        if kind == "ww":
            out[case] = om[k[0]] * om[k[1]]
        elif kind == "al":
            out[case] = der.ddt(om[k[0]])
        else:  # the origin's acceleration: once for the three a_i
            acc = der.ddt(fr.V) + _cross(om, fr.V) - fr.g if acc is None else acc
            out[case] = acc[k[0]]
    return out


def _load_case_energy(der, b: FlexibleBeam) -> sp.Expr:
    """The prestress of a body from finite-element data: V = 1/2 sum_c f_c rho A L^(m_c - 1)
    q^T D_c q on each bending plane's coordinates, D_c the geometric stiffness of unit load
    case c projected on the plane's modes (fedata.load_case_stiffness), f_c its frame's
    actual motion (_load_case_factors): the stiffening follows the frame's rotation, angular
    and linear acceleration and gravity, whatever they are."""
    d = der.spatial[b.name]
    P, sym, keys, modes = d["P"], d["sym"], d["keys"], d["modes"]
    planes = {}
    for plane in ("v", "vz"):
        names = [n for n, g, _ in beam_coordinates(b) if g == "bending" and n.split("_")[0] == plane]
        planes[plane] = (names, load_case_stiffness(b.model.body, [modes[keys[n]].shape for n in names]))
    # the frame's factors once for both planes (their cases are the same: K_G,e is either's)
    f = _load_case_factors(der, der.spatial["frames"][b.name], {c for _, D in planes.values() for c in D})
    V = sp.Integer(0)
    for names, D in planes.values():
        qv = sp.Matrix([sym[n] for n in names])
        for case, Dc in D.items():
            Dm = sp.Matrix(Dc.shape[0], Dc.shape[1], [sp.Float(repr(float(v)), 17) for v in Dc.ravel()])
            V += f[case] * P["rho"] * P["A"] * P["L"]**(load_case_scale(case) - 1) * (qv.T * Dm * qv)[0, 0] / 2
    return sp.expand(V)


def _load_case_axial_force(der, b: FlexibleBeam, fr: Frame, x: float) -> sp.Expr:
    """N at station x of a body from finite-element data under its frame's inertial load: the
    unit load cases' element forces there (the element beyond a node) times the frame's
    values, scaled by the run-time rho A L^m (fedata.load_case_forces)."""
    body, P = b.model.body, der.spatial[b.name]["P"]
    e = int(locate(body, np.array([x / b.length]), +1)[0])
    r, Lb = body.reference, body.length
    forces = {c: N[e] for c, N in load_case_forces(body).items()}
    f = _load_case_factors(der, fr, [c for c, v in forces.items() if v])
    return sp.Add(*[f[c] * P["rho"] * P["A"] * P["L"]**load_case_scale(c)
                    * sp.Float(repr(round_sig(forces[c] / (r.rho * r.A * Lb**load_case_scale(c)))), 17)
                    for c in f])


def derive_spatial(system: System, ef_free_ad: bool = False) -> SystemDerivation:
    """ef_free_ad: spatial ef beams on a free frame get their elements' kinetic energy through the
    whole-system AD path (der.casadi_T) instead of the per-element C kernels (a check)."""
    system.validate()
    tree = system.tree()
    guided = _guided(system)
    guided_by_joint = {g.joint: g for g in guided}  # by the guided coordinate's name
    params, psyms = _params(system)

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
    for b in system.bodies:
        if b.flexible and is_ef(b):  # rod3d: per free node, displacement and rotation vector
            coords += [Coordinate(f"{b.name}_{n}", "node", b.name, start=(0.0, 0.0))
                       for n in ef_coordinates(b)]
        elif b.flexible:
            coords += [Coordinate(f"{b.name}_{n}", g, b.name) for n, g, _ in beam_coordinates(b)]
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
    der.casadi_T_out = []

    for b in system.bodies:  # the modal beams' fields first: a body may hang from a marker
        if b.flexible and not is_ef(b):
            strain = STRAIN_MODELS[b.model.validate().strain]
            names = beam_coordinates(b)
            keys, modes = _beam_modes(b)
            body = b.model.body
            table = IntegralTable(modes) if body is None else BodyIntegralTable(body, modes)
            sym, symd, symdd = ({n: sp.Symbol(f"{b.name}_{n}{k}", real=True) for n, _, _ in names}
                                for k in ("", "_d", "_dd"))
            F = _fields(b, sym, symd, symdd, table, strain.foreshortening, keys)
            der.spatial[b.name] = dict(F=F, table=table, modes=modes, keys=keys, P=psyms[b.name],
                                       sym=sym, r=sp.Matrix([psyms[b.name]["L"] * s + F["u"], F["v"], F["vz"]]))

    grav = next((ld.g for ld in system.loads if isinstance(ld, Gravity)), (0, 0, 0))
    frames = {GROUND: Frame(sp.eye(3), sp.zeros(3, 1), sp.zeros(3, 1), sp.zeros(3, 1), _vec(grav))}
    for body in tree.order:
        j = system.joint(tree.joint_of(body))
        if j.parent == GROUND:
            fp, m_p = frames[GROUND], _vec(j.point)
        else:
            pbody, pm = system.marker(j.parent)
            if system.body(pbody).flexible:  # a modal beam's marker (System.validate)
                fp, m_p = _section_frame(der, frames[pbody], pbody, pm.x), sp.zeros(3, 1)
            else:
                fp, m_p = frames[pbody], _vec((pm.x, pm.y, pm.z))
        cm = system.marker(j.child)[1]
        m_c = _vec((cm.x, cm.y, cm.z))
        if j.kind == "spherical":
            e = sp.Matrix([x for x, _ in joint_sym[j.name]])
            ed = sp.Matrix([xd for _, xd in joint_sym[j.name]])
            Q, rel = euler_rotation(e), 2 * euler_G(e) * ed
            # e.e = 1 as a constraint row scaled to a length (the runtime's tolerances are
            # lengths); (e.e')^2 k/2 in T makes M regular and vanishes with its forces on it
            scale = exact(length_scale(system))
            der.constraints.append((f"{j.name}.norm", scale * (e.dot(e) - 1) / 2))
            der.T += 2 * _spin_inertia(system, body, psyms) * e.dot(ed)**2
            slide, v_rel = sp.zeros(3, 1), sp.zeros(3, 1)
        else:
            Q, rel, slide, v_rel = axis_motion(j, joint_sym.get(j.name, ()))
        m_p = m_p + slide
        omega = Q.T * fp.omega + rel
        # v_rel = a s' needs no Q^T: Q turns about a itself (a cylindrical joint), or is I
        V = Q.T * (fp.V + _cross(fp.omega, m_p)) - _cross(omega, m_c) + v_rel
        A_ = fp.A * Q
        R = fp.R + fp.A * m_p - A_ * m_c
        frames[body] = Frame(A_, R, omega, V, Q.T * fp.g)
    der.spatial["frames"] = frames
    early = not any(b.flexible and is_ef(b) for b in system.bodies)
    if early:  # the loops' rows and their checks before the costly work (an ef beam's markers: after it)
        _cut_rows(der)

    V_grav, Q_ = sp.Integer(0), sp.zeros(len(coords), 1)
    gvec = _vec(grav)
    der.frame_T = []  # (T in the frame-motion placeholders, their actual values): sysgen, by AD
    for b in system.bodies:
        fr = frames[b.name]
        om, vf = _motion_symbols(b.name)
        actual = {x: e for x, e in zip(om, fr.omega)} | {x: e for x, e in zip(vf, fr.V)}
        if not b.flexible:
            c = _vec(b.com)
            m = exact(b.mass)
            vG = vf + _cross(om, c)
            I3 = [exact(v) for v in b.inertia]
            der.frame_T.append((m * vG.dot(vG) / 2 + sum(I3[k] * om[k]**2 for k in range(3)) / 2,
                                actual))
            V_grav += -m * (gvec.dot(fr.R) + fr.g.dot(c))
            continue
        P = psyms[b.name]
        if is_ef(b):
            V_grav += ef_body(der, b, P, fr, om, vf, actual, gvec)
            continue
        strain = STRAIN_MODELS[b.model.strain]
        F, table, modes, r = (der.spatial[b.name][k] for k in ("F", "table", "modes", "r"))
        L, rho, A = P["L"], P["rho"], P["A"]
        w = table.weight
        rd = sp.Matrix([F["u_d"], F["v_d"], F["vz_d"]])
        vel = vf + rd + _cross(om, r)  # in the placeholders: short expansions, short integrals
        spin = F["phi_d"] + om[0] + (om[1] * F["v_s"] + om[2] * F["vz_s"]) / L

        def integral(density, a=0, b_=1, table=table, P=P):
            generic = {gp.symbol: P[gp.name] for gp in BEAM_PARAMS}
            return table.integrate(sp.expand(density), a, b_).xreplace(table.substitutions()).xreplace(generic)

        der.frame_T.append((integral(rho * A * L / 2 * w("mu") * vel.dot(vel)
                                     + rho * (P["Iy"] + P["I"]) * L / 2 * w("ip") * spin**2), actual))
        V_grav += (-integral(rho * A * L * w("mu")) * gvec.dot(fr.R)
                   - integral(rho * A * L * w("mu") * fr.g.dot(r)))
        for term_name, wrt in strain.terms + (("torsion", ("torsion",)),):
            if term_name == "prestress" and b.model.body is not None:
                Vt = _load_case_energy(der, b)  # the unit inertial load cases (fedata)
            else:
                Vt = integral(_strain_density(term_name, F, P, fr.omega, w))
            Qk = generalized_force(Vt, q, [c.body == b.name and c.group in wrt for c in coords])
            der.terms.append((b.name, term_name, wrt, Vt, Qk))
            der.V += Vt
            Q_ += Qk
        if b.damped:  # D in the elastic rates (body_kinds.modal.damping_dissipation), Q -= dD/dq'
            der.dissipation[b.name] = _dissipation(b, P, table, integral, der.spatial[b.name]["keys"])
            Q_ -= sp.Matrix([sp.diff(der.dissipation[b.name], x) for x in qd])
        der.spatial[b.name] = dict(F=F, table=table, modes=modes, P=P, r=r, vel=vel, spin=spin,
                                   integral=integral, om=om, vf=vf, actual=actual)
    der.V += V_grav
    der.V_grav = V_grav
    Q_ += sp.Matrix([-sp.diff(V_grav, x) for x in q])
    for load in system.loads:
        if isinstance(load, SpringDamper):
            Q_ += add_spring(der, load, _spring_ends(der, load))
    Q_ += _applied(der)
    # a force that reads a free frame's acceleration (a body's unit load cases) is part of M
    reads_qdd = any(e.has(*qdd) for e in Q_)  # else no system pays for the Jacobian below
    B = Q_.jacobian(qdd) if reads_qdd else None
    if reads_qdd:
        Q_ = Q_.xreplace(dict.fromkeys(qdd, 0))
        der.V = der.V.xreplace(dict.fromkeys(qdd, 0))  # V holds such terms at q'' = 0
    der.Q = Q_.applyfunc(sp.expand)
    der.M, der.f = equations_of_motion(der.T, der.Q, q, qd, [gd.symbols for gd in guided])
    if reads_qdd:
        der.M = (der.M - B).applyfunc(sp.expand)
    if not early:
        _cut_rows(der)
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
    a = _vec(axis)
    return a / sp.sqrt(a.dot(a))


def _dissipation(b: FlexibleBeam, P: dict, table: IntegralTable, integral, keys: dict) -> sp.Expr:
    """D of a damped spatial modal beam: as in the plane, from the strain-rate energy (axial,
    both bending planes, torsion) and the relative kinetic energy (translation and the
    section's spin, as T holds them) of the undeformed beam's elastic rates."""
    rate = {n: sp.Symbol(f"{b.name}_{n}_d", real=True) for n, _, _ in beam_coordinates(b)}
    R = _fields(b, rate, rate, rate, table, False, keys)  # fields linear in the rates
    w = table.weight
    K2 = integral(sum(_strain_density(t, R, P, None, w) for t in ("axial", "bending", "torsion")))
    M2 = integral(P["rho"] * P["A"] * P["L"] / 2 * w("mu") * (R["u"]**2 + R["v"]**2 + R["vz"]**2)
                  + P["rho"] * (P["Iy"] + P["I"]) * P["L"] / 2 * w("ip") * R["phi"]**2)
    return damping_dissipation(b.damping, K2, M2, list(rate.values()))


def _section_frame(der, fb: Frame, beam: str, x: float) -> Frame:
    """The frame of a modal beam's deformed section at station x, for a body hung from a marker
    there: origin at the axis point r(x), axes turned from the beam frame's by the rotation
    S = R_z(theta_z) R_y(theta_y) R_x(theta_x), theta = (phi, -vz_x, v_x): exactly a rotation,
    I + [theta]x to first order as the modal kinematics, and in a plane (theta = (0, 0, v_x)) the
    planar tangent angle itself, so a planar system run as a spatial one keeps its rows. Its
    angular velocity relative to the beam frame, in its own axes: R_x^T R_y^T theta_z' e_z +
    R_x^T theta_y' e_y + theta_x' e_x."""
    th = _section_angles(der, beam, x)
    Rx, Ry, Rz = _section_turns(th)
    rate = [der.ddt(t_) for t_ in th]
    rel = (Rx.T * Ry.T * sp.Matrix([0, 0, rate[2]]) + Rx.T * sp.Matrix([0, rate[1], 0])
           + sp.Matrix([rate[0], 0, 0]))
    S = Rz * Ry * Rx
    r = _at(der, beam, x, "r")
    return Frame(fb.A * S, fb.R + fb.A * r, S.T * fb.omega + rel,
                 S.T * (fb.V + _cross(fb.omega, r) + der.ddt(r)), S.T * fb.g)


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
    vals |= {sym: v for _, sym, v in der.params}
    return vals | getattr(der, "ef_start", {})  # an ef node's section rotation: I


def _section_turns(th: sp.Matrix) -> tuple[sp.Matrix, sp.Matrix, sp.Matrix]:
    """(R_x, R_y, R_z) of a section's angles theta: its axes are the beam frame's turned by
    S = R_z R_y R_x, a rotation (orthonormal, unlike I + [theta]x), equal to it to first order."""
    return tuple(rotation(axis, angle) for axis, angle in zip(((1, 0, 0), (0, 1, 0), (0, 0, 1)), th))


def _section_rotation(der, ref: str) -> sp.Matrix:
    """Ground <- section axes at 'body.marker' (a beam's: the frame turned by the section's
    rotation S = R_z R_y R_x of theta = (phi, -vz_x, v_x), as a hung body's, _section_frame)."""
    body, m = der.system.marker(ref)
    fr = der.spatial["frames"][body]
    if not der.system.body(body).flexible:
        return fr.A
    if is_ef(der.system.body(body)):  # a node's section: exp(psi), exact (spatial_ef.ef_rotation)
        return fr.A * ef_rotation(der, body, m.x)
    Rx, Ry, Rz = _section_turns(_section_angles(der, body, m.x))
    return fr.A * Rz * Ry * Rx


def _section_angles(der, beam: str, x: float) -> sp.Matrix:
    """theta = (phi, -vz_x, v_x): a modal beam section's rotation at station x from its frame
    (torsion, then the slopes of the two bending planes), first order as the modal kinematics."""
    L = der.spatial[beam]["P"]["L"]
    return sp.Matrix([_at(der, beam, x, "phi"), -_at(der, beam, x, "vz_s") / L, _at(der, beam, x, "v_s") / L])


def _cut_point(der, ref: str, point) -> sp.Matrix:
    """A cut joint's side's point (ground's: the joint's point)."""
    return _vec(point) if ref == GROUND else _marker_point(der, ref)


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
    start = None
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
            start = start or _start_values(der)
            e1 = der.spatial["frames"][system.marker(j.child)[0]].A * _vec(j.axis)
            e1 = e1 / sp.sqrt(_vec(j.axis).dot(_vec(j.axis)))
            Rp = _section_rotation(der, j.parent)
            start |= getattr(der, "ef_start", {})  # an ef node's section: placeholders
            e1_0 = [float(v) for v in e1.xreplace(start).evalf()]
            x_0 = [float(v) for v in (Rp * sp.Matrix([1, 0, 0])).xreplace(start).evalf()]
            e2_0 = _vec(_unit(np.cross(e1_0, x_0)))
            e2_local = sp.Matrix([exact(float(v)) for v in (Rp.xreplace(start).evalf().T * e2_0)])
            e2 = Rp * e2_local
            der.constraints.append((f"{name}.cross", scale * e1.dot(e2)))
            loads.append(("turn", e1, e2))
        elif turn_rows:
            start = start or _start_values(der)
            Ap, Ac = _cut_axes_of(der, j.parent), _cut_axes_of(der, j.child)
            p, c = _cut_point(der, j.parent, j.point), _marker_point(der, j.child)
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
        start = start or _start_values(der)
        for row, phi in der.constraints:
            if row.endswith(".norm"):
                continue
            gap = float(phi.xreplace(start).evalf())
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
                torque += -lam * _cross(n, gap)
        else:
            u, w = load[1], load[2]
            mu = lam * scale
            torque += -mu * (_cross(w, u) if parent else _cross(u, w))
    return force, torque


def _motion_symbols(body: str) -> tuple[sp.Matrix, sp.Matrix]:
    """Placeholders of a body frame's angular velocity and origin velocity (its components)."""
    return (sp.Matrix(sp.symbols(f"{body}_Om_x {body}_Om_y {body}_Om_z", real=True)),
            sp.Matrix(sp.symbols(f"{body}_V_x {body}_V_y {body}_V_z", real=True)))


def euler_rotation(e: sp.Matrix) -> sp.Matrix:
    """A(e) (ground <- frame) of Euler parameters e = (e0, e1, e2, e3), |e| = 1."""
    v = e[1:, 0]
    return (e[0]**2 - v.dot(v)) * sp.eye(3) + 2 * v * v.T + 2 * e[0] * _skew(v)


def euler_G(e: sp.Matrix) -> sp.Matrix:
    """G(e): the frame's angular velocity in its own components is 2 G e' (G e = 0)."""
    e0, e1, e2, e3 = e
    return sp.Matrix([[-e1, e0, e3, -e2], [-e2, -e3, e0, e1], [-e3, e2, -e1, e0]])


def _spin_inertia(system: System, body: str, psyms: dict) -> sp.Expr:
    """A moment of inertia of the body (its scale only sets the regularisation's size)."""
    b = system.body(body)
    if b.flexible:
        P = psyms[body]
        return P["rho"] * P["A"] * P["L"]**3 / 3
    return exact(max(b.inertia))


def _momentum(der, bodies=None) -> sp.Matrix:
    """Angular momentum about the ground origin of `bodies` (None: all), ground components:
    per rigid body m G x v_G + A (I omega); per beam A [int rho A (A^T R + r) x v dx + int rho
    (I_y + I_z) spin t dx] (the momentum conjugate to this T's rotation: conserved about an
    axis about which nothing acts)."""
    H = sp.zeros(3, 1)
    for b in der.system.bodies:
        if bodies is not None and b.name not in bodies:
            continue
        fr = der.spatial["frames"][b.name]
        if not b.flexible:
            c, m = _vec(b.com), exact(b.mass)
            vG = fr.V + _cross(fr.omega, c)
            I3 = sp.diag(*[exact(v) for v in b.inertia])
            H += fr.A * (m * _cross(fr.A.T * fr.R + c, vG) + I3 * fr.omega)
            continue
        d = der.spatial[b.name]
        P, F = d["P"], d["F"]
        L = P["L"]
        tangent = sp.Matrix([1, F["v_s"] / L, F["vz_s"] / L])
        Rl = sp.Matrix(sp.symbols(f"{b.name}_R_x {b.name}_R_y {b.name}_R_z", real=True))
        w = d["table"].weight
        dens = P["rho"] * P["A"] * L * w("mu") * _cross(Rl + d["r"], d["vel"]) \
            + P["rho"] * (P["Iy"] + P["I"]) * L * w("ip") * d["spin"] * tangent
        now = d["actual"] | dict(zip(Rl, fr.A.T * fr.R))  # substituted after integrating
        H += fr.A * sp.Matrix([d["integral"](e).xreplace(now) for e in dens])
    return H


def _first_moment(der, bodies) -> tuple[sp.Expr, sp.Matrix]:
    """(mass, first moment about the ground origin, ground components) of `bodies`: per rigid
    body m (R + A c), per modal beam m R + A int rho A r dx."""
    mass, S = sp.Integer(0), sp.zeros(3, 1)
    for name in sorted(bodies):
        b, fr = der.system.body(name), der.spatial["frames"][name]
        if not b.flexible:
            m = exact(b.mass)
            mass, S = mass + m, S + m * (fr.R + fr.A * _vec(b.com))
            continue
        d = der.spatial[name]
        mu = d["P"]["rho"] * d["P"]["A"] * d["P"]["L"] * d["table"].weight("mu")
        m = d["integral"](mu)
        mass += m
        S += m * fr.R + fr.A * sp.Matrix([d["integral"](mu * e) for e in d["r"]])
    return mass, S


def joint_reaction(der, joint) -> tuple[sp.Matrix, sp.Matrix]:
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
        F, Mo = F + force, Mo + _cross(at, force)

    def inside(ref):
        return ref != GROUND and system.marker(ref)[0] in bodies

    gvec = _vec(next((ld.g for ld in system.loads if isinstance(ld, Gravity)), (0, 0, 0)))
    F, Mo = F + mass * gvec, Mo + _cross(S, gvec)
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
    Fr = der.ddt(S, 2) - F
    return Fr, der.ddt(_momentum(der, bodies)) - Mo - _cross(P, Fr)


def _marker_point(der, ref: str) -> sp.Matrix:
    """Ground position of 'body.marker' (on a beam: the deformed axis point)."""
    body, m = der.system.marker(ref)
    fr = der.spatial["frames"][body]
    if not der.system.body(body).flexible:
        return fr.R + fr.A * _vec((m.x, m.y, m.z))
    if der.spatial[body].get("kind") == "ef":
        return fr.R + fr.A * ef_at(der, body, m.x)
    return fr.R + fr.A * _at(der, body, m.x, "r")


def _spring_ends(der, load: SpringDamper) -> list[sp.Matrix]:
    return [_vec(pt) if ref == GROUND else _marker_point(der, ref)
            for ref, pt in ((load.a, load.point_a), (load.b, load.point_b))]


def _at(der, body: str, x: float, what: str):
    """A field of a beam at station x (the table's values substituted)."""
    d = der.spatial[body]
    beam = der.system.body(body)
    at = exact(x) / exact(beam.length)
    view = _View(d["table"], d["modes"])
    generic = {gp.symbol: d["P"][gp.name] for gp in BEAM_PARAMS}

    def fa(e):  # field_at leaves s (in L s) alone: the station is s = at
        e = field_at(view, e, at).xreplace({s: at})
        return e.xreplace(d["table"].substitutions()).xreplace(generic)
    if what == "r":
        return sp.Matrix([fa(e) for e in d["r"]])
    return fa(d["F"][what])


@dataclass
class _View:
    table: IntegralTable
    modes: dict


def _applied(der) -> sp.Matrix:
    """Generalised forces of point forces, motors and torques (virtual power: F . dr/dq,
    tau . d omega / dq')."""
    system = der.system
    Q = sp.zeros(len(der.q), 1)
    names = _names(der)
    for load in system.loads:
        if isinstance(load, PointForce):
            F = _point_force(der, load)
            p = _marker_point(der, load.marker)
            Q += sp.Matrix([F.dot(sp.diff(p, x)) for x in der.q])
        elif isinstance(load, Torque):  # virtual power tau . omega, omega in the body's axes
            fr = der.spatial["frames"][load.body]
            tau = _torque(der, load, names)
            if load.frame == "ground":
                tau = fr.A.T * tau
            Q += sp.Matrix([tau.dot(sp.diff(fr.omega, xd)) for xd in der.qd])
    for d in system.drivers:
        if d.kind == "motor":
            tau = parse_expression(d.expression, tuple(names.items()),
                                   f"system '{system.name}': driver '{d.name}'")
            k = next(i for i, c in enumerate(der.coords) if c.name == system.driven(d))
            Q[k] += tau
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
    F = _vec((load.fx, load.fy, load.fz))
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
    if fn == "T":  # EF_T: what casadi adds (the bodies' T in their frame's motion)
        return der.T + EF_T + (ef_kinetic_output(der) if der.casadi_T_out else 0)
    ef = getattr(der, "rod_bodies", [])
    if fn == "V":
        return der.V + (ef_elastic_output(der) if ef else 0)
    if fn == "violation":
        return violation(der)
    if fn == "dissipation":  # 2 D: the power of the damped modal beams
        return 2 * sp.Add(*der.dissipation.values())
    if fn in ("Hx", "Hy", "Hz"):  # modal beams only (System.validate)
        return _momentum(der)["xyz".index(fn[1])]
    if fn == "reaction":  # x, y, z: the force; mx, my, mz: the moment (REACTION_COMPONENTS)
        F, M = joint_reaction(der, system.joint(args[0]))
        return (F if len(args[1]) == 1 else M)["xyz".index(args[1][-1])]
    beam = system.body(args[0])
    x = beam_station(system, beam, args[1], where)
    if fn == "sigma":
        return _sigma(der, beam, x, args[2:], where)
    if is_ef(beam):
        if fn in ("u", "v", "vz"):
            r = ef_at(der, beam.name, x)
            k = ("u", "v", "vz").index(fn)
            return r[k] - (exact(x) / exact(beam.length) * der.spatial[beam.name]["P"]["L"]
                           if k == 0 else 0)
        if fn == "w":
            p0, p1, px = (ef_at(der, beam.name, xx) for xx in (0.0, beam.length, x))
            d = p1 - p0
            c = _cross(d, px - p0)
            return sp.sqrt(c.dot(c) / d.dot(d))
        return ef_section(der, beam, x, fn)
    if fn in ("u", "v", "vz"):
        return _at(der, beam.name, x, fn)
    if fn == "w":  # distance from the chord root-tip
        p0, p1, px = (_at(der, beam.name, xx, "r") for xx in (0.0, beam.length, x))
        d = p1 - p0
        c = _cross(d, px - p0)
        return sp.sqrt(c.dot(c) / d.dot(d))
    return _section(der, beam, x, fn)


def _sigma(der, beam: FlexibleBeam, x: float, point, where: str) -> sp.Expr:
    """The normal stress at the section point (y, z): E eps with eps = u' - y v'' - z vz'',
    and Mz = E I_z v'', My = -E I_y vz'' (a fibre at y > 0 shortens under Mz > 0, as in the
    plane; one at z > 0 stretches under My > 0), so sigma = N/A - Mz y/I_z + My z/I_y, with the
    beam's N, My and Mz (constitutive or from equilibrium, modal or ef)."""
    y, z = (exact(c) for c in section_point(beam, x, point, where))
    P = der.spatial[beam.name]["P"]
    section = ef_section if is_ef(beam) else _section
    N, My, Mz = (section(der, beam, x, f) for f in ("N", "My", "Mz"))
    sec = beam.section  # the section at x, as the run-time parameters scaled (section_at)
    A, Iz, Iy = (P[k] * exact(v / getattr(sec, k)) for k, v in zip(("A", "I", "Iy"), section_at(beam, x)))
    return N / A - Mz * y / Iz + My * z / Iy


def _section(der, beam: FlexibleBeam, x: float, fn: str) -> sp.Expr:
    """N (along the frame's x, as in the plane), Qy, Qz, Mx, My, Mz at station x in the deformed
    section's axes, constitutive or from equilibrium (Q: always from equilibrium, the
    Euler-Bernoulli beam has no shear strain). The equilibrium force S and moment M, found in the
    frame's components, are turned by the section's rotation theta = (phi, -vz_x, v_x) to first
    order, X_section = X - theta x X, the order of the modal kinematics; N stays S_x (the planar
    N; the turn would add v_x S_y + vz_x S_z, slope times shear)."""
    if fn[0] == "Q" or (fn != "N" and beam.model.moment == "equilibrium"):
        X = sp.Matrix([_frame_section(der, beam, x, ("S" if fn[0] == "Q" else "M") + k) for k in "xyz"])
        return (X - _cross(_section_angles(der, beam.name, x), X))["xyz".index(fn[1])]
    return _frame_section(der, beam, x, fn)


def _frame_section(der, beam: FlexibleBeam, x: float, fn: str) -> sp.Expr:
    """N, Mx, My, Mz at station x: constitutive, or from equilibrium in the frame's components;
    Sx, Sy, Sz: the force of the part beyond x, from equilibrium (N from equilibrium is Sx).
    Each once per derivation: the turned moments, Q and sigma at one station share them (the
    integrals take seconds each)."""
    if fn == "N" and beam.model.axial_force == "equilibrium":
        fn = "Sx"
    memo = der.spatial[beam.name].setdefault("sections", {})
    if (x, fn) not in memo:
        memo[(x, fn)] = _frame_section_of(der, beam, x, fn)
    return memo[(x, fn)]


def _frame_section_of(der, beam: FlexibleBeam, x: float, fn: str) -> sp.Expr:
    d = der.spatial[beam.name]
    P = d["P"]
    source = "equilibrium" if fn[0] == "S" else beam.model.axial_force if fn == "N" else beam.model.moment
    if source != "equilibrium":
        L = P["L"]
        at = exact(x) / exact(beam.length)
        w = lambda kind: d["table"].weight_at(kind, at)  # noqa: E731 (the section there)
        if fn == "N":
            if beam.model.strain == "prestress":
                fr = der.spatial["frames"][beam.name]
                if beam.model.body is not None:  # the unit load cases' axial forces there
                    return _load_case_axial_force(der, beam, fr, x)
                om = fr.omega
                return P["rho"] * P["A"] * (om[1]**2 + om[2]**2) * L**2 * (1 - at**2) / 2
            if not beam.model.axial:
                raise SpecError(f"system '{der.system.name}': body '{beam.name}': strain model "
                                f"'{beam.model.strain}' has no axial coordinate to carry N")
            return P["E"] * P["A"] * w("ea") / L * _at(der, beam.name, x, "u_stretch_s")
        return {"Mx": P["G"] * P["J"] * w("gj") / L * _at(der, beam.name, x, "phi_s"),
                "My": -P["E"] * P["Iy"] * w("eiy") / L**2 * _at(der, beam.name, x, "vz_ss"),
                "Mz": P["E"] * P["I"] * w("ei") / L**2 * _at(der, beam.name, x, "v_ss")}[fn]
    # equilibrium of the part beyond x: S = int (g - a) rho A dx + loads on its markers,
    # M = int (r - r_x) x rho A (g - a) dx - d/dt int rho (I_y + I_z) spin t dx + load moments
    # the acceleration in the frame's components, a = a_0 + alpha x r + omega x (omega x r)
    # + 2 omega x r' + r'', integrated in placeholders and then given the frame's actual motion
    fr = der.spatial["frames"][beam.name]
    at = exact(x) / exact(beam.length)
    om, F, r = d["om"], d["F"], d["r"]
    al = sp.Matrix(sp.symbols(f"{beam.name}_Al_x {beam.name}_Al_y {beam.name}_Al_z", real=True))
    a0 = sp.Matrix(sp.symbols(f"{beam.name}_A0_x {beam.name}_A0_y {beam.name}_A0_z", real=True))
    gl = sp.Matrix(sp.symbols(f"{beam.name}_g_x {beam.name}_g_y {beam.name}_g_z", real=True))
    rd = sp.Matrix([F["u_d"], F["v_d"], F["vz_d"]])
    rdd = sp.Matrix([F["u_dd"], F["v_dd"], F["vz_dd"]])
    acc = a0 + _cross(al, r) + _cross(om, _cross(om, r)) + 2 * _cross(om, rd) + rdd
    L, rho, A = P["L"], P["rho"], P["A"]
    w = d["table"].weight
    load = rho * A * L * w("mu") * (gl - acc)
    force, k = fn[0] == "S", "xyz".index(fn[1])
    if force:
        out = d["integral"](load[k], at, 1)
    else:
        rx = sp.Matrix([field_at(_View(d["table"], d["modes"]), e, at).xreplace({s: at})
                        for e in r])
        mom = _cross(r - rx, load)
        # minus the rate of the sections' spin momentum beyond x, h = rho (I_y + I_z) spin t
        # along the tangent t (as T's rotary term and _momentum hold it): its rate in the frame
        # plus omega x h (the gyroscopic part, in all three components)
        spin_rate = F["phi_dd"] + al[0] + (al[1] * F["v_s"] + om[1] * F["v_d_s"]
                                           + al[2] * F["vz_s"] + om[2] * F["vz_d_s"]) / L
        tangent = sp.Matrix([1, F["v_s"] / L, F["vz_s"] / L])
        h_rate = (spin_rate * tangent + d["spin"] * sp.Matrix([0, F["v_d_s"] / L, F["vz_d_s"] / L])
                  + _cross(om, d["spin"] * tangent))
        out = d["integral"](mom[k] - rho * (P["Iy"] + P["I"]) * L * w("ip") * h_rate[k], at, 1)
    omega = fr.omega
    now = (d["actual"] | dict(zip(al, der.ddt(omega))) | dict(zip(gl, fr.g))
           | dict(zip(a0, der.ddt(fr.V) + _cross(omega, fr.V))))
    out = out.xreplace(now)
    section = _at(der, beam.name, x, "r")

    def beyond(ref):  # a marker of this beam on the part beyond x
        if ref == GROUND:
            return None
        body, m = der.system.marker(ref)
        on = body == beam.name and (m.x > x or (x >= beam.length and m.x >= beam.length))
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
            out += _cross(_at(der, beam.name, m.x, "r") - section, Floc)[k] + tloc[k]
    for ld in der.system.loads:  # point forces and spring ends on the part beyond x
        if isinstance(ld, PointForce):
            acting = [(beyond(ld.marker), _vec((ld.fx, ld.fy, ld.fz)), ld.frame == "body")]
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
                out += _cross(_at(der, beam.name, m.x, "r") - section, Floc)[k]
    return out
