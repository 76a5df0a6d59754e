"""Planar mechanisms as data: bodies, markers, joints, drivers, loads, outputs (the spec layer).

A System is frozen data, validated structurally here (names, references, positive masses, a
spanning tree) before any derivation starts; nothing here knows the physics. The derivation
(flexsym/physics/assemble.py) reads a validated System.

Formulation (relative coordinates on a spanning tree): ground is the root; every body gets
exactly one *tree joint* (its parent), found by a breadth-first search from ground over the
joints in file order, always from a joint's declared parent to its child; every other joint is
a *cut joint* and becomes constraint equations. A flexible beam's tree joint must hold its root
marker (x = 0) as the joint's child: its floating frame is the root's tangent frame (the modes
are clamped at the root; modes with a free root slope, pp and pf, need a revolute joint there:
_check_pinned_roots), so joints elsewhere on a flexible body are never tree joints.
"""
from __future__ import annotations

import itertools
import math
import re
from collections import deque
from dataclasses import dataclass, field, fields, replace
from typing import NamedTuple

from flexsym.core.errors import SpecError
from flexsym.model.joint_kinds import KINDS
from flexsym.model.limits import MAX_BODIES, MAX_JOINTS, MIN_AXIS, check_number, check_positive, is_real
from flexsym.model.modes import ModeRef, root_slope_free
from flexsym.model.output_names import system_alias
from flexsym.model.variant import NAME_RE, TORSION_MODES  # one name rule for variants and systems (names become C identifiers)

GROUND = "ground"
JOINT_KINDS = tuple(KINDS)  # one module each: flexsym/model/joint_kinds/
DIMENSIONS = (2, 3)  # a planar system (the x-y plane) or a spatial one
# Joints closing a loop in 3D, by kind: their constraint rows (physics/spatial._cut_rows, the
# assembly's scenes/assembly.cut_axes), as data: the gap rows ("point": the two points coincide,
# three rows; "across": only across the axis, two rows along directions fixed in the parent) and
# the rotation rows ("": none; "cross": a universal joint's one; "axis": the child's axis stays
# parallel to the parent's, two; "lock": the relative rotation stays what it is at t = 0, three)
SPATIAL_CUT_ROWS = {k: kind.cut_rows for k, kind in KINDS.items() if 3 in kind.dimensions}
SPATIAL_JOINT_KINDS = tuple(SPATIAL_CUT_ROWS)
SPATIAL_STRAINS = ("linear", "geometric_stiffness", "foreshortening", "prestress")
STARTS = ("undeformed", "static")  # the flexible bodies at t = 0
DRIVER_KINDS = ("guided", "motor")
OUTPUT_FUNCTIONS = {  # name -> what its first argument names
    "angle": "joint", "rate": "joint", "reaction": "joint", "torque": "driver",
    # a joint's second coordinate (SECOND, Joint.coordinates): a cylindrical joint's slide, a
    # universal joint's second angle (in the tree)
    "slide": "joint", "slide_rate": "joint", "angle2": "joint", "rate2": "joint",
    "x": "marker", "y": "marker",
    "v": "beam", "u": "beam", "w": "beam", "N": "beam", "M": "beam", "sigma": "beam",
    # spatial systems only: the marker's ground z, the deflection along the beam frame's z, and
    # the section moments about the section's own x (torsion), y and z axes, and the shear
    # forces along its y and z axes; sigma takes (beam, x, y) in the plane, (beam, x, y, z) in 3D
    "z": "marker", "vz": "beam", "Mx": "beam", "My": "beam", "Mz": "beam", "Qy": "beam", "Qz": "beam",
    # and a marker's orientation: R(B.m, i, j), the ground axis i's component of its axis j
    "R": "marker",
}
# H: the angular momentum about the origin; Q: the shear forces
SPATIAL_ONLY = ("z", "vz", "Mx", "My", "Mz", "Qy", "Qz", "R", "Hx", "Hy", "Hz")
PLANAR_ONLY = ("M", "momentum")  # not in 3D: Mx, My, Mz and Hx, Hy, Hz
SIGMA_REACH = 10.0  # a section point lies within this many radii of gyration sqrt(I/A) of the axis
OUTPUT_SCALARS = ("T", "V", "momentum", "violation", "dissipation", "Hx", "Hy", "Hz")
# a section force or moment may name its recovery, N(B, x, equilibrium), over its beam model's
# axial_force (N) / moment (the moments): one run can carry both (output_beam)
RECOVERABLE = ("N", "M", "Mx", "My", "Mz")
OUTPUT_RECOVERIES = ("equilibrium", "constitutive")
# a section force, moment or stress may name the side of its station, x- or x+ (step-, 5.0+):
# where they jump (a step of the section, a point mass, a load at a marker), one side's value
SIDED = ("N", "M", "sigma", "Mx", "My", "Mz", "Qy", "Qz")
# reaction(joint, c) per dimension: the force's ground components, then the moment about the
# joint's child point (the plane's one, or its ground components)
REACTION_COMPONENTS = {2: ("x", "y", "moment"), 3: ("x", "y", "z", "mx", "my", "mz")}
# A joint's second coordinate, by its kind (Joint.coordinates): its motion, what it is, and
# the Joint fields of its value and rate at t = 0, which are also its initial table's keys and
# its outputs' functions; the value's field names it: J_slide, J_angle2 (the result column;
# with J_slide_rate, J_angle2_rate the names expressions use)
SECOND = {k: kind.second for k, kind in KINDS.items() if kind.second}
_OUTPUT_RE = re.compile(r"\s*([A-Za-z_][A-Za-z0-9_]*)\s*(?:\((.*)\))?\s*\Z")


def _finite(v) -> bool:
    return is_real(v) and math.isfinite(v)


def _numbers(item, label: str):
    """(label, value) of every number slot in a system's item (a dataclass), nested tuples,
    sections and (name, value) parameters included; its text fields (names, kinds,
    references, expressions), flags (a joint's `fixed`), an optional slot left None (a missing
    axis or rate) and a beam's deformation model (checked by its own validate) are not number
    slots, anything else in a slot is (and must be a real number)."""
    for f in fields(item):
        v = getattr(item, f.name)
        text = isinstance(v, str) or (isinstance(v, (tuple, list)) and v and all(isinstance(x, str) for x in v))
        if f.name == "model" or text or f.type == "bool" or (v is None and "None" in str(f.type)):
            continue  # no axis: a revolute or clamp joint (_check_joint decides); fixed: checked there
        if f.name == "params" and isinstance(v, (tuple, list)):
            for p in v:
                if isinstance(p, (tuple, list)) and len(p) == 2:
                    yield from _leaves(p[1], f"{label} {f.name} {p[0]}")
            continue
        yield from _leaves(v, f"{label} {f.name}")


def _leaves(v, label):
    if hasattr(v, "__dataclass_fields__"):
        yield from _numbers(v, label)
    elif isinstance(v, (tuple, list)):
        for k, x in enumerate(v):
            yield from _leaves(x, f"{label}[{k}]")
    else:
        yield label, v


def _name(what: str, name) -> None:
    if not isinstance(name, str) or not NAME_RE.match(name) or name == GROUND:
        raise SpecError(f"{what} name {name!r}: use lower-case letters, digits and _, starting "
                        f"with a letter (and not '{GROUND}')")


@dataclass(frozen=True)
class Section:
    """A uniform beam section and material (SI). I resists bending in the beam frame's x-y
    plane (deflection along y: the planar I, the spatial I_z); a spatial beam adds Iy (bending
    along z), J (St Venant torsion constant) and G (shear modulus)."""

    rho: float
    E: float
    A: float
    I: float
    Iy: float | None = None
    J: float | None = None
    G: float | None = None

    SPATIAL = ("Iy", "J", "G")

    def check(self, where: str, dimension: int = 2) -> None:
        for key in ("rho", "E", "A", "I") + (self.SPATIAL if dimension == 3 else ()):
            v = getattr(self, key)
            if v is None:
                raise SpecError(f"{where}: section {key} is missing (a spatial beam needs Iy, J "
                                "and G besides rho, E, A and I = Iz)")
            if not _finite(v) or v <= 0:
                raise SpecError(f"{where}: section {key} = {v!r} must be a finite number > 0")
            check_positive(v, f"{where}: section {key}")
        if dimension == 2:
            given = [k for k in self.SPATIAL if getattr(self, k) is not None]
            if given:
                raise SpecError(f"{where}: section {given[0]} applies to spatial systems "
                                "(dimension = 3) only")


