"""flexsym command line: generate, build, run, inspect, select, spinup, paper, sweep, variants."""
from __future__ import annotations

import argparse
import os
import re
import signal
import sys
import threading
from dataclasses import replace
from pathlib import Path

from flexsym.core.errors import FlexsymError, SpecError
from flexsym.model.limits import MAX_EF_ELEMENTS
from flexsym.model.options import (BY_NAME, CLI, OPTIONS, RUNTIME_DEFAULTS, Where, add_arguments,
                                  given_options, validate, with_overrides)


def _variant_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("variant", help="built-in variant name or alias (m0..m3, prestress, ef), the base "
                   "for overrides, or a scene file (.toml)")
    g = p.add_argument_group("custom mode set (any of these makes a new variant)")
    g.add_argument("--strain", help="strain model (see `flexsym variants`)")
    g.add_argument("--axial", help="axial modes, e.g. static,sin1,sin2 (empty string for none)")
    g.add_argument("--bending", help="bending modes, e.g. static,cp1,cp2,cp3,cp4")
    g.add_argument("--maneuver", help="manoeuvre kind (spin_up, constant)")
    g.add_argument("--outputs", help="output quantities, e.g. v_tip,u_tip,N_A,M_A,M@0.25 "
                   "(positions as fractions of L; default: all the variant can give)")
    g.add_argument("--stress", help="stress recovery: continuum (default) or element:N "
                   "(the paper's element method on N elements)")
    g.add_argument("--axial-force", dest="axial_force", choices=("constitutive", "equilibrium"),
                   help="axial force from the axial strain (default) or from the axial inertial forces")
    g.add_argument("--moment", choices=("constitutive", "equilibrium"),
                   help="bending moment from the curvature (default) or from the inertial loads")
    g.add_argument("--elements", help="number of finite elements (variant ef; with a scene file, "
                   "after --model ef)")
    g.add_argument("--name", help="name of the custom variant (default: derived from the base)")


_OVERRIDES = ("strain", "axial", "bending", "maneuver", "outputs", "stress", "axial_force", "moment", "elements",
              "name")
RUN_OPTIONS = tuple(o.name for o in OPTIONS)  # every option of the table is a `flexsym run` flag
SPINUP_OPTIONS = ("ws", "ts", "t_end", "dt", "integrator")


def _given(args, keys) -> list[str]:
    return [k for k in keys if getattr(args, k, None) is not None]


def _elements(text):
    if text is None:
        return None
    try:
        return int(text)
    except ValueError:
        raise SpecError(f"--elements: '{text}' is not a whole number") from None


def _mesh(scene: str, text, variant: str) -> int:
    """--elements with a scene file and --model: the ef variant's elements (1..MAX_EF_ELEMENTS)."""
    from flexsym.model.variant import builtin

    try:
        if builtin(variant).kind != "fe":
            raise SpecError(f"--elements: applies to --model ef, not to '{variant}'")
        n = _elements(text)
        if not 1 <= n <= MAX_EF_ELEMENTS:
            raise SpecError(f"--elements: must be in 1..{MAX_EF_ELEMENTS} (got {n})")
    except SpecError as exc:
        raise SpecError(f"{scene}: {exc}") from None
    return n


def resolve(args):
    """(spec, scene or None) from a variant name with overrides, or from a scene file; a system
    scene gives (None, SystemScene)."""
    from flexsym.model.variant import customize

    if args.variant.endswith(".toml"):
        from flexsym.scenes.scene import load_scene

        given = _given(args, _OVERRIDES)
        model = getattr(args, "model", None)
        if given == ["elements"] and model is not None:  # ef's mesh with --model ef
            model = {"variant": model, "elements": _mesh(args.variant, args.elements, model)}
        elif given:
            raise SpecError(f"{args.variant}: --{given[0].replace('_', '-')} does not combine with a "
                            "scene file: set it in the scene's [model] table"
                            + (" (--elements goes with --model ef)" if given[0] == "elements" else ""))
        scene = load_scene(args.variant, model=model)
        if getattr(scene, "system", None) is not None:  # a mechanism: every command takes it
            return None, scene
        return scene.spec, scene
    if getattr(args, "model", None) is not None:
        raise SpecError(f"--model replaces the model of a scene file; '{args.variant}' is not one")
    overrides = {k: getattr(args, k, None) for k in _OVERRIDES if k != "name"}
    overrides["elements"] = _elements(overrides["elements"])
    base = _base_variant(args.variant)
    if all(v is None for v in overrides.values()) and getattr(args, "name", None) is None:
        return base.validate(), None
    return customize(base, name=getattr(args, "name", None), **overrides), None


def _chain(name: str) -> tuple[str, dict]:
    """(built-in base, overrides) of a built-in variant or of one saved by `flexsym generate
    BASE --name NAME ...`."""
    from flexsym.model.variant import builtin
    from flexsym.toolchain.pipeline import saved_variant

    try:
        return builtin(name).name, {}
    except SpecError as exc:
        saved = saved_variant(name) if re.fullmatch(r"[a-z][a-z0-9_]{0,47}", name) else None
        if saved is None:
            raise SpecError(f"{exc}; a custom variant is run by name once `flexsym generate BASE "
                            "--name NAME ...` has made it") from None
        return saved


def _definition(spec) -> dict:
    """The customize() arguments that rebuild spec from its built-in base, every one explicit
    (so that defaults a base implies, such as its outputs, cannot change the saved variant)."""
    if spec.kind == "fe":
        return {"elements": spec.elements, "maneuver": spec.maneuver, "outputs": ",".join(spec.outputs)}
    return {"strain": spec.strain, "axial": ",".join(m.token for m in spec.axial),
            "bending": ",".join(m.token for m in spec.bending), "maneuver": spec.maneuver,
            "outputs": ",".join(spec.outputs), "stress": spec.stress,
            "axial_force": spec.axial_force, "moment": spec.moment}


