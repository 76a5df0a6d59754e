"""A modal beam: its elastic coordinates are the amplitudes of its modes; T, gravity and
momentum are densities (physics/energy.py) integrated over the beam by its integral table,
in frame components with the frame's actual motion; its strain terms and their `wrt` groups
are the strain model's. A uniform beam and a beam from finite-element data are one kind: the
data only change the table (IntegralTable or BodyIntegralTable, with rho A (x) and point
masses in its weights).

Structural damping: D = beta/2 int (EA u_x'^2 + EI v_xx'^2) dx + alpha/2 q'^T M_ee q'
+ sum_i c_i q_i'^2/2, c_i = 2 zeta_i sqrt(K_ii M_ii) (physics/assemble.py's module doc).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from types import SimpleNamespace

import sympy as sp

from flexsym.core.errors import SpecError
from flexsym.model.exact_numbers import exact
from flexsym.model.strain_models import STRAIN_MODELS
from flexsym.model.modes import s
from flexsym.model.system import FlexibleBeam
from flexsym.physics.body_kinds.base import (BeamKind, exact_number, frame_acceleration, record_body,
                                             station)
from flexsym.physics.energy import (BEAM_PARAMS, ENERGY_TERMS, FrameMotion, A, L, build_fields,
                                    gravity_density, kinetic_density, momentum_density, rho, w)
from flexsym.physics.integrals import BodyIntegralTable, IntegralTable
from flexsym.physics.lagrange import generalized_force
from flexsym.physics.outputs import field_at, output_expression
from flexsym.physics.validity import modal_gauges


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
    shortened: object = None  # prestress: the fields with the foreshortening (inertial_stress)

    def inertial_fields(self, system):
        """The fields whose inertia the sections, the momentum and the reactions read. Prestress
        on a frame that the joints spin takes the foreshortening's: its -V_p in T (Modal.contribute)
        is m3's T to second order in the deflection, so its sections balance the motion T gives
        (S1's root moment then equals the clamp's reaction, as m3's does)."""
        return self.shortened if prestress_in_T(system, self.beam) else self.fields

    def view(self):
        """What outputs.field_at / output_expression read (a derivation-like object)."""
        return SimpleNamespace(spec=self.beam.model, table=self.table, modes=self.modes,
                               fields=self.fields)


def prestress_in_T(system, beam) -> bool:
    """Whether a beam's prestress V_p is written into T as -V_p (the centrifugal part of m3's T
    that is linear in the foreshortening), planar and spatial: when the joints' rates spin its
    frame, so that Lagrange's equations take V_p's dependence on them; under a guided drive
    alone it stays a potential that varies in time."""
    return beam.model.strain == "prestress" and not system.frame_driven(beam.name)


ROOT_LOAD_TERM = "prestress (the root's acceleration and gravity along the beam, in T and V)"


def root_load_energy(S, S_dot, R, R_dot, omega, V, g) -> tuple[sp.Expr, sp.Expr]:
    """(T_a, V_a): the parts of m3's T and V_g linear in the second-order displacement field
    du (the foreshortening -1/2 int_0^x v_x^2 along the beam, or a mesh's), besides the
    centrifugal -V_p, in the frame's components (3-vectors: omega its rate, V its origin's
    velocity, g gravity), from S = int rho A du and R = int rho A r x du and their rates:
    T_a = V.(S' + omega x S) + omega.R', V_a = -g.S. Lagrange's equations make them the load
    (a_0 - g).dS/dq + alpha.dR/dq of the origin's acceleration, the angular acceleration and
    gravity: on a straight beam the stiffening of the axial load rho A (a_0x - g_x)(L - x),
    which the centrifugal N-hat alone leaves out (a blade clamped 0.5 m off a link's axis was
    0.37 of w_mid's peak off m3; S3's pendulum 0.34 off ef, where m3 is 0.11). Written into T
    and V as m3 holds them, T + V stays conserved and no force reads q''. Zero for a root on
    the axis of a frame turning about a fixed point, without gravity along the beam."""
    return V.dot(S_dot + omega.cross(S)) + omega.dot(R_dot), -g.dot(S)


def root_load_density(part: FlexPart, ph) -> tuple[sp.Expr, sp.Expr]:
    """root_load_energy per unit s of a planar beam (ph: the frame's placeholders, LocalMotion):
    S = rho A L mu du along the frame's x axis, R = 0 (r x du e_x = 0 on the axis)."""
    f, sh = part.fields, part.shortened
    k = rho * A * L * f.weights["mu"]
    along = lambda e: sp.Matrix([k * e, 0, 0])  # noqa: E731
    zero = sp.zeros(3, 1)
    return root_load_energy(along(sh.u - f.u), along(sh.u_dot - f.u_dot), zero, zero,
                            sp.Matrix([0, 0, ph[0]]), sp.Matrix([ph[1], ph[2], 0]), sp.Matrix([ph[5], ph[6], 0]))


def _beyond_root(ref, beam: str) -> bool:
    return isinstance(ref, str) and ref.partition(".")[0] == beam and ref.partition(".")[2] != "root"


def loaded_beyond_root(system, beam: str) -> str:
    """The first force or spring acting on the beam anywhere but at its root ('' if none)."""
    for load in system.loads:
        if any(_beyond_root(getattr(load, k, ""), beam) for k in ("marker", "a", "b")):
            return f"load '{load.name or type(load).__name__}'"
    return ""


def _held_beyond_root(system, beam: str) -> str:
    """The first joint, force or spring acting on the beam anywhere but at its root ('' if none)."""
    for j in system.joints:
        if _beyond_root(j.parent, beam) or _beyond_root(j.child, beam):
            return f"joint '{j.name}'"
    return loaded_beyond_root(system, beam)


def field_reader(part: FlexPart, x: float):
    """e -> the field expression e at station x, in the body's coordinate and parameter symbols."""
    at = exact(x) / exact(part.beam.length)
    view = part.view()

    def fa(e):
        return field_at(view, e, at).xreplace(part.table.substitutions()).xreplace(part.psyms)
    return fa


class Modal(BeamKind):
    name = "modal"

    def applies(self, body) -> bool:
        return body.flexible and body.model.kind == "modal" and not body.model.exact_kinematics

    def coordinates(self, b) -> list[tuple[str, str]]:
        return [(f"{b.name}_{r.coordinate}", r.axis) for r in b.model.modes]

    def gauges(self, b, length: float) -> list:
        def columns(refs):
            return [(f"{b.name}_{r.coordinate}", b.model.mode(r)) for r in refs]
        return modal_gauges(b, length, columns(b.model.axial), [columns(b.model.bending)])

    def check(self, system, tree, b) -> None:
        if b.model.strain == "prestress":
            held = _held_beyond_root(system, b.name)
            if held:
                raise SpecError(f"system '{system.name}': body '{b.name}': the prestress model's axial "
                                f"force is the beam's own centrifugal load, which holds for a beam free "
                                f"beyond its root; {held} loads it axially: use m2 or m3 (N from "
                                "equilibrium), or ef")
        super().check(system, tree, b)

    @staticmethod
    def part_args(b, psyms: dict) -> tuple:
        """FlexPart's arguments: the body, its table, its fields in its own coordinate symbols,
        its modes, their groups and names, its parameters' symbols."""
        spec = b.model.validate()
        modes = {r.coordinate: spec.mode(r) for r in spec.modes}
        names = list(modes)
        sym = {n: sp.Symbol(f"{b.name}_{n}", real=True) for n in names}
        symd = {n: sp.Symbol(f"{b.name}_{n}_d", real=True) for n in names}
        symdd = {n: sp.Symbol(f"{b.name}_{n}_dd", real=True) for n in names}
        table = IntegralTable(modes) if spec.body is None else BodyIntegralTable(spec.body, modes)
        strain = STRAIN_MODELS[spec.strain]
        def fields(foreshortening):
            return build_fields([modes[r.coordinate] for r in spec.axial],
                                [modes[r.coordinate] for r in spec.bending], sym, symd, table,
                                foreshortening, symdd)
        return (b, table, fields(strain.foreshortening), modes, {r.coordinate: r.axis for r in spec.modes},
                names, psyms, fields(True) if spec.strain == "prestress" else None)

    def part(self, b, psyms: dict, qnames: list[str]):
        return FlexPart(*self.part_args(b, psyms))

    def contribute(self, der, b, frame, integral_symbols: bool) -> None:
        """Its inertia (`inertia`: what the exact kind replaces), then its strain terms, each
        differentiated with respect to its `wrt` groups only, and its damping."""
        part = der.flex[b.name]
        loc = frame.local()
        ph, actual = loc.ph, loc.actual
        mass = BEAM_PARAMS[0].symbol * BEAM_PARAMS[2].symbol * BEAM_PARAMS[4].symbol
        tab, fl = part.table, part.fields

        def body_expr(expr):  # the table's integrals (or their symbols), this body's symbols
            values = {} if integral_symbols else tab.substitutions()
            return expr.xreplace(values).xreplace(part.psyms).xreplace(actual)

        mass = mass * tab.integrate(fl.weights["mu"])  # 1 for a uniform beam; a body's own
        self.inertia(der, b, part, frame, loc, body_expr, mass)
        strain = STRAIN_MODELS[b.model.strain]
        for term_name, wrt in strain.terms:
            term = ENERGY_TERMS[term_name]
            V = body_expr(tab.integrate(term.density(fl)).xreplace({w: ph[0]}))
            if term_name == "prestress":
                Ta, Va = (body_expr(tab.integrate(e)) for e in root_load_density(part, ph))
                der.T += Ta
                der.V_grav += Va
                if Ta != 0 or Va != 0:  # (a root on a fixed axis without gravity: none)
                    der.terms.append((b.name, ROOT_LOAD_TERM, wrt, Ta - Va, sp.zeros(len(der.q), 1)))
                if prestress_in_T(der.system, b):
                    # as a potential read at the current spin, S3's T + V drifted 1.4e-6 of V's peak
                    der.T -= V
                    der.terms.append((b.name, term_name + " (centrifugal, in T: the joints' spin)", wrt, V,
                                      sp.zeros(len(der.q), 1)))
                    continue
            Qk = generalized_force(V, der.q, [c.body == b.name and c.group in wrt for c in der.coords])
            der.terms.append((b.name, term_name, wrt, V, Qk))
            der.V += V
            der.Q += Qk
        if b.damped:
            der.dissipation[b.name] = _modal_dissipation(b, part, body_expr)

    def inertia(self, der, b, part, frame, loc, body_expr, mass) -> None:
        """T, V_g and the momentum: the densities integrated by the table."""
        ph = loc.ph
        tab, fl = part.table, part.fields
        motion = FrameMotion(ph[0], ph[1], ph[2])
        der.T += body_expr(tab.integrate(kinetic_density(fl, motion)))
        der.V_grav += body_expr(tab.integrate(gravity_density(fl, ph[5], ph[6]))) \
            - body_expr(mass) * frame.g.dot(frame.pose.R)
        fi = part.inertial_fields(der.system)
        H_ = body_expr(tab.integrate(momentum_density(fi, motion, ph[3], ph[4])))
        der.momentum += H_
        Ig = tab.integrate(gravity_density(fi, ph[5], ph[6]))  # linear in g: -g.(first moment)
        record_body(der, b.name, body_expr(mass), frame.pose, frame.A,
                    [body_expr(-sp.diff(Ig, gk)) for gk in ph[5:]], H_)

    def fields_at(self, der, body: str, x: float):
        part = der.flex[body]
        fa = field_reader(part, x)
        L_ = part.psyms[BEAM_PARAMS[4].symbol]
        return fa(part.fields.u), fa(part.fields.v), fa(part.fields.v_s) / L_

    def from_equilibrium(self, beam, fn: str) -> bool:
        return (beam.model.axial_force if fn == "N" else beam.model.moment) == "equilibrium"

    def own_stress(self, der, beam, x: float, fn: str, where: str, side: int = 0) -> sp.Expr:
        """N = EA eps (or the prestress model's), M = EI v'' (outputs.output_expression; at a
        node of a body from finite-element data, the element on the station's side, or the
        mean of both)."""
        part = der.flex[beam.name]
        frac = exact(x) / exact(beam.length)
        label = "o" + {-1: "_left", 0: "", 1: "_right"}[side]
        spec = replace(beam.model, points=((label, str(frac)),))
        if fn == "N" and not spec.axial and spec.strain != "prestress":
            raise SpecError(f"{where}: strain model '{spec.strain}' has no axial coordinate to carry "
                            "an axial force")
        view = SimpleNamespace(spec=spec, table=part.table, modes=part.modes, fields=part.fields)
        expr = output_expression(view, f"{fn}_{label}")
        _, (omega, _, a0x, _, gx, _) = frame_acceleration(der, beam.name)
        if fn == "N" and spec.strain == "prestress":  # the root's acceleration and gravity (root_load_density)
            expr -= rho * A * L * part.table.integrate(part.fields.weights["mu"], frac, 1) * (a0x - gx)
        return expr.xreplace(part.table.substitutions()).xreplace(part.psyms).xreplace({w: omega})

    def inertial_stress(self, der, beam, x: float, fn: str, closed: bool = False):
        """The inertial loads -rho A (a - g) beyond x (a in frame components: A^T R'' + the
        relative, Coriolis, angular and centripetal terms, as outputs._equilibrium_* for a
        guided hub) integrated by the table, a point mass at x with them if closed
        (system.loads_at); N along the frame's x axis."""
        part = der.flex[beam.name]
        rho_, A_, L_ = (BEAM_PARAMS[k].symbol for k in (0, 2, 4))
        f, tab = part.inertial_fields(der.system), part.table
        om, al, a0x, a0y, gx, gy = sp.symbols("Om_ Al_ A0x_ A0y_ gx_ gy_", real=True)
        at = exact(x) / exact(beam.length)
        X = L_ * s + f.u
        ax = a0x - gx + f.u_ddot - 2 * om * f.v_dot - al * f.v - om**2 * X
        ay = a0y - gy + f.v_ddot + 2 * om * f.u_dot + al * X - om**2 * f.v
        damp = _damping_field(der, beam)
        if damp is not None:  # the dampers' load -rho A (u_w, v_w) on the part beyond x
            ax, ay = ax + damp[0], ay + damp[1]
        view = part.view()
        if fn == "N":
            out = -rho_ * A_ * L_ * tab.integrate(f.weights["mu"] * ax, at, 1, closed)
        else:
            dx = X - L_ * at - field_at(view, f.u, at)
            dy = f.v - field_at(view, f.v, at)
            out = -rho_ * A_ * L_ * tab.integrate(f.weights["mu"] * (dx * ay - dy * ax), at, 1, closed)
            if f.weights["rot"] != 0:
                out -= rho_ * A_ * L_**3 * tab.integrate(f.weights["rot"] * (al + f.v_ddot_s / L_), at, 1, closed)
        Arot, motion = frame_acceleration(der, beam.name)
        actual = dict(zip((om, al, a0x, a0y, gx, gy), motion))
        out = out.xreplace(tab.substitutions()).xreplace(part.psyms).xreplace(actual)
        u, v, _ = self.fields_at(der, beam.name, x)
        section = der.poses[beam.name].R + Arot * sp.Matrix([station(der, beam.name, x) + u, v])
        return out, section, sp.Matrix([1, 0])

    def damping_load(self, der, b):
        """-rho A (u_w, v_w) of _damping_field over the beam, and its moment about the frame's
        origin (at the deformed points)."""
        part = der.flex[b.name]
        damp = _damping_field(der, b)
        if damp is None:
            return None
        rho_, A_, L_ = (BEAM_PARAMS[k].symbol for k in (0, 2, 4))
        f, tab = part.fields, part.table
        X = L_ * s + f.u
        F = [-rho_ * A_ * L_ * tab.integrate(f.weights["mu"] * c) for c in damp]
        M = -rho_ * A_ * L_ * tab.integrate(f.weights["mu"] * (X * damp[1] - f.v * damp[0]))
        values = tab.substitutions()
        return (sp.Matrix(F).xreplace(values).xreplace(part.psyms),
                M.xreplace(values).xreplace(part.psyms))


def _rate_fields(b: FlexibleBeam, part: FlexPart, values: dict):
    """(K2, M2, the rates, the fields of given coordinate values): the strain-rate and
    relative kinetic energies of the undeformed beam's elastic rates (the fields linear in the
    rates: no foreshortening), the quadratic forms its D is written in, and fields(values)
    builds the same linear fields of other values (in the table's symbols)."""
    spec, tab = b.model, part.table
    axial = [part.modes[r.coordinate] for r in spec.axial]
    bending = [part.modes[r.coordinate] for r in spec.bending]
    rate = {n: sp.Symbol(f"{b.name}_{n}_d", real=True) for n in part.coords}
    rf = build_fields(axial, bending, rate, rate, tab, False)
    K2 = tab.integrate(ENERGY_TERMS["axial"].density(rf) + ENERGY_TERMS["bending"].density(rf))
    M2 = tab.integrate(kinetic_density(rf, FrameMotion(sp.Integer(0))))
    fields = lambda v: build_fields(axial, bending, v, v, tab, False)  # noqa: E731
    return K2.xreplace(values), M2.xreplace(values), [rate[n] for n in part.coords], fields


def _damping_field(der, b: FlexibleBeam):
    """(u_w, v_w) such that the load -rho A (u_w, v_w) on the beam does the virtual work of its
    mass-proportional and modal dampers (their generalised force -dD/dq'; beta's strain-rate
    stress is internal, no load): w = M^-1 dD/dq' with M the modal mass of the rate fields
    linear in q' (those D is written in), and the field sum_j w_j phi_j, the one load in the
    modes' span weighted by rho A (for alpha: alpha times the relative velocity). None when
    the beam has neither. In the table's symbols and the global beam parameters; once per
    derivation."""
    d, part = b.damping, der.flex[b.name]
    if not b.damped or not (d.alpha or any(d.zetas(len(part.coords)))):
        return None

    def field():
        K2, M2, rates, fields = _rate_fields(b, part, part.table.substitutions())
        D = damping_dissipation(replace(d, beta=0.0), K2, M2, rates)
        w = sp.hessian(M2, rates).LUsolve(sp.Matrix([sp.diff(D, r) for r in rates]))
        wf = fields(dict(zip(part.coords, w)))
        return wf.u, wf.v
    return der.once(("damping_field", b.name), field)


def _modal_dissipation(b: FlexibleBeam, part: FlexPart, body_expr) -> sp.Expr:
    """D of a damped modal beam (module doc) from its rate energies (_rate_fields)."""
    K2, M2, rates, _ = _rate_fields(b, part, {})
    return damping_dissipation(b.damping, body_expr(K2), body_expr(M2), rates)


def damping_dissipation(d, K2: sp.Expr, M2: sp.Expr, rates: list) -> sp.Expr:
    """D of a damped modal beam in both dimensions (module doc) from its strain-rate and
    relative kinetic energies K2, M2 (the undeformed beam's, quadratic in its elastic rates):
    beta K2 + alpha M2 + a dashpot 2 zeta_i omega_i m_i on each rate."""
    D = exact_number(d.beta) * K2 + exact_number(d.alpha) * M2
    for qd, z in zip(rates, d.zetas(len(rates))):
        if z:
            c = 2 * exact_number(z) * sp.sqrt(sp.diff(K2, qd, 2) * sp.diff(M2, qd, 2))
            D += c * qd**2 / 2
    return sp.expand(D)


KIND = Modal()