@dataclass(frozen=True)
class Damping:
    """Structural damping of a flexible beam (a property of its material and section; none
    by default, and all zero adds nothing to the equations). Acts on the beam's elastic
    coordinates only (rigid-body motion is never damped), through a dissipation function D
    (generalised force -dD/dq'):

    beta (s): stiffness-proportional, the strain-rate (Kelvin-Voigt) form
        D = beta/2 int (EA eps'^2 + EI kappa'^2) dx with the model's own strain measures
        (modal: eps = u_x of the axial modes, kappa = v_xx, i.e. beta K q'; ef: the Green
        strain and material curvature of the element, i.e. beta dQ_el/dq q' at small strain);
    alpha (1/s): mass-proportional, D = alpha/2 q_e'^T M_ee q_e' (M_ee: the undeformed mass
        matrix of the elastic coordinates, their motion relative to the floating frame);
    zeta: modal damping ratios, one number for every mode or a list with one per coordinate
        of the model (in its order: axial modes, then bending; a spatial beam's: axial, bending
        v, bending vz, torsion, as beam_coordinates): a dashpot 2 zeta_i omega_i m_i
        on coordinate i, omega_i = sqrt(k_ii / m_ii) of the undeformed modal stiffness and
        mass (exact for natural modes, e.g. cf1, cf2; an approximation for a basis whose
        modes couple, e.g. static + cp1). Modal models only: ef has no modes (refused)."""

    zeta: object = 0.0  # a number or a tuple of numbers
    alpha: float = 0.0
    beta: float = 0.0

    @property
    def active(self) -> bool:
        return bool(self.alpha or self.beta or any(self.zetas(1)))

    def zetas(self, n: int) -> tuple[float, ...]:
        """The ratio of each of n coordinates."""
        if isinstance(self.zeta, (tuple, list)):
            return tuple(float(z) for z in self.zeta)
        return (float(self.zeta),) * n

    def check(self, where: str, model, coordinates=None) -> None:
        """The one place damping values are checked: finite numbers >= 0, zeta a number or
        one per coordinate of a modal model (coordinates: a spatial beam's names, else the
        model's)."""
        for key in ("alpha", "beta"):
            v = getattr(self, key)
            if not _finite(v) or v < 0:
                raise SpecError(f"{where}: damping {key} = {v!r} must be a finite number >= 0")
        zs = self.zeta if isinstance(self.zeta, (tuple, list)) else (self.zeta,)
        for z in zs:
            if not _finite(z) or z < 0:
                raise SpecError(f"{where}: damping zeta = {_show(self.zeta)} must be a finite "
                                "number >= 0 or a list of them")
        modal = getattr(model, "kind", None) == "modal"
        coords = tuple(coordinates if coordinates is not None else getattr(model, "coordinates", ()))
        if modal and isinstance(self.zeta, (tuple, list)) and len(self.zeta) != len(coords):
            raise SpecError(f"{where}: damping zeta has {len(self.zeta)} values, model "
                            f"'{model.name}' has {len(coords)} coordinates ({', '.join(coords)}): "
                            "give one per coordinate, or one number for all")
        if not any(zs):
            return
        if not modal:
            raise SpecError(f"{where}: damping zeta applies to modal models (a ratio per mode); "
                            "ef has no modes: give beta (and alpha), e.g. beta = 2 zeta / omega "
                            "for the ratio zeta at omega (docs/howto/mechanisms.md, Structural "
                            "damping)")


def _show(v) -> str:
    return repr(list(v)) if isinstance(v, (tuple, list)) else repr(v)


@dataclass(frozen=True)
class Marker:
    """A named point, in body-local coordinates (on a beam: x along the undeformed axis,
    y = z = 0; z: spatial systems only)."""

    name: str
    x: float
    y: float = 0.0
    z: float = 0.0


@dataclass(frozen=True)
class RigidBody:
    """mass (kg), inertia about the centre of mass (kg m^2), com and markers in the body frame.
    Spatial: inertia = (Ixx, Iyy, Izz), the principal moments along the body frame's axes, and
    com = (x, y, z)."""

    name: str
    mass: float
    inertia: object  # a number (planar) or three (spatial)
    com: tuple = (0.0, 0.0)
    markers: tuple[Marker, ...] = ()
    flexible = False

    @property
    def all_markers(self) -> tuple[Marker, ...]:
        return self.markers

    def check(self, dimension: int = 2) -> None:
        where = f"body '{self.name}'"
        if not _finite(self.mass) or self.mass <= 0:
            raise SpecError(f"{where}: mass {self.mass!r} must be a finite number > 0")
        check_positive(self.mass, f"{where}: mass")
        moments = self.inertia if dimension == 3 else (self.inertia,)
        if (not isinstance(moments, (tuple, list)) or len(moments) != (3 if dimension == 3 else 1)
                or not all(_finite(v) and v > 0 for v in moments)):
            what = "three finite numbers > 0 (Ixx, Iyy, Izz)" if dimension == 3 else "a finite number > 0"
            raise SpecError(f"{where}: inertia {self.inertia!r} must be {what}")
        for v in moments:
            check_positive(v, f"{where}: inertia")
        if dimension == 3 and any(a + b < c for a, b, c in itertools.permutations(moments)):
            raise SpecError(f"{where}: inertia {list(moments)} breaks the triangle inequality "
                            "(each principal moment <= the sum of the other two)")
        if len(self.com) != dimension or not all(_finite(c) for c in self.com):
            raise SpecError(f"{where}: com {self.com!r} must be {dimension} finite numbers")
        _check_markers(where, self.markers, dimension)


@dataclass(frozen=True)
class FlexibleBeam:
    """A straight beam along its frame's x axis, clamped at x = 0 in its floating frame: uniform
    (section), or with the sections and point masses of its model's finite-element data
    (model.body, a fedata.BeamBody; then length and section are the body's length and root
    section, the run-time parameters that scale it).

    model: the deformation model, a spec.VariantSpec (mode set + strain model) or a fe.FESpec
    ('ef' elements); only its deformation fields are used (its manoeuvre and outputs are not).
    Markers 'root' (x = 0) and 'tip' (x = length) always exist. damping: a Damping or None
    (undamped)."""

    name: str
    length: float
    section: Section
    model: object
    markers: tuple[Marker, ...] = ()
    damping: Damping | None = None
    flexible = True

    def __post_init__(self):
        # N and M of a beam in a mechanism come from equilibrium unless its model says
        # "constitutive": the modes' curvature is 5e-2 of the peak off at S1's clamped root
        # (equilibrium 2.6e-4) and reads a moment at a pinned end where there is none
        model = self.model
        if getattr(model, "kind", None) == "modal" and "auto" in (model.axial_force, model.moment):
            object.__setattr__(self, "model", replace(
                model, **{k: "equilibrium" for k in ("axial_force", "moment")
                          if getattr(model, k) == "auto"}))

    @property
    def damped(self) -> bool:
        return self.damping is not None and self.damping.active

    @property
    def all_markers(self) -> tuple[Marker, ...]:
        given = {m.name for m in self.markers}
        implied = tuple(m for m in (Marker("root", 0.0), Marker("tip", float(self.length)))
                        if m.name not in given)
        return implied + self.markers

    def check(self, dimension: int = 2) -> None:
        where = f"body '{self.name}'"
        if not _finite(self.length) or self.length <= 0:
            raise SpecError(f"{where}: length {self.length!r} must be a finite number > 0")
        check_positive(self.length, f"{where}: length")
        if not isinstance(self.section, Section):
            raise SpecError(f"{where}: section must be a Section(rho, E, A, I)")
        self.section.check(where, dimension)
        if getattr(self.model, "kind", None) not in ("modal", "fe"):
            raise SpecError(f"{where}: model must be a modal variant or 'ef' (got {self.model!r})")
        if dimension == 2 and self.model.kind == "modal" and self.model.torsion != TORSION_MODES:
            raise SpecError(f"{where}: torsion modes apply to spatial beams (a planar beam does not twist)")
        if self.damping is not None:
            if not isinstance(self.damping, Damping):
                raise SpecError(f"{where}: damping must be a Damping(zeta, alpha, beta) or None")
            spatial = dimension == 3 and getattr(self.model, "kind", None) == "modal"
            self.damping.check(where, self.model, [n for n, _, _ in beam_coordinates(self)] if spatial else None)
        _check_markers(where, self.markers, dimension)
        for m in self.markers:
            if m.y != 0 or m.z != 0:
                raise SpecError(f"{where}: marker '{m.name}' has y = {m.y}, z = {m.z}; markers on a "
                                "beam lie on its axis (y = z = 0)")
            if not 0 <= m.x <= self.length:
                raise SpecError(f"{where}: marker '{m.name}' at x = {m.x} is outside the beam "
                                f"(0 <= x <= {self.length})")
            if m.name in ("root", "tip") and m.x != {"root": 0.0, "tip": self.length}[m.name]:
                raise SpecError(f"{where}: marker '{m.name}' is reserved (root is x = 0, tip is "
                                "x = length)")


