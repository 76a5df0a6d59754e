"""Mode library: assumed deformation shapes of the beam, as sympy functions of s = x/L.

Every mode is dimensionless; its amplitude (the generalised coordinate) is in metres.
A mode knows its axis (axial: contributes to u_o, bending: contributes to v_o), its
family, its boundary conditions (checked by the tests), and whether its shape is
"exact" (polynomial or sin(k*pi*s): modal integrals can be done by sympy in closed form)
or transcendental with numerically solved eigenvalues (integrals by Gauss quadrature).
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache

import mpmath
import sympy as sp

from flexsym.core.errors import SpecError

s = sp.Symbol("s", real=True)

# Digits kept for solved eigenvalues: far beyond double precision, so that mode shapes
# evaluated at quadrature points carry no eigenvalue error into the modal integrals.
EIGEN_DPS = 40


@dataclass(frozen=True, order=True)
class ModeRef:
    """A mode by name: axis ('axial' | 'bending'), family and 1-based index."""

    axis: str
    family: str
    index: int = 1

    @property
    def token(self) -> str:
        """Short name used on the command line and in coordinate names."""
        fam = FAMILIES.get((self.axis, self.family))
        if fam is None:  # a shape built outside the library (tests, element shape functions)
            return f"{self.family}{self.index}"
        return fam.short if fam.single else f"{fam.short}{self.index}"

    @property
    def coordinate(self) -> str:
        return ("u_" if self.axis == "axial" else "v_") + self.token


@dataclass(frozen=True)
class BoundaryCondition:
    """d^order/ds^order of the mode at s equals value."""

    order: int
    at: int  # 0 (root) or 1 (tip)
    value: int

    def describe(self, field: str) -> str:
        ticks = "'" * self.order
        return f"{field}{ticks}({self.at}) = {self.value}"


@dataclass(frozen=True)
class Mode:
    ref: ModeRef
    expr: sp.Expr  # shape as a function of s
    exact: bool  # closed-form modal integrals are possible
    bcs: tuple[BoundaryCondition, ...]
    latex: str
    description: str
    eigenvalue: sp.Float | None = None  # beta for beam modes, None otherwise

    @property
    def name(self) -> str:
        return self.ref.coordinate

    def derivative(self, order: int) -> sp.Expr:
        return _derivative(self, order) if order else self.expr

    def value_at(self, order: int, at, side: int = 0) -> sp.Expr:
        """d^order/ds^order at s = at; a boundary condition gives the exact value (side: a
        mode from finite-element data's, fedata.BodyMode; an analytic shape is smooth)."""
        return _value_at(self, order, at)

    def _value_at(self, order: int, at) -> sp.Expr:
        for bc in self.bcs:
            if bc.order == order and bc.at == at:
                return sp.Integer(bc.value)
        v = self.derivative(order).subs(s, at)
        return sp.simplify(v) if self.exact else sp.Float(sp.N(v, EIGEN_DPS - 6), EIGEN_DPS - 6)


# A derivation asks for the same few shapes' derivatives and station values thousands of times
# (each spatial section output reads every field at its station): each is worked out once.
@lru_cache(maxsize=None)
def _derivative(m: Mode, order: int) -> sp.Expr:
    return sp.diff(m.expr, s, order)


@lru_cache(maxsize=None, typed=True)  # a Rational station is not its Float
def _value_at(m: Mode, order: int, at) -> sp.Expr:
    return m._value_at(order, at)


@dataclass(frozen=True)
class Family:
    axis: str
    name: str
    short: str
    single: bool  # only index 1 exists (static modes)
    build: object  # callable(index) -> Mode
    summary: str


def _bc(*triples) -> tuple[BoundaryCondition, ...]:
    return tuple(BoundaryCondition(o, a, v) for (o, a, v) in triples)


def _to_float(x) -> sp.Float:
    return sp.Float(mpmath.nstr(x, EIGEN_DPS), EIGEN_DPS)


@lru_cache(maxsize=None)
def clamped_pinned_beta(k: int) -> mpmath.mpf:
    """k-th root of tan(b) = tanh(b), solved as sin(b)cosh(b) - cos(b)sinh(b) = 0 (no poles)."""
    with mpmath.workdps(EIGEN_DPS + 10):
        g = lambda b: mpmath.sin(b) * mpmath.cosh(b) - mpmath.cos(b) * mpmath.sinh(b)
        return +mpmath.findroot(g, (k + mpmath.mpf(1) / 4) * mpmath.pi)


@lru_cache(maxsize=None)
def clamped_free_beta(k: int) -> mpmath.mpf:
    """k-th root of 1 + cos(b)cosh(b) = 0, solved as cos(b) + 1/cosh(b) = 0."""
    with mpmath.workdps(EIGEN_DPS + 10):
        g = lambda b: mpmath.cos(b) + 1 / mpmath.cosh(b)
        return +mpmath.findroot(g, (k - mpmath.mpf(1) / 2) * mpmath.pi)


def _axial_static(k: int) -> Mode:
    return Mode(ModeRef("axial", "static", 1), s, True, _bc((0, 0, 0), (0, 1, 1)),
                r"\Phi_{1}", "static axial mode: unit axial tip displacement, root fixed")


def _axial_sine(k: int) -> Mode:
    return Mode(ModeRef("axial", "sine", k), sp.sin(k * sp.pi * s), True,
                _bc((0, 0, 0), (0, 1, 0)), rf"\chi_{{{k}}}",
                f"axial sine mode sin({k} pi s): zero at both ends (fixed-interface)")


def _axial_fixed_free(k: int) -> Mode:
    return Mode(ModeRef("axial", "fixed_free", k), sp.sin((2 * k - 1) * sp.pi * s / 2), True,
                _bc((0, 0, 0), (1, 1, 0)), rf"\Upsilon_{{{k}}}",
                f"natural axial mode {k} of the fixed-free bar")


def _bending_static(k: int) -> Mode:
    expr = sp.Rational(3, 2) * s**2 - sp.Rational(1, 2) * s**3
    return Mode(ModeRef("bending", "static", 1), expr, True,
                _bc((0, 0, 0), (1, 0, 0), (0, 1, 1), (2, 1, 0)), r"\Phi_{2}",
                "static bending mode: unit tip deflection, root clamped")


def _pinned_pinned(k: int) -> Mode:
    return Mode(ModeRef("bending", "pinned_pinned", k), sp.sin(k * sp.pi * s), True,
                _bc((0, 0, 0), (2, 0, 0), (0, 1, 0), (2, 1, 0)), rf"\Pi_{{{k}}}",
                f"pinned-pinned natural bending mode sin({k} pi s): the frame is the chord frame, "
                "the root slope free")


def _pinned_free(k: int) -> Mode:
    # tan(b) = tanh(b), as clamped-pinned: the pinned-free beam's elastic modes, orthogonal to
    # its rotation about the pin (s), so the frame is the one whose turn that rotation is
    with mpmath.workdps(EIGEN_DPS + 10):
        b = clamped_pinned_beta(k)
        c = mpmath.sin(b) / mpmath.sinh(b)
    B, C = _to_float(b), _to_float(c)
    expr = sp.sin(B * s) + C * sp.sinh(B * s)
    return Mode(ModeRef("bending", "pinned_free", k), expr, False,
                _bc((0, 0, 0), (2, 0, 0), (2, 1, 0), (3, 1, 0)), rf"\Omega_{{{k}}}",
                f"pinned-free natural bending mode {k} (beta = {mpmath.nstr(b, 15)}): the root "
                "slope free", B)


def _clamped_pinned(k: int) -> Mode:
    with mpmath.workdps(EIGEN_DPS + 10):
        b = clamped_pinned_beta(k)
        alpha = (mpmath.sin(b) - mpmath.sinh(b)) / (mpmath.cos(b) - mpmath.cosh(b))
    B, a = _to_float(b), _to_float(alpha)
    expr = sp.sin(B * s) - sp.sinh(B * s) + a * (sp.cosh(B * s) - sp.cos(B * s))
    return Mode(ModeRef("bending", "clamped_pinned", k), expr, False,
                _bc((0, 0, 0), (1, 0, 0), (0, 1, 0), (2, 1, 0)), rf"\Psi_{{{k}}}",
                f"clamped-pinned natural bending mode {k} (beta = {mpmath.nstr(b, 15)})", B)


def _clamped_free(k: int) -> Mode:
    with mpmath.workdps(EIGEN_DPS + 10):
        b = clamped_free_beta(k)
        sigma = (mpmath.cosh(b) + mpmath.cos(b)) / (mpmath.sinh(b) + mpmath.sin(b))
    B, sg = _to_float(b), _to_float(sigma)
    expr = sp.cosh(B * s) - sp.cos(B * s) - sg * (sp.sinh(B * s) - sp.sin(B * s))
    return Mode(ModeRef("bending", "clamped_free", k), expr, False,
                _bc((0, 0, 0), (1, 0, 0), (2, 1, 0), (3, 1, 0)), rf"\Lambda_{{{k}}}",
                f"clamped-free natural bending mode {k} (beta = {mpmath.nstr(b, 15)})", B)


FAMILIES: dict[tuple[str, str], Family] = {
    ("axial", "static"): Family("axial", "static", "static", True, _axial_static,
                                "Phi1 = s"),
    ("axial", "sine"): Family("axial", "sine", "sin", False, _axial_sine,
                              "sin(k pi s), k = 1, 2, ..."),
    ("axial", "fixed_free"): Family("axial", "fixed_free", "ff", False, _axial_fixed_free,
                                    "sin((2k-1) pi s / 2)"),
    ("bending", "static"): Family("bending", "static", "static", True, _bending_static,
                                  "Phi2 = 3/2 s^2 - 1/2 s^3"),
    ("bending", "clamped_pinned"): Family("bending", "clamped_pinned", "cp", False,
                                          _clamped_pinned, "clamped-pinned natural modes"),
    ("bending", "clamped_free"): Family("bending", "clamped_free", "cf", False,
                                        _clamped_free, "clamped-free natural modes"),
    ("bending", "pinned_pinned"): Family("bending", "pinned_pinned", "pp", False, _pinned_pinned,
                                         "sin(k pi s): pinned-pinned natural modes (root slope free)"),
    ("bending", "pinned_free"): Family("bending", "pinned_free", "pf", False, _pinned_free,
                                       "pinned-free natural modes (root slope free)"),
}


def root_slope_free(ref: ModeRef) -> bool:
    """A bending mode without w'(0) = 0 among its boundary conditions (pp): the floating frame
    is then not the root section's (pp: the chord's), so the root must be free to turn (a pin)."""
    return ref.axis == "bending" and (1, 0, 0) not in {(b.order, b.at, b.value) for b in mode(ref).bcs}

MAX_INDEX = 12  # beyond this the hyperbolic terms overflow double-precision evaluation


@lru_cache(maxsize=None)
def mode(ref: ModeRef) -> Mode:
    fam = FAMILIES.get((ref.axis, ref.family))
    if fam is None:
        known = ", ".join(f for (a, f) in FAMILIES if a == ref.axis)
        raise SpecError(f"unknown {ref.axis} mode family '{ref.family}' (known: {known})")
    if not isinstance(ref.index, int) or ref.index < 1 or ref.index > MAX_INDEX:
        raise SpecError(f"{ref.axis} mode '{ref.family}' index {ref.index!r} must be 1..{MAX_INDEX}")
    if fam.single and ref.index != 1:
        raise SpecError(f"{ref.axis} mode '{ref.family}' has a single member, not index {ref.index}")
    return fam.build(ref.index)


_TOKEN = re.compile(r"^([a-z_]+?)(\d*)$")


def parse_mode_token(axis: str, token: str) -> ModeRef:
    """'static', 'sin2', 'cp1', 'clamped_pinned3' -> ModeRef."""
    m = _TOKEN.fullmatch(token.strip())
    if not m:
        raise SpecError(f"cannot read {axis} mode '{token}' (expected e.g. static, sin1, cp2)")
    name, digits = m.group(1), m.group(2)
    for (ax, fam_name), fam in FAMILIES.items():
        if ax == axis and name in (fam.short, fam.name):
            if fam.single:
                if digits not in ("", "1"):
                    raise SpecError(f"{axis} mode '{token}': '{name}' has a single member")
                return ModeRef(axis, fam_name, 1)
            if not digits:
                raise SpecError(f"{axis} mode '{token}' needs an index, e.g. {fam.short}1")
            ref = ModeRef(axis, fam_name, int(digits))
            mode(ref)  # validates the index
            return ref
    known = ", ".join(f.short for (a, _), f in FAMILIES.items() if a == axis)
    raise SpecError(f"unknown {axis} mode '{token}' (families: {known})")
