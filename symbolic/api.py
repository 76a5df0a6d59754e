"""Python API mirroring the command line: load a scene or pick a variant, build, run, inspect.

    from flexsym import api
    scene = api.load_scene("scenes/paper.toml")
    result = api.run(scene)                 # RunResult: result["v_tip"], result.t, result.columns
    result = api.simulate("m3", ws=4.0, t_end=10.0)
    print(api.inspect("m1", sections="energy"))
    hub = api.load_scene("scenes/hub.toml")  # a system scene ([[body]] entries): SystemScene
    result = api.run(hub)                   # columns theta_h, omega_h, v_tip, M_A
    pendulum = api.system({...})            # the same data as a scene, as a dict: a checked System
"""
from __future__ import annotations

from pathlib import Path

from .errors import SpecError
from .pipeline import compiled, generated_folder, prepare
from .options import API, validate
from .run import RunResult, check_output_path, run_built
from .scene import Scene, load_scene
from .spec import builtin

__all__ = ["load_scene", "system", "variant", "generate", "build", "run", "simulate", "inspect", "kernels"]


def variant(name_or_spec, **overrides):
    """A spec: a built-in name/alias (m0..m3, prestress, ef) or a spec, with optional overrides
    as on the command line (strain=, axial="static,sin1", bending=, outputs=, elements=, ...)."""
    from .spec import customize

    spec = builtin(name_or_spec) if isinstance(name_or_spec, str) else name_or_spec
    return customize(spec, **overrides) if overrides else spec.validate()


def _spec_of(target):
    if isinstance(target, Scene):
        return target.spec
    if isinstance(target, (str, Path)) and str(target).endswith(".toml"):
        return load_scene(target).spec
    return variant(target)


def generate(target) -> Path:
    """The folder with current generated code (generated now if needed)."""
    return generated_folder(_spec_of(target))


def build(target):
    return prepare(_spec_of(target))


def kernels(target):
    """The compiled kernels, callable on numpy arrays (CompiledModel)."""
    return compiled(_spec_of(target))


def system(data, name: str = "system", t_end: float | None = None):
    """A System from the data of a system scene as a dict ({"body": [...], "joint": [...],
    "driver": [...], "output": {"columns": {...}}, ...}), or a System built in Python (e.g. by
    flexsym.systems_library): checked exactly as a scene file is (one line per problem)."""
    from .system import System
    from .system_scene import check_system, system_from_dict

    if isinstance(data, System):
        return check_system(data, 20.0 if t_end is None else t_end)
    return system_from_dict(data, name, t_end)


def run(scene, out=None) -> RunResult:
    """Run a scene (a Scene, a SystemScene or a path to a .toml file); results as numpy arrays."""
    if not isinstance(scene, Scene) and not hasattr(scene, "system"):
        scene = load_scene(scene)
    out = out if out is not None else scene.output_file
    if out is not None:
        out = check_output_path(out, "out")
    if hasattr(scene, "system"):  # a mechanism: symbolic/sysgen.py generates and builds it
        from .sysgen import prepare_system

        return run_built(prepare_system(scene.system), scene.options, out=out)
    return run_built(prepare(scene.spec), scene.options, out=out)


def simulate(target="m3", *, out=None, **options) -> RunResult:
    """Run a variant on the spin-up (or its own manoeuvre). Options as `flexsym run` and the
    table in flexsym.options (t_end, dt, integrator, ws, ts, params={...}, tol, step, ...):
    checked before anything is generated or built; defaults from the table."""
    spec = _spec_of(target)
    o = validate(options, API, spec)
    if out is not None:
        out = check_output_path(out, "out")
    return run_built(prepare(spec), o, out=out)


def inspect(target, sections="modes,energy,integrals,mass,stiffness,equations,ops", latex=False) -> str:
    from .inspect_model import SECTIONS, Report

    chosen = sections.split(",") if isinstance(sections, str) else list(sections)
    for s in chosen:
        if s not in SECTIONS:
            raise SpecError(f"unknown section '{s}' (known: {', '.join(SECTIONS)})")
    return Report(_spec_of(target), latex=latex).render(chosen)
