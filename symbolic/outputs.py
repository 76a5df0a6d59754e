"""Output quantities: tip displacements and stress resultants, as expressions of the state.

Sign convention: N > 0 in tension; M = EI * curvature, positive when the beam curves toward
+y of the moving frame (v'' > 0).

Names: v_tip, u_tip, and N_P / M_P at a point P: A (root, x = 0), B (x = L/2), C (tip,
x = L) or s<fraction> for x = fraction * L, written with 'p' for the decimal point
(N_s0p25 is N at x = L/4; on the command line N@0.25).

Methods (spec.stress):
  continuum   N = EA u_o', M = EI v_o''                                  (paper eq. 26)
  element:n   the paper's element method (22)-(25) on n beam elements: nodal u, v, theta
              from the modes, S^e = (K_L^e + P K_GL^e) u_e with P = EA (u2 - u1)/l
Moment source (spec.moment):
  constitutive  the method above
  equilibrium   M(x) from the inertial loads of the part beyond x (the strain model exact
                evaluates both equilibrium sources on its exact kinematics, exact.py)
Axial force source (spec.axial_force):
  constitutive  from the axial strain of the model's axial modes (prestress: N(x) assumed by
                the model); unavailable without axial modes (foreshortening)
  equilibrium   N(x) = -rho A int_x^L a_x dx, the axial inertial forces of the part beyond x
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import sympy as sp

from .energy import A, E, I, L, alpha, rho, w
from . import beam_element
from .errors import SpecError
from .integrals import Factor
from .modes import s

POINTS = {"A": sp.Integer(0), "B": sp.Rational(1, 2), "C": sp.Integer(1)}
STRESS_OUTPUTS = tuple(f"{q}_{p}" for q in "NM" for p in "ABC")
_POINT_RE = re.compile(r"^([NM])_(A|B|C|s(\d+)(?:p(\d+))?)$")
_AT_RE = re.compile(r"^([NM])@([0-9]*\.?[0-9]+)$")


@dataclass(frozen=True)
class OutputInfo:
    name: str
    unit: str
    description: str


def canonical_output(token: str) -> str:
    """'N@0.25' -> 'N_s0p25'; names already canonical are returned unchanged."""
    token = token.strip()
    m = _AT_RE.fullmatch(token)
    if m:
        frac = sp.nsimplify(m.group(2))
        if not 0 <= frac <= 1:
            raise SpecError(f"output '{token}': position {m.group(2)} is outside [0, 1] "
                            "(positions are fractions of the beam length)")
        text = m.group(2).rstrip("0").rstrip(".") if "." in m.group(2) else m.group(2)
        text = text if not text.startswith(".") else "0" + text
        return f"{m.group(1)}_s{text.replace('.', 'p')}"
    return token


LABEL_RE = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,31}$")


def point_of(name: str, points=()):
    """(quantity 'N'|'M', exact position s) of a stress output name, or None. `points` are the
    spec's named positions (label, fraction of L)."""
    if len(name) > 2 and name[0] in "NM" and name[1] == "_":
        for label, frac in points:
            if name[2:] == label:
                return name[0], sp.Rational(frac)
    m = _POINT_RE.fullmatch(name)
    if not m:
        return None
    where = m.group(2)
    if where in POINTS:
        return m.group(1), POINTS[where]
    frac = sp.nsimplify(f"{m.group(3)}.{m.group(4) or 0}")
    return m.group(1), frac


def info(name: str, points=()) -> OutputInfo:
    if name == "v_tip":
        return OutputInfo(name, "m", "transverse tip deflection v_o(L) in the moving frame")
    if name == "u_tip":
        return OutputInfo(name, "m", "axial tip displacement u_o(L) in the moving frame")
    q, at = point_of(name, points)
    what = "axial force (tension > 0)" if q == "N" else "bending moment (EI v'')"
    return OutputInfo(name, "N" if q == "N" else "N m", f"{what} at x = {at} L")


def check_output_names(spec, extra=()) -> None:
    for label, frac in spec.points:
        if not LABEL_RE.fullmatch(label) or label in POINTS or re.match(r"s\d", label):
            raise SpecError(f"variant '{spec.name}': position name '{label}' must be letters, digits "
                            "and _ (it reaches generated C), start with a letter, and not be A, B, C")
        try:
            value = sp.Rational(frac)
        except (TypeError, ValueError):
            raise SpecError(f"variant '{spec.name}': position '{label}' = {frac!r} is not a number") from None
        if not 0 <= value <= 1:
            raise SpecError(f"variant '{spec.name}': position '{label}' is outside the beam")
    seen = set()
    for name in spec.outputs:
        if name not in ("v_tip", "u_tip") and name not in extra:
            p = point_of(name, spec.points)
            if p is None:
                raise SpecError(f"variant '{spec.name}': unknown output '{name}' (known: v_tip, "
                                "u_tip, N_A, N_B, N_C, M_A, M_B, M_C, N@<x/L>, M@<x/L>)")
            if not 0 <= p[1] <= 1:
                raise SpecError(f"variant '{spec.name}': output '{name}' is outside the beam")
            if p[0] == "N" and spec.kind == "modal" and not axial_force_available(spec):
                raise SpecError(
                    f"variant '{spec.name}': {name} is not available: strain model "
                    f"'{spec.strain}' has no axial coordinate to carry an axial force; use "
                    "--axial-force equilibrium to recover N from the inertial forces")
        if name in seen:
            raise SpecError(f"variant '{spec.name}': duplicate output '{name}'")
        seen.add(name)


