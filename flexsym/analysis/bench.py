"""`flexsym bench`: CPU time against error for every variant x integrator x step (or tol).

For each case, on the paper's 20 s spin-up (omega_s = 6 rad/s, T_s = 15 s):
  cpu_s            median CPU time of the integration inside the C runtime over --repeat runs
                   after a warm-up (min and max reported as the spread)
  err_integration  max |v_tip - v_tip(same variant, tiny step)| over the run: the solver's error
  err_reference    max |v_tip - v_tip(ef, 32 elements, dt = 5e-4 s)|: solver plus model error
  err_N_A, err_M_A error of the peak |N_A|, |M_A| against the reference, where available
and per variant the time to derive + generate its code and to compile it, from scratch.
Rows (where the errors are measured) every 10 ms, or at every step when steps are longer and
the method has no dense output (rk4, generalized-alpha); radau5 and dopri5 interpolate.
Writes bench.csv, bench.md and work_precision.png to --out.
"""
from __future__ import annotations

import csv
import math
import tempfile
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from flexsym.toolchain.build import build
from flexsym.codegen.folder import write_folder
from flexsym.codegen.generate import generate_files
from flexsym.toolchain.pipeline import prepare
from flexsym.core.progress import Progress
from flexsym.toolchain.run import run_built
from flexsym.model.variant import builtin

SPIN = {"ws": 6.0, "ts": 15.0}
T_END = 20.0
REF_GRID = 0.001  # rows of the references; every case's rows fall on it (steps: multiples of 1 ms)
REF_ELEMENTS, REF_DT = 32, 5e-4
ROWS = 0.01  # s between rows, where the method allows


@dataclass(frozen=True)
class Case:
    integrator: str
    dt: float  # the step; dopri5: the output interval
    tol: float | None = None  # dopri5
    newton: str | None = None  # "full": the unmodified Newton reference

    @property
    def rows_every(self) -> float:
        """Rows every ROWS s where the method can (radau5 and dopri5 from their dense output),
        else at every step: every case pays for about the same output."""
        if self.integrator in ("radau5", "dopri5"):
            return ROWS
        return self.dt * max(1, round(ROWS / self.dt))


def _cases(rk4=(), dopri5=(), alpha=(), full=(), radau=(), radau_full=()):
    return ([Case("rk4", dt) for dt in rk4] + [Case("dopri5", ROWS, tol) for tol in dopri5]
            + [Case("genalpha", dt) for dt in alpha] + [Case("genalpha", dt, None, "full") for dt in full]
            + [Case("radau5", dt) for dt in radau] + [Case("radau5", dt, None, "full") for dt in radau_full])


# Fixed steps are multiples of the reference grid (their rows fall on it); radau5's rows come
# from its collocation polynomial every 10 ms, whatever its step.
CASES = {
    "m3": _cases((0.038, 0.03, 0.02, 0.01), (1e-4, 1e-6, 1e-8), (0.02, 0.015, 0.01, 0.005), (0.01,),
                 (0.3, 0.25, 0.2, 0.1, 0.05), (0.25,)),
    "prestress": _cases((0.038, 0.02, 0.01), (1e-6,), (0.015, 0.01, 0.005), radau=(0.3, 0.25, 0.2, 0.1)),
    "m1": _cases((0.003, 0.002), (1e-5, 1e-7), (0.02, 0.01, 0.008, 0.006, 0.004, 0.002), (0.008,),
                 (0.25, 0.22, 0.2, 0.1, 0.05), (0.2,)),
    "m2": _cases((0.001,), (1e-6,), (0.02, 0.01, 0.008, 0.006, 0.004, 0.002), (0.008,),
                 (0.25, 0.22, 0.2, 0.1, 0.05), (0.2,)),
    "exact": _cases((0.012, 0.01), (1e-6,), (0.02, 0.01, 0.005), radau=(0.5, 0.4, 0.25, 0.1)),
    "ef": _cases(alpha=(0.005, 0.004, 0.002, 0.001, 0.0005), full=(0.001,),
                 radau=(0.2, 0.1, 0.05, 0.02), radau_full=(0.1,)),
}
QUICK = {"m3": _cases(rk4=(0.038,), alpha=(0.01,), radau=(0.25,)), "m1": _cases(alpha=(0.008,)),
         "ef": _cases(alpha=(0.004,))}


