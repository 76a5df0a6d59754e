"""Parameter sweeps: many in-process runs of one scene or variant, a table with one row per run.

    flexsym sweep SCENE|VARIANT --vary ws=2:6:9 --vary L=8,10 --out table.csv
    flexsym sweep m3 --vary ws=2:8 --vary ts=5:15 --samples 200 --seed 1 --sampling lhs ...

--vary NAME=START:STOP:COUNT is a grid (COUNT values, ends included), NAME=a,b,c a list; the
runs are the Cartesian product of all --vary, in the order given (the last varies fastest).
With --samples N every --vary is a range NAME=LO:HI sampled uniformly (random) or by Latin
hypercube, reproducibly from --seed. NAME is a run-time parameter: beam (rho, E, A, I, L),
manoeuvre (ws, ts for the spin-up), an initial value (q0_<coordinate>, qd0_<coordinate>) or
a solver option t_end, dt, step (radau5); mode sets are structural (one model each). A system
scene (SystemTarget): its p and drive parameter names (E or BEAM_E, ws or DRIVER_ws), read
from its built model, and a violation column when it has constraints.

Table (CSV, one row per run, in run order): run, the varied inputs, status (ok | diverged |
failed), valid (ok and |v| <= 0.1 L for modal models), message, then per output quantity
<o>_min, <o>_max, <o>_final, <o>_t_peak (time of the peak |o|) and <o>_at_<T> for --at T,
then t_stop, steps, newton_iterations and cpu_s (CPU time of that run's integration).
Summaries are over the rows of the output grid (the scene's interval, else every 0.01 s).

Executors: local processes (all cores by default), or --dask ADDRESS, an existing
dask.distributed cluster; every worker loads (building if needed) the model once, by its
fingerprint. Finished runs go to TABLE.csv.partial as they arrive, each row with a check value
(Partial); the table is written atomically at the end; --resume continues an interrupted sweep
from the partial file, whose rows are checked against the plan first (claim_partial), and which
a running sweep locks. Workers end with the sweep (_init_local_worker).
"""
from __future__ import annotations

import contextlib
import csv
import errno
import hashlib
import io
import itertools
import json
import math
import os
import time
import re
import threading
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from flexsym.core.errors import FlexsymError, SpecError, ToolchainError
from flexsym.core.progress import Progress
from flexsym.model.options import API, BY_NAME, Option, Where, check_params, validate

SAMPLINGS = ("random", "lhs")
MAX_RUNS = 10_000_000
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


@dataclass(frozen=True)
class Vary:
    name: str
    values: tuple | None = None  # a grid or a list
    low: float | None = None  # a range, for sampling
    high: float | None = None


def _number(text: str, where: str) -> float:
    text = text.strip()
    if not re.fullmatch(_NUMBER, text):
        raise SpecError(f"--vary {where}: '{text}' is not a number")
    value = float(text)
    if not math.isfinite(value):
        raise SpecError(f"--vary {where}: '{text}' is not finite")
    return value


def parse_vary(text: str) -> Vary:
    """NAME=START:STOP:COUNT, NAME=a,b,c, or NAME=LO:HI (with --samples)."""
    if "=" not in text:
        raise SpecError(f"--vary '{text}': expected NAME=START:STOP:COUNT, NAME=a,b,c or NAME=LO:HI")
    name, spec = (s.strip() for s in text.split("=", 1))
    if not _NAME.match(name):
        raise SpecError(f"--vary '{text}': '{name}' is not a parameter name")
    if not spec:
        raise SpecError(f"--vary {name}: no values")
    if ":" in spec:
        parts = spec.split(":")
        if len(parts) == 2:
            lo, hi = (_number(p, name) for p in parts)
            if not lo < hi:
                raise SpecError(f"--vary {name}={spec}: empty range (need LO < HI)")
            return Vary(name, low=lo, high=hi)
        if len(parts) != 3:
            raise SpecError(f"--vary {name}={spec}: expected START:STOP:COUNT")
        start, stop = _number(parts[0], name), _number(parts[1], name)
        if not re.fullmatch(r"\s*[-+]?\d+\s*", parts[2]):
            raise SpecError(f"--vary {name}={spec}: COUNT '{parts[2].strip()}' is not a whole number")
        count = int(parts[2])
        if count < 1:
            raise SpecError(f"--vary {name}={spec}: COUNT must be >= 1 (got {count})")
        if count > 1 and start == stop:
            raise SpecError(f"--vary {name}={spec}: empty range (START = STOP with COUNT > 1)")
        if count == 1 and start != stop:
            raise SpecError(f"--vary {name}={spec}: COUNT 1 with START != STOP (give one value: {name}={parts[0]})")
        return Vary(name, values=tuple(np.linspace(start, stop, count).tolist()))
    items = spec.split(",")
    if any(not s.strip() for s in items):
        raise SpecError(f"--vary {name}={spec}: empty value in the list")
    values = tuple(_number(s, name) for s in items)
    if len(set(values)) != len(values):
        raise SpecError(f"--vary {name}={spec}: duplicate values")
    return Vary(name, values=values)


