"""The beam parameters every flexible body carries at run time (their order is the layout of
the parameter vector p in every generated kernel)."""
from __future__ import annotations

from flexsym.model.maneuver import Param

# Order fixes the layout of the parameter vector p in every generated kernel.
BEAM_PARAMS: tuple[Param, ...] = (
    Param("rho", 3000.0, "kg/m^3", "density"),
    Param("E", 7.0e10, "N/m^2", "Young's modulus"),
    Param("A", 4.0e-4, "m^2", "cross-section area"),
    Param("I", 2.0e-7, "m^4", "second moment of area"),
    Param("L", 10.0, "m", "length"),
)

# A spatial beam's section adds these (physics/spatial.py: after each beam's BEAM_PARAMS; I is
# then I_z, the bending along the frame's y).
SPATIAL_BEAM_PARAMS: tuple[Param, ...] = (
    Param("Iy", 8.0e-7, "m^4", "second moment of area for bending along z"),
    Param("J", 4.0e-7, "m^4", "torsion constant"),
    Param("G", 2.7e10, "N/m^2", "shear modulus"),
)
