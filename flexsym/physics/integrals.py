"""Modal integrals: integrals over s in [0, 1] of products of mode-shape functions.

Energy densities are polynomials in *factor* placeholders (a mode shape or one of its
s-derivatives, or the foreshortening kernel H_ij(s) = int_0^s b_i' b_j' ds) and in s.
Each distinct monomial of factors becomes one integral symbol J[...]; its value is

* exact (sympy closed form) when every factor is built from exact modes
  (polynomials and sin(k pi s)), or
* Gauss-Legendre quadrature in mpmath at QUAD_DPS digits, with the node count doubled
  until two successive rules agree to QUAD_TOL of the integrand's scale; the estimate is
  recorded and a value whose estimate exceeds REL_TOL is refused.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import mpmath
import sympy as sp
from sympy.simplify.fu import TR8

from flexsym.core.errors import FlexsymError
from flexsym.model.exact_numbers import exact
from flexsym.model.modes import Mode, s

QUAD_DPS = 34
QUAD_TOL = mpmath.mpf("1e-20")  # target agreement of successive rules (relative to scale)
ZERO_TOL = mpmath.mpf("1e-25")  # |value| below this (relative to scale) is an exact zero
REL_TOL = 1e-13  # refuse any integral whose error estimate is larger than this
N_START = 24
N_MAX = 384


@dataclass(frozen=True, order=True)
class Factor:
    """A function of s: d^order/ds^order of mode `a`, or (kind 'fs') H_ab(s)."""

    kind: str  # 'mode' | 'fs' | 'weight' (a section distribution of a body: mu, ea, ei, nhat, rot)
    a: str
    b: str = ""
    order: int = 0

    @property
    def label(self) -> str:
        if self.kind == "fs":
            return f"H[{self.a},{self.b}]"
        if self.kind == "weight":
            return self.a
        return "phi_" + self.a + "'" * self.order


@dataclass(frozen=True)
class IntegralValue:
    value: mpmath.mpf
    method: str  # 'exact' | 'gauss'
    error: float  # estimated absolute error (0 for exact)
    scale: float  # int |integrand| ds, for relative statements
    exact: sp.Expr | None = None
    nodes: int = 0

    @property
    def rel_error(self) -> float:
        return self.error / self.scale if self.scale else 0.0


@lru_cache(maxsize=None)
def gauss_legendre(n: int) -> tuple[tuple[mpmath.mpf, ...], tuple[mpmath.mpf, ...]]:
    """Nodes and weights on [0, 1] at QUAD_DPS digits (Newton on P_n from Chebyshev guesses)."""
    with mpmath.workdps(QUAD_DPS + 10):
        xs, ws = [], []
        for i in range(1, n + 1):
            x = mpmath.cos(mpmath.pi * (i - mpmath.mpf(1) / 4) / (n + mpmath.mpf(1) / 2))
            for _ in range(100):
                p0, p1 = mpmath.mpf(1), x
                for k in range(2, n + 1):
                    p0, p1 = p1, ((2 * k - 1) * x * p1 - (k - 1) * p0) / k
                dp = n * (x * p1 - p0) / (x * x - 1)
                dx = p1 / dp
                x -= dx
                if abs(dx) < mpmath.mpf(10) ** (-(QUAD_DPS + 8)):
                    break
            p0, p1 = mpmath.mpf(1), x
            for k in range(2, n + 1):
                p0, p1 = p1, ((2 * k - 1) * x * p1 - (k - 1) * p0) / k
            dp = n * (x * p1 - p0) / (x * x - 1)
            xs.append((1 - x) / 2)
            ws.append(1 / ((1 - x * x) * dp * dp))
        return tuple(xs), tuple(ws)


class IntegralTable:
    """Creates integral symbols for factor monomials and evaluates them on demand."""

    def __init__(self, modes: dict[str, Mode]):
        self.modes = modes
        self._placeholders: dict[Factor, sp.Symbol] = {}
        self._factor_of: dict[sp.Symbol, Factor] = {}
        self._symbols: dict[tuple, sp.Symbol] = {}
        self._monomial_of: dict[sp.Symbol, tuple] = {}
        self._values: dict[sp.Symbol, IntegralValue] = {}
        self._terms_of: dict[sp.Expr, list[tuple[list, sp.Expr]]] = {}  # _terms, per density
        self._numeric_cache: dict[tuple, list] = {}
        self._floats: dict[sp.Symbol, sp.Float] = {}  # substitutions()
        self._fs_series: dict[Factor, list | None] = {}  # _fs_samples

    # ----- placeholders used while building energy densities ---------------------------
    def factor(self, f: Factor) -> sp.Symbol:
        if f.kind == "fs" and f.b < f.a:  # H is symmetric: one placeholder per pair
            f = Factor("fs", f.b, f.a)
        sym = self._placeholders.get(f)
        if sym is None:
            sym = sp.Symbol(f.label, real=True)
            self._placeholders[f] = sym
            self._factor_of[sym] = f
        return sym

    def mode_value(self, name: str, order: int = 0) -> sp.Symbol:
        return self.factor(Factor("mode", name, "", order))

    def fs_value(self, a: str, b: str) -> sp.Symbol:
        return self.factor(Factor("fs", a, b))

    @property
    def placeholders(self) -> list[sp.Symbol]:
        return list(self._placeholders.values())

    # ----- section distributions (relative to the reference section p = [rho, E, A, I, L]) --
    def weight(self, kind: str) -> sp.Expr:
        """mu = rho A, ea = E A, ei = E I, nhat = centrifugal prestress N / (rho A w^2 L^2 / 2),
        rot = rotary inertia of point masses: for the uniform beam 1, 1, 1, 1 - s^2, 0; a
        spatial beam's eiy = E I_y, gj = G J, ip = rho (I_y + I_z): 1."""
        return UNIFORM_WEIGHTS[kind]

    def weight_at(self, kind: str, at, side: int = 0) -> sp.Expr:
        """The weight at s = at (side: a body's, BodyIntegralTable.weight_at)."""
        return UNIFORM_WEIGHTS[kind].subs(s, at) if kind == "nhat" else UNIFORM_WEIGHTS[kind]

    # ----- integration of a density ---------------------------------------------------
    def integrate(self, density: sp.Expr, a=0, b=1, closed=None) -> sp.Expr:
        """int_a^b density ds, with each factor monomial replaced by its integral symbol. A
        body's point masses count in (a, b], and at a = 0; closed (True, False) says whether
        one at a counts instead (a section's side: system.loads_at)."""
        return sp.Add(*[k * sp.Add(*v) for k, v in self._grouped(density, a, b, closed).items()])

    def integrate_values(self, density: sp.Expr, a=0, b=1, closed=None) -> sp.Expr:
        """integrate() with each integral symbol's value in place: the same expression as
        integrate(...).xreplace(substitutions()), built without rebuilding its whole tree
        (which took a spatial beam's section outputs a third of their time)."""
        groups = self._grouped(density, a, b, closed)
        values = self.substitutions()
        return sp.Add(*[values.get(k, k) * sp.Add(*v) for k, v in groups.items()])

    def _grouped(self, density: sp.Expr, a, b, closed=None) -> dict[sp.Expr, list[sp.Expr]]:
        """The rest of each term of the density, grouped by its monomial's integral symbol."""
        a, b = exact(a), exact(b)
        groups: dict[sp.Expr, list[sp.Expr]] = {}
        for key_parts, rest in self._terms(density):
            groups.setdefault(self.monomial_symbol(key_parts, a, b, closed), []).append(rest)
        return groups

    def _terms(self, density: sp.Expr) -> list[tuple[list, sp.Expr]]:
        """(factor monomial, the rest) of each term of the expanded density. Kept per density:
        section outputs integrate one density from several stations, and its expansion is what
        costs (seconds for a spatial beam's moment)."""
        memo = self._terms_of
        if density not in memo:
            terms = []
            for term in sp.Add.make_args(sp.expand(density)):
                key_parts, rest = [], []
                for base, exp in term.as_powers_dict().items():
                    if base == s or base in self._factor_of:
                        key_parts.append((base, exp))
                    else:
                        rest.append(base**exp)
                terms.append((key_parts, sp.Mul(*rest)))
            memo[density] = terms
        return memo[density]

    def monomial_symbol(self, parts, a=0, b=1, closed=None) -> sp.Expr:
        """The symbol of int_a^b s^k * prod(factors) ds (a, b exact fractions of the length);
        closed: integrate's."""
        a, b = exact(a), exact(b)
        s_pow = 0
        factors: list[Factor] = []
        for base, exp in parts:
            if base == s:
                s_pow += int(exp)
            else:
                factors.extend([self._factor_of[base]] * int(exp))
        if not factors:
            return (b**(s_pow + 1) - a**(s_pow + 1)) / (s_pow + 1)
        key = (a, b, s_pow, tuple(sorted(factors)))
        if closed is not None and closed != (a == 0):  # the point masses at a otherwise than by default
            key += (closed,)
        sym = self._symbols.get(key)
        if sym is None:
            label = "*".join(([f"s^{s_pow}"] if s_pow > 1 else ["s"] if s_pow == 1 else [])
                             + [f.label for f in key[3]])
            interval = ("" if (a, b) == (0, 1) else f"({a},{b})") if len(key) == 4 else \
                f"{'[' if closed else '('}{a},{b}]"
            sym = sp.Symbol(f"J{interval}[{label}]", real=True)
            self._symbols[key] = sym
            self._monomial_of[sym] = key
        return sym

    @property
    def symbols(self) -> list[sp.Symbol]:
        return list(self._symbols.values())

    def monomial(self, sym: sp.Symbol) -> tuple:
        return self._monomial_of[sym]

    # ----- values ---------------------------------------------------------------------
    def value(self, sym: sp.Symbol) -> IntegralValue:
        v = self._values.get(sym)
        if v is None:
            v = self._evaluate(*self._monomial_of[sym])
            if v.rel_error > REL_TOL:
                raise FlexsymError(f"modal integral {sym} did not converge: estimated relative "
                                   f"error {v.rel_error:.1e} > {REL_TOL:.0e}")
            self._values[sym] = v
        return v

    def substitutions(self) -> dict[sp.Symbol, sp.Float]:
        """Every integral symbol made so far, with its value (kept: asked after each integral)."""
        floats = self._floats
        for sym in self._symbols.values():
            if sym not in floats:
                floats[sym] = sp.Float(self.value(sym).value, QUAD_DPS)
        return dict(floats)

    def _exact_factor(self, f: Factor) -> sp.Expr | None:
        if f.kind == "mode":
            m = self.modes[f.a]
            return m.derivative(f.order) if m.exact else None
        ma, mb = self.modes[f.a], self.modes[f.b]
        if not (ma.exact and mb.exact):
            return None
        sig = sp.Symbol("sigma", real=True)
        integrand = (sp.diff(ma.expr, s) * sp.diff(mb.expr, s)).subs(s, sig)
        return _integrate_exact(integrand, sig, 0, s)

    def _evaluate(self, a, b, s_pow: int, factors: tuple[Factor, ...], closed=None) -> IntegralValue:
        exact = [self._exact_factor(f) for f in factors]  # (no point masses: closed changes nothing)
        if all(e is not None for e in exact):
            expr = _integrate_exact(s**s_pow * sp.Mul(*exact), s, a, b)
            with mpmath.workdps(QUAD_DPS):
                val = mpmath.mpf(sp.N(expr, QUAD_DPS + 5))
                xs, ws = _nodes(N_START, a, b)
                fn = sp.lambdify(s, s**s_pow * sp.Mul(*exact), "mpmath")
                scale = float(mpmath.fsum(w * abs(fn(x)) for x, w in zip(xs, ws)))
            return IntegralValue(val, "exact", 0.0, scale or float(abs(val)), expr)
        return self._gauss(a, b, s_pow, factors)

    def _samples(self, f: Factor, n: int, a, b) -> list:
        """The factor at the n Gauss nodes of [a, b] (H_ab by an inner rule on [0, x])."""
        key = (f, n, a, b)
        cached = self._numeric_cache.get(key)
        if cached is not None:
            return cached
        xs, _ = _nodes(n, a, b)
        with mpmath.workdps(QUAD_DPS):
            if f.kind == "mode":
                fn = sp.lambdify(s, self.modes[f.a].derivative(f.order), "mpmath")
                vals = [fn(x) for x in xs]
            else:
                vals = self._fs_samples(f, xs)
        self._numeric_cache[key] = vals
        return vals

    def _fs_samples(self, f: Factor, xs) -> list:
        """H_ab at xs: the antiderivative of a Chebyshev series of b_a' b_b' (CHEB_DEGREES:
        the first whose tail is below CHEB_TAIL of its largest coefficient), which costs a few
        products per node where an inner rule on [0, x] costs its node count n (the first took
        a minute of a spatial beam's section outputs); an inner rule at the outer node count
        where no degree converges."""
        def slopes():
            return (sp.lambdify(s, sp.diff(self.modes[m].expr, s), "mpmath") for m in (f.a, f.b))
        with mpmath.workdps(QUAD_DPS + 10):
            if f not in self._fs_series:  # once per pair: every station's nodes read it
                da, db = slopes()
                self._fs_series[f] = next(
                    (c for c in (chebyshev_antiderivative(lambda x: da(x) * db(x), degree)
                                 for degree in CHEB_DEGREES) if c is not None), None)
            series = self._fs_series[f]
            if series is not None:
                return [clenshaw(series, 2 * x - 1) for x in xs]
            da, db = slopes()
            ixs, iws = gauss_legendre(len(xs))
            return [x * mpmath.fsum(w * da(x * y) * db(x * y) for y, w in zip(ixs, iws)) for x in xs]

    def _gauss(self, a, b, s_pow: int, factors: tuple[Factor, ...]) -> IntegralValue:
        prev = None
        n = N_START
        while n <= N_MAX:
            xs, ws = _nodes(n, a, b)
            cols = [self._samples(f, n, a, b) for f in factors]
            with mpmath.workdps(QUAD_DPS):
                terms = []
                for k, (x, w) in enumerate(zip(xs, ws)):
                    p = w * x**s_pow
                    for c in cols:
                        p *= c[k]
                    terms.append(p)
                val = mpmath.fsum(terms)
                scale = mpmath.fsum(abs(t) for t in terms)
            if prev is not None:
                err = abs(val - prev)
                if err <= QUAD_TOL * scale:
                    if abs(val) <= ZERO_TOL * scale:  # orthogonal modes: zero to ~25 digits
                        val = mpmath.mpf(0)
                    return IntegralValue(val, "gauss", float(err), float(scale), None, n)
            prev = val
            n *= 2
        return IntegralValue(val, "gauss", float(abs(val - prev)), float(scale), None, n // 2)


UNIFORM_WEIGHTS = {"mu": sp.Integer(1), "ea": sp.Integer(1), "ei": sp.Integer(1),
                   "nhat": 1 - s**2, "rot": sp.Integer(0),
                   # a spatial beam's: E I_y, G J, the sections' spin inertia rho (I_y + I_z)
                   "eiy": sp.Integer(1), "gj": sp.Integer(1), "ip": sp.Integer(1)}


class BodyIntegralTable(IntegralTable):
    """The same named invariants for a body from finite-element data: weights are the body's
    section distributions (point masses as Dirac terms of mu and rot), modes are piecewise
    polynomial (element interpolation), so Gauss-Legendre per element is exact; values are
    doubles (eigenvectors), rounded to fedata.SIG_DIGITS significant digits."""

    def __init__(self, body, modes):
        super().__init__(modes)
        self.body = body

    def weight(self, kind: str) -> sp.Expr:
        if kind == "rot" and not any(m.rotary for m in self.body.masses):
            return sp.Integer(0)
        return self.factor(Factor("weight", kind))

    def weight_at(self, kind: str, at, side: int = 0) -> sp.Expr:
        """The weight at s = at: at a node, the element's beyond it for side +1, else the
        one before."""
        import numpy as np

        from flexsym.model import fedata

        body, x = self.body, float(at)
        if kind == "nhat":
            return sp.Float(repr(fedata.round_sig(float(fedata.nhat(body, x)[0]))), 17)
        if kind == "rot":
            return sp.Integer(0)
        e = int(fedata.locate(body, np.array([x]), 1 if side > 0 else -1)[0])
        return sp.Float(repr(float(body.ratios()[kind][e])), 17)

    def _factor_values(self, f: Factor, elem, pts):
        """The factor at points pts, each inside element elem[i]."""
        import numpy as np

        from flexsym.model import fedata

        body = self.body
        if f.kind == "weight":
            if f.a == "nhat":
                return fedata.nhat(body, pts, elem)
            if f.a == "rot":
                return np.zeros_like(pts)
            return body.ratios()[f.a][elem]
        if f.kind == "mode":
            m = self.modes[f.a]
            return fedata.evaluate(body, m.shape, f.order, pts, elem)
        # H_ab(s) = int_0^s a' b': whole elements before, then a Gauss rule on [s_e, s]
        ma, mb = self.modes[f.a], self.modes[f.b]
        sn = body.s_nodes
        gx, gw = fedata.gauss()
        ne = body.elements
        ee = np.arange(ne)
        inner = sn[:-1, None] + (sn[1:] - sn[:-1])[:, None] * gx[None, :]
        eg = np.repeat(ee, len(gx))
        prod = (fedata.evaluate(body, ma.shape, 1, inner.ravel(), eg)
                * fedata.evaluate(body, mb.shape, 1, inner.ravel(), eg)).reshape(ne, -1)
        whole = (prod * gw[None, :]).sum(axis=1) * (sn[1:] - sn[:-1])
        start = np.concatenate([[0.0], np.cumsum(whole)[:-1]])
        s0 = sn[elem]
        sub = s0[:, None] + (pts - s0)[:, None] * gx[None, :]
        es = np.repeat(elem, len(gx))
        p2 = (fedata.evaluate(body, ma.shape, 1, sub.ravel(), es)
              * fedata.evaluate(body, mb.shape, 1, sub.ravel(), es)).reshape(len(pts), -1)
        return start[elem] + (p2 * gw[None, :]).sum(axis=1) * (pts - s0)

    def _evaluate(self, a, b, s_pow: int, factors: tuple[Factor, ...], closed=None) -> IntegralValue:
        import numpy as np

        from flexsym.model import fedata

        body = self.body
        a, b = float(a), float(b)
        sn = body.s_nodes
        gx, gw = fedata.gauss()
        lo, hi = np.maximum(a, sn[:-1]), np.minimum(b, sn[1:])
        elems = np.nonzero(hi > lo)[0]
        pts = (lo[elems, None] + (hi - lo)[elems, None] * gx[None, :]).ravel()
        wts = ((hi - lo)[elems, None] * gw[None, :]).ravel()
        elem = np.repeat(elems, len(gx))
        terms = wts * pts**s_pow
        for f in factors if len(pts) else ():  # (a = b: no element, the point masses alone)
            terms = terms * self._factor_values(f, elem, pts)
        total, scale = float(terms.sum()), float(np.abs(terms).sum())
        # point masses (Dirac terms of mu and rot) in (a, b], and at a if closed (by default
        # at a = 0)
        weights = [f.a for f in factors if f.kind == "weight" and f.a in ("mu", "rot")]
        at_a = a == 0.0 if closed is None else closed
        if weights:
            ref, L = body.reference, body.length
            for pm in body.masses:
                sk = pm.x / L
                if not (a < sk <= b or (sk == a and at_a)):
                    continue
                c = (pm.mass / (ref.rho * ref.A * L) if weights[0] == "mu"
                     else pm.rotary / (ref.rho * ref.A * L**3))
                at = np.array([sk])
                el = fedata.locate(body, at)
                term = c * sk**s_pow
                for f in factors:
                    if f.kind != "weight":
                        term = term * float(self._factor_values(f, el, at)[0])
                total += term
                scale += abs(term)
        value = fedata.round_sig(total)
        if abs(total) <= fedata.ORTHO_TOL * scale:
            value = 0.0
        return IntegralValue(mpmath.mpf(repr(value)), "fe_gauss", 1e-15 * scale, scale or 1.0,
                             None, fedata.GAUSS_POINTS)


CHEB_DEGREES = (64, 128, 256)
CHEB_TAIL = mpmath.mpf("1e-32")


def chebyshev_antiderivative(g, degree: int):
    """Coefficients C_k (of T_k(t), x = (1 + t)/2) of G(x) = int_0^x g, from g's interpolant at
    the degree + 1 Chebyshev points of [0, 1]; None when the interpolant's last eight
    coefficients exceed CHEB_TAIL of its largest (g not resolved at this degree)."""
    D = degree
    cosines = [mpmath.cos(mpmath.pi * m / D) for m in range(2 * D)]
    vals = [g((1 + cosines[j]) / 2) for j in range(D + 1)]
    vals[0], vals[D] = vals[0] / 2, vals[D] / 2
    c = [2 * mpmath.fsum(v * cosines[(j * k) % (2 * D)] for j, v in enumerate(vals)) / D
         for k in range(D + 1)]
    c[0], c[D] = c[0] / 2, c[D] / 2
    top = max(abs(x) for x in c)
    if top and max(abs(x) for x in c[-8:]) > CHEB_TAIL * top:
        return None
    # int T_0 = T_1, int T_1 = T_2 / 4, int T_k = T_(k+1) / (2(k+1)) - T_(k-1) / (2(k-1)); dx = dt / 2
    C = [mpmath.mpf(0)] * (D + 2)
    C[1] += c[0]
    C[2] += c[1] / 4
    for k in range(2, D + 1):
        C[k + 1] += c[k] / (2 * (k + 1))
        C[k - 1] -= c[k] / (2 * (k - 1))
    C = [x / 2 for x in C]
    C[0] = -mpmath.fsum(x * (-1) ** k for k, x in enumerate(C))  # G(0) = 0: T_k(-1) = (-1)^k
    return C


def clenshaw(coeffs, t):
    """sum_k coeffs[k] T_k(t)."""
    b1 = b2 = mpmath.mpf(0)
    for ck in reversed(coeffs[1:]):
        b1, b2 = 2 * t * b1 - b2 + ck, b1
    return t * b1 - b2 + coeffs[0]


def _nodes(n: int, a, b):
    """Gauss-Legendre nodes and weights mapped from [0, 1] to [a, b]."""
    xs, ws = gauss_legendre(n)
    if (a, b) == (0, 1):
        return xs, ws
    with mpmath.workdps(QUAD_DPS + 10):
        A, B = mpmath.mpf(sp.Rational(a).p) / sp.Rational(a).q, mpmath.mpf(sp.Rational(b).p) / sp.Rational(b).q
        return tuple(A + (B - A) * x for x in xs), tuple((B - A) * w for w in ws)


def _integrate_exact(expr: sp.Expr, var: sp.Symbol, a, b) -> sp.Expr:
    """Term-by-term closed-form integral of a product of polynomials and sin/cos(k pi s)."""
    total = sp.Integer(0)
    expr = sp.expand(TR8(sp.expand(expr))) if expr.has(sp.sin, sp.cos) else sp.expand(expr)
    for term in sp.Add.make_args(expr):
        anti = sp.integrate(term, var)
        if anti.has(sp.Integral):
            raise FlexsymError(f"sympy could not integrate {term} exactly")
        total += anti.subs(var, b) - anti.subs(var, a)
    return sp.expand(total)
