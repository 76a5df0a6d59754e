"""`flexsym bench-systems`: CPU time against integration error on the mechanisms S1-S3 and
the spatial S5-S7.

For each system scene x model x case (integrator, step, options), on the scene's own run
(t_end, rows):
  cpu_s        median CPU time of the integration inside the C runtime over --repeat runs
  err_<column> max |y - y(same model, reference step)| over the rows, divided by the peak
               |y| of the reference: the integrator's error, per output column
  err_max      the largest of them
The reference is the same model at REF_DIVISOR times smaller a step than the smallest of the
cases, by rk4 for a tree (no cut joint: the smallest error per step of the methods here;
rk4 at 0.1 ms is within 3e-5 of the peak of rk4 at 10 us on S3), by the scene's integrator
for a closed loop (ali3p on S2), and by rk4p (order 4) for the spatial systems with
constraints (S6's ball joint, S7's loop). Next to it, the total error of the case against
the geometrically exact `ef` on the same system (EF_REFERENCE: elements, integrator, step;
none yet for S6 and S7, whose beams hang on free joints):
  ef_<column>  max |y - y_ef| over the rows, divided by the peak |y_ef|
  ef_max       the largest of them (model error + integration error)
Writes bench_systems.csv and bench_systems.md to --out.
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from dataclasses import replace

from flexsym.model.options import Where, validate
from flexsym.model.variant import builtin, customize
from flexsym.core.paths import PACKAGE_DIR
from flexsym.toolchain.run import run_built
from flexsym.scenes.scene import load_scene
from flexsym.model.system import RECOVERABLE, Output, parse_output
from flexsym.toolchain.pipeline import prepare_system

SCENES_DIR = PACKAGE_DIR.parent / "scenes"
REF_DIVISOR = 10


@dataclass(frozen=True)
class Case:
    integrator: str
    dt: float  # divides the row interval
    options: tuple[tuple[str, float], ...] = ()  # further run options, e.g. FOX_GOODWIN

    @property
    def label(self) -> str:
        return " ".join([self.integrator] + [f"{k}={v:.4g}" for k, v in self.options])


@dataclass(frozen=True)
class SystemCases:
    models: tuple[str, ...]
    cases: tuple[Case, ...]
    reference: str | None = None  # its integrator; None: rk4 for a tree, the scene's for a loop


# Newmark beta = 1/12: fourth-order period error, stable for omega_max dt <= sqrt(6) (S3: the
# released strip rings for 2 s, and M_mid's error is the phase of that ringing)
FOX_GOODWIN = (("newmark_beta", 1 / 12),)
SYSTEMS = {
    "hub": SystemCases(("m1", "m3", "prestress"),
                       tuple(Case("genalpha", dt) for dt in (0.01, 0.005, 0.002, 0.001)) + (Case("rk4", 0.001),)),
    # m3 has no axial coordinate: its N_mid comes from equilibrium (the scene's N output).
    # rk4p (order 4) at 0.2 ms, below m3's stability limit 0.241 ms (m2's axial mode: 0.045 ms,
    # so refused there)
    "slider_crank": SystemCases(("m2", "m3"),
                                tuple(Case("ali3p", dt) for dt in (2e-4, 1e-4, 5e-5))
                                + tuple(Case("genalpha3", dt) for dt in (1e-4, 5e-5))
                                + tuple(Case("rk4p", dt) for dt in (2e-4, 1e-4))),
    "pendulum": SystemCases(("m1", "m3", "prestress"),
                            tuple(Case("genalpha", dt) for dt in (1e-3, 1e-4, 5e-5))
                            + tuple(Case("rk4", dt) for dt in (2.5e-4, 1e-4))
                            + (Case("dopri5", 1e-3, (("tol", 1e-5),)),)
                            + tuple(Case("newmark", dt, FOX_GOODWIN) for dt in (5e-4, 1e-3 / 3, 2.5e-4))),
    # the spatial S5-S7 (docs/validation/spatial.md)
    "flap": SystemCases(("m1", "m3", "prestress"),
                        tuple(Case("genalpha", dt) for dt in (0.01, 0.005, 0.002, 0.001)) + (Case("rk4", 0.001),)),
    "spherical_pendulum": SystemCases(("m3",), tuple(Case("genalpha3", dt) for dt in (5e-4, 2.5e-4, 1e-4))
                                      + tuple(Case("rk4p", dt) for dt in (5e-4, 2.5e-4, 1e-4)), reference="rk4p"),
    # rk4p above 1e-5 s: m3 only (m2's axial mode sets a stability limit of about 1e-5 s)
    "spatial_slider_crank": SystemCases(("m2", "m3"), tuple(Case("genalpha3", dt) for dt in (4e-5, 2e-5, 1e-5))
                                        + tuple(Case("rk4p", dt) for dt in (2e-4, 1e-4, 1e-5)), reference="rk4p"),
}
DEFAULT_SYSTEMS = ("hub", "slider_crank", "pendulum")  # without --systems: the planar S1-S3
# The ef reference of each system: (elements, integrator, step); see docs/validation/ef-systems.md
# and, for S5, docs/validation/spatial.md (32 elements: 1e-3 to 5e-3 of the peaks from converged).
EF_REFERENCE = {"hub": (16, "genalpha", 5e-4), "slider_crank": (16, "ali3p", 5e-6),
                "pendulum": (16, "genalpha", 1.25e-5), "flap": (32, "genalpha", 1e-3)}
# Columns the ef study (ef_convergence, measured from the elements' curvature) adds from
# equilibrium: S1's root moment is minus the clamp's reaction moment (the beam's momentum
# balance), which converges at the rate of the motion (0.2 % of the peak with 4 elements where
# the root curvature is 3 % off; docs/validation/ef-systems.md). The bench's reference takes
# every N and M from equilibrium (ef_reference).
EF_EQUILIBRIUM = {"hub": {"M_A": ("reaction(clamp, moment)", -1.0)}}
QUICK = {"pendulum": SystemCases(("m3",), (Case("genalpha", 1e-3), Case("genalpha", 5e-4),
                                           Case("newmark", 5e-4, FOX_GOODWIN)))}
# --quick: a coarse ef (fast to build; 4 elements are 2e-1 of M_mid's history from converged)
QUICK_EF_REFERENCE = {"pendulum": (4, "genalpha", 1e-4)}


def run_rows(built, scene, integrator, dt, repeat=1, options=()):
    """A built system on a scene's rows (t_end, row interval) with integrator at step dt."""
    given = {"integrator": integrator, "dt": dt, "t_end": scene.options.t_end,
             "interval": scene.options.out_every * scene.options.dt, "repeat": repeat} | dict(options)
    return run_built(built, validate(given, Where("api")))


