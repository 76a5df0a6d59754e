"""Scene files (TOML): the beam, the manoeuvre, the model, the solver and the outputs of one
simulation, turned into exactly the variant that scene needs.

    [beam]      length, density, youngs_modulus, area, inertia            (SI units)
    [body]      instead of [beam]: a body from finite-element data: segments (length and
                section each), point_masses, elements (for its modes), ef_elements, or
                folder (an imported one; fedata.scene_body, feimport)
    [maneuver]  kind = "spin-up" (omega, duration) | "constant" (omega) | "expression" (theta)
    [model]     variant = "m3"  or  strain + axial + bending (mode lists); optional stress,
                axial_force, elements (ef), keep_axial, name
    [solver]    integrator, dt, t_end; tol for dopri5, optional step for radau5 (then dt is the
                output interval)
    [output]    file (relative to the working directory), quantities (v_tip, u_tip, N(x), M(x)),
                positions = { name = x [m] }, interval (s between rows, default 0.01)

Every problem is reported as one line naming the file, the key and what is wrong, before
anything is generated, built or written.
"""
from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path

import sympy as sp

from flexsym.core.errors import SpecError
from flexsym.core.files import read_limited
from flexsym.model.limits import MAX_FILE_BYTES, MAX_MAGNITUDE, MIN_POSITIVE
from flexsym.model.maneuver import EXPRESSION_PREFIX, parse_theta
from flexsym.model.options import OPTIONS, RunOptions, Where, validate
from flexsym.model.strain_models import STRAIN_MODELS

# Keys of each table; run options (solver, output, manoeuvre values) come from the option table.
_RUN_KEYS = {o.scene: o.name for o in OPTIONS if o.scene}
TABLES = {
    "beam": {"length", "density", "youngs_modulus", "area", "inertia"},
    "body": {"segments", "point_masses", "elements", "ef_elements", "folder"},
    "maneuver": {"kind", "theta"},
    "model": {"variant", "strain", "axial", "bending", "stress", "axial_force", "moment", "elements",
              "keep_axial", "name"},
    "solver": set(),
    "output": {"file", "quantities", "positions"},
}
for _key in _RUN_KEYS:
    TABLES[_key.split(".")[0]].add(_key.split(".")[1])
BEAM_KEYS = {"density": "rho", "youngs_modulus": "E", "area": "A", "inertia": "I", "length": "L"}
_QUANTITY = re.compile(r"([NM])\(\s*([^()]+?)\s*\)")


@dataclass
class Scene:
    path: Path
    spec: object  # VariantSpec | FESpec
    options: RunOptions  # validated: solver, output interval, beam and manoeuvre parameters
    output_file: Path | None
    columns: dict = field(default_factory=dict)  # scene quantity -> result column
    full_spec: object = None  # the same model without the scene's reductions (for comparison)
    given: dict = field(default_factory=dict)  # run options as the scene gives them (None: not)

    # the run options most callers read
    params = property(lambda self: self.options.params)
    integrator = property(lambda self: self.options.integrator)
    dt = property(lambda self: self.options.dt)
    t_end = property(lambda self: self.options.t_end)
    out_every = property(lambda self: self.options.out_every)
    tol = property(lambda self: self.options.tol)
    step = property(lambda self: self.options.step)


class _SceneError(SpecError):
    """Already names the file and the key: not to be wrapped again."""


