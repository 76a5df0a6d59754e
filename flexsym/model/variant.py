"""Frozen variant specifications: the data that defines a model, and its fingerprint.

A variant is data (strain model + axial modes + bending modes + manoeuvre + outputs, or a
number of `ef` elements) run through one derivation mechanism; nothing here is specific to one
variant. Checked against data only (names of strain models, modes, manoeuvres, outputs): the
derivations (derive.py, fe.py) import this module, never the other way round.
"""
from __future__ import annotations

import hashlib
import json
import re
from dataclasses import dataclass, field, replace

import sympy as sp

from flexsym.core.errors import SpecError
from flexsym.model.limits import MAX_EF_ELEMENTS
from flexsym.model.maneuver import maneuver_of
from flexsym.model.modes import ModeRef, mode, parse_mode_token, root_slope_free
from flexsym.model.output_names import (CLAMP_OUTPUTS, STRESS_OUTPUTS, canonical_output, check_output_names,
                                        default_outputs, stress_method)
from flexsym.model.strain_models import STRAIN_MODELS

NAME_RE = re.compile(r"[a-z][a-z0-9_]{0,47}\Z")  # used with match: \Z, not $ (a trailing newline)
QUAD_POINTS = 5  # ef: Gauss points per element (exact for EA eps^2, degree 8 in xi; kappa^2 is rational)
RECOVERIES = ("auto", "constitutive", "equilibrium")
# A spatial beam's torsion modes (the bar's shapes: St Venant torsion is the bar's equation):
# one by default; a scene may give more, or none where nothing reads the twist and its stiff
# mode would only cap the step (model = { ..., torsion = [] })
TORSION_MODES = (ModeRef("axial", "fixed_free", 1),)


