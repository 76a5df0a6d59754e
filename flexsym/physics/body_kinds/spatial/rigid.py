"""A spatial rigid body: no coordinates of its own; T = 1/2 m |v_G|^2 + 1/2 omega^T I omega in
its frame's placeholders, V_g = -m g.r_G."""
from __future__ import annotations

import sympy as sp

from flexsym.model.exact_numbers import exact
from flexsym.physics.body_kinds import rigid as planar
from flexsym.physics.body_kinds.spatial.base import SpatialKind, cross, vec


class Rigid(SpatialKind):
    name = "rigid"
    applies = staticmethod(planar.KIND.applies)  # the same data in both dimensions

    def spin_inertia(self, b, P: dict) -> sp.Expr:
        return exact(max(b.inertia))

    def hang(self, der, fr, body: str, m):
        return fr, vec((m.x, m.y, m.z))

    def contribute(self, der, b, P, fr, motion, gvec) -> None:
        om, vf = motion.om, motion.vf
        c = vec(b.com)
        m = exact(b.mass)
        vG = vf + cross(om, c)
        I3 = [exact(v) for v in b.inertia]
        der.frame_T.append((m * vG.dot(vG) / 2 + sum(I3[k] * om[k]**2 for k in range(3)) / 2,
                            motion.actual))
        der.V_grav += -m * (gvec.dot(fr.R) + fr.g.dot(c))

    def local_point(self, der, body: str, m) -> sp.Matrix:
        return vec((m.x, m.y, m.z))

    def section_rotation(self, der, body: str, m) -> sp.Matrix:
        return der.spatial["frames"][body].A

    def momentum(self, der, b, fr) -> sp.Matrix:
        """m G x v_G + A (I omega)."""
        c, m = vec(b.com), exact(b.mass)
        vG = fr.V + cross(fr.omega, c)
        I3 = sp.diag(*[exact(v) for v in b.inertia])
        return fr.A * (m * cross(fr.A.T * fr.R + c, vG) + I3 * fr.omega)

    def first_moment(self, der, b, fr):
        m = exact(b.mass)
        return m, m * (fr.R + fr.A * vec(b.com))


KIND = Rigid()