def beam_coordinates(beam: FlexibleBeam) -> list[tuple[str, str, ModeRef]]:
    """(coordinate name, group, mode) of a spatial modal beam: axial u_*, bending v_* (its
    frame's x-y plane) and vz_* (x-z plane) on the model's bending modes, torsion phi_*."""
    spec = beam.model
    out = [(r.coordinate, "axial", r) for r in spec.axial]
    out += [(r.coordinate, "bending", r) for r in spec.bending]
    out += [("vz_" + r.token, "bending", r) for r in spec.bending]
    out += [("phi_" + r.token, "torsion", r) for r in spec.torsion]
    return out


def _check_markers(where, markers, dimension: int = 2):
    seen = set()
    for m in markers:
        if not isinstance(m, Marker):
            raise SpecError(f"{where}: markers must be Marker(name, x, y)")
        _name(f"{where}: marker", m.name)
        if m.name in seen:
            raise SpecError(f"{where}: duplicate marker '{m.name}'")
        seen.add(m.name)
        if not (_finite(m.x) and _finite(m.y) and _finite(m.z)):
            raise SpecError(f"{where}: marker '{m.name}' position must be finite numbers")
        if dimension == 2 and m.z != 0:
            raise SpecError(f"{where}: marker '{m.name}' has z = {m.z}: a planar system's markers "
                            "lie in the x-y plane")


class JointCoordinate(NamedTuple):
    """One coordinate of a joint (Joint.coordinates)."""

    name: str
    motion: str  # "turn" about its axis or "slide" along it
    value: float  # at t = 0 (a guess the assembly may move)
    rate: float | None  # at t = 0 (None: 0, or what the loops need)
    axis: tuple  # a direction (normalised where used), in the frame it moves in (Joint.coordinates)


@dataclass(frozen=True)
class Joint:
    """parent, child: 'body.marker', or 'ground' (then `point` is the ground point).

    revolute: coordinate = relative angle, child frame angle = parent's + offset + q;
    prismatic: coordinate = displacement along `axis` (fixed in the parent, a unit vector after
    normalisation), child frame angle = parent's + offset; clamp: no coordinate, angle =
    parent's + offset; spherical (spatial systems): three rotations, as Euler parameters, the
    child's frame parallel to the parent's at t = 0, `rate` its angular velocity relative to the
    parent then (three numbers, parent's frame); cylindrical (spatial systems): a revolute's
    turn about `axis` and a prismatic's slide along it, `initial`/`rate` the angle's and
    `slide`/`slide_rate` the slide's (closing a spatial loop, a revolute, prismatic or
    cylindrical joint or a clamp has no coordinate: its rows, SPATIAL_CUT_ROWS, hold the child's
    motion relative to the parent as the joint allows it from the assembled start, its axis
    in the parent's frame); universal (spatial systems): closing a loop, the child's
    `axis` (child's frame) stays across a cross axis fixed in the parent (no coordinate); in
    the tree, two turns in series, about `parent_axis` (parent's frame) by the angle
    `initial`/`rate`, then about `axis` (child's frame) by `angle2`/`rate2` (Joint.coordinates
    names them all). `initial`: the coordinate at t = 0, a guess that the assembly at t = 0
    (flexsym/scenes/assembly.py) may move to close the loops, unless `fixed`; `rate`: its rate
    at t = 0 when given (None: 0, or what the loops need)."""

    name: str
    kind: str
    parent: str
    child: str
    axis: tuple[float, float] | None = None
    offset: float = 0.0
    point: tuple[float, float] = (0.0, 0.0)
    initial: float = 0.0
    fixed: bool = False
    rate: float | None = None
    direction: tuple | None = None  # spatial spherical: the child's x axis at t = 0 (parent's frame)
    slide: float = 0.0  # cylindrical: the slide's initial value (m) ...
    slide_rate: float | None = None  # ... and its rate at t = 0 (m/s; None: 0, or what the loops need)
    parent_axis: tuple | None = None  # universal in the tree: the first turn's axis (parent's frame)
    angle2: float = 0.0  # universal in the tree: the second angle (about axis) at t = 0 (rad) ...
    rate2: float | None = None  # ... and its rate (rad/s; None: 0, or what the loops need)

    @property
    def has_coordinate(self) -> bool:
        return bool(self.coordinates)

    @property
    def coordinates(self) -> tuple[JointCoordinate, ...]:
        """The joint's coordinates in the order of q, each moving the child in series after the
        ones before it: the one place they are named. A revolute joint's angle (a turn about its
        axis, default z) and a prismatic joint's displacement (a slide along it) carry the
        joint's name (outputs angle(J), rate(J); initial, rate); a joint with two (SECOND)
        names its second J_<field>: a cylindrical joint turns about its axis, then slides along
        it (J_slide: slide(J), slide_rate(J); initial slide, slide_rate); a universal joint in
        the tree (it has parent_axis) turns about parent_axis, then about axis in the turned
        frame, the child's (J_angle2: angle2(J), rate2(J); initial angle2, rate2). A universal
        joint closing a loop, a spherical joint (Euler parameters, physics/spatial.py) and a
        clamp have none."""
        kind = KINDS.get(self.kind)
        if kind is None:
            return ()  # _check_joint refuses it
        starts = [(self.name, self.initial, self.rate)]
        if kind.second:
            value, rate = kind.second[2:]
            starts.append((f"{self.name}_{value}", getattr(self, value), getattr(self, rate)))
        return tuple(JointCoordinate(name, motion, value, rate, axis) for (name, value, rate), motion, axis
                     in zip(starts, kind.motions_of(self), kind.axes(self)))

    def fields_of(self, coordinate: str) -> tuple[str, str]:
        """The Joint fields of a coordinate's value and rate at t = 0 (Joint.coordinates)."""
        return ("initial", "rate") if coordinate == self.name else SECOND[self.kind][2:]


@dataclass(frozen=True)
class Driver:
    """guided: the tree joint's coordinate is theta(t), a named manoeuvre (`maneuver`, with
    `params` as (name, value) pairs) or `expression` of t; motor: a generalised force on it,
    `expression` of t and of named joint coordinates and rates (J and J_rate). A joint with two
    coordinates (Joint.coordinates, spatial systems) is driven in its first (coordinate "": a
    cylindrical joint's turn, a tree universal joint's first angle) or, with `coordinate` its
    second's field (SECOND: "slide", "angle2"), in its second (System.driven)."""

    name: str
    kind: str
    joint: str
    expression: str = ""
    maneuver: str = ""
    params: tuple[tuple[str, float], ...] = ()
    coordinate: str = ""  # "" the joint's first coordinate, or its second's field ("slide", "angle2")


@dataclass(frozen=True)
class Gravity:
    g: tuple[float, float] = (0.0, -9.81)


@dataclass(frozen=True)
class PointForce:
    marker: str  # "body.marker"
    fx: float
    fy: float
    frame: str = "ground"  # or "body": components in the body's frame
    name: str = ""
    fz: float = 0.0  # spatial systems


@dataclass(frozen=True)
class Torque:
    """A torque on a body: planar, one expression (about z); spatial, three (tx, ty, tz) in the
    ground's or the body's axes (frame)."""

    body: str
    expression: str | tuple[str, str, str]
    name: str = ""
    frame: str = "ground"


@dataclass(frozen=True)
class SpringDamper:
    """A linear spring-damper between two points: force k (l - l0) + c l' along the line
    (V = k (l - l0)^2 / 2; l0 = 0: V = k * abs(r_b - r_a)^2 / 2, smooth at l = 0)."""

    a: str  # "body.marker" or "ground" (at point_a)
    b: str
    k: float
    c: float = 0.0
    l0: float = 0.0
    name: str = ""
    point_a: tuple[float, float] = (0.0, 0.0)
    point_b: tuple[float, float] = (0.0, 0.0)


@dataclass(frozen=True)
class Output:
    column: str
    quantity: str


