"""`flexsym exact-study`: the exact-kinematics model against the converged `ef`.

For each case (the 20 s spin-up at omega_s = 6, 10, 20 rad/s with T_s = 15 s, and the abrupt
spin-up T_s = 1 s at omega_s = 6) and each model (the exact model with 1..K modes of two
families, the second-order variants #3 and prestress with 3 and 5 bending modes):
  err_v     max |v_tip - v_tip(ef)| over [0, t_end] (rows every 10 ms)
  peak_v    peak |v_tip| relative to ef's
  err_M_A   peak |M_A| relative to ef's;  err_N_A likewise, against ef's clamp reaction
            N_A_clamp (at large deflection ef's element resultant at the root swings with the
            cable element's axial strain: 9.0 kN against 7.5 kN on the abrupt spin-up)
  share     the exact model's truncation indicator (validity.py): the peak share of the last
            bending mode in the curvature
  quad_err  the exact model's quadrature error at the states of the run (every 20th row):
            largest relative change of M and f with a 4x finer rule
Reference: `ef` with 32 elements at dt = 5e-4 s (generalized-alpha). Models run with radau5 at
a 10 ms step (integration error far below the model errors measured here).
Writes exact_study.csv, exact_study.md and exact_modes.png to --out.
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from flexsym.core.errors import FlexsymError
from flexsym.toolchain.pipeline import prepare
from flexsym.toolchain.run import run_built
from flexsym.model.variant import builtin, customize
from flexsym.physics.validity import truncation_share

REF_ELEMENTS, REF_DT = 32, 5e-4
ROWS = 0.01
STEP = 0.01


@dataclass(frozen=True)
class StudyCase:
    name: str
    ws: float
    ts: float
    t_end: float = 20.0


CASES = (StudyCase("ws6", 6.0, 15.0), StudyCase("ws10", 10.0, 15.0), StudyCase("ws20", 20.0, 15.0),
         StudyCase("abrupt", 6.0, 1.0))
QUICK_CASES = (StudyCase("ws6_short", 6.0, 15.0, 8.0),)


def models(max_modes: int = 6, quick: bool = False) -> list[tuple[str, str, int, object]]:
    """(family label, name, coordinates, spec) of every model in the study."""
    exact = builtin("exact")
    out = []
    ks = (2, 3) if quick else range(1, max_modes + 1)
    for k in ks:
        cf = ",".join(f"cf{i}" for i in range(1, k + 1))
        out.append(("exact cf", f"exact_cf{k}", k, customize(exact, bending=cf, name=f"exact_cf{k}")))
    if not quick:
        five = ",".join(f"cf{i}" for i in range(1, 6))
        out.append(("exact cf, extensible (ff1)", "exact_cf5_ff1", 6,
                    customize(exact, bending=five, axial="ff1", name="exact_cf5_ff1")))
        for k in range(1, max_modes + 1):
            cp = ",".join(["static"] + [f"cp{i}" for i in range(1, k)])
            out.append(("exact static+cp", f"exact_cp{k}", k,
                        customize(exact, bending=cp, name=f"exact_cp{k}")))
        five = "static,cp1,cp2,cp3,cp4"
        for base in ("m3", "prestress"):
            b = builtin(base)
            label = "#3 foreshortening" if base == "m3" else "prestress"
            axial_force = "equilibrium" if base == "m3" else None
            out.append((label, b.name, 3, customize(b, axial_force=axial_force, name=f"{b.name}_eq")
                        if axial_force else b))
            out.append((label, f"{b.name}_5", 5, customize(b, bending=five, axial_force=axial_force,
                                                           name=f"{b.name}_5")))
    return out


def reference(case: StudyCase):
    spec = replace(builtin("ef"), name=f"ef_n{REF_ELEMENTS}", elements=REF_ELEMENTS, aliases=())
    return run_built(prepare(spec, log=lambda m: None), t_end=case.t_end, dt=REF_DT,
                     params={"ws": case.ws, "ts": case.ts}, out_every=round(ROWS / REF_DT))


def _peak_rel(r, ref, col, ref_col=None) -> float:
    if col not in r.columns:
        return math.nan
    return float(np.max(np.abs(r[col])) / np.max(np.abs(ref[ref_col or col])) - 1)


def compare(r, ref) -> dict:
    n = min(len(r.t), len(ref.t))
    if not r.ok:
        return {"err_v": math.nan, "peak_v": math.nan, "err_M_A": math.nan, "err_N_A": math.nan,
                "status": r.message}
    return {"err_v": float(np.max(np.abs(r.minus(ref)[:n]))), "peak_v": _peak_rel(r, ref, "v_tip"),
            "err_M_A": _peak_rel(r, ref, "M_A"), "err_N_A": _peak_rel(r, ref, "N_A", "N_A_clamp"),
            "status": "ok"}


def quadrature_error_of_run(spec, r, case: StudyCase) -> float:
    import sympy as sp

    from flexsym.codegen.derive import derive
    from flexsym.model.parameters import BEAM_PARAMS
    from flexsym.physics.exact import quadrature_error
    from flexsym.model.maneuver import maneuver_of, t as t_sym

    der = derive(spec)
    man = maneuver_of(spec.maneuver)
    vals = {p.symbol: {"ws": case.ws, "ts": case.ts}[p.name] for p in man.params}
    rate = sp.lambdify(t_sym, man.rate.xreplace(vals), "numpy")
    acc = sp.lambdify(t_sym, man.acceleration.xreplace(vals), "numpy")
    Q = np.column_stack([r[c] for c in spec.coordinates])
    Qd = np.gradient(Q, r.t, axis=0)
    rows = range(0, len(r.t), 20)
    return quadrature_error(der, Q[rows], Qd[rows], [[float(rate(r.t[i])), float(acc(r.t[i]))] for i in rows],
                            np.array([p.default for p in BEAM_PARAMS]))


def run_study(out: Path, quick: bool = False, max_modes: int = 6, log=print) -> list[dict]:
    out.mkdir(parents=True, exist_ok=True)
    cases = QUICK_CASES if quick else CASES
    rows = []
    refs = {}
    for case in cases:
        log(f"reference: ef, {REF_ELEMENTS} elements, dt = {REF_DT:g} s, {case.name} ...")
        refs[case.name] = reference(case)
        if not refs[case.name].ok:
            raise FlexsymError(f"the reference failed on {case.name}: {refs[case.name].message}")
    for family, name, ncoord, spec in models(max_modes, quick):
        built = prepare(spec, log=lambda m: None)
        for case in cases:
            r = run_built(built, t_end=case.t_end, dt=ROWS, step=STEP, integrator="radau5",
                          params={"ws": case.ws, "ts": case.ts}, out_every=1)
            row = {"case": case.name, "family": family, "model": name, "coordinates": ncoord,
                   "cpu_s": r.summary["cpu_median"]} | compare(r, refs[case.name])
            exact = spec.strain == "exact" and len(spec.bending) > 1 and r.ok
            row["share"] = float(np.nanmax(truncation_share(spec, r))) if exact else math.nan
            row["quad_err"] = quadrature_error_of_run(spec, r, case) if exact else math.nan
            rows.append(row)
            log(f"  {case.name:7s} {name:14s} {ncoord} coords  max|dv| {row['err_v']:.2e} m  "
                f"peak v {row['peak_v']:+.2%}  M_A {row['err_M_A']:+.2%}  N_A {row['err_N_A']:+.2%}"
                f"  share {row['share']:.3f}  quad {row['quad_err']:.1e}"
                f"  {'' if row['status'] == 'ok' else row['status']}")
    with open(out / "exact_study.csv", "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    (out / "exact_study.md").write_text(markdown(rows, refs), encoding="utf-8")
    plot(rows, out / "exact_modes.png")
    log(f"wrote {out / 'exact_study.csv'}, {out / 'exact_study.md'}, {out / 'exact_modes.png'}")
    return rows


def _pct(x) -> str:
    return "-" if isinstance(x, float) and math.isnan(x) else f"{x:+.2%}"


def markdown(rows, refs) -> str:
    lines = []
    for case, ref in refs.items():
        lines += ["", f"### {case}: ef peak abs(v_tip) {np.max(np.abs(ref['v_tip'])):.4f} m, "
                      f"peak abs(M_A) {np.max(np.abs(ref['M_A'])):.2f} N m, "
                      f"peak abs(N_A_clamp) {np.max(np.abs(ref['N_A_clamp'])):.1f} N", "",
                  "| model | coordinates | max abs(Δv_tip) [m] | peak abs(v_tip) | peak abs(M_A) "
                  "| peak abs(N_A) | last mode's share | quadrature check | status |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for r in rows:
            if r["case"] == case:
                err = "-" if math.isnan(r["err_v"]) else f"{r['err_v']:.2e}"
                lines.append(f"| {r['model']} | {r['coordinates']} | {err} | {_pct(r['peak_v'])} | "
                             f"{_pct(r['err_M_A'])} | {_pct(r['err_N_A'])} | "
                             f"{'-' if math.isnan(r['share']) else format(r['share'], '.3f')} | "
                             f"{'-' if math.isnan(r['quad_err']) else format(r['quad_err'], '.1e')} | "
                             f"{r['status'][:60]} |")
    return "\n".join(lines).lstrip() + "\n"


def plot(rows, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = list(dict.fromkeys(r["case"] for r in rows))
    families = list(dict.fromkeys(r["family"] for r in rows))
    colour = {f: plt.get_cmap("tab10")(i) for i, f in enumerate(families)}
    fig, axes = plt.subplots(1, len(cases), figsize=(4.5 * len(cases), 4.2), squeeze=False)
    for ax, case in zip(axes[0], cases):
        for family in families:
            pts = [(int(r["coordinates"]), float(r["err_v"])) for r in rows
                   if r["case"] == case and r["family"] == family and not math.isnan(float(r["err_v"]))]
            if pts:
                x, y = zip(*sorted(pts))
                ax.semilogy(x, y, marker="o", color=colour[family],
                            ls="-" if family.startswith("exact") else "--", label=family)
        ax.set_title(case)
        ax.set_xlabel("elastic coordinates")
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].set_ylabel("max |v_tip - v_tip(ef)| [m]")
    handles = [plt.Line2D([], [], color=colour[f], marker="o", ls="-" if f.startswith("exact") else "--",
                          label=f) for f in families]
    fig.legend(handles=handles, loc="lower center", ncol=len(families), fontsize=9)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)
