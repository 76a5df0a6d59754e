"""flexsym command line: generate, build, run, inspect, select, spinup, paper, variants."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .errors import FlexsymError, SpecError
from .run import INTEGRATORS


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
    g.add_argument("--elements", type=int, help="number of finite elements (variant ef)")
    g.add_argument("--name", help="name of the custom variant (default: derived from the base)")


_OVERRIDES = ("strain", "axial", "bending", "maneuver", "outputs", "stress", "axial_force", "elements",
              "name")
RUN_DEFAULTS = {"ws": 6.0, "ts": 15.0, "t_end": 20.0, "dt": 1e-3, "integrator": "genalpha"}


def _given(args, keys) -> list[str]:
    return [k for k in keys if getattr(args, k, None) is not None]


def resolve(args):
    """(spec, scene or None) from a variant name with overrides, or from a scene file."""
    from .spec import builtin, customize

    if args.variant.endswith(".toml"):
        from .scene import load_scene

        scene = load_scene(args.variant)
        given = _given(args, _OVERRIDES)
        if given:
            raise SpecError(f"{args.variant}: --{given[0].replace('_', '-')} does not combine with a "
                            "scene file: set it in the scene's [model] table")
        return scene.spec, scene
    base = builtin(args.variant)
    overrides = {k: getattr(args, k, None) for k in _OVERRIDES if k != "name"}
    if all(v is None for v in overrides.values()) and not getattr(args, "name", None):
        return base.validate(), None
    return customize(base, name=getattr(args, "name", None), **overrides), None


def resolve_spec(args):
    return resolve(args)[0]


def _run_args(p: argparse.ArgumentParser, defaults: bool = True) -> None:
    d = RUN_DEFAULTS if defaults else dict.fromkeys(RUN_DEFAULTS)
    p.add_argument("--ws", type=float, default=d["ws"], help="final spin rate omega_s [rad/s] (default 6)")
    p.add_argument("--ts", type=float, default=d["ts"], help="spin-up time T_s [s] (default 15)")
    p.add_argument("--t-end", type=float, default=d["t_end"], help="end time [s] (default 20)")
    p.add_argument("--dt", type=float, default=d["dt"],
                   help="time step [s] (default 1e-3); the output interval for dopri5, and for radau5 "
                        "with --step")
    p.add_argument("--integrator", choices=INTEGRATORS, default=d["integrator"],
                   help="rk4, dopri5 (adaptive, see --tol), genalpha (default), newmark, "
                        "radau5 (implicit, order 5, large steps)")


def cmd_generate(args) -> int:
    from .generate import generate
    from .pipeline import cache_folder, checked_in_folder, is_builtin
    from .spec import BUILTIN

    if args.variant == "all":  # every built-in variant into generated/
        for spec in BUILTIN:
            generate(spec, checked_in_folder(spec))
            print(f"generated '{spec.name}' in {checked_in_folder(spec)}")
        return 0
    spec = resolve_spec(args)
    dest = Path(args.out) if args.out else (checked_in_folder(spec) if is_builtin(spec) else cache_folder(spec))
    g = generate(spec, dest)
    ops = ", ".join(f"{k} {v['total_ops']}" for k, v in g.manifest["kernels"].items())
    print(f"generated '{spec.name}' in {dest}\n  fingerprint {g.manifest['fingerprint'][:16]}...\n  ops: {ops}")
    return 0


def cmd_build(args) -> int:
    from .pipeline import prepare

    built = prepare(resolve_spec(args))
    print(f"built '{built.name}': {built.executable}")
    return 0


def _run_settings(args, spec, scene) -> tuple[dict, Path | None]:
    """Run options from a scene file, or from the command line with the defaults filled in."""
    if scene is not None:
        given = _given(args, list(RUN_DEFAULTS) + ["tol", "step"]) + (["param"] if args.param else [])
        if given:
            raise SpecError(f"{scene.path}: --{given[0].replace('_', '-')} does not combine with a "
                            "scene file: set it in the scene")
        return (dict(t_end=scene.t_end, dt=scene.dt, integrator=scene.integrator, params=scene.params,
                     out_every=scene.out_every, tol=scene.tol, step=scene.step),
                Path(args.out) if args.out else scene.output_file)
    for k, v in RUN_DEFAULTS.items():
        if getattr(args, k) is None:
            setattr(args, k, v)
    params = {}
    if not spec.maneuver.startswith("expression:"):
        params = {"ws": args.ws, "ts": args.ts} if spec.maneuver == "spin_up" else {"ws": args.ws}
    for item in args.param or []:
        if "=" not in item:
            raise SpecError(f"--param '{item}': expected NAME=VALUE")
        k, v = item.split("=", 1)
        try:
            params[k.strip()] = float(v)
        except ValueError:
            raise SpecError(f"--param '{item}': '{v}' is not a number") from None
    return (dict(t_end=args.t_end, dt=args.dt, integrator=args.integrator, params=params, tol=args.tol,
                 step=args.step),
            Path(args.out) if args.out else None)


def cmd_run(args) -> int:
    from .spinup import Summary, describe, plot, table
    from .pipeline import prepare
    from .run import check_options, run_built
    from .validity import assess

    spec, scene = resolve(args)
    settings, out = _run_settings(args, spec, scene)
    check_options(**{k: v for k, v in settings.items() if k != "out_every"}, spec=spec)
    built = prepare(spec)
    res = run_built(built, **settings, out=out)
    s = Summary(spec, res)
    ts = settings["params"].get("ts", settings["t_end"])
    print(describe(res, spec.outputs) if scene is not None or "v_tip" not in res.columns else
          table([s], ts, settings["t_end"]))
    if out:
        print(f"results: {out}")
    if args.plot and "v_tip" in res.columns:
        plot([s], Path(args.plot), f"{spec.name}, {spec.maneuver}")
        print(f"plot: {args.plot}")
    verdict = assess(spec, res, settings["params"])
    for note in verdict.notes:
        print(f"flexsym: {note}", file=sys.stderr)
    if not res.ok:
        return 3
    return 0 if verdict.valid else 4


def cmd_inspect(args) -> int:
    from .inspect_model import SECTIONS, Report

    sections = args.section.split(",") if args.section else SECTIONS
    for s in sections:
        if s not in SECTIONS:
            raise SpecError(f"unknown section '{s}' (known: {', '.join(SECTIONS)})")
    spec, scene = resolve(args)
    sys.stdout.write(Report(spec, latex=args.latex).render(sections))
    if scene is not None:
        from .inspect_model import savings

        sys.stdout.write(savings(spec, scene.full_spec))
    return 0


def cmd_spinup(args) -> int:
    from .spec import builtin
    from .spinup import plot, run_variants, table

    specs = [builtin(v.strip()) for v in args.variants.split(",") if v.strip()]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print(f"spin-up beam: omega_s = {args.ws:g} rad/s, T_s = {args.ts:g} s, t_end = {args.t_end:g} s, "
          f"{args.integrator}, dt = {args.dt:g} s")
    sums = run_variants(specs, ws=args.ws, ts=args.ts, t_end=args.t_end, dt=args.dt,
                        integrator=args.integrator, out_dir=out)
    text = table(sums, args.ts, args.t_end)
    print()
    print(text)
    (out / "summary.md").write_text(text + "\n", encoding="utf-8")
    plot(sums, out / "spinup.png",
         f"Spin-up beam, omega_s = {args.ws:g} rad/s, T_s = {args.ts:g} s")
    print(f"\nwrote {out / 'summary.md'}, {out / 'spinup.png'} and one CSV per variant in {out}")
    return 0


def cmd_paper(args) -> int:
    from .paper import run_paper

    run_paper(Path(args.out), ws=args.ws, ts=args.ts, t_end=args.t_end, dt=args.dt,
              repeat=args.repeat, end_to_end=not args.no_end_to_end, ref_elements=args.ref_elements,
              ref_dt=args.ref_dt)
    return 0


def cmd_select(args) -> int:
    from .scene import load_scene
    from .select import select, table

    if not args.tol > 0:
        raise SpecError(f"--tol must be > 0 (got {args.tol})")
    if not 1 <= args.max_bending <= 5:
        raise SpecError(f"--max-bending must be in 1..5 (got {args.max_bending})")
    scene = load_scene(args.scene)
    print(f"{scene.path}: candidates on outputs {', '.join(scene.spec.outputs)}, tolerance {args.tol:g}")
    results, best = select(scene, args.tol, max_bending=args.max_bending, repeat=args.repeat,
                           exact=args.exact)
    print()
    print(table(results, best, args.tol))
    if best is None:
        print(f"\nno candidate is within {args.tol:g}; the reference ef is the model to use")
        return 1
    s = best.spec
    print(f"\nchosen: strain = \"{s.strain}\", axial = {[m.token for m in s.axial]}, "
          f"bending = {[m.token for m in s.bending]} ({best.cost * 1e3:.3f} ms, error {best.error:.2e})")
    return 0


def cmd_bench(args) -> int:
    from .bench import QUICK, CASES, run_bench

    variants = [v.strip() for v in args.variants.split(",")] if args.variants else None
    known = QUICK if args.quick else CASES
    for v in variants or []:
        if v not in known:
            raise SpecError(f"no benchmark cases for variant '{v}' (have: {', '.join(known)})")
    run_bench(Path(args.out), variants=variants, quick=args.quick, repeat=args.repeat)
    return 0


def cmd_exact_study(args) -> int:
    from .exact_study import run_study

    if not 1 <= args.max_modes <= 12:
        raise SpecError(f"--max-modes must be 1..12 (got {args.max_modes})")
    run_study(Path(args.out), quick=args.quick, max_modes=args.max_modes)
    return 0


def cmd_variants(args) -> int:
    from .energy import STRAIN_MODELS
    from .modes import FAMILIES
    from .spec import BUILTIN

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


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="flexsym", description=__doc__)
    sub = ap.add_subparsers(dest="command", required=True)

    p = sub.add_parser("generate", help="derive and generate C for a variant ('all': every built-in)")
    _variant_args(p)
    p.add_argument("--out", help="target folder (default: generated/NAME for built-ins, the cache otherwise)")
    p.set_defaults(func=cmd_generate)

    p = sub.add_parser("build", help="compile a variant (generating it if needed)")
    _variant_args(p)
    p.set_defaults(func=cmd_build)

    p = sub.add_parser("run", help="simulate the spin-up with a variant, or a scene file")
    _variant_args(p)
    _run_args(p, defaults=False)
    p.add_argument("--param", action="append", help="beam or manoeuvre parameter NAME=VALUE "
                   "(rho, E, A, I, L, ws, ts); repeatable")
    p.add_argument("--tol", type=float, help="dopri5 error tolerance (rtol; atol = tol * L), "
                   "default 1e-6; 0: fixed steps --dt")
    p.add_argument("--step", type=float, help="radau5 step [s] (default --dt); rows stay every --dt, "
                   "from its collocation polynomial")
    p.add_argument("--out", help="CSV file for the results")
    p.add_argument("--plot", help="PNG file for a plot of v_tip(t)")
    p.set_defaults(func=cmd_run)

    p = sub.add_parser("inspect", help="show the derivation of a variant")
    _variant_args(p)
    p.add_argument("--latex", action="store_true", help="print expressions as LaTeX")
    p.add_argument("--section", help="comma-separated subset of: modes, energy, integrals, mass, "
                   "stiffness, equations, ops")
    p.set_defaults(func=cmd_inspect)

    p = sub.add_parser("spinup", help="the benchmark: variants #0-#3, summary table and plot")
    _run_args(p)
    p.add_argument("--variants", default="m0,m1,m2,m3")
    p.add_argument("--out", default="results", help="output folder (default: results)")
    p.set_defaults(func=cmd_spinup)

    p = sub.add_parser("bench", help="CPU time against error: variants x integrators x steps")
    p.add_argument("--quick", action="store_true", help="a few cases (under a minute)")
    p.add_argument("--out", default="bench", help="output folder (default: bench)")
    p.add_argument("--variants", help="comma-separated subset (default: all with cases)")
    p.add_argument("--repeat", type=int, help="runs per case after a warm-up (default 21; quick 3)")
    p.set_defaults(func=cmd_bench)

    p = sub.add_parser("select", help="cheapest model whose error on a scene stays under a tolerance")
    p.add_argument("scene", help="scene file (.toml)")
    p.add_argument("--tol", type=float, required=True,
                   help="largest allowed error, relative to each output's peak (e.g. 0.01)")
    p.add_argument("--max-bending", type=int, default=4, help="largest bending set tried (default 4)")
    p.add_argument("--repeat", type=int, default=3, help="repeats for the CPU medians (default 3)")
    p.add_argument("--exact", action="store_true", help="also try the exact-kinematics model "
                   "(strain exact, bending cf1..cfK)")
    p.set_defaults(func=cmd_select)

    p = sub.add_parser("paper", help="reproduce the paper's Fig. 7-9 and Table 1, with an "
                       "accuracy table against a converged finite-element reference")
    p.add_argument("--out", default="paper", help="output folder (default: paper)")
    p.add_argument("--ws", type=float, default=6.0)
    p.add_argument("--ts", type=float, default=15.0)
    p.add_argument("--t-end", type=float, default=20.0)
    p.add_argument("--dt", type=float, default=1e-3, help="step of the compared models (default 1e-3)")
    p.add_argument("--repeat", type=int, default=5, help="repeats for the CPU medians (default 5)")
    p.add_argument("--ref-elements", type=int, default=32, help="elements of the reference (default 32)")
    p.add_argument("--ref-dt", type=float, default=5e-4, help="step of the reference (default 5e-4)")
    p.add_argument("--no-end-to-end", action="store_true",
                   help="skip timing generation + compilation from scratch")
    p.set_defaults(func=cmd_paper)

    p = sub.add_parser("exact-study", help="the exact-kinematics model against ef: error against "
                       "the number of modes at omega_s = 6, 10, 20 and the abrupt spin-up")
    p.add_argument("--out", default="exact_study", help="output folder (default: exact_study)")
    p.add_argument("--max-modes", type=int, default=6, help="largest mode count (default 6)")
    p.add_argument("--quick", action="store_true", help="8 s of one case, 2 and 3 modes")
    p.set_defaults(func=cmd_exact_study)

    p = sub.add_parser("variants", help="list built-in variants, strain models and mode families")
    p.set_defaults(func=cmd_variants)
    return ap


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except FlexsymError as e:
        print(f"flexsym: error: {e}", file=sys.stderr)
        return e.exit_code
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
