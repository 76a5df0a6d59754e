"""A beam with exact kinematics (strain model `exact`, physics/exact_body.py): a modal beam
whose V is the modal beam's (sympy), while its T, gravity and positions are casadi
quadratures (sysgen reads der.exact_bodies and der.casadi_outputs)."""
from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from flexsym.core.errors import SpecError
from flexsym.model.system import output_beam, parse_output
from flexsym.physics.body_kinds.base import rot, station
from flexsym.physics.body_kinds.modal import FlexPart, Modal, field_reader, loaded_beyond_root
from flexsym.physics.energy import BEAM_PARAMS
from flexsym.physics.exact_body import body_quadrature, inertial_section_load, position_symbols
from flexsym.physics.exact_kinematics import ExactKinematics, Quadrature
from flexsym.physics.validity import truncation_gauge


@dataclass
class ExactPart(FlexPart, ExactKinematics):
    """A beam with exact kinematics: its V is the modal beam's (the FlexPart's fields), its T,
    gravity and positions are casadi quadratures."""

    quad: Quadrature = None
    frame: tuple = ()  # (omega, V_x, V_y, g_x, g_y, R_x, R_y) in frame components, sympy
    index: list = field(default_factory=list)  # its coordinates' places in q, in mode order

    @property
    def fe_body(self):
        return self.beam.model.body


def differentiated(system, tree, beam: str) -> bool:
    """Sympy differentiates the beam's positions: a tree joint hangs a body from it (the
    body's pose, hence its T and V, reads them), or a load acts on it beyond its root (its
    generalised force, or its spring's V). Its placeholders are then functions of its
    coordinates (exact_body.position_symbols); else plain symbols, the derivatives of a cut
    joint's rows (Phi_q, gamma) and of the outputs being casadi's alone."""
    return bool(loaded_beyond_root(system, beam)) or any(
        j.parent.partition(".")[0] == beam and j.name not in tree.cut for j in system.joints)


class Exact(Modal):
    name = "exact"

    def gauges(self, b, length: float) -> list:
        """Its axial strain (modal_gauges keeps no deflection limit: its kinematics is exact)
        and its truncation share."""
        return super().gauges(b, length) + truncation_gauge(b)

    def applies(self, body) -> bool:
        return body.flexible and body.model.kind == "modal" and body.model.exact_kinematics

    def check(self, system, tree, b) -> None:
        """What it is derived for: a planar beam (uniform, or sections and point masses from
        finite-element data; damped as a modal beam, its strain measures being linear in its
        coordinates); bodies may hang from it and loads act on it anywhere (`differentiated`:
        its positions are then functions of its coordinates, differentiated by casadi); no
        output that needs its momentum (momentum, the reaction of a tree joint it lies beyond,
        N or M from equilibrium of a beam it hangs from)."""
        where = f"system '{system.name}': body '{b.name}': the exact kinematics (strain model 'exact')"
        if system.dimension != 2:
            raise SpecError(f"{where} is derived for planar systems only")
        body = b.model.body
        if body is not None and (body.matrices is not None or any(m.rotary for m in body.masses)):
            raise SpecError(f"{where} is derived for a beam from its sections and point masses "
                            "(not from imported matrices, nor with a point mass's rotary inertia)")
        beyond = {j.name for j in system.joints if j.name not in tree.cut
                  and b.name in tree.subtree(system, j.name)}
        for o in system.outputs:
            fn, args = parse_output(system, o.quantity)
            keys = {"M": ("moment",), "N": ("axial_force",), "sigma": ("moment", "axial_force")}.get(fn, ())
            model = output_beam(system, fn, args).model if keys else None  # its recovery, if named
            on_beam = keys and args[0] != b.name and any(
                getattr(model, k, "") == "equilibrium" for k in keys) and any(
                j.parent.partition(".")[0] == args[0] for j in system.joints if j.name in beyond)
            if fn == "momentum" or (fn == "reaction" and args[0] in beyond) or on_beam:
                raise SpecError(f"{where}: output '{o.quantity}' needs its momentum, which is not "
                                "derived yet")
            d = b.damping
            if (keys and args[0] == b.name and b.damped and (d.alpha or any(d.zetas(1)))
                    and any(getattr(model, k) == "equilibrium" for k in keys)):
                raise SpecError(f"{where}: output '{o.quantity}' from equilibrium would leave out "
                                "its damping's alpha / zeta loads (not derived for exact yet): give "
                                "beta, or moment / axial_force = \"constitutive\"")
        super().check(system, tree, b)

    def part(self, b, psyms: dict, qnames: list[str]):
        args = self.part_args(b, psyms)
        part = ExactPart(*args, index=[qnames.index(f"{b.name}_{n}") for n in args[5]])
        part.quad = body_quadrature(part)
        return part

    def inertia(self, der, b, part, frame, loc, body_expr, mass) -> None:
        """T and the deformation's gravity: exact_body, in casadi (sysgen)."""
        part.frame = (frame.omega, loc.V[0], loc.V[1], loc.g[0], loc.g[1], loc.R[0], loc.R[1])
        der.exact_bodies.append(part)

    def fields_at(self, der, body: str, x: float):
        """The section angle is the slope field, exactly; the position the quadrature's."""
        part = der.flex[body]
        fa = field_reader(part, x)
        L_ = part.psyms[BEAM_PARAMS[4].symbol]
        if differentiated(der.system, der.tree, body):
            args = [der.q[i] for i in part.index]
            rx, ry = position_symbols(part, der.casadi_functions, x, args)
        else:
            rx, ry = position_symbols(part, der.casadi_outputs, x)
        return rx - station(der, body, x), ry, fa(part.fields.v_s) / L_

    def inertial_stress(self, der, beam, x: float, fn: str, closed: bool = False):
        """The inertial loads over its quadrature (casadi); N along the section's tangent."""
        part = der.flex[beam.name]
        pose = der.poses[beam.name]
        Arot = rot(pose.angle)
        u, v, slope = self.fields_at(der, beam.name, x)
        tangent = sp.Matrix([sp.cos(slope), sp.sin(slope)])  # the section's axis, frame components
        section = pose.R + Arot * sp.Matrix([station(der, beam.name, x) + u, v])
        return inertial_section_load(part, der.casadi_outputs, x, fn, closed), section, tangent


KIND = Exact()