def axial_force_available(spec) -> bool:
    return bool(spec.axial) or spec.strain == "prestress" or spec.axial_force == "equilibrium"


def default_outputs(spec) -> tuple[str, ...]:
    """v_tip, u_tip and every stress at A, B, C that the variant can give."""
    outs = ["v_tip", "u_tip"]
    outs += [n for n in STRESS_OUTPUTS if n[0] == "M" or axial_force_available(spec)]
    return tuple(outs)


# ----- expressions ---------------------------------------------------------------------

def field_at(der, expr: sp.Expr, at) -> sp.Expr:
    """Replace every factor placeholder in a field expression by its value at s = at."""
    subs = {}
    table = der.table
    for ph in table.placeholders:
        f: Factor = table._factor_of[ph]
        if f.kind == "mode":
            subs[ph] = der.modes[f.a].value_at(f.order, at)
        elif f.kind == "weight":
            subs[ph] = table.weight_at(f.a, at)
        elif at == 0:
            subs[ph] = sp.Integer(0)
        else:  # H_ab(at) = int_0^at a' b' ds: an ordinary modal integral on [0, at]
            subs[ph] = table.monomial_symbol(
                [(table.mode_value(f.a, 1), 1), (table.mode_value(f.b, 1), 1)], 0, at)
    return sp.expand(expr.xreplace(subs))


def _continuum_N(der, at) -> sp.Expr:
    return E * A / L * field_at(der, der.fields.u_stretch_s, at)


def _continuum_M(der, at) -> sp.Expr:
    return E * I / L**2 * field_at(der, der.fields.v_ss, at)


def _prestress_N(der, at) -> sp.Expr:
    return rho * A * w**2 * L**2 * der.table.weight_at("nhat", at) / 2


def _equilibrium_N(der, at) -> sp.Expr:
    """N(x) = -int_x^L rho A a_x dx (with the point masses beyond x), a_x the axial (moving x)
    inertial acceleration."""
    f = der.fields
    a_x = f.u_ddot - 2 * w * f.v_dot - alpha * f.v - w**2 * (L * s + f.u)
    return -rho * A * L * der.table.integrate(f.weights["mu"] * a_x, at, 1)


def _equilibrium_M(der, at) -> sp.Expr:
    """M(x) from the equilibrium of the part beyond x: the moment about the section of its
    inertial loads q = -rho A a (a in the moving frame, point masses included) and of the
    inertial couples -J (theta'' + v'') of point rotary inertias:
    M(x) = int_x^L [(xb + u(xb) - x - u(x)) q_y - (v(xb) - v(x)) q_x] dxb."""
    f = der.fields
    x_abs = L * s + f.u
    a_x = f.u_ddot - 2 * w * f.v_dot - alpha * f.v - w**2 * x_abs
    a_y = f.v_ddot + 2 * w * f.u_dot + alpha * x_abs - w**2 * f.v
    dx = x_abs - L * at - field_at(der, f.u, at)
    dy = f.v - field_at(der, f.v, at)
    M = -rho * A * L * der.table.integrate(f.weights["mu"] * (dx * a_y - dy * a_x), at, 1)
    rot = f.weights["rot"]
    if rot != 0:
        M -= rho * A * L**3 * der.table.integrate(rot * (alpha + f.v_ddot_s / L), at, 1)
    return M


def element_matrices(le, EA=E * A, EI=E * I):
    """The paper's K_L^e (7) and K_G^e (8) (beam_element.py; (th1, th2) = -le/30)."""
    return beam_element.element_matrices(le, EA, EI)[1:]


def _element_end_values(der, n: int, e: int, want_N: bool):
    """(N or M at the left end, at the right end) of element e of n, from (23)-(25)."""
    return _element_ends(der, (sp.Rational(e, n), sp.Rational(e + 1, n)), 1, 1, want_N)


