"""Equations of motion of a variant by Lagrange's equations, kept as M(q) q'' = f(q, q', w, alpha).

The root rotation theta(t) is guided, so the unknowns are the elastic coordinates only and
w = theta', alpha = theta'' enter as known inputs (T reads w, not theta):

    d/dt dT/dq' - dT/dq = Q,   Q_i = -sum over energy terms V_k with i in wrt(k) of dV_k/dq_i

M and f come from lagrange.equations_of_motion, the same function a system's derivation uses.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from .energy import BEAM_PARAMS, ENERGY_TERMS, STRAIN_MODELS, StrainModel, alpha, build_fields, kinetic_density, w
from .integrals import BodyIntegralTable, IntegralTable
from .lagrange import equations_of_motion, generalized_force, jacobi_integral
from .maneuver import Maneuver, maneuver_of
from .modes import Mode
from .outputs import output_expression
from .spec import VariantSpec


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


def derive(spec: VariantSpec) -> Derivation:
    spec.validate()
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
    cls = Derivation
    if strain.kinematics == "exact":
        from .exact import ExactDerivation as cls
    der = cls(spec, strain, maneuver, modes, groups, q, qd, qdd, table, fields)

    Q = sp.zeros(len(names), 1)
    for term_name, wrt in strain.terms:
        term = ENERGY_TERMS[term_name]
        V = table.integrate(term.density(fields))
        Qk = generalized_force(V, q, [groups[n] in wrt for n in names]).applyfunc(sp.expand)
        der.terms.append(DerivedTerm(term_name, term.formula, wrt, V, Qk))
        Q += Qk
    der.Q = Q
    if strain.kinematics == "exact":  # T, M, f by quadrature and casadi AD
        from .exact import finish

        return finish(der)

    der.T = table.integrate(kinetic_density(fields))
    der.M, der.f = equations_of_motion(der.T, Q, q, qd, [(None, w, alpha)])
    if not maneuver.accelerates:
        der.f = der.f.xreplace({alpha: 0})
        der.dropped.append({"what": "theta'' (alpha) terms",
                            "why": f"manoeuvre '{maneuver.name}' has theta'' = 0 identically"})
    if not any(groups[n] == "axial" for n in names) and strain.foreshortening:
        der.dropped.append({"what": "axial coordinates",
                            "why": "foreshortening carries the axial field kinematically"})

    der.outputs = {name: output_expression(der, name) for name in spec.outputs}
    if not maneuver.accelerates:
        der.outputs = {k: v.xreplace({alpha: 0}) for k, v in der.outputs.items()}
    return der
