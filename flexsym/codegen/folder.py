"""A generated folder as files: its names (the model's C prefix and accessor), its templates'
environment, its manifest, and writing it whole (a temporary sibling swapped in, so a failed
generation never leaves a half-written folder behind). Output is deterministic: no
timestamps, no absolute paths, no hash-ordered iteration."""
from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
from pathlib import Path

import jinja2

from flexsym.core.paths import templates_dir

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


def environment() -> jinja2.Environment:
    return jinja2.Environment(loader=jinja2.FileSystemLoader(str(templates_dir())),
                              undefined=jinja2.StrictUndefined, keep_trailing_newline=True,
                              autoescape=False)


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


def read_manifest(folder: Path) -> dict | None:
    try:
        return json.loads((Path(folder) / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def unchanged(folder: Path, fingerprint: str) -> str | None:
    """None when folder holds the files its manifest lists, unedited, generated for
    fingerprint; else why not."""
    manifest = read_manifest(folder)
    if manifest is None:
        return f"{folder} has no readable {MANIFEST}"
    if manifest.get("fingerprint") != fingerprint:
        return (f"{folder} was generated from another spec or generator version "
                f"(fingerprint {str(manifest.get('fingerprint'))[:12]}..., expected {fingerprint[:12]}...)")
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
