"""A beam with exact kinematics (strain model `exact`, physics/exact_body.py): a modal beam
whose V is the modal beam's (sympy), while its T, gravity and positions are casadi
quadratures (sysgen reads der.exact_bodies and der.casadi_outputs)."""
from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from flexsym.core.errors import SpecError
from flexsym.model.strain_models import STRAIN_MODELS
from flexsym.model.system import parse_output
from flexsym.physics.body_kinds.base import rot, station
from flexsym.physics.body_kinds.modal import FlexPart, Modal, field_reader, loaded_beyond_root
from flexsym.physics.energy import BEAM_PARAMS
from flexsym.physics.exact_body import body_quadrature, inertial_section_load, position_symbols
from flexsym.physics.exact_kinematics import ExactKinematics, Quadrature


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


class Exact(Modal):
    name = "exact"

    def applies(self, body) -> bool:
        return (body.flexible and body.model.kind == "modal"
                and STRAIN_MODELS[body.model.strain].kinematics == "exact")

    def check(self, system, tree, b) -> None:
        """What it is derived for: a planar beam (uniform, or sections and point masses from
        finite-element data; damped as a modal beam, its strain measures being linear in its
        coordinates) from which nothing hangs and on which no load acts
        beyond its root (their equations would differentiate its quadrature positions in
        sympy), N and M its own (EA eps, EI dphi/dx), and no output that needs its momentum
        (momentum, the reaction of a tree joint it lies beyond, N or M from equilibrium of a
        beam it hangs from)."""
        where = f"system '{system.name}': body '{b.name}': the exact kinematics (strain model 'exact')"
        if system.dimension != 2:
            raise SpecError(f"{where} is derived for planar systems only")
        body = b.model.body
        if body is not None and (body.matrices is not None or any(m.rotary for m in body.masses)):
            raise SpecError(f"{where} is derived for a beam from its sections and point masses "
                            "(not from imported matrices, nor with a point mass's rotary inertia)")
        loaded = loaded_beyond_root(system, b.name)
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
        rx, ry = position_symbols(part, der.casadi_outputs, x)
        return rx - station(der, body, x), ry, fa(part.fields.v_s) / L_

    def inertial_stress(self, der, beam, x: float, fn: str):
        """The inertial loads over its quadrature (casadi); N along the section's tangent."""
        part = der.flex[beam.name]
        pose = der.poses[beam.name]
        Arot = rot(pose.angle)
        u, v, slope = self.fields_at(der, beam.name, x)
        tangent = sp.Matrix([sp.cos(slope), sp.sin(slope)])  # the section's axis, frame components
        section = pose.R + Arot * sp.Matrix([station(der, beam.name, x) + u, v])
        return inertial_section_load(part, der.casadi_outputs, x, fn), section, tangent


KIND = Exact()
