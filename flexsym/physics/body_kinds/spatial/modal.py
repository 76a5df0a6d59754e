"""A spatial modal beam (physics/spatial.py's module doc: its fields, energies, sections): its
elastic coordinates are the amplitudes of its modes, axial, bending in the frame's two planes
and torsion; T in its frame's placeholders, V_g, the strain terms and their generalised forces
are integrated by its table. A uniform beam and a beam from finite-element data are one kind,
as in the plane: the data give the table's weights, each plane's modes (_beam_modes) and the
prestress from the unit load cases (_load_case_energy)."""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import sympy as sp

from flexsym.core.errors import SpecError
from flexsym.model.exact_numbers import exact
from flexsym.model.fedata import (body_mode, load_case_forces, load_case_scale, load_case_stiffness, locate,
                                  round_sig)
from flexsym.model.modes import mode, s
from flexsym.model.parameters import BEAM_PARAMS
from flexsym.model.strain_models import STRAIN_MODELS
from flexsym.model.system import FlexibleBeam, beam_coordinates, loads_at
from flexsym.physics.assemble import Coordinate
from flexsym.physics.body_kinds import modal as planar
from flexsym.physics.body_kinds.modal import damping_dissipation
from flexsym.physics.body_kinds.spatial.base import Frame, SpatialBeam, cross, rotation
from flexsym.physics.integrals import BodyIntegralTable, IntegralTable
from flexsym.physics.lagrange import generalized_force
from flexsym.physics.outputs import field_at
from flexsym.physics.validity import modal_gauges