@dataclass
class SweepPlan:
    """Everything a sweep runs: the model, the options shared by all runs, and one row of
    inputs per run."""
    spec: object
    settings: dict  # run options shared by every run (validated; batch() keywords), see inprocess.settings_of
    base_params: dict  # run-time parameters every run starts from
    names: tuple  # varied inputs
    table: np.ndarray  # runs x len(names)
    outputs: list  # summarized quantities: the model's outputs
    at: tuple = ()
    sampling: str = "grid"
    seed: int | None = None
    fingerprint: str = ""  # of the model (filled in by prepare_plan)
    extra: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.table)

    def key(self) -> str:
        """Identifies the sweep (the partial file must belong to the same one to resume)."""
        h = hashlib.sha256(json.dumps([self.fingerprint, self.settings, self.base_params, self.names,
                                       self.at, self.outputs], sort_keys=True, default=str).encode())
        h.update(np.ascontiguousarray(self.table).tobytes())
        return h.hexdigest()[:24]

    def header(self) -> list[str]:
        cols = ["run", *self.names, "status", "valid", "message"]
        for o in self.outputs:
            cols += [f"{o}_min", f"{o}_max", f"{o}_final", f"{o}_t_peak"]
            cols += [f"{o}_at_{_label(t)}" for t in self.at]
        return cols + ["t_stop", "steps", "newton_iterations", "cpu_s"]


def _label(t: float) -> str:
    return f"{t:g}".replace("-", "m")


@dataclass(frozen=True)
class SystemTarget:
    """A system scene's model as a sweep target: what a sweep uses of a one-beam VariantSpec
    (name, outputs, coordinates), with the run-time names read from the built model."""
    system: object  # system.System
    name: str
    outputs: tuple  # the scene's columns, then violation when the system has constraints
    coordinates: tuple
    params: tuple  # p (beam parameters, e.g. E or BEAM_E) and drive parameters (e.g. ws)
    fingerprint: str
    maneuver = None


def system_target(system) -> SystemTarget:
    """Build (or find) and load the system's model here; its manifest names what can vary."""
    from flexsym.codegen.sysgen import fingerprint

    key = fingerprint(system)
    with _models_lock:
        if key not in _models:
            from flexsym.sim.inprocess import load_system

            _models[key] = load_system(system)
        m = _models[key]
    outputs = tuple(c for c in m.columns if c not in m.coordinates)
    return SystemTarget(system, system.name, outputs, tuple(m.coordinates),
                        tuple(m.params) + tuple(m.maneuver_params), key)


def fingerprint_of(spec) -> str:
    """The model's fingerprint (a variant's without generating or building it)."""
    from flexsym.codegen.generate import fingerprint

    return spec.fingerprint if isinstance(spec, SystemTarget) else fingerprint(spec)


def sweepable(spec) -> list[str]:
    from flexsym.model.parameters import BEAM_PARAMS
    from flexsym.model.maneuver import maneuver_of

    if isinstance(spec, SystemTarget):
        return list(spec.params) + initial_state_names(spec)
    man = [] if spec.maneuver.startswith("expression:") else [p.name for p in maneuver_of(spec.maneuver).params]
    return [p.name for p in BEAM_PARAMS] + man + initial_state_names(spec)


def sweepable_options(settings: dict) -> list[str]:
    """Solver options a sweep may vary per run (the others are shared by a batch)."""
    return ["t_end", "dt"] + (["step"] if settings["integrator"] == "radau5" else [])


def _vary_error(name: str, value: float, exc: SpecError) -> SpecError:
    return SpecError(f"--vary {name}={value:g}: {exc}")