def ef_system(system, elements: int, recovery: str = "constitutive"):
    """The system with every flexible body replaced by `elements` ef elements, N and M by
    `recovery`: "constitutive", the elements' strain and curvature (the references of the
    studies and bench-systems, docs/validation/ef-systems.md, and their Richardson
    extrapolation, were measured so), "equilibrium" (select's reference,
    docs/theory/stress-recovery.md), or "auto", a scene's ef beam's own. An output that names
    its own recovery, M(B, x, constitutive), gets the reference's (but with "auto"): a
    candidate's curvature moment is measured against the reference's moment."""
    ef = replace(customize(builtin("ef"), elements=elements), axial_force=recovery, moment=recovery)

    def reference(o: Output) -> Output:  # an output's own recovery gives way to the reference's
        fn, args = parse_output(system, o.quantity)
        named = recovery != "auto" and fn in RECOVERABLE and len(args) == 3
        return replace(o, quantity=f"{fn}({args[0]}, {args[1]})") if named else o
    return replace(system, bodies=tuple(replace(b, model=ef) if b.flexible else b for b in system.bodies),
                   outputs=tuple(reference(o) for o in system.outputs))


def _ef_run(name: str, scene, case, repeat=1):
    """A system scene with `ef` on case = (elements, integrator, step), N and M from the
    elements' strains (as the study was measured), with the equilibrium columns of
    EF_EQUILIBRIUM added as <column>_eq."""
    elements, integrator, dt = case
    system = ef_system(scene.system, elements)
    extra = EF_EQUILIBRIUM.get(name, {})
    system = replace(system, outputs=system.outputs + tuple(
        Output(f"{c}_eq", quantity) for c, (quantity, _) in extra.items()))
    r = run_rows(prepare_system(system), scene, integrator, dt, repeat)
    if not r.ok:
        raise RuntimeError(f"{name} ef {case}: the run stopped: {r.message}")
    if extra:
        r.data = r.data.copy()
        for c, (_, sign) in extra.items():
            r.data[:, r.columns.index(f"{c}_eq")] *= sign
    return r


