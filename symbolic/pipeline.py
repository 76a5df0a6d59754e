"""Resolve a variant to a current generated folder and a build, regenerating only when needed."""
from __future__ import annotations

import sys
from pathlib import Path

from .build import Built, build
from .generate import check_folder, fingerprint, generate
from .paths import cache_dir, file_lock, generated_dir
from .spec import BUILTIN, VariantSpec


def is_builtin(spec: VariantSpec) -> bool:
    return any(spec == b for b in BUILTIN)


def checked_in_folder(spec: VariantSpec) -> Path:
    return generated_dir() / spec.name


def cache_folder(spec: VariantSpec) -> Path:
    return cache_dir() / "variants" / f"{spec.name}-{fingerprint(spec)[:12]}"


def generated_folder(spec: VariantSpec, log=None) -> Path:
    """A folder with current generated code for spec: the checked-in one when it is current,
    else one in the cache (generated now if needed). Checked-in files are never rewritten
    here; `flexsym generate` does that."""
    log = log or (lambda msg: print(msg, file=sys.stderr))
    if is_builtin(spec):
        folder = checked_in_folder(spec)
        why = check_folder(spec, folder)
        if why is None:
            return folder
        log(f"flexsym: checked-in code not used: {why}")
    folder = cache_folder(spec)
    if check_folder(spec, folder) is not None:
        with file_lock(folder.parent / f".{folder.name}.lock"):
            if check_folder(spec, folder) is not None:  # not done meanwhile by another process
                log(f"flexsym: generating variant '{spec.name}' into {folder}")
                generate(spec, folder)
    return folder


def prepare(spec: VariantSpec, log=None) -> Built:
    return build(generated_folder(spec, log))


def compiled(spec: VariantSpec, log=None):
    """The built variant's kernels, callable from Python (see native.py)."""
    from .native import CompiledModel

    folder = generated_folder(spec, log)
    return CompiledModel(build(folder), folder)
