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

from .cemit import EmittedKernel, c_double, emit
from .derive import Derivation, derive
from .energy import BEAM_PARAMS
from .kernels import build_kernels
from .outputs import OUTPUTS
from .paths import templates_dir
from .spec import VariantSpec
from .versions import generator_hash, tool_versions

MANIFEST = "manifest.json"
C_PREFIX = "fsm_"


def fingerprint(spec: VariantSpec) -> str:
    """What the generated code depends on: the spec, the generator code and the tool versions."""
    payload = {"spec": spec.to_dict(), "generator": generator_hash(), "versions": tool_versions()}
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


def _mode_description(der: Derivation, name: str) -> str:
    return der.modes[name].description


def render(spec: VariantSpec, der: Derivation, emitted: list[EmittedKernel], fp: str) -> dict[str, str]:
    versions = tool_versions()
    ctx = {
        "spec": {"name": spec.name, "strain": spec.strain,
                 "axial": [m.token for m in spec.axial], "bending": [m.token for m in spec.bending]},
        "name": spec.name,
        "NAME": spec.name.upper(),
        "generator": f"flexsym {versions['flexsym']}",
        "versions": versions,
        "fingerprint": fp,
        "header": f"fsm_{spec.name}.h",
        "coords": [{"name": c, "description": _mode_description(der, c)} for c in der.coords],
        "outputs": [{"name": o, "unit": OUTPUTS[o].unit, "description": OUTPUTS[o].description}
                    for o in spec.outputs],
        "params": [{"name": p.name, "unit": p.unit, "description": p.description,
                    "c_default": c_double(p.default)} for p in BEAM_PARAMS],
        "maneuver": {"name": der.maneuver.name},
        "maneuver_params": [{"name": p.name, "unit": p.unit, "description": p.description,
                             "c_default": c_double(p.default)} for p in der.maneuver.params],
        "mass_constant": der.mass_constant,
        "length_param": [p.name for p in BEAM_PARAMS].index("L"),
        "v_tip_output": list(spec.outputs).index("v_tip") if "v_tip" in spec.outputs else -1,
        "kernels": emitted,
    }
    env = _environment()
    return {
        f"fsm_{spec.name}.h": env.get_template("model.h.j2").render(ctx),
        "kernels.c": env.get_template("kernels.c.j2").render(ctx),
        "model.c": env.get_template("model.c.j2").render(ctx),
        "CMakeLists.txt": env.get_template("CMakeLists.txt.j2").render(ctx),
    }


def build_manifest(spec: VariantSpec, der: Derivation, emitted: list[EmittedKernel], fp: str,
                   files: dict[str, str]) -> dict:
    integrals = []
    for sym in der.table.symbols:
        v = der.table.value(sym)
        integrals.append({"symbol": str(sym), "value": mpmath.nstr(v.value, 20),
                          "method": v.method, "error_estimate": float(f"{v.error:.3e}"),
                          "exact": str(v.exact) if v.exact is not None else None})
    return {
        "generator": f"flexsym {tool_versions()['flexsym']}",
        "versions": tool_versions(),
        "fingerprint": fp,
        "spec": spec.to_dict(),
        "description": spec.description,
        "coordinates": [{"name": c, "group": der.groups[c], "mode": der.modes[c].description}
                        for c in der.coords],
        "outputs": list(spec.outputs),
        "params": [{"name": p.name, "default": p.default, "unit": p.unit} for p in BEAM_PARAMS],
        "maneuver": {"name": der.maneuver.name, "theta": str(der.maneuver.theta),
                     "params": [{"name": p.name, "default": p.default, "unit": p.unit}
                                for p in der.maneuver.params]},
        "energy_terms": [{"term": t.name, "formula": t.formula, "differentiated_wrt": list(t.wrt)}
                         for t in der.terms],
        "mass_constant": der.mass_constant,
        "conservative": der.conservative,
        "left_out": der.dropped,
        "kernels": {k.kernel.name: {"c_name": k.c_name, "ops": k.ops, "total_ops": k.total_ops,
                                    "inputs": {p.name: p.size for p in k.kernel.inputs},
                                    "outputs": {p.name: [p.rows, p.cols] for p in k.kernel.outputs}}
                    for k in emitted},
        "modal_integrals": integrals,
        "files": {name: hashlib.sha256(text.encode()).hexdigest() for name, text in sorted(files.items())},
    }


def generate_files(spec: VariantSpec) -> tuple[dict[str, str], Derivation, list[EmittedKernel]]:
    """Everything a generated folder holds, as text, without touching the disk."""
    spec.validate()
    fp = fingerprint(spec)
    der = derive(spec)
    emitted = [emit(k, C_PREFIX) for k in build_kernels(der)]
    files = render(spec, der, emitted, fp)
    manifest = build_manifest(spec, der, emitted, fp, files)
    files[MANIFEST] = json.dumps(manifest, indent=2, sort_keys=False) + "\n"
    return files, der, emitted


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


def generate(spec: VariantSpec, dest: Path) -> Generated:
    files, _, _ = generate_files(spec)
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