class _Reader:
    """Typed access to the parsed TOML with errors that name the file and the key."""

    def __init__(self, path: Path, data: dict):
        self.path, self.data = path, data

    def fail(self, where: str, msg: str):
        raise _SceneError(f"{self.path}: {where}: {msg}")

    def table(self, name: str, required: bool = True) -> dict:
        tab = self.data.get(name)
        if tab is None:
            if required:
                self.fail(f"[{name}]", "missing table")
            return {}
        if not isinstance(tab, dict):
            self.fail(f"[{name}]", f"must be a table, not {type(tab).__name__}")
        unknown = sorted(set(tab) - TABLES[name])
        if unknown:
            self.fail(f"[{name}] {unknown[0]}", f"unknown key (known: {', '.join(sorted(TABLES[name]))})")
        return tab

    def number(self, tab: str, key: str, *, positive=False, required=True, default=None) -> float | None:
        val = self.data.get(tab, {}).get(key)
        if val is None:
            if required:
                self.fail(f"[{tab}] {key}", "missing")
            return default
        if isinstance(val, bool) or not isinstance(val, (int, float)):
            self.fail(f"[{tab}] {key}", f"must be a number, not {type(val).__name__} ({val!r})")
        if not math.isfinite(val):
            self.fail(f"[{tab}] {key}", f"must be finite (got {val!r})")
        if abs(val) > MAX_MAGNITUDE:
            self.fail(f"[{tab}] {key}", f"{val!r} is beyond the limit |x| <= {MAX_MAGNITUDE:g} (SI units; "
                      "larger values overflow the generated code's arithmetic)")
        if positive and not val > 0:
            self.fail(f"[{tab}] {key}", f"must be > 0 (got {val!r})")
        if positive and val < MIN_POSITIVE:
            self.fail(f"[{tab}] {key}", f"{val!r} is below the limit {MIN_POSITIVE:g} (a positive quantity; "
                      "its reciprocal powers appear in the equations)")
        return float(val)

    def string(self, tab: str, key: str, required=True, default=None) -> str | None:
        val = self.data.get(tab, {}).get(key)
        if val is None:
            if required:
                self.fail(f"[{tab}] {key}", "missing")
            return default
        if not isinstance(val, str):
            self.fail(f"[{tab}] {key}", f"must be a string, not {type(val).__name__} ({val!r})")
        return val

    def strings(self, tab: str, key: str, required=True) -> list[str] | None:
        val = self.data.get(tab, {}).get(key)
        if val is None:
            if required:
                self.fail(f"[{tab}] {key}", "missing")
            return None
        if not isinstance(val, list) or not all(isinstance(v, str) for v in val):
            self.fail(f"[{tab}] {key}", f"must be a list of strings (got {val!r})")
        return val


