"""System scenes: planar mechanisms described in TOML (or the same data as a Python dict).

A scene is a *system scene* when it has `[[body]]` entries (an array of tables) or any of
[system], [[joint]], [[driver]], [[load]], [gravity]; every other scene is today's one-beam
scene (flexsym/scenes/scene.py), unchanged.

    [system]    name (default: the file's stem), description
    [[body]]    name, kind = "rigid": mass, inertia (about the com), com = [x, y],
                markers = { name = [x, y] }                             (body frame, m)
                name, kind = "beam": length, density, youngs_modulus, area, inertia,
                model = "m3" | { variant = "ef", elements = 8 } | { strain, axial, bending },
                markers = { name = x }   (x along the beam, m; root and tip always exist),
                damping = { zeta = z | [z1, ...], alpha = a, beta = b } (structural damping,
                system.py's Damping; none by default);
                or, for a beam from finite-element data, instead of length ... inertia:
                segments + point_masses, or folder (relative to the scene file), with
                elements and ef_elements: the one-beam scene's [body] keys, read by the same
                reader (fedata.scene_body, feimport.scene_folder)
    [[joint]]   name, kind = revolute | prismatic | clamp, parent = "body.marker" | "ground"
                (then point = [x, y]), child = "body.marker", axis = [ax, ay] (prismatic, in
                the parent's frame), offset (rad, child frame angle relative to the parent's),
                initial = x (a guess of the coordinate at t = 0) or { value = x, fixed = true,
                rate = v } (fixed: never moved by the assembly; rate: the rate at t = 0);
                spatial (dimension = 3) also spherical, universal and cylindrical; a
                cylindrical joint's initial table adds slide = s, slide_rate = v, a universal
                joint's in the tree (parent_axis = [x, y, z], parent's frame) angle2 = a,
                rate2 = w (Joint.coordinates)
    [[driver]]  name, kind = "guided", joint, and maneuver = "spin-up" (omega, duration) |
                "constant" (omega) or theta = "expression of t";
                name, kind = "motor", joint, torque (revolute) | force (prismatic) =
                "expression of t, J and J_rate for every joint J with a coordinate"; on a
                spatial joint with two coordinates, coordinate = "slide" (a cylindrical
                joint's, with force) or "angle2" (a tree universal joint's) drives the second
                (System.driven; none: the first)
    [gravity]   g = [gx, gy]  (m/s^2)
    [[load]]    kind = "force": marker, fx, fy, frame = ground | body;
                kind = "torque": body, torque = "expression" (spatial: ["tx", "ty", "tz"], frame =
                "ground" | "body"); kind = "spring": a, b
                (body.marker each), k, c, l0
    [solver]    run options (flexsym/model/options.py: integrator, dt, t_end, ...)
    [output]    file, interval, energy, columns = { name = "quantity" } (system.py's output
                grammar: angle(J), rate(J), x(B.m), y(B.m), v(B, x), u(B, x), w(B, x), N(B, x),
                M(B, x), sigma(B, x, y), reaction(J), torque(D), T, V, momentum, violation,
                dissipation; spatial: z(B.m), vz, Mx, My, Mz, Qy, Qz (B, x), sigma(B, x, y, z),
                Hx, Hy, Hz, slide(J), slide_rate(J), angle2(J), rate2(J))

Checks, each one line naming the file and the item, before anything is derived or written:
the TOML's types and keys here; names, references, masses, the spanning tree, drivers,
loads and output names in System.validate (flexsym/model/system.py); then check_system: every
expression through the bounded parser of maneuver.py with only its allowed names, manoeuvre
parameters, each requested beam output carried by some mode of the body's model, and the
assembly at t = 0 (flexsym/scenes/assembly.py: the free joint coordinates and rates are solved
so that every cut joint closes with undeformed bodies; a loop that cannot close, or is singular
there, is refused; in a spatial system, also a universal joint's axis along its parent's x
axis at t = 0).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import sympy as sp

from flexsym.core.errors import SpecError
from flexsym.scenes.assembly import Assembly, assemble, poses, rotations3, theta0
from flexsym.model.maneuver import check_theta, check_time_function, maneuver_of, parse_expression, t
from flexsym.model.limits import MAX_BODIES, MAX_JOINTS
from flexsym.model.options import OPTIONS, RunOptions, Where, validate
from flexsym.model.joint_kinds import KINDS
from flexsym.model.end_modes import with_end_modes
from flexsym.model.modes import mode
from flexsym.model.system import (GROUND, SECOND, beam_coordinates, Damping, Driver, FlexibleBeam, Gravity, Joint, Marker, Output, PointForce,
                     RigidBody, Section, SpringDamper, System, Torque, beam_station, length_scale,
                     output_beam, parse_output)

SYSTEM_TABLES = ("system", "body", "joint", "driver", "gravity", "load", "solver", "output")
_ARRAYS = ("body", "joint", "driver", "load")
_RUN_KEYS = {o.scene: o.name for o in OPTIONS if o.scene and o.maneuvers is None}
UNIFORM_KEYS = ("length", "density", "youngs_modulus", "area", "inertia")
# a spatial beam's section: inertia_z is the planar inertia (bending in the frame's x-y plane)
SPATIAL_KEYS = ("length", "density", "youngs_modulus", "area", "inertia_z", "inertia_y",
                "torsion_constant", "shear_modulus")
FE_KEYS = ("segments", "point_masses", "elements", "ef_elements", "folder")  # scene.py's [body]
EF_ELEMENTS = 32  # ef elements of a body from finite-element data (scene.py's [body] default)
KEYS = {
    "system": {"name", "description", "start", "dimension"},
    "rigid": {"name", "kind", "mass", "inertia", "com", "markers"},
    "beam": {"name", "kind", "model", "markers", "damping", *UNIFORM_KEYS, *FE_KEYS},
    "beam3": {"name", "kind", "model", "markers", "damping", *SPATIAL_KEYS, *FE_KEYS},
    "joint": {"name", "kind", "parent", "child", "point", "axis", "offset", "initial", "direction",
              "parent_axis"},
    "guided": {"name", "kind", "joint", "maneuver", "omega", "duration", "theta", "coordinate"},
    "motor": {"name", "kind", "joint", "torque", "force", "coordinate"},
    "gravity": {"g"},
    "force": {"kind", "name", "marker", "fx", "fy", "fz", "frame"},
    "torque": {"kind", "name", "body", "torque", "frame"},
    "spring": {"kind", "name", "a", "b", "k", "c", "l0"},
    "solver": {k.split(".")[1] for k in _RUN_KEYS if k.startswith("solver.")},
    "output": {"file", "columns"} | {k.split(".")[1] for k in _RUN_KEYS if k.startswith("output.")},
}
MANEUVERS = {"spin-up": ("spin_up", {"omega": "ws", "duration": "ts"}),
             "constant": ("constant", {"omega": "ws"})}

@dataclass
class SystemScene:
    path: Path | None
    system: System
    options: RunOptions
    output_file: Path | None
    model: str | dict | None = None  # the --model that replaced every beam's model (load_system_scene)
    assembly: Assembly = Assembly()  # what the assembly at t = 0 moved (system: assembled)
    given: dict = field(default_factory=dict)  # run options as the scene gives them (None: not)

    @property
    def columns(self) -> dict:
        return {o.column: o.quantity for o in self.system.outputs}


def is_system_scene(data: dict) -> bool:
    return isinstance(data.get("body"), list) or any(k in data for k in _ARRAYS[1:] + ("system", "gravity"))


class _Located(SpecError):
    """Already names the source and the item: not to be wrapped again."""


class _Items:
    """Typed access to one entry of the data, with errors naming the source and the item."""

    def __init__(self, prefix: str):
        self.prefix = prefix

    def fail(self, where: str, msg: str):
        raise _Located(f"{self.prefix}{where}: {msg}")

    def table(self, where: str, tab, keys: set) -> dict:
        if not isinstance(tab, dict):
            self.fail(where, f"must be a table, not {type(tab).__name__}")
        unknown = sorted(set(tab) - keys)
        if unknown:
            self.fail(f"{where} {unknown[0]}", f"unknown key (known: {', '.join(sorted(keys))})")
        return tab

    def number(self, where, tab, key, *, positive=False, default=None):
        val = tab.get(key, default)
        if val is None:
            self.fail(f"{where} {key}", "missing")
        if isinstance(val, bool) or not isinstance(val, (int, float)) or not math.isfinite(val):
            self.fail(f"{where} {key}", f"must be a finite number (got {val!r})")
        if positive and not val > 0:
            self.fail(f"{where} {key}", f"must be > 0 (got {val!r})")
        return float(val)

    def string(self, where, tab, key, default=None) -> str:
        val = tab.get(key, default)
        if val is None:
            self.fail(f"{where} {key}", "missing")
        if not isinstance(val, str):
            self.fail(f"{where} {key}", f"must be a string (got {val!r})")
        return val

    def pair(self, where, tab, key, default=None, n: int = 2):
        """n finite numbers (a planar pair, or a spatial triple with n = 3)."""
        val = tab.get(key, default)
        if val is None:
            return None
        if (not isinstance(val, (list, tuple)) or len(val) != n
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                           for v in val)):
            form = "two finite numbers [x, y]" if n == 2 else "three finite numbers [x, y, z]"
            self.fail(f"{where} {key}", f"must be {form} (got {val!r})")
        return tuple(float(v) for v in val)


def _entries(r: _Items, data: dict, name: str) -> list:
    val = data.get(name, [])
    if not isinstance(val, list) or not all(isinstance(v, dict) for v in val):
        r.fail(f"[[{name}]]", "must be an array of tables ([[{name}]] entries)")
    return val


def _label(kind: str, k: int, tab: dict) -> str:
    name = tab.get("name")
    return f"[[{kind}]] '{name}'" if isinstance(name, str) else f"[[{kind}]] #{k + 1}"


def system_from_data(data: dict, prefix: str = "", name: str = "system", model: str | dict | None = None,
                     base: Path = Path(".")):
    """(System, given run options, output file or None) from parsed scene data. prefix names
    the source in every message ("scenes/hub.toml: "); model replaces every beam's model; base:
    the directory a body's folder is relative to (the scene file's)."""
    r = _Items(prefix)
    unknown = sorted(set(data) - set(SYSTEM_TABLES))
    if unknown:
        r.fail(unknown[0], f"unknown table (a system scene has: {', '.join(SYSTEM_TABLES)})")
    for key in ("system", "gravity", "solver", "output"):
        if key in data:
            r.table(f"[{key}]", data[key], KEYS[key])
    if not isinstance(data.get("body"), list):
        r.fail("[[body]]", "a system scene needs [[body]] entries")
    system_tab = data.get("system", {})
    name = r.string("[system]", system_tab, "name", default=name)
    description = r.string("[system]", system_tab, "description", default="")
    start = r.string("[system]", system_tab, "start", default="undeformed")
    dim = system_tab.get("dimension", 2)
    if type(dim) is not int or dim not in (2, 3):  # 3.0 too: it counts the coordinates
        r.fail("[system] dimension", f"must be 2 (planar) or 3 (spatial) (got {dim!r})")
    for key, limit in (("body", MAX_BODIES), ("joint", MAX_JOINTS)):
        if len(_entries(r, data, key)) > limit:  # before anything is read (system.py's limit)
            r.fail(f"[[{key}]]", f"{len(data[key])} entries, more than the limit of {limit} (the "
                   "derivation's cost grows quickly with the number of bodies)")
    bodies = tuple(_body(r, k, tab, model, base, dim) for k, tab in enumerate(_entries(r, data, "body")))
    joints = tuple(_joint(r, k, tab, dim) for k, tab in enumerate(_entries(r, data, "joint")))
    drivers = tuple(_driver(r, k, tab) for k, tab in enumerate(_entries(r, data, "driver")))
    kinds = {j.name: j.kind for j in joints}
    for k, (d, tab) in enumerate(zip(drivers, _entries(r, data, "driver"))):
        kind = KINDS.get(kinds.get(d.joint))  # a coordinate it lacks: System.validate says so
        known = kind is not None and d.coordinate in ("", *(kind.second or ())[2:3])
        law = kind.law(bool(d.coordinate)) if known else None
        if d.kind == "motor" and law is not None and law not in tab:
            what = f"{d.coordinate} of the" if d.coordinate else "the"
            r.fail(f"{_label('driver', k, tab)}", f"a motor on {what} {kinds[d.joint]} joint "
                   f"'{d.joint}' gives a {law} (write {law} = \"...\")")
    loads = tuple(_load(r, k, tab, dim) for k, tab in enumerate(_entries(r, data, "load")))
    if "gravity" in data:
        if dim == 3 and "g" not in data["gravity"]:
            r.fail("[gravity] g", "missing (a spatial system has no default down: give [gx, gy, gz])")
        loads = (Gravity(r.pair("[gravity]", data["gravity"], "g", default=(0.0, -9.81), n=dim)),) + loads
    out = data.get("output", {})
    columns = out.get("columns", {})
    if not isinstance(columns, dict) or not all(isinstance(v, str) for v in columns.values()):
        r.fail("[output] columns", "must be a table of column = \"quantity\" (e.g. theta_h = "
               "\"angle(hub_joint)\")")
    if not columns:
        r.fail("[output] columns", "missing (name at least one output)")
    outputs = tuple(Output(c, q) for c, q in columns.items())
    output_file = r.string("[output]", out, "file", default="") or None
    given = {opt: data.get(key.split(".")[0], {}).get(key.split(".")[1]) for key, opt in _RUN_KEYS.items()}
    system = System(name, bodies, joints, drivers, loads, outputs, description=description, start=start,
                    dimension=dim)
    return system, given, output_file


def _markers(r, where, tab, beam: bool, dim: int = 2) -> tuple[Marker, ...]:
    given = tab.get("markers", {})
    if not isinstance(given, dict):
        r.fail(f"{where} markers", "must be a table of name = " + (
            "x (m)" if beam else "[x, y] (m)" if dim == 2 else "[x, y, z] (m)"))
    out = []
    for name, pos in given.items():
        if beam:
            if isinstance(pos, list):  # [x, y, z]: a beam's markers lie on its axis
                r.fail(f"{where} markers {name}", f"a beam's marker is its distance x along the "
                       f"axis (m), one number: markers on a beam lie on its axis (got {pos!r})")
            x = r.number(f"{where} markers", given, name)
            out.append(Marker(name, x))
        else:
            out.append(Marker(name, *r.pair(f"{where} markers", given, name, n=dim)))
    return tuple(out)


def _body(r: _Items, k: int, tab: dict, model: str | dict | None, base: Path, dim: int = 2):
    where = _label("body", k, tab)
    kind = tab.get("kind")
    if kind not in ("rigid", "beam"):
        r.fail(f"{where} kind", f"must be \"rigid\" or \"beam\" (got {kind!r})")
    if dim == 3 and kind == "beam" and "inertia" in tab:
        r.fail(f"{where} inertia", "a spatial beam has inertia_z (bending in its x-y plane) and "
               "inertia_y (x-z plane), with torsion_constant and shear_modulus")
    r.table(where, tab, KEYS["beam3" if dim == 3 and kind == "beam" else kind])
    name = r.string(where, tab, "name")
    if kind == "rigid":
        inertia = (r.pair(where, tab, "inertia", n=3) or r.fail(f"{where} inertia", "missing")
                   if dim == 3 else r.number(where, tab, "inertia"))
        return RigidBody(name, r.number(where, tab, "mass"), inertia,
                         r.pair(where, tab, "com", default=(0.0,) * dim, n=dim),
                         _markers(r, where, tab, False, dim))
    spec = _model(r, f"{where} model", tab.get("model") if model is None else model,
                  "--model" if model is not None else None)
    markers = _markers(r, where, tab, True)
    damping = _damping(r, where, tab)
    uniform_keys = SPATIAL_KEYS if dim == 3 else UNIFORM_KEYS
    if "segments" not in tab and "folder" not in tab:
        extra = [key for key in FE_KEYS if key in tab]
        if extra:
            r.fail(f"{where} {extra[0]}", "applies to a beam from finite-element data only (give "
                   f"segments or folder instead of {', '.join(uniform_keys)})")
        num = {key: r.number(where, tab, key, positive=True) for key in uniform_keys}
        section = (Section(num["density"], num["youngs_modulus"], num["area"], num["inertia_z"],
                           Iy=num["inertia_y"], J=num["torsion_constant"], G=num["shear_modulus"])
                   if dim == 3 else Section(*(num[key] for key in UNIFORM_KEYS[1:])))
        return FlexibleBeam(name, num["length"], section, spec, markers, damping)
    uniform = [key for key in uniform_keys if key in tab]
    if uniform:
        r.fail(f"{where} {uniform[0]}", f"give either {', '.join(uniform_keys)} (a uniform beam) or "
               "segments / folder (finite-element data), not both")
    body = _fe_body(r, where, tab, base, dim == 3)
    if body.spatial != (dim == 3):
        r.fail(f"{where} folder", f"its elements are {'spatial' if body.spatial else 'planar'}, the "
               f"system is {'spatial' if dim == 3 else 'planar'} (dimension = {dim})")
    ref = body.reference
    if spec.kind == "fe":  # ef: the body remeshed, as the one-beam scene's --model ef
        given = tab.get("model") if model is None else model  # --model ef [--elements n]
        n = given["elements"] if isinstance(given, dict) and "elements" in given else \
            tab.get("ef_elements", EF_ELEMENTS)
        mesh = body.remeshed(n)
        spec = replace(spec, body=mesh, elements=mesh.elements)
    else:
        spec = replace(spec, body=body)
    try:
        spec.validate()
    except SpecError as exc:
        r.fail(f"{where} model", str(exc))
    return FlexibleBeam(name, body.length, Section(ref.rho, ref.E, ref.A, ref.I, ref.Iy, ref.J, ref.G),
                        spec, markers, damping)


def _damping(r: _Items, where: str, tab: dict) -> Damping | None:
    """damping = { zeta, alpha, beta } as a Damping (its values are checked in one place,
    Damping.check, with the system); none given: None (undamped)."""
    given = tab.get("damping")
    if given is None:
        return None
    at = f"{where} damping"
    r.table(at, given, {"zeta", "alpha", "beta"})
    zeta = given.get("zeta", 0.0)
    return Damping(tuple(zeta) if isinstance(zeta, list) else zeta, given.get("alpha", 0.0),
                   given.get("beta", 0.0))


class _BodyData:
    """A [[body]] entry seen as the one-beam scene's [body] table, so that its finite-element
    data are read by the same reader (fedata.scene_body, feimport.scene_folder) with the same
    checks; their messages name the entry instead of [body]."""

    def __init__(self, r: _Items, where: str, tab: dict, base: Path):
        self.r, self.where = r, where
        self.data = {"body": {key: tab[key] for key in FE_KEYS if key in tab}}
        self.path = base / "scene.toml"  # the reader takes folders relative to path.parent

    def fail(self, where: str, msg: str):
        self.r.fail(where.replace("[body]", self.where, 1), msg)

    def string(self, table: str, key: str) -> str:
        return self.r.string(f"{self.where}", self.data[table], key)


def _fe_body(r: _Items, where: str, tab: dict, base: Path, spatial: bool = False):
    from flexsym.model.fedata import scene_body
    from flexsym.scenes.feimport import scene_folder

    reader = _BodyData(r, where, tab, base)
    if "folder" not in tab:
        return scene_body(reader, spatial)
    try:
        return scene_folder(reader)
    except _Located:
        raise
    except SpecError as exc:  # the folder's own files: the message names the file
        r.fail(f"{where} folder", str(exc))


def _model(r: _Items, where: str, given, flag: str | None):
    """A deformation model: a variant name, or { variant, elements } or { strain, axial, bending },
    either table with axial_force / moment = "constitutive" | "equilibrium" (and a modal one's
    stress = "continuum" | "element:N", torsion = [...])."""
    from flexsym.model.variant import _refs, body_model, builtin, customize

    where = flag or where
    if given is None:
        r.fail(where, "missing (a variant name such as \"m3\" or \"ef\", or a table)")
    try:
        if isinstance(given, str):
            return builtin(given)
        if not isinstance(given, dict):
            r.fail(where, f"must be a variant name or a table (got {given!r})")
        r.table(where, given, {"variant", "elements", "strain", "axial", "bending", "axial_force",
                               "moment", "torsion", "stress"})
        recovery = {}  # what modifies the model the other keys give
        for key in ("axial_force", "moment"):
            if key in given:
                if given[key] not in ("constitutive", "equilibrium"):
                    r.fail(f"{where} {key}", f"must be \"constitutive\" or \"equilibrium\" "
                           f"(got {given[key]!r})")
                recovery[key] = given[key]
        if "stress" in given:  # the constitutive N and M by the paper's element method (variant.py)
            recovery["stress"] = r.string(where, given, "stress")
        if "torsion" in given:
            val = given["torsion"]
            if not isinstance(val, list) or not all(isinstance(v, str) for v in val):
                r.fail(f"{where} torsion", f"must be a list of mode names, e.g. [\"ff1\"] or [] "
                       f"(got {val!r})")
            try:
                recovery["torsion"] = _refs("axial", val)
            except SpecError as exc:  # the bar's shapes, read as axial modes: name them as torsion's
                r.fail(f"{where} torsion", str(exc).replace("axial mode", "torsion mode"))
        given = {k: v for k, v in given.items() if k not in recovery}
        if recovery:
            base = _model(r, where, given if len(given) > 1 or "strain" in given
                          else given.get("variant"), flag)
            if base.kind != "modal" and (base.kind != "fe" or {"torsion", "stress"} & set(recovery)):
                r.fail(where, "axial_force / moment apply to modal and ef variants, torsion to "
                       "modal variants only, and stress too")
            return replace(base, **recovery).validate()
        if "variant" in given:
            base = builtin(r.string(where, given, "variant"))
            if set(given) & {"strain", "axial", "bending"}:
                r.fail(where, "give either variant or strain/axial/bending, not both")
            if "elements" in given and base.kind != "fe":
                r.fail(f"{where} elements", f"applies to variant = \"ef\" only, not to '{given['variant']}'")
            return customize(base, elements=given["elements"]) if "elements" in given else base
        if "elements" in given:
            r.fail(f"{where} elements", "applies to variant = \"ef\" only")
        strain = r.string(where, given, "strain")
        axial, bending = given.get("axial", []), given.get("bending")
        for key, val in (("axial", axial), ("bending", bending)):
            if not isinstance(val, list) or not all(isinstance(v, str) for v in val):
                r.fail(f"{where} {key}", f"must be a list of mode names (got {val!r})")
        return body_model(strain, _refs("axial", axial), _refs("bending", bending))
    except _Located:
        raise
    except SpecError as exc:
        r.fail(where, str(exc))


def _joint(r: _Items, k: int, tab: dict, dim: int = 2) -> Joint:
    where = _label("joint", k, tab)
    r.table(where, tab, KEYS["joint"])
    kind = r.string(where, tab, "kind")
    parent = r.string(where, tab, "parent")
    point = r.pair(where, tab, "point", n=dim)
    if parent == GROUND and point is None:
        r.fail(f"{where} point", "missing (a joint to ground needs the ground point "
               + ("[x, y])" if dim == 2 else "[x, y, z])"))
    if parent != GROUND and point is not None:
        r.fail(f"{where} point", "applies to a joint whose parent is \"ground\" only")
    if kind == "clamp" and "initial" in tab:
        r.fail(f"{where} initial", "applies to revolute and prismatic joints only (a clamp has no "
               "coordinate; use offset for its angle)")
    second = {}  # a second coordinate's start (SECOND: a cylindrical joint's slide, ...)
    if kind in KINDS and KINDS[kind].euler:  # its one start datum: the angular velocity, a vector
        given = tab.get("initial", {})
        if not isinstance(given, dict):  # an angle: it has three, and starts at its direction
            r.fail(f"{where} initial", "a spherical joint starts with the child's frame parallel to "
                   "the parent's (or its x along direction): give initial = { rate = [wx, wy, wz] } "
                   f"only (got {given!r})")
        r.table(f"{where} initial", given, {"rate"})
        initial, fixed, rate = 0.0, False, r.pair(f"{where} initial", given, "rate", n=3)
    else:
        keys = SECOND[kind][2:] if kind in SECOND else ()
        initial, fixed, rate = _initial(r, where, tab, keys)
        given = tab.get("initial")
        if keys and isinstance(given, dict):
            value, rate_key = keys
            second = {value: r.number(f"{where} initial", given, value, default=0.0),
                      rate_key: r.number(f"{where} initial", given, rate_key) if rate_key in given else None}
    return Joint(r.string(where, tab, "name"), kind, parent, r.string(where, tab, "child"),
                 axis=r.pair(where, tab, "axis", n=dim), offset=r.number(where, tab, "offset", default=0.0),
                 point=point or (0.0,) * dim, initial=initial, fixed=fixed, rate=rate,
                 direction=r.pair(where, tab, "direction", n=3) if "direction" in tab else None,
                 parent_axis=r.pair(where, tab, "parent_axis", n=3), **second)


def _initial(r: _Items, where: str, tab: dict, second: tuple = ()) -> tuple[float, bool, float | None]:
    """initial = 0.5 (a guess) or { value = 0.5, fixed = true, rate = 2.0 } (see assembly.py); a
    joint with a second coordinate also takes its keys (second: SECOND's, e.g. slide = 0.1,
    slide_rate = 0.3 of a cylindrical joint; value and rate: its first)."""
    given = tab.get("initial", 0.0)
    if not isinstance(given, dict):
        return r.number(where, tab, "initial", default=0.0), False, None
    at = f"{where} initial"
    r.table(at, given, {"value", "fixed", "rate"} | set(second))
    fixed = given.get("fixed", False)
    if not isinstance(fixed, bool):
        r.fail(f"{at} fixed", f"must be true or false (got {fixed!r})")
    if fixed and not ({"value"} | set(second[:1])) & set(given):
        r.fail(f"{at} fixed", "fixes the value: give value = ...")
    rate = r.number(at, given, "rate") if "rate" in given else None
    return r.number(at, given, "value", default=0.0), fixed, rate


def _driver(r: _Items, k: int, tab: dict) -> Driver:
    where = _label("driver", k, tab)
    kind = tab.get("kind")
    if kind not in ("guided", "motor"):
        r.fail(f"{where} kind", f"must be \"guided\" or \"motor\" (got {kind!r})")
    r.table(where, tab, KEYS[kind])
    name, joint = r.string(where, tab, "name"), r.string(where, tab, "joint")
    which = {"coordinate": r.string(where, tab, "coordinate")} if "coordinate" in tab else {}
    if kind == "motor":
        laws = [key for key in ("torque", "force") if key in tab]
        if len(laws) != 1:
            r.fail(where, "a motor needs torque = \"...\" (revolute) or force = \"...\" (prismatic)")
        return Driver(name, kind, joint, expression=r.string(where, tab, laws[0]), **which)
    if ("theta" in tab) == ("maneuver" in tab):
        r.fail(where, "a guided driver needs maneuver = \"spin-up\" | \"constant\" or theta = \"...\"")
    if "theta" in tab:
        extra = sorted(set(tab) & {"omega", "duration"})
        if extra:
            r.fail(f"{where} {extra[0]}", "does not apply to theta = \"...\"")
        return Driver(name, kind, joint, expression=r.string(where, tab, "theta"), **which)
    man = r.string(where, tab, "maneuver")
    if man not in MANEUVERS:
        r.fail(f"{where} maneuver", f"unknown manoeuvre '{man}' (known: {', '.join(MANEUVERS)})")
    internal, keys = MANEUVERS[man]
    extra = sorted(set(tab) & ({"omega", "duration"} - set(keys)))
    if extra:
        r.fail(f"{where} {extra[0]}", f"does not apply to maneuver '{man}'")
    params = tuple((p, r.number(where, tab, key)) for key, p in keys.items())
    if internal == "spin_up" and params[1][1] <= 0:
        r.fail(f"{where} duration", f"must be > 0 (got {params[1][1]!r})")
    return Driver(name, kind, joint, maneuver=internal, params=params, **which)


def _load(r: _Items, k: int, tab: dict, dim: int = 2):
    where = _label("load", k, tab)
    kind = tab.get("kind")
    if kind not in ("force", "torque", "spring"):
        r.fail(f"{where} kind", f"must be \"force\", \"torque\" or \"spring\" (got {kind!r})")
    r.table(where, tab, KEYS[kind])
    name = r.string(where, tab, "name", default="")
    if kind == "force":
        if dim == 2 and "fz" in tab:
            r.fail(f"{where} fz", "applies to spatial systems ([system] dimension = 3) only")
        return PointForce(r.string(where, tab, "marker"), r.number(where, tab, "fx"),
                          r.number(where, tab, "fy"), r.string(where, tab, "frame", default="ground"), name,
                          r.number(where, tab, "fz", default=0.0))
    if kind == "torque":  # a planar torque's frame is refused by System.validate
        frame = r.string(where, tab, "frame", default="ground")
        if dim == 2:
            return Torque(r.string(where, tab, "body"), r.string(where, tab, "torque"), name, frame)
        val = tab.get("torque")
        if not (isinstance(val, list) and len(val) == 3 and all(isinstance(e, str) for e in val)):
            r.fail(f"{where} torque", f"must be three expressions [\"tx\", \"ty\", \"tz\"] (got {val!r:.80})")
        return Torque(r.string(where, tab, "body"), tuple(val), name, frame)
    for end in ("a", "b"):
        if r.string(where, tab, end) == GROUND:
            r.fail(f"{where} {end}", "a spring ends on a body marker (put a marker on a body fixed "
                   "to ground for a ground end)")
    return SpringDamper(tab["a"], tab["b"], r.number(where, tab, "k"), r.number(where, tab, "c", default=0.0),
                        r.number(where, tab, "l0", default=0.0), name)


# ----- checks beyond the structure: expressions, outputs' carriers, the initial assembly --------
def _modes_text(spec) -> str:
    """A modal model's strain and modes, as `inspect` shows them (the built-in exact's are the
    beam's ends', end_modes.py)."""
    axial = ", ".join(m.token for m in spec.axial) or "none"
    return f"strain {spec.strain}, axial {axial}, bending {', '.join(m.token for m in spec.bending)}"


def check_system(system: System, t_end: float = 20.0) -> System:
    """System.validate, the built-in `exact`'s modes from each beam's end joints (end_modes),
    then the checks that need expressions and modes (checked_system adds the assembly at t = 0)."""
    system = with_end_modes(system.validate()).validate()
    tree = system.tree()
    where = f"system '{system.name}'"
    joints = {j.name: j for j in system.joints if j.has_coordinate and j.name not in tree.cut}
    coords = {c[0]: c[2] for j in joints.values() for c in j.coordinates}  # name -> initial value
    names = {"t": t}
    for c in coords:  # the names an expression may use: J and J_rate of every joint coordinate
        names[c] = sp.Symbol(c, real=True)
        names[f"{c}_rate"] = sp.Symbol(f"{c}_rate", real=True)
    for d in system.drivers:
        label = f"{where}: driver '{d.name}'"
        if d.kind == "motor":
            motion = next(c.motion for c in joints[d.joint].coordinates if c.name == system.driven(d))
            law = f"{label} {'torque' if motion == 'turn' else 'force'}"
            _at_rest(_expression(d.expression, names, law), coords, names, t_end, d.expression, law)
        elif d.expression:
            try:
                check_theta(d.expression, t_end)
            except SpecError as exc:
                raise SpecError(f"{label}: {exc}") from None
        else:
            try:
                man = maneuver_of(d.maneuver)
            except SpecError as exc:
                raise SpecError(f"{label}: {exc}") from None
            known = {p.name for p in man.params}
            for p, v in d.params:
                if p not in known:
                    raise SpecError(f"{label}: parameter '{p}' does not apply to manoeuvre "
                                    f"'{d.maneuver}' (known: {', '.join(sorted(known)) or 'none'})")
                if not v > 0 and p == "ts":
                    raise SpecError(f"{label}: parameter ts = {v!r} must be > 0")
    for load in system.loads:
        if isinstance(load, Torque):
            label = f"{where}: load {load.name or 'torque'} torque"
            for e in (load.expression if system.dimension == 3 else (load.expression,)):
                _at_rest(_expression(e, names, label), coords, names, t_end, e, label)
    for o in system.outputs:
        _carried(system, o)
    return system


def checked_system(system: System, t_end: float = 20.0) -> tuple[System, Assembly]:
    """check_system, then the assembly at t = 0 and the linkage's reach until t_end: (the
    assembled system, what moved)."""
    return check_assembly(check_system(system, t_end), t_end)


def _at_rest(expr, coords: dict, names: dict, t_end: float, text: str, label: str) -> None:
    """A motor's law on [0, t_end] with every joint at its initial value and at rest: a pole
    or an overflow in t (e.g. 1/(t - 1), exp(100 t)) is refused here, naming the driver,
    rather than stopping the run."""
    at_rest = {names[c]: value for c, value in coords.items()} | {names[f"{c}_rate"]: 0.0 for c in coords}
    expr = expr.xreplace(at_rest)
    if expr.has(sp.zoo, sp.oo, -sp.oo, sp.nan):
        raise SpecError(f"{label} = '{text}' is infinite or undefined with every joint at its initial "
                        "value and at rest (a division by zero?)")
    check_time_function(expr, t_end, text, label)


def _expression(text: str, names: dict, label: str) -> sp.Expr:
    if not isinstance(text, str):
        raise SpecError(f"{label}: must be a string (got {text!r})")
    return parse_expression(text, tuple(names.items()), label)


def _carried(system: System, o: Output) -> None:
    """A beam output that no mode of the body's model can make non-zero is refused."""
    fn, args = parse_output(system, o.quantity)
    if fn not in ("v", "u", "w", "N", "M", "vz", "Mx", "My", "Mz", "sigma"):
        return
    beam = output_beam(system, fn, args)  # N and the moments: the recovery it names, if it does
    model = beam.model
    where = f"system '{system.name}': output {o.column} = '{o.quantity}'"
    x = beam_station(system, beam, args[1], where)
    if fn == "w" and x in (0.0, beam.length):
        raise SpecError(f"{where}: the distance from the chord is zero at the beam's ends by definition")
    if model.kind != "modal":
        return  # finite elements carry every field
    s = sp.nsimplify(x / beam.length, rational=True) if 0 < x < beam.length else sp.Integer(int(x > 0))
    from flexsym.model.output_names import axial_force_available

    if fn == "Mx":
        if model.moment == "equilibrium":
            return  # the loads' torque
        if not model.torsion:
            raise SpecError(f"{where}: model '{model.name}' has no torsion modes (torsion = []), so "
                            "the constitutive torsion moment would be identically zero (give a "
                            "torsion mode, or moment = \"equilibrium\")")
        if all(float(mode(m).value_at(1, s)) == 0 for m in model.torsion):
            raise SpecError(f"{where}: the twist rate of every torsion mode of model '{model.name}' "
                            f"is zero at x = {x:g} m, so the constitutive torsion moment would be "
                            "identically zero")
        return
    if fn in ("v", "w", "vz") or (fn in ("M", "My", "Mz") and model.moment != "equilibrium"):
        order = 2 if fn in ("M", "My", "Mz") else 0
        if all(float(model.mode(m).value_at(order, s)) == 0 for m in model.bending):
            what = "deflection" if order == 0 else "curvature"
            raise SpecError(f"{where}: no bending mode of model '{model.name}' has {what} at "
                            f"x = {x:g} m, so the output would be identically zero")
    elif (fn == "N" or (fn == "sigma" and system.dimension == 3)) and not axial_force_available(model):
        raise SpecError(f"{where}: model '{model.name}' (strain {model.strain}) has no axial mode to "
                        "carry N (choose a model with axial modes, e.g. m2)")
    elif fn == "u" and not model.axial and model.strain not in ("foreshortening", "exact"):
        raise SpecError(f"{where}: model '{model.name}' has no axial mode and no foreshortening, so u "
                        "would be identically zero")


