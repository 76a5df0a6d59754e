"""Run a built model in this process: many parameter sets per call through the C runtime's
batch entry point (fsr_batch in runtime_c/src/batch.c), results as numpy arrays.

Each run goes through the same fsr_simulate, with the options set as the driver sets them,
so its rows are bit for bit those of `flexsym run` on the same inputs (tests/test_inprocess.py).
Summaries (min, max, their times, time of the peak |y|, final value, values at chosen times)
are computed in C over the rows of the output grid (every out_every * dt), so a sweep need
not move the rows; keep them with rows=True. A run that fails (divergence, Newton failure)
has its own status and message and does not affect the others.

    from flexsym.apps import api
    model = api.inprocess("m3")
    b = model.batch({"ws": [2.0, 4.0, 6.0]}, integrator="radau5", dt=0.01, step=0.25, at=[15.0])
    b.summary("v_tip", "min")      # one value per run
    b.result(0)                    # a RunResult, with rows=True
"""
from __future__ import annotations

import ctypes
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexsym.toolchain.build import Built
from flexsym.core.errors import SpecError
from flexsym.model.limits import is_real
from flexsym.codegen.folder import read_manifest
from flexsym.model.integrators import REGISTRY
from flexsym.model.options import API, BY_NAME, RunOptions, validate
from flexsym.toolchain.run import RunResult
from flexsym.physics.validity import VALIDITY_LIMIT, deflection_weights

# fsr_method codes (the runtime's integrator registry) and the driver's status words
METHOD_CODES = {i.name: i.code for i in REGISTRY}
STATUS_WORDS = {0: "ok", 1: "diverged"}  # any other fsr_status: "failed"
SUMMARY_FIELDS = ("min", "max", "t_min", "t_max", "t_peak", "final")  # FSR_SUM_*, then `at`
STAT_FIELDS = ("t_stop", "steps", "rejected_steps", "newton_iterations", "jacobian_evaluations",
               "force_evaluations", "omega_max", "rows", "ncols", "cpu_s", "bound_peak",
               "bound_t")  # FSR_STAT_*
MESSAGE = 512  # FSR_BATCH_MESSAGE
GAUGE_CHUNK = 256  # runs whose rows a system's gauges hold at once (batch)
PER_RUN_OPTIONS = ("t_end", "dt", "step", "out_every")  # options batch() also takes per run
# batch() options: the option table's (options.py) but the timing, the energy columns and the
# manoeuvre values (parameters of a run, given in `runs`), plus out_every
RUN_OPTIONS = tuple(n for n in BY_NAME if n not in ("repeat", "energy", "ws", "ts")) + ("out_every",)
# option -> fsr_batch input (batch.c), for those whose names differ
INPUT_NAMES = {"newmark_gamma": "nm_gamma", "newmark_beta": "nm_beta"}

_dptr = ctypes.POINTER(ctypes.c_double)


def option_inputs(o: RunOptions) -> dict[str, float]:
    """The runtime inputs (fsr_batch names) of validated options, as the driver gets them from
    RunOptions.driver_args(); options left at None keep the runtime's defaults."""
    out = {"method": METHOD_CODES[o.integrator], "t_end": o.t_end, "dt": o.dt,
           "out_every": o.out_every}
    for name in ("tol", "step", "rho_inf", "blowup", "newton_tol", "max_steps", "newmark_gamma",
                 "newmark_beta", "penalty"):
        if getattr(o, name) is not None:
            out[INPUT_NAMES.get(name, name)] = getattr(o, name)
    if o.newton is not None:
        out["newton_full"] = float(o.newton == "full")
    return {k: float(v) for k, v in out.items()}


