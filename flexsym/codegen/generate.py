"""A one-beam variant's generated folder: the folder of its S0 (library.variant_system: its beam
on a guided revolute to ground), which sysgen derives and writes as any system's, with the
variant's own spec in the manifest ("variant"). One path from a model to C: a variant's and a
mechanism's folders differ in their data only."""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from flexsym.codegen.folder import MANIFEST, unchanged, write_folder
from flexsym.codegen.sysgen import fingerprint as system_fingerprint
from flexsym.codegen.sysgen import generate_system_files
from flexsym.model.library import variant_system


def fingerprint(spec) -> str:
    """What the variant's generated code depends on: its S0 (the spec), the generator's code
    and the tool versions (sysgen.fingerprint)."""
    spec.validate()
    return system_fingerprint(variant_system(spec))


@dataclass
class Generated:
    spec: object
    path: Path
    manifest: dict


def generate_files(spec, log=None) -> dict[str, str]:
    """Everything a variant's generated folder holds, as text, without touching the disk."""
    spec.validate()
    files = generate_system_files(variant_system(spec), log)
    manifest = json.loads(files[MANIFEST])
    manifest["variant"] = spec.to_dict()
    manifest["description"] = spec.description
    files[MANIFEST] = json.dumps(manifest, indent=2) + "\n"
    return files


def generate(spec, dest: Path) -> Generated:
    files = generate_files(spec)
    write_folder(files, dest)
    return Generated(spec, Path(dest), json.loads(files[MANIFEST]))


def check_folder(spec, folder: Path) -> str | None:
    """None when folder holds current, unmodified code for spec; else why it does not."""
    return unchanged(folder, fingerprint(spec))
