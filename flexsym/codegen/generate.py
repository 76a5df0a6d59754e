"""Spec -> derivation -> kernels -> a generated folder (C, CMakeLists, manifest.json).

The folder is written to a temporary sibling and swapped in, so a failed generation never
leaves a half-written variant behind. Output is deterministic: no timestamps, no absolute
paths, no hash-ordered iteration.
"""
from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

import jinja2
import mpmath

from flexsym.emit.cemit import EmittedKernel, c_double, emit
from flexsym.codegen.derive import build_kernels, derive
from flexsym.model.parameters import BEAM_PARAMS
from flexsym.physics.fe import build_element_kernels, derive_element, output_plan
from flexsym.model.maneuver import maneuver_of
from flexsym.model.output_names import info as output_info
from flexsym.core.paths import templates_dir
from flexsym.model.variant import CLAMP_OUTPUTS, QUAD_POINTS, VariantSpec
from flexsym.core.versions import generator_hash, tool_versions

MANIFEST = "manifest.json"


def c_prefix(name: str) -> str:
    """The prefix of a model's C symbols, fsm_<name>_: kernels fsm_<name>_<kernel>, so that
    several models link into one program or library (model names are C identifiers)."""
    return f"fsm_{name}_"


def model_accessor(name: str) -> str:
    """The one function a generated folder exports for the runtime: fsm_<name>_model(), its
    model as the struct of runtime_c/include/flexsym/system.h. The generated CMakeLists.txt
    gives it to the driver, the manifest ("model") to the in-process library and the FMU."""
    return c_prefix(name) + "model"


def _versions(spec) -> dict[str, str]:
    """Tool versions; a body from finite-element data adds numpy and scipy (its eigenvectors)."""
    versions = tool_versions()
    if getattr(spec, "body", None) is not None:
        import numpy
        import scipy

        versions |= {"numpy": numpy.__version__, "scipy": scipy.__version__}
    return versions


def param_defaults(spec) -> dict[str, float]:
    """Beam parameters compiled in as defaults: a body's reference (root) section and length."""
    values = {p.name: p.default for p in BEAM_PARAMS}
    body = getattr(spec, "body", None)
    if body is not None:
        r = body.reference
        values |= {"rho": r.rho, "E": r.E, "A": r.A, "I": r.I, "L": body.length}
    return values


def fingerprint(spec) -> str:
    """What the generated code depends on: the spec, the generator code and the tool versions."""
    payload = {"spec": spec.to_dict(), "generator": generator_hash(), "versions": _versions(spec)}
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()


@dataclass
class Generated:
    spec: VariantSpec
    path: Path
    manifest: dict


def _environment() -> jinja2.Environment:
    return jinja2.Environment(loader=jinja2.FileSystemLoader(str(templates_dir())),
                              undefined=jinja2.StrictUndefined, keep_trailing_newline=True,
                              autoescape=False)


def _common_context(spec, fp: str, maneuver, emitted: list[EmittedKernel]) -> dict:
    versions = _versions(spec)
    defaults = param_defaults(spec)
    return {
        "name": spec.name,
        "NAME": spec.name.upper(),
        "generator": f"flexsym {versions['flexsym']}",
        "versions": versions,
        "fingerprint": fp,
        "header": f"fsm_{spec.name}.h",
        "prefix": c_prefix(spec.name),
        "accessor": model_accessor(spec.name),
        "params": [{"name": p.name, "unit": p.unit, "description": p.description,
                    "c_default": c_double(defaults[p.name])} for p in BEAM_PARAMS],
        "maneuver": {"name": maneuver.name},
        "maneuver_params": [{"name": p.name, "unit": p.unit, "description": p.description,
                             "c_default": c_double(p.default)} for p in maneuver.params],
        "length_param": [p.name for p in BEAM_PARAMS].index("L"),
        "kernels": emitted,
        "has_residual": any(k.kernel.name == "residual" for k in emitted),
        "element_kernels": [],
        "bandwidth": -1,
    }