@dataclass
class BatchResult:
    """Results of n runs: per-run status, messages, statistics, summaries over each column
    (the outputs, then the coordinates), and the rows when kept."""
    variant: str
    inputs: dict  # name -> array of n values (the run-time inputs, as given)
    options: dict  # the options shared by every run (integrator, dt, ...)
    columns: list  # summarized columns: outputs, then coordinates
    outputs: list  # the output quantities (a prefix of columns)
    at: np.ndarray  # times of the `at` values
    codes: np.ndarray  # fsr_status per run
    messages: list
    stats: dict  # STAT_FIELDS -> array
    values: np.ndarray  # n x len(columns) x (len(SUMMARY_FIELDS) + len(at))
    valid: np.ndarray  # bool: ok and inside the modal model's range of validity
    validity_notes: list  # per run: "" or why not valid
    rows: list | None = None  # per run: rows x (t, outputs, coordinates) arrays
    row_columns: list | None = None

    def __len__(self) -> int:
        return len(self.codes)

    @property
    def status(self) -> list[str]:
        return [STATUS_WORDS.get(int(c), "failed") for c in self.codes]

    def summary(self, column: str, field: str = "max") -> np.ndarray:
        """One value per run: field in SUMMARY_FIELDS, or "at:T" for the value at time T."""
        if column not in self.columns:
            raise KeyError(f"no column '{column}' (columns: {', '.join(self.columns)})")
        if field.startswith("at:"):
            hits = np.flatnonzero(self.at == float(field[3:]))
            if not len(hits):
                raise KeyError(f"no values at t = {field[3:]} (at: {', '.join(map(repr, self.at))})")
            f = len(SUMMARY_FIELDS) + int(hits[0])
        else:
            f = SUMMARY_FIELDS.index(field)
        return self.values[:, self.columns.index(column), f]

    def result(self, i: int) -> RunResult:
        """Run i as a RunResult (needs rows=True); its summary has the driver's keys."""
        if self.rows is None:
            raise ValueError("rows were not kept: call batch(..., rows=True)")
        st = {k: self.stats[k][i] for k in STAT_FIELDS}
        summary = {"status": self.status[i], "message": self.messages[i], "t_stop": st["t_stop"],
                   "steps": int(st["steps"]), "rejected_steps": int(st["rejected_steps"]),
                   "newton_iterations": int(st["newton_iterations"]),
                   "jacobian_evaluations": int(st["jacobian_evaluations"]),
                   "force_evaluations": int(st["force_evaluations"]), "omega_max": st["omega_max"],
                   "rows": int(st["rows"]), "cpu_median": st["cpu_s"]}
        given = {k: float(v[i]) for k, v in self.inputs.items()}
        params = {k: v for k, v in given.items() if k not in PER_RUN_OPTIONS}
        per_run = {k: v for k, v in given.items() if k in PER_RUN_OPTIONS}
        return RunResult(self.variant, self.status[i], self.messages[i], summary, list(self.row_columns),
                         self.rows[i], None, self.options | per_run | {"params": params})


SHARED_OPTIONS = ("integrator", "t_end", "dt", "step", "tol", "max_steps", "newton", "newton_tol",
                  "rho_inf", "newmark_gamma", "newmark_beta", "blowup")


def settings_of(o: RunOptions, keep_interval: bool) -> dict:
    """The run options every run of a batch or sweep shares, from validated ones. keep_interval
    (a scene, or an interval given): rows stay every out_every * dt when dt varies per run;
    else each run gets the table's default rows for its dt."""
    settings = {k: getattr(o, k) for k in SHARED_OPTIONS if getattr(o, k) is not None}
    if keep_interval:
        settings["interval"] = o.out_every * o.dt
    return settings