def load_scene(path, model: str | dict | None = None):
    """A Scene, or a SystemScene for a mechanism. model: a variant name that replaces the
    scene's [model] (flexsym run --model), or every flexible body's model in a system; or
    {"variant": "ef", "elements": n} (--model ef --elements n)."""
    if not isinstance(path, (str, Path)):
        raise SpecError(f"load_scene(): path must be the path of a .toml scene (got "
                        f"{type(path).__name__} {path!r})")
    path = Path(path)
    try:
        data = tomllib.loads(read_limited(path, MAX_FILE_BYTES, "scene file").decode("utf-8"))
    except FileNotFoundError:
        raise SpecError(f"{path}: no such scene file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SpecError(f"{path}: cannot read: {exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise SpecError(f"{path}: not valid TOML: {exc}") from None
    from flexsym.scenes.system_scene import is_system_scene, load_system_scene

    if model is not None:  # --model (and --elements), checked once for either kind of scene
        mesh = dict(model) if isinstance(model, dict) else {"variant": model}
        variant = mesh.pop("variant", None)
        if not isinstance(variant, str) or not re.match(r"^[a-z][a-z0-9_]*$", variant):
            raise SpecError(f"{path}: --model: '{variant}' is not a variant name")
    if is_system_scene(data):  # a mechanism ([[body]] entries): flexsym/scenes/system_scene.py
        return load_system_scene(path, data, _default_name(path), model)
    r = _Reader(path, data)
    unknown = sorted(set(data) - set(TABLES))
    if unknown:
        r.fail(unknown[0], f"unknown table (known: {', '.join(TABLES)})")
    if model is not None:
        model = variant
        data["model"] = {"variant": model, **mesh, "name": f"{_default_name(path)}_{model}"[:48]}
        from flexsym.model.output_names import axial_force_available
        from flexsym.model.variant import builtin

        try:
            base = builtin(model)
        except SpecError as exc:
            r.fail("--model", str(exc))
        if base.kind == "modal" and not axial_force_available(base):
            data["model"]["axial_force"] = "equilibrium"  # its only way to give the scene's N
    for name in TABLES:
        r.table(name, required=name in ("maneuver", "model", "solver"))

    body = None
    if "body" in data:
        if "beam" in data:
            r.fail("[body]", "give either [beam] (a uniform beam) or [body] (finite-element data), not both")
        from flexsym.model.fedata import scene_body
        from flexsym.scenes.feimport import scene_folder

        body = scene_folder(r) if "folder" in data["body"] else scene_body(r)
        ref = body.reference
        beam = {"rho": ref.rho, "E": ref.E, "A": ref.A, "I": ref.I, "L": body.length}
    else:
        r.table("beam")
        beam = {BEAM_KEYS[k]: r.number("beam", k, positive=True) for k in BEAM_KEYS}
    maneuver = _maneuver(r)
    for key in ("solver.dt", "solver.t_end"):
        table, name = key.split(".")
        if name not in data[table]:
            r.fail(f"[{table}] {name}", "missing")
    given = {name: data.get(key.split(".")[0], {}).get(key.split(".")[1]) for key, name in _RUN_KEYS.items()}
    output_file = r.string("output", "file", required=False)
    if output_file is not None and not output_file.strip():
        r.fail("[output] file", "is empty (leave the key out for no file)")
    quantities = r.strings("output", "quantities", required=False)
    if quantities is not None and not quantities:
        r.fail("[output] quantities", "is empty (leave the key out for v_tip only)")
    points, outputs, columns = _outputs(r, quantities or ["v_tip"], beam["L"])
    spec, full = _spec(r, maneuver, outputs, points, body)
    given = given | {"params": beam}
    options = validate(given, Where("scene", path), spec)
    return Scene(path, spec, options, Path(output_file) if output_file else None, columns, full, given)


def _maneuver(r: _Reader) -> str:
    """The manoeuvre's name; its values (omega, duration) are run options (options.py)."""
    kind = r.string("maneuver", "kind")
    tab = r.data["maneuver"]
    allowed = {"spin-up": {"kind", "omega", "duration"}, "constant": {"kind", "omega"},
               "expression": {"kind", "theta"}}
    if kind not in allowed:
        r.fail("[maneuver] kind", f"unknown kind '{kind}' (known: spin-up, constant, expression)")
    extra = sorted(set(tab) - allowed[kind])
    if extra:
        r.fail(f"[maneuver] {extra[0]}", f"does not apply to kind '{kind}'")
    for key in sorted(allowed[kind] - {"kind"}):
        if key not in tab:
            r.fail(f"[maneuver] {key}", "missing")
    if kind == "expression":
        theta = r.string("maneuver", "theta")
        try:
            parse_theta(theta)
        except SpecError as exc:
            r.fail("[maneuver] theta", str(exc))
        return EXPRESSION_PREFIX + theta
    return {"spin-up": "spin_up", "constant": "constant"}[kind]


def _number_label(x: float) -> str:
    text = repr(float(x)).rstrip("0").rstrip(".") if "." in repr(float(x)) else repr(x)
    return "x" + text.replace(".", "p").replace("-", "m")


def _outputs(r: _Reader, quantities: list[str], length: float):
    """Scene quantities -> (named points, output names, column names)."""
    named = r.data.get("output", {}).get("positions", {})
    if not isinstance(named, dict):
        r.fail("[output] positions", "must be a table of name = position in metres")
    points, outputs, columns = {}, [], {}
    from flexsym.model.output_names import LABEL_RE, POINTS

    def position(label: str, x) -> None:
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
            r.fail(f"[output] positions.{label}", f"must be a number of metres (got {x!r})")
        if not 0 <= x <= length:
            r.fail(f"[output] positions.{label}", f"x = {x:g} m is outside the beam [0, {length:g}] m")
        points[label] = str(sp.nsimplify(repr(float(x))) / sp.nsimplify(repr(float(length))))

    for label, x in named.items():
        if not isinstance(label, str) or not LABEL_RE.fullmatch(label) or label in POINTS:
            r.fail(f"[output] positions.{label}", "a position name must be letters, digits and _, "
                   "start with a letter (it reaches generated C) and not be A, B or C")
        position(label, x)
    for q in quantities:
        q = q.strip()
        if q in ("v_tip", "u_tip") or re.fullmatch(r"[NM]_[A-C]", q):
            name = q
        else:
            m = _QUANTITY.fullmatch(q)
            if not m:
                r.fail("[output] quantities", f"unknown quantity '{q}' (v_tip, u_tip, N(x), M(x) "
                       "with x a position name, A, B, C or metres)")
            where = m.group(2)
            if where in POINTS:
                name = f"{m.group(1)}_{where}"
            elif where in named:
                name = f"{m.group(1)}_{where}"
            else:
                try:
                    x = float(where)
                except ValueError:
                    r.fail("[output] quantities", f"'{q}': '{where}' is neither a number of metres nor "
                           "a name in [output] positions")
                label = _number_label(x)
                position(label, x)
                name = f"{m.group(1)}_{label}"
        if name in outputs:
            r.fail("[output] quantities", f"'{q}' is asked for twice")
        outputs.append(name)
        columns[q] = name
    used = {o[2:] for o in outputs if o[:2] in ("N_", "M_")}
    return tuple((k, v) for k, v in points.items() if k in used), tuple(outputs), columns


def _spec(r: _Reader, maneuver: str, outputs, points, body=None):
    from flexsym.model.variant import VariantSpec, _refs, builtin, customize

    tab = r.data["model"]
    variant = r.string("model", "variant", required=False)
    name = r.string("model", "name", required=False)
    if variant is not None and ("strain" in tab or "axial" in tab or "bending" in tab):
        r.fail("[model] variant", "give either variant or strain/axial/bending, not both")
    try:
        if variant is not None:
            base = builtin(variant)
        else:
            strain = r.string("model", "strain", required=False)
            if strain is None:
                r.fail("[model]", "needs variant = \"...\" or strain with axial and bending mode lists")
            base = VariantSpec("scene", strain, _refs("axial", r.strings("model", "axial", required=False) or []),
                               _refs("bending", r.strings("model", "bending")))
        elements = None
        if "elements" in tab:
            elements = tab["elements"]
            if isinstance(elements, bool) or not isinstance(elements, int):
                r.fail("[model] elements", f"must be an integer (got {elements!r})")
        stress = r.string("model", "stress", required=False)
        axial_force = r.string("model", "axial_force", required=False)
        moment = r.string("model", "moment", required=False)
        keep_axial = tab.get("keep_axial", False)
        if not isinstance(keep_axial, bool):
            r.fail("[model] keep_axial", f"must be true or false (got {keep_axial!r})")
        name = name or _default_name(r.path)
        if body is not None:  # the body replaces the uniform beam of every model
            if base.kind == "fe":
                n = elements if elements is not None else r.data["body"].get("ef_elements", 32)
                base, elements = replace(base, body=body.remeshed(n), elements=None), None
                base = replace(base, elements=base.body.elements)
            elif getattr(STRAIN_MODELS.get(base.strain), "kinematics", "") == "exact":  # in a system only
                raise SpecError("the exact kinematics on the guided hub integrates a uniform beam; "
                                "a [body] from finite-element data needs another strain model here "
                                "(in a system it runs: scenes/stepped_hub.toml)")
            else:
                base = replace(base, body=body)
        spec = customize(base, name=name, outputs=list(outputs), maneuver=maneuver, stress=stress,
                         axial_force=axial_force, elements=elements, points=points, moment=moment)
        full = customize(base, name=name, maneuver="spin_up", stress=stress, axial_force=axial_force,
                         moment=moment,
                         elements=elements)
    except _SceneError:
        raise
    except SpecError as exc:
        r.fail("[model]", str(exc))
    if spec.kind == "modal" and not keep_axial:
        spec = _drop_unused_axial(spec)
    return spec, full


def _default_name(path: Path) -> str:
    stem = re.sub(r"[^a-z0-9_]", "_", path.stem.lower()).strip("_") or "scene"
    return ("scene_" + stem if not stem[0].isalpha() else stem)[:40]


def _drop_unused_axial(spec):
    """Axial modes that no energy term couples to bending and no output reads are left out
    (strain models linear, foreshortening, prestress). They still touch bending through
    Coriolis terms: about 1e-4 of v_tip on the paper's spin-up (tests/test_scene.py);
    keep_axial = true keeps them."""
    if not spec.axial or spec.strain not in ("linear", "foreshortening", "prestress"):
        return spec
    if any(o == "u_tip" or o.startswith("N_") for o in spec.outputs):
        return spec
    note = (f"axial modes {', '.join(m.token for m in spec.axial)}",
            f"strain model '{spec.strain}' takes no stiffening from them and no requested output "
            "reads them; they couple to bending only through Coriolis terms (~1e-4 of v_tip); "
            "keep_axial = true keeps them")
    return replace(spec, axial=(), left_out=spec.left_out + (note,)).validate()