def _base_variant(name: str):
    from flexsym.model.variant import builtin, customize

    base, overrides = _chain(name)
    return customize(builtin(base), name=name, **overrides) if overrides else builtin(name)


def cmd_generate(args) -> int:
    from flexsym.codegen.generate import generate
    from flexsym.toolchain.pipeline import cache_folder, checked_in_folder, is_builtin
    from flexsym.model.variant import BUILTIN

    if args.variant == "all":  # every built-in variant and the mechanisms S1-S3 into generated/
        from flexsym.codegen.folder import write_folder
        from flexsym.codegen.sysgen import generate_system_files
        from flexsym.toolchain.pipeline import golden_system_folder, golden_systems

        for spec in BUILTIN:
            generate(spec, checked_in_folder(spec))
            print(f"generated '{spec.name}' in {checked_in_folder(spec)}")
        for name, system in golden_systems().items():
            write_folder(generate_system_files(system), golden_system_folder(name))
            print(f"generated system '{name}' in {golden_system_folder(name)}")
        return 0
    spec, scene = resolve(args)
    if args.out is not None:
        from flexsym.toolchain.run import check_output_dir

        check_output_dir(args.out, "--out")
    if spec is None:  # a system scene: its folder in the cache, or in --out
        return _generate_system(scene.system, args.out)
    dest = Path(args.out) if args.out else (checked_in_folder(spec) if is_builtin(spec) else cache_folder(spec))
    g = generate(spec, dest)
    if getattr(args, "name", None) is not None:  # `flexsym run NAME` finds it again
        from flexsym.toolchain.pipeline import save_variant

        save_variant(spec.name, _chain(args.variant)[0], _definition(spec))
    ops = ", ".join(f"{k} {v['total_ops']}" for k, v in g.manifest["kernels"].items())
    print(f"generated '{spec.name}' in {dest}\n  fingerprint {g.manifest['fingerprint'][:16]}...\n  ops: {ops}")
    return 0


def _generate_system(system, out) -> int:
    """flexsym generate SYSTEM_SCENE [--out DIR]: the system's generated folder."""
    import json

    from flexsym.codegen.folder import MANIFEST, write_folder
    from flexsym.toolchain.pipeline import generated_system_folder

    say = lambda msg: print(f"flexsym: system '{system.name}': {msg}", file=sys.stderr, flush=True)
    folder = generated_system_folder(system, say)
    if out is not None:
        write_folder({f.name: f.read_text(encoding="utf-8") for f in sorted(folder.iterdir()) if f.is_file()},
                     Path(out))
        folder = Path(out)
    manifest = json.loads((folder / MANIFEST).read_text(encoding="utf-8"))
    ops = ", ".join(f"{k} {v['total_ops']}" for k, v in manifest["kernels"].items())
    print(f"generated system '{system.name}' in {folder}\n  fingerprint {manifest['fingerprint'][:16]}..."
          f"\n  ops: {ops}")
    return 0


def cmd_build(args) -> int:
    from flexsym.toolchain.pipeline import prepare, prepare_system

    spec, scene = resolve(args)
    if spec is None:  # a system scene
        built = prepare_system(scene.system, log=lambda msg: print(msg, file=sys.stderr, flush=True))
    else:
        built = prepare(spec)
    print(f"built '{built.name}': {built.executable}")
    return 0


def _params(items) -> dict:
    params = {}
    for item in items or []:
        if "=" not in item:
            raise SpecError(f"--param '{item}': expected NAME=VALUE")
        k, v = item.split("=", 1)
        if k.strip() in params:
            raise SpecError(f"--param {k.strip()}: given twice")
        params[k.strip()] = v.strip()
    return params


def _run_options(args, spec, scene, overrides: bool = False):
    """Validated run options, from a scene file or from the command line (one table); with
    overrides (flexsym run), the command line's options replace the scene's."""
    given = given_options(args, RUN_OPTIONS)
    if scene is not None and overrides and not args.param:
        if spec is None and {"ws", "ts"} & set(given):  # a system's manoeuvres are its drivers'
            name = sorted({"ws", "ts"} & set(given))[0]
            raise SpecError(f"{scene.path}: --{name} given with a system scene: set the driver's "
                            f"{'omega' if name == 'ws' else 'duration'} in the scene")
        return with_overrides(scene.given, given, scene.path, spec) if given else scene.options
    if scene is not None:
        if given or args.param:
            name = "param" if args.param else next(iter(given))
            opt = BY_NAME.get(name)
            where = (f"set [{opt.scene.replace('.', '] ')} in the scene" if opt is not None and opt.scene
                     else "it does not combine with a scene file")
            raise SpecError(f"{scene.path}: --{name.replace('_', '-')} given with a scene file: {where}")
        return scene.options
    return validate(given | {"params": _params(args.param)}, CLI, spec)


def _outputs_checked(args, spec, scene) -> tuple[Path | None, Path | None]:
    """The CSV and plot paths, checked before any work (never created, never half-written)."""
    from flexsym.toolchain.run import check_output_path

    out = None
    if args.out is not None:
        out = check_output_path(args.out, "--out")
    elif scene is not None and scene.output_file is not None:
        out = check_output_path(scene.output_file, f"{scene.path}: [output] file")
    plot = None
    if args.plot is not None:
        if "v_tip" not in spec.outputs:
            raise SpecError(f"--plot: the plot shows v_tip, which is not an output of this run "
                            f"(outputs: {', '.join(spec.outputs)})")
        plot = check_output_path(args.plot, "--plot", PLOT_TYPES)
    return out, plot


PLOT_TYPES = (".png", ".pdf", ".svg")


