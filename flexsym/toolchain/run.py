"""Run a built variant's driver and read its results back as numpy arrays."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flexsym.toolchain.build import Built
from flexsym.core.errors import FlexsymError, SimulationError, SpecError
from flexsym.model.options import API, INTEGRATORS, RunOptions, validate

__all__ = ["INTEGRATORS", "RunResult", "run_built", "check_options", "check_output_path"]


def check_options(*, spec=None, **given) -> RunOptions:
    """Refuse bad run options before anything is generated, built or written: the option table
    (flexsym.model.options.validate) with keyword names; returns the validated options."""
    return validate(given, API, spec)


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
    written: str = "none"  # what happened to the output file: complete | truncated | none
    header: tuple = ()  # the CSV's comment lines (what set up the run)
    # why the rows are outside their model's range (physics/validity: a system's bodies' gauges,
    # a one-beam model's |v| or truncation share); empty: inside. Set by whoever knows the model
    # (pipeline.run_system, api.run, api.simulate; `flexsym run` prints it and exits with 4).
    validity: tuple = ()

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


def check_output_path(path, label: str, suffixes: tuple[str, ...] | None = None) -> Path:
    """Refuse, before any work, an output file that could not be written: its directory must
    exist and be writable (it is never created), and the path must not be a directory."""
    path = Path(path)
    if str(path).strip() == "" or path.name in ("", ".", ".."):
        raise SpecError(f"{label} '{path}': not a file name")
    if suffixes is not None and path.suffix.lower() not in suffixes:
        raise SpecError(f"{label} {path}: unsupported file type '{path.suffix}' "
                        f"(use {', '.join(suffixes)})")
    parent = path.parent
    if not parent.is_dir():
        raise SpecError(f"{label} {path}: directory {parent} does not exist (it is not created)")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise SpecError(f"{label} {path}: directory {parent} is not writable")
    if path.is_dir():
        raise SpecError(f"{label} {path}: is a directory")
    if path.exists() and not os.access(path, os.W_OK):
        raise SpecError(f"{label} {path}: the file exists and is read-only")
    return path


def check_output_dir(path, label: str) -> Path:
    """An output folder: created if missing, so its nearest existing ancestor must be a
    writable directory; an existing path must be a directory."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise SpecError(f"{label} {path}: exists and is not a directory")
    probe = path
    while not probe.exists():
        probe = probe.parent
    if not probe.is_dir() or not os.access(probe, os.W_OK | os.X_OK):
        raise SpecError(f"{label} {path}: {probe} is not a writable directory")
    return path


def _driver(cmd: list[str]) -> subprocess.CompletedProcess:
    """Run the driver; it ends with this process (FLEXSYM_PARENT_PID, see driver.c), and an
    exception here (a signal turned into one by the CLI, Ctrl-C) kills it before it returns."""
    env = dict(os.environ, FLEXSYM_PARENT_PID=str(os.getpid()))
    with subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env) as proc:
        try:
            out, err = proc.communicate()
        except BaseException:
            # subprocess.run kills the driver on Ctrl-C but does not wait for it: the driver
            # could still write into its temporary folder while that is being removed.
            proc.kill()
            proc.wait()
            raise
    return subprocess.CompletedProcess(cmd, proc.returncode, out, err)


def _with_header(csv: Path, header) -> None:
    """Comment lines ('# ...') after the CSV's column line: what set up the run (numpy's
    loadtxt and genfromtxt skip them; pandas needs comment='#')."""
    tmp = csv.with_name(csv.name + ".h")
    with open(csv, encoding="utf-8") as src, open(tmp, "w", encoding="utf-8") as dst:
        dst.write(src.readline())
        dst.writelines(f"# {line}\n" for line in header)
        shutil.copyfileobj(src, dst)
    os.replace(tmp, csv)


def drop_columns(csv: Path, names) -> None:
    """Rewrite a result CSV without the named columns (text kept as written; atomic): the
    columns a picture needed stay out of the user's file."""
    names = set(names)
    tmp = csv.with_name(f".{csv.name}.cols.{os.getpid()}")
    with open(csv, encoding="utf-8") as src, open(tmp, "w", encoding="utf-8") as dst:
        header = src.readline().rstrip("\n").split(",")
        keep = [i for i, c in enumerate(header) if c not in names]
        dst.write(",".join(header[i] for i in keep) + "\n")
        for line in src:
            if line.startswith("#"):
                dst.write(line)
            else:
                fields = line.rstrip("\n").split(",")
                dst.write(",".join(fields[i] for i in keep) + "\n")
    os.replace(tmp, csv)


def run_built(built: Built, options: RunOptions | None = None, *, out: Path | None = None,
              raise_on_failure: bool = False, header=(), **given) -> RunResult:
    """Integrate with the built driver. Options are a RunOptions from `options.validate`, or
    keywords checked here against the same table (t_end, dt, integrator, params, tol, step,
    out_every, repeat, newton, energy, ...; see flexsym.model.options.OPTIONS).
    dt is the step of the fixed-step integrators (rk4, genalpha, newmark, radau5); for dopri5
    (steps adapted to tol) and for radau5 given a step, it sets the output grid.
    out: the CSV is replaced only by a completed run or, when the run stopped after at least
    one step, by the rows computed until then (result.written says which); a run that stops
    before its first step leaves it untouched. header: lines written as comments ('# ...')
    after the CSV's column line (result.header)."""
    o = options if options is not None else validate(given, API)
    if options is not None and given:
        raise TypeError(f"run_built: give either options or keywords, not both ({', '.join(given)})")
    if out is not None:
        out = check_output_path(out, "output file")
    cmd = [str(built.executable)] + o.driver_args()
    where = out.parent if out is not None else None
    with tempfile.TemporaryDirectory(prefix=".flexsym-run-", dir=where) as tmp:
        csv = Path(tmp) / "out.csv"
        proc = _driver(cmd + ["--out", str(csv)])
        if proc.returncode == 2:  # the runtime's own last-line check refused an option
            raise SpecError(proc.stderr.strip().removeprefix("flexsym runtime: ") or "invalid run options")
        if proc.returncode not in (0, 3):
            why = (f"killed by signal {-proc.returncode}" if proc.returncode < 0
                   else f"exit {proc.returncode}")
            raise FlexsymError(f"{built.executable.name} failed ({why}): {proc.stderr.strip()}")
        summary = json.loads(proc.stdout.strip().splitlines()[-1])
        with open(csv, encoding="utf-8") as fh:
            columns = fh.readline().strip().split(",")
        data = np.loadtxt(csv, delimiter=",", skiprows=1, ndmin=2)
        written = "none"
        if out is not None and (summary["status"] == "ok" or summary["steps"] > 0):
            if header:
                _with_header(csv, header)
            os.replace(csv, out)  # same directory: atomic
            written = "complete" if summary["status"] == "ok" else "truncated"
    result = RunResult(built.name, summary["status"], summary["message"], summary, columns, data,
                       out if written != "none" else None,
                       {"t_end": o.t_end, "dt": o.dt, "integrator": o.integrator, "params": o.params,
                        "tol": o.tol, "newton": o.newton, "step": o.step}, written, tuple(header))
    if raise_on_failure and not result.ok:
        raise SimulationError(f"{built.name}: {result.message}", result)
    return result