def _check_values(spec, v: Vary, initial, options: list[str], where: Where) -> None:
    """Parameters against the option table's rules (options are checked per run in make_plan)."""
    if v.name in initial or v.name in options:
        return  # initial values: any finite number (parse_vary)
    for value in (v.values if v.values is not None else (v.low, v.high)):
        try:
            if isinstance(spec, SystemTarget):  # BEAM_E, crank_ws: the rule of E (> 0), ws
                base = v.name.rsplit("_", 1)[-1]
                rule = BY_NAME.get(base) or Option(v.name, float, None, "", low=0.0, low_open=True)
                replace(rule, name=v.name).convert(value, API)
                continue
            check_params({v.name: value}, where, spec.maneuver)
        except SpecError as exc:
            raise _vary_error(v.name, value, exc) from None


def _check_options(spec, settings: dict, names: list[str], table: np.ndarray, where: Where) -> None:
    """Each distinct combination of varied options of the runs, with the shared ones, by
    options.validate (as batch() checks them again in the workers)."""
    cols = [j for j, n in enumerate(names) if n in sweepable_options(settings)]
    for combo in dict.fromkeys(map(tuple, table[:, cols].tolist())) if cols else ():
        given = dict(zip((names[j] for j in cols), combo))
        try:
            validate(settings | given, where, spec)
        except SpecError as exc:
            name, value = next(iter(given.items())) if len(given) == 1 else (None, None)
            raise (_vary_error(name, value, exc) if name else
                   SpecError(f"--vary {', '.join(f'{k}={x:g}' for k, x in given.items())}: {exc}")) from None


def initial_state_names(spec) -> list[str]:
    """Initial values of the coordinates (the runtime starts the others at rest)."""
    return [f"{k}_{c}" for k in ("q0", "qd0") for c in spec.coordinates]


def make_plan(spec, settings: dict, base_params: dict, varies: list[str], *, samples: int | None = None,
              seed: int | None = None, sampling: str | None = None, at=(), where: Where = API) -> SweepPlan:
    """Check the sweep specification (one clear line and nothing run when wrong) and list the runs."""
    if not varies:
        raise SpecError("give at least one --vary NAME=...")
    vs = [parse_vary(v) for v in varies]
    known, initial = sweepable(spec) + sweepable_options(settings), initial_state_names(spec)
    seen = set()
    for v in vs:
        if v.name not in known:
            coords = list(spec.coordinates)
            shown = ", ".join(coords[:4]) + (", ..." if len(coords) > 4 else "")
            raise SpecError(f"--vary {v.name}: unknown parameter (run-time parameters of {spec.name}: "
                            f"{', '.join(n for n in known if n not in initial)}, and initial values "
                            f"q0_<coordinate>, qd0_<coordinate> of {shown}; mode sets are not swept)")
        if v.name in seen:
            raise SpecError(f"--vary {v.name}: given twice")
        seen.add(v.name)
        _check_values(spec, v, initial, sweepable_options(settings), where)
    if seed is not None and samples is None:
        raise SpecError("--seed is for --samples N (random or Latin-hypercube sampling)")
    if sampling is not None and samples is None:
        raise SpecError("--sampling is for --samples N")
    if samples is not None:
        if not (isinstance(samples, int) and samples >= 1):
            raise SpecError(f"--samples must be a whole number >= 1 (got {samples})")
        if samples > MAX_RUNS:
            raise SpecError(f"--samples {samples}: more than {MAX_RUNS} runs")
        sampling = sampling or "lhs"
        if sampling not in SAMPLINGS:
            raise SpecError(f"--sampling '{sampling}': known: {', '.join(SAMPLINGS)}")
        grid = [v.name for v in vs if v.low is None]
        if grid:
            raise SpecError(f"--vary {grid[0]}: with --samples give a range NAME=LO:HI")
        seed = 0 if seed is None else seed
        u = _unit_samples(samples, len(vs), seed, sampling)
        table = np.array([v.low for v in vs]) + u * np.array([v.high - v.low for v in vs])
    else:
        ranges = [v.name for v in vs if v.values is None]
        if ranges:
            raise SpecError(f"--vary {ranges[0]}: a range LO:HI needs --samples N (or give START:STOP:COUNT)")
        n = math.prod(len(v.values) for v in vs)
        if n > MAX_RUNS:
            raise SpecError(f"the grid has {n} runs, more than {MAX_RUNS}")
        table = np.array(list(itertools.product(*(v.values for v in vs))), dtype=float).reshape(n, len(vs))
        sampling = "grid"
    names = [v.name for v in vs]
    _check_options(spec, settings, names, table, where)
    at = tuple(float(t) for t in at)
    t_end = float(np.max(table[:, names.index("t_end")])) if "t_end" in names else settings["t_end"]
    for t in at:
        if not (math.isfinite(t) and 0 <= t <= t_end):
            raise SpecError(f"--at {t:g}: not a time in [0, t_end = {t_end:g}]")
    if len(set(at)) != len(at):
        raise SpecError("--at: duplicate times")
    return SweepPlan(spec, dict(settings), dict(base_params), tuple(v.name for v in vs), table,
                     list(spec.outputs), at, sampling, seed)