class Modal(SpatialBeam):
    name = "modal"
    applies = staticmethod(planar.KIND.applies)  # the same data in both dimensions

    def coordinates(self, b) -> list:
        return [Coordinate(f"{b.name}_{n}", g, b.name) for n, g, _ in beam_coordinates(b)]

    def gauges(self, b, length: float) -> list:
        keys, modes = _beam_modes(b)  # each coordinate's own mode (a body's: its plane's)
        cols = [(f"{b.name}_{n}", g, modes[keys[n]]) for n, g, _ in beam_coordinates(b)]
        bending = [(c, m) for c, g, m in cols if g == "bending"]
        half = len(bending) // 2  # v_* (the frame's x-y plane), then vz_* (x-z)
        return modal_gauges(b, length, [(c, m) for c, g, m in cols if g == "axial"],
                            [bending[:half], bending[half:]], [(c, m) for c, g, m in cols if g == "torsion"])

    def part(self, der, b, P: dict) -> None:
        """Its table and fields, before the frames: a body may hang from its marker."""
        strain = STRAIN_MODELS[b.model.validate().strain]
        names = beam_coordinates(b)
        keys, modes = _beam_modes(b)
        body = b.model.body
        table = IntegralTable(modes) if body is None else BodyIntegralTable(body, modes)
        sym, symd, symdd = ({n: sp.Symbol(f"{b.name}_{n}{k}", real=True) for n, _, _ in names}
                            for k in ("", "_d", "_dd"))
        F = _fields(b, sym, symd, symdd, table, strain.foreshortening, keys)
        # prestress: the fields with the foreshortening, its inertia's on a spun frame (contribute)
        short = _fields(b, sym, symd, symdd, table, True, keys) if strain.name == "prestress" else None
        der.spatial[b.name] = dict(F=F, table=table, modes=modes, keys=keys, P=P, short=short,
                                   sym=sym, symd=symd, r=sp.Matrix([P["L"] * s + F["u"], F["v"], F["vz"]]))

    def hang(self, der, fr: Frame, body: str, m):
        return _section_frame(der, fr, body, m.x), sp.zeros(3, 1)

    def contribute(self, der, b, P, fr, motion, gvec) -> None:
        om, vf, actual = motion.om, motion.vf, motion.actual
        q, qd, coords = der.q, der.qd, der.coords
        strain = STRAIN_MODELS[b.model.strain]
        F, table, modes, r = (der.spatial[b.name][k] for k in ("F", "table", "modes", "r"))
        L, rho, A = P["L"], P["rho"], P["A"]
        w = table.weight
        rd = sp.Matrix([F["u_d"], F["v_d"], F["vz_d"]])
        vel = vf + rd + cross(om, r)  # in the placeholders: short expansions, short integrals
        spin = F["phi_d"] + om[0] + (om[1] * F["v_s"] + om[2] * F["vz_s"]) / L

        def integral(density, a=0, b_=1, closed=None, table=table, P=P):
            generic = {gp.symbol: P[gp.name] for gp in BEAM_PARAMS}
            return table.integrate_values(density, a, b_, closed).xreplace(generic)

        der.frame_T.append((integral(rho * A * L / 2 * w("mu") * vel.dot(vel)
                                     + rho * (P["Iy"] + P["I"]) * L / 2 * w("ip") * spin**2), actual))
        der.V_grav += (-integral(rho * A * L * w("mu")) * gvec.dot(fr.R)
                       - integral(rho * A * L * w("mu") * fr.g.dot(r)))
        spun = planar.prestress_in_T(der.system, b)
        for term_name, wrt in strain.terms + (("torsion", ("torsion",)),):
            if term_name == "prestress":
                # in T when the joints spin the frame (planar.prestress_in_T): as a potential
                # read at the current spin, the joint's equation missed d/dt dV_p/dq' (a tilted
                # hinge's T + V drifted 47 %). The root's acceleration and gravity: in T and V
                # always, as m3 holds them (a mesh's acceleration load cases as a potential read
                # q'', and a tilted hinge's T + V drifted 1.6e-4 of V's peak).
                turn = om if spun else fr.omega  # the frame's placeholders, or its actual motion
                if b.model.body is None:  # the foreshortening along the beam (planar.root_load_density)
                    Vp = integral(_strain_density(term_name, F, P, turn, w))
                    short, k, zero = der.spatial[b.name]["short"], rho * A * L * w("mu"), sp.zeros(3, 1)
                    S, S_d = (sp.Matrix([integral(k * (short[c] - F[c])), 0, 0]) for c in ("u", "u_d"))
                    Ta, Va = planar.root_load_energy(S, S_d, zero, zero, om, vf, fr.g)
                else:  # the unit inertial load cases (fedata)
                    Ta, Va, Vp = _load_case_energy(der, b, turn, om, vf)
                if Ta.xreplace(actual) != 0 or Va != 0:  # (a root on a fixed axis without gravity: none)
                    der.frame_T.append((Ta, actual))
                    der.V_grav += Va
                    der.terms.append((b.name, planar.ROOT_LOAD_TERM, wrt, Ta.xreplace(actual) - Va,
                                      sp.zeros(len(q), 1)))
                if spun:
                    der.frame_T.append((-Vp, actual))
                    der.terms.append((b.name, term_name + " (centrifugal, in T: the joints' spin)", wrt,
                                      Vp.xreplace(actual), sp.zeros(len(q), 1)))
                    continue
                Vt = Vp
            else:
                Vt = integral(_strain_density(term_name, F, P, fr.omega, w))
            Qk = generalized_force(Vt, q, [c.body == b.name and c.group in wrt for c in coords])
            der.terms.append((b.name, term_name, wrt, Vt, Qk))
            der.V += Vt
            der.Q += Qk
        keys, energies = der.spatial[b.name]["keys"], None
        if b.damped:  # D in the elastic rates (body_kinds.modal.damping_dissipation), Q -= dD/dq'
            energies = _rate_energies(b, P, table, integral, keys)
            der.dissipation[b.name] = damping_dissipation(b.damping, *energies)
            der.Q -= sp.Matrix([sp.diff(der.dissipation[b.name], x) for x in qd])
        if spun:
            # -V_p in T is m3's T to second order in the deflection: the sections, momentum and
            # reactions take the foreshortening's inertia as m3's do (as in the plane,
            # FlexPart.inertial_fields), so they balance the motion T gives
            short = der.spatial[b.name]["short"]
            ri = sp.Matrix([L * s + short["u"], short["v"], short["vz"]])
            inertial = (short, ri, vf + sp.Matrix([short["u_d"], short["v_d"], short["vz_d"]]) + cross(om, ri))
        else:
            inertial = (F, r, vel)
        der.spatial[b.name] = dict(F=F, table=table, modes=modes, P=P, r=r, vel=vel, spin=spin,
                                   inertial=inertial,
                                   integral=integral, om=om, vf=vf, actual=actual, keys=keys,
                                   energies=energies)

    def damping_load(self, der, b) -> tuple[sp.Matrix, sp.Matrix] | None:
        """The alpha and zeta dampers' load (_damping_field) over the beam: its force and its
        moment about the ground origin, ground components (a tree joint's momentum balance)."""
        d = der.spatial[b.name]
        W = _damping(der, b)
        if W is None:
            return None
        P, F, integral = d["P"], d["F"], d["integral"]
        L = P["L"]
        f = -P["rho"] * P["A"] * L * d["table"].weight("mu") * sp.Matrix([W["u"], W["v"], W["vz"]])
        tangent = sp.Matrix([1, F["v_s"] / L, F["vz_s"] / L])
        torque = -P["rho"] * (P["Iy"] + P["I"]) * L * d["table"].weight("ip") * W["phi"] * tangent
        moment = cross(d["inertial"][1], f) + torque
        fr = der.spatial["frames"][b.name]
        force = fr.A * sp.Matrix([integral(c) for c in f])
        return force, cross(fr.R, force) + fr.A * sp.Matrix([integral(c) for c in moment])

    def axis_point(self, der, body: str, x: float) -> sp.Matrix:
        return _at(der, body, x, "r")

    def section_rotation(self, der, body: str, m) -> sp.Matrix:
        """The frame turned by the section's rotation S = R_z R_y R_x of theta = (phi, -vz_x,
        v_x), as a hung body's (_section_frame)."""
        Rx, Ry, Rz = _section_turns(_section_angles(der, body, m.x))
        return der.spatial["frames"][body].A * Rz * Ry * Rx

    def momentum(self, der, b, fr) -> sp.Matrix:
        """A [int rho A (A^T R + r) x v dx + int rho (I_y + I_z) spin t dx] (the momentum
        conjugate to this T's rotation)."""
        d = der.spatial[b.name]
        P, F = d["P"], d["F"]
        L = P["L"]
        tangent = sp.Matrix([1, F["v_s"] / L, F["vz_s"] / L])
        Rl = sp.Matrix(sp.symbols(f"{b.name}_R_x {b.name}_R_y {b.name}_R_z", real=True))
        w = d["table"].weight
        _, r, vel = d["inertial"]
        dens = P["rho"] * P["A"] * L * w("mu") * cross(Rl + r, vel) \
            + P["rho"] * (P["Iy"] + P["I"]) * L * w("ip") * d["spin"] * tangent
        now = d["actual"] | dict(zip(Rl, fr.A.T * fr.R))  # substituted after integrating
        return fr.A * sp.Matrix([d["integral"](e).xreplace(now) for e in dens])

    def first_moment(self, der, b, fr):
        """m R + A int rho A r dx."""
        d = der.spatial[b.name]
        mu = d["P"]["rho"] * d["P"]["A"] * d["P"]["L"] * d["table"].weight("mu")
        m = d["integral"](mu)
        return m, m * fr.R + fr.A * sp.Matrix([d["integral"](mu * e) for e in d["inertial"][1]])

    def displacement(self, der, beam, x: float, fn: str) -> sp.Expr:
        return _at(der, beam.name, x, fn)

    def section(self, der, beam, x: float, fn: str, loads_beyond, side: int = 0) -> sp.Expr:
        """N (along the frame's x, as in the plane), Qy, Qz, Mx, My, Mz at station x in the
        deformed section's axes, constitutive or from equilibrium (Q: always from equilibrium,
        the Euler-Bernoulli beam has no shear strain). The equilibrium force S and moment M,
        found in the frame's components, are turned by the section's rotation theta = (phi,
        -vz_x, v_x) to first order, X_section = X - theta x X, the order of the modal
        kinematics; N stays S_x (the planar N; the turn would add v_x S_y + vz_x S_z, slope
        times shear). loads_beyond(der, beam, x, fn, out, section, side): out plus the loads on
        the part beyond x (physics/spatial.py). side: the station's (system.station_side)."""
        if fn[0] == "Q" or (fn != "N" and beam.model.moment == "equilibrium"):
            X = sp.Matrix([_frame_section(der, beam, x, ("S" if fn[0] == "Q" else "M") + k, loads_beyond, side)
                           for k in "xyz"])
            return (X - cross(_section_angles(der, beam.name, x), X))["xyz".index(fn[1])]
        return _frame_section(der, beam, x, fn, loads_beyond, side)