@dataclass(frozen=True)
class Tree:
    """The spanning-tree decision: each body's tree joint (body -> joint name), bodies in
    breadth-first order (parents before children), and the cut joints in file order."""

    parent_joint: tuple[tuple[str, str], ...]
    order: tuple[str, ...]
    cut: tuple[str, ...]

    def joint_of(self, body: str) -> str:
        return dict(self.parent_joint)[body]

    def subtree(self, system: "System", joint: str) -> set[str]:
        """The bodies whose path to ground passes through tree joint `joint`."""
        out = set()
        for body in self.order:
            b = body
            while True:
                j = system.joint(self.joint_of(b))
                if j.name == joint:
                    out.add(body)
                    break
                if j.parent == GROUND:
                    break
                b = system.marker(j.parent)[0]
        return out


@dataclass(frozen=True)
class System:
    name: str
    bodies: tuple = ()
    joints: tuple[Joint, ...] = ()
    drivers: tuple[Driver, ...] = ()
    loads: tuple = ()
    outputs: tuple[Output, ...] = ()
    params: tuple[tuple[str, float], ...] = ()
    description: str = field(default="", compare=False)
    start: str = "undeformed"  # or "static": elastic coordinates in equilibrium at t = 0
    dimension: int = 2  # 3: a spatial system (physics/spatial.py)
    # A one-beam variant's S0 (library.variant_system): its beam's coordinates keep the
    # variant's names (v_static, ux1; a system's carry the body's: beam_v_static)
    one_beam: bool = False

    # ----- lookups ----------------------------------------------------------------------
    def body(self, name: str):
        for b in self.bodies:
            if b.name == name:
                return b
        raise SpecError(f"system '{self.name}': unknown body '{name}'")

    def beam_param(self, beam: str, name: str) -> str:
        """The run-time parameter of a flexible body's length or section value (rho, E, A, I,
        L; in 3D also Iy, J, G): its plain name for a system's only beam, as a one-beam
        variant's, else beam_name."""
        return name if sum(b.flexible for b in self.bodies) == 1 else f"{beam}_{name}"

    def joint(self, name: str) -> Joint:
        for j in self.joints:
            if j.name == name:
                return j
        raise SpecError(f"system '{self.name}': unknown joint '{name}'")

    def marker(self, ref: str) -> tuple[str, Marker]:
        """'body.marker' -> (body name, Marker)."""
        body, _, mname = ref.partition(".")
        b = self.body(body)
        for m in b.all_markers:
            if m.name == mname:
                return body, m
        known = ", ".join(m.name for m in b.all_markers) or "none"
        raise SpecError(f"system '{self.name}': body '{body}' has no marker '{mname}' "
                        f"(its markers: {known})")

    def driven(self, d: Driver) -> str:
        """The name of the coordinate driver d drives (Joint.coordinates): its joint's first (the
        joint's own name), or its second (J_slide, J_angle2) with coordinate = its field."""
        return self.joint(d.joint).coordinates[1].name if d.coordinate else d.joint

    def reserved_columns(self) -> dict:
        """Names the results already use besides the outputs -> what they are: t, violation,
        T, V, h (energy), every joint (its coordinate) and every elastic coordinate."""
        taken = {"t": "the time", "violation": "the constraint violation", "T": "the kinetic energy",
                 "V": "the potential energy", "h": "the energy's step error"}
        taken |= {j.name: f"joint '{j.name}'" for j in self.joints if isinstance(j, Joint)}
        taken |= {c.name: f"the {SECOND[j.kind][1]} of joint '{j.name}'" for j in self.joints
                  if isinstance(j, Joint) for c in j.coordinates if c.name != j.name}
        taken |= {f"{j.name}_e{k}": f"an Euler parameter of joint '{j.name}'" for j in self.joints
                  if isinstance(j, Joint) and getattr(KINDS.get(j.kind), "euler", False) for k in range(4)}
        for b in self.bodies:
            if getattr(b, "flexible", False):
                names = (getattr(b.model, "coordinates", ()) if self.dimension == 2 or
                         getattr(b.model, "kind", None) != "modal" else
                         [n for n, _, _ in beam_coordinates(b)])
                taken |= {f"{b.name}_{c}": f"an elastic coordinate of '{b.name}'" for c in names}
        return taken

    def tree(self) -> Tree:
        return spanning_tree(self)

    def frame_driven(self, body: str) -> bool:
        """Whether the body's frame moves by the drives alone (a function of t): every tree
        joint between it and ground is a clamp or guided, and no body on the way is flexible (a
        body hung from a beam's marker moves with its deformation). A spatial ef beam's element
        kinetic energy is then a C kernel; otherwise it needs the system's AD path
        (physics/spatial_ef)."""
        tree, guided = self.tree(), {self.driven(d) for d in self.drivers if d.kind == "guided"}
        while body != GROUND:
            j = self.joint(tree.joint_of(body))
            if not KINDS[j.kind].welds and not (j.coordinates and all(c.name in guided for c in j.coordinates)):
                return False
            body = j.parent.partition(".")[0] if j.parent != GROUND else GROUND
            if body != GROUND and self.body(body).flexible:
                return False
        return True

    # ----- structural validation ---------------------------------------------------------
    def validate(self) -> "System":
        _name("system", self.name)
        where = f"system '{self.name}'"
        if not self.bodies:
            raise SpecError(f"{where}: no bodies")
        for what, items, types in (("body", self.bodies, (RigidBody, FlexibleBeam)), ("joint", self.joints, (Joint,)),
                                   ("driver", self.drivers, (Driver,)), ("output", self.outputs, (Output,)),
                                   ("load", self.loads, (Gravity, PointForce, Torque, SpringDamper))):
            if not isinstance(items, (tuple, list)) or not all(isinstance(x, types) for x in items):
                kinds = " or ".join(t.__name__ for t in types)
                raise SpecError(f"{where}: {what} entries must be {kinds} (got {items!r:.80})")
        for what, items, limit in (("bodies", self.bodies, MAX_BODIES), ("joints", self.joints, MAX_JOINTS)):
            if len(items) > limit:
                raise SpecError(f"{where}: {len(items)} {what}, more than the limit of {limit} (the "
                                "derivation's cost grows quickly with the number of bodies)")
        self._check_magnitudes()
        if type(self.dimension) is not int or self.dimension not in DIMENSIONS:
            raise SpecError(f"{where}: dimension {self.dimension!r} must be 2 (planar) or 3 (spatial)")
        n = self.dimension
        names: dict[str, str] = {}
        for what, items in (("body", self.bodies), ("joint", self.joints),
                            ("driver", self.drivers)):
            for item in items:
                _name(f"{where}: {what}", item.name)
                if item.name in names:
                    raise SpecError(f"{where}: duplicate name '{item.name}' ({names[item.name]} "
                                    f"and {what})")
                names[item.name] = what
        for b in self.bodies:
            if not isinstance(b, (RigidBody, FlexibleBeam)):
                raise SpecError(f"{where}: body {b!r} is not a RigidBody or FlexibleBeam")
            b.check(n)
        if n == 3:
            self._check_spatial()
        for j in self.joints:
            self._check_joint(j)
        connected = {r.partition(".")[0] for j in self.joints for r in (j.parent, j.child)}
        for b in self.bodies:
            if b.name not in connected:
                raise SpecError(f"{where}: body '{b.name}' is connected to nothing (no joint "
                                "names it)")
        tree = spanning_tree(self)
        for name in tree.cut if n == 3 else ():
            j = self.joint(name)
            given = [k for k, v in (("initial", j.initial), ("slide", j.slide), ("angle2", j.angle2))
                     if v != 0] + [k for k, v in (("rate", j.rate), ("slide_rate", j.slide_rate),
                                                  ("rate2", j.rate2)) if v is not None]
            if not KINDS[j.kind].euler and (given or j.fixed):
                raise SpecError(f"{where}: joint '{name}' closes a loop: {', '.join(given or ['fixed'])} "
                                "applies to joints in the tree (a joint closing a loop has no "
                                "coordinate: its rows hold the child's relative motion)")
        for j in self.joints if n == 3 else ():  # a spatial ef beam's section: at its nodes
            for ref in (j.parent, j.child):
                self._check_ef_node(ref, f"{where}: joint '{j.name}'")
        for j in self.joints:
            KINDS[j.kind].check_in_tree(j, j.name in tree.cut, f"{where}: joint '{j.name}'")
        self._check_pinned_roots(tree)
        guided = set()
        for d in self.drivers:
            self._check_driver(d, tree, guided)
        for load in self.loads:
            self._check_load(load)
        columns = set()
        taken = self.reserved_columns()
        for o in self.outputs:
            if not isinstance(o, Output):
                raise SpecError(f"{where}: outputs must be Output(column, quantity)")
            if not isinstance(o.column, str) or not re.match(r"[A-Za-z][A-Za-z0-9_]{0,47}\Z",
                                                              o.column) or o.column == "t":
                raise SpecError(f"{where}: output column {o.column!r}: use letters, digits and _ "
                                "(not 't')")
            if o.column in columns:
                raise SpecError(f"{where}: duplicate output column '{o.column}'")
            same = isinstance(o.quantity, str) and o.column == o.quantity.strip()  # T = "T": itself
            if o.column in taken and not same:
                raise SpecError(f"{where}: output column '{o.column}' is already the name of "
                                f"{taken[o.column]} in the results (choose another name)")
            columns.add(o.column)
            fn, args = parse_output(self, o.quantity)
            if n == 2 and fn in SPATIAL_ONLY:
                raise SpecError(f"{where}: output '{o.quantity}': {fn} applies to spatial systems "
                                "(dimension = 3) only")
            if n == 3 and fn == "R":
                self._check_ef_node(args[0], f"{where}: output '{o.quantity}'")
            if n == 3 and fn in PLANAR_ONLY:
                hint = " (use Mx, My or Mz: the torsion and bending moments)" if fn == "M" else ""
                raise SpecError(f"{where}: output '{o.quantity}': {fn} is not derived for spatial "
                                f"systems yet{hint}")
        for p in self.params:
            if len(p) != 2 or not NAME_RE.match(str(p[0])) or not _finite(p[1]):
                raise SpecError(f"{where}: parameter {p!r} must be (name, finite number)")
        if self.start not in STARTS:
            raise SpecError(f"{where}: start {self.start!r} must be one of {', '.join(STARTS)}")
        if self.start == "static":
            if not any(b.flexible for b in self.bodies):
                raise SpecError(f"{where}: start = \"static\" puts the flexible bodies in equilibrium, "
                                "and there is none")
        return self

    def _check_ef_node(self, ref: str, where: str) -> None:
        """A spatial ef beam's section is derived at its elements' nodes (its rotation vector
        coordinates): a marker that a joint or an orientation reads must sit on one."""
        if ref == GROUND:
            return
        body, m = self.marker(ref)
        b = self.body(body)
        if getattr(getattr(b, "model", None), "kind", None) != "fe":
            return
        n = b.model.elements
        k = m.x / b.length * n
        if abs(k - round(k)) > 1e-9:
            raise SpecError(f"{where}: marker '{ref}' at x = {m.x:g} m is not on a node of the ef "
                            f"beam's {n} elements (every {b.length / n:g} m): a spatial ef beam's "
                            "section is derived at its nodes; move the marker or change the elements")

    def _check_pinned_roots(self, tree: Tree) -> None:
        """A beam with bending modes whose root slope is free (pp: its frame is the chord's, not
        the root section's) is a beam pinned at its root: its tree joint must be a planar
        revolute whose angle nothing prescribes or loads (no driver, not fixed), and no torque
        acts on its frame. A clamp or prismatic joint there holds the root section, which those
        modes cannot (use clamped modes, cf, on a clamped root)."""
        for b in self.bodies:
            if not b.flexible or getattr(b.model, "kind", None) != "modal":
                continue
            free = [m.token for m in b.model.bending if root_slope_free(m)]
            why = self.unpinned_root(tree, b) if free else ""
            if why:
                raise SpecError(f"system '{self.name}': body '{b.name}': bending mode {free[0]} leaves "
                                f"the root slope free (the frame is the chord's), so the root must be "
                                f"pinned{why}")

    def unpinned_root(self, tree: Tree, b) -> str:
        """Why beam b's root is not a free pin ('' when it is), as the end of
        _check_pinned_roots' message: it must be a planar revolute joint that no driver turns,
        not fixed, with no torque on the beam (all would act on the frame those modes move).
        end_modes chooses such modes only where this is ''."""
        if self.dimension == 3:
            return ": not derived for spatial systems (use cf modes)"
        j = self.joint(tree.joint_of(b.name))
        if j.kind != "revolute":
            return f", not held by a {j.kind} joint ('{j.name}': use cf modes)"
        if j.fixed:
            return f": joint '{j.name}' is fixed, a clamp (use cf modes)"
        d = next((d for d in self.drivers if d.joint == j.name), None)
        if d is not None:
            return (f": driver '{d.name}' on joint '{j.name}' would turn the chord, not the root "
                    "section (use cf modes)")
        if any(isinstance(load, Torque) and load.body == b.name for load in self.loads):
            return f": a torque on '{b.name}' would act on the chord frame, not on a section (use cf modes)"
        return ""

    def _check_spatial(self) -> None:
        """What the spatial derivation (physics/spatial.py) supports so far, refused in one line
        before any work: revolute, prismatic, cylindrical, universal, spherical and clamp joints
        in a tree, modal beams (uniform, or from finite-element data with spatial sections) or
        the geometrically exact ef (rod3d: uniform)."""
        where = f"system '{self.name}'"
        for j in self.joints:
            if j.kind not in SPATIAL_JOINT_KINDS:
                raise SpecError(f"{where}: joint '{j.name}': a {j.kind} joint is not derived for "
                                f"spatial systems yet (derived: {', '.join(SPATIAL_JOINT_KINDS)})")
        for b in self.bodies:
            if not b.flexible:
                continue
            body = b.model.body
            if body is not None and not body.spatial:
                raise SpecError(f"{where}: body '{b.name}': its finite-element data are planar (a "
                                "spatial beam's elements need inertia_y, inertia_z, torsion_constant "
                                "and shear_modulus)")
            if getattr(b.model, "kind", None) == "fe":
                if body is not None and (len(set(body.sections)) > 1 or body.masses):
                    raise SpecError(f"{where}: body '{b.name}': the spatial ef is a uniform rod; "
                                    "this body's sections vary or carry point masses (run a modal "
                                    "model, or give the uniform section)")
                continue  # the geometrically exact rod (physics/rod3d.py), uniform
            if b.model.strain not in SPATIAL_STRAINS:
                raise SpecError(f"{where}: body '{b.name}': strain model '{b.model.strain}' is not "
                                f"derived in 3D (derived: {', '.join(SPATIAL_STRAINS)})")
            if b.model.stress != "continuum":
                raise SpecError(f"{where}: body '{b.name}': the element stress method ('{b.model.stress}') "
                                "is the plane's (the paper's eqs. 22-25); a spatial beam's N and "
                                "moments are continuum or from equilibrium")

    def _check_magnitudes(self) -> None:
        """Every number of the system: a real number (not bool, complex, str, None), finite and
        |x| <= MAX_MAGNITUDE (flexsym/model/limits.py), before anything else uses it."""
        where = f"system '{self.name}'"
        for kind, items in (("body", self.bodies), ("joint", self.joints), ("driver", self.drivers),
                            ("load", self.loads)):
            for k, item in enumerate(items):
                if not hasattr(item, "__dataclass_fields__"):
                    continue  # the type checks below name it
                name = getattr(item, "name", "") or f"#{k + 1}"
                for label, v in _numbers(item, f"{where}: {kind} '{name}'"):
                    check_number(v, label)
        for p in self.params:
            if isinstance(p, tuple) and len(p) == 2:
                check_number(p[1], f"{where}: parameter {p[0]!r}")

    def _check_joint(self, j: Joint) -> None:
        where = f"system '{self.name}': joint '{j.name}'"
        if j.kind not in JOINT_KINDS:
            raise SpecError(f"{where}: kind '{j.kind}' is not one of {', '.join(JOINT_KINDS)}")
        bodies = []
        for side in ("parent", "child"):
            ref = getattr(j, side)
            if ref == GROUND:
                if side == "child":
                    raise SpecError(f"{where}: the child cannot be ground (make ground the parent)")
                bodies.append(GROUND)
                continue
            if not isinstance(ref, str) or "." not in ref:
                raise SpecError(f"{where}: {side} {ref!r} must be 'body.marker' or 'ground'")
            body = ref.partition(".")[0]
            if body not in {b.name for b in self.bodies}:
                raise SpecError(f"{where}: {side} '{ref}' names an unknown body '{body}'")
            try:
                self.marker(ref)
            except SpecError as exc:
                raise SpecError(f"{where}: {side} '{ref}': {str(exc).split(': ', 1)[1]}") from None
            bodies.append(body)
        if bodies[0] == bodies[1]:
            raise SpecError(f"{where}: joins body '{bodies[0]}' to itself")
        n = self.dimension
        jkind = KINDS[j.kind]
        if n not in jkind.dimensions:  # a planar cylindrical: a revolute or a prismatic
            raise SpecError(f"{where}: a {j.kind} joint applies to spatial systems (dimension = 3) only")
        if j.direction is not None:
            d = j.direction
            if j.kind != "spherical" or n != 3:
                raise SpecError(f"{where}: direction applies to spatial spherical joints only")
            if (not isinstance(d, (tuple, list)) or len(d) != 3 or not all(_finite(c) for c in d)
                    or math.hypot(*d) < MIN_AXIS):
                raise SpecError(f"{where}: direction {d!r} must be three finite numbers, not all 0 "
                                "(the child's x axis at t = 0, in the parent's frame)")
        if n in jkind.axis_needed or (n in jkind.axis_dims and j.axis is not None):
            ax, count, frame = j.axis, ("two", "three")[n - 2], jkind.axis_frame
            if ax is None or len(ax) != n or not all(_finite(a) for a in ax) or not any(ax):
                raise SpecError(f"{where}: a {j.kind} joint needs an axis ({count} finite numbers, "
                                f"not all 0) in the {frame} frame")
            if math.hypot(*ax) < MIN_AXIS:
                raise SpecError(f"{where}: axis {list(ax)} is shorter than {MIN_AXIS:g} (it is a "
                                f"direction, normalised: write e.g. {[1] + [0] * (n - 1)})")
        elif j.axis is not None:
            takes = [k for k, other in KINDS.items() if n in other.axis_dims]
            raise SpecError(f"{where}: axis applies to {', '.join(takes[:-1]) + ' and ' if takes[1:] else ''}"
                            f"{takes[-1]} joints only")
        jkind.check(j, n, where)
        if n == 3 and j.offset != 0:
            raise SpecError(f"{where}: offset (a planar angle) does not apply to spatial joints: "
                            "the child's frame starts parallel to the parent's")
        for key in ("offset", "initial") + tuple(v[2] for v in SECOND.values()):
            if not _finite(getattr(j, key)):
                raise SpecError(f"{where}: {key} {getattr(j, key)!r} must be a finite number")
        own = SECOND[j.kind][2:] if len(j.coordinates) == 2 else ()
        for kind, (_, _, value, rate) in SECOND.items():  # a second coordinate's start values
            if (value, rate) != own and (getattr(j, value) != 0 or getattr(j, rate) is not None):
                raise SpecError(f"{where}: {value} and {rate} apply to {kind} joints only"
                                + (" in the tree (with parent_axis)" if kind == "universal" else ""))
            if getattr(j, rate) is not None and not _finite(getattr(j, rate)):
                raise SpecError(f"{where}: {rate} {getattr(j, rate)!r} must be a finite number")
        if not isinstance(j.fixed, bool):
            raise SpecError(f"{where}: fixed {j.fixed!r} must be true or false")
        if (j.fixed or j.rate is not None) and not j.has_coordinate and not jkind.euler:
            raise SpecError(f"{where}: a {j.kind} joint has no coordinate to fix or give a rate")
        if (j.parent == GROUND or any(j.point)) and (len(j.point) != n or not all(_finite(c) for c in j.point)):
            raise SpecError(f"{where}: point {j.point!r} must be {('two', 'three')[n - 2]} finite numbers")

    def _check_driver(self, d: Driver, tree: Tree, guided: set) -> None:
        where = f"system '{self.name}': driver '{d.name}'"
        if d.kind not in DRIVER_KINDS:
            raise SpecError(f"{where}: kind '{d.kind}' is not one of {', '.join(DRIVER_KINDS)}")
        if d.joint not in {j.name for j in self.joints}:
            raise SpecError(f"{where}: joint '{d.joint}' does not exist")
        j = self.joint(d.joint)
        if not j.has_coordinate:
            raise SpecError(f"{where}: joint '{d.joint}' is a {j.kind} (no coordinate to drive)")
        if d.joint in tree.cut:
            raise SpecError(f"{where}: joint '{d.joint}' is a cut joint (it closes a loop); drive "
                            "a tree joint")
        if not isinstance(d.coordinate, str):
            raise SpecError(f"{where}: coordinate {d.coordinate!r} must be a string")
        second = SECOND[j.kind][2] if len(j.coordinates) == 2 else None
        if d.coordinate and d.coordinate != second:
            names = ", ".join(f"'{c.name}'" for c in j.coordinates)
            hint = (f"coordinate = \"{second}\" drives its second, none its first" if second else
                    "it has one: give no coordinate")
            raise SpecError(f"{where}: joint '{d.joint}' ({j.kind}) has no coordinate '{d.coordinate}' "
                            f"(its coordinates: {names}; {hint})")
        driven = self.driven(d)
        if driven in guided:
            raise SpecError(f"{where}: joint '{d.joint}' already has a guided driver"
                            + (f" on its coordinate '{driven}'" if len(j.coordinates) > 1 else ""))
        if d.kind == "guided":
            if bool(d.expression) == bool(d.maneuver):
                raise SpecError(f"{where}: a guided driver needs exactly one of maneuver or "
                                "expression")
            if any((x.joint, x.coordinate) == (d.joint, d.coordinate) and x.kind == "motor" for x in self.drivers):
                raise SpecError(f"{where}: joint '{d.joint}' is guided and also has a motor")
            rate = getattr(j, j.fields_of(driven)[1])
            if j.fixed or rate is not None:
                raise SpecError(f"{where}: joint '{d.joint}' is guided: its coordinate and rate at "
                                "t = 0 are the driver's theta(0), theta'(0) (no fixed, no rate)")
            guided.add(driven)
        else:
            if not d.expression or d.maneuver:
                raise SpecError(f"{where}: a motor driver needs an expression (and no maneuver)")
        for p in d.params:
            if len(p) != 2 or not isinstance(p[0], str) or not _finite(p[1]):
                raise SpecError(f"{where}: parameter {p!r} must be (name, finite number)")

    def _check_load(self, load) -> None:
        where = f"system '{self.name}': load {getattr(load, 'name', '') or type(load).__name__}"
        n = self.dimension
        if n == 3 and not isinstance(load, (Gravity, PointForce, SpringDamper, Torque)):
            raise SpecError(f"{where}: a {type(load).__name__} is not derived for spatial systems "
                            "yet (gravity, point forces, torques and spring-dampers are)")
        if isinstance(load, Gravity):
            if len(load.g) != n or not all(_finite(c) for c in load.g):
                raise SpecError(f"{where}: g {load.g!r} must be {('two', 'three')[n - 2]} finite numbers")
        elif isinstance(load, PointForce):
            self._ref(where, load.marker)
            if not (_finite(load.fx) and _finite(load.fy) and _finite(load.fz)):
                raise SpecError(f"{where}: fx, fy, fz must be finite numbers")
            if n == 2 and load.fz != 0:
                raise SpecError(f"{where}: fz applies to spatial systems (dimension = 3) only")
            if load.frame not in ("ground", "body"):
                raise SpecError(f"{where}: frame '{load.frame}' must be 'ground' or 'body'")
        elif isinstance(load, Torque):
            self.body(load.body)  # refuses an unknown body
            if n == 3 and (not isinstance(load.expression, (tuple, list)) or len(load.expression) != 3):
                raise SpecError(f"{where}: a spatial torque is three expressions [tx, ty, tz] "
                                f"(got {load.expression!r:.80})")
            for e in (load.expression if n == 3 else (load.expression,)):
                if not isinstance(e, str) or not e.strip():
                    raise SpecError(f"{where}: empty torque expression")
            if n == 2 and load.frame != "ground":
                raise SpecError(f"{where}: frame applies to spatial torques ([system] dimension = 3): "
                                "a planar torque is about z")
            if load.frame not in ("ground", "body"):
                raise SpecError(f"{where}: frame '{load.frame}' must be 'ground' or 'body' (the "
                                "spatial torque's axes)")
        elif isinstance(load, SpringDamper):
            for end, ref, point in (("a", load.a, load.point_a), ("b", load.b, load.point_b)):
                if ref != GROUND:
                    self._ref(where, ref)
                elif len(point) != n or not all(_finite(c) for c in point):
                    raise SpecError(f"{where}: point_{end} {point!r} (its ground end) must be "
                                    f"{('two', 'three')[n - 2]} finite numbers")
            for key in ("k", "c", "l0"):
                v = getattr(load, key)
                if not _finite(v) or v < 0:
                    raise SpecError(f"{where}: {key} {v!r} must be a finite number >= 0")
        else:
            raise SpecError(f"{where}: unknown load type {type(load).__name__}")

    def _ref(self, where, ref):
        if not isinstance(ref, str) or "." not in ref:
            raise SpecError(f"{where}: {ref!r} must be 'body.marker'")
        try:
            return self.marker(ref)
        except SpecError as exc:
            raise SpecError(f"{where}: {str(exc).split(': ', 1)[1]}") from None


