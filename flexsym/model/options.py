"""Run options: one table of rules shared by the command line, scene files, the Python API
and the C driver.

Every option of a run is a row of OPTIONS: its type, default, allowed values, the integrators
it applies to, its command-line flag, its scene key and the driver flag it becomes. `validate`
checks a set of given values against the table, and against each other (step, row and memory
counts against LIMITS), before anything is generated, built or written; it names an option as
its source spells it (`--dt`, `[solver] dt` in a scene, `dt=` in Python). The C runtime keeps
its own checks only as a last line of defence; its limits and defaults come from this table
through runtime_c/include/flexsym/limits.h, written by `python -m flexsym.model.options`
(tests/test_validation.py fails when the header is stale).

Adding an option: add a row to OPTIONS (and, if the driver takes it, a `driver` flag that
driver.c parses); the CLI, scenes and the API pick it up from the table.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

from flexsym.core.errors import SpecError
from flexsym.model.integrators import names

# the runtime's integrator registry (integrators.py): all of them, those that solve with Newton,
# those that adapt their step to a tolerance
INTEGRATORS = names()
IMPLICIT = names("implicit")
ADAPTIVE = names("adaptive")

# Limits of one run: beyond them a run is refused up front (and by the runtime as a last line).
LIMITS = {
    "max_steps": 10**8,      # steps, or points of the output grid (the driver counts in long)
    "max_rows": 10**7,       # rows kept in memory and written
    "max_row_bytes": 2**30,  # rows x columns x 8 bytes
    "max_repeat": 1000,      # timed repetitions of one run
}


@dataclass(frozen=True)
class Option:
    name: str                 # keyword in run_built / api.simulate
    kind: type                # float, int, str or bool
    default: object           # None: no default (the option is off unless given)
    help: str
    flag: str | None = None   # command-line flag of `flexsym run`
    scene: str | None = None  # "table.key" in a scene file
    driver: str | None = None  # flag of the C driver
    low: float | None = None  # allowed range [low, high]; open ends when *_open
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    choices: tuple = ()
    integrators: tuple = INTEGRATORS  # integrators it applies to
    maneuvers: tuple | None = None     # manoeuvres it applies to (None: not a manoeuvre value)
    metavar: str | None = None

    def range_text(self) -> str:
        if self.choices:
            return "one of " + ", ".join(map(str, self.choices))
        lo = None if self.low is None else f"{'>' if self.low_open else '>='} {self.low:g}"
        hi = None if self.high is None else f"{'<' if self.high_open else '<='} {self.high:g}"
        return " and ".join(x for x in (lo, hi) if x) or "any"

    def convert(self, value, where) -> object:
        """The value as self.kind, in range; SpecError naming it otherwise."""
        if self.kind is bool:
            if not isinstance(value, bool):
                raise where.error(self, f"must be true or false (got {value!r})")
            return value
        if self.kind is str:
            if not isinstance(value, str):
                raise where.error(self, f"must be a string (got {value!r})")
            if self.choices and value not in self.choices:
                raise where.error(self, f"unknown {self.name} '{value}' (known: {', '.join(self.choices)})")
            return value
        if isinstance(value, bool):
            raise where.error(self, f"must be a number, not {value!r}")
        if isinstance(value, str):
            try:
                value = float(value)  # "1e6" is a whole number too
            except ValueError:
                raise where.error(self, f"'{value}' is not {'an integer' if self.kind is int else 'a number'}") from None
        if not isinstance(value, (int, float)):
            raise where.error(self, f"must be a number, not {type(value).__name__} ({value!r})")
        if isinstance(value, int) and abs(value) > 2**53:
            raise where.error(self, f"{value:.3g} is out of range")
        if not math.isfinite(value):
            raise where.error(self, f"must be finite (got {value!r})")
        if self.kind is int:
            if value != int(value):
                raise where.error(self, f"must be a whole number (got {value!r})")
            value = int(value)
        else:
            value = float(value)
        ok = ((self.low is None or (value > self.low if self.low_open else value >= self.low))
              and (self.high is None or (value < self.high if self.high_open else value <= self.high)))
        if not ok:
            raise where.error(self, f"must be {self.range_text()} (got {value:g})")
        return value


_o = Option  # rows below: name, type, default, help, flag, scene key, driver flag, rules
OPTIONS: tuple[Option, ...] = (
    _o("integrator", str, "genalpha", "rk4, dopri5 (adaptive, see --tol), genalpha (default), newmark, "
       "radau5 (implicit, order 5, large steps), ali3p, genalpha3 (constrained systems; without "
       "constraints: the trapezoidal rule, generalized-alpha), rk4p (constrained systems, explicit, "
       "order 4: RK4 on the index-1 form with projections)", "--integrator", "solver.integrator", "--integrator",
       choices=INTEGRATORS),
    _o("t_end", float, 20.0, "end time [s] (default 20)", "--t-end", "solver.t_end", "--t-end",
       low=0.0, low_open=True),
    _o("dt", float, 1e-3, "time step [s] (default 1e-3); the output grid for dopri5, and for radau5 "
       "with --step", "--dt", "solver.dt", "--dt", low=0.0, low_open=True),
    _o("step", float, None, "radau5 step [s] (default --dt); rows stay every --dt, from its "
       "collocation polynomial", "--step", "solver.step", "--step", low=0.0, low_open=True,
       integrators=("radau5",)),
    _o("tol", float, None, "dopri5 error tolerance (rtol; atol = tol * L), default 1e-6; 0: fixed "
       "steps --dt", "--tol", "solver.tol", "--tol", low=0.0, high=1.0, high_open=True,
       integrators=ADAPTIVE),
    _o("max_steps", int, None, "dopri5: accepted + rejected steps before giving up (default 1e6)",
       "--max-steps", "solver.max_steps", "--max-steps", low=1, high=LIMITS["max_steps"],
       integrators=ADAPTIVE),
    _o("newton", str, None, "implicit integrators: modified (default, reuses the iteration matrix) "
       "or full (rebuilt every iteration, a reference)", "--newton", "solver.newton", "--newton",
       choices=("modified", "full"), integrators=IMPLICIT),
    _o("newton_tol", float, None, "implicit integrators: Newton tolerance on max abs(dq), relative to L "
       "(default 1e-12); rk4p: its projection's tolerance on max abs(Phi)", "--newton-tol",
       "solver.newton_tol", "--newton-tol", low=1e-16, high=1e-3, integrators=IMPLICIT + ("rk4p",)),
    _o("rho_inf", float, None, "generalized-alpha spectral radius at infinity in [0, 1] (default 0.9)",
       "--rho-inf", "solver.rho_inf", "--rho-inf", low=0.0, high=1.0, integrators=("genalpha", "genalpha3")),
    _o("newmark_gamma", float, None, "Newmark gamma (default 0.5; the paper: 0.5)", "--newmark-gamma",
       "solver.newmark_gamma", "--newmark-gamma", low=0.5, high=1.0, integrators=("newmark",)),
    _o("newmark_beta", float, None, "Newmark beta (default 0.25; the paper: 0.5625); below gamma/2 "
       "only stable for omega_max dt <= 1/sqrt(gamma/2 - beta), checked by the runtime (1/12: "
       "Fox-Goodwin, fourth-order period error)", "--newmark-beta", "solver.newmark_beta",
       "--newmark-beta", low=0.0, low_open=True, high=1.0, integrators=("newmark",)),
    _o("blowup", float, None, "stop when a coordinate exceeds this many length scales (a one-beam "
       "model's L, a system's size; a system's revolute joint angles and ANCF slopes are not "
       "bounded; default 10)", "--blowup", "solver.blowup", "--blowup", low=0.0, low_open=True, high=1e6),
    _o("penalty", float, None, "ali3p penalty kappa: the penalty term's weight against the mass "
       "matrix (default 1e7; the constraint residual after projection is about 1/kappa)", "--penalty",
       "solver.penalty", "--penalty", low=0.0, low_open=True, high=1e15, integrators=("ali3p",)),
    _o("interval", float, None, "time between output rows [s], a whole number of steps --dt "
       "(default: about 0.01 s)", "--interval", "output.interval", None, low=0.0, low_open=True),
    _o("energy", bool, False, "append the kinetic and potential energy and the Jacobi integral "
       "(columns T, V, h)", "--energy", "output.energy", "--energy"),
    _o("repeat", int, 1, "timed runs (after a warm-up when more than 1); the CPU time reported is their median",
       "--repeat", None, "--repeat", low=1, high=LIMITS["max_repeat"]),
    _o("ws", float, 6.0, "final spin rate omega_s [rad/s] (default 6)", "--ws", "maneuver.omega", None,
       low=-1e4, high=1e4, maneuvers=("spin_up", "constant")),
    _o("ts", float, 15.0, "spin-up time T_s [s] (default 15)", "--ts", "maneuver.duration", None,
       low=0.0, low_open=True, high=1e9, maneuvers=("spin_up",)),
)
BY_NAME = {o.name: o for o in OPTIONS}
DEFAULTS = {o.name: o.default for o in OPTIONS}
RUNTIME_DEFAULTS = {"tol": 1e-6, "max_steps": 10**6, "newton": "modified", "newton_tol": 1e-12,
                    "rho_inf": 0.9, "newmark_gamma": 0.5, "newmark_beta": 0.25, "blowup": 10.0,
                    "penalty": 1e7}
ROW_INTERVAL = 0.01  # default time between rows [s]


# ----- where a value came from: names an option as the user wrote it ----------------------
@dataclass(frozen=True)
class Where:
    kind: str = "api"  # "cli" | "scene" | "api"
    path: Path | None = None
    flags: tuple[str, ...] = ()  # a scene's options given on the command line (named as flags)

    def label(self, opt: Option | str) -> str:
        opt = BY_NAME[opt] if isinstance(opt, str) else opt
        if (self.kind == "cli" or opt.name in self.flags) and opt.flag:
            return opt.flag
        if self.kind == "scene" and opt.scene:
            table, key = opt.scene.split(".")
            return f"[{table}] {key}"
        return opt.name

    def error(self, opt: Option | str, msg: str) -> SpecError:
        prefix = f"{self.path}: " if self.kind == "scene" and self.path else ""
        return SpecError(f"{prefix}{self.label(opt)}: {msg}")


CLI, API = Where("cli"), Where("api")


@dataclass(frozen=True)
class RunOptions:
    """Validated options of one run: every value checked, defaults filled in."""

    integrator: str
    t_end: float
    dt: float
    params: dict = field(default_factory=dict)  # beam (rho, E, A, I, L) and manoeuvre (ws, ts)
    out_every: int = 1
    step: float | None = None
    tol: float | None = None
    max_steps: int | None = None
    newton: str | None = None
    newton_tol: float | None = None
    rho_inf: float | None = None
    newmark_gamma: float | None = None
    newmark_beta: float | None = None
    blowup: float | None = None
    penalty: float | None = None
    energy: bool = False
    repeat: int = 1
    steps: int = 0  # integration steps (fixed-step methods, radau5) or output-grid points
    rows: int = 0

    def describe(self) -> str:
        """The effective options in one line (the CSV header's record of a run)."""
        parts = [f"integrator = {self.integrator}", f"t_end = {self.t_end!r}", f"dt = {self.dt!r}",
                 f"interval = {self.out_every * self.dt:.12g}"]
        parts += [f"{o.name} = {getattr(self, o.name)!r}" for o in OPTIONS
                  if o.name not in ("integrator", "t_end", "dt", "interval", "repeat")
                  and getattr(self, o.name, None) not in (None, False)]
        parts += [f"{k} = {v!r}" for k, v in sorted(self.params.items())]
        return ", ".join(parts)

    def driver_args(self) -> list[str]:
        """The C driver's command line for these options (its flags come from the table)."""
        args = ["--out-every", str(self.out_every)]
        for opt in OPTIONS:
            value = getattr(self, opt.name, None)
            if opt.driver is None or value is None:
                continue
            if opt.kind is bool:
                args += [opt.driver] if value else []
            else:
                args += [opt.driver, repr(value) if opt.kind is float else str(value)]
        for name, value in self.params.items():
            args += ["--param", f"{name}={float(value)!r}"]
        return args


def validate(given: dict, where: Where = API, spec=None) -> RunOptions:
    """Check the given options (None = not given) against the table and each other; fill the
    defaults. spec (optional) names the manoeuvre and the columns of a row (without it the
    memory estimate assumes 16 columns; the runtime checks the exact count)."""
    unknown = sorted(set(given) - set(BY_NAME) - {"params", "out_every"})
    if unknown:
        raise SpecError(f"unknown run option '{unknown[0]}' (known: {', '.join(BY_NAME)})")
    values = {}
    for name, value in given.items():
        if name in BY_NAME and value is not None:
            values[name] = BY_NAME[name].convert(value, where)
    integrator = values.get("integrator", DEFAULTS["integrator"])
    for name in values:
        opt = BY_NAME[name]
        if integrator not in opt.integrators:
            names = opt.integrators
            listed = names[0] if len(names) == 1 else f"{', '.join(names[:-1])} and {names[-1]}"
            raise where.error(opt, f"applies to {listed}, not to "
                                   f"integrator {integrator} (it would be ignored)")
    maneuver = getattr(spec, "maneuver", None)
    params = check_params(given.get("params") or {}, where, maneuver)
    for name in ("ws", "ts"):
        if name in values:
            opt = BY_NAME[name]
            kind = "expression" if maneuver and maneuver.startswith("expression:") else maneuver
            if maneuver is not None and kind not in opt.maneuvers:
                raise where.error(opt, f"does not apply to the manoeuvre '{kind}' (it would be ignored)")
            if name in params:
                raise where.error(opt, f"given twice (also as --param {name}=...)")
            params[name] = values.pop(name)
    if maneuver is not None:  # defaults of the manoeuvre's own parameters
        from flexsym.model.maneuver import maneuver_of

        for p in maneuver_of(maneuver).params:
            params.setdefault(p.name, DEFAULTS[p.name] if p.name in DEFAULTS else p.default)

    t_end = values.pop("t_end", DEFAULTS["t_end"])
    dt = values.pop("dt", DEFAULTS["dt"])
    if dt > t_end:
        raise where.error("dt", f"{dt:g} s is larger than {where.label('t_end')} = {t_end:g} s")
    if maneuver is not None and maneuver.startswith("expression:"):
        from flexsym.model.maneuver import check_theta

        try:
            check_theta(maneuver[len("expression:"):], t_end)
        except SpecError as exc:
            label = {"scene": "[maneuver] theta", "cli": "--maneuver"}.get(where.kind, "theta(t)")
            prefix = f"{where.path}: " if where.kind == "scene" and where.path else ""
            raise SpecError(f"{prefix}{label}: {exc}") from None
    step = values.get("step")
    if step is not None and step > t_end:
        raise where.error("step", f"{step:g} s is larger than {where.label('t_end')} = {t_end:g} s")

    grid = t_end / dt  # points of the row grid (and steps, for the fixed-step methods)
    limit = LIMITS["max_steps"]
    if grid > limit:
        raise where.error("dt", f"{where.label('t_end')} / {where.label('dt')} = {grid:.3g} "
                                f"{'grid points' if integrator in ('dopri5', 'radau5') else 'steps'} "
                                f"exceeds the limit of {limit:.0e}")
    if step is not None and t_end / step > limit:
        raise where.error("step", f"{t_end / step:.3g} steps exceeds the limit of {limit:.0e}")

    steps = max(1, math.ceil(grid - 1e-9))  # an int now: grid is within the limit
    interval = values.pop("interval", None)
    out_every = given.get("out_every")
    if out_every is not None:  # Python callers may give rows every k steps instead of interval
        if interval is not None:
            raise where.error("interval", "give either interval or out_every, not both")
        if isinstance(out_every, bool) or not isinstance(out_every, int) or out_every < 1:
            raise SpecError(f"out_every must be a whole number of steps >= 1 (got {out_every!r})")
        out_every = min(out_every, steps)
    elif interval is None:
        out_every = min(max(1, round(ROW_INTERVAL / dt)), steps)
    else:
        if interval > t_end:
            raise where.error("interval", f"{interval:g} s is longer than {where.label('t_end')} = "
                                          f"{t_end:g} s (only the first and last rows would be written)")
        out_every = round(interval / dt)
        if out_every < 1 or abs(out_every * dt - interval) > 1e-9 * interval:
            raise where.error("interval", f"must be a whole number of steps {where.label('dt')} = {dt:g} s "
                                          f"(got {interval:g} s)")
    rows = steps // out_every + 2
    if rows > LIMITS["max_rows"]:
        raise where.error("dt", f"{rows:.3g} output rows exceeds the limit of {LIMITS['max_rows']:.0e}; "
                                f"use a longer {where.label('interval')}")
    ncols = 1 + len(spec.outputs) + len(spec.coordinates) if spec is not None else 16
    ncols += 3 if values.get("energy") else 0
    if rows * ncols * 8 > LIMITS["max_row_bytes"]:
        raise where.error("dt", f"{rows:.3g} rows of {ncols} columns need {rows * ncols * 8 / 2**30:.1f} GiB, "
                                f"above the limit of {LIMITS['max_row_bytes'] / 2**30:g} GiB; use a longer "
                                f"{where.label('interval')}")
    return RunOptions(integrator=integrator, t_end=t_end, dt=dt, params=params, out_every=out_every,
                      steps=steps, rows=rows,
                      **{k: v for k, v in values.items() if k != "integrator"})


def check_params(params: dict, where: Where = API, maneuver: str | None = None) -> dict:
    """Beam parameters (positive, finite) and manoeuvre parameters (as the table says)."""
    from flexsym.model.parameters import BEAM_PARAMS, SPATIAL_BEAM_PARAMS
    from flexsym.model.maneuver import MANEUVERS, maneuver_of

    # a model without one refuses it; bending_inertia: a spatial ef beam's on a free frame
    beam = {p.name for p in BEAM_PARAMS + SPATIAL_BEAM_PARAMS} | {"bending_inertia"}
    man = ({p.name for p in maneuver_of(maneuver).params} if maneuver is not None
           else {p.name for m in MANEUVERS.values() for p in m.params})
    out = {}
    label = "--param " if where.kind == "cli" else "params "
    for name, value in params.items():
        # a system with several beams names each one's body_<name> (System.beam_param); the
        # model itself refuses a body it does not have (the runtime's one line, exit 2)
        base = name if name in beam | man else next(
            (b for b in sorted(beam, key=len, reverse=True)
             if name.endswith("_" + b) and len(name) > len(b) + 1), None)
        if base is None:
            known = f"beam: {', '.join(sorted(beam))}; manoeuvre: {', '.join(sorted(man)) or 'none'}"
            raise SpecError(f"{label.strip()}: unknown parameter '{name}' ({known}; in a system with "
                            "several beams, <body>_<beam parameter>)")
        rule = BY_NAME.get(base) or Option(name, float, None, "", low=0.0, low_open=True)
        out[name] = replace(rule, name=label + name).convert(value, API)
    return out


# ----- the command line ----------------------------------------------------------------------
def add_arguments(parser, names, defaults: dict | None = None) -> None:
    """argparse options from the table. Values stay text (None when not given): `validate`
    converts and checks them, so a bad value is one line naming the flag."""
    for name in names:
        opt = BY_NAME[name]
        default = (defaults or {}).get(name)
        text = opt.help + (f" (here: default {default})" if default is not None else "")
        if opt.kind is bool:
            parser.add_argument(opt.flag, dest=name, action="store_const", const=True, default=default,
                                help=text)
        else:
            parser.add_argument(opt.flag, dest=name, default=default, help=text,
                                metavar=opt.metavar or name.upper())


def given_options(args, names) -> dict:
    return {n: getattr(args, n) for n in names if getattr(args, n, None) is not None}


def with_overrides(scene_given: dict, overrides: dict, path: Path, spec=None) -> RunOptions:
    """A scene's run options with some replaced from the command line (`flexsym run SCENE --dt
    ...`), validated once, together: a value is named as its source spells it (`--dt`, or
    `[solver] t_end` in the scene)."""
    return validate(scene_given | overrides, Where("scene", path, tuple(overrides)), spec)


# ----- the C runtime's limits and defaults -----------------------------------------------------
def c_header() -> str:
    lines = ["/* DO NOT EDIT: written by `python -m flexsym.model.options > runtime_c/include/flexsym/limits.h`",
             " * from the option table in flexsym/model/options.py (the one place for run limits and",
             " * defaults). The runtime refuses runs beyond these limits as a last line of defence. */",
             "#ifndef FLEXSYM_LIMITS_H", "#define FLEXSYM_LIMITS_H", ""]
    for key, value in LIMITS.items():
        lines.append(f"#define FSR_{key.upper()} {value}L")
    for key in ("t_end", "dt"):
        lines.append(f"#define FSR_DEFAULT_{key.upper()} {DEFAULTS[key]!r}")
    for key, value in RUNTIME_DEFAULTS.items():
        if key == "newton":
            continue
        lines.append(f"#define FSR_DEFAULT_{key.upper()} {value!r}" + ("L" if isinstance(value, int) else ""))
    lines += ["", "#endif", ""]
    return "\n".join(lines)


def markdown_table() -> str:
    """The option table as README markdown (tests/test_validation.py keeps the README's copy
    identical: `python -m flexsym.model.options --markdown`)."""
    rows = ["| option | scene key | default | allowed | integrators | what |", "|---|---|---|---|---|---|"]
    for o in OPTIONS:
        default = RUNTIME_DEFAULTS.get(o.name, o.default)
        default = "-" if default is None else ("off" if default is False else f"{default:g}"
                                               if isinstance(default, float) else str(default))
        allowed = "true/false" if o.kind is bool else o.range_text().replace("|", "\\|")
        scene = f"[{o.scene.replace('.', '] ')}" if o.scene else "-"
        applies = ", ".join(o.integrators) if o.integrators != INTEGRATORS else "all"
        if o.maneuvers:
            applies = "manoeuvre " + ", ".join(o.maneuvers)
        rows.append(f"| `{o.flag}` | {scene} | {default} | {allowed} | {applies} | {o.help} |")
    return "\n".join(rows) + "\n"


if __name__ == "__main__":
    import sys

    print(markdown_table() if "--markdown" in sys.argv else c_header(), end="")