def _unit_samples(n: int, k: int, seed: int, sampling: str) -> np.ndarray:
    rng = np.random.default_rng(seed)
    if sampling == "random":
        return rng.random((n, k))
    # Latin hypercube: one sample in each of n equal strata per dimension, strata shuffled
    return np.column_stack([(rng.permutation(n) + rng.random(n)) / n for _ in range(k)])


# ------------------------------------------------------------------------------- workers

_models: dict = {}
_models_lock = threading.Lock()


def _model(spec):
    """The worker's loaded model for spec (built here if needed), once per process."""
    key = fingerprint_of(spec)
    with _models_lock:
        if key not in _models:
            from flexsym.sim.inprocess import load, load_system

            _restore_malloc_thresholds()
            _models[key] = load_system(spec.system) if isinstance(spec, SystemTarget) else load(spec)
        return _models[key]


def _restore_malloc_thresholds() -> None:
    """Dask's nanny starts workers with MALLOC_TRIM_THRESHOLD_=65536, which turns off glibc's
    adaptive mmap threshold: every run's row buffer (150 kB for 2001 rows of #3) then becomes
    an mmap and its pages fault in again, 25 % more CPU per run (measured: 0.145 against
    0.115 ms). Keeping buffers below 8 MB on the heap restores the usual cost."""
    if "MALLOC_TRIM_THRESHOLD_" not in os.environ:
        return
    import ctypes

    mallopt = getattr(ctypes.CDLL(None), "mallopt", None)  # glibc only
    if mallopt is not None:
        M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
        mallopt(M_MMAP_THRESHOLD, 8 << 20)
        mallopt(M_TRIM_THRESHOLD, 16 << 20)


def run_chunk(spec, settings: dict, base_params: dict, names: tuple, start: int, table: np.ndarray,
              at: tuple, outputs: list) -> list[tuple[int, str]]:
    """Runs start, start + 1, ... (rows of table): (run, its table line) each. Lines are made
    here, in the workers, so that the collecting process only appends them."""
    model = _model(spec)
    runs = {k: np.full(len(table), v) for k, v in base_params.items()}
    runs |= {k: table[:, j] for j, k in enumerate(names)}
    options = {k: v for k, v in settings.items() if k not in runs}
    b = model.batch(runs, at=at, **options)
    notes = [n.replace("\r", " ").replace("\n", " ") for n in b.validity_notes]  # a row is one line
    cols = [np.arange(start, start + len(b)), *table.T, b.status, b.valid, notes]
    for o in outputs:
        cols += [b.summary(o, f) for f in ("min", "max", "final", "t_peak")]
        cols += [b.summary(o, f"at:{t!r}") for t in at]
    cols += [b.stats["t_stop"], b.stats["steps"].astype(int), b.stats["newton_iterations"].astype(int),
             b.stats["cpu_s"]]
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    for row in zip(*(np.asarray(c).tolist() if isinstance(c, np.ndarray) else c for c in cols)):
        writer.writerow([_cell(x) for x in row])
    return list(zip(range(start, start + len(b)), buf.getvalue().splitlines(keepends=True)))


def _init_local_worker(spec, parent: int, inherited=()) -> None:
    """A local worker: it ends with the sweep (SIGKILL of the parent included: the pool's pipes
    would keep it waiting, or running its chunks, as an orphan), dies on SIGTERM and SIGHUP (the
    CLI's handlers, inherited by fork, would turn them into an exception its task loop catches),
    ignores Ctrl-C (the parent handles it and keeps the finished runs), and closes the
    descriptors it inherited from the parent (the partial file and its lock)."""
    import signal

    _die_with_parent(parent)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    for sig in (signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, signal.SIG_DFL)
    for fd in inherited:
        try:
            os.close(fd)
        except OSError:
            pass
    _model(spec)


def _die_with_parent(parent: int) -> None:
    """SIGKILL when the parent ends (Linux: PR_SET_PDEATHSIG, as the driver does, see driver.c;
    elsewhere a thread that watches the parent's pid); at once when it already has."""
    import signal

    try:
        import ctypes

        PR_SET_PDEATHSIG = 1
        if ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) != 0:
            raise OSError
    except (OSError, AttributeError):
        def watch():
            while os.getppid() == parent:
                time.sleep(0.5)
            os._exit(1)

        threading.Thread(target=watch, daemon=True).start()
    if os.getppid() != parent:  # the parent ended before the watch began
        os._exit(1)