KIND = Modal()


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
            acc = der.ddt(fr.V) + cross(om, fr.V) - fr.g if acc is None else acc
            out[case] = acc[k[0]]
    return out


def _load_case_energy(der, b: FlexibleBeam, spin: sp.Matrix, om: sp.Matrix, vf: sp.Matrix):
    """The prestress of a body from finite-element data, from its unit load cases: each case c
    gives the quadratic form E_c = 1/2 rho A L^(m_c - 1) q^T D_c q on each bending plane's
    coordinates, D_c the geometric stiffness of the unit load case projected on the plane's
    modes (fedata.load_case_stiffness). The centrifugal cases omega_i omega_j: V_w = sum
    spin_i spin_j E_c (spin: the frame's placeholders om, or its actual rate). The acceleration
    cases a_i and alpha_i: S_i = E_(a_i), R_i = E_(alpha_i) in planar.root_load_energy, whose
    Lagrange equations are the load (a - g).dS/dq + alpha.dR/dq of the frame's actual
    acceleration, angular acceleration and gravity, whatever they are. Returns (T_a, V_a, V_w)."""
    d = der.spatial[b.name]
    P, sym, symd, keys, modes = d["P"], d["sym"], d["symd"], d["keys"], d["modes"]
    g = der.spatial["frames"][b.name].g
    forms, Vw = {}, sp.Integer(0)
    for plane in ("v", "vz"):
        names = [n for n, grp, _ in beam_coordinates(b) if grp == "bending" and n.split("_")[0] == plane]
        qv = sp.Matrix([sym[n] for n in names])
        for case, Dc in load_case_stiffness(b.model.body, [modes[keys[n]].shape for n in names]).items():
            Dm = sp.Matrix(Dc.shape[0], Dc.shape[1], [sp.Float(repr(float(v)), 17) for v in Dc.ravel()])
            E = P["rho"] * P["A"] * P["L"]**(load_case_scale(case) - 1) * (qv.T * Dm * qv)[0, 0] / 2
            if case.startswith("ww"):
                Vw += spin["xyz".index(case[3])] * spin["xyz".index(case[4])] * E
            else:
                forms[case] = forms.get(case, 0) + E

    def rate(e):
        return sum(sp.diff(e, sym[n]) * symd[n] for n in sym)
    S = sp.Matrix([forms.get(f"a_{c}", 0) for c in "xyz"])
    R = sp.Matrix([forms.get(f"al_{c}", 0) for c in "xyz"])
    Ta, Va = planar.root_load_energy(S, S.applyfunc(rate), R, R.applyfunc(rate), om, vf, g)
    return sp.expand(Ta), sp.expand(Va), sp.expand(Vw)


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


