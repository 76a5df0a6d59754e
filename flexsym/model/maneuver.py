"""Guided root rotation theta(t): sympy expressions differentiated symbolically.

theta is a guided coordinate, so only its rate w = theta' and acceleration alpha = theta''
enter the equations of motion, as known inputs. The manoeuvre is generated as a kernel
(t, manoeuvre parameters) -> (theta, w, alpha) like every other kernel.
"""
from __future__ import annotations

import ast
import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import sympy as sp

from flexsym.core.errors import SpecError

t = sp.Symbol("t", real=True)


@dataclass(frozen=True)
class Param:
    """A run-time parameter of the generated code (beam or manoeuvre): its value is an input
    of the kernels, so changing it needs no regeneration."""

    name: str
    default: float
    unit: str
    description: str

    @property
    def symbol(self) -> sp.Symbol:
        return sp.Symbol(self.name, positive=True)


@dataclass(frozen=True)
class Maneuver:
    name: str
    params: tuple[Param, ...]
    theta: sp.Expr
    description: str

    @property
    def rate(self) -> sp.Expr:
        return sp.diff(self.theta, t)

    @property
    def acceleration(self) -> sp.Expr:
        return sp.diff(self.theta, t, 2)

    @property
    def accelerates(self) -> bool:
        """False when theta'' vanishes identically: the alpha terms are then dropped. A value
        that is not zero at some sample time decides it without sympy's simplify, whose cost
        is not bounded for arbitrary expressions; simplify runs only when every sample is 0."""
        acc = self.acceleration
        if acc == 0:
            return False
        free = sorted(acc.free_symbols - {t}, key=str)
        probe = {p: 1.0 + 0.37 * k for k, p in enumerate(free)}
        for tk in (0.0, 0.3, 1.1, 2.9, 7.3, 13.7, 19.1):
            try:
                value = complex(acc.subs(probe).subs(t, tk).evalf(15))
            except (TypeError, ValueError, ArithmeticError):
                continue
            if value != 0:
                return True
        return sp.simplify(acc) != 0


def _spin_up() -> Maneuver:
    ws = Param("ws", 6.0, "rad/s", "final spin rate omega_s")
    ts = Param("ts", 15.0, "s", "spin-up duration T_s")
    w, T = ws.symbol, ts.symbol
    ramp = (w / T) * (t**2 / 2 + (T / (2 * sp.pi))**2 * (sp.cos(2 * sp.pi * t / T) - 1))
    theta = sp.Piecewise((ramp, t <= T), (w * (t - T / 2), True))
    return Maneuver("spin_up", (ws, ts), theta,
                    "paper eq. (39): smooth spin-up to ws over ts, then constant speed")


def _constant() -> Maneuver:
    om = Param("ws", 6.0, "rad/s", "constant spin rate")
    return Maneuver("constant", (om,), om.symbol * t, "constant spin rate from t = 0")


MANEUVERS: dict[str, Maneuver] = {m.name: m for m in (_spin_up(), _constant())}


# ----- theta(t) given as text (scenes) ----------------------------------------------------
# Parsed by walking Python's syntax tree with a whitelist and building sympy objects directly:
# nothing is ever evaluated, so no text can reach eval() (sympy's parse_expr would use it).
EXPRESSION_PREFIX = "expression:"
_FUNCTIONS = {"sin": sp.sin, "cos": sp.cos, "tan": sp.tan, "exp": sp.exp, "log": sp.log,
              "sqrt": sp.sqrt, "sinh": sp.sinh, "cosh": sp.cosh, "tanh": sp.tanh,
              "atan": sp.atan, "asin": sp.asin, "acos": sp.acos}
_CONSTANTS = {"pi": sp.pi, "e": sp.E}
_BINARY = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b,
           ast.Mult: lambda a, b: a * b, ast.Div: lambda a, b: a / b}
_COMPARE = {ast.Lt: sp.Lt, ast.LtE: sp.Le, ast.Gt: sp.Gt, ast.GtE: sp.Ge}
MAX_NODES = 300
MAX_EXPONENT = 64
MAX_MAGNITUDE = 300  # |constant| <= 1e300: every number must stay a finite double
GRID = 4001  # samples of [0, t_end] for the numeric checks
MAX_SWITCHES = 200  # condition changes of ifelse, or zero crossings of a denominator
_SYMPY_ERRORS = (TypeError, ValueError, ArithmeticError, RecursionError, AttributeError, MemoryError)