def _local_results(plan, chunks, workers, inherited=()):
    import concurrent.futures as cf
    import multiprocessing as mp

    ctx = mp.get_context("fork") if "fork" in mp.get_all_start_methods() else None
    pool = cf.ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_init_local_worker,
                                  initargs=(plan.spec, os.getpid(), tuple(inherited)))
    finished = False
    try:
        futures = [pool.submit(run_chunk, plan.spec, plan.settings, plan.base_params, plan.names, s,
                               plan.table[s:e], plan.at, plan.outputs) for s, e in chunks]
        for fut in cf.as_completed(futures):
            yield fut.result()
        finished = True
    finally:
        # Wait for the pool's own thread, else it may still be closing its pipe when the
        # interpreter exits ("Exception ignored ... Bad file descriptor"). Interrupted: kill the
        # workers first. Left to finish their chunks (they ignore Ctrl-C), they kept the exit
        # waiting, and a second SIGINT then (GNU timeout sends two: to the command and to its
        # group) cut the interpreter's wait for the pool's thread short: multiprocessing's exit
        # closed the task queue before that thread sent the workers their stop, and waited for
        # them forever. Their unfinished runs are dropped; --resume runs them.
        with _sigint_ignored(not finished):
            if not finished:
                for proc in list((getattr(pool, "_processes", None) or {}).values()):
                    proc.kill()
            pool.shutdown(wait=True, cancel_futures=not finished)


@contextlib.contextmanager
def _sigint_ignored(ignore: bool):
    """Ctrl-C ignored inside (in the main thread, where signals are handled): a repeated one
    cannot cut the clean-up of an interrupted sweep short."""
    import signal

    if not ignore or threading.current_thread() is not threading.main_thread():
        yield
        return
    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before)


def dask_client(dask):
    """(client, own): a distributed.Client connected to the scheduler at address `dask`, or
    `dask` itself when it is a Client; connected before anything is written."""
    if hasattr(dask, "submit"):
        return dask, False
    try:
        from distributed import Client
    except ImportError:
        raise ToolchainError("--dask needs dask.distributed: pip install 'flexsym[sweep]'") from None
    try:
        return Client(dask, timeout="10s"), True
    except (OSError, TimeoutError, ValueError) as exc:
        raise FlexsymError(f"--dask {dask}: cannot connect to the scheduler: {exc}") from None


def _dask_results(plan, chunks, client, own: bool):
    from distributed import as_completed

    try:
        futures = [client.submit(run_chunk, plan.spec, plan.settings, plan.base_params, plan.names, s,
                                 plan.table[s:e], plan.at, plan.outputs, pure=False) for s, e in chunks]
        try:
            for fut in as_completed(futures):
                yield fut.result()
        finally:
            for fut in futures:
                fut.cancel()
    finally:
        if own:
            client.close()


# ------------------------------------------------------------------------------- the table

def _cell(x) -> str:
    if isinstance(x, float):
        return repr(x)  # round-trips; nan for runs that did not reach a summary
    return str(x)


def partial_path(out: Path) -> Path:
    return out.with_name(out.name + ".partial")


PARTIAL_FORMAT = 2  # rows end in a check cell


def _check_value(key: str, row: str) -> str:
    """A row's check cell: a digest of the sweep's key and the row as the table has it (no
    newline), so that a row edited, cut or copied from another sweep is seen."""
    return hashlib.blake2b(f"{key}\n{row}".encode(), digest_size=8).hexdigest()