def _modal(spec: VariantSpec, fp: str) -> tuple[dict, dict, str]:
    der = derive(spec)
    emitted = [emit(k, c_prefix(spec.name)) for k in build_kernels(der)]
    ctx = _common_context(spec, fp, der.maneuver, emitted) | {
        "summary": f"Strain model: {spec.strain}; axial modes: "
                   f"{', '.join(m.token for m in spec.axial) or 'none'}; bending modes: "
                   f"{', '.join(m.token for m in spec.bending)}.",
        "coords": [{"name": c, "description": der.modes[c].description} for c in der.coords],
        "outputs": [vars(output_info(o, spec.points)) for o in spec.outputs],
        "mass_constant": der.mass_constant,
        "outputs_use_acceleration": der.outputs_use_acceleration,
        "outputs_use_drive": der.outputs_use_drive,
    }
    integrals = []
    if spec.body is not None:
        ctx["summary"] += " " + spec.body.summary() + " (modes computed from it)."
    for sym in der.integrals:
        v = der.table.value(sym)
        integrals.append({"symbol": str(sym), "value": mpmath.nstr(v.value, 20),
                          "method": v.method, "error_estimate": float(f"{v.error:.3e}"),
                          "exact": str(v.exact) if v.exact is not None else None})
    manifest = {
        "coordinates": [{"name": c, "group": der.groups[c], "mode": der.modes[c].description}
                        for c in der.coords],
        "energy_terms": [{"term": t.name, "formula": t.formula, "differentiated_wrt": list(t.wrt)}
                         for t in der.terms],
        "conservative": der.conservative,
        "left_out": [{"what": w, "why": y} for w, y in spec.left_out] + der.dropped,
        "modal_integrals": integrals,
    }
    if getattr(der, "exact", False):
        manifest["exact_kinematics"] = {"quadrature": der.quadrature.describe()}
    if spec.body is not None:
        manifest["body"] = spec.body.to_dict() | {
            "modes": [{"coordinate": c, "description": der.modes[c].description} for c in der.coords],
            "invariants": "fe_gauss: Gauss-Legendre per element (exact for the piecewise "
                          "polynomial shapes) in double precision, rounded to 13 digits"}
    return ctx, manifest, "model.c.j2"


def _fe_body(body) -> dict | None:
    """Per-element ratios to the reference section, node fractions, point masses (ef)."""
    if body is None:
        return None
    r, L = body.reference, body.length
    rows = [[c_double(v) for v in (s.rho / r.rho, s.E / r.E, s.A / r.A, s.I / r.I, (b - a) / L)]
            for s, a, b in zip(body.sections, body.nodes, body.nodes[1:])]
    masses = [{"node": body.node_index(m.x), "ratio": c_double(m.mass / (r.rho * r.A * L))}
              for m in body.masses if body.node_index(m.x) > 0 and m.mass > 0]
    return {"elements": rows, "nodes": [c_double(x) for x in body.s_nodes], "masses": masses}


def _finite_elements(spec, fp: str) -> tuple[dict, dict, str]:
    der = derive_element(spec)
    emitted = [emit(k, c_prefix(spec.name)) for k in build_element_kernels(der)]
    needs_clamp = any(o in CLAMP_OUTPUTS for o in spec.outputs)
    outputs = [{"name": o, "unit": "N" if o.startswith("N") else "N m",
                "description": f"{'axial force' if o.startswith('N') else 'bending moment'} at the "
                               "root from the clamp reaction"} if o in CLAMP_OUTPUTS
               else vars(output_info(o, spec.points)) for o in spec.outputs]
    names = {"ux": "x displacement", "uy": "y displacement", "dx": "change of x_x", "dy": "change of y_x"}
    ctx = _common_context(spec, fp, der.maneuver, emitted) | {
        "summary": f"Finite elements: {spec.elements} geometrically exact ANCF cable elements.",
        "coords": [{"name": c, "description": f"{names[c[:2]]} of node {c[2:]}"} for c in spec.coordinates],
        "outputs": outputs,
        "mass_constant": True,
        "outputs_use_acceleration": needs_clamp,
        "outputs_use_drive": needs_clamp,  # the clamp reaction has the frame's inertia in it
        "bandwidth": 7,  # a node couples to its neighbours only: 4 + 3 coordinates
        "element_kernels": [k for k in emitted if k.kernel.name != "maneuver"],
        "elements": spec.elements,
        "plan": output_plan(spec),
        "needs_clamp": needs_clamp,
        "needs_stress": any(o not in CLAMP_OUTPUTS and o not in ("v_tip", "u_tip") for o in spec.outputs),
        "body": _fe_body(spec.body),
    }
    manifest = {
        "coordinates": [{"name": c["name"], "group": "node", "mode": c["description"]} for c in ctx["coords"]],
        "element": {"formulation": "ANCF cable (cubic Hermite positions and slopes)",
                    "strain": str(der.strain), "curvature": str(der.curvature),
                    "kinetic_energy": str(der.T), "quadrature_points": QUAD_POINTS},
        "conservative": True,
        "left_out": [{"what": w, "why": y} for w, y in spec.left_out],
    }
    return ctx, manifest, "fe_model.c.j2"