def _rate_energies(b: FlexibleBeam, P: dict, table: IntegralTable, integral, keys: dict):
    """(K2, M2, rates): the strain-rate energy (axial, both bending planes, torsion) and the
    relative kinetic energy (translation and the section's spin, as T holds them) of the
    undeformed beam's elastic rates, the quadratic forms a damped beam's D is written in."""
    rate = {n: sp.Symbol(f"{b.name}_{n}_d", real=True) for n, _, _ in beam_coordinates(b)}
    R = _fields(b, rate, rate, rate, table, False, keys)  # fields linear in the rates
    w = table.weight
    K2 = integral(sum(_strain_density(t, R, P, None, w) for t in ("axial", "bending", "torsion")))
    M2 = integral(P["rho"] * P["A"] * P["L"] / 2 * w("mu") * (R["u"]**2 + R["v"]**2 + R["vz"]**2)
                  + P["rho"] * (P["Iy"] + P["I"]) * P["L"] / 2 * w("ip") * R["phi"]**2)
    return K2, M2, list(rate.values())


def _damping(der, b: FlexibleBeam):
    """_damping_field of a damped beam, made when an output first reads it, once per derivation
    (None: undamped, or damped by beta alone)."""
    d = der.spatial[b.name]
    if d["energies"] is None:
        return None
    return der.once(("damping_field", b.name),
                    lambda: _damping_field(b, d["energies"], d["table"], d["keys"]))


def _damping_field(b: FlexibleBeam, energies: tuple, table: IntegralTable, keys: dict):
    """The planar _damping_field in 3D (body_kinds/modal.py): w = M^-1 dD/dq' of the alpha and
    zeta dampers, M the modal mass of the rate fields (translation and the section's spin;
    energies: _rate_energies), and the fields u, v, vz, phi of w: the load
    -rho A (u_w, v_w, vz_w) and the torque -rho (I_y + I_z) phi_w about the axis do the
    dampers' virtual work. None without them."""
    d = b.damping
    names = [n for n, _, _ in beam_coordinates(b)]
    if not (d.alpha or any(d.zetas(len(names)))):
        return None
    K2, M2, rates = energies
    D = damping_dissipation(replace(d, beta=0.0), K2, M2, rates)
    w = sp.hessian(M2, rates).LUsolve(sp.Matrix([sp.diff(D, r) for r in rates]))
    wd = dict(zip(names, w))
    return _fields(b, wd, wd, wd, table, False, keys)


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
                 S.T * (fb.V + cross(fb.omega, r) + der.ddt(r)), S.T * fb.g)


