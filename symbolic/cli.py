"""flexsym command line: generate, build, run, inspect, spinup, variants."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .errors import FlexsymError, SpecError
from .run import INTEGRATORS


def _variant_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("variant", help="built-in variant name or alias (m0..m3), the base for overrides")
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
    g.add_argument("--name", help="name of the custom variant (default: derived from the base)")


def resolve_spec(args):
    from .spec import builtin, customize

    base = builtin(args.variant)
    overrides = {k: getattr(args, k, None) for k in ("strain", "axial", "bending", "maneuver",
                                                     "outputs", "stress", "axial_force")}
    if all(v is None for v in overrides.values()) and not getattr(args, "name", None):
        return base.validate()
    return customize(base, name=getattr(args, "name", None), **overrides)


def _run_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--ws", type=float, default=6.0, help="final spin rate omega_s [rad/s] (default 6)")
    p.add_argument("--ts", type=float, default=15.0, help="spin-up time T_s [s] (default 15)")
    p.add_argument("--t-end", type=float, default=20.0, help="end time [s] (default 20)")
    p.add_argument("--dt", type=float, default=1e-3,
                   help="time step [s] (default 1e-3); for dopri5 the output interval")
    p.add_argument("--integrator", choices=INTEGRATORS, default="genalpha",
                   help="rk4, dopri5 (adaptive, see --tol), genalpha (default), newmark")


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


def cmd_run(args) -> int:
    from .spinup import Summary, plot, table
    from .pipeline import prepare
    from .run import check_options, run_built

    spec = resolve_spec(args)
    params = {"ws": args.ws, "ts": args.ts} if spec.maneuver == "spin_up" else {"ws": args.ws}
    for item in args.param or []:
        if "=" not in item:
            raise SpecError(f"--param '{item}': expected NAME=VALUE")
        k, v = item.split("=", 1)
        try:
            params[k.strip()] = float(v)
        except ValueError:
            raise SpecError(f"--param '{item}': '{v}' is not a number") from None
    check_options(t_end=args.t_end, dt=args.dt, integrator=args.integrator, params=params, spec=spec,
                  tol=args.tol)
    built = prepare(spec)
    res = run_built(built, t_end=args.t_end, dt=args.dt, integrator=args.integrator, params=params,
                    out=Path(args.out) if args.out else None, tol=args.tol)
    s = Summary(spec, res, 0.0)
    print(table([s], args.ts, args.t_end))
    if args.out:
        print(f"results: {args.out}")
    if args.plot:
        plot([s], Path(args.plot), f"{spec.name}, omega_s = {args.ws:g} rad/s, T_s = {args.ts:g} s")
        print(f"plot: {args.plot}")
    if not res.ok:
        print(f"flexsym: {res.message}", file=sys.stderr)
        return 3
    return 0


def cmd_inspect(args) -> int:
    from .inspect_model import SECTIONS, Report

    sections = args.section.split(",") if args.section else SECTIONS
    for s in sections:
        if s not in SECTIONS:
            raise SpecError(f"unknown section '{s}' (known: {', '.join(SECTIONS)})")
    sys.stdout.write(Report(resolve_spec(args), latex=args.latex).render(sections))
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

    p = sub.add_parser("run", help="simulate the spin-up with a variant")
    _variant_args(p)
    _run_args(p)
    p.add_argument("--param", action="append", help="beam or manoeuvre parameter NAME=VALUE "
                   "(rho, E, A, I, L, ws, ts); repeatable")
    p.add_argument("--tol", type=float, help="dopri5 error tolerance (rtol; atol = tol * L), "
                   "default 1e-6; 0: fixed steps --dt")
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
