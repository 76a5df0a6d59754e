"""An `ef` beam (planar ANCF cable elements, physics/efbody.py) as a body: its nodal
coordinates; point masses' T, gravity and momentum in sympy, the elements' T and elastic
energy (and damping) in casadi by sysgen (der.ef_kinetic, der.elastic, der.ef_damping)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sympy as sp

from flexsym.physics.body_kinds.base import (BeamKind, exact_number, frame_acceleration, record_body,
                                             station)
from flexsym.physics.efbody import A0X, A0Y, AL, GX, GY, OM, ef_part
from flexsym.physics.validity import Prefixed, strain_gauge


@dataclass
class EfKinetic:
    """An ef body's frame motion in frame components (omega, V = A^T R'), which sysgen feeds
    to the generic element's kinetic energy (efbody.generic_element) per element."""

    body: str
    omega: sp.Expr
    V: tuple[sp.Expr, sp.Expr]


class Ef(BeamKind):
    name = "ef"

    def applies(self, body) -> bool:
        return body.flexible and body.model.kind == "fe"

    def coordinates(self, b) -> list[tuple[str, str]]:
        return [(f"{b.name}_{c}", "node") for c in b.model.coordinates]

    def gauges(self, b, length: float) -> list:
        """The axial strain |r'| - 1 at its nodes, r' = (1 + dx_k, dy_k) in its frame (the
        root's slope 1 + dx0 along the frame's axis)."""
        def strain(cols):
            c = Prefixed(cols, b.name)
            return np.max([np.abs(c["dx0"])] + [np.abs(np.hypot(1 + c[f"dx{k}"], c[f"dy{k}"]) - 1)
                                                 for k in range(1, b.model.elements + 1)], axis=0)
        return [strain_gauge(b, strain)]

    def part(self, b, psyms: dict, qnames: list[str]):
        return ef_part(b, psyms)

    def contribute(self, der, b, frame, integral_symbols: bool) -> None:
        part = der.flex[b.name]
        loc = frame.local()
        ph, actual = loc.ph, loc.actual
        Vg_, H_ = part.energies()
        der.ef_kinetic.append(EfKinetic(b.name, frame.omega, (loc.V[0], loc.V[1])))
        der.T += part.point_mass_kinetic().xreplace(actual)  # elements' T: sysgen, by AD
        der.V_grav += Vg_.xreplace(actual) - part.mass * frame.g.dot(frame.pose.R)
        der.momentum += H_.xreplace(actual)
        record_body(der, b.name, part.mass, frame.pose, frame.A,
                    [-sp.diff(Vg_, gk).xreplace(actual) for gk in ph[5:]], H_.xreplace(actual))
        der.elastic.append(part)
        der.terms.append((b.name, "ancf_elastic", ("node",), None, None))
        if b.damped:
            alpha, beta = (exact_number(getattr(b.damping, k)) for k in ("alpha", "beta"))
            der.ef_damping[b.name] = (alpha, beta)
            der.dissipation[b.name] = part.point_mass_dissipation(alpha)

    def fields_at(self, der, body: str, x: float):
        rx, ry, slope = der.flex[body].position(x)
        return rx - station(der, body, x), ry, slope

    def own_stress(self, der, beam, x: float, fn: str, where: str, side: int = 0) -> sp.Expr:
        return der.flex[beam.name].stress(fn, x, side)

    def from_equilibrium(self, beam, fn: str) -> bool:
        return (beam.model.axial_force if fn == "N" else beam.model.moment) != "constitutive"

    def inertial_stress(self, der, beam, x: float, fn: str, closed: bool = False):
        """The elements' and point masses' inertial loads and gravity beyond x (efbody's
        EfPart.inertial) with the frame's actual motion; N along the section's tangent."""
        part = der.flex[beam.name]
        index = {sym: i for i, sym in enumerate(der.q)}
        qdd = {c: der.qdd[index[sym]] for c, sym in part.q.items()}
        alpha = der.ef_damping.get(beam.name, (0, 0))[0]
        out, section, axis = part.inertial(fn, x, qdd, alpha, closed)
        Arot, motion = frame_acceleration(der, beam.name)
        actual = dict(zip((OM, AL, A0X, A0Y, GX, GY), motion))
        return out.xreplace(actual), der.poses[beam.name].R + Arot * section, axis

    def damping_load(self, der, b):
        """The mass-proportional damping's force and moment (EfPart.damping_load)."""
        alpha = der.ef_damping.get(b.name, (0, 0))[0]
        return der.flex[b.name].damping_load(alpha) if alpha else None


KIND = Ef()