def _section_turns(th: sp.Matrix) -> tuple[sp.Matrix, sp.Matrix, sp.Matrix]:
    """(R_x, R_y, R_z) of a section's angles theta: its axes are the beam frame's turned by
    S = R_z R_y R_x, a rotation (orthonormal, unlike I + [theta]x), equal to it to first order."""
    return tuple(rotation(axis, angle) for axis, angle in zip(((1, 0, 0), (0, 1, 0), (0, 0, 1)), th))


def _section_angles(der, beam: str, x: float) -> sp.Matrix:
    """theta = (phi, -vz_x, v_x): a modal beam section's rotation at station x from its frame
    (torsion, then the slopes of the two bending planes), first order as the modal kinematics."""
    L = der.spatial[beam]["P"]["L"]
    return sp.Matrix([_at(der, beam, x, "phi"), -_at(der, beam, x, "vz_s") / L, _at(der, beam, x, "v_s") / L])


def _at(der, body: str, x: float, what: str, side: int = 0):
    """A field of a beam at station x (the table's values substituted; side: field_at's)."""
    d = der.spatial[body]
    beam = der.system.body(body)
    at = exact(x) / exact(beam.length)
    view = _View(d["table"], d["modes"])
    generic = {gp.symbol: d["P"][gp.name] for gp in BEAM_PARAMS}

    def fa(e):  # field_at leaves s (in L s) alone: the station is s = at
        e = field_at(view, e, at, side).xreplace({s: at})
        return e.xreplace(d["table"].substitutions()).xreplace(generic)
    if what in ("r", "inertial r"):  # the axis point; or the fields' the inertia reads (contribute)
        return sp.Matrix([fa(e) for e in (d["r"] if what == "r" else d["inertial"][1])])
    return fa(d["F"][what])


@dataclass
class _View:
    table: IntegralTable
    modes: dict


def _frame_section(der, beam: FlexibleBeam, x: float, fn: str, loads_beyond, side: int = 0) -> sp.Expr:
    """N, Mx, My, Mz at station x: constitutive, or from equilibrium in the frame's components;
    Sx, Sy, Sz: the force of the part beyond x, from equilibrium (N from equilibrium is Sx).
    Each once per derivation: the turned moments, Q and sigma at one station share them (the
    integrals take seconds each)."""
    if fn == "N" and beam.model.axial_force == "equilibrium":
        fn = "Sx"
    # an output may name its own recovery (system.output_beam): the key holds the one asked for
    source = "equilibrium" if fn[0] == "S" else beam.model.axial_force if fn == "N" else beam.model.moment
    memo = der.spatial[beam.name].setdefault("sections", {})
    key = (x, fn, source, side)
    if key not in memo:
        memo[key] = _frame_section_of(der, beam, x, fn, source, loads_beyond, side)
    return memo[key]