@lru_cache(maxsize=256)
def parse_theta(text: str) -> sp.Expr:
    """theta(t) from text: numbers, t, pi, e, + - * / **, the functions in _FUNCTIONS and
    ifelse(condition, a, b) with a comparison as condition. Raises SpecError otherwise.
    The cost is bounded for any input: at most MAX_NODES syntax nodes, numeric exponents up
    to MAX_EXPONENT, and the magnitude of every constant result is estimated before sympy
    computes it exactly."""
    return parse_expression(text, (("t", t),), "theta(t)")


@lru_cache(maxsize=256)
def parse_expression(text: str, names: tuple[tuple[str, sp.Symbol], ...], label: str) -> sp.Expr:
    """parse_theta's grammar with the names given (name, symbol) instead of t alone (a motor's
    torque: t and joint coordinates and rates); `label` names the expression in messages."""
    env = dict(names)
    if not isinstance(text, str) or not text.strip():
        raise SpecError(f"{label} expression is empty")
    if len(text) > 2000:
        raise SpecError(f"{label} expression is longer than 2000 characters")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        raise SpecError(f"cannot parse {label} = '{text}': {exc.msg} at column {exc.offset}") from None
    except (ValueError, RecursionError, MemoryError) as exc:
        raise SpecError(f"cannot parse {label} = '{text}': {exc}") from None
    if sum(1 for _ in ast.walk(tree)) > MAX_NODES:
        raise SpecError(f"{label} expression has more than {MAX_NODES} syntax nodes")
    try:
        expr = _build(tree.body, text, env, label)
    except _SYMPY_ERRORS as exc:
        raise SpecError(f"{label} = '{text}': cannot be built ({type(exc).__name__}: {exc})") from None
    extra = expr.free_symbols - set(env.values())
    if extra:
        raise SpecError(f"{label} = '{text}' depends on {', '.join(sorted(map(str, extra)))}, not only "
                        f"{', '.join(env)}")
    if expr.has(sp.zoo, sp.oo, -sp.oo):
        raise SpecError(f"{label} = '{text}' is infinite (a division by zero?)")
    if expr.has(sp.nan):
        raise SpecError(f"{label} = '{text}' is undefined (nan)")
    if expr.has(sp.I):
        raise SpecError(f"{label} = '{text}' is not real (it contains the imaginary unit)")
    return expr


def _log10_abs(x: sp.Number) -> float:
    if x.is_zero:  # not x == 0: sympy's Float(0.0) == 0 is False
        return -math.inf
    return float(sp.log(abs(x), 10).evalf(15))


def _check_magnitude(value, text, label="theta(t)"):
    if value.is_Number and value.is_finite is not False and not value.is_zero:
        if _log10_abs(value) > MAX_MAGNITUDE:
            raise SpecError(f"{label} = '{text}': the constant {sp.Float(value, 3)} is beyond "
                            f"1e{MAX_MAGNITUDE} (double precision)")
    return value


def _build(node, text, env=None, label="theta(t)"):
    env = {"t": t} if env is None else env
    def bad(what):
        return SpecError(f"{label} = '{text}': {what} is not allowed (use numbers, t, pi, e, "
                         f"{', '.join(n for n in env if n != 't')}{', ' if len(env) > 1 else ''}+ - * / **, ifelse(cond, a, b) and {', '.join(_FUNCTIONS)})")

    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)) \
                or not math.isfinite(node.value):
            raise bad(f"the constant {node.value!r}")
        return _check_magnitude(sp.Integer(node.value) if isinstance(node.value, int)
                                else sp.Float(repr(node.value)), text, label)
    if isinstance(node, ast.Name):
        if node.id in env:
            return env[node.id]
        if node.id in _CONSTANTS:
            return _CONSTANTS[node.id]
        raise bad(f"the name '{node.id}'")
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        val = _build(node.operand, text, env, label)
        return -val if isinstance(node.op, ast.USub) else val
    if isinstance(node, ast.BinOp):
        a, b = _build(node.left, text, env, label), _build(node.right, text, env, label)
        if isinstance(node.op, ast.Pow):
            if b.is_Number and abs(b) > MAX_EXPONENT:
                raise bad(f"the exponent {b}")
            if a.is_Number and b.is_Number:  # estimate before sympy computes it exactly
                if a == 0 and b < 0:
                    raise SpecError(f"{label} = '{text}' divides by zero (0 to a negative power)")
                if a != 0 and float(b) * _log10_abs(a) > MAX_MAGNITUDE:
                    raise SpecError(f"{label} = '{text}': {a}**{b} is beyond 1e{MAX_MAGNITUDE} "
                                    "(double precision)")
            return _check_magnitude(a**b, text, label)
        op = _BINARY.get(type(node.op))
        if op is None:
            raise bad(f"the operator {type(node.op).__name__}")
        return _check_magnitude(op(a, b), text, label)
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and not node.keywords:
        name, args = node.func.id, node.args
        if name == "ifelse" and len(args) == 3:
            cond = args[0]
            if not (isinstance(cond, ast.Compare) and len(cond.ops) == 1
                    and type(cond.ops[0]) in _COMPARE):
                raise bad("an ifelse condition other than one comparison (<, <=, >, >=)")
            c = _COMPARE[type(cond.ops[0])](_build(cond.left, text, env, label), _build(cond.comparators[0], text, env, label))
            return sp.Piecewise((_build(args[1], text, env, label), c), (_build(args[2], text, env, label), True))
        if name in _FUNCTIONS and len(args) == 1:
            return _FUNCTIONS[name](_build(args[0], text, env, label))
        raise bad(f"the call {name}(...) with {len(args)} argument(s)")
    raise bad(f"a {type(node).__name__}")


