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
