"""An `ef` beam (planar ANCF cable elements, fe.py's element) as a body of a system.

The elements live in the body's floating frame, the frame of its tree joint, with the root
clamped in it as in the one-beam `ef` (r(0) = 0, r_x(0) along x, its length free): a revolute
tree joint is then a pin whose angle is the frame's, a clamp holds the root slope. Per element,
in frame components, with (V_x, V_y) = A^T R' and omega = phi' of the frame:
    T^e = int rho A/2 |V + r' + omega k x r|^2 dx   (exact: a polynomial in xi)
    V_g^e = -int rho A g_loc . r dx                 (exact), g_loc = A^T g
    V^e = int [EA eps^2/2 + EI kappa^2/2] dx        (fe.elastic_element: Gauss-Legendre, material kappa)
The elastic energy stays unexpanded (a square root per Gauss point): sysgen makes one element
kernel of it (V, gradient, Hessian by casadi AD, as fe.py does for the one-beam `ef`) and
system.c assembles it per element; the summed V_elastic here is for inspection and tests.
A body from finite-element data (the model's fedata.BeamBody) sets the nodes, each element's
section relative to the root's (rho A, E A, E I ratios: the run-time p scales the whole body)
and point masses at nodes, which add m/2 |V + r' + omega k x r|^2, -m g.r and their momentum.
T^e is not summed in sympy either: sysgen instantiates the generic T^e per element in casadi
with the frame's actual (omega, V) and takes the body's Lagrange terms by casadi AD (expanding
and differentiating the summed T in sympy took most of an ef system's build).
Structural damping (system.Damping, a damped body only) is a dissipation function per element,
in the rates e' of its nodal coordinates relative to the frame (rigid-body motion is not damped):
    D^e = beta int [EA eps'^2/2 + EI kappa'^2/2] dx    (strain rate, Kelvin-Voigt: the same
          Gauss points, Green strain and material curvature as V^e; eps' = r_x . r_x')
        + alpha int rho A |r'|^2 / 2 dx                 (exact: the element's mass matrix)
sysgen instantiates it per element in casadi like T^e (force -dD/de'); a body's point masses
add alpha m |r'_k|^2 / 2 (point_mass_dissipation, sympy).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property, lru_cache

import sympy as sp

from flexsym.model.exact_numbers import exact
from flexsym.physics.energy import A, E, I, L, rho
from flexsym.physics.fe import elastic_element, hermite, le, xi
from flexsym.physics.integrals import gauss_legendre

_E = sp.Matrix(sp.symbols("x1 y1 dx1 dy1 x2 y2 dx2 dy2", real=True))
_ED = sp.Matrix([sp.Symbol(str(c) + "_d", real=True) for c in _E])
OM, VX, VY, RX, RY, GX, GY = sp.symbols("Om_ Vx_ Vy_ Rx_ Ry_ gx_ gy_", real=True)
AL, A0X, A0Y = sp.symbols("Al_ A0x_ A0y_", real=True)  # the frame's angular, origin's acceleration
# an element's section in its damping: rho A, E A, E I (a body's elements scale them apart)
RA, EA, EI = sp.symbols("rhoA_ EA_ EI_", positive=True)


def _shape(e):
    N = hermite(le)
    rx = sum(Ni * e[j] for Ni, j in zip(N, (0, 2, 4, 6)))
    ry = sum(Ni * e[j] for Ni, j in zip(N, (1, 3, 5, 7)))
    return rx, ry


def _integral01(expr):
    """int_0^1 expr dxi of a polynomial in xi, term by term (exact, as sp.integrate, faster)."""
    poly = sp.Poly(sp.expand(expr), xi)
    return sp.Add(*[c / (k + 1) for (k,), c in poly.terms()])


@lru_cache(maxsize=None)
def generic_element():
    """(T, V_g, H, V_elastic, eps, kappa, stretch) of one element in the generic symbols."""
    rx, ry = _shape(_E)
    vx, vy = _shape(_ED)
    ax, ay = VX + vx - OM * ry, VY + vy + OM * rx
    T = sp.expand(le * _integral01(rho * A / 2 * (ax**2 + ay**2)))
    Vg = sp.expand(le * _integral01(-rho * A * (GX * rx + GY * ry)))
    H = sp.expand(le * _integral01(rho * A * ((RX + rx) * ay - (RY + ry) * ax)))
    eps, kappa, stretch, V = elastic_element(rx, ry)
    return T, Vg, H, V, eps, kappa, stretch


@lru_cache(maxsize=None)
def generic_dissipation():
    """(D_beta, D_alpha) of one element in the generic symbols (e, e', l) and its section (RA,
    EA, EI): D^e = beta D_beta + alpha D_alpha. D_beta is the strain-rate form of the elastic
    energy (Kelvin-Voigt: eps' and kappa' at V^e's Gauss points, linear in e' through the
    derivatives of fe.elastic_element's eps and kappa); D_alpha = int rho A |r'|^2 / 2 dx."""
    from flexsym.model.variant import QUAD_POINTS

    _, _, _, _, eps, kappa, _ = generic_element()
    rate = lambda f: sp.Add(*[sp.diff(f, c) * cd for c, cd in zip(_E, _ED)])
    eps_d, kappa_d = rate(eps), rate(kappa)
    D_beta = sp.Integer(0)
    for xg, wg in zip(*gauss_legendre(QUAD_POINTS)):
        at = {xi: sp.Float(xg, 30)}
        D_beta += sp.Float(wg, 30) * le * (EA / 2 * eps_d.xreplace(at)**2 + EI / 2 * kappa_d.xreplace(at)**2)
    vx, vy = _shape(_ED)
    D_alpha = sp.expand(le * _integral01(RA / 2 * (vx**2 + vy**2)))
    return D_beta, D_alpha


def _exact(x: float) -> sp.Rational:
    return sp.Rational(repr(float(x)))


@dataclass
class EfPart:
    beam: object
    n: int
    q: dict  # coordinate name -> symbol (fe.FESpec.coordinates)
    qd: dict
    psyms: dict  # global beam parameter symbol -> this body's
    body: object = None  # fedata.BeamBody or None (uniform)
    memo: dict = field(default_factory=dict, repr=False, compare=False)  # _beyond's loads

    @property
    def coords(self) -> list[str]:
        return list(self.q)

    @cached_property
    def fractions(self) -> list:
        """Node positions as exact fractions of L."""
        if self.body is None:
            return [sp.Rational(k, self.n) for k in range(self.n + 1)]
        return [_exact(x) / _exact(self.body.length) for x in self.body.nodes]

    @cached_property
    def ratios(self) -> list[tuple]:
        """Per element (rho A, E A, E I) relative to the root section (exact rationals)."""
        if self.body is None:
            return [(1, 1, 1)] * self.n
        r = self.body.reference
        return [(_exact(s.rho) * _exact(s.A) / (_exact(r.rho) * _exact(r.A)),
                 _exact(s.E) * _exact(s.A) / (_exact(r.E) * _exact(r.A)),
                 _exact(s.E) * _exact(s.I) / (_exact(r.E) * _exact(r.I))) for s in self.body.sections]

    @cached_property
    def point_masses(self) -> list[tuple[int, sp.Rational]]:
        """(node, mass) of the body's point masses (rotary inertia is refused in fe.FESpec)."""
        if self.body is None:
            return []
        return [(self.body.node_index(m.x), _exact(m.mass)) for m in self.body.masses if m.mass]

    @property
    def mass(self) -> sp.Expr:
        """The body's mass in this body's parameters."""
        f = self.fractions
        mu = sum(r[0] * (f[e + 1] - f[e]) for e, r in enumerate(self.ratios))
        return (rho * A * L * mu + sum(m for _, m in self.point_masses)).xreplace(self.psyms)

    def nodes(self, sym) -> list[list]:
        """Absolute nodal coordinates (x, y, x_x, y_x) of every node in the frame."""
        Ls = L
        out = [[sp.Integer(0), sp.Integer(0), 1 + sym["dx0"], sp.Integer(0)]]
        for k in range(1, self.n + 1):
            out.append([Ls * self.fractions[k] + sym[f"ux{k}"], sym[f"uy{k}"],
                        1 + sym[f"dx{k}"], sym[f"dy{k}"]])
        return out

    def rates(self) -> list[list]:
        out = [[0, 0, self.qd["dx0"], 0]]
        for k in range(1, self.n + 1):
            out.append([self.qd[f"ux{k}"], self.qd[f"uy{k}"], self.qd[f"dx{k}"], self.qd[f"dy{k}"]])
        return out

    def _element_subs(self, e: int) -> dict:
        nodes, rates = self.nodes(self.q), self.rates()
        vals = nodes[e] + nodes[e + 1]
        dvals = rates[e] + rates[e + 1]
        return dict(zip(_E, vals)) | dict(zip(_ED, dvals)) | {le: L * (self.fractions[e + 1] - self.fractions[e])}

    def _section(self, e: int) -> dict:
        """The element's section in the generic symbols (the energies are linear in rho A, and
        depend on E A and E I only)."""
        mu, ea, ei = self.ratios[e]
        return {} if self.body is None else {rho: rho * mu, A: A * ea, I: I * ei}

    def energies(self):
        """(V_g, H) summed over the elements and point masses, in placeholders OM, VX, ... and
        this body's parameters (T: sysgen.ef_kinetic_energy plus point_mass_kinetic;
        V_elastic: elastic_energy)."""
        _, Vgg, Hg, *_ = generic_element()
        Vg = H = sp.Integer(0)
        for e in range(self.n):
            sub = self._element_subs(e)
            mu = self.ratios[e][0]
            Vg += mu * Vgg.xreplace(sub)
            H += mu * Hg.xreplace(sub)
        for m, (x, y), (ax, ay) in self._point_mass_motion():
            Vg += -m * (GX * x + GY * y)
            H += m * ((RX + x) * ay - (RY + y) * ax)
        return tuple(x.xreplace(self.psyms) for x in (sp.expand(Vg), sp.expand(H)))

    def _point_mass_motion(self):
        """(m, position, velocity) of each point mass in frame components (placeholders)."""
        nodes, rates = self.nodes(self.q), self.rates()
        for k, m in self.point_masses:
            (x, y), (xd, yd) = nodes[k][:2], rates[k][:2]
            yield m, (x, y), (VX + xd - OM * y, VY + yd + OM * x)

    def point_mass_kinetic(self) -> sp.Expr:
        """The point masses' kinetic energy (placeholders; 0 for a uniform beam)."""
        T = sum((m * (ax**2 + ay**2) / 2 for m, _, (ax, ay) in self._point_mass_motion()),
                sp.Integer(0))
        return sp.expand(T).xreplace(self.psyms)

    def point_mass_dissipation(self, alpha) -> sp.Expr:
        """alpha sum m |r'_k|^2 / 2 of the point masses (their motion relative to the frame;
        0 for a uniform beam): the mass-proportional damping of a body's point masses."""
        rel = {OM: 0, VX: 0, VY: 0}
        T = sum((m * (ax.xreplace(rel)**2 + ay.xreplace(rel)**2) / 2
                 for m, _, (ax, ay) in self._point_mass_motion()), sp.Integer(0))
        return (alpha * sp.expand(T)).xreplace(self.psyms)

    def elastic_energy(self):
        """The summed elastic energy (the V output and tests; the kernels use the element's)."""
        V_el = generic_element()[3]
        return sp.Add(*[V_el.xreplace(self._element_subs(e)).xreplace(self._section(e))
                        for e in range(self.n)]).xreplace(self.psyms)

    def _locate(self, x: float, side: int = 0) -> list[tuple[int, sp.Expr, float]]:
        """(element, xi, weight): at an interior node the end of the element on the side
        asked (-1 before, +1 beyond), or the two adjacent ends averaged (0)."""
        at = exact(x) / exact(self.beam.length)
        f = self.fractions
        e = max(k for k in range(self.n) if f[k] <= at)
        if at == f[e] and e > 0:
            ends = [(e - 1, sp.Integer(1)), (e, sp.Integer(0))]
            return [(k, xk, 1.0) for k, xk in ends[side > 0:][:1]] if side else \
                [(k, xk, 0.5) for k, xk in ends]
        if at >= f[self.n]:
            return [(self.n - 1, sp.Integer(1), 1.0)]
        return [(e, (at - f[e]) / (f[e + 1] - f[e]), 1.0)]

    def position(self, x: float):
        """(r_x, r_y, slope angle) at x in the frame (positions are continuous: one element)."""
        e, at, _ = self._locate(x)[0]
        sub = self._element_subs(e)
        rx, ry = (c.xreplace({xi: at}).xreplace(sub).xreplace(self.psyms) for c in _shape(_E))
        dx, dy = (sp.diff(c, xi).xreplace({xi: at}).xreplace(sub).xreplace(self.psyms) for c in _shape(_E))
        return rx, ry, sp.atan2(dy, dx)

    def inertial(self, fn: str, x: float, qdd: dict, alpha=0, closed=False):
        """(N or M of the inertial loads and gravity on the part beyond station x, the section
        point, the section's unit tangent), in frame components and the placeholders OM, AL,
        A0X, A0Y, GX, GY of the frame's motion and gravity (their actual values: the body kind).
        The loads are -rho A (a - g) per unit length, a = A0 + r'' + 2 OM k x r' + AL k x r
        - OM^2 r (r of the elements' shapes: a polynomial in xi, integrated exactly), and
        -m (a - g) of the point masses at nodes beyond x, and the mass-proportional damping's
        -alpha rho A r' (r' relative to the frame; -alpha m r'_k): the dissipation function's
        force, external to the section (the strain-rate damping is internal: no load). N is
        their component along the tangent, M their moment about the section point.
        qdd: coordinate name -> q''; closed: a point mass at x is beyond (system.loads_at)."""
        F, M, section, tangent = self._beyond(x, qdd, alpha, closed)
        return (F.dot(tangent) if fn == "N" else M), section, tangent

    def damping_load(self, alpha):
        """The mass-proportional damping's force -alpha int rho A r' (frame components; point
        masses -alpha m r'_k) and its moment about the frame's origin (the clamped root)."""
        F, M, _, _ = self._beyond(0.0, None, alpha, False)
        return F, M

    def _beyond(self, x: float, qdd: dict | None, alpha, closed: bool):
        """(force, moment about the section point, section point, unit tangent) of the loads on
        the part beyond station x (inertial() says which; qdd None: the damping's alone); once
        per station (N and M share it)."""
        key = (x, qdd is None, alpha, closed)
        if key not in self.memo:
            self.memo[key] = self._loads_beyond(x, qdd, alpha, closed)
        return self.memo[key]

    def _loads_beyond(self, x: float, qdd: dict | None, alpha, closed: bool):
        at = exact(x) / exact(self.beam.length)
        f, nodes, rates = self.fractions, self.nodes(self.q), self.rates()
        accel = None if qdd is None else (
            [[0, 0, qdd["dx0"], 0]] + [[qdd[f"{c}{k}"] for c in ("ux", "uy", "dx", "dy")]
                                       for k in range(1, self.n + 1)])
        e0 = min(max(k for k in range(self.n) if f[k] <= at), self.n - 1)
        lo = (at - f[e0]) / (f[e0 + 1] - f[e0])
        rx0, ry0 = (c.xreplace({xi: lo}) for c in _shape(_E))
        dx0, dy0 = (sp.diff(c, xi).xreplace({xi: lo}) for c in _shape(_E))
        sub0 = self._element_subs(e0)
        sx, sy, tx, ty = (c.xreplace(sub0) for c in (rx0, ry0, dx0, dy0))
        norm = sp.sqrt(tx**2 + ty**2)

        def load(m, r, v, a):
            """-m times the acceleration the load balances, its moment about the section."""
            ax, ay = alpha * v[0], alpha * v[1]
            if a is not None:
                ax += A0X - GX + a[0] - 2 * OM * v[1] - AL * r[1] - OM**2 * r[0]
                ay += A0Y - GY + a[1] + 2 * OM * v[0] + AL * r[0] - OM**2 * r[1]
            return sp.Matrix([-m * ax, -m * ay, -m * ((r[0] - sx) * ay - (r[1] - sy) * ax)])

        # the densities are polynomials of degree <= 6 in xi: 4 Gauss points integrate them
        # exactly, without expanding the products (sympy took a minute for 64 elements)
        xg, wg = (tuple(sp.Float(v, 30) for v in vals) for vals in gauss_legendre(4))
        out = sp.zeros(3, 1)
        for e in range(e0, self.n):
            sub = dict(zip(_E, nodes[e] + nodes[e + 1])) | {le: L * (f[e + 1] - f[e])}
            r = [c.xreplace(sub) for c in _shape(_E)]
            v, a = ([c.xreplace(dict(zip(_E, w[e] + w[e + 1]))).xreplace({le: sub[le]})
                     for c in _shape(_E)] if w is not None else None for w in (rates, accel))
            dens = load(rho * A * self.ratios[e][0] * sub[le], r, v, a)
            start = lo if e == e0 else 0
            out += sum(((1 - start) * wk * dens.xreplace({xi: start + (1 - start) * xk})
                        for xk, wk in zip(xg, wg)), sp.zeros(3, 1))
        for k, m in self.point_masses:
            if f[k] > at or (closed and f[k] == at):
                out += load(m, nodes[k][:2], rates[k][:2], None if accel is None else accel[k][:2])
        out = out.xreplace(self.psyms)
        tangent = sp.Matrix([tx / norm, ty / norm]).xreplace(self.psyms)
        return out[:2, 0], out[2], sp.Matrix([sx, sy]).xreplace(self.psyms), tangent

    def stress(self, fn: str, x: float, side: int = 0):
        """N = EA eps |r_x| or M = EI kappa at x (at a node: _locate's side, or the mean of
        the two ends)."""
        _, _, _, _, eps, kappa, stretch = generic_element()
        expr = E * A * eps * stretch if fn == "N" else E * I * kappa
        out = sp.Integer(0)
        for e, at, wt in self._locate(x, side):
            out += wt * expr.xreplace({xi: at}).xreplace(self._element_subs(e)).xreplace(self._section(e))
        return out.xreplace(self.psyms)


def ef_part(beam, psyms) -> EfPart:
    spec = beam.model.validate()
    q = {c: sp.Symbol(f"{beam.name}_{c}", real=True) for c in spec.coordinates}
    qd = {c: sp.Symbol(f"{beam.name}_{c}_d", real=True) for c in spec.coordinates}
    return EfPart(beam, spec.elements, q, qd, psyms, spec.body)