def _frame_section_of(der, beam: FlexibleBeam, x: float, fn: str, source: str, loads_beyond,
                      side: int) -> sp.Expr:
    d = der.spatial[beam.name]
    P = d["P"]
    if source != "equilibrium":
        L = P["L"]
        at = exact(x) / exact(beam.length)
        body = beam.model.body
        node = body is not None and 0 < x < beam.length and body.node_index(x * body.length / beam.length) is not None

        sides = ((side,) if side else (-1, 1)) if node else (0,)

        def own(kind, what):  # stiffness x strain: at a node its side's element's, or the mean of both
            return sum(d["table"].weight_at(kind, at, k) * _at(der, beam.name, x, what, k)
                       for k in sides) / len(sides)
        if fn == "N":
            if beam.model.strain == "prestress":
                fr = der.spatial["frames"][beam.name]
                if beam.model.body is not None:  # the unit load cases' axial forces there
                    return _load_case_axial_force(der, beam, fr, x)
                om, a0x = fr.omega, _load_case_factors(der, fr, ["a_x"])["a_x"]  # a_0x - g_x
                return P["rho"] * P["A"] * L * ((om[1]**2 + om[2]**2) * L * (1 - at**2) / 2 - (1 - at) * a0x)
            if not beam.model.axial:
                raise SpecError(f"system '{der.system.name}': body '{beam.name}': strain model "
                                f"'{beam.model.strain}' has no axial coordinate to carry N")
            return P["E"] * P["A"] * own("ea", "u_stretch_s") / L
        kind, what, scale = {"Mx": ("gj", "phi_s", P["G"] * P["J"] / L),
                             "My": ("eiy", "vz_ss", -P["E"] * P["Iy"] / L**2),
                             "Mz": ("ei", "v_ss", P["E"] * P["I"] / L**2)}[fn]
        return scale * own(kind, what)
    # equilibrium of the part beyond x: S = int (g - a) rho A dx + loads on its markers,
    # M = int (r - r_x) x rho A (g - a) dx - d/dt int rho (I_y + I_z) spin t dx + load moments
    # the acceleration in the frame's components, a = a_0 + alpha x r + omega x (omega x r)
    # + 2 omega x r' + r'', integrated in placeholders and then given the frame's actual motion
    fr = der.spatial["frames"][beam.name]
    at = exact(x) / exact(beam.length)
    om, (F, r, _) = d["om"], d["inertial"]
    al = sp.Matrix(sp.symbols(f"{beam.name}_Al_x {beam.name}_Al_y {beam.name}_Al_z", real=True))
    a0 = sp.Matrix(sp.symbols(f"{beam.name}_A0_x {beam.name}_A0_y {beam.name}_A0_z", real=True))
    gl = sp.Matrix(sp.symbols(f"{beam.name}_g_x {beam.name}_g_y {beam.name}_g_z", real=True))
    rd = sp.Matrix([F["u_d"], F["v_d"], F["vz_d"]])
    rdd = sp.Matrix([F["u_dd"], F["v_dd"], F["vz_dd"]])
    W = _damping(der, beam)  # the alpha and zeta dampers' load, as an acceleration field (and spin)
    if W is not None:
        rdd += sp.Matrix([W["u"], W["v"], W["vz"]])
    acc = a0 + cross(al, r) + cross(om, cross(om, r)) + 2 * cross(om, rd) + rdd
    L, rho, A = P["L"], P["rho"], P["A"]
    w = d["table"].weight
    load = rho * A * L * w("mu") * (gl - acc)
    force, k = fn[0] == "S", "xyz".index(fn[1])
    section = _at(der, beam.name, x, "inertial r")  # the moments' point, of the fields r is
    closed = loads_at(beam, x, side)  # a point mass at x on the part beyond
    if force:
        out = d["integral"](load[k], at, 1, closed)
    else:
        # int (r - r_x) x load = int r x load - r_x x int load (r_x is the station's, constant
        # along the part): the densities are the same at every station, so each is expanded
        # once (IntegralTable._terms) for all the stations an output list asks for
        mom = cross(r, load)
        # minus the rate of the sections' spin momentum beyond x, h = rho (I_y + I_z) spin t
        # along the tangent t (as T's rotary term and _momentum hold it): its rate in the frame
        # plus omega x h (the gyroscopic part, in all three components)
        spin_rate = F["phi_dd"] + al[0] + (al[1] * F["v_s"] + om[1] * F["v_d_s"]
                                           + al[2] * F["vz_s"] + om[2] * F["vz_d_s"]) / L
        if W is not None:
            spin_rate += W["phi"]
        tangent = sp.Matrix([1, F["v_s"] / L, F["vz_s"] / L])
        h_rate = (spin_rate * tangent + d["spin"] * sp.Matrix([0, F["v_d_s"] / L, F["vz_d_s"] / L])
                  + cross(om, d["spin"] * tangent))
        out = d["integral"](mom[k] - rho * (P["Iy"] + P["I"]) * L * w("ip") * h_rate[k], at, 1, closed) \
            - cross(section, sp.Matrix([d["integral"](load[j], at, 1, closed) for j in range(3)]))[k]
    omega = fr.omega
    now = (d["actual"] | dict(zip(al, der.ddt(omega))) | dict(zip(gl, fr.g))
           | dict(zip(a0, der.ddt(fr.V) + cross(omega, fr.V))))
    out = out.xreplace(now)
    return loads_beyond(der, beam, x, fn, out, section, side)
