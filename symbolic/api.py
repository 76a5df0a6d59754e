"""Python API mirroring the command line: load a scene or pick a variant, build, run, inspect.

    from flexsym import api
    scene = api.load_scene("scenes/paper.toml")
    result = api.run(scene)                 # RunResult: result["v_tip"], result.t, result.columns
    result = api.simulate("m3", ws=4.0, t_end=10.0)
    print(api.inspect("m1", sections="energy"))
"""
from __future__ import annotations

from pathlib import Path

from .errors import SpecError
from .pipeline import compiled, generated_folder, prepare
from .run import RunResult, check_options, run_built
from .scene import Scene, load_scene
from .spec import builtin

__all__ = ["load_scene", "variant", "generate", "build", "run", "simulate", "inspect", "kernels",
           "inprocess"]


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


def run(scene, out=None) -> RunResult:
    """Run a scene (a Scene or a path to a .toml file); results as numpy arrays."""
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    return run_built(prepare(scene.spec), t_end=scene.t_end, dt=scene.dt,
                     integrator=scene.integrator, params=scene.params, out_every=scene.out_every,
                     tol=scene.tol, step=scene.step, out=out if out is not None else scene.output_file)


def simulate(target="m3", *, ws=6.0, ts=15.0, t_end=20.0, dt=1e-3, integrator="genalpha",
             params=None, out=None, **run_options) -> RunResult:
    """Run a variant on the spin-up (or its own manoeuvre) with run-time parameters."""
    spec = _spec_of(target)
    p = {"ws": ws} | ({"ts": ts} if spec.maneuver == "spin_up" else {})
    if spec.maneuver.startswith("expression:"):
        p = {}
    p |= params or {}
    check_options(t_end=t_end, dt=dt, integrator=integrator, params=p, spec=spec)
    return run_built(prepare(spec), t_end=t_end, dt=dt, integrator=integrator, params=p, out=out,
                     **run_options)


def inspect(target, sections="modes,energy,integrals,mass,stiffness,equations,ops", latex=False) -> str:
    from .inspect_model import SECTIONS, Report

    chosen = sections.split(",") if isinstance(sections, str) else list(sections)
    for s in chosen:
        if s not in SECTIONS:
            raise SpecError(f"unknown section '{s}' (known: {', '.join(SECTIONS)})")
    return Report(_spec_of(target), latex=latex).render(chosen)


def inprocess(target):
    """The built model's library loaded in this process (InProcessModel): model.batch(runs, ...)
    runs many parameter sets per call and returns arrays (see flexsym.inprocess)."""
    from .inprocess import load

    return load(_spec_of(target))