def initial_poses(system: System) -> dict:
    """Each body's frame (X, Y, angle) at t = 0 from its tree joint: undeformed beams, joint
    coordinates at `initial` (a guided joint: theta(0))."""
    q = {j.name: j.initial for j in system.joints} | {k: v[0] for k, v in theta0(system).items()}
    return {b: tuple(float(c) for c in pose) for b, pose in poses(system, q).items()}


def check_assembly(system: System, t_end: float | None = None) -> tuple[System, Assembly]:
    """The system assembled at t = 0 (flexsym/scenes/assembly.py: the free joint coordinates
    and rates moved to close every cut joint with undeformed bodies) and what moved; refuses a
    loop that cannot close or is singular there, and (t_end given) guided drives that take it
    beyond its reach before t_end."""
    for j in system.joints:
        if j.name in system.tree().cut and (j.fixed or j.rate is not None):
            raise SpecError(f"system '{system.name}': joint '{j.name}' is a cut joint (it closes a "
                            "loop, no coordinate): fixed and rate do not apply")
    system, report = assemble(system, length_scale(system), t_end)
    if system.dimension == 3:
        _check_universal_axes(system)
    return system, report


def _check_universal_axes(system: System) -> None:
    """A loop-closing universal joint's cross axis e2 is perpendicular to its axis e1 and to the
    parent's x axis at t = 0 (physics/spatial.py): e1 along that x leaves no such direction (one
    in the tree has its parent_axis)."""
    frames = None
    for j in system.joints:
        if j.kind != "universal" or j.has_coordinate:
            continue
        frames = frames or rotations3(system)
        e1 = frames[j.child.partition(".")[0]] @ np.asarray(j.axis, float)
        x = frames[j.parent.partition(".")[0]][:, 0]
        if np.linalg.norm(np.cross(e1 / np.linalg.norm(e1), x)) < 1e-9:
            raise SpecError(f"system '{system.name}': joint '{j.name}': axis {list(j.axis)} lies along "
                            f"the x axis of '{j.parent}' at t = 0 (the cross axis, perpendicular to "
                            "both, is undefined): give an axis across it, in the child's frame")