def cmd_run(args) -> int:
    from flexsym.analysis.spinup import Summary, describe, plot, table
    from flexsym.toolchain.pipeline import prepare
    from flexsym.toolchain.run import run_built
    from flexsym.physics.validity import assess

    spec, scene = resolve(args)
    if spec is None:
        return _run_system(args, scene)
    options = _run_options(args, spec, scene, overrides=True)
    out, plot_path = _outputs_checked(args, spec, scene)
    if options.energy and out is None:
        raise SpecError("--energy: the energy columns (T, V, h) go to the CSV file, and there is none: "
                        "give --out")
    built = prepare(spec)
    from flexsym.model.output_names import info

    units = {o: info(o, spec.points).unit for o in spec.outputs}
    res = run_built(built, options, out=out, header=[_units_line(units)] + _options_header(args, scene, options))
    verdict = assess(spec, res, options.params)
    s = Summary(spec, res)
    ts = options.params.get("ts", options.t_end)
    if scene is not None or "v_tip" not in res.columns:
        print(describe(res, spec.outputs, verdict.status, units))
    else:
        print(table([s], ts, options.t_end))
    if out is not None:
        if res.written == "complete":
            print(f"results: {out}")
        elif res.written == "truncated":
            print(f"results (truncated: rows up to t = {res.summary['t_stop']:.6g} s, where the run "
                  f"stopped): {out}")
        else:
            print(f"results: nothing written to {out} (the run stopped before its first step; an "
                  "existing file is left as it was)")
    if plot_path is not None:
        if len(res.t) > 1:
            plot([s], plot_path, f"{spec.name}, {spec.maneuver}")
            print(f"plot: {plot_path}")
        else:
            print(f"plot: nothing written to {plot_path} (no step was computed)")
    for note in verdict.notes:
        print(f"flexsym: {note}", file=sys.stderr)
    if not res.ok:
        return 3
    return 0 if verdict.valid else 4


def _static_start_line(system) -> str:
    """The CSV header's line for start = "static": which joint coordinates follow a loop's
    deformation (the generated model's manifest says, sysgen._static_unknowns)."""
    import json

    from flexsym.codegen.folder import MANIFEST
    from flexsym.toolchain.pipeline import system_folder

    manifest = json.loads((system_folder(system) / MANIFEST).read_text())
    group = {c["name"]: c["group"] for c in manifest["coordinates"]}
    joints = [c for c in manifest["static_start"]["solved"] if group[c] == "joint"]
    held = (f"joints held but {', '.join(joints)}, which follow the loop" if joints
            else "joints held")
    return ("start: the flexible bodies in static equilibrium under the loads at t = 0 "
            f"({held}; solved by Newton to 1e-12 of the size)")


def _units_line(units: dict) -> str:
    """The CSV header's units of the time and output columns (SI; the coordinates that may
    follow are SI too: m, rad, and the modes' amplitudes in m)."""
    return "units: " + ", ".join(f"{c} [{u}]" for c, u in ({"t": "s"} | units).items())


def _options_header(args, scene, options) -> list[str]:
    """The CSV header's record of what the command line replaced in a scene: its run options
    (the effective ones), its model (--model, --elements)."""
    if scene is None:
        return []
    given = given_options(args, RUN_OPTIONS)
    lines = [f"run options: {options.describe()} (from the command line: "
             f"{', '.join(BY_NAME[n].flag for n in given)})"] if given else []
    model = getattr(args, "model", None)
    if model is not None:
        mesh = f" on {int(args.elements)} elements" if getattr(args, "elements", None) is not None else ""
        lines.append(f"model: {model}{mesh}, in place of the scene's (from the command line: --model"
                     f"{', --elements' if mesh else ''})")
    return lines


def _run_system(args, scene) -> int:
    """flexsym run SYSTEM_SCENE: options from the scene (some replaced by the command line's),
    --out/--plot checked before any work; what the assembly at t = 0 moved on stderr and in
    the CSV header."""
    from flexsym.toolchain.run import check_output_path

    options = _run_options(args, None, scene, overrides=True)
    if options.t_end > scene.options.t_end:  # the linkage's reach, checked to the scene's end
        from flexsym.scenes.system_scene import check_assembly

        try:
            check_assembly(scene.system, options.t_end)
        except SpecError as exc:
            raise SpecError(f"{scene.path}: --t-end {options.t_end:g}: {exc}") from None
    out = None
    if args.out is not None:
        out = check_output_path(args.out, "--out")
    elif scene.output_file is not None:
        out = check_output_path(scene.output_file, f"{scene.path}: [output] file")
    plot = check_output_path(args.plot, "--plot", PLOT_TYPES) if args.plot is not None else None
    system, geometry = scene.system, None
    if plot is not None:  # the picture's marker positions become extra output columns
        from flexsym.analysis.system_plot import with_plot_outputs

        system, geometry = with_plot_outputs(system)
    from flexsym.toolchain.run import run_built
    from flexsym.toolchain.pipeline import prepare_system

    try:
        built = prepare_system(system, log=lambda msg: print(msg, file=sys.stderr, flush=True))
    except SpecError as exc:  # what the derivation does not support yet, named with the file
        raise SpecError(f"{scene.path}: {exc}") from None
    from flexsym.model.system import output_unit

    shown = [o.column for o in scene.system.outputs]  # the user's, not the plot's columns
    units = {o.column: output_unit(scene.system, o.quantity) for o in scene.system.outputs}
    header = [_units_line(units)] + _options_header(args, scene, options)
    if system.start == "static":
        header.insert(0, _static_start_line(system))
    moved = scene.assembly.line(options.newton_tol or RUNTIME_DEFAULTS["newton_tol"])
    if moved:
        print(f"flexsym: {scene.path}: {moved}", file=sys.stderr)
        header.insert(0, moved)
    res = run_built(built, options, out=out, header=header)
    from flexsym.physics.validity import assess_system

    verdict = assess_system(system, res)  # every body inside its model's range
    status = f"stopped: {res.message}" if not res.ok else verdict.status
    print(f"{system.name}: {options.integrator}, dt = {options.dt:g} s, t_end = {options.t_end:g} s: "
          + (status if verdict.valid or not res.ok else "outside its model's range (below)"))
    if len(res.t):
        from flexsym.analysis.spinup import describe

        print(describe(res, shown, status, units))
    if res.written != "none":
        if plot is not None:  # the CSV does not depend on whether a picture was asked for
            from flexsym.toolchain.run import drop_columns

            drop_columns(out, {o.column for o in system.outputs} - {o.column for o in scene.system.outputs})
        print(f"results{' (truncated)' if res.written == 'truncated' else ''}: {out}")
    if plot is not None and len(res.t) > 1:
        from flexsym.analysis.system_plot import plot_system

        factor = plot_system(system, geometry, {"t": res.t} | {c: res[c] for c in res.columns}, plot)
        print(f"plot: {plot} (beam deflection from the chord scaled x{factor:g})")
    for note in verdict.notes:
        if note != res.message:
            print(f"flexsym: {note}", file=sys.stderr)
    if not res.ok:
        return 3
    return 0 if verdict.valid else 4


