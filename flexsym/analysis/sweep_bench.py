"""Speed of in-process runs and sweeps (docs/howto/inprocess-and-sweeps.md).

    python -m flexsym.analysis.sweep_bench [--runs 10000] [--batch 2000] [--subprocess-runs 50]

On #3 (foreshortening), the 20 s spin-up, radau5 with steps of 0.25 s (the bench's cheapest
case at integration error <= 1e-4 m), omega_s spread over [2, 8] rad/s:
  1. the integration error of that case (max |v_tip - v_tip(radau5, 0.01 s steps)| over rows
     every 10 ms, at omega_s = 2, 6, 8);
  2. runs per second (wall clock) of one in-process batch in one process, with rows every
     10 ms (what the sweep summaries see by default) and with rows at the 80 steps only,
     against the one-process-per-run path (`run_built`, the driver behind `flexsym run`);
  3. a sweep of --runs runs (table written) on the local process pool (all cores) and on a
     Dask LocalCluster on loopback with one single-threaded worker process per core: a first
     sweep (workers import flexsym and load the model), then --repeat sweeps on each executor,
     alternated (the best of each, and the ratios of each Dask sweep to the pool's next one).
Prints a Markdown table. Rates are wall-clock and depend on the machine and its load; the CPU
times per run (this process and its children) depend less on the load.
"""
from __future__ import annotations

import argparse
import logging
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from flexsym.sim.inprocess import load
from flexsym.model.options import API, validate
from flexsym.toolchain.pipeline import prepare
from flexsym.toolchain.run import run_built
from flexsym.model.variant import builtin
from flexsym.sim.inprocess import settings_of
from flexsym.sim.sweep import make_plan, prepare_plan, run_sweep

CASE = dict(integrator="radau5", dt=0.01, step=0.25, t_end=20.0)


def _cpu() -> float:
    """CPU seconds of this process and its finished children (the drivers of run_built)."""
    import resource

    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def _rate(n: int, seconds: float) -> str:
    return f"{n / seconds:,.0f} runs/s ({seconds * 1e3 / n:.3f} ms/run)"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m flexsym.analysis.sweep_bench", description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=10_000, help="runs of the pool and Dask sweeps")
    ap.add_argument("--batch", type=int, default=2000, help="runs of the in-process batch")
    ap.add_argument("--subprocess-runs", type=int, default=50, help="runs of the one-process-per-run path")
    ap.add_argument("--repeat", type=int, default=5, help="timed sweeps per executor (best reported)")
    ap.add_argument("--no-dask", action="store_true")
    args = ap.parse_args(argv)
    spec = builtin("m3")
    model = load(spec)
    lines = ["| measure | result |", "|---|---|"]

    ws = [2.0, 6.0, 8.0]
    got = model.batch({"ws": ws}, rows=True, **CASE)
    ref = model.batch({"ws": ws}, rows=True, **(CASE | {"step": 0.01}))
    err = max(np.max(np.abs(got.result(i).minus(ref.result(i)))) for i in range(len(ws)))
    lines.append(f"| integration error, radau5 step 0.25 s (omega_s = 2, 6, 8) | {err:.2e} m |")

    wsv = np.linspace(2.0, 8.0, args.batch)
    model.batch({"ws": wsv[:50]}, **CASE)  # warm-up
    for label, opts in (("rows every 10 ms", CASE), ("rows at the 80 steps", CASE | {"dt": 0.25})):
        t0, c0 = time.perf_counter(), _cpu()
        b = model.batch({"ws": wsv}, **opts)
        wall, cpu = time.perf_counter() - t0, _cpu() - c0
        assert all(s == "ok" for s in b.status)
        lines.append(f"| in-process batch, 1 process, {label} | {_rate(args.batch, wall)}; CPU "
                     f"{cpu / args.batch * 1e3:.3f} ms/run, of which integration "
                     f"{np.median(b.stats['cpu_s']) * 1e3:.3f} (median) |")

    built = prepare(spec)
    t0, c0 = time.perf_counter(), _cpu()
    for w in np.linspace(2.0, 8.0, args.subprocess_runs):
        run_built(built, params={"ws": float(w)}, **CASE)
    wall, cpu = time.perf_counter() - t0, _cpu() - c0
    lines.append(f"| one process per run (`run_built`, CSV), 1 at a time | {_rate(args.subprocess_runs, wall)}; "
                 f"CPU {cpu / args.subprocess_runs * 1e3:.3f} ms/run (driver process and Python) |")

    o = validate(CASE, API, spec)
    plan = prepare_plan(make_plan(spec, settings_of(o, keep_interval=False), o.params,
                                  [f"ws=2:8:{args.runs // 2}", "L=9.5,10"]))
    cores = os.cpu_count() or 1
    with tempfile.TemporaryDirectory() as tmp:
        def timed(name, **kw) -> float:
            t0 = time.perf_counter()
            run_sweep(plan, Path(tmp) / f"{name}.csv", **kw)
            return time.perf_counter() - t0

        pool = [timed("pool")]
        if args.no_dask:
            pool += [timed("pool") for _ in range(args.repeat - 1)]
        else:
            from distributed import LocalCluster

            dask = {}
            with LocalCluster(n_workers=cores, threads_per_worker=1, processes=True, host="127.0.0.1",
                              protocol="tcp", dashboard_address=":0", silence_logs=logging.ERROR) as cluster:
                first = timed("dask", dask=cluster.scheduler_address)  # workers import flexsym, load the model
                for _ in range(args.repeat):  # alternated: the machine's load changes under both alike
                    dask.setdefault("processes", []).append(timed("dask", dask=cluster.scheduler_address))
                    pool.append(timed("pool"))
        lines.append(f"| sweep, local process pool ({cores} processes), {len(plan)} runs, best of "
                     f"{len(pool)} | {min(pool):.2f} s, {_rate(len(plan), min(pool))} |")
        if not args.no_dask:
            lines.append(f"| sweep, Dask LocalCluster ({cores} single-threaded worker processes, loopback), "
                         f"first sweep | {first:.2f} s, {first / min(pool):.2f} x the pool |")
            best = min(dask["processes"])
            paired = sorted(d / p for d, p in zip(dask["processes"], pool[1:]))
            lines.append(f"| sweep, Dask LocalCluster, best of {len(dask['processes'])} | {best:.2f} s, "
                         f"{best / min(pool):.2f} x the pool's best; median of the paired ratios "
                         f"{paired[len(paired) // 2]:.2f} (range {paired[0]:.2f}-{paired[-1]:.2f}) |")
            strip = lambda name: [r.rsplit(",", 1)[0] for r in (Path(tmp) / name).read_text().splitlines()]
            lines.append(f"| Dask table = pool table (cpu_s aside) | {strip('pool.csv') == strip('dask.csv')} |")
    logging.getLogger("distributed").setLevel(logging.CRITICAL)  # shutdown chatter
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
