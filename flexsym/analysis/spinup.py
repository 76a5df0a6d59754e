"""The main job: the paper's spin-up beam for variants #0-#3, a summary table and a plot."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexsym.toolchain.pipeline import prepare
from flexsym.toolchain.run import RunResult, run_built
from flexsym.model.variant import VariantSpec


@dataclass
class Summary:
    spec: VariantSpec
    result: RunResult

    def value_at(self, t: float) -> float | None:
        r = self.result
        if not r.ok or r.t[-1] < t - 1e-9:  # values of a run that stopped mean nothing
            return None
        return float(np.interp(t, r.t, r["v_tip"]))

    @property
    def minimum(self) -> tuple[float, float]:
        r = self.result
        i = int(np.argmin(r["v_tip"]))
        return float(r["v_tip"][i]), float(r.t[i])


def run_variants(specs: list[VariantSpec], *, ws: float, ts: float, t_end: float, dt: float,
                 integrator: str, out_dir: Path | None, log=print) -> list[Summary]:
    out = []
    for spec in specs:
        built = prepare(spec)
        csv = out_dir / f"{spec.name}.csv" if out_dir else None
        res = run_built(built, t_end=t_end, dt=dt, integrator=integrator,
                        params={"ws": ws, "ts": ts}, out=csv)
        out.append(Summary(spec, res))
        log(f"  {spec.name}: {res.status} ({res.summary['cpu_median'] * 1e3:.1f} ms CPU)")
    return out


def _fmt(x: float | None, spec: str = "+.4f") -> str:
    return "-" if x is None else format(x, spec)


def table(summaries: list[Summary], ts: float, t_end: float) -> str:
    head = (f"| variant | alias | min v_tip [m] | at t [s] | v_tip({ts:g}) [m] | v_tip({t_end:g}) [m] "
            f"| integration CPU [ms] | status |")
    rows = [head, "|" + "---|" * 8]
    from flexsym.physics.validity import assess

    for s in summaries:
        vmin, tmin = s.minimum if s.result.ok else (None, None)  # a diverging minimum means nothing
        status = assess(s.spec, s.result, s.result.options.get("params")).status
        rows.append(f"| {s.spec.name} | {'/'.join(s.spec.aliases) or '-'} | {_fmt(vmin)} | {_fmt(tmin, '.2f')} "
                    f"| {_fmt(s.value_at(ts))} | {_fmt(s.value_at(t_end))} "
                    f"| {s.result.summary['cpu_median'] * 1e3:.2f} | {status} |")
    return "\n".join(rows)


def plot(summaries: list[Summary], path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4.5))
    finite = [s for s in summaries if s.result.ok]
    for s in summaries:
        label = f"{s.spec.name} ({'/'.join(s.spec.aliases)})" if s.spec.aliases else s.spec.name
        if not s.result.ok:
            label += f", diverged at {s.result.summary['t_stop']:.2f} s"
        ax.plot(s.result.t, s.result["v_tip"], label=label, lw=1.2)
    if finite:  # keep a diverged curve from flattening the others
        lo = min(float(np.min(s.result["v_tip"])) for s in finite)
        hi = max(float(np.max(s.result["v_tip"])) for s in finite)
        pad = 0.15 * (hi - lo or 1.0)
        ax.set_ylim(lo - pad, hi + pad)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("v_tip [m] (moving frame)")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    _save_atomically(fig, Path(path))
    plt.close(fig)


def _save_atomically(fig, path: Path) -> None:
    """Into a temporary file next to path, then renamed (core/files.atomic_write): an existing
    plot is replaced by a complete one or not at all. The directory must exist (it is not
    created)."""
    from flexsym.core.files import atomic_write

    with atomic_write(path, "wb") as fh:
        fig.savefig(fh, dpi=120, format=path.suffix.lstrip(".").lower() or "png")


def describe(r: RunResult, outputs, status: str | None = None, units: dict | None = None) -> str:
    """Per output column: extremes with their times and the final value (in `units`, when
    given: column -> SI unit). status: the verdict on the result (validity.assess), else the
    run's own status."""
    units = units or {}
    rows = ["| quantity | unit | min | at t [s] | max | at t [s] | final |",
            "|---|---|---|---|---|---|---|"]
    for c in outputs:
        y = r[c]
        i, j = int(np.argmin(y)), int(np.argmax(y))
        rows.append(f"| {c} | {units.get(c, '')} | {y[i]:.6g} | {r.t[i]:.3f} | {y[j]:.6g} | {r.t[j]:.3f} "
                    f"| {y[-1]:.6g} |")
    status = status if status is not None else ("ok" if r.ok else r.message)
    return "\n".join(rows) + f"\n\nstatus: {status}; integration CPU {r.summary['cpu_median'] * 1e3:.2f} ms"
