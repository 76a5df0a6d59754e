"""Guided root rotation theta(t): sympy expressions differentiated symbolically.

theta is a guided coordinate, so only its rate w = theta' and acceleration alpha = theta''
enter the equations of motion, as known inputs. The manoeuvre is generated as a kernel
(t, manoeuvre parameters) -> (theta, w, alpha) like every other kernel.
"""
from __future__ import annotations

import ast
import math
from dataclasses import dataclass

import sympy as sp

from .errors import SpecError

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
        """False when theta'' vanishes identically: the alpha terms are then dropped."""
        return sp.simplify(self.acceleration) != 0


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


def parse_theta(text: str) -> sp.Expr:
    """theta(t) from text: numbers, t, pi, e, + - * / **, the functions in _FUNCTIONS and
    ifelse(condition, a, b) with a comparison as condition. Raises SpecError otherwise."""
    if not isinstance(text, str) or not text.strip():
        raise SpecError("theta(t) expression is empty")
    if len(text) > 2000:
        raise SpecError("theta(t) expression is longer than 2000 characters")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        raise SpecError(f"cannot parse theta(t) = '{text}': {exc.msg} at column {exc.offset}") from None
    if sum(1 for _ in ast.walk(tree)) > MAX_NODES:
        raise SpecError(f"theta(t) expression has more than {MAX_NODES} syntax nodes")
    expr = _build(tree.body, text)
    extra = expr.free_symbols - {t}
    if extra:
        raise SpecError(f"theta(t) = '{text}' depends on {', '.join(sorted(map(str, extra)))}, not only t")
    return expr


def _build(node, text):
    def bad(what):
        return SpecError(f"theta(t) = '{text}': {what} is not allowed (use numbers, t, pi, e, "
                         f"+ - * / **, ifelse(cond, a, b) and {', '.join(_FUNCTIONS)})")

    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)) \
                or not math.isfinite(node.value):
            raise bad(f"the constant {node.value!r}")
        return sp.nsimplify(node.value) if isinstance(node.value, int) else sp.Float(repr(node.value))
    if isinstance(node, ast.Name):
        if node.id == "t":
            return t
        if node.id in _CONSTANTS:
            return _CONSTANTS[node.id]
        raise bad(f"the name '{node.id}'")
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        val = _build(node.operand, text)
        return -val if isinstance(node.op, ast.USub) else val
    if isinstance(node, ast.BinOp):
        a, b = _build(node.left, text), _build(node.right, text)
        if isinstance(node.op, ast.Pow):
            if b.is_Number and abs(b) > MAX_EXPONENT:
                raise bad(f"the exponent {b}")
            return a**b
        op = _BINARY.get(type(node.op))
        if op is None:
            raise bad(f"the operator {type(node.op).__name__}")
        return op(a, b)
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and not node.keywords:
        name, args = node.func.id, node.args
        if name == "ifelse" and len(args) == 3:
            cond = args[0]
            if not (isinstance(cond, ast.Compare) and len(cond.ops) == 1
                    and type(cond.ops[0]) in _COMPARE):
                raise bad("an ifelse condition other than one comparison (<, <=, >, >=)")
            c = _COMPARE[type(cond.ops[0])](_build(cond.left, text), _build(cond.comparators[0], text))
            return sp.Piecewise((_build(args[1], text), c), (_build(args[2], text), True))
        if name in _FUNCTIONS and len(args) == 1:
            return _FUNCTIONS[name](_build(args[0], text))
        raise bad(f"the call {name}(...) with {len(args)} argument(s)")
    raise bad(f"a {type(node).__name__}")


def maneuver_of(name: str) -> Maneuver:
    """A named manoeuvre, or 'expression:<theta(t)>'."""
    if name.startswith(EXPRESSION_PREFIX):
        text = name[len(EXPRESSION_PREFIX):]
        return Maneuver("expression", (), parse_theta(text), f"theta(t) = {text}")
    if name not in MANEUVERS:
        raise SpecError(f"unknown manoeuvre '{name}' (known: {', '.join(MANEUVERS)}, or "
                        f"{EXPRESSION_PREFIX}<theta(t)>)")
    return MANEUVERS[name]
