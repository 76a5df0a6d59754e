"""Names of a one-beam variant's outputs, their defaults and checks: data, no physics.

Names: v_tip, u_tip, and N_P / M_P at a point P: A (root, x = 0), B (x = L/2), C (tip,
x = L) or s<fraction> for x = fraction * L, written with 'p' for the decimal point
(N_s0p25 is N at x = L/4; on the command line N@0.25), or a label the spec names (points).
The expressions behind the names are outputs.py's.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import sympy as sp

from flexsym.core.errors import SpecError

POINTS = {"A": sp.Integer(0), "B": sp.Rational(1, 2), "C": sp.Integer(1)}
CLAMP_OUTPUTS = ("N_A_clamp", "M_A_clamp")  # ef: N and M at the root from the clamp reaction
STRESS_OUTPUTS = tuple(f"{q}_{p}" for q in "NM" for p in "ABC")
_POINT_RE = re.compile(r"^([NM])_(A|B|C|s(\d+)(?:p(\d+))?)$")
_AT_RE = re.compile(r"^([NM])@([0-9]*\.?[0-9]+)$")


@dataclass(frozen=True)
class OutputInfo:
    name: str
    unit: str
    description: str


def canonical_output(token: str) -> str:
    """'N@0.25' -> 'N_s0p25'; names already canonical are returned unchanged."""
    token = token.strip()
    m = _AT_RE.fullmatch(token)
    if m:
        frac = sp.nsimplify(m.group(2))
        if not 0 <= frac <= 1:
            raise SpecError(f"output '{token}': position {m.group(2)} is outside [0, 1] "
                            "(positions are fractions of the beam length)")
        text = m.group(2).rstrip("0").rstrip(".") if "." in m.group(2) else m.group(2)
        text = text if not text.startswith(".") else "0" + text
        return f"{m.group(1)}_s{text.replace('.', 'p')}"
    return token


LABEL_RE = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,31}$")


def point_of(name: str, points=()):
    """(quantity 'N'|'M', exact position s) of a stress output name, or None. `points` are the
    spec's named positions (label, fraction of L)."""
    if len(name) > 2 and name[0] in "NM" and name[1] == "_":
        for label, frac in points:
            if name[2:] == label:
                return name[0], sp.Rational(frac)
    m = _POINT_RE.fullmatch(name)
    if not m:
        return None
    where = m.group(2)
    if where in POINTS:
        return m.group(1), POINTS[where]
    frac = sp.nsimplify(f"{m.group(3)}.{m.group(4) or 0}")
    return m.group(1), frac


def system_alias(name: str, labels=()) -> tuple[str, object, int, str] | None:
    """A one-beam output name read in the system grammar: (function, station, side, recovery),
    the station a fraction of the length (a sympy Rational: A, B, C, s<fraction>, @<fraction>)
    or one of `labels` (the beam's markers), side -1 / +1 for a label's *_left / *_right (the
    element before / beyond a node), else 0; recovery "" (the beam's own) or "equilibrium" for
    ef's clamp reactions N_A_clamp, M_A_clamp (the section force at the root that balances the
    whole beam). None: not a one-beam output name."""
    name = canonical_output(name)
    if name in ("v_tip", "u_tip"):
        return name[0], sp.Integer(1), 0, ""
    if name in CLAMP_OUTPUTS:
        return name[0], sp.Integer(0), 0, "equilibrium"
    fixed = _POINT_RE.fullmatch(name)
    if fixed:  # A, B, C and fractions before any label: what the one-beam grammar reserves
        q, at = point_of(name)
        return q, at, 0, ""
    if len(name) < 3 or name[0] not in "NM" or name[1] != "_":
        return None
    label, side = name[2:], 0
    for suffix, s in (("_left", -1), ("_right", 1)):
        if label.endswith(suffix):
            base = label[:-len(suffix)]
            label, side = (label, s) if label in labels else (base, s)
    return (name[0], label, side, "") if label in labels else None


