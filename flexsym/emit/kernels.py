"""Derived sympy expressions -> casadi SX functions (the kernels), with CSE.

Codegen only: it knows no physics. A derivation hands it sympy expressions and the symbols
that stand for the kernel inputs (which kernels a model has is sysgen.py's; `translator`
serves exact.py's one-beam derivation and its quadrature check); cemit.py prints the casadi
functions as C.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import sympy as sp

from flexsym.model.maneuver import t as t_sym


@dataclass(frozen=True)
class Port:
    name: str
    rows: int
    cols: int = 1

    @property
    def size(self) -> int:
        return self.rows * self.cols


@dataclass
class Kernel:
    name: str
    doc: str
    inputs: tuple[Port, ...]
    outputs: tuple[Port, ...]
    function: ca.Function


class SympyToCasadi:
    """Translate sympy expressions to casadi SX, sharing every repeated sub-expression.

    Products are built with parameters first, then drive inputs, then coordinates, and the
    numeric coefficient last, so that prefixes like rho*A*L*w^2 are computed once.
    """

    def __init__(self, symbols: dict[sp.Symbol, ca.SX], priority: dict[sp.Symbol, int]):
        self.symbols = symbols
        self.priority = priority
        self.memo: dict = {}
        # e -> SX or None: the value of what is neither a symbol nor a known function (an
        # applied function placeholder or its Derivative: sysgen.placeholder_values)
        self.resolve = None

    def __call__(self, expr) -> ca.SX:
        key = expr if isinstance(expr, tuple) else (expr,)
        hit = self.memo.get(key)
        if hit is None:
            hit = self._tr(expr)
            self.memo[key] = hit
        return hit

    def _product(self, factors: tuple) -> ca.SX:
        if len(factors) == 1:
            return self(factors[0])
        return self(factors[:-1]) * self(factors[-1])

    def _tr(self, e):
        if isinstance(e, tuple):  # a product prefix
            return self._product(e)
        if e.is_Number or e in (sp.pi, sp.E):
            val = float(e)
            if not math.isfinite(val):
                raise ValueError(f"non-finite constant {e} in a kernel")
            return ca.SX(val)
        if e.is_Symbol:
            if e not in self.symbols:
                raise ValueError(f"unexpected symbol {e} in a kernel expression")
            return self.symbols[e]
        if e.is_Add:
            terms = [self(a) for a in e.args]
            acc = terms[0]
            for x in terms[1:]:
                acc = acc + x
            return acc
        if e.is_Mul:
            coeff, rest = e.as_coeff_mul()
            rest = tuple(sorted(rest, key=lambda f: (self._rank(f), sp.default_sort_key(f))))
            body = self._product(rest) if rest else ca.SX(1.0)
            if coeff == 1:
                return body
            if coeff == -1:
                return -body
            return body * float(coeff)
        if e.is_Pow:
            base, ex = e.args
            b = self(base)
            if ex.is_Integer:
                n = int(ex)
                if n == 2:
                    return b * b
                if n == -1:
                    return 1 / b
                return b**n if n > 0 else 1 / (b**(-n))
            if ex.is_Rational and ex.q == 2:  # b^(k/2) = sqrt(b)^k: no pow() call
                r = ca.sqrt(b)
                k = abs(int(ex.p))
                acc = r
                for _ in range(k - 1):
                    acc = acc * r
                return acc if ex > 0 else 1 / acc
            return b**self(ex)
        if isinstance(e, sp.Piecewise):
            out = None
            for val, cond in reversed(e.args):
                v = self(val)
                out = v if (out is None and cond == sp.true) else ca.if_else(self(cond), v, out)
            return out
        # sympy folds the conditions of nested Piecewise (a max over several rows: the
        # violation) into ITE, And, Or
        if isinstance(e, sp.logic.boolalg.ITE):
            c, a, b = (self(x) for x in e.args)
            return ca.if_else(c, a, b)
        if isinstance(e, (sp.And, sp.Or)):
            join = ca.logic_and if isinstance(e, sp.And) else ca.logic_or
            out = self(e.args[0])
            for x in e.args[1:]:
                out = join(out, self(x))
            return out
        if isinstance(e, sp.Not):
            return ca.logic_not(self(e.args[0]))
        if e.is_Relational:
            a, b = self(e.lhs), self(e.rhs)
            return {"<": a < b, "<=": a <= b, ">": a > b, ">=": a >= b, "==": a == b,
                    "!=": a != b}[e.rel_op]
        fn = _FUNCS.get(type(e))
        if fn is not None:
            return fn(*[self(a) for a in e.args])
        value = self.resolve(e) if self.resolve is not None else None
        if value is not None:
            return value
        raise ValueError(f"cannot translate {type(e).__name__} ({e}) to casadi")

    def _rank(self, f) -> int:
        base = f.base if f.is_Pow else f
        return self.priority.get(base, 9)


_FUNCS = {sp.sin: ca.sin, sp.cos: ca.cos, sp.tan: ca.tan, sp.exp: ca.exp, sp.log: ca.log,
          sp.sinh: ca.sinh, sp.cosh: ca.cosh, sp.tanh: ca.tanh, sp.Abs: ca.fabs,
          sp.sign: ca.sign, sp.atan: ca.atan, sp.asin: ca.asin, sp.acos: ca.acos,
          sp.atan2: ca.atan2}


def group_by_parameters(expr: sp.Expr, params: list[sp.Symbol]) -> sp.Expr:
    """sum_k g_k(params) * poly_k(state): multiply by each parameter group once."""
    groups: dict[sp.Expr, list[sp.Expr]] = {}
    pset = set(params)
    for term in sp.Add.make_args(sp.expand(expr)):
        pp, rest = [], []
        for fac in sp.Mul.make_args(term):
            base = fac.base if fac.is_Pow else fac
            (pp if base in pset else rest).append(fac)
        groups.setdefault(sp.Mul(*pp), []).append(sp.Mul(*rest))
    return sp.Add(*[g * sp.Add(*v) for g, v in groups.items()], evaluate=False)


def matrix_sx(tr: SympyToCasadi, mat: sp.Matrix, params) -> ca.SX:
    rows = [[tr(group_by_parameters(mat[i, j], params)) for j in range(mat.cols)]
            for i in range(mat.rows)]
    return ca.vertcat(*[ca.horzcat(*r) for r in rows])


def translator(q_syms, qd_syms, qdd_syms, params, maneuver, drive) -> tuple[SympyToCasadi, dict]:
    """casadi inputs {q, qd, qdd, drive, p, t, mp} and a translator from the sympy symbols
    (drive: the symbols of the two drive inputs, a guided hub's rate and acceleration)."""
    n = len(q_syms)
    sx = {"q": ca.SX.sym("q", n), "qd": ca.SX.sym("qd", n), "qdd": ca.SX.sym("qdd", n),
          "drive": ca.SX.sym("drive", 2), "p": ca.SX.sym("p", len(params)), "t": ca.SX.sym("t"),
          "mp": ca.SX.sym("mp", len(maneuver.params))}
    symbols = {drive[0]: sx["drive"][0], drive[1]: sx["drive"][1], t_sym: sx["t"]}
    priority = {drive[0]: 1, drive[1]: 1}
    for i, ps in enumerate(params):
        symbols[ps] = sx["p"][i]
        priority[ps] = 0
    for i, mpar in enumerate(maneuver.params):
        symbols[mpar.symbol] = sx["mp"][i]
    for i in range(n):
        for key, syms in (("q", q_syms), ("qd", qd_syms), ("qdd", qdd_syms)):
            symbols[syms[i]] = sx[key][i]
            priority[syms[i]] = 2
    return SympyToCasadi(symbols, priority), sx


def make_kernels(specs) -> list[Kernel]:
    """specs: (name, doc, [(input name, SX)], [(output name, SX)]); CSE over all outputs."""
    kernels = []
    for name, doc, ins, outs in specs:
        out_exprs = [ca.densify(e) for _, e in outs]
        shared = ca.cse(ca.vertcat(*[ca.vec(e) for e in out_exprs]))
        offs, pieces = 0, []
        for e in out_exprs:
            pieces.append(ca.reshape(shared[offs:offs + e.numel()], e.shape))
            offs += e.numel()
        fn = ca.Function(name, [x for _, x in ins], pieces, [a for a, _ in ins], [a for a, _ in outs])
        kernels.append(Kernel(name, doc, tuple(Port(a, x.shape[0], x.shape[1]) for a, x in ins),
                              tuple(Port(a, e.shape[0], e.shape[1]) for (a, _), e in zip(outs, out_exprs)),
                              fn))
    return kernels