def label(c: Case) -> str:
    if c.integrator == "dopri5":
        return f"dopri5 tol={c.tol:g}"
    return f"{c.integrator}{' (full Newton)' if c.newton == 'full' else ''} dt={c.dt * 1e3:g} ms"


def integration_reference(built, spec):
    """The same variant with a tiny step: RK4 at 1e-4 s, or generalized-alpha at 5e-5 s for ef."""
    dt, integ = (5e-5, "genalpha") if spec.kind == "fe" else (1e-4, "rk4")
    return run_built(built, t_end=T_END, dt=dt, integrator=integ, params=SPIN,
                     out_every=round(REF_GRID / dt), raise_on_failure=True)


def model_reference():
    spec = replace(builtin("ef"), name=f"ef_n{REF_ELEMENTS}", elements=REF_ELEMENTS, aliases=())
    return run_built(prepare(spec, log=lambda m: None), t_end=T_END, dt=REF_DT, params=SPIN,
                     out_every=round(REF_GRID / REF_DT), raise_on_failure=True)


def _peak_error(r, ref, col):
    if col not in r.columns:
        return math.nan
    return float(np.max(np.abs(r[col])) - np.max(np.abs(ref[col])))


def run_case(built, c: Case, iref, mref, repeat: int) -> dict:
    if c.integrator == "radau5":
        grid = dict(step=c.dt, dt=ROWS, out_every=1)
    else:
        grid = dict(dt=c.dt, out_every=round(c.rows_every / c.dt))
    r = run_built(built, t_end=T_END, integrator=c.integrator, params=SPIN, tol=c.tol,
                  newton=c.newton, repeat=repeat, **grid)
    s = r.summary
    ok = r.ok
    return {
        "integrator": c.integrator + ("_full_newton" if c.newton == "full" else ""),
        "dt": c.dt, "tol": c.tol if c.tol is not None else "", "rows_every": c.rows_every,
        "cpu_s": s["cpu_median"], "cpu_min_s": s["cpu_min"], "cpu_max_s": s["cpu_max"],
        "err_integration": float(np.max(np.abs(r.minus(iref)))) if ok else math.nan,
        "err_reference": float(np.max(np.abs(r.minus(mref)))) if ok else math.nan,
        "err_N_A": _peak_error(r, mref, "N_A") if ok else math.nan,
        "err_M_A": _peak_error(r, mref, "M_A") if ok else math.nan,
        "steps": s["accepted_steps"], "rejected": s["rejected_steps"],
        "force_evaluations": s["force_evaluations"], "jacobians": s["jacobian_evaluations"],
        "status": "ok" if ok else r.message,
    }


def build_times(spec) -> tuple[float, float]:
    """Seconds to derive and generate the code, and to compile it, from an empty cache."""
    with tempfile.TemporaryDirectory(prefix="flexsym-bench-") as tmp:
        t0 = time.perf_counter()
        folder = Path(tmp) / spec.name
        write_folder(generate_files(spec), folder)
        t1 = time.perf_counter()
        build(folder, root=Path(tmp) / "build")
        return t1 - t0, time.perf_counter() - t1


def run_bench(out: Path, variants=None, quick=False, repeat=None, log=print) -> list[dict]:
    out.mkdir(parents=True, exist_ok=True)
    table = QUICK if quick else CASES
    variants = variants or list(table)
    repeat = repeat or (3 if quick else 21)
    log(f"model reference: ef, {REF_ELEMENTS} elements, dt = {REF_DT:g} s ...")
    mref = model_reference()
    rows, times = [], {}
    bar = Progress(sum(len(table.get(name, [])) + 1 for name in variants), "bench")
    log = bar.wrap(log)
    for name in variants:
        bar.update()
        spec = builtin(name)
        times[spec.name] = build_times(spec)
        log(f"{spec.name}: generation {times[spec.name][0]:.2f} s, compilation {times[spec.name][1]:.2f} s")
        built = prepare(spec, log=lambda m: None)
        iref = integration_reference(built, spec)
        reps = min(repeat, 5) if spec.kind == "fe" else repeat
        for c in table.get(name, []):
            row = {"variant": spec.name} | run_case(built, c, iref, mref, reps)
            rows.append(row)
            bar.update()
            log(f"  {label(c):30s} {row['cpu_s'] * 1e3:9.3f} ms  integration {row['err_integration']:.2e} m"
                f"  reference {row['err_reference']:.2e} m  {'' if row['status'] == 'ok' else row['status']}")
    bar.close()
    _write_csv(rows, out / "bench.csv")
    (out / "bench.md").write_text(markdown(rows, times), encoding="utf-8")
    plot(rows, out / "work_precision.png")
    log(f"wrote {out / 'bench.csv'}, {out / 'bench.md'}, {out / 'work_precision.png'}")
    return rows