class Partial:
    """TABLE.csv.partial of a sweep, checked and then locked by this process (flock) until the
    sweep ends: a second sweep on the same table is refused while this one runs.

    Line 1 identifies the sweep ("# flexsym sweep 2 KEY": model fingerprint, options, runs),
    line 2 holds the table's columns and "check", then one line per finished run: its table
    row and a check value (_check_value). done: run -> its table line (newline included)."""

    def __init__(self, path: Path, fd: int, key: str, done: dict, head: str = ""):
        """fd: the locked file at its end, owned from here; head: written first (a partial file
        without rows: new, or its head cut off)."""
        from flexsym.core.files import _discard, _fdopen, writing

        self.path, self.key, self.done = path, key, done
        try:
            self.fh = _fdopen(fd, "a")
        except BaseException:
            os.close(fd)
            raise
        self.finished = False
        if head:
            try:
                with writing(path):
                    self.fh.write(head)
                    self.fh.flush()
            except BaseException:
                _discard(self.fh)
                path.unlink(missing_ok=True)  # no row in it: nothing lost
                raise

    def fileno(self) -> int:
        return self.fh.fileno()

    def append(self, rows) -> None:
        """rows: [(run, table line)], written with their check values and flushed."""
        from flexsym.core.files import writing

        text = "".join(f"{line[:-1]},{_check_value(self.key, line[:-1])}\n" for _, line in rows)
        with writing(self.path):
            self.fh.write(text)
            self.fh.flush()
        self.done.update(rows)

    def finish(self) -> None:
        """The table is written: the partial file goes."""
        self.path.unlink(missing_ok=True)
        self.finished = True
        self.close()

    def close(self) -> None:
        """Release the lock; a partial file without a finished run is removed (nothing to keep)."""
        if self.fh.closed:
            return
        if not self.done and not self.finished:
            self.path.unlink(missing_ok=True)
        from flexsym.core.files import _discard

        _discard(self.fh)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def claim_partial(plan: SweepPlan, out: Path, resume: bool) -> Partial:
    """Check the partial file of out against the plan and lock it, before any work (one line,
    SpecError, naming the file and the line): in use by a running sweep; not a regular file;
    another sweep's; finished runs without resume; a row that is not one this sweep wrote for
    one of its runs (wrong cell count, not a number, a run out of range, inputs other than the
    plan's, a check value that does not match, a run twice with different values). A last line
    without its newline was cut off by an interruption: it is dropped (said on stderr) and its
    run is run again. Without a partial file: one is started. plan.fingerprint must be set."""
    import fcntl
    import stat
    import sys

    from flexsym.core.files import output_error

    part = partial_path(Path(out))
    key = plan.key()
    for _ in range(100):  # again when a finishing sweep removed the file between open and lock
        try:
            fd = os.open(part, os.O_RDWR | os.O_CREAT | os.O_NONBLOCK | os.O_CLOEXEC, 0o666)
        except IsADirectoryError:
            raise SpecError(f"{part}: not a regular file (a sweep's partial file; a directory is in "
                            "its place): move it away") from None
        except OSError as exc:
            if exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EIO, errno.EROFS):
                raise output_error(exc, part) from None
            raise SpecError(f"{part}: cannot open: {exc.strerror}") from None
        try:
            st = os.fstat(fd)
            if not stat.S_ISREG(st.st_mode):
                raise SpecError(f"{part}: not a regular file (a sweep's partial file; a device, FIFO "
                                "or socket is in its place): move it away")
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                raise SpecError(f"{part}: in use by a sweep still running on {out}: wait for it to "
                                "end, or stop it (Ctrl-C keeps its finished runs) and run this "
                                "command with --resume") from None
            try:
                now = os.stat(part)
            except FileNotFoundError:
                now = None
            if now is None or (now.st_dev, now.st_ino) != (st.st_dev, st.st_ino):
                os.close(fd)
                continue
            data = _read_fd(fd)
            done, keep, cut = _check_rows(data, part, plan, key)
            if done and not resume:
                raise SpecError(f"{part} holds {len(done)} finished runs of this sweep, which was "
                                "interrupted: pass --resume to continue it, or delete the file to "
                                "start over")
            if cut is not None:
                print(f"flexsym: {part}: line {cut} was cut off by an interruption (no newline at "
                      "its end): it is dropped and its run is run again", file=sys.stderr)
            try:
                os.ftruncate(fd, keep)
                os.lseek(fd, 0, os.SEEK_END)
            except OSError as exc:
                raise output_error(exc, part) from None
        except BaseException:
            os.close(fd)
            raise
        return Partial(part, fd, key, done, _partial_head(plan, key) if keep == 0 else "")  # owns fd
    raise SpecError(f"{part}: replaced again and again while being opened: is another sweep "
                    "starting on the same table?")


def _read_fd(fd: int) -> bytes:
    chunks = []
    while chunk := os.read(fd, 1 << 20):
        chunks.append(chunk)
    return b"".join(chunks)


def _partial_head(plan: SweepPlan, key: str) -> str:
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow([*plan.header(), "check"])
    return f"# flexsym sweep {PARTIAL_FORMAT} {key}\n" + buf.getvalue()