@dataclass(frozen=True)
class VariantSpec:
    """A modal (floating frame of reference) variant."""

    kind = "modal"
    name: str
    strain: str
    axial: tuple[ModeRef, ...]
    bending: tuple[ModeRef, ...]
    maneuver: str = "spin_up"
    outputs: tuple[str, ...] = ("v_tip", "u_tip")
    stress: str = "continuum"  # or "element:N" (paper eq. 22-25 on N elements)
    # N and M recovery: "constitutive" (EA u', EI v'' of the modes) or "equilibrium" (from the
    # inertial and external loads beyond the station); "auto" is the one-beam spin-up's
    # constitutive (the paper's) and a mechanism's equilibrium (FlexibleBeam resolves it)
    axial_force: str = "auto"
    moment: str = "auto"
    points: tuple[tuple[str, str], ...] = ()  # named output positions (label, fraction of L)
    left_out: tuple[tuple[str, str], ...] = ()  # (what, why): decided by a scene, in the manifest
    description: str = ""
    aliases: tuple[str, ...] = field(default=(), compare=False)
    body: object = None  # fedata.BeamBody: modes computed from finite-element data
    torsion: tuple[ModeRef, ...] = TORSION_MODES  # a spatial beam's (planar systems: none given)

    @property
    def exact_kinematics(self) -> bool:
        """The section rotation from the modes' slopes (`exact`), not a floating frame's."""
        return STRAIN_MODELS[self.strain].kinematics == "exact"

    def mode(self, ref: ModeRef):
        """The shape of a mode: the library's analytic one, or the body's computed one."""
        if self.body is None:
            return mode(ref)
        from flexsym.model.fedata import body_mode

        return body_mode(self.body, ref)

    @property
    def modes(self) -> tuple[ModeRef, ...]:
        return self.axial + self.bending

    @property
    def coordinates(self) -> tuple[str, ...]:
        return tuple(m.coordinate for m in self.modes)

    def to_dict(self) -> dict:
        """Canonical content (no aliases, no description): what the generated code depends on."""
        return {
            "name": self.name,
            "strain": self.strain,
            "axial": [m.token for m in self.axial],
            "bending": [m.token for m in self.bending],
            "maneuver": self.maneuver,
            "outputs": list(self.outputs),
            "stress": self.stress,
            "axial_force": "constitutive" if self.axial_force == "auto" else self.axial_force,
            "points": [list(p) for p in self.points],
            "left_out": [list(x) for x in self.left_out],
        } | ({"body": self.body.to_dict()} if self.body is not None else {}) | (
            {"moment": self.moment} if self.moment == "equilibrium" else {}) | (
            {"torsion": [m.token for m in self.torsion]} if self.torsion != TORSION_MODES else {})

    def validate(self) -> "VariantSpec":
        if not isinstance(self.name, str) or not NAME_RE.match(self.name):
            raise SpecError(f"variant name {self.name!r}: use lower-case letters, digits and _ "
                            "(it becomes a C identifier), starting with a letter")
        model = STRAIN_MODELS.get(self.strain)
        if model is None:
            raise SpecError(f"variant '{self.name}': unknown strain model '{self.strain}' "
                            f"(known: {', '.join(STRAIN_MODELS)})")
        for axis, refs, what in (("axial", self.axial, "axial"), ("bending", self.bending, "bending"),
                                 ("axial", self.torsion, "torsion")):
            seen = set()
            for r in refs:
                if r.axis != axis:
                    raise SpecError(f"variant '{self.name}': mode {r.token} is not a{'n' if axis == 'axial' else ''} "
                                    f"{axis} mode{' (torsion takes the bar shapes)' if what == 'torsion' else ''}")
                # validates family and index (and computes a body's mode; a body's torsion
                # shapes are its torsion view's, computed where they are used)
                if what == "torsion":
                    mode(r)
                else:
                    self.mode(r)
                if r in seen:
                    raise SpecError(f"variant '{self.name}': duplicate {what} mode '{r.token}'")
                seen.add(r)
        if not self.bending:
            raise SpecError(f"variant '{self.name}': at least one bending mode is required")
        if model.needs_axial and not self.axial:
            raise SpecError(f"variant '{self.name}': strain model '{self.strain}' needs at least "
                            "one axial mode (its stiffening term is linear in the axial amplitudes)")
        if "v_tip" in self.outputs and all(self.mode(r).value_at(0, 1) == 0 for r in self.bending):
            raise SpecError(f"variant '{self.name}': no bending mode moves the tip, so v_tip would "
                            "be identically zero (add the static mode or a clamped-free mode)")
        try:
            maneuver_of(self.maneuver)
        except SpecError as exc:
            raise SpecError(f"variant '{self.name}': {exc}") from None
        if not self.outputs:
            raise SpecError(f"variant '{self.name}': no outputs requested")
        if self.moment not in RECOVERIES:
            raise SpecError(f"variant '{self.name}': moment '{self.moment}' must be "
                            "'constitutive' or 'equilibrium'")
        if self.axial_force not in RECOVERIES:
            raise SpecError(f"variant '{self.name}': axial force '{self.axial_force}' must be "
                            "'constitutive' or 'equilibrium'")
        stress_method(self)
        check_output_names(self)
        return self


@dataclass(frozen=True)
class FESpec:
    """The finite-element reference `ef` (geometrically exact ANCF elements, fe.py)."""

    name: str
    elements: int = 16
    maneuver: str = "spin_up"
    outputs: tuple[str, ...] = ("v_tip", "u_tip") + STRESS_OUTPUTS + CLAMP_OUTPUTS
    points: tuple[tuple[str, str], ...] = ()  # named output positions (label, fraction of L)
    left_out: tuple[tuple[str, str], ...] = ()
    description: str = ""
    aliases: tuple[str, ...] = field(default=(), compare=False)
    body: object = None  # fedata.BeamBody: per-element sections and point masses
    # N and M of an ef beam in a system: the equilibrium of the part of the beam beyond the
    # station ("equilibrium", and "auto", as a modal beam's in a mechanism) or the elements'
    # own strain and curvature ("constitutive"); the one-beam ef's are its elements' own
    axial_force: str = "auto"
    moment: str = "auto"
    kind = "fe"

    @property
    def coordinates(self) -> tuple[str, ...]:
        """x_x of the clamped root (free: it is the root stretch), then 4 per further node."""
        return ("dx0",) + tuple(f"{c}{k}" for k in range(1, self.elements + 1)
                                for c in ("ux", "uy", "dx", "dy"))

    def to_dict(self) -> dict:
        return {"name": self.name, "kind": "fe", "formulation": "ancf_cable",
                "elements": self.elements, "quadrature": QUAD_POINTS, "maneuver": self.maneuver,
                "outputs": list(self.outputs), "points": [list(p) for p in self.points],
                "left_out": [list(x) for x in self.left_out]} | (
                    {"body": self.body.to_dict()} if self.body is not None else {}) | {
                    k: v for k, v in (("axial_force", self.axial_force), ("moment", self.moment))
                    if v != "auto"}

    def validate(self) -> "FESpec":
        if not NAME_RE.match(self.name):
            raise SpecError(f"variant name '{self.name}': use lower-case letters, digits and _")
        if not isinstance(self.elements, int) or not 1 <= self.elements <= MAX_EF_ELEMENTS:
            raise SpecError(f"variant '{self.name}': elements must be an integer in 1..{MAX_EF_ELEMENTS} "
                            f"(got {self.elements!r})")
        if self.body is not None:
            if self.body.elements != self.elements:
                raise SpecError(f"variant '{self.name}': {self.elements} elements but its body has "
                                f"{self.body.elements}")
            if any(m.rotary for m in self.body.masses):
                raise SpecError(f"variant '{self.name}': point rotary inertia is not modelled in "
                                "'ef' (its nodes carry slopes, not rotations); modal variants take it")
        maneuver_of(self.maneuver)
        check_output_names(self, extra=CLAMP_OUTPUTS)
        return self

    def node_fractions(self) -> list:
        """Node positions as exact fractions of L (uniform mesh) or the body's nodes."""
        if self.body is None:
            return [sp.Rational(k, self.elements) for k in range(self.elements + 1)]
        return [sp.Rational(repr(float(x))) for x in self.body.s_nodes]


