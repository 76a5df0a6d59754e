"""A rigid body: no coordinates of its own; T = 1/2 m |v_G|^2 + 1/2 J phi'^2, V_g = -m g.r_G."""
from __future__ import annotations

import sympy as sp

from flexsym.model.exact_numbers import exact
from flexsym.physics.body_kinds.base import BodyKind, cross, rot


class Rigid(BodyKind):
    name = "rigid"

    def applies(self, body) -> bool:
        return not body.flexible

    def contribute(self, der, b, frame, integral_symbols: bool) -> None:
        pose, A_, omega, gvec = frame.pose, frame.A, frame.omega, frame.g
        G = pose.R + A_ * sp.Matrix([exact(x) for x in b.com])
        vG = der.ddt(G)
        m, J = exact(b.mass), exact(b.inertia)
        der.T += m * vG.dot(vG) / 2 + J * omega**2 / 2
        der.V_grav += -m * gvec.dot(G)
        der.momentum += m * cross(G, vG) + J * omega
        der.mass[b.name], der.first_moment[b.name] = m, m * G
        der.body_momentum[b.name] = m * cross(G, vG) + J * omega

    def origin(self, point: sp.Matrix, angle: sp.Expr, marker) -> sp.Matrix:
        """Its frame is its body frame, in which the marker is given."""
        return point - rot(angle) * sp.Matrix([exact(marker.x), exact(marker.y)])

    def marker_pose(self, der, body, m) -> tuple[sp.Matrix, sp.Expr]:
        pose = der.poses[body]
        return pose.R + rot(pose.angle) * sp.Matrix([exact(m.x), exact(m.y)]), pose.angle


KIND = Rigid()