class InProcessModel:
    """A built variant's shared library, loaded once; batch() runs parameter sets through it."""

    def __init__(self, built: Built, gen_dir: Path, spec=None, system=None):
        self.built, self.spec, self.system = built, spec, system
        # what batch() uses where a call gives nothing: a scene's run options and values
        # (with_scene); else the option table's defaults and the model's
        self.settings: dict = {}
        self.base: dict = {}
        self.manifest = read_manifest(gen_dir)
        self.outputs = list(self.manifest["outputs"])
        self.coordinates = [c["name"] for c in self.manifest["coordinates"]]
        # a system with constraints has a violation column in its rows (runtime.h), summarized too
        violation = ["violation"] if self.manifest.get("constraints") else []
        self.columns = self.outputs + violation + self.coordinates
        self.params = {p["name"]: p["default"] for p in self.manifest["params"]}
        self.maneuver_params = {p["name"]: p["default"] for p in self.manifest["drive_params"]}
        self.lib = ctypes.CDLL(str(built.library))
        # the model as the struct of system.h, from the accessor the manifest names; every
        # runtime call takes it
        accessor = getattr(self.lib, self.manifest["model"])
        accessor.restype, accessor.argtypes = ctypes.c_void_p, []
        self.model = ctypes.c_void_p(accessor())
        fn = self.lib.fsr_batch
        fn.restype = ctypes.c_int
        fn.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.POINTER(ctypes.c_char_p), ctypes.c_int, _dptr, ctypes.c_int,
                       _dptr, _dptr, ctypes.c_double, _dptr, _dptr, ctypes.POINTER(ctypes.c_int),
                       ctypes.c_char_p, ctypes.POINTER(_dptr)]
        self.lib.fsr_batch_free.restype = None
        self.lib.fsr_batch_free.argtypes = [ctypes.POINTER(_dptr), ctypes.c_int]
        self._weights = deflection_weights(spec, self.columns) if spec is not None else None

    def with_scene(self, scene) -> InProcessModel:
        """Run as the scene says where a batch() call does not: its run options (integrator,
        dt, t_end, rows every interval, ...) and its beam and manoeuvre values (a one-beam
        scene's are run-time parameters of its variant; a system scene's are its model's)."""
        self.settings = settings_of(scene.options, keep_interval=True)
        self.base = {k: v for k, v in scene.options.params.items() if k in self.run_time_names}
        return self

    @property
    def run_time_names(self) -> list[str]:
        """The names batch() varies per run: beam and manoeuvre parameters (a system's p and
        drive parameters), and the initial state q0_<coordinate>, qd0_<coordinate> (coordinates
        not named start where the model starts them: a system's joint initial values, else rest)."""
        return (list(self.params) + list(self.maneuver_params) + [f"q0_{c}" for c in self.coordinates]
                + [f"qd0_{c}" for c in self.coordinates])

    def batch(self, runs: dict, *, at=(), rows: bool = False, **options) -> BatchResult:
        """Run every parameter set in `runs` (name -> sequence of n values; beam parameters rho,
        E, A, I, L, manoeuvre parameters such as ws, ts, initial values q0_<coordinate> and
        qd0_<coordinate>; the others keep the model's defaults, or rest),
        with the run options of run_built (t_end, dt, integrator, out_every or interval, tol,
        step, newton, ...; checked against the option table) shared by all, except those of
        PER_RUN_OPTIONS given in `runs` (each run then has the rows run_built gives it).
        at: times at which to report each column's value."""
        unknown = [k for k in options if k not in RUN_OPTIONS]
        if unknown:
            raise TypeError(f"batch() got an unknown option '{unknown[0]}'")
        rows_given = {"interval", "out_every"} & set(options) or {"interval", "out_every"} & set(runs)
        options = {k: v for k, v in self.settings.items() if not (rows_given and k == "interval")} | options
        runs = dict(runs)
        for name in runs:
            if name not in self.run_time_names and name not in PER_RUN_OPTIONS:
                raise SpecError(f"unknown parameter '{name}' of {self.built.name} "
                                f"(run-time parameters: {', '.join(self.run_time_names)}; "
                                f"options: {', '.join(PER_RUN_OPTIONS)})")
        cols = {k: _values(k, runs[k]) for k in runs}
        n = len(next(iter(cols.values()))) if cols else 1
        if any(len(c) != n for c in cols.values()):
            raise SpecError("every parameter needs the same number of values (one per run)")
        cols |= {k: np.full(n, float(v)) for k, v in self.base.items() if k not in cols}
        o = self._options(options, cols, n)
        names = list(cols)
        table = np.array(list(cols.values())).T.reshape(n, len(names))
        opts = {k: v for k, v in option_inputs(o).items() if k not in cols}
        all_names = list(opts) + names
        inputs = np.ascontiguousarray(np.hstack([np.tile(list(opts.values()), (n, 1)), table]))
        at = _values("at", at, finite=True, allow_empty=True)
        # a system's bodies are gauged on each run's rows (validity.system_range_notes, as
        # `flexsym run` does): kept for GAUGE_CHUNK runs at a time when the call keeps none
        gauged = self.system is not None
        step = n if rows or not gauged else GAUGE_CHUNK
        parts = [self._call(all_names, inputs[i:i + step], at, rows or gauged) for i in range(0, n, step)]
        values, stats, codes = (np.concatenate([p[k] for p in parts]) for k in range(3))
        msgs = [m for p in parts for m in p[3]]
        stat = {k: stats[:, i].copy() for i, k in enumerate(STAT_FIELDS)}
        ranges = None
        if gauged:  # at each run's lengths: L is a run-time parameter
            given = [{k: float(v[i]) for k, v in cols.items()} for i in range(n)]
            ranges = [self._range_notes(r, given[i]) for i, r in enumerate(r for p in parts for r in p[5])]
        kept = [r for p in parts for r in p[4]] if rows else None
        valid, notes = self._validity(codes, msgs, stat, ranges)
        used = {"t_end": o.t_end, "dt": o.dt, "integrator": o.integrator, "tol": o.tol, "newton": o.newton,
                "step": o.step}  # as run_built's RunResult.options
        return BatchResult(self.built.name, {k: table[:, j].copy() for j, k in enumerate(names)}, used,
                           self.columns, self.outputs, at, codes, msgs, stat, values, valid, notes, kept,
                           ["t"] + self.columns if rows else None)

    def _options(self, options: dict, cols: dict, n: int) -> RunOptions:
        """The shared options, validated by the option table with each run's own t_end, dt and
        step (one check per distinct combination); a run's rows are those run_built gives it:
        cols gets each run's out_every when these vary and it was not given per run."""
        shared = {k: v for k, v in options.items() if v is not None}
        varied = [k for k in ("t_end", "dt", "step") if k in cols]
        combos = list(zip(*(cols[k].tolist() for k in varied))) if varied else [()] * n
        checked = {c: validate(shared | dict(zip(varied, c)), API, self.spec) for c in dict.fromkeys(combos)}
        if varied and "out_every" not in cols:
            cols["out_every"] = np.array([float(checked[c].out_every) for c in combos])
        return checked[combos[0]] if combos else validate(shared, API, self.spec)

    def _call(self, names: list, inputs: np.ndarray, at: np.ndarray, rows: bool):
        """fsr_batch on the runs of `inputs`: (summaries, statistics, codes, messages, the rows
        when kept, each as (t, columns) by name for the gauges)."""
        n = len(inputs)
        ncs, nf = len(self.columns), len(SUMMARY_FIELDS) + len(at)
        values = np.zeros((n, ncs, nf))
        stats = np.zeros((n, len(STAT_FIELDS)))
        codes = np.zeros(n, dtype=np.intc)
        messages = ctypes.create_string_buffer(MESSAGE * n)
        c_names = (ctypes.c_char_p * len(names))(*[s.encode() for s in names])
        weights = None if self._weights is None else np.ascontiguousarray(self._weights, dtype=float)
        row_ptrs = (_dptr * n)() if rows else None
        ret = self.lib.fsr_batch(self.model, len(names), c_names, n, _ptr(np.ascontiguousarray(inputs)), len(at),
                                 _ptr(at), None if weights is None else _ptr(weights), VALIDITY_LIMIT,
                                 _ptr(values), _ptr(stats),
                                 codes.ctypes.data_as(ctypes.POINTER(ctypes.c_int)), messages, row_ptrs)
        raw = messages.raw
        msgs = [raw[i * MESSAGE:(i + 1) * MESSAGE].split(b"\0", 1)[0].decode() for i in range(n)]
        if ret < 0:
            raise SpecError(f"{self.built.name}: {msgs[0]}")
        kept = []
        if rows:
            for i in range(n):
                nr, nc = int(stats[i, STAT_FIELDS.index("rows")]), int(stats[i, STAT_FIELDS.index("ncols")])
                kept.append(np.ctypeslib.as_array(row_ptrs[i], shape=(nr, nc)).copy() if nr else
                            np.zeros((0, nc)))
            self.lib.fsr_batch_free(row_ptrs, n)
        return values, stats, codes, msgs, kept, [_Rows(r, ["t"] + self.columns) for r in kept]

    def _range_notes(self, rows, params: dict) -> str:
        from flexsym.physics.validity import system_range_notes

        return "; ".join(system_range_notes(self.system, rows, params))

    def _validity(self, codes, messages, stat, ranges=None):
        """Per run: ok and inside its model's range: a one-beam model's |v| <= 0.1 L from the
        summary (validity.assess's criterion), a system's bodies' gauges from its rows (ranges:
        per run, why not, or "")."""
        valid, notes = [], []
        for i, code in enumerate(codes):
            note = [ranges[i]] if ranges and ranges[i] else []
            t_over = stat["bound_t"][i]
            if not np.isnan(t_over):
                what = "|v_tip|" if "v_tip" in self.columns else "a bound on |v|"
                note.append(f"deformation left the range of validity of the modal model at t = "
                            f"{t_over:.3g} s: {what} > {VALIDITY_LIMIT:g} L (peak {stat['bound_peak'][i]:.3g} m)")
            if code != 0:
                note.append(messages[i])
            valid.append(not note)
            notes.append("; ".join(note))
        return np.array(valid, dtype=bool), notes