def _refs(axis: str, tokens) -> tuple[ModeRef, ...]:
    if isinstance(tokens, str):  # "" is the empty set; an empty name inside a list is a mistake
        tokens = [t.strip() for t in tokens.split(",")] if tokens.strip() else []
        if not all(tokens):
            raise SpecError(f"{axis} modes: empty name in the list")
    return tuple(parse_mode_token(axis, t) for t in tokens)


PAPER_BENDING = ("static", "cp1", "cp2")

def with_default_outputs(spec: VariantSpec) -> VariantSpec:
    return replace(spec, outputs=default_outputs(spec))


BUILTIN: tuple[VariantSpec, ...] = tuple(with_default_outputs(v) for v in (
    VariantSpec("linear", "linear", _refs("axial", ["static"]), _refs("bending", PAPER_BENDING),
                description="#0: linear strain, no geometric stiffening (fails above the first "
                            "bending frequency)", aliases=("m0",)),
    VariantSpec("geometric", "geometric_stiffness", _refs("axial", ["static"]),
                _refs("bending", PAPER_BENDING),
                description="#1: geometric stiffness K_G(eta) on the bending equations (eq. 18-19), "
                            "linear axial mode", aliases=("m1",)),
    VariantSpec("geometric_sine", "geometric_stiffness", _refs("axial", ["static", "sin1"]),
                _refs("bending", PAPER_BENDING),
                description="#2: as #1 with the axial sine mode sin(pi s) added (eq. 27-29)",
                aliases=("m2",)),
    VariantSpec("foreshortening", "foreshortening", (), _refs("bending", PAPER_BENDING),
                description="#3: foreshortening u_fs = -1/2 int v'^2 (eq. 30-31), no axial "
                            "coordinate", aliases=("m3",)),
    VariantSpec("prestress", "prestress", (), _refs("bending", PAPER_BENDING),
                description="bending modes with the centrifugal-prestress geometric stiffness "
                            "w^2 int N(x) v'^2 dx, N(x) = rho A (L^2 - x^2)/2 (not in the paper)"),
    VariantSpec("exact", "exact", (), _refs("bending", ["cf1", "cf2", "cf3", "cf4", "cf5"]),
                moment="equilibrium", axial_force="equilibrium",
                description="exact kinematics: section rotation from the clamped-free modes' "
                            "slopes, inextensible; N and M from equilibrium; only modal "
                            "truncation (not in the paper)"),
)) + (FESpec("ef", 16, description="geometrically exact finite elements (planar ANCF cable "
                                  "elements, 16 by default): the reference"),)


def builtin(name: str) -> VariantSpec:
    for v in BUILTIN:
        if name == v.name or name in v.aliases:
            return v
    known = ", ".join(f"{v.name} ({'/'.join(v.aliases)})" if v.aliases else v.name for v in BUILTIN)
    raise SpecError(f"unknown variant '{name}' (built-in: {known})")