# ----- the scene ------------------------------------------------------------------------------
def load_system_scene(path: Path, data: dict, name: str, model: str | dict | None = None) -> SystemScene:
    """A system scene, checked completely (path names the file in every message); name: the
    system's name when the scene gives none (from the file name, as for one-beam scenes);
    model: --model's variant name, or {"variant": "ef", "elements": n}, as scene.load_scene
    checked it."""
    prefix = f"{path}: "
    system, given, output_file = system_from_data(data, prefix, name, model, Path(path).parent)
    options = validate(given, Where("scene", path))
    try:
        system, assembly = checked_system(system, options.t_end)
    except SpecError as exc:
        raise SpecError(f"{prefix}{exc}") from None
    return SystemScene(path, system, options, Path(output_file) if output_file else None, model,
                       assembly, given)


def system_from_dict(data: dict, name: str = "system", t_end: float | None = None,
                     base: Path = Path(".")) -> System:
    """The Python API: the same data as a scene (a dict of lists/tables), the same checks; a
    body's folder is relative to base."""
    system, given, _ = system_from_data(data, "system data: ", name, base=Path(base))
    return checked_system(system, t_end if t_end is not None else validate(given).t_end)[0]


def summary(system: System) -> str:
    """What `flexsym inspect SCENE --section system` prints: bodies, joints (tree or cut),
    coordinates, drivers, loads, outputs, the initial assembly."""
    tree = system.tree()
    if system.dimension == 3:
        return _summary3(system)
    poses = initial_poses(system)
    guided = {d.joint for d in system.drivers if d.kind == "guided"}
    lines = [f"system '{system.name}'" + (f": {system.description}" if system.description else ""), "",
             "bodies (frame at t = 0: X, Y [m], angle [rad]):"]
    for b in system.bodies:
        X, Y, phi = poses[b.name]
        marks = ", ".join(f"{m.name} ({m.x:g}, {m.y:g})" for m in b.all_markers)
        if b.flexible:
            s = b.section
            what = (f"beam L = {b.length:g} m, rho {s.rho:g}, E {s.E:g}, A {s.A:g}, I {s.I:g}; "
                    f"model {b.model.name}")
            if b.model.kind == "modal":
                what += f" ({_modes_text(b.model)}; N {b.model.axial_force}, M {b.model.moment})"
            what = _mesh_text(b, what) + _damping_text(b)
        else:
            what = f"rigid m = {b.mass:g} kg, J = {b.inertia:g} kg m^2, com ({b.com[0]:g}, {b.com[1]:g})"
        lines.append(f"  {b.name}: {what}; frame ({X:.6g}, {Y:.6g}, {phi:.6g}); markers {marks}")
    lines += ["", "joints (tree: one per body, from ground; cut: constraint equations):"]
    for j in system.joints:
        role = "cut" if j.name in tree.cut else f"tree of {dict((v, k) for k, v in tree.parent_joint)[j.name]}"
        parent = f"ground at ({j.point[0]:g}, {j.point[1]:g})" if j.parent == GROUND else j.parent
        axis = f", axis ({j.axis[0]:g}, {j.axis[1]:g})" if j.axis else ""
        lines.append(f"  {j.name}: {j.kind} {parent} -> {j.child}{axis} [{role}]")
    lines.append("constraint equations: " + (", ".join(f"{n}: {_planar_equations(system.joint(n))}"
                                                       for n in tree.cut) or "none (a tree)"))
    free = [f"{c.name} ({'angle' if c.motion == 'turn' else 'displacement'})" for j in system.joints
            if j.name not in tree.cut for c in j.coordinates if c.name not in guided]
    lines += ["", "joint coordinates: " + (", ".join(free) or "none")
              + (f"; guided (known functions of t): {', '.join(sorted(guided))}" if guided else ""),
              "elastic coordinates: " + ", ".join(
                  f"{b.name}: {len(b.model.coordinates)} ({b.model.name})"
                  for b in system.bodies if b.flexible) if any(b.flexible for b in system.bodies)
              else "elastic coordinates: none"]
    lines += ["", "drivers:"] + [
        f"  {d.name}: {d.kind} on {d.joint}: " + (d.expression or f"{d.maneuver} "
                                                  + ", ".join(f"{k} = {v:g}" for k, v in d.params))
        for d in system.drivers] if system.drivers else ["", "drivers: none"]
    lines += ["", "loads: " + (", ".join(type(x).__name__ + (f" g = {x.g}" if isinstance(x, Gravity) else "")
                                        for x in system.loads) or "none")]
    lines += ["", "outputs:"] + [f"  {o.column} = {o.quantity}" for o in system.outputs]
    return "\n".join(lines) + "\n"