FMU_OPTIONS = tuple(n for n in RUN_OPTIONS if n not in ("repeat", "energy"))  # as `run`'s


def _fmu_request(args, out: Path | None):
    """(spec, FmuOptions) for export-fmu and bench-fmu, checked before any work (one table)."""
    from flexsym.sim.fmu import FmuOptions, check_request, tuning_of

    spec, scene = resolve(args)
    o = _run_options(args, spec, scene, overrides=True)  # as `flexsym run` takes them
    if o.energy:  # only a scene can ask for it (export-fmu has no --energy)
        raise SpecError(f"{getattr(scene, 'path', 'energy')}: [output] energy: the FMU's outputs are the scene's columns; "
                        "energy columns are not exported")
    opts = FmuOptions(integrator=o.integrator, dt=o.dt, step=o.step, tol=o.tol, t_end=o.t_end,
                      interval=o.out_every * o.dt, params=o.params,
                      input=getattr(args, "input", "none"), tuning=tuning_of(o))
    check_request(opts, out, spec)
    return (spec if spec is not None else scene), opts


def _fmu_model(target):
    """(generated folder, build) of a one-beam spec or a system scene."""
    from flexsym.toolchain.pipeline import generated_folder, prepare

    if hasattr(target, "system"):
        from flexsym.toolchain.pipeline import prepare_system, system_folder

        try:
            built = prepare_system(target.system)
        except SpecError as exc:
            raise SpecError(f"{target.path}: {exc}") from None
        return system_folder(target.system), built
    return generated_folder(target), prepare(target)


def cmd_export_fmu(args) -> int:
    from flexsym.sim.fmu import export_fmu

    out = Path(args.out)
    spec, opts = _fmu_request(args, out)
    export_fmu(_fmu_model(spec)[0], opts, out)
    print(f"wrote {out}: FMI 3.0 Co-Simulation, {opts.integrator} at dt = {opts.dt:g} s"
          f"{', drive from the inputs theta_dot, theta_ddot' if opts.input == 'drive' else ''}")
    return 0


def cmd_bench_fmu(args) -> int:
    from flexsym.sim.fmu import bench

    if not 1 <= args.repeat <= 1000:
        raise SpecError(f"--repeat must be in 1..1000 (got {args.repeat})")
    spec, opts = _fmu_request(args, None)
    r = bench(*_fmu_model(spec), opts, repeat=args.repeat)
    name = spec.system.name if hasattr(spec, "system") else spec.name
    print(f"{name}, {opts.integrator} at dt = {opts.dt:g} s, {r['steps']} steps, doStep every "
          f"{opts.interval:g} s ({r['communication_steps']} calls, every output read after each), "
          f"median of {args.repeat} runs:")
    print(f"  FMU doStep loop   {r['fmu'] * 1e3:8.3f} ms  (min {r['fmu_min'] * 1e3:.3f}, max {r['fmu_max'] * 1e3:.3f})")
    print(f"  native runtime    {r['native'] * 1e3:8.3f} ms  (min {r['native_min'] * 1e3:.3f}, "
          f"max {r['native_max'] * 1e3:.3f})")
    print(f"  ratio FMU / native: {r['ratio']:.3f}")
    return 0


def cmd_fe_export(args) -> int:
    from flexsym.scenes.feimport import write_folder
    from flexsym.scenes.scene import load_scene
    from flexsym.toolchain.run import check_output_dir

    out = Path(args.out)
    if out.exists() or out.is_symlink():
        raise SpecError(f"--out {out}: already exists (choose a new folder)")
    check_output_dir(out, "--out")
    scene = load_scene(args.scene)
    system = getattr(scene, "system", None)
    if system is not None:  # a mechanism: its one beam from finite-element data
        meshes = [b.model.body for b in system.bodies if b.flexible and b.model.body is not None]
        if len(meshes) != 1:
            raise SpecError(f"{args.scene}: has {len(meshes)} beams from finite-element data "
                            "(segments or folder); fe-export writes a scene's one such beam")
        body = meshes[0]
    else:
        body = getattr(scene.spec, "body", None)
        if body is None:
            raise SpecError(f"{args.scene}: has no [body] table to export")
    folder = write_folder(body, out)
    order = {"body.toml": 0, "M.mtx": 1, "K.mtx": 2}  # then the KG files
    files = sorted((p.name for p in folder.iterdir()), key=lambda n: (order.get(n, 3), n))
    print(f"{body.summary()}: written to {folder} ({', '.join(files)})")
    return 0