def ef_reference(name: str, log=print, quick=False):
    """The converged-ef run of a system scene (EF_REFERENCE; QUICK_EF_REFERENCE for --quick),
    N and M from equilibrium: they converge at the rate of the motion, where the elements'
    strain and curvature lag (S5's root moments on 32 elements: 6.1e-3 of the peak from the
    strains, 6.2e-5 from equilibrium; docs/theory/stress-recovery.md)."""
    elements, integrator, dt = (QUICK_EF_REFERENCE if quick else EF_REFERENCE)[name]
    scene = load_scene(SCENES_DIR / f"{name}.toml", model="ef")
    ref = run_rows(prepare_system(ef_system(scene.system, elements, "equilibrium")), scene, integrator, dt)
    if not ref.ok:
        raise RuntimeError(f"{name} ef reference: the run stopped: {ref.message}")
    log(f"{name}: ef reference, {elements} elements, {integrator} dt = {dt:g} s, N and M from equilibrium")
    return ref


def ef_convergence(name: str, cases, reference, log=print) -> list[dict]:
    """The `ef` convergence study of a system scene (docs/validation/ef-systems.md): each case
    (elements, integrator, step) against `reference` (the same), on the scene's rows. Per case:
    the integration CPU (median of 3) and, per output (the scene's columns and the equilibrium
    ones, <column>_eq), max |y - y_ref| / peak |y_ref| and the error of the peak |y|
    (err_<column>, peak_<column>)."""
    scene = load_scene(SCENES_DIR / f"{name}.toml", model="ef")
    columns = list(scene.columns) + [f"{c}_eq" for c in EF_EQUILIBRIUM.get(name, {})]
    ref = _ef_run(name, scene, reference)
    log(f"{name}: reference {reference}, CPU {ref.summary['cpu_median']:.3g} s")
    rows = []
    for case in cases:
        r = _ef_run(name, scene, case, 3)
        row = {"elements": case[0], "integrator": case[1], "dt": case[2],
               "cpu_s": r.summary["cpu_median"]}
        for c in columns:
            peak = float(np.max(np.abs(ref[c]))) or 1.0
            row[f"err_{c}"] = float(np.max(np.abs(r[c] - ref[c]))) / peak
            row[f"peak_{c}"] = abs(float(np.max(np.abs(r[c]))) - peak) / peak
        rows.append(row)
        log(f"  {case}: CPU {row['cpu_s']:.3g} s  " + "  ".join(
            f"{c} {row[f'err_{c}']:.1e} / {row[f'peak_{c}']:.1e}" for c in columns))
    return rows