def generate_files(spec) -> dict[str, str]:
    """Everything a generated folder holds, as text, without touching the disk."""
    spec.validate()
    fp = fingerprint(spec)
    ctx, extra, model_template = (_finite_elements if spec.kind == "fe" else _modal)(spec, fp)
    env = _environment()
    files = {
        f"fsm_{spec.name}.h": env.get_template("model.h.j2").render(ctx),
        "kernels.c": env.get_template("kernels.c.j2").render(ctx),
        "model.c": env.get_template(model_template).render(ctx),
        "CMakeLists.txt": env.get_template("CMakeLists.txt.j2").render(ctx),
    }
    emitted = ctx["kernels"]
    maneuver = maneuver_of(spec.maneuver)
    manifest = {
        "generator": ctx["generator"],
        "versions": ctx["versions"],
        "fingerprint": fp,
        "model": ctx["accessor"],
        "spec": spec.to_dict(),
        "description": spec.description,
        "outputs": list(spec.outputs),
        "params": [{"name": p.name, "default": v, "unit": p.unit}
                   for p, v in zip(BEAM_PARAMS, param_defaults(spec).values())],
        "maneuver": {"name": maneuver.name, "theta": str(maneuver.theta),
                     "params": [{"name": p.name, "default": p.default, "unit": p.unit}
                                for p in maneuver.params]},
        "mass_constant": ctx["mass_constant"],
        "outputs_use_acceleration": ctx["outputs_use_acceleration"],
        "outputs_use_drive": ctx["outputs_use_drive"],
        "bandwidth": ctx["bandwidth"],
        **extra,
        "kernels": {k.kernel.name: {"c_name": k.c_name, "ops": k.ops, "total_ops": k.total_ops,
                                    "inputs": {p.name: p.size for p in k.kernel.inputs},
                                    "outputs": {p.name: [p.rows, p.cols] for p in k.kernel.outputs}}
                    for k in emitted},
        "files": {name: hashlib.sha256(text.encode()).hexdigest() for name, text in sorted(files.items())},
    }
    files[MANIFEST] = json.dumps(manifest, indent=2) + "\n"
    return files


def write_folder(files: dict[str, str], dest: Path) -> None:
    """Write files into dest as a whole: a temporary sibling, then swapped in."""
    dest = Path(dest)
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{dest.name}.tmp-", dir=dest.parent))
    try:
        for name, text in files.items():
            (tmp / name).write_text(text, encoding="utf-8", newline="\n")
        old = None
        if dest.exists():
            old = dest.parent / f".{dest.name}.old-{os.getpid()}"
            os.rename(dest, old)
        os.rename(tmp, dest)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def generate(spec, dest: Path) -> Generated:
    files = generate_files(spec)
    write_folder(files, dest)
    return Generated(spec, Path(dest), json.loads(files[MANIFEST]))


def read_manifest(folder: Path) -> dict | None:
    try:
        return json.loads((Path(folder) / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def check_folder(spec: VariantSpec, folder: Path) -> str | None:
    """None when folder holds current, unmodified code for spec; else why it does not."""
    manifest = read_manifest(folder)
    if manifest is None:
        return f"{folder} has no readable {MANIFEST}"
    if manifest.get("fingerprint") != fingerprint(spec):
        return (f"{folder} was generated from another spec or generator version "
                f"(fingerprint {str(manifest.get('fingerprint'))[:12]}..., expected {fingerprint(spec)[:12]}...)")
    for name, digest in manifest.get("files", {}).items():
        try:
            actual = hashlib.sha256((Path(folder) / name).read_bytes()).hexdigest()
        except OSError:
            return f"{folder}/{name} is missing"
        if actual != digest:
            return f"{folder}/{name} was edited by hand (its hash differs from the manifest)"
    return None


def folder_hash(folder: Path) -> str:
    h = hashlib.sha256()
    for f in sorted(Path(folder).iterdir()):
        if f.is_file():
            h.update(f.name.encode() + b"\0" + f.read_bytes())
    return h.hexdigest()

