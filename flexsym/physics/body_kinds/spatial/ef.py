"""A spatial `ef` beam (physics/spatial_ef.py, rod3d's Simo-Reissner elements in casadi) as a
body: its nodes' coordinates; gravity in sympy, the elements' T and elastic energy by sysgen
(der.rod_bodies, der.casadi_T); its axis points, section axes at a node and section forces."""
from __future__ import annotations

import numpy as np
import sympy as sp

from flexsym.model.exact_numbers import exact
from flexsym.physics.assemble import Coordinate
from flexsym.physics.body_kinds import ef as planar
from flexsym.physics.body_kinds.spatial.base import SpatialBeam
from flexsym.physics.spatial_ef import ef_at, ef_body, ef_coordinates, ef_rotation, ef_section
from flexsym.physics.validity import Prefixed, strain_gauge


class Ef(SpatialBeam):
    name = "ef"
    applies = staticmethod(planar.KIND.applies)  # the same data in both dimensions
    markers_after_energies = True  # ef_body registers its nodes (der.spatial) in the loop

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

    def contribute(self, der, b, P, fr, motion, gvec) -> None:
        der.V_grav += ef_body(der, b, P, fr, motion.om, motion.vf, motion.actual, gvec)

    def axis_point(self, der, body: str, x: float) -> sp.Matrix:
        return ef_at(der, body, x)

    def section_rotation(self, der, body: str, m) -> sp.Matrix:
        """A node's section: exp(psi), exact (spatial_ef.ef_rotation)."""
        return der.spatial["frames"][body].A * ef_rotation(der, body, m.x)

    def displacement(self, der, beam, x: float, fn: str) -> sp.Expr:
        r = ef_at(der, beam.name, x)
        k = ("u", "v", "vz").index(fn)
        return r[k] - (exact(x) / exact(beam.length) * der.spatial[beam.name]["P"]["L"] if k == 0 else 0)

    def section(self, der, beam, x: float, fn: str, loads_beyond) -> sp.Expr:
        """rod3d's own section forces (constitutive, shear included)."""
        return ef_section(der, beam, x, fn)


KIND = Ef()
