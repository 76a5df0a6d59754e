"""Python API mirroring the command line: load a scene or pick a variant, build, run, inspect.

    from flexsym.apps import api
    scene = api.load_scene("scenes/paper.toml")
    result = api.run(scene)                 # RunResult: result["v_tip"], result.t, result.columns
    result.validity                         # () or why the rows are outside the model's range
    result = api.simulate("m3", ws=4.0, t_end=10.0)
    print(api.inspect("m1", sections="energy"))
    hub = api.load_scene("scenes/hub.toml")  # a system scene ([[body]] entries): SystemScene
    result = api.run(hub)                   # columns theta_h, omega_h, v_tip, M_A
    pendulum = api.system({...})            # the same data as a scene, as a dict: a checked System
    result = api.run(pendulum, t_end=2.0, dt=1e-4)  # a System: with run options
"""
from __future__ import annotations

from pathlib import Path

from flexsym.core.errors import SpecError
from flexsym.toolchain.pipeline import compiled, generated_folder, prepare
from flexsym.model.limits import is_real
from flexsym.model.options import API, validate
from flexsym.physics.validity import range_notes
from flexsym.toolchain.run import RunResult, check_output_path, run_built
from flexsym.scenes.scene import Scene, load_scene
from flexsym.model.variant import builtin

__all__ = ["load_scene", "system", "variant", "generate", "build", "run", "simulate", "inspect", "kernels",
           "inprocess", "sweep"]


def variant(name_or_spec, **overrides):
    """A spec: a built-in name/alias (m0..m3, prestress, ef) or a spec, with optional overrides
    as on the command line (strain=, axial="static,sin1", bending=, outputs=, elements=, ...)."""
    from flexsym.model.variant import customize

    if not isinstance(name_or_spec, str) and not hasattr(name_or_spec, "validate"):
        raise SpecError(f"variant(): name_or_spec must be a variant name such as 'm3' or a spec "
                        f"(got {type(name_or_spec).__name__} {name_or_spec!r})")
    spec = builtin(name_or_spec) if isinstance(name_or_spec, str) else name_or_spec
    return customize(spec, **overrides) if overrides else spec.validate()


def _loaded(target):
    """A target checked, and a .toml path loaded (once) as its scene."""
    _check_target(target)
    if isinstance(target, (str, Path)) and str(target).endswith(".toml"):
        return load_scene(target)
    return target


def _spec_of(target, what: str = "", instead: str = ""):
    """The one-beam spec of a target; a mechanism (a System, its scene) refused in one line by
    the functions that take none (what: the function's name; instead: what to use)."""
    target = _loaded(target)
    if _system_of(target) is not None:
        raise SpecError(f"{what}(): takes a one-beam variant or scene, not a mechanism (a System or a "
                        f"system scene){instead}")
    return target.spec if isinstance(target, Scene) else variant(target)


def _system_of(target):
    """The System a loaded target is (a System, or a system scene's), else None."""
    from flexsym.model.system import System

    if isinstance(target, System):
        return target
    return target.system if hasattr(target, "system") else None


def _check_target(target, what: str = "target") -> None:
    """One clear line for a target of the wrong type (instead of Python's own error later)."""
    if not (isinstance(target, (str, Path, Scene)) or hasattr(target, "system")
            or hasattr(target, "validate")):
        raise SpecError(f"{what} must be a variant name (e.g. 'm3'), a spec, a scene or the path "
                        f"of a .toml scene (got {type(target).__name__} {target!r})")


def generate(target) -> Path:
    """The folder with current generated code (generated now if needed): a variant's, a
    scene's or a System's."""
    target = _loaded(target)
    system = _system_of(target)
    if system is not None:
        from flexsym.toolchain.pipeline import generated_system_folder

        return generated_system_folder(system)
    return generated_folder(_spec_of(target))


def build(target):
    """The built model (Built: its driver and library) of a variant, a scene or a System."""
    target = _loaded(target)
    system = _system_of(target)
    if system is not None:
        from flexsym.toolchain.pipeline import prepare_system

        return prepare_system(system)
    return prepare(_spec_of(target))


