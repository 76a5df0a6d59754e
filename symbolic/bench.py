"""CPU time against integration error, per variant and integrator (the spin-up, 20 s).

    python -m flexsym.bench [--variants m3,m1,m2,prestress,ef] [--repeat 21] [--quick]

The error is max |v_tip - v_tip_ref| over the output rows, v_tip_ref from a tiny step
(RK4 at 1e-4 s for the modal variants; generalized-alpha at 5e-5 s for ef, whose
discretisation error is then 1/400 of the one at 1e-3 s). CPU is the driver's median of
--repeat runs of the integration alone (rows included, CSV writing excluded).
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass

import numpy as np

from .pipeline import prepare
from .run import run_built
from .spec import builtin

SPIN = {"ws": 6.0, "ts": 15.0}
REF_GRID = 0.001  # reference rows; every case's rows fall on it (steps: multiples of 1 ms)


@dataclass(frozen=True)
class Case:
    integrator: str
    dt: float                 # step (fixed-step) or output interval (dopri5)
    tol: float | None = None  # dopri5
    newton: str | None = None


def _cases(rk4, dopri5, alpha, full=()):
    return ([Case("rk4", dt) for dt in rk4] + [Case("dopri5", 0.01, tol) for tol in dopri5]
            + [Case("genalpha", dt) for dt in alpha] + [Case("genalpha", dt, None, "full") for dt in full])


CASES = {
    "m3": _cases((0.038, 0.03, 0.02, 0.01), (1e-4, 1e-6, 1e-8), (0.02, 0.015, 0.01, 0.005), (0.01,)),
    "prestress": _cases((0.038, 0.02, 0.01), (1e-6,), (0.015, 0.01)),
    "m1": _cases((0.003, 0.002), (1e-5, 1e-7), (0.02, 0.01, 0.008, 0.006, 0.004, 0.002), (0.008,)),
    "m2": _cases((0.001,), (1e-6,), (0.02, 0.01, 0.008, 0.006, 0.004), (0.008,)),
    "ef": _cases((), (), (0.005, 0.004, 0.002, 0.001, 0.0005), (0.001,)),
}
QUICK = {"m3": CASES["m3"][:1] + CASES["m3"][8:9], "m1": CASES["m1"][6:7], "ef": CASES["ef"][3:4]}


def reference(built, name: str):
    ref_dt, integ = (5e-5, "genalpha") if name == "ef" else (1e-4, "rk4")
    return run_built(built, t_end=20.0, dt=ref_dt, integrator=integ, params=SPIN,
                     out_every=int(round(REF_GRID / ref_dt)), raise_on_failure=True)


def error(r, ref) -> float:
    idx = np.searchsorted(ref.t, r.t - 1e-9)
    if np.any(idx >= len(ref.t)) or not np.allclose(ref.t[idx], r.t, atol=1e-9, rtol=0):
        raise ValueError("rows not on the reference grid")
    return float(np.max(np.abs(r["v_tip"] - ref["v_tip"][idx])))


def run_case(built, c: Case, ref, repeat: int) -> dict:
    out_every = max(1, int(round(0.01 / c.dt)))
    r = run_built(built, t_end=20.0, dt=c.dt, integrator=c.integrator, params=SPIN, tol=c.tol,
                  newton=c.newton, out_every=out_every, repeat=repeat)
    s = r.summary
    return {"status": r.status if r.ok else r.message, "cpu_ms": s["cpu_median"] * 1e3,
            "error": error(r, ref) if r.ok else float("nan"), "steps": s["accepted_steps"],
            "rejected": s["rejected_steps"], "f": s["force_evaluations"],
            "jac": s["jacobian_evaluations"], "rows": s["rows"]}


def label(c: Case) -> str:
    if c.integrator == "dopri5":
        return f"dopri5 tol={c.tol:g}"
    return f"{c.integrator}{' (full Newton)' if c.newton == 'full' else ''} dt={c.dt * 1e3:g} ms"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m flexsym.bench", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--variants", default="m3,prestress,m1,m2,ef")
    ap.add_argument("--repeat", type=int, default=21, help="runs per case (ef: at most 5)")
    ap.add_argument("--quick", action="store_true", help="a few cases only")
    args = ap.parse_args(argv)
    print("| variant | integrator | CPU [ms] | error [m] | steps (rejected) | f evals | Jacobians | rows |")
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    for name in args.variants.split(","):
        built = prepare(builtin(name))
        ref = reference(built, name)
        repeat = min(args.repeat, 5) if name == "ef" else args.repeat
        for c in (QUICK if args.quick else CASES).get(name, []):
            m = run_case(built, c, ref, repeat)
            err = f"{m['error']:.2g}" if m["status"] == "ok" else m["status"]
            print(f"| {name} | {label(c)} | {m['cpu_ms']:.3g} | {err} | {m['steps']} ({m['rejected']}) "
                  f"| {m['f']} | {m['jac']} | {m['rows']} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