_SPATIAL_DEFAULTS = {"Iy": None, "J": None, "G": None, "z": 0.0, "fz": 0.0, "dimension": 2,
                     "direction": None, "slide": 0.0, "slide_rate": None, "parent_axis": None,
                     "angle2": 0.0, "rate2": None, "coordinate": "",
                     "one_beam": False}


def system_to_dict(system: System) -> dict:
    """Canonical content of a system (what generated code depends on): every field, a flexible
    body's model as its variant's to_dict(); a beam's damping only when given (an undamped
    system's content is what it was before damping existed)."""
    def item(x):
        out = {"type": type(x).__name__}
        for f in fields(x):
            v = getattr(x, f.name)
            if f.name in _SPATIAL_DEFAULTS and v == _SPATIAL_DEFAULTS[f.name]:
                continue  # a planar system's content is what it was before 3D existed
            if f.name == "damping":
                if v is not None:
                    out[f.name] = {"zeta": list(v.zeta) if isinstance(v.zeta, (tuple, list)) else v.zeta,
                                   "alpha": v.alpha, "beta": v.beta}
                continue
            if f.name == "model":
                v = v.to_dict()
            elif isinstance(v, Section):
                v = item(v)
            elif isinstance(v, tuple):
                v = [item(e) if hasattr(e, "__dataclass_fields__") else
                     (list(e) if isinstance(e, tuple) else e) for e in v]
            out[f.name] = v
        return out
    d = item(system)
    d.pop("description", None)
    if d.get("start") == "undeformed":  # the default: the same content as before it existed
        d.pop("start")
    return d