# ----- theta(t) must be real, finite and smooth enough on [0, t_end] -------------------------
# theta'' enters the equations of motion as a load, so the integrator needs theta and theta'
# continuous (a jump in theta' is an impulse the integrator cannot see) and theta'' bounded; a
# jump in theta'' (a suddenly applied angular acceleration) is a finite load and allowed.
def check_theta(text: str, t_end: float | None = None) -> sp.Expr:
    """parse_theta, then numeric checks on [0, t_end] (default 20 s): theta, theta', theta''
    real and finite on a grid of GRID points and at every located switch of an ifelse or
    zero of a denominator; theta and theta' continuous at every switch; no pole (zero of a
    denominator, of cos under tan, of the argument of log or of a fractional power)."""
    expr = parse_theta(text)
    t_end = 20.0 if t_end is None else float(t_end)
    try:
        _check_numeric(expr, t_end, text)
    except SpecError:
        raise
    except _SYMPY_ERRORS + (NameError, KeyError) as exc:
        raise SpecError(f"theta(t) = '{text}': cannot be evaluated ({type(exc).__name__}: {exc})") from None
    return expr


NAMES = ("theta", "theta'", "theta''")


def _numeric(exprs):
    # Integers beyond int64 would make numpy fall back to Python objects: evaluate them as
    # doubles, as the generated C does.
    big = {n: sp.Float(n) for e in exprs for n in e.atoms(sp.Rational) if abs(n.p) > 2**53 or n.q > 2**53}
    fn = sp.lambdify(t, [e.xreplace(big) for e in exprs], modules="numpy")

    def call(x):
        x = np.asarray(x, dtype=float)
        with np.errstate(all="ignore"):
            out = fn(x)
        return [np.broadcast_to(np.asarray(v), x.shape) for v in out]
    return call


def _bad_values(values, times, text):
    for name, v in zip(NAMES, values):
        if np.iscomplexobj(v) and np.any(np.imag(v) != 0):
            k = int(np.argmax(np.imag(v) != 0))
            raise SpecError(f"theta(t) = '{text}': {name} is not real at t = {times[k]:.6g} s")
        v = np.real(v).astype(float) if v.dtype != object else np.array(v, dtype=complex).real
        bad = ~np.isfinite(v)
        if np.any(bad):
            k = int(np.argmax(bad))
            raise SpecError(f"theta(t) = '{text}': {name} is not finite at t = {times[k]:.6g} s "
                            f"(refused: the run needs theta, theta' and theta'' finite on [0, t_end])")