def _element_ends(der, nodes, ea, ei, want_N: bool):
    """End values of the element between s = nodes[0] and nodes[1] with section ratios ea, ei."""
    le = L * (nodes[1] - nodes[0])
    f = der.fields
    u_hat = []
    for at in nodes:
        u_hat += [field_at(der, f.u_stretch, at), field_at(der, f.v, at), field_at(der, f.v_s, at) / L]
    u_hat = sp.Matrix(u_hat)
    KL, KG = element_matrices(le, E * A * ea, E * I * ei)
    P = E * A * ea / le * (u_hat[3] - u_hat[0])
    S = (KL + P * KG) * u_hat
    if want_N:
        return -S[0], S[3]
    return -S[2], S[5]


def _element_method(der, n: int, at, want_N: bool) -> sp.Expr:
    t = at * n
    e = int(sp.floor(t))
    if t == e:  # a node: the average of the adjacent element ends
        ends = []
        if e > 0:
            ends.append(_element_end_values(der, n, e - 1, want_N)[1])
        if e < n:
            ends.append(_element_end_values(der, n, e, want_N)[0])
        return sp.expand(sp.Add(*ends) / len(ends))
    left, right = _element_end_values(der, n, e, want_N)
    xi = t - e  # end forces vary linearly along an element loaded only at its nodes
    return sp.expand((1 - xi) * left + xi * right)


def _body_element_method(der, at, want_N: bool, side: int = 0) -> sp.Expr:
    """The element method (23)-(25) on the body's own elements and sections. At a node: the
    end value of the element on the left (side -1), on the right (+1), or their mean (0)."""
    import numpy as np

    from .fedata import locate

    body = der.spec.body
    sn = [sp.Float(repr(float(x)), 17) for x in body.s_nodes]
    ratios = body.ratios()
    x = float(at)

    def ends(e):
        return _element_ends(der, (sn[e], sn[e + 1]), sp.Float(repr(float(ratios["ea"][e])), 17),
                             sp.Float(repr(float(ratios["ei"][e])), 17), want_N)

    node = body.node_index(x * body.length)
    if node is None:
        e = int(locate(body, np.array([x]))[0])
        left, right = ends(e)
        xi = (x - float(body.s_nodes[e])) / float(body.s_nodes[e + 1] - body.s_nodes[e])
        return sp.expand((1 - sp.Float(repr(xi), 17)) * left + sp.Float(repr(xi), 17) * right)
    vals = []
    if node > 0 and side <= 0:
        vals.append(ends(node - 1)[1])
    if node < body.elements and side >= 0:
        vals.append(ends(node)[0])
    if not vals:  # the root asked from the left, or the tip from the right
        raise SpecError(f"no element on that side of x = {x * body.length:g} m")
    return sp.expand(sp.Add(*vals) / len(vals))


def stress_method(spec) -> tuple[str, int]:
    if getattr(spec, "body", None) is not None:
        if spec.stress != "continuum":
            raise SpecError(f"variant '{spec.name}': a body from finite-element data recovers "
                            "stresses on its own elements; --stress does not apply")
        return "body", 0
    if spec.stress == "continuum":
        return "continuum", 0
    if getattr(spec, "strain", None) == "exact" and spec.stress != "continuum":
        raise SpecError(f"variant '{spec.name}': the element method reads small-deflection nodal "
                        "values; the exact kinematics takes --stress continuum (and --moment / "
                        "--axial-force equilibrium for the resultants from the inertial loads)")
    m = re.fullmatch(r"element:(\d+)", spec.stress)
    if not m or not 1 <= int(m.group(1)) <= 1000:
        raise SpecError(f"variant '{spec.name}': stress method '{spec.stress}' must be "
                        "'continuum' or 'element:N' with 1 <= N <= 1000 elements")
    return "element", int(m.group(1))


def output_expression(der, name: str) -> sp.Expr:
    spec = der.spec
    if name == "v_tip":
        return field_at(der, der.fields.v, 1)
    if name == "u_tip":
        return field_at(der, der.fields.u, 1)
    quantity, at = point_of(name, spec.points)
    method, n = stress_method(spec)
    # a body's node: a position named *_left / *_right takes that side's element
    side = -1 if name.endswith("_left") else 1 if name.endswith("_right") else 0

    def from_modes(want_N):
        if method == "body":
            return _body_element_method(der, at, want_N, side)
        if method == "element":
            return _element_method(der, n, at, want_N)
        return _continuum_N(der, at) if want_N else _continuum_M(der, at)

    if quantity == "M":
        return _equilibrium_M(der, at) if spec.moment == "equilibrium" else from_modes(False)
    if spec.axial_force == "equilibrium":
        return _equilibrium_N(der, at)
    N = sp.Integer(0)
    if spec.axial:
        N = from_modes(True)
    if spec.strain == "prestress":
        N += _prestress_N(der, at)
    return N
