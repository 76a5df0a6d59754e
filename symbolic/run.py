"""Run a built variant's driver and read its results back as numpy arrays."""
from __future__ import annotations

import json
import subprocess
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .build import Built
from .errors import FlexsymError, SimulationError, SpecError

INTEGRATORS = ("rk4", "dopri5", "genalpha", "newmark", "radau5")
NEWTON = ("modified", "full")


@dataclass
class RunResult:
    variant: str
    status: str  # 'ok' | 'diverged' | 'failed'
    message: str
    summary: dict
    columns: list[str]
    data: np.ndarray  # rows x columns
    csv: Path | None = None
    options: dict = field(default_factory=dict)

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.data[:, self.columns.index(name)]
        except ValueError:
            raise KeyError(f"no column '{name}' in the results of {self.variant} "
                           f"(columns: {', '.join(self.columns)})") from None

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    @property
    def t(self) -> np.ndarray:
        return self["t"]

    def minus(self, ref: "RunResult", col: str = "v_tip") -> np.ndarray:
        """self[col] - ref[col] at this run's rows, which must all be on ref's time grid."""
        idx = np.searchsorted(ref.t, self.t - 1e-9)
        if np.any(idx >= len(ref.t)) or not np.allclose(ref.t[idx], self.t, atol=1e-9, rtol=0):
            raise ValueError(f"rows of {self.variant} are not on the reference's time grid")
        return self[col] - ref[col][idx]


def default_out_every(dt: float) -> int:
    """Steps between rows when not given: about 100 rows per second of simulated time."""
    return max(1, int(round(0.01 / dt)))


def _positive(name: str, value) -> None:
    if not (isinstance(value, (int, float)) and not isinstance(value, bool) and value > 0
            and np.isfinite(value)):
        raise SpecError(f"{name} must be a positive number (got {value!r})")


def check_options(*, t_end, dt, integrator, params: dict, spec=None, tol=None, newton=None,
                  step=None) -> None:
    """Refuse bad run options before anything is generated, built or written."""
    from .energy import BEAM_PARAMS
    from .maneuver import MANEUVERS, maneuver_of

    if integrator not in INTEGRATORS:
        raise SpecError(f"unknown integrator '{integrator}' (known: {', '.join(INTEGRATORS)})")
    _positive("t_end", t_end)
    _positive("dt", dt)
    if tol is not None and not (isinstance(tol, (int, float)) and not isinstance(tol, bool)
                                and 0 <= tol < 1):
        raise SpecError(f"tol must be a number in [0, 1) (got {tol!r}; 0 = fixed steps dt)")
    if step is not None:
        _positive("step", step)
        if integrator != "radau5":
            raise SpecError(f"step is for radau5 (its step, rows every dt); {integrator} steps at dt")
    if newton is not None and newton not in NEWTON:
        raise SpecError(f"unknown newton '{newton}' (known: {', '.join(NEWTON)})")
    beam = {p.name for p in BEAM_PARAMS}
    man = {p.name for p in maneuver_of(spec.maneuver).params} if spec else \
        {p.name for m in MANEUVERS.values() for p in m.params}
    for name, value in params.items():
        if name not in beam | man:
            raise SpecError(f"unknown parameter '{name}' (beam: {', '.join(sorted(beam))}; "
                            f"manoeuvre: {', '.join(sorted(man))})")
        if name in beam:
            _positive(name, value)
        elif not (isinstance(value, (int, float)) and np.isfinite(value)):
            raise SpecError(f"{name} must be a finite number (got {value!r})")
    if "ts" in params and params["ts"] <= 0:
        raise SpecError(f"ts must be a positive number (got {params['ts']!r})")


def run_built(built: Built, *, t_end: float = 20.0, dt: float = 1e-3, integrator: str = "genalpha",
              params: dict | None = None, out: Path | None = None, out_every: int | None = None,
              repeat: int = 1, rho_inf: float | None = None, newmark: tuple | None = None,
              blowup: float | None = None, newton_tol: float | None = None,
              tol: float | None = None, max_steps: int | None = None, newton: str | None = None,
              energy: bool = False, step: float | None = None,
              raise_on_failure: bool = False) -> RunResult:
    """Integrate with the built driver. dt is the step of the fixed-step integrators (rk4,
    genalpha, newmark, radau5); for dopri5 (steps adapted to tol, default 1e-6; tol=0: fixed
    steps dt), and for radau5 given a step, it sets the output grid (rows from the method's
    dense output).
    Rows are written every out_every * dt (default: about every 0.01 s) and at t_end.
    newton: 'modified' (default, reuses the iteration matrix) or 'full'."""
    check_options(t_end=t_end, dt=dt, integrator=integrator, params=params or {}, tol=tol,
                  newton=newton, step=step)
    if out_every is None:
        out_every = default_out_every(dt)
    cmd = [str(built.executable), "--t-end", repr(float(t_end)), "--dt", repr(float(dt)),
           "--integrator", integrator, "--out-every", str(out_every), "--repeat", str(repeat)]
    for name, value in (params or {}).items():
        cmd += ["--param", f"{name}={float(value)!r}"]
    if rho_inf is not None:
        cmd += ["--rho-inf", repr(float(rho_inf))]
    if newmark is not None:
        cmd += ["--newmark-gamma", repr(float(newmark[0])), "--newmark-beta", repr(float(newmark[1]))]
    if blowup is not None:
        cmd += ["--blowup", repr(float(blowup))]
    if newton_tol is not None:
        cmd += ["--newton-tol", repr(float(newton_tol))]
    if tol is not None:
        cmd += ["--tol", repr(float(tol))]
    if step is not None:
        cmd += ["--step", repr(float(step))]
    if max_steps is not None:
        cmd += ["--max-steps", str(int(max_steps))]
    if newton is not None:
        cmd += ["--newton", newton]
    if energy:
        cmd += ["--energy"]

    with tempfile.TemporaryDirectory(prefix="flexsym-run-") as tmp:
        csv = Path(out) if out is not None else Path(tmp) / "out.csv"
        if out is not None:
            csv.parent.mkdir(parents=True, exist_ok=True)
        proc = subprocess.run(cmd + ["--out", str(csv)], capture_output=True, text=True)
        if proc.returncode == 2:
            raise SpecError(proc.stderr.strip().removeprefix("flexsym runtime: ") or "invalid run options")
        if proc.returncode not in (0, 3):
            raise FlexsymError(f"{built.executable.name} failed (exit {proc.returncode}): "
                               f"{proc.stderr.strip()}")
        summary = json.loads(proc.stdout.strip().splitlines()[-1])
        with open(csv, encoding="utf-8") as fh:
            columns = fh.readline().strip().split(",")
        data = np.loadtxt(csv, delimiter=",", skiprows=1, ndmin=2)
    result = RunResult(built.name, summary["status"], summary["message"], summary, columns, data,
                       Path(out) if out is not None else None,
                       {"t_end": t_end, "dt": dt, "integrator": integrator, "params": params or {},
                        "tol": tol, "newton": newton, "step": step})
    if raise_on_failure and not result.ok:
        raise SimulationError(f"{built.name}: {result.message}", result)
    return result