def _check_numeric(expr, t_end, text):
    derivs = (expr, sp.diff(expr, t), sp.diff(expr, t, 2))
    for name, d in zip(NAMES, derivs):
        if d.has(sp.DiracDelta, sp.Heaviside, sp.Derivative, sp.Subs, sp.sign):
            raise SpecError(f"theta(t) = '{text}': {name} is not a smooth function of t (sympy "
                            f"gives {type(next(iter(d.atoms(sp.DiracDelta, sp.Heaviside, sp.Derivative, sp.Subs, sp.sign)))).__name__}); "
                            "theta and theta' must be continuous")
    f = _numeric(derivs)
    grid = np.linspace(0.0, t_end, GRID)
    values = f(grid)
    _bad_values(values, grid, text)
    scale = [1.0 + float(np.max(np.abs(np.real(v)))) for v in values]

    def switches(g):
        """Zeros of g(t) on (0, t_end), located by bisection on the grid's sign changes."""
        gv = np.real(np.asarray(_numeric([g])(grid)[0], dtype=complex))
        s = np.sign(gv)
        idx = np.nonzero((s[:-1] * s[1:] < 0) | ((s[1:] == 0) & (s[:-1] != 0)))[0]
        if len(idx) > MAX_SWITCHES:
            raise SpecError(f"theta(t) = '{text}': switches more than {MAX_SWITCHES} times on [0, t_end]")
        lo, hi = grid[idx], grid[idx + 1]
        glo = gv[idx]
        gfn = _numeric([g])
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            gm = np.real(np.asarray(gfn(mid)[0], dtype=complex))
            left = np.sign(gm) == np.sign(glo)
            lo, hi = np.where(left, mid, lo), np.where(left, hi, mid)
        return 0.5 * (lo + hi)

    for pw in expr.atoms(sp.Piecewise):
        for _, cond in pw.args:
            for rel in cond.atoms(sp.core.relational.Relational):
                for ts in switches(rel.lhs - rel.rhs):
                    delta = 1e-7 * max(1.0, abs(ts))
                    if ts <= delta or ts >= t_end - delta:
                        continue
                    l, r = f(np.array([ts - delta])), f(np.array([ts + delta]))
                    _bad_values(l, [ts], text)
                    _bad_values(r, [ts], text)
                    for k in (0, 1):
                        jump = abs(float(np.real(r[k][0] - l[k][0])))
                        slope = max(abs(float(np.real(l[k + 1][0]))), abs(float(np.real(r[k + 1][0]))))
                        if jump - 2 * delta * slope > 1e-6 * scale[k]:
                            raise SpecError(
                                f"theta(t) = '{text}': {NAMES[k]} jumps by {jump:.3g} at t = {ts:.6g} s; "
                                "theta and theta' must be continuous (theta'' is a load on the beam: "
                                "a jump in theta' would be an impulse)")
    for g, what in _singular_points(expr):
        for ts in switches(g):
            if 0.0 < ts < t_end:
                raise SpecError(f"theta(t) = '{text}': singular at t = {ts:.6g} s ({what})")


def check_time_function(expr: sp.Expr, t_end: float, text: str, label: str) -> None:
    """A function of t alone (a motor's torque at a fixed state) on [0, t_end]: real and finite
    on check_theta's grid, and no pole (a zero of a denominator, of cos under tan, of the
    argument of log or of a fractional power, found as a sign change on the grid)."""
    grid = np.linspace(0.0, float(t_end), GRID)
    try:
        v = np.asarray(_numeric([expr])(grid)[0])
        bad = ~np.isfinite(v) if v.dtype != object else np.ones(v.shape, bool)
        if np.iscomplexobj(v):
            bad |= np.imag(v) != 0
        if np.any(bad):
            k = int(np.argmax(bad))
            raise SpecError(f"{label} = '{text}' is not real and finite at t = {grid[k]:.6g} s (it "
                            "must be on [0, t_end])")
        for g, what in _singular_points(expr):
            gv = np.real(np.asarray(_numeric([g])(grid)[0], dtype=complex))
            idx = np.nonzero((np.sign(gv[:-1]) * np.sign(gv[1:]) < 0) | (gv == 0)[1:])[0]
            if len(idx):
                raise SpecError(f"{label} = '{text}': singular near t = {grid[idx[0] + 1]:.6g} s ({what})")
    except SpecError:
        raise
    except _SYMPY_ERRORS + (NameError, KeyError) as exc:
        raise SpecError(f"{label} = '{text}': cannot be evaluated ({type(exc).__name__}: {exc})") from None


def _singular_points(expr):
    """Expressions whose zeros are poles or branch points of theta or its derivatives."""
    for node in sp.preorder_traversal(expr):
        if isinstance(node, sp.Pow) and node.exp.is_Number and (node.exp < 0 or not node.exp.is_integer):
            if node.base.has(t):
                yield node.base, f"a zero of {node.base}"
        elif isinstance(node, sp.tan) and node.args[0].has(t):
            yield sp.cos(node.args[0]), f"a pole of {node}"
        elif isinstance(node, sp.log) and node.args[0].has(t):
            yield node.args[0], f"a zero of the argument of {node}"


def maneuver_of(name: str) -> Maneuver:
    """A named manoeuvre, or 'expression:<theta(t)>'."""
    if name.startswith(EXPRESSION_PREFIX):
        text = name[len(EXPRESSION_PREFIX):]
        return Maneuver("expression", (), parse_theta(text), f"theta(t) = {text}")
    if name not in MANEUVERS:
        raise SpecError(f"unknown manoeuvre '{name}' (known: {', '.join(MANEUVERS)}, or "
                        f"{EXPRESSION_PREFIX}<theta(t)>)")
    return MANEUVERS[name]