class _Rows:
    """A run's rows by column name (t, outputs, coordinates): what the gauges read."""

    def __init__(self, data: np.ndarray, columns: list):
        self.data, self.index = data, {c: j for j, c in enumerate(columns)}

    @property
    def t(self) -> np.ndarray:
        return self.data[:, 0]

    def __getitem__(self, name: str) -> np.ndarray:
        return self.data[:, self.index[name]]


def _values(name: str, given, finite: bool = False, allow_empty: bool = False) -> np.ndarray:
    """A parameter's values (one per run) as a contiguous float array: real numbers only (a
    bool, complex, string or None is refused, not converted to 1.0 or nan). nan and inf are
    real: the runtime checks each run's values and fails that run alone (its message says
    which value); finite=True refuses them here (for values shared by every run, such as at)."""
    items = np.atleast_1d(np.asarray(given, dtype=object)).ravel()
    for v in items:
        if not is_real(v) or (finite and not np.isfinite(float(v))):
            raise SpecError(f"batch(): {name}: {v!r} is not a {'finite ' if finite else ''}real number")
    if not len(items) and not allow_empty:
        raise SpecError(f"batch(): {name}: no values")
    return np.ascontiguousarray(items.astype(float))


def _ptr(a: np.ndarray):
    return a.ctypes.data_as(_dptr)


def load(spec) -> InProcessModel:
    """Generate and build spec when needed, and load its library."""
    from flexsym.toolchain.pipeline import generated_folder
    from flexsym.toolchain.build import build

    folder = generated_folder(spec)
    return InProcessModel(build(folder), folder, spec)


def load_system(system) -> InProcessModel:
    """Generate and build a system (flexsym/model/system.py) when needed, and load its library;
    batch() then takes its p and drive parameter names (e.g. E, or BEAM_E with several beams)."""
    from flexsym.toolchain.pipeline import prepare_system, system_folder

    return InProcessModel(prepare_system(system), system_folder(system), system=system)