FIELDS = ["variant", "integrator", "dt", "tol", "rows_every", "cpu_s", "cpu_min_s", "cpu_max_s", "err_integration",
          "err_reference", "err_N_A", "err_M_A", "steps", "rejected", "force_evaluations", "jacobians",
          "status"]


def _write_csv(rows, path: Path) -> None:
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=FIELDS)
        w.writeheader()
        w.writerows(rows)


def _num(x, fmt):
    return "-" if isinstance(x, float) and math.isnan(x) else format(x, fmt)


def markdown(rows, times) -> str:
    lines = ["| variant | integrator | step / tol | rows every | CPU median [ms] (min-max) "
             "| integration error [m] | error vs ef [m] | peak N_A error [N] | peak M_A error [N m] |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        step = f"tol {r['tol']:g}" if r["tol"] != "" else f"{r['dt'] * 1e3:g} ms"
        lines.append(f"| {r['variant']} | {r['integrator']} | {step} | {r['rows_every'] * 1e3:g} ms "
                     f"| {r['cpu_s'] * 1e3:.3f} "
                     f"({r['cpu_min_s'] * 1e3:.3f}-{r['cpu_max_s'] * 1e3:.3f}) | "
                     f"{_num(r['err_integration'], '.1e')} | {_num(r['err_reference'], '.1e')} | "
                     f"{_num(r['err_N_A'], '+.1f')} | {_num(r['err_M_A'], '+.1f')} |")
    lines += ["", "| variant | derive + generate [s] | compile [s] |", "|---|---|---|"]
    lines += [f"| {n} | {g:.2f} | {c:.2f} |" for n, (g, c) in times.items()]
    return "\n".join(lines) + "\n"


MARKERS = {"rk4": ("o", "-"), "dopri5": ("s", ":"), "genalpha": ("^", "-"),
           "genalpha_full_newton": ("x", "--"), "radau5": ("D", "-."), "radau5_full_newton": ("+", "--")}


def plot(rows, path: Path) -> None:
    """Log-log CPU time against error: colour = variant, marker and line = integrator."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    variants = list(dict.fromkeys(r["variant"] for r in rows))
    colour = {v: plt.get_cmap("tab10")(i) for i, v in enumerate(variants)}
    fig, axes = plt.subplots(1, 2, figsize=(12, 5), sharey=True)
    curves: dict[tuple, list] = {}
    for r in rows:
        if r["status"] == "ok":
            curves.setdefault((r["variant"], r["integrator"]), []).append(r)
    for ax, key, title in ((axes[0], "err_integration", "integration error (vs tiny step)"),
                           (axes[1], "err_reference", "total error (vs ef, 32 elements)")):
        for (variant, integ), pts in curves.items():
            pts = sorted(pts, key=lambda p: p["cpu_s"])
            marker, line = MARKERS.get(integ, ("o", "-"))
            ax.loglog([max(p[key], 1e-13) for p in pts], [p["cpu_s"] for p in pts], marker=marker,
                      ls=line, color=colour[variant], ms=5)
        ax.set_xlabel(f"max |v_tip error| [m]: {title}")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("CPU time of the 20 s spin-up [s]")
    handles = [Line2D([], [], color=colour[v], lw=3, label=v) for v in variants]
    handles += [Line2D([], [], color="k", marker=m, ls=ls, label=i) for i, (m, ls) in MARKERS.items()
                if any(k[1] == i for k in curves)]
    axes[1].legend(handles=handles, fontsize=8, loc="lower left")
    fig.suptitle("flexsym work-precision: spin-up beam, omega_s = 6 rad/s, T_s = 15 s, 20 s")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)