def cmd_inspect(args) -> int:
    from flexsym.analysis.inspect_model import SECTIONS, Report

    spec, scene = resolve(args)
    if spec is None:  # a system scene: its structure, then its derivation
        from flexsym.analysis.inspect_model import SYSTEM_SECTIONS, system_report

        chosen = args.section.split(",") if args.section is not None else list(SYSTEM_SECTIONS)
        if args.plot_modes or args.latex:
            raise SpecError(f"{scene.path}: a system scene shows --section system,derivation (no "
                            "--latex, --plot-modes)")
        try:  # system_report checks the sections before any derivation
            sys.stdout.write(system_report(scene.system, chosen))
        except SpecError as exc:
            raise SpecError(f"{scene.path}: {exc}") from None
        return 0
    sections = args.section.split(",") if args.section is not None else SECTIONS
    for s in sections:
        if s not in SECTIONS:
            raise SpecError(f"unknown section '{s}' (known: {', '.join(SECTIONS)})")
    if args.plot_modes and spec.kind != "modal":
        raise SpecError(f"--plot-modes: '{spec.name}' has no mode shapes (finite elements)")
    report = Report(spec, latex=args.latex)
    sys.stdout.write(report.render(sections))
    if args.plot_modes:
        from flexsym.analysis.inspect_model import plot_modes

        plot_modes(report.der, Path(args.plot_modes))
        print(f"mode shapes: {args.plot_modes}")
    if scene is not None:
        from flexsym.analysis.inspect_model import savings

        sys.stdout.write(savings(spec, scene.full_spec))
    return 0


def _names(text: str, label: str) -> list[str]:
    names = [v.strip() for v in text.split(",")]
    if not all(names):
        raise SpecError(f"{label} '{text}': empty name in the list")
    return names


def cmd_spinup(args) -> int:
    from flexsym.toolchain.run import check_output_dir
    from flexsym.model.variant import builtin
    from flexsym.analysis.spinup import plot, run_variants, table

    specs = [builtin(v) for v in _names(args.variants, "--variants")]
    o = validate(given_options(args, SPINUP_OPTIONS), CLI, specs[0])
    ws, ts = o.params["ws"], o.params["ts"]
    out = check_output_dir(args.out, "--out")
    print(f"spin-up beam: omega_s = {ws:g} rad/s, T_s = {ts:g} s, t_end = {o.t_end:g} s, "
          f"{o.integrator}, dt = {o.dt:g} s")
    out.mkdir(parents=True, exist_ok=True)
    sums = run_variants(specs, ws=ws, ts=ts, t_end=o.t_end, dt=o.dt, integrator=o.integrator, out_dir=out)
    text = table(sums, ts, o.t_end)
    print()
    print(text)
    (out / "summary.md").write_text(text + "\n", encoding="utf-8")
    plot(sums, out / "spinup.png", f"Spin-up beam, omega_s = {ws:g} rad/s, T_s = {ts:g} s")
    print(f"\nwrote {out / 'summary.md'}, {out / 'spinup.png'} and one CSV per variant in {out}")
    return 0


def cmd_paper(args) -> int:
    from flexsym.analysis.paper import run_paper
    from flexsym.toolchain.run import check_output_dir
    from flexsym.model.variant import builtin

    o = validate(given_options(args, SPINUP_OPTIONS[:4] + ("repeat",)), CLI, builtin("m3"))
    ref_dt = replace(BY_NAME["dt"], flag="--ref-dt").convert(args.ref_dt, CLI)
    elements = _elements(args.ref_elements)
    if not 1 <= elements <= MAX_EF_ELEMENTS:
        raise SpecError(f"--ref-elements: must be in 1..{MAX_EF_ELEMENTS} (got {elements})")
    out = check_output_dir(args.out, "--out")
    run_paper(out, ws=o.params["ws"], ts=o.params["ts"], t_end=o.t_end, dt=o.dt,
              repeat=o.repeat, end_to_end=not args.no_end_to_end, ref_elements=elements,
              ref_dt=ref_dt)
    return 0


MAX_BENDING = 5


def _select_system(args, scene, tol: float, repeat: int) -> int:
    from flexsym.analysis.system_select import select_system, table

    if args.max_bending is not None:
        raise SpecError(f"{args.scene}: --max-bending applies to one-beam scenes; a mechanism's "
                        "candidates are the built-in models m1, m2, m3 and prestress (and exact with "
                        "--exact) at 1, 2, 4 and 5 times its step")
    print(f"{scene.path}: candidates on outputs {', '.join(scene.columns)}, tolerance {tol:g}")
    results, best, ref_error = select_system(scene, tol, repeat=repeat, exact=args.exact)
    print()
    print(table(results, best, tol))
    if ref_error > tol / 3:
        print(f"\nnote: the reference's own error {ref_error:.1e} (its estimates above) is "
              "not well under the tolerance: the errors above are partly the reference's")
    if best is None and ref_error > tol:
        print(f"\nno candidate is within {tol:g}, and neither is the reference (its own error "
              f"{ref_error:.1e}): ef at select's mesh and step does not converge these outputs over "
              "this run either; measure a finer ef by hand (`flexsym run SCENE --model ef` on a "
              "copy with more elements and a smaller step), or score a shorter run")
        return 1
    if best is None:
        print(f"\nno candidate is within {tol:g}; ef is the model to use (`flexsym run {scene.path} --model ef`)")
        return 1
    print(f"\nchosen: model = \"{best.model}\" at dt = {best.dt:g} s ({best.cost * 1e3:.3f} ms, error "
          f"{best.error:.2e}): `flexsym run {scene.path} --model {best.model} --dt {best.dt:g}`")
    return 0


def cmd_select(args) -> int:
    from flexsym.scenes.scene import load_scene
    from flexsym.analysis.model_select import select, table

    try:
        tol = float(args.tol)
    except ValueError:
        raise SpecError(f"--tol: '{args.tol}' is not a number") from None
    if not 0 < tol < 1:
        raise SpecError(f"--tol: must be > 0 and < 1, relative to each output's peak (got {args.tol})")
    if args.max_bending is not None and args.max_bending not in [str(k) for k in range(1, MAX_BENDING + 1)]:
        raise SpecError(f"--max-bending: must be one of 1..{MAX_BENDING} (got {args.max_bending})")
    repeat = validate(given_options(args, ("repeat",)), CLI).repeat
    scene = load_scene(args.scene)
    if not hasattr(scene, "spec"):  # a mechanism (system scene)
        return _select_system(args, scene, tol, repeat)
    print(f"{scene.path}: candidates on outputs {', '.join(scene.spec.outputs)}, tolerance {tol:g}")
    results, best = select(scene, tol, max_bending=int(args.max_bending or 4), repeat=repeat,
                           exact=args.exact)
    print()
    print(table(results, best, tol))
    if best is None:
        print(f"\nno candidate is within {tol:g}; the reference ef is the model to use")
        return 1
    s = best.spec
    print(f"\nchosen: strain = \"{s.strain}\", axial = {[m.token for m in s.axial]}, "
          f"bending = {[m.token for m in s.bending]} ({best.cost * 1e3:.3f} ms, error {best.error:.2e})")
    return 0


