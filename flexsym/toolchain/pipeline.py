"""Resolve a variant or a system to a current generated folder and a build, regenerating only
when needed."""
from __future__ import annotations

import json
import sys
from pathlib import Path

from flexsym.toolchain.build import Built, build
from flexsym.codegen.folder import unchanged, write_folder
from flexsym.codegen.generate import check_folder, fingerprint, generate
from flexsym.codegen.sysgen import derivation_fingerprint, derive_folder, folder_files
from flexsym.codegen.sysgen import fingerprint as system_fingerprint
from flexsym.core.paths import cache_dir, file_lock, generated_dir
from flexsym.model.system import System
from flexsym.physics.assemble import check_derivable
from flexsym.model.variant import BUILTIN, VariantSpec
from flexsym.toolchain.run import check_options, check_output_path, run_built


def saved_variant_file(name: str) -> Path:
    return cache_dir() / "variants" / f"{name}.json"


def save_variant(name: str, base: str, overrides: dict) -> Path:
    """Remember how `flexsym generate BASE --name NAME ...` made a variant, so that
    `flexsym run NAME` (build, inspect, ...) finds it again: the base and its overrides,
    which rebuild the same spec (and so the same fingerprint and cached code)."""
    from flexsym.core.files import atomic_write

    path = saved_variant_file(name)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(path) as fh:
        fh.write(json.dumps({"base": base, "overrides": overrides}, indent=1) + "\n")
    return path


def saved_variant(name: str):
    """(base, overrides) of a variant saved by `generate --name`, or None."""
    from flexsym.core.errors import SpecError
    from flexsym.core.files import read_limited

    path = saved_variant_file(name)
    try:
        data = json.loads(read_limited(path, 1 << 16, "saved variant"))
        base, overrides = data["base"], data["overrides"]
        if not isinstance(base, str) or not isinstance(overrides, dict):
            raise ValueError
    except FileNotFoundError:
        return None
    except (ValueError, KeyError, TypeError, UnicodeDecodeError):
        raise SpecError(f"{path}: not a saved variant (written by flexsym generate --name); "
                        "generate it again") from None
    return base, overrides


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
    from flexsym.toolchain.native import CompiledModel

    folder = generated_folder(spec, log)
    return CompiledModel(build(folder), folder)


def golden_systems() -> dict:
    """The mechanisms S1-S3 with the model their scenes name, whose generated folders are kept
    in generated/systems/ (written by `flexsym generate all`, checked by the tests), so that a
    change of the derivation or of the templates shows as a diff."""
    from flexsym.model.library import hub_system, pendulum_system, slider_crank_system
    from flexsym.model.variant import builtin

    return {s.name: s for s in (hub_system(builtin("m3")), slider_crank_system(builtin("m2")),
                                pendulum_system(builtin("m3")))}


def golden_system_folder(name: str) -> Path:
    return generated_dir() / "systems" / name


def system_folder(system: System) -> Path:
    return cache_dir() / "systems" / f"{system.name}-{system_fingerprint(system)[:12]}"


def prepare_system(system: System, log=None) -> Built:
    """Generate (when not current) and build a system; returns the build (run with run_built).
    log(msg): a line per stage of work actually done (nothing when cached)."""
    say = (lambda msg: log(f"flexsym: system '{system.name}': {msg}")) if log else None
    return build(generated_system_folder(system, say), log=say)


def generated_system_folder(system: System, say=None) -> Path:
    """The system's generated folder, generated now when not current."""
    system.validate()
    check_derivable(system)  # refused in one line before the first progress line
    folder = system_folder(system)
    fp = system_fingerprint(system)
    if unchanged(folder, fp) is not None:
        with file_lock(folder.parent / f".{folder.name}.lock"):
            if unchanged(folder, fp) is not None:
                write_folder(_system_files(system, say), folder)
    return folder


def _system_files(system: System, say) -> dict[str, str]:
    """The generated folder's files, from the derivation (sysgen.derive_folder) kept per
    derivation_fingerprint: a system whose sections' values alone changed (a density edited in
    its scene) is not derived again. A kept file this code cannot fill is derived again."""
    from flexsym.core.files import atomic_write

    path = cache_dir() / "systems" / ".derived" / f"{system.name}-{derivation_fingerprint(system)[:20]}.json"
    try:
        files = folder_files(system, json.loads(path.read_text(encoding="utf-8")))
        if say:
            say("derivation reused (the sections' values are run-time parameters)")
        return files
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        pass
    if say:
        say("deriving the equations (sympy; once per model, then cached)")
    derived = derive_folder(system, say)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(path) as fh:
        fh.write(json.dumps(derived))
    return folder_files(system, derived)


def run_system(system: System, out: Path | None = None, **options):
    """Check, assemble, generate, build and run a system (api.run's for a System): run.run_built's
    options (t_end, dt, integrator, params, ...) checked against the option table, the system as
    a scene is (system_scene.checked_system: its loops closed at t = 0 and followed to t_end),
    before any work; result.validity: why the rows are outside its models' range (empty:
    inside). The CSV's header records what the assembly moved."""
    from flexsym.scenes.system_scene import checked_system

    opts = check_options(**options)
    if out is not None:
        out = check_output_path(out, "out")
    return run_assembled(*checked_system(system, opts.t_end), opts, out)


def run_assembled(system: System, assembly, options, out: Path | None = None):
    """Run a checked, assembled system (checked_system's, a system scene's) with validated
    options: what the assembly moved heads the CSV; result.validity is set."""
    from flexsym.model.options import RUNTIME_DEFAULTS
    from flexsym.physics.validity import system_range_notes

    moved = assembly.line(options.newton_tol or RUNTIME_DEFAULTS["newton_tol"])
    result = run_built(prepare_system(system), options, out=out, header=[moved] if moved else [])
    result.validity = tuple(system_range_notes(system, result))
    return result
