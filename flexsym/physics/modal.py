"""A one-beam modal variant: its equations of motion, kept as M(q) q'' = f(q, q', w, alpha),
its outputs and its kernels.

The root rotation theta(t) is guided, so the unknowns are the elastic coordinates only and
w = theta', alpha = theta'' enter as known inputs (T reads w, not theta):

    d/dt dT/dq' - dT/dq = Q,   Q_i = -sum over energy terms V_k with i in wrt(k) of dV_k/dq_i

T, the energy terms, M and f are not derived here: they are the spin-up system's (S0, the
variant's beam on a guided revolute to ground) from assemble.derive_system, renamed to the
variant's symbols, so variants and systems share one derivation (and lagrange.py's equations).
The exact kinematics (exact.py) subclasses Derivation; derive.py picks one of the two by the
strain model's kinematics.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from dataclasses import fields as dataclass_fields

import sympy as sp

from flexsym.physics.assemble import derive_system
from flexsym.physics.energy import BEAM_PARAMS, ENERGY_TERMS, alpha, w
from flexsym.physics.integrals import IntegralTable
from flexsym.physics.lagrange import jacobi_integral
from flexsym.model.maneuver import Maneuver, maneuver_of
from flexsym.model.modes import Mode
from flexsym.physics.outputs import output_expression
from flexsym.model.variant import VariantSpec
from flexsym.model.strain_models import STRAIN_MODELS, StrainModel
from flexsym.model.system import Output, Section
from flexsym.model.library import spin_up_system


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
    def integrals(self) -> list[sp.Symbol]:
        """The modal integrals that T, the energy terms, M, f and the outputs read (table order;
        the table may hold more: the system derivation's frame-velocity terms)."""
        used = set().union(self.T.free_symbols, self.M.free_symbols, self.f.free_symbols,
                           *(t.V.free_symbols for t in self.terms),
                           *(e.free_symbols for e in self.outputs.values()))
        return [x for x in self.table.symbols if x in used]

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


def derive_modal(spec: VariantSpec) -> Derivation:
    """T, the energy terms, M and f are the spin-up system's (S0: this variant's beam on a
    guided revolute to ground, assemble.derive_system), with its symbols renamed to the
    variant's: coordinates without the body prefix, the hub's rate and acceleration w, alpha.
    One derivation of the physics serves variants and systems."""
    sd = derive_system(one_body_system(spec), integral_symbols=True)
    part = next(iter(sd.flex.values()))
    names = list(part.modes)
    q = sp.Matrix([sp.Symbol(n, real=True) for n in names])
    qd = sp.Matrix([sp.Symbol(n + "_d", real=True) for n in names])
    qdd = sp.Matrix([sp.Symbol(n + "_dd", real=True) for n in names])
    _, hub_rate, hub_acc = sd.guided[0].symbols
    rename = dict(zip(sd.q, q)) | dict(zip(sd.qd, qd)) | dict(zip(sd.qdd, qdd)) | {
        hub_rate: w, hub_acc: alpha}
    fields = replace(part.fields, **{f.name: getattr(part.fields, f.name).xreplace(rename)
                                     for f in dataclass_fields(part.fields) if f.name != "weights"})
    der = Derivation(spec, STRAIN_MODELS[spec.strain], maneuver_of(spec.maneuver), part.modes,
                     part.groups, q, qd, qdd, part.table, fields)
    for _, name, wrt, V, Qk in sd.terms:
        der.terms.append(DerivedTerm(name, ENERGY_TERMS[name].formula, wrt, V.xreplace(rename),
                                     Qk.xreplace(rename).applyfunc(sp.expand)))
    der.Q = sd.Q.xreplace(rename)
    der.T = sd.T.xreplace(rename)
    der.M, der.f = sd.M.xreplace(rename), sd.f.xreplace(rename)
    maneuver, groups = der.maneuver, der.groups
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


def one_body_system(spec: VariantSpec):
    """S0 for this variant: its beam (the paper's section, or its finite-element body's root
    section and length) on a guided revolute to ground."""
    if spec.body is None:
        system = spin_up_system(spec)
    else:
        r = spec.body.reference
        system = spin_up_system(spec, Section(r.rho, r.E, r.A, r.I), spec.body.length)
    return replace(system, outputs=(Output("theta", "angle(hub)"),))


