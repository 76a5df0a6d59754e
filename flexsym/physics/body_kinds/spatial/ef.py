"""A spatial `ef` beam (physics/spatial_ef.py, rod3d's Simo-Reissner elements in casadi) as a
body: its nodes' coordinates; gravity in sympy, the elements' T and elastic energy by sysgen
(der.rod_bodies, der.casadi_T); its axis points, section axes at a node, the frame of a body
hung from a node's marker, and section forces."""
from __future__ import annotations

import numpy as np
import sympy as sp

from flexsym.model.exact_numbers import exact
from flexsym.physics.assemble import Coordinate
from flexsym.physics.body_kinds import ef as planar
from flexsym.physics.body_kinds.spatial.base import Frame, SpatialBeam, cross, euler_G, euler_rotation
from flexsym.physics.spatial_ef import ef_at, ef_body, ef_coordinates, ef_part, ef_quaternion, ef_section
from flexsym.physics.validity import Prefixed, strain_gauge


class Ef(SpatialBeam):
    name = "ef"
    applies = staticmethod(planar.KIND.applies)  # the same data in both dimensions

    def coordinates(self, b) -> list:
        """Per free node, the displacement and the rotation vector."""
        return [Coordinate(f"{b.name}_{n}", "node", b.name, start=(0.0, 0.0)) for n in ef_coordinates(b)]

    def gauges(self, b, length: float) -> list:
        """The axial strain of each element's chord, |X_k - X_k-1| / (L / n) - 1, X_k the node's
        position in its frame (k L / n, 0, 0) + (ux, uy, uz)_k, the root's X_0 = 0."""
        n = b.model.elements

        def strain(cols):
            c = Prefixed(cols, b.name)
            X = [np.zeros((len(c["ux1"]), 3))] + [
                np.column_stack([k * length / n + c[f"ux{k}"], c[f"uy{k}"], c[f"uz{k}"]])
                for k in range(1, n + 1)]
            return np.max([np.abs(np.linalg.norm(X[k] - X[k - 1], axis=1) * n / length - 1)
                           for k in range(1, n + 1)], axis=0)
        return [strain_gauge(b, strain)]

    def part(self, der, b, P) -> None:
        ef_part(der, b, P)

    def hang(self, der, fr: Frame, body: str, m):
        """The section's frame at a node: origin at the node r, axes Lambda(e) from the beam's
        frame, e the node's quaternion (functions of its rotation vector psi that sympy
        differentiates: spatial_ef.ef_quaternion); its angular velocity in its own axes
        Lambda^T omega + 2 G(e) e', as a ball joint's, its origin's velocity
        Lambda^T (V + omega x r + r')."""
        r, e = ef_at(der, body, m.x), ef_quaternion(der, body, m.x)
        Lam = euler_rotation(e)
        return Frame(fr.A * Lam, fr.R + fr.A * r, Lam.T * fr.omega + 2 * euler_G(e) * der.ddt(e),
                     Lam.T * (fr.V + cross(fr.omega, r) + der.ddt(r)), Lam.T * fr.g), sp.zeros(3, 1)

    def contribute(self, der, b, P, fr, motion, gvec) -> None:
        der.V_grav += ef_body(der, b, P, fr, motion.om, motion.vf, motion.actual, gvec)

    def axis_point(self, der, body: str, x: float) -> sp.Matrix:
        return ef_at(der, body, x)

    def section_rotation(self, der, body: str, m) -> sp.Matrix:
        """A node's section: exp(psi), exact (the rotation of its quaternion: spatial_ef.ef_quaternion)."""
        return der.spatial["frames"][body].A * euler_rotation(ef_quaternion(der, body, m.x))

    def displacement(self, der, beam, x: float, fn: str) -> sp.Expr:
        r = ef_at(der, beam.name, x)
        k = ("u", "v", "vz").index(fn)
        return r[k] - (exact(x) / exact(beam.length) * der.spatial[beam.name]["P"]["L"] if k == 0 else 0)

    def section(self, der, beam, x: float, fn: str, loads_beyond) -> sp.Expr:
        """rod3d's own section forces (constitutive, shear included)."""
        return ef_section(der, beam, x, fn)


KIND = Ef()