def cmd_bench(args) -> int:
    from flexsym.analysis.bench import QUICK, CASES, run_bench
    from flexsym.toolchain.run import check_output_dir

    variants = _names(args.variants, "--variants") if args.variants is not None else None
    known = QUICK if args.quick else CASES
    for v in variants or []:
        if v not in known:
            raise SpecError(f"--variants: no benchmark cases for variant '{v}' (have: {', '.join(known)})")
    repeat = validate(given_options(args, ("repeat",)), CLI).repeat if args.repeat is not None else None
    out = check_output_dir(args.out, "--out")
    run_bench(out, variants=variants, quick=args.quick, repeat=repeat)
    return 0


SWEEP_OPTIONS = tuple(n for n in RUN_OPTIONS if n not in ("repeat", "energy"))


def cmd_sweep(args) -> int:
    import numpy as np

    from flexsym.toolchain.run import check_output_path
    from flexsym.sim.inprocess import settings_of
    from flexsym.sim.sweep import (claim_partial, fingerprint_of, make_plan, partial_path, plot, prepare_plan,
                                   read_table, run_sweep)

    spec, scene = resolve(args)
    o = _run_options(args, spec, scene)
    if spec is None:  # a system scene: its model is built first (its manifest names what varies)
        from flexsym.sim.sweep import system_target

        try:
            spec = system_target(scene.system)
        except SpecError as exc:
            raise SpecError(f"{scene.path}: {exc}") from None
    keep_interval = scene is not None or args.interval is not None
    at = []
    for item in (args.at or "").split(",") if args.at else []:
        try:
            at.append(float(item))
        except ValueError:
            raise SpecError(f"--at '{item}' is not a number") from None
    if args.workers is not None and args.workers < 1:
        raise SpecError(f"--workers must be >= 1 (got {args.workers})")
    where = CLI if scene is None else Where("scene", scene.path)
    plan = make_plan(spec, settings_of(o, keep_interval), o.params, args.vary or [], samples=args.samples,
                     seed=args.seed, sampling=args.sampling, at=at, where=where)
    plot_x = args.plot_x.split(",") if args.plot_x else list(plan.names[:2])
    for name in plot_x:
        if name not in plan.names:
            raise SpecError(f"--plot-x {name}: not a varied input ({', '.join(plan.names)})")
    if len(plot_x) > 2:
        raise SpecError("--plot-x: one or two varied inputs")
    plot_y = args.plot_y or f"{plan.outputs[0]}_min"
    if args.plot and plot_y not in plan.header():
        raise SpecError(f"--plot-y {plot_y}: not a column of the table ({', '.join(plan.header())})")
    out = check_output_path(args.out, "--out")
    plot_path = check_output_path(args.plot, "--plot", PLOT_TYPES) if args.plot else None
    plan.fingerprint = fingerprint_of(plan.spec)  # the partial file is checked before any build
    with claim_partial(plan, out, args.resume) as partial:
        prepare_plan(plan)
        runs_on = f"dask at {args.dask}" if args.dask else f"{args.workers or os.cpu_count()} local processes"
        print(f"sweep {spec.name}: {len(plan)} runs ({plan.sampling}"
              + (f", seed {plan.seed}" if plan.seed is not None else "") + f") on {runs_on}"
              + (f"; {len(partial.done)} finished runs kept from {partial.path}" if partial.done else ""))
        try:
            run_sweep(plan, out, workers=args.workers, dask=args.dask,
                      progress=True if args.progress else None, partial=partial)
        except KeyboardInterrupt:
            print(f"flexsym: sweep interrupted; finished runs kept in {partial_path(out)}: "
                  "run the same command with --resume to continue", file=sys.stderr)
            return 130
    table = read_table(out)
    status = table["status"]
    ok = int(np.sum(status == "ok"))
    valid = int(np.sum(table["valid"] == "True"))
    print(f"table: {out} ({len(status)} runs: {ok} ok, {len(status) - ok} stopped, "
          f"{valid} valid)")
    if plot_path is not None:
        plot(table, plot_x, plot_y, plot_path, f"{spec.name}: {plot_y}",
             others=[n for n in plan.names if n not in plot_x])
        print(f"plot: {plot_path}")
    return 0


def cmd_bench_systems(args) -> int:
    from flexsym.toolchain.run import check_output_dir
    from flexsym.analysis.system_bench import QUICK, SYSTEMS, run_system_bench

    table = QUICK if args.quick else SYSTEMS
    systems = _names(args.systems, "--systems") if args.systems else None
    for name in systems or ():
        if name not in table:
            raise SpecError(f"--systems: unknown system '{name}' (here: {', '.join(table)})")
    models = _names(args.models, "--models") if args.models else None
    repeat = BY_NAME["repeat"].convert(args.repeat, CLI) if args.repeat is not None else None
    run_system_bench(check_output_dir(args.out, "--out"), systems, models, args.quick, repeat)
    return 0


def cmd_exact_study(args) -> int:
    from flexsym.analysis.exact_study import run_study

    from flexsym.toolchain.run import check_output_dir

    if args.max_modes not in [str(k) for k in range(1, 13)]:
        raise SpecError(f"--max-modes: must be one of 1..12 (got {args.max_modes})")
    run_study(check_output_dir(args.out, "--out"), quick=args.quick, max_modes=int(args.max_modes))
    return 0