def spanning_tree(system: System) -> Tree:
    """Breadth-first search from ground over the joints in file order (see the module doc)."""
    where = f"system '{system.name}'"
    parent_of = {}
    order = []
    queue = deque([GROUND])
    seen = {GROUND}
    by_parent: dict[str, list] = {}  # joints by their parent body, in file order (linear)
    for j in system.joints:
        by_parent.setdefault(j.parent.partition(".")[0] if j.parent != GROUND else GROUND, []).append(j)
    while queue:
        here = queue.popleft()
        for j in by_parent.get(here, ()):
            cbody = j.child.partition(".")[0]
            if cbody in seen:
                continue
            child = system.body(cbody)
            if child.flexible and system.marker(j.child)[1].x != 0:
                continue  # a flexible body hangs from its root only
            parent_of[cbody] = j.name
            order.append(cbody)
            seen.add(cbody)
            queue.append(cbody)
    for b in system.bodies:
        if b.name not in seen:
            if b.flexible:
                raise SpecError(f"{where}: flexible body '{b.name}' is not reached from ground by "
                                f"a joint whose child is '{b.name}.root' (its floating frame is "
                                "the root's; attach it there, parent side towards ground)")
            raise SpecError(f"{where}: body '{b.name}' is not connected to ground through joints "
                            "(parent side towards ground)")
    tree_joints = set(parent_of.values())
    cut = tuple(j.name for j in system.joints if j.name not in tree_joints)
    return Tree(tuple(parent_of.items()), tuple(order), cut)


