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
           "inprocess", "sweep"]


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


def sweep(target, vary, out, *, samples=None, seed=None, sampling=None, at=(), resume=False,
          workers=None, dask=None, progress=None, on_chunk=None, ws=6.0, ts=15.0, params=None,
          **run_options) -> dict:
    """`flexsym sweep` from Python: vary is a list of "NAME=START:STOP:COUNT" / "NAME=a,b,c" /
    "NAME=LO:HI" strings, or a dict NAME -> list of values or such a string. Runs a scene with its
    own settings, or a variant on the spin-up (ws, ts, params, t_end, dt, integrator, tol, step,
    out_every as in simulate()). dask: a scheduler address or a distributed.Client. Writes the
    table to out and returns it as column -> numpy array (see flexsym.sweep)."""
    from .sweep import check_partial, make_plan, prepare_plan, read_table, run_sweep

    if isinstance(vary, dict):
        vary = [f"{k}={v}" if isinstance(v, str) else f"{k}={','.join(repr(float(x)) for x in v)}"
                for k, v in vary.items()]
    if isinstance(target, Scene) or (isinstance(target, (str, Path)) and str(target).endswith(".toml")):
        scene = target if isinstance(target, Scene) else load_scene(target)
        if run_options or params:
            raise SpecError(f"{scene.path}: run options do not combine with a scene: set them in the scene")
        spec, base = scene.spec, dict(scene.params)
        settings = dict(t_end=scene.t_end, dt=scene.dt, integrator=scene.integrator,
                        out_every=scene.out_every, tol=scene.tol, step=scene.step)
    else:
        spec = _spec_of(target)
        base = {} if spec.maneuver.startswith("expression:") else \
            {"ws": ws} | ({"ts": ts} if spec.maneuver == "spin_up" else {})
        base |= params or {}
        settings = dict(t_end=20.0, dt=1e-3, integrator="genalpha", out_every=None, tol=None,
                        step=None) | run_options
    check_options(**{k: v for k, v in settings.items() if k != "out_every"}, params=base, spec=spec)
    plan = make_plan(spec, settings, base, list(vary), samples=samples, seed=seed, sampling=sampling,
                     at=at)
    check_partial(Path(out), resume)
    prepare_plan(plan)
    run_sweep(plan, Path(out), resume=resume, workers=workers, dask=dask, progress=progress,
              on_chunk=on_chunk)
    return read_table(out)