def _check_rows(data: bytes, part: Path, plan: SweepPlan, key: str) -> tuple[dict, int, int | None]:
    """(done, bytes to keep, number of a cut last line or None) of a partial file's bytes; a
    SpecError naming the line for anything but rows this sweep wrote."""
    head = _partial_head(plan, key).encode()
    lines = data.split(b"\n")
    tail = lines.pop()  # after the last newline: b"", or a line cut off
    keep = len(data) - len(tail)
    cut = len(lines) + 1 if tail else None
    if len(lines) < 2:  # no row yet; a head cut off by an interruption is written again
        if head.startswith(data):
            return {}, 0, None
    if not data.startswith(head[:head.index(b"\n") + 1]):
        first = lines[0] if lines else tail
        what = ("belongs to a different sweep (its model, options or runs differ) or another flexsym "
                "version" if first.startswith(b"# flexsym sweep ") else "is not a sweep's partial file")
        raise SpecError(f"{part}: line 1: {what}: it cannot be resumed; delete it (or choose another "
                        "--out) to start over")
    if len(lines) < 2 or lines[1] + b"\n" != head[head.index(b"\n") + 1:]:
        raise SpecError(f"{part}: line 2: not this sweep's columns (edited?): delete the file to "
                        "start over")
    ncells = len(plan.header()) + 1
    done, where = {}, {}
    for k, raw in enumerate(lines[2:], start=3):
        def bad(what: str):
            return SpecError(f"{part}: line {k}: {what}: delete that line to run its run again, or the "
                             "file to start over")
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError:
            raise bad("not UTF-8 text") from None
        try:
            cells = next(csv.reader([text], strict=True), [])
        except csv.Error as exc:
            raise bad(f"not a row of the table ({exc})") from None
        if len(cells) != ncells:
            raise bad(f"{len(cells)} cells, where a row of this sweep has {ncells} (its columns and "
                      "a check value)")
        if not re.fullmatch(r"\d{1,12}", cells[0]):
            raise bad(f"run '{cells[0][:40]}' is not a run number")
        run = int(cells[0])
        if run >= len(plan):
            raise bad(f"run {run} is not a run of this sweep (runs 0 to {len(plan) - 1})")
        for j, name in enumerate(plan.names):
            cell, want = cells[1 + j], float(plan.table[run, j])
            try:
                got = float(cell)
            except ValueError:
                raise bad(f"{name} = '{cell[:40]}' is not a number") from None
            if got != want:
                raise bad(f"run {run} with {name} = {cell[:40]}, but run {run} of this sweep has "
                          f"{name} = {want!r}")
        row = text[:text.rindex(",")]
        if cells[-1] != _check_value(key, row):
            raise bad(f"the row of run {run} is not the one the sweep wrote (its check value does not "
                      "match: edited, or copied from another sweep)")
        if run in done:
            if done[run] != row + "\n":
                raise bad(f"run {run} again, with other values than on line {where[run]}")
            continue
        done[run], where[run] = row + "\n", k
    return done, keep, cut


def run_sweep(plan: SweepPlan, out: Path, *, resume: bool = False, workers: int | None = None,
              dask=None, progress: bool | None = None, on_chunk=None, chunk: int | None = None,
              partial: Partial | None = None) -> Path:
    """Run every run of the plan not already in the partial file and write the table to out
    (atomically). partial: from claim_partial (checked before the model was built), else
    claimed here. on_chunk(done, total) is called after each finished chunk (e.g. to stop it in
    tests). The disk full (OutputError): the finished runs stay in the partial file."""
    from flexsym.core.errors import OutputError
    from flexsym.core.files import atomic_write

    out = Path(out)
    if partial is None:
        plan.fingerprint = plan.fingerprint or fingerprint_of(plan.spec)
        partial = claim_partial(plan, out, resume)
    with partial:
        hold = os.environ.get("FLEXSYM_TEST_HOLD_SWEEP_AFTER")
        if hold and on_chunk is None:  # tests: a sweep that cannot finish before their signal
            on_chunk = _hold_after(int(hold))
        done = partial.done
        todo = [i for i in range(len(plan)) if i not in done]
        client = own = None
        if dask is not None and todo:
            client, own = dask_client(dask)
            workers = sum(client.nthreads().values()) or 1
        workers = workers or os.cpu_count() or 1
        size = chunk or max(1, min(256, math.ceil(len(todo) / (8 * workers))))
        chunks = []  # consecutive runs still to do, at most `size` per chunk
        for _, grp in itertools.groupby(enumerate(todo), key=lambda p: p[1] - p[0]):
            idx = [i for _, i in grp]
            chunks += [(idx[k], idx[min(k + size, len(idx)) - 1] + 1) for k in range(0, len(idx), size)]
        try:
            if chunks:
                results = (_dask_results(plan, chunks, client, own) if client is not None else
                           _local_results(plan, chunks, workers, (partial.fileno(),)))
                _collect(plan, partial, results, progress, on_chunk)
            with atomic_write(out) as fh:
                csv.writer(fh, lineterminator="\n").writerow(plan.header())
                fh.writelines(done[i] for i in range(len(plan)))
        except OutputError as exc:
            if done:
                raise OutputError(f"{exc}; the runs finished so far are kept in {partial.path}: "
                                  "make room, then run the same command with --resume") from None
            raise
        partial.finish()
    return out


