"""Strain models as data: which energy term (energy.py's ENERGY_TERMS) is differentiated with
respect to which coordinate group, and the kinematics that carries them.

That choice is the difference between the paper's variants #1/#2 (eq. 18-19: the cubic
coupling term acts on the bending equations only) and the blind gradient of the truncated
energy (eq. 5), which pulls the axial coordinate into compression and collapses (benchmark.md
section 3). Plain data (no physics imported): specs check names against it, the derivations
read it, `flexsym inspect` prints it.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class StrainModel:
    name: str
    foreshortening: bool  # kinematic u_fs in the axial field
    terms: tuple[tuple[str, tuple[str, ...]], ...]  # (energy term, coordinate groups differentiated)
    needs_axial: bool
    description: str
    kinematics: str = "second_order"  # or "exact" (exact.py: positions from the rotation field)

    def conservative(self, axial_present: bool) -> bool:
        """True when every term is differentiated w.r.t. every coordinate group it depends on."""
        for term, wrt in self.terms:
            depends = {"axial": term in ("axial", "cubic", "stretch") and axial_present,
                       "bending": term in ("bending", "cubic", "quartic", "prestress", "curvature")}
            if any(dep and g not in wrt for g, dep in depends.items()):
                return False
        return True


_BASE = (("axial", ("axial",)), ("bending", ("bending",)))

STRAIN_MODELS: dict[str, StrainModel] = {m.name: m for m in (
    StrainModel("linear", False, _BASE, False,
                "linear strain: no geometric stiffening (variant #0)"),
    StrainModel("geometric_stiffness", False, _BASE + (("cubic", ("bending",)),), True,
                "eq. (18)-(19): K_G(eta) y acts on the bending coordinates only; the axial "
                "equations see K_L alone (variants #1, #2)"),
    StrainModel("cubic_energy", False, _BASE + (("cubic", ("axial", "bending")),), True,
                "full gradient of the truncated energy (5): the trap of docs/theory/benchmark.md, section 3, "
                "unbounded below; offered only to show that it collapses"),
    StrainModel("von_karman", False,
                _BASE + (("cubic", ("axial", "bending")), ("quartic", ("axial", "bending"))),
                True, "consistent energy (4) with the quartic term: bounded, but linear axial "
                "modes lock (far too stiff)"),
    StrainModel("foreshortening", True, _BASE, False,
                "eq. (30)-(31): axial field carries u_fs = -1/2 int v_x^2; linear strain energy "
                "(variant #3)"),
    StrainModel("prestress", False, _BASE + (("prestress", ("bending",)),), False,
                "bending modes with the prestress geometric stiffness 1/2 int N(x) v_x^2 of the "
                "rigid beam's axial load, N = rho A w^2 (L^2 - x^2)/2 on a hub, plus "
                "rho A (g_x - a_0x)(L - x) where its root accelerates or gravity acts along it"),
    StrainModel("exact", False, (("stretch", ("axial",)), ("curvature", ("bending",))), False,
                "exact kinematics: bending modes' slopes are the section rotation, axial modes' "
                "strains the stretch (none: inextensible); r = int (1 + eps)(cos phi, sin phi) dx, "
                "no strain truncated (exact.py)", kinematics="exact"),
)}