def _mesh_text(b, what: str) -> str:
    """A beam's description, said to be from finite-element data (its root section) if it is."""
    body = getattr(b.model, "body", None)
    if body is None:
        return what
    return what.replace(", rho", ", root section rho").replace(
        "beam L", f"beam from finite-element data ({body.summary()}), L")


def _damping_text(b) -> str:
    """'; damping zeta ..., alpha ..., beta ...' of a damped beam (empty if undamped)."""
    if not b.damped:
        return ""
    d = b.damping
    zeta = ", ".join(f"{z:g}" for z in d.zeta) if isinstance(d.zeta, (tuple, list)) else f"{d.zeta:g}"
    return f"; damping zeta {zeta}, alpha {d.alpha:g} 1/s, beta {d.beta:g} s"


def _planar_equations(j: Joint) -> str:
    """A planar cut joint's constraint equations, e.g. "2 (across the axis, angle)"."""
    what = {"x": "position", "normal": "across the axis", "angle": "angle"}
    rows = [s for s, _ in KINDS[j.kind].planar_rows()]
    return f"{len(rows)} ({', '.join(what[s] for s in rows if s != 'y')})"


def _axes_text(j: Joint) -> str:
    """A spatial joint's axes and coordinates for summary(): each coordinate's name, motion and
    axis (Joint.coordinates; a universal joint in the tree: parent_axis, then axis in the
    child's frame), or a loop-closing universal joint's axis (child's frame)."""
    def vec(a):
        return f"({', '.join(f'{c:g}' for c in a)})"
    if j.kind == "universal" and not j.has_coordinate:
        return f", axis {vec(j.axis)} (child's frame)"
    return "".join(f", {c.name}: {c.motion} {'about' if c.motion == 'turn' else 'along'} {vec(c.axis)}"
                   for c in j.coordinates)