def kernels(target):
    """A variant's compiled kernels, callable on numpy arrays (CompiledModel)."""
    return compiled(_spec_of(target, "kernels", "; build() builds a mechanism's model"))


def system(data, name: str = "system", t_end: float | None = None):
    """A System from the data of a system scene as a dict ({"body": [...], "joint": [...],
    "driver": [...], "output": {"columns": {...}}, ...}), or a System built in Python (e.g. by
    flexsym.model.library): checked exactly as a scene file is (one line per problem), and
    assembled at t = 0 (flexsym/scenes/assembly.py: the joints' initial values closing the loops)."""
    from flexsym.model.system import System
    from flexsym.scenes.system_scene import checked_system, system_from_dict

    if not isinstance(data, (dict, System)):
        raise SpecError(f"system(): data must be a dict (a system scene's tables) or a System "
                        f"(got {type(data).__name__} {data!r})")
    if not isinstance(name, str):
        raise SpecError(f"system(): name must be a string (got {name!r})")
    if t_end is not None and not (is_real(t_end) and t_end > 0 and t_end < float("inf")):
        raise SpecError(f"system(): t_end must be a finite number > 0 (got {t_end!r})")
    if isinstance(data, System):
        return checked_system(data, 20.0 if t_end is None else t_end)[0]
    return system_from_dict(data, name, t_end)


def run(scene, out=None, **options) -> RunResult:
    """Run a scene (a Scene, a SystemScene or a path to a .toml file) as it says, or a System
    (api.system's, flexsym.model.library's) with run options (t_end, dt, integrator, params,
    ...: the option table, checked, and the linkage assembled and followed to t_end, before any
    work); results as numpy arrays. result.validity says why the rows are outside their model's
    range (empty: inside), as `flexsym run`'s exit code 4 does."""
    from flexsym.model.system import System

    if isinstance(scene, System):
        from flexsym.toolchain.pipeline import run_system

        return run_system(scene, out, **options)
    if options:
        raise SpecError(f"run(): options ({', '.join(options)}) are for a System: a scene's are "
                        "set in the scene")
    _check_target(scene, "scene")
    if not isinstance(scene, Scene) and not hasattr(scene, "system"):
        if not isinstance(scene, (str, Path)):
            raise SpecError(f"scene must be a scene or the path of a .toml scene (got "
                            f"{type(scene).__name__} {scene!r})")
        scene = load_scene(scene)
    out = out if out is not None else scene.output_file
    if out is not None:
        out = check_output_path(out, "out")
    if hasattr(scene, "system"):  # a mechanism: flexsym/codegen/sysgen.py generates and builds it
        from flexsym.toolchain.pipeline import run_assembled

        return run_assembled(scene.system, scene.assembly, scene.options, out)
    result = run_built(prepare(scene.spec), scene.options, out=out)
    result.validity = tuple(range_notes(scene.spec, result, scene.options.params))
    return result


def simulate(target="m3", *, out=None, **options) -> RunResult:
    """Run a variant on the spin-up (or its own manoeuvre). Options as `flexsym run` and the
    table in flexsym.model.options (t_end, dt, integrator, ws, ts, params={...}, tol, step, ...):
    checked before anything is generated or built; defaults from the table."""
    spec = _spec_of(target, "simulate", "; run(system, t_end=..., dt=...) runs one")
    o = validate(options, API, spec)
    if out is not None:
        out = check_output_path(out, "out")
    result = run_built(prepare(spec), o, out=out)
    result.validity = tuple(range_notes(spec, result, o.params))
    return result