def _hold_after(rows: int):
    """on_chunk that, once `rows` runs are in the partial file, waits for a signal: a test
    interrupts the sweep at a known point whatever the machine's speed."""
    def hold(done: int, total: int) -> None:
        while done >= rows:
            time.sleep(3600)
    return hold


def _collect(plan: SweepPlan, partial: Partial, results, progress, on_chunk) -> None:
    """Append finished rows to the partial file (and to its done) as the chunks arrive."""
    with Progress(len(plan), f"sweep {plan.spec.name}", progress) as bar:
        bar.update(len(partial.done))
        try:
            for rows in results:
                partial.append(rows)
                bar.update(len(rows))
                if on_chunk:
                    on_chunk(len(partial.done), len(plan))
        finally:
            results.close()


def read_table(path) -> dict[str, np.ndarray]:
    """A sweep table as column -> array (numbers as floats, the rest as strings)."""
    with open(path, encoding="utf-8", newline="") as fh:
        rows = list(csv.reader(fh))
    header, body = rows[0], rows[1:]
    table = {}
    for j, name in enumerate(header):
        col = [r[j] for r in body]
        try:
            table[name] = np.array([float(x) for x in col])
        except ValueError:
            table[name] = np.array(col, dtype=object)
    return table


def prepare_plan(plan: SweepPlan) -> SweepPlan:
    """Build (or find) and load the model; note its fingerprint."""
    _model(plan.spec)
    plan.fingerprint = fingerprint_of(plan.spec)
    return plan


# ------------------------------------------------------------------------------- plots

def plot(table: dict, x: list[str], y: str, out: Path, title: str = "", others=()) -> Path:
    """y against one varied input (a curve per combination of the other varied inputs, when
    there are at most 10), or against two (coloured points); runs that failed or left the
    range of validity are marked with a red x."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if y not in table:
        raise SpecError(f"--plot-y {y}: no such column (have: {', '.join(table)})")
    for name in x:
        if name not in table:
            raise SpecError(f"--plot-x {name}: not a column of the table")
    valid = table["valid"] == "True"
    fig, ax = plt.subplots(figsize=(7, 4.5))
    if len(x) == 1:
        keys = list(zip(*(table[o] for o in others))) if others else [()] * len(valid)
        groups = sorted(set(keys))
        for g, key in enumerate(groups):
            sel = np.array([k == key for k in keys])
            order = np.argsort(table[x[0]][sel], kind="stable")
            xs, ys, ok = table[x[0]][sel][order], table[y][sel][order], valid[sel][order]
            label = ", ".join(f"{o} = {v:g}" for o, v in zip(others, key)) or None
            ax.plot(xs, ys, "-" if len(groups) <= 10 else "", color=f"C{g % 10}", lw=1, label=label
                    if len(groups) <= 10 else None)
            ax.plot(xs[ok], ys[ok], "o", color=f"C{g % 10}", ms=4)
            ax.plot(xs[~ok], ys[~ok], "x", color="C3", ms=7)
        if not valid.all():
            ax.plot([], [], "x", color="C3", label="failed or not valid")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8)
        ax.set_xlabel(x[0])
        ax.set_ylabel(y)
    else:
        sc = ax.scatter(table[x[0]], table[x[1]], c=table[y], cmap="viridis", s=30)
        if not valid.all():
            ax.scatter(table[x[0]][~valid], table[x[1]][~valid], marker="x", color="C3", s=30,
                       label="not valid / failed")
            ax.legend()
        fig.colorbar(sc, ax=ax, label=y)
        ax.set_xlabel(x[0])
        ax.set_ylabel(x[1])
    ax.set_title(title)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    from flexsym.core.files import atomic_write

    try:
        with atomic_write(out, "wb") as fh:  # complete or absent; an earlier plot kept until then
            fig.savefig(fh, dpi=120, format=out.suffix[1:].lower() or "png")
    finally:
        plt.close(fig)
    return out