def cmd_variants(args) -> int:
    from flexsym.model.strain_models import STRAIN_MODELS
    from flexsym.model.modes import FAMILIES
    from flexsym.model.variant import BUILTIN

    print("built-in variants:")
    for v in BUILTIN:
        print(f"  {v.name:16s} {'/'.join(v.aliases):4s} {v.description}")
    print("strain models:")
    for m in STRAIN_MODELS.values():
        print(f"  {m.name:20s} {m.description}")
    print("mode families (token: description):")
    for (axis, _), f in FAMILIES.items():
        tok = f.short if f.single else f"{f.short}K"
        print(f"  {axis:8s} {tok:8s} {f.summary}")
    return 0


class _Parser(argparse.ArgumentParser):
    """Bad command lines are bad input too: one line naming the problem, exit 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _model_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--model", help="with a scene file: replace its model by this variant (m1, m2, "
                   "m3, prestress, ef, ...; a body's modes are computed from its data)")


def build_parser() -> argparse.ArgumentParser:
    ap = _Parser(prog="flexsym", description=__doc__)
    sub = ap.add_subparsers(dest="command", required=True, parser_class=_Parser)

    p = sub.add_parser("generate", help="derive and generate C for a variant or a scene ('all': every built-in)")
    _variant_args(p)
    p.add_argument("--out", help="target folder (default: generated/NAME for built-ins, the cache otherwise)")
    _model_arg(p)
    p.set_defaults(func=cmd_generate)

    p = sub.add_parser("build", help="compile a variant or a scene (generating it if needed)")
    _variant_args(p)
    _model_arg(p)
    p.set_defaults(func=cmd_build)

    p = sub.add_parser("run", help="simulate the spin-up with a variant, or a scene file")
    _variant_args(p)
    g = p.add_argument_group("run options (checked against the table in flexsym/model/options.py)")
    add_arguments(g, RUN_OPTIONS)
    p.add_argument("--param", action="append", help="beam or manoeuvre parameter NAME=VALUE "
                   "(rho, E, A, I, L, ws, ts); repeatable")
    p.add_argument("--out", help="CSV file for the results (its directory must exist)")
    p.add_argument("--plot", help="PNG/PDF/SVG file for a plot of v_tip(t) (its directory must exist)")
    _model_arg(p)
    p.set_defaults(func=cmd_run)

    p = sub.add_parser("export-fmu", help="export a variant or scene as an FMI 3.0 Co-Simulation FMU")
    _variant_args(p)
    add_arguments(p, FMU_OPTIONS)
    p.add_argument("--param", action="append", help="start value of a beam or manoeuvre parameter "
                   "NAME=VALUE; repeatable")
    p.add_argument("--input", default="none", help="none (default): the built-in manoeuvre, its "
                   "parameters tunable; drive: theta_dot, theta_ddot are inputs from the importer")
    p.add_argument("--out", required=True, help="the FMU file (NAME.fmu)")
    p.set_defaults(func=cmd_export_fmu)

    p = sub.add_parser("bench-fmu", help="CPU time of an exported FMU's doStep loop against the native "
                       "runtime on the same steps")
    _variant_args(p)
    add_arguments(p, FMU_OPTIONS)
    p.add_argument("--param", action="append", help="beam or manoeuvre parameter NAME=VALUE; repeatable")
    p.add_argument("--repeat", type=int, default=21, help="runs after a warm-up (default 21)")
    p.set_defaults(func=cmd_bench_fmu, out=None)

    p = sub.add_parser("fe-export", help="write a scene's body as finite-element data (body.toml + "
                       "Matrix Market M, K, KG)")
    p.add_argument("scene", help="scene file (.toml) with a [body] table")
    p.add_argument("--out", required=True, help="new folder to write")
    p.set_defaults(func=cmd_fe_export)

    p = sub.add_parser("inspect", help="show the derivation of a variant")
    _variant_args(p)
    p.add_argument("--latex", action="store_true", help="print expressions as LaTeX")
    p.add_argument("--plot-modes", dest="plot_modes", help="PNG file for a plot of the mode shapes")
    p.add_argument("--model", help="with a scene file: inspect this variant on the scene's body")
    p.add_argument("--section", help="comma-separated subset of: modes, energy, integrals, mass, "
                   "stiffness, equations, ops (a system scene: system, derivation)")
    p.set_defaults(func=cmd_inspect)

    p = sub.add_parser("spinup", help="the benchmark: variants #0-#3, summary table and plot")
    add_arguments(p, SPINUP_OPTIONS)
    p.add_argument("--variants", default="m0,m1,m2,m3")
    p.add_argument("--out", default="results", help="output folder (default: results)")
    p.set_defaults(func=cmd_spinup)

    p = sub.add_parser("bench", help="CPU time against error: variants x integrators x steps")
    p.add_argument("--quick", action="store_true", help="a few cases (under a minute)")
    p.add_argument("--out", default="bench", help="output folder (default: bench)")
    p.add_argument("--variants", help="comma-separated subset (default: all with cases)")
    p.add_argument("--repeat", help="runs per case after a warm-up (default 21; quick 3)")
    p.set_defaults(func=cmd_bench)

    p = sub.add_parser("bench-systems", help="CPU time against integration error on the mechanisms "
                       "S1-S3 and S5-S7 (scenes hub, slider_crank, pendulum, flap, spherical_pendulum, "
                       "spatial_slider_crank)")
    p.add_argument("--quick", action="store_true", help="two cases on the pendulum (about 10 s)")
    p.add_argument("--out", default="bench_systems", help="output folder (default: bench_systems)")
    p.add_argument("--systems", help="comma-separated subset of hub, slider_crank, pendulum, flap, "
                   "spherical_pendulum, spatial_slider_crank (default: the planar hub, slider_crank, "
                   "pendulum)")
    p.add_argument("--models", help="comma-separated models (default: each system's list)")
    p.add_argument("--repeat", help="timed runs per case (default 5; quick 1)")
    p.set_defaults(func=cmd_bench_systems)

    p = sub.add_parser("select", help="cheapest model whose error on a scene stays under a tolerance")
    p.add_argument("scene", help="scene file (.toml)")
    p.add_argument("--tol", required=True,
                   help="largest allowed error, relative to each output's peak (e.g. 0.01)")
    p.add_argument("--max-bending", default=None, help="largest bending set tried (1..5, default 4; "
                   "one-beam scenes)")
    add_arguments(p, ("repeat",), defaults={"repeat": "3"})
    p.add_argument("--exact", action="store_true", help="also try the exact-kinematics model "
                   "(one-beam scene: strain exact, bending cf1..cfK; mechanism: the built-in exact "
                   "on every flexible body, its modes from the beam's ends). Opt-in: an exact model takes "
                   "tens of seconds (one beam) to a few minutes (a mechanism) to compile")
    p.set_defaults(func=cmd_select)

    p = sub.add_parser("paper", help="reproduce the paper's Fig. 7-9 and Table 1, with an "
                       "accuracy table against a converged finite-element reference")
    p.add_argument("--out", default="paper", help="output folder (default: paper)")
    add_arguments(p, SPINUP_OPTIONS[:4])
    add_arguments(p, ("repeat",), defaults={"repeat": "5"})
    p.add_argument("--ref-elements", default="32", help="elements of the reference (default 32)")
    p.add_argument("--ref-dt", default="5e-4", help="step of the reference (default 5e-4)")
    p.add_argument("--no-end-to-end", action="store_true",
                   help="skip timing generation + compilation from scratch")
    p.set_defaults(func=cmd_paper)

    p = sub.add_parser("sweep", help="many runs of a scene or variant over run-time parameters: "
                       "a table with one row per run (local processes or a Dask cluster)")
    _variant_args(p)
    g = p.add_argument_group("run options shared by every run (checked against the table in "
                             "flexsym/model/options.py)")
    add_arguments(g, SWEEP_OPTIONS)
    p.add_argument("--param", action="append", help="fixed beam or manoeuvre parameter NAME=VALUE")
    p.add_argument("--vary", action="append", metavar="NAME=SPEC",
                   help="START:STOP:COUNT (grid), a,b,c (list) or LO:HI (with --samples); repeatable; "
                        "names: rho, E, A, I, L, ws, ts, q0_<coordinate>, qd0_<coordinate>, t_end, dt, "
                        "step (radau5)")
    p.add_argument("--samples", type=int, help="N random or Latin-hypercube samples of the LO:HI ranges")
    p.add_argument("--seed", type=int, help="seed of the samples (default 0)")
    p.add_argument("--sampling", choices=("random", "lhs"), help="with --samples (default lhs)")
    p.add_argument("--at", help="comma-separated times [s]: also report every output's value there")
    p.add_argument("--out", required=True, help="the table (CSV; its directory must exist); finished "
                   "runs go to OUT.partial first")
    p.add_argument("--resume", action="store_true", help="continue an interrupted sweep from OUT.partial")
    p.add_argument("--workers", type=int, help="local processes (default: all cores)")
    p.add_argument("--dask", metavar="ADDRESS", help="run on an existing dask.distributed scheduler "
                   "(e.g. tcp://host:8786)")
    p.add_argument("--plot", help="PNG/PDF/SVG file: a summary column against one or two varied inputs "
                   "(its directory must exist)")
    p.add_argument("--plot-y", help="column to plot (default: <first output>_min)")
    p.add_argument("--plot-x", help="one or two varied inputs, comma-separated (default: the first two)")
    p.add_argument("--progress", action="store_true", help="progress bar on stderr even when not a terminal")
    p.set_defaults(func=cmd_sweep)

    p = sub.add_parser("exact-study", help="the exact-kinematics model against ef: error against "
                       "the number of modes at omega_s = 6, 10, 20 and the abrupt spin-up")
    p.add_argument("--out", default="exact_study", help="output folder (default: exact_study)")
    p.add_argument("--max-modes", default="6", help="largest mode count (default 6)")
    p.add_argument("--quick", action="store_true", help="8 s of one case, 2 and 3 modes")
    p.set_defaults(func=cmd_exact_study)

    p = sub.add_parser("variants", help="list built-in variants, strain models and mode families")
    p.set_defaults(func=cmd_variants)
    return ap


class Terminated(BaseException):
    """SIGTERM or SIGHUP, raised in the main thread so that cleanup runs: the driver is
    killed (subprocess.run kills its child on any exception) and temporary files go."""

    def __init__(self, signum):
        super().__init__(signum)
        self.signum = signum


def _terminate(signum, frame):
    raise Terminated(signum)


def main(argv=None) -> int:
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as e:  # --help, or a command line argparse refused (one line, exit 2)
        return e.code
    main_thread = threading.current_thread() is threading.main_thread()
    previous = {sig: signal.signal(sig, _terminate) for sig in (signal.SIGTERM, signal.SIGHUP)} \
        if main_thread else {}
    try:
        return args.func(args)
    except FlexsymError as e:
        text = str(e)
        if isinstance(e, SpecError):  # bad input is one line, whatever the input held
            text = text.replace("\r", "\\r").replace("\n", "\\n")
        print(f"flexsym: error: {text}", file=sys.stderr)
        return e.exit_code
    except KeyboardInterrupt:
        print("flexsym: interrupted", file=sys.stderr)
        return 130
    except Terminated as e:
        print(f"flexsym: terminated by signal {e.signum}", file=sys.stderr)
        return 128 + e.signum
    except BrokenPipeError:  # `flexsym ... | head`: the reader left; files were written as usual
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # no second error when Python flushes stdout at exit
        return 128 + signal.SIGPIPE
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def entry() -> None:
    """The `flexsym` command. A second Ctrl-C while an interrupted command is stopping (GNU
    timeout sends two) lands outside main's own handling: it ends the command with 130 too,
    not with a traceback."""
    try:
        code = main()
    except KeyboardInterrupt:
        code = 130
    sys.exit(code)


if __name__ == "__main__":
    entry()