def customize(base, *, name=None, strain=None, axial=None, bending=None, outputs=None,
              maneuver=None, stress=None, axial_force=None, elements=None, points=None, moment=None):
    """A new variant from a base one with some fields replaced (mode lists as 'static,cp1,...').
    Outputs not given explicitly are the defaults of the new variant."""
    if isinstance(outputs, str):
        outputs = [o.strip() for o in outputs.split(",")]
    if outputs is not None and (not outputs or not all(outputs)):
        raise SpecError(f"outputs {','.join(outputs)!r}: empty name in the list (give at least one "
                        "output, e.g. v_tip)")
    if elements is not None and (isinstance(elements, bool) or not isinstance(elements, int)
                                 or not 1 <= elements <= MAX_EF_ELEMENTS):
        raise SpecError(f"elements must be a whole number in 1..{MAX_EF_ELEMENTS} (got {elements!r})")
    if base.kind == "fe":
        modal_only = {"strain": strain, "axial": axial, "bending": bending, "stress": stress,
                      "axial_force": axial_force, "moment": moment}
        given = [k for k, v in modal_only.items() if v is not None]
        if given:
            raise SpecError(f"--{given[0].replace('_', '-')} does not apply to the finite-element "
                            f"variant '{base.name}' (it takes --elements, --outputs, --maneuver)")
        changes = {k: v for k, v in (("elements", elements), ("maneuver", maneuver),
                                     ("points", points)) if v is not None}
        if outputs is not None:
            changes["outputs"] = tuple(canonical_output(o) for o in outputs)
        spec = replace(base, **changes, aliases=(), description=f"custom variant derived from {base.name}")
        if name is None:
            name = f"{base.name}_n{spec.elements}" if set(changes) <= {"elements"} else None
        return _named(spec, base, name)
    if elements is not None:
        raise SpecError(f"--elements applies to the finite-element variant 'ef', not to '{base.name}'")

    changes = {}
    if strain is not None:
        changes["strain"] = strain
    if axial is not None:
        changes["axial"] = _refs("axial", axial)
    if bending is not None:
        changes["bending"] = _refs("bending", bending)
    if outputs is not None:
        changes["outputs"] = tuple(canonical_output(o) for o in outputs)
    for key, val in (("maneuver", maneuver), ("stress", stress), ("axial_force", axial_force),
                     ("moment", moment),
                     ("points", points)):
        if val is not None:
            changes[key] = val
    spec = replace(base, **changes, aliases=(), description=f"custom variant derived from {base.name}")
    if outputs is None:
        spec = with_default_outputs(spec)
    return _named(spec, base, name)


def body_model(strain: str, axial: tuple, bending: tuple) -> "VariantSpec":
    """A system body's model from a strain model and mode sets (a scene's { strain, axial,
    bending }, or the modes end_modes chooses). Its outputs are the body's scene's; validate
    checks one the modes can carry: the one-beam v_tip (v at the tip, in the frame), or M_B
    when every bending mode is zero at the tip (pp: the frame is the chord's)."""
    tip = any(mode(m).value_at(0, 1) != 0 for m in bending)
    return VariantSpec("body", strain, tuple(axial), tuple(bending),
                       outputs=("v_tip",) if tip else ("M_B",)).validate()


def check_clamped_root(spec) -> None:
    """A one-beam model clamps the beam to its hub: bending modes whose root slope is free
    (pp, pf: made for a pinned root, their frame the chord's or the pin's) are refused there."""
    free = [m.token for m in getattr(spec, "bending", ()) if root_slope_free(m)]
    if free:
        raise SpecError(f"variant '{spec.name}': bending mode {free[0]} leaves the root slope free "
                        "(for a pinned root), but a one-beam model clamps the beam to its hub (use "
                        "clamped modes, e.g. cf1, here; pinned modes on a beam pinned in a system)")


def _named(spec, base, name):
    """Give a customised spec its name (a readable default with a content digest) and validate."""
    if name is None:
        digest = hashlib.sha256(json.dumps(replace(spec, name="x").to_dict(),
                                           sort_keys=True).encode()).hexdigest()[:8]
        name = f"{base.name}_custom_{digest}"
    spec = replace(spec, name=name)
    check_clamped_root(spec)
    return spec.validate()