def info(name: str, points=()) -> OutputInfo:
    if name == "v_tip":
        return OutputInfo(name, "m", "transverse tip deflection v_o(L) in the moving frame")
    if name == "u_tip":
        return OutputInfo(name, "m", "axial tip displacement u_o(L) in the moving frame")
    if name.endswith("_clamp"):  # ef's N_A_clamp, M_A_clamp
        return OutputInfo(name, "N" if name[0] == "N" else "N m",
                          f"{'axial force' if name[0] == 'N' else 'bending moment'} at the root "
                          "from the clamp reaction")
    q, at = point_of(name, points)
    what = "axial force (tension > 0)" if q == "N" else "bending moment (EI v'')"
    return OutputInfo(name, "N" if q == "N" else "N m", f"{what} at x = {at} L")


def check_output_names(spec, extra=()) -> None:
    for label, frac in spec.points:
        if not LABEL_RE.fullmatch(label) or label in POINTS or re.match(r"s\d", label):
            raise SpecError(f"variant '{spec.name}': position name '{label}' must be letters, digits "
                            "and _ (it reaches generated C), start with a letter, and not be A, B, C")
        try:
            value = sp.Rational(frac)
        except (TypeError, ValueError):
            raise SpecError(f"variant '{spec.name}': position '{label}' = {frac!r} is not a number") from None
        if not 0 <= value <= 1:
            raise SpecError(f"variant '{spec.name}': position '{label}' is outside the beam")
    seen = set()
    for name in spec.outputs:
        if name not in ("v_tip", "u_tip") and name not in extra:
            p = point_of(name, spec.points)
            if p is None:
                raise SpecError(f"variant '{spec.name}': unknown output '{name}' (known: v_tip, "
                                "u_tip, N_A, N_B, N_C, M_A, M_B, M_C, N@<x/L>, M@<x/L>)")
            if not 0 <= p[1] <= 1:
                raise SpecError(f"variant '{spec.name}': output '{name}' is outside the beam")
            if p[0] == "N" and spec.kind == "modal" and not axial_force_available(spec):
                raise SpecError(
                    f"variant '{spec.name}': {name} is not available: strain model "
                    f"'{spec.strain}' has no axial coordinate to carry an axial force; use "
                    "--axial-force equilibrium to recover N from the inertial forces")
        if name in seen:
            raise SpecError(f"variant '{spec.name}': duplicate output '{name}'")
        seen.add(name)


def axial_force_available(spec) -> bool:
    return bool(spec.axial) or spec.strain == "prestress" or spec.axial_force == "equilibrium"


def default_outputs(spec) -> tuple[str, ...]:
    """v_tip, u_tip and every stress at A, B, C that the variant can give."""
    outs = ["v_tip", "u_tip"]
    outs += [n for n in STRESS_OUTPUTS if n[0] == "M" or axial_force_available(spec)]
    return tuple(outs)


def stress_method(spec) -> tuple[str, int]:
    if getattr(spec, "body", None) is not None:
        if spec.stress != "continuum":
            raise SpecError(f"variant '{spec.name}': a body from finite-element data recovers "
                            "stresses on its own elements; --stress does not apply")
        return "body", 0
    if spec.stress == "continuum":
        return "continuum", 0
    if getattr(spec, "strain", None) == "exact" and spec.stress != "continuum":
        raise SpecError(f"variant '{spec.name}': the element method reads small-deflection nodal "
                        "values; the exact kinematics takes --stress continuum (and --moment / "
                        "--axial-force equilibrium for the resultants from the inertial loads)")
    m = re.fullmatch(r"element:(\d+)", spec.stress)
    if not m or not 1 <= int(m.group(1)) <= 1000:
        raise SpecError(f"variant '{spec.name}': stress method '{spec.stress}' must be "
                        "'continuum' or 'element:N' with 1 <= N <= 1000 elements")
    return "element", int(m.group(1))