def parse_output(system: System, quantity: str) -> tuple[str, tuple[str, ...]]:
    """'fn(a, b)' or a scalar name -> (fn, args), checking that the names exist."""
    where = f"system '{system.name}': output '{quantity}'"
    alias = one_beam_alias(system, quantity, where) if isinstance(quantity, str) else None
    if alias is not None:
        return parse_output(system, alias)
    m = _OUTPUT_RE.match(quantity) if isinstance(quantity, str) else None
    if not m:
        raise SpecError(f"{where}: not of the form name(args)")
    fn, argtext = m.group(1), m.group(2)
    if argtext is None:
        if fn not in OUTPUT_SCALARS:
            raise SpecError(f"{where}: unknown quantity (known: {', '.join(OUTPUT_SCALARS)}, "
                            f"{', '.join(f + '(...)' for f in OUTPUT_FUNCTIONS)}; and on a system's "
                            "one flexible beam v_tip, u_tip, N_A, M_B, M@0.25, M_<marker>)")
        return fn, ()
    if fn not in OUTPUT_FUNCTIONS:
        raise SpecError(f"{where}: unknown function '{fn}' (known: {', '.join(OUTPUT_FUNCTIONS)})")
    args = tuple(a.strip() for a in argtext.split(","))
    kind = OUTPUT_FUNCTIONS[fn]
    if kind == "joint":
        if fn == "reaction":
            allowed = REACTION_COMPONENTS[system.dimension]
            if len(args) != 2 or args[1] not in allowed:
                raise SpecError(f"{where}: needs (joint, component) with component one of "
                                f"{', '.join(allowed)} (dimension = {system.dimension})")
            if args[0] not in {j.name for j in system.joints}:
                raise SpecError(f"{where}: '{args[0]}' is not a joint of the system")
        elif len(args) != 1 or args[0] not in {j.name for j in system.joints}:
            raise SpecError(f"{where}: needs one joint name")
        if fn in ("angle", "rate") and not system.joint(args[0]).has_coordinate:
            raise SpecError(f"{where}: joint '{args[0]}' has no coordinate")
        owner = next((k for k, v in SECOND.items() if fn in v[2:]), None)  # a second coordinate's
        j = system.joint(args[0])
        if owner is not None and (j.kind != owner or len(j.coordinates) != 2):
            hint = {"cylindrical": "a prismatic joint's displacement is angle(J), its rate rate(J)",
                    "universal": "a revolute joint's angle is angle(J), its rate rate(J)"}[owner]
            raise SpecError(f"{where}: {fn}(J) is a {owner} joint's {SECOND[owner][1]}"
                            + (" (in the tree)" if owner == "universal" else "")
                            + f", and '{args[0]}' is a {j.kind} joint"
                            + (" closing a loop" if j.kind == owner else "") + f" ({hint})")
    elif kind == "driver":
        if len(args) != 1 or args[0] not in {d.name for d in system.drivers}:
            raise SpecError(f"{where}: needs one driver name")
    elif kind == "marker":
        if fn == "R":
            if len(args) != 3 or "." not in args[0] or not {args[1], args[2]} <= set("xyz"):
                raise SpecError(f"{where}: needs ('body.marker', i, j) with i, j each x, y or z: the "
                                "ground axis i's component of the marker's axis j")
        elif len(args) != 1 or "." not in args[0]:
            raise SpecError(f"{where}: needs one 'body.marker'")
        system._ref(where, args[0])
    else:
        want = (3 if system.dimension == 2 else 4) if fn == "sigma" else 2
        if fn in RECOVERABLE and len(args) == 3:
            if args[2] not in OUTPUT_RECOVERIES:
                raise SpecError(f"{where}: the recovery '{args[2]}' must be one of "
                                f"{', '.join(OUTPUT_RECOVERIES)}")
            want = 3
        if len(args) != want:
            if fn in RECOVERABLE:
                raise SpecError(f"{where}: needs (beam, x) or (beam, x, recovery) with x a marker name "
                                f"or a position in m and recovery {' or '.join(OUTPUT_RECOVERIES)}")
            if fn != "sigma":
                raise SpecError(f"{where}: needs (beam, x) with x a marker name or a position in m")
            if want == 3:
                raise SpecError(f"{where}: needs (beam, x, y): x a marker name or a position in m, y "
                                "the section point's distance from the beam's axis in m (+ toward the "
                                "beam frame's +y)")
            raise SpecError(f"{where}: needs (beam, x, y, z) in a spatial system: x a marker name or "
                            "a position in m, (y, z) the section point in m along the section's y "
                            "and z axes")
        b = system.body(args[0]) if args[0] in {b.name for b in system.bodies} else None
        if b is None or not b.flexible:
            raise SpecError(f"{where}: '{args[0]}' is not a flexible body")
        x = beam_station(system, b, args[1], where)
        side = station_side(args[1])
        if side and fn not in SIDED:
            raise SpecError(f"{where}: a side of the station ({args[1]}) applies to section "
                            f"forces, moments and stresses (they jump; {fn} does not)")
        if (side < 0 and x == 0) or (side > 0 and x == b.length):
            raise SpecError(f"{where}: no beam on that side of x = {x:g} m ({args[1]})")
        if fn == "sigma":
            if not side and section_at(b, x, -1) != section_at(b, x, 1):
                raise SpecError(f"{where}: the section steps at x = {x:g} m, so sigma has a value "
                                f"on either side: name one, {args[1]}- or {args[1]}+")
            section_point(b, x, args[2:], where, side)
    return fn, args