def inspect(target, sections=None, latex=False) -> str:
    """The derivation as text, as `flexsym inspect`: a variant's or one-beam scene's sections
    (default modes,energy,integrals,mass,stiffness,equations,ops), or a mechanism's (a System,
    a system scene: system,derivation)."""
    from flexsym.analysis.inspect_model import SECTIONS, SYSTEM_SECTIONS, Report, system_report

    if sections is not None and not isinstance(sections, (str, list, tuple)):
        raise SpecError(f"inspect(): sections must be a string such as 'modes,energy' or a list "
                        f"(got {type(sections).__name__} {sections!r})")
    target = _loaded(target)
    system = _system_of(target)
    chosen = list(SYSTEM_SECTIONS if system is not None else SECTIONS) if sections is None else (
        sections.split(",") if isinstance(sections, str) else list(sections))
    if system is not None:
        if latex:
            raise SpecError("inspect(): a mechanism has no LaTeX form (latex=False)")
        return system_report(system, chosen)
    for s in chosen:
        if not isinstance(s, str) or s not in SECTIONS:
            raise SpecError(f"unknown section '{s}' (known: {', '.join(SECTIONS)})")
    return Report(_spec_of(target, "inspect", "; its generated folder (generate()) holds its "
                                  "equations and manifest"), latex=latex).render(chosen)


def inprocess(target):
    """The built model's library loaded in this process (InProcessModel): model.batch(runs, ...)
    runs many parameter sets per call and returns arrays (see flexsym.sim.inprocess). Loaded
    from a scene, a batch runs as the scene says (its run options, its beam and manoeuvre
    values) where the call does not say otherwise."""
    from flexsym.sim.inprocess import load, load_system

    target = _loaded(target)
    system = _system_of(target)
    if system is target:  # a System as built: batch() gives the run options
        return load_system(system)
    if system is not None:  # a mechanism's scene: its p and drive parameters vary (flexsym.sim.inprocess)
        return load_system(system).with_scene(target)
    model = load(_spec_of(target))
    return model.with_scene(target) if isinstance(target, Scene) else model


def sweep(target, vary, out, *, samples=None, seed=None, sampling=None, at=(), resume=False,
          workers=None, dask=None, progress=None, on_chunk=None, **run_options) -> dict:
    """`flexsym sweep` from Python: vary is a list of "NAME=START:STOP:COUNT" / "NAME=a,b,c" /
    "NAME=LO:HI" strings, or a dict NAME -> list of values or such a string. Runs a scene with its
    own settings, or a variant on the spin-up or a System with the run options of simulate()
    (ws, ts, params={...}, t_end, dt, integrator, tol, step, interval, ...; the option table). dask: a
    scheduler address or a distributed.Client. Writes the table to out and returns it as
    column -> numpy array (see flexsym.sim.sweep)."""
    from flexsym.sim.inprocess import settings_of
    from flexsym.sim.sweep import claim_partial, fingerprint_of, make_plan, prepare_plan, read_table, run_sweep

    if isinstance(vary, dict):
        vary = [f"{k}={v}" if isinstance(v, str) else f"{k}={','.join(repr(float(x)) for x in v)}"
                for k, v in vary.items()]
    if isinstance(target, (str, Path)) and str(target).endswith(".toml"):
        target = load_scene(target)
    if isinstance(target, Scene) or hasattr(target, "system"):
        scene = target
        if run_options:
            raise SpecError(f"{scene.path}: run options do not combine with a scene: set them in the scene")
        if hasattr(scene, "system"):  # a mechanism: names from its built model
            from flexsym.sim.sweep import system_target

            spec = system_target(scene.system)
        else:
            spec = scene.spec
        o, keep_interval = scene.options, True
    else:
        from flexsym.model.system import System

        if isinstance(target, System):  # as built, with the run options given here
            from flexsym.sim.sweep import system_target

            spec = system_target(target)
        else:
            spec = _spec_of(target)
        o = validate(run_options, API, None if isinstance(target, System) else spec)
        keep_interval = run_options.get("interval") is not None or run_options.get("out_every") is not None
    plan = make_plan(spec, settings_of(o, keep_interval), o.params, list(vary), samples=samples, seed=seed,
                     sampling=sampling, at=at)
    out = check_output_path(out, "out")
    plan.fingerprint = fingerprint_of(plan.spec)  # the partial file is checked before any build
    with claim_partial(plan, out, resume) as partial:
        prepare_plan(plan)
        run_sweep(plan, out, workers=workers, dask=dask, progress=progress, on_chunk=on_chunk, partial=partial)
    return read_table(out)
