"""Output quantities: tip displacements and stress resultants, as expressions of the state
(their names, defaults and checks: output_names.py).

Sign convention: N > 0 in tension; M = EI * curvature, positive when the beam curves toward
+y of the moving frame (v'' > 0).

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

import sympy as sp

from flexsym.physics.energy import A, E, I, L, alpha, rho, w
from flexsym.model import beam_element
from flexsym.core.errors import SpecError
from flexsym.physics.integrals import Factor
from flexsym.model.modes import s
from flexsym.model.output_names import point_of, stress_method


def field_at(der, expr: sp.Expr, at, side: int = 0) -> sp.Expr:
    """Replace every factor placeholder in a field expression by its value at s = at (at a
    node of a body from finite-element data: side -1 / +1 the element's before / beyond it; 0,
    the modes' mean of both and the weights' before)."""
    subs = {}
    table = der.table
    for ph in table.placeholders:
        f: Factor = table._factor_of[ph]
        if f.kind == "mode":
            subs[ph] = der.modes[f.a].value_at(f.order, at, side)
        elif f.kind == "weight":
            subs[ph] = table.weight_at(f.a, at, side)
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

    from flexsym.model.fedata import locate

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