def _summary3(system: System) -> str:
    """summary() of a spatial system: bodies, joints, coordinates, loads, outputs."""
    guided = {d.joint for d in system.drivers if d.kind == "guided"}
    cut = system.tree().cut
    lines = [f"system '{system.name}' (spatial)" + (f": {system.description}" if system.description else ""),
             "", "bodies:"]
    for b in system.bodies:
        marks = ", ".join(f"{m.name} ({m.x:g}, {m.y:g}, {m.z:g})" for m in b.all_markers)
        if b.flexible:
            s_ = b.section
            what = (f"beam L = {b.length:g} m, rho {s_.rho:g}, E {s_.E:g}, G {s_.G:g}, A {s_.A:g}, "
                    f"I_z {s_.I:g}, I_y {s_.Iy:g}, J {s_.J:g}; model {b.model.name} "
                    + (f"({_modes_text(b.model)}; N {b.model.axial_force}, M {b.model.moment})"
                       if b.model.kind == "modal" else "(ef)"))
            what = _mesh_text(b, what) + _damping_text(b)
        else:
            what = (f"rigid m = {b.mass:g} kg, principal inertia ({', '.join(f'{v:g}' for v in b.inertia)}) "
                    f"kg m^2, com ({', '.join(f'{c:g}' for c in b.com)})")
        lines.append(f"  {b.name}: {what}; markers {marks}")
    lines += ["", "joints (a tree from ground, and those closing loops):"]
    for j in system.joints:
        parent = f"ground at ({', '.join(f'{c:g}' for c in j.point)})" if j.parent == GROUND else j.parent
        lines.append(f"  {j.name}: {j.kind} {parent} -> {j.child}{_axes_text(j)}"
                     + (" [guided]" if j.name in guided else "")
                     + (" [closes a loop]" if j.name in cut else ""))
    lines += ["", "elastic coordinates: " + "; ".join(
        f"{b.name}: " + (", ".join(n for n, _, _ in beam_coordinates(b)) if b.model.kind == "modal"
                         else f"ux, uy, uz, px, py, pz of nodes 1..{b.model.elements} (ef)")
        for b in system.bodies if b.flexible)]
    lines += ["", "loads: " + (", ".join(type(x).__name__ + (f" g = {x.g}" if isinstance(x, Gravity) else "")
                                        for x in system.loads) or "none")]
    lines += ["", "outputs:"] + [f"  {o.column} = {o.quantity}" for o in system.outputs]
    return "\n".join(lines) + "\n"
