"""The limits every input is checked against before any work starts (one place for each).

MAX_MAGNITUDE: every number of a system or a one-beam scene (masses, lengths, section values,
positions, forces, spring constants, gravity, angles, manoeuvre values) in SI units. No physical
quantity of a mechanism comes near it (the stiffest material, diamond, has E ~ 1.2e12 Pa), and
the derivation multiplies up to ~20 of them (mass x length^2 x rate^2 ...): with |x| <= 1e13
such products stay far below the largest double (1.8e308), where 1e200 or 1e308 overflow to inf
in the generated code.
MAX_BODIES, MAX_JOINTS: the derivation's cost grows steeply with a chain's length (sympy
expands the kinematics of every body along its path from ground): a chain of rigid links under
gravity took 2 s with 4 links, 30 s with 8 and 160 s with 12 on a loaded 2-core machine (about
n^4); beyond these counts it would run for a very long time without a result.
MIN_POSITIVE: a quantity that must be > 0 (mass, inertia, length, density, Young's modulus,
area, second moment) must be at least this: the equations divide by them and by their powers
(1 / L^4), so 1e-300 overflows where a thin wire (I ~ 5e-14 m^4) is still far inside.
MIN_AXIS: a prismatic axis is a direction (normalised); a shorter one is a typo, and its
squared length underflows.
MAX_FILE_BYTES: a scene file, body.toml or a Matrix Market file larger than this is refused
before it is read (and so is anything but a regular file: a FIFO or /dev/zero never ends).
MAX_EF_ELEMENTS: an ef beam's elements (a variant's, --elements, --ref-elements): the converged
references take 16 to 64, and the derivation's cost grows with each element.
"""
from __future__ import annotations

import math
import numbers

from flexsym.core.errors import SpecError

MAX_MAGNITUDE = 1e13
MAX_BODIES = 12
MAX_JOINTS = 24
MIN_POSITIVE = 1e-20  # masses, inertias, lengths, section values: their reciprocals appear
MIN_AXIS = 1e-6
MAX_FILE_BYTES = 64 * 2**20
MAX_EF_ELEMENTS = 512


def is_real(v) -> bool:
    """A real number: int or float (numpy's too), not bool, complex, str or None."""
    return isinstance(v, numbers.Real) and not isinstance(v, bool) and type(v).__name__ != "bool_"


def check_number(v, what: str, *, finite_only: bool = False) -> float:
    """v as a float: a real number, finite, |v| <= MAX_MAGNITUDE (unless finite_only)."""
    if not is_real(v):
        raise SpecError(f"{what} must be a real number (got {type(v).__name__} {v!r})")
    if not math.isfinite(v):
        raise SpecError(f"{what} must be finite (got {v!r})")
    if not finite_only and abs(v) > MAX_MAGNITUDE:
        raise SpecError(f"{what} = {float(v):.6g} is beyond the limit |x| <= {MAX_MAGNITUDE:g} (SI units; "
                        "larger values overflow the generated code's arithmetic)")
    return float(v)


def check_positive(v, what: str) -> float:
    """check_number, and MIN_POSITIVE <= v."""
    v = check_number(v, what)
    if not v >= MIN_POSITIVE:
        raise SpecError(f"{what} = {v:.6g} must be >= {MIN_POSITIVE:g} (a positive quantity; its "
                        "reciprocal powers appear in the equations)")
    return v