def column_errors(r, ref, columns, prefix):
    """prefix_<column>: max |y - y_ref| / peak |y_ref| (nan for a failed or short run); prefix_max."""
    out = {}
    for c in columns:
        peak = float(np.max(np.abs(ref[c]))) or 1.0
        out[f"{prefix}_{c}"] = (float(np.max(np.abs(r[c] - ref[c]))) / peak
                                if r.ok and len(r[c]) == len(ref[c]) else math.nan)
    out[f"{prefix}_max"] = max(out[f"{prefix}_{c}"] for c in columns)
    return out


def run_system_bench(out: Path | None = None, systems=None, models=None, quick=False, repeat=None,
                     log=print, versus_ef=True) -> list[dict]:
    table = QUICK if quick else SYSTEMS
    repeat = repeat or (1 if quick else 5)
    rows = []
    for name in systems or [n for n in table if quick or n in DEFAULT_SYSTEMS]:
        spec = table[name]
        ef = ef_reference(name, log, quick) if versus_ef and name in (
            QUICK_EF_REFERENCE if quick else EF_REFERENCE) else None
        for model in models or spec.models:
            scene = load_scene(SCENES_DIR / f"{name}.toml", model=model)
            built = prepare_system(scene.system)
            columns = list(scene.columns)
            ref_dt = min(case.dt for case in spec.cases) / REF_DIVISOR
            ref_integrator = spec.reference or ("rk4" if not scene.system.tree().cut
                                                else scene.options.integrator)
            ref = run_rows(built, scene, ref_integrator, ref_dt)
            if not ref.ok:
                raise RuntimeError(f"{name} {model}: the reference run stopped: {ref.message}")
            log(f"{name}, {model}: reference {ref_integrator} dt = {ref_dt:g} s")
            for case in spec.cases:
                integrator, dt = case.label, case.dt
                r = run_rows(built, scene, case.integrator, dt, repeat, case.options)
                row = {"system": name, "model": model, "integrator": integrator, "dt": dt,
                       "cpu_s": r.summary["cpu_median"], "status": "ok" if r.ok else r.message}
                row |= column_errors(r, ref, columns, "err")
                if ef is not None:
                    row |= column_errors(r, ef, columns, "ef")
                rows.append(row)
                log(f"  {integrator:9s} dt = {dt:<8.4g} {row['cpu_s'] * 1e3:8.3f} ms  max error "
                    f"{row['err_max']:.2e} of the peak"
                    + (f", vs ef {row['ef_max']:.2e}" if ef is not None else "")
                    + f"  {'' if r.ok else r.message}")
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        keys = sorted({k for r in rows for k in r})
        fields = ["system", "model", "integrator", "dt", "cpu_s", "err_max"] + [
            f for f in keys if f.startswith("err_") and f != "err_max"]
        if versus_ef:
            fields += ["ef_max"] + [f for f in keys if f.startswith("ef_") and f != "ef_max"]
        fields += ["status"]
        with open(out / "bench_systems.csv", "w", newline="", encoding="utf-8") as fh:
            w = csv.DictWriter(fh, fieldnames=fields, restval="")
            w.writeheader()
            w.writerows(rows)
        (out / "bench_systems.md").write_text(markdown(rows), encoding="utf-8")
        log(f"wrote {out / 'bench_systems.csv'}, {out / 'bench_systems.md'}")
    return rows


def markdown(rows) -> str:
    lines = ["| system | model | integrator | step | CPU | integration error | error vs ef |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        ef = f"{r['ef_max']:.2e}" if "ef_max" in r else "-"
        lines.append(f"| {r['system']} | {r['model']} | {r['integrator']} | {r['dt']:.4g} s | "
                     f"{r['cpu_s'] * 1e3:.3f} ms | {r['err_max']:.2e} | {ef}"
                     f"{'' if r['status'] == 'ok' else ' (' + r['status'] + ')'} |")
    lines.append("")
    lines.append("errors: max over the outputs of max |y - y_ref| / peak |y_ref|; integration error "
                 "against the same model at a 10x smaller step, error vs ef against EF_REFERENCE")
    return "\n".join(lines) + "\n"
