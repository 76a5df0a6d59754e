"""A one-beam modal variant: its equations of motion by Lagrange's equations, kept as
M(q) q'' = f(q, q', w, alpha), and its kernels.

The root rotation theta(t) is guided, so the unknowns are the elastic coordinates only and
w = theta', alpha = theta'' enter as known inputs (T reads w, not theta):

    d/dt dT/dq' - dT/dq = Q,   Q_i = -sum over energy terms V_k with i in wrt(k) of dV_k/dq_i

M and f come from lagrange.equations_of_motion, the same function a system's derivation uses.
`prepare` (modes, fields, energy terms) is shared with the exact kinematics (exact.py, which
subclasses Derivation); derive.py picks one of the two by the strain model's kinematics.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

import casadi as ca

from .energy import BEAM_PARAMS, ENERGY_TERMS, alpha, build_fields, kinetic_density, w
from .integrals import BodyIntegralTable, IntegralTable
from .kernels import Kernel, make_kernels, maneuver_sx, matrix_sx, translator
from .lagrange import equations_of_motion, generalized_force, jacobi_integral
from .maneuver import Maneuver, maneuver_of
from .modes import Mode
from .outputs import output_expression
from .spec import VariantSpec
from .strain_models import STRAIN_MODELS, StrainModel


@dataclass
class DerivedTerm:
    name: str
    formula: str
    wrt: tuple[str, ...]  # coordinate groups this term is differentiated with respect to
    V: sp.Expr  # the energy term (in integral symbols)
    Q: sp.Matrix  # its generalised force contribution


@dataclass
class Derivation:
    spec: VariantSpec
    strain: StrainModel
    maneuver: Maneuver
    modes: dict[str, Mode]
    groups: dict[str, str]  # coordinate -> 'axial' | 'bending'
    q: sp.Matrix
    qd: sp.Matrix
    qdd: sp.Matrix
    table: IntegralTable
    fields: object
    T: sp.Expr = None
    terms: list[DerivedTerm] = field(default_factory=list)
    Q: sp.Matrix = None
    M: sp.Matrix = None
    f: sp.Matrix = None
    outputs: dict[str, sp.Expr] = field(default_factory=dict)
    dropped: list[dict] = field(default_factory=list)  # what was left out of the kernels and why

    @property
    def coords(self) -> list[str]:
        return list(self.modes)

    @property
    def params(self) -> list[sp.Symbol]:
        return [p.symbol for p in BEAM_PARAMS]

    @property
    def mass_constant(self) -> bool:
        return not (self.M.free_symbols & set(self.q))

    @property
    def outputs_use_acceleration(self) -> bool:
        """The outputs read q'' (axial force from equilibrium): the runtime then computes it."""
        return any(e.has(*self.qdd) for e in self.outputs.values())

    @property
    def outputs_use_drive(self) -> bool:
        """The outputs read w or alpha: the runtime then evaluates the manoeuvre for them."""
        return any(e.has(w, alpha) for e in self.outputs.values())

    @property
    def conservative(self) -> bool:
        return self.strain.conservative(bool(self.spec.axial))

    def numeric(self, expr):
        """Replace integral symbols by their values (34 digits)."""
        subs = self.table.substitutions()
        return expr.xreplace(subs)

    def energies(self) -> tuple[sp.Expr, sp.Expr, sp.Expr]:
        """(T, V, Jacobi integral h = T2 - T0 + V); h is conserved at constant w when conservative."""
        V = sp.Add(*[t.V for t in self.terms])
        return self.T, V, sp.expand(jacobi_integral(self.T, self.M, self.qd, V))

    def stiffness_split(self) -> tuple[sp.Matrix, sp.Matrix]:
        """K_L (constant) and K_G(q, w) = -dQ/dq - K_L, the geometric stiffness."""
        K = -self.Q.jacobian(self.q)
        at_rest = {x: 0 for x in self.q} | {w: 0}
        K_L = K.xreplace(at_rest)
        return K_L, (K - K_L).applyfunc(sp.expand)


def prepare(spec: VariantSpec, cls=None) -> Derivation:
    """A `cls` (Derivation or a subclass) with modes, fields and energy terms with their
    generalised forces Q; T, M, f and the outputs are the kinematics' own. `spec` is
    validated (derive.derive)."""
    strain = STRAIN_MODELS[spec.strain]
    maneuver = maneuver_of(spec.maneuver)
    modes = {r.coordinate: spec.mode(r) for r in spec.modes}
    groups = {r.coordinate: r.axis for r in spec.modes}
    names = list(modes)
    q = sp.Matrix([sp.Symbol(n, real=True) for n in names])
    qd = sp.Matrix([sp.Symbol(n + "_d", real=True) for n in names])
    qdd = sp.Matrix([sp.Symbol(n + "_dd", real=True) for n in names])
    qmap, qdmap, qddmap = dict(zip(names, q)), dict(zip(names, qd)), dict(zip(names, qdd))

    table = IntegralTable(modes) if spec.body is None else BodyIntegralTable(spec.body, modes)
    axial = [modes[r.coordinate] for r in spec.axial]
    bending = [modes[r.coordinate] for r in spec.bending]
    fields = build_fields(axial, bending, qmap, qdmap, table, strain.foreshortening, qddmap)
    der = (cls or Derivation)(spec, strain, maneuver, modes, groups, q, qd, qdd, table, fields)

    Q = sp.zeros(len(names), 1)
    for term_name, wrt in strain.terms:
        term = ENERGY_TERMS[term_name]
        V = table.integrate(term.density(fields))
        Qk = generalized_force(V, q, [groups[n] in wrt for n in names]).applyfunc(sp.expand)
        der.terms.append(DerivedTerm(term_name, term.formula, wrt, V, Qk))
        Q += Qk
    der.Q = Q
    return der


def derive_modal(spec: VariantSpec) -> Derivation:
    der = prepare(spec)
    q, qd, groups, maneuver = der.q, der.qd, der.groups, der.maneuver
    der.T = der.table.integrate(kinetic_density(der.fields))
    der.M, der.f = equations_of_motion(der.T, der.Q, q, qd, [(None, w, alpha)])
    if not maneuver.accelerates:
        der.f = der.f.xreplace({alpha: 0})
        der.dropped.append({"what": "theta'' (alpha) terms",
                            "why": f"manoeuvre '{maneuver.name}' has theta'' = 0 identically"})
    if not any(g == "axial" for g in groups.values()) and der.strain.foreshortening:
        der.dropped.append({"what": "axial coordinates",
                            "why": "foreshortening carries the axial field kinematically"})

    der.outputs = {name: output_expression(der, name) for name in spec.outputs}
    if not maneuver.accelerates:
        der.outputs = {k: v.xreplace({alpha: 0}) for k, v in der.outputs.items()}
    return der


def build_modal_kernels(der: Derivation) -> list[Kernel]:
    """Kernels (row-major dense outputs, p = beam parameters, drive = [w, alpha]):
      mass(q, p) -> M                               mass matrix, symmetric positive definite
      force(q, qd, drive, p) -> f                   M q'' = f
      residual_jac(q, qd, qdd, drive, p) -> (dr_dq, dr_dqd) of r = M(q) q'' - f (Newton)
      outputs(q, qd, qdd, drive, p) -> y             v_tip, u_tip, N and M at points
      energy(q, qd, drive, p) -> [T, V, h]           kinetic, potential, Jacobi integral
      maneuver(t, mp) -> [theta, w, alpha]           guided root rotation
    """
    params = der.params
    tr, x = translator(der.q, der.qd, der.qdd, params, der.maneuver, (w, alpha))
    M = matrix_sx(tr, der.numeric(der.M), params)
    f = matrix_sx(tr, der.numeric(der.f), params)
    y = matrix_sx(tr, der.numeric(sp.Matrix(list(der.outputs.values()))), params)
    T, V, h = der.energies()
    en = matrix_sx(tr, der.numeric(sp.Matrix([T, V, h])), params)
    r = ca.mtimes(M, x["qdd"]) - f
    q, qd, qdd, drive, p = x["q"], x["qd"], x["qdd"], x["drive"], x["p"]
    return make_kernels([
        ("mass", "mass matrix M(q)", [("q", q), ("p", p)], [("M", M)]),
        ("force", "right-hand side f of M q'' = f", [("q", q), ("qd", qd), ("drive", drive), ("p", p)],
         [("f", f)]),
        ("residual_jac", "Jacobians of r = M(q) q'' - f", [("q", q), ("qd", qd), ("qdd", qdd),
                                                          ("drive", drive), ("p", p)],
         [("dr_dq", ca.jacobian(r, q)), ("dr_dqd", ca.jacobian(r, qd))]),
        ("outputs", "output quantities " + ", ".join(der.outputs),
         [("q", q), ("qd", qd), ("qdd", qdd), ("drive", drive), ("p", p)], [("y", y)]),
        ("energy", "[T, V, h]: kinetic, potential energy and Jacobi integral",
         [("q", q), ("qd", qd), ("drive", drive), ("p", p)], [("e", en)]),
        ("maneuver", f"[theta, w, alpha] of manoeuvre '{der.maneuver.name}'",
         [("t", x["t"]), ("mp", x["mp"])], [("drive3", maneuver_sx(tr, der.maneuver))]),
    ])