def one_beam_alias(system: System, text: str, where: str) -> str | None:
    """The system spelling of a one-beam output name on the system's one flexible beam B
    (output_names.system_alias): v_tip -> v(B, L), u_tip -> u(B, L), N_A -> N(B, 0),
    M@0.25 -> M(B, 0.25 L), M_B -> M(B, L/2), N_<marker> -> N(B, <marker>), M_<marker>_left ->
    M(B, <marker>-), ef's clamp reactions M_A_clamp -> M(B, 0, equilibrium); None when text is
    not such a name. The recovery is otherwise the beam model's, as for M(B, x)."""
    text = text.strip()
    if "(" in text or text in OUTPUT_SCALARS:
        return None
    beams = [b for b in system.bodies if getattr(b, "flexible", False)]
    labels = tuple(m.name for m in beams[0].all_markers) if len(beams) == 1 else ()
    try:
        hit = system_alias(text, labels)
    except SpecError as exc:  # M@1.5: its position, in the system's words
        raise SpecError(f"{where}: {str(exc).split(': ', 1)[-1]}") from None
    if hit is None:
        return None
    fn, at, side, recovery = hit
    if len(beams) != 1:
        raise SpecError(f"{where}: a one-beam output name reads the system's one flexible beam, "
                        f"and it has {len(beams)}{': ' if beams else ''}"
                        f"{', '.join(b.name for b in beams)} (write {fn}(beam, x))")
    beam = beams[0]
    station = at if isinstance(at, str) else repr(beam.length if at == 1 else float(at) * beam.length)
    return (f"{fn}({beam.name}, {station}{'-' if side < 0 else '+' if side > 0 else ''}"
            + (f", {recovery})" if recovery else ")"))


def output_beam(system: System, fn: str, args: tuple[str, ...]) -> FlexibleBeam:
    """The beam an output reads (parse_output's fn, args): the system's, with the output's own
    recovery, if it names one, in place of its model's axial_force (N) or moment."""
    beam = system.body(args[0])
    if fn in RECOVERABLE and len(args) == 3:
        key = "axial_force" if fn == "N" else "moment"
        beam = replace(beam, model=replace(beam.model, **{key: args[2]}))
    return beam


def section_at(beam: FlexibleBeam, x: float, side: int = 0) -> tuple[float, float, float | None]:
    """(A, I, Iy) of the section at station x (Iy: a spatial beam's, else None): the beam's, or
    for a body from finite-element data its element's there (at a node, the element before it
    for side -1, else the one beyond; at the tip, the last one), the beam's section scaled as
    the run-time parameters are."""
    body = getattr(beam.model, "body", None)
    sec = beam.section
    if body is None:
        return sec.A, sec.I, sec.Iy
    L = beam.length
    before = (lambda e: x <= body.nodes[e + 1] * L / body.length) if side < 0 else \
        (lambda e: x < body.nodes[e + 1] * L / body.length)
    k = next((e for e in range(len(body.sections)) if before(e)), len(body.sections) - 1)
    ref, here = body.sections[0], body.sections[k]
    return (sec.A * here.A / ref.A, sec.I * here.I / ref.I,
            sec.Iy * here.Iy / ref.Iy if here.Iy is not None else sec.Iy)


def section_point(beam: FlexibleBeam, x: float, texts, where: str, side: int = 0) -> tuple[float, ...]:
    """(y,) of sigma(beam, x, y) or (y, z) of sigma(beam, x, y, z): numbers (m), each within
    SIGMA_REACH radii of gyration of the axis in its bending plane, sqrt(I/A) for y (I_z in 3D)
    and sqrt(I_y/A) for z (farther is outside any section with this A and I: a typing error)."""
    A, I, Iy = section_at(beam, x, side)
    point = []
    names = ("I",) if len(texts) == 1 else ("Iz", "Iy")  # the planar I is the spatial I_z
    for axis, text, Ik, name in zip("yz", texts, (I, Iy), names):
        try:
            c = float(text)
        except ValueError:
            raise SpecError(f"{where}: {axis} = '{text}' is not a number (the section point's distance "
                            "from the axis, in m)") from None
        reach = SIGMA_REACH * math.sqrt(Ik / A)
        if not (math.isfinite(c) and abs(c) <= reach):
            raise SpecError(f"{where}: {axis} = {text} m is farther from the axis than any section with "
                            f"A = {A:g} m^2 and {name} = {Ik:g} m^4 reaches ({SIGMA_REACH:g} "
                            f"sqrt({name}/A) = {reach:.3g} m)")
        point.append(c)
    return tuple(point)


def output_unit(system: System, quantity: str) -> str:
    """The SI unit of an output quantity (for summaries, CSV readers and plot axes)."""
    fn, args = parse_output(system, quantity)
    second = {v[2]: False for v in SECOND.values()} | {v[3]: True for v in SECOND.values()}
    if fn in ("angle", "rate") or fn in second:  # a joint coordinate (Joint.coordinates) or its rate
        c = system.joint(args[0]).coordinates[fn in second]
        return ("m" if c.motion == "slide" else "rad") + ("/s" if second.get(fn, fn == "rate") else "")
    if fn == "torque":
        d = next(d for d in system.drivers if d.name == args[0])
        return "N" if KINDS[system.joint(d.joint).kind].law(bool(d.coordinate)) == "force" else "N m"
    if fn == "reaction":
        return "N" if args[1] in ("x", "y", "z") else "N m"
    if fn in ("Hx", "Hy", "Hz"):
        return "kg m^2/s"
    if fn == "R":
        return "1"
    return {"x": "m", "y": "m", "z": "m", "v": "m", "vz": "m", "u": "m", "w": "m", "N": "N", "M": "N m",
            "Mx": "N m", "My": "N m", "Mz": "N m", "Qy": "N", "Qz": "N", "sigma": "Pa", "T": "J",
            "V": "J", "momentum": "kg m^2/s", "violation": "1 (of the size)", "dissipation": "W"}[fn]


def station_side(text: str) -> int:
    """The side a station names: -1 for x- (the element before it), +1 for x+ (beyond), else 0."""
    return {"-": -1, "+": 1}.get(text[-1:], 0) if len(text) > 1 else 0


def loads_at(beam: FlexibleBeam, x: float, side: int) -> bool:
    """Whether the loads exactly at station x (a point mass, a marker's joint, force or spring)
    belong to the part beyond it, whose equilibrium gives N and M there: for x- (side -1) and
    at the tip (its only side); not for x+, nor for x without a side inside the beam or at the
    root (the section just beyond x)."""
    return side < 0 or x >= beam.length


def beam_station(system: System, beam: FlexibleBeam, text: str, where: str) -> float:
    """A station on a beam: a marker name or a number (m), 0 <= x <= length, with or without
    a side (station_side)."""
    if station_side(text):
        text = text[:-1].rstrip()
    for m in beam.all_markers:
        if m.name == text:
            return float(m.x)
    try:
        x = float(text)
    except ValueError:
        raise SpecError(f"{where}: '{text}' is neither a marker of '{beam.name}' nor a number") from None
    if not (math.isfinite(x) and 0 <= x <= beam.length):
        raise SpecError(f"{where}: x = {text} is outside 0..{beam.length}")
    return x


def length_scale(system: System) -> float:
    """The mechanism's size: the largest beam length, rigid marker distance from its body's
    origin, or ground joint point distance from the origin (tolerances, blow-up and the
    violation output use it)."""
    sizes = [b.length for b in system.bodies if b.flexible]
    sizes += [_norm((m.x, m.y, m.z)) for b in system.bodies if not b.flexible for m in b.markers]
    sizes += [_norm(j.point) for j in system.joints if j.parent == "ground"]
    return max([x for x in sizes if x > 0] or [1.0])


def _norm(v) -> float:
    """|v|: a planar vector as it always was (abs of a complex: the scales of generated planar
    code stay bit for bit), a spatial one by hypot."""
    if len(v) == 2 or not v[2]:
        return abs(complex(v[0], v[1]))
    return math.hypot(*v)
