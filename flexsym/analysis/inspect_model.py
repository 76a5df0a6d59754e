"""Human-readable report of a derivation: modes, integrals, energies, M, K_L, K_G, equations, op counts."""
from __future__ import annotations

import mpmath
import textwrap

import sympy as sp

from flexsym.core.errors import SpecError
from flexsym.codegen.derive import derive
from flexsym.codegen.generate import fingerprint
from flexsym.physics.modal import Derivation
from flexsym.model.variant import QUAD_POINTS, VariantSpec
from flexsym.model.strain_models import STRAIN_MODELS

SECTIONS = ("modes", "energy", "integrals", "mass", "stiffness", "equations", "ops")

SYSTEM_SECTIONS = ("system", "derivation")


def system_report(system, sections=SYSTEM_SECTIONS) -> str:
    """A mechanism inspected: its structure (bodies, joints in the tree and cut, coordinates,
    drivers, loads, outputs) and its derivation (energy terms, operation counts)."""
    from flexsym.codegen.sysgen import describe
    from flexsym.scenes.system_scene import summary

    unknown = [s for s in sections if s not in SYSTEM_SECTIONS]
    if unknown:
        raise SpecError(f"a mechanism shows the sections {', '.join(SYSTEM_SECTIONS)} "
                        f"(not {', '.join(map(str, unknown))})")
    parts = ([summary(system)] if "system" in sections else []) + (
        [describe(system)] if "derivation" in sections else [])
    return "\n".join(parts)


def _latex_names(der: Derivation) -> dict:
    names = {}
    for m in der.modes.values():
        tex = m.name.replace("_", r"\_")
        names[sp.Symbol(m.name, real=True)] = r"q_{\mathrm{" + tex + "}}"
    for sym in der.table.symbols:
        a, b, s_pow, factors = der.table.monomial(sym)[:4]
        parts = ([f"s^{{{s_pow}}}"] if s_pow > 1 else ["s"] if s_pow == 1 else [])
        for f in factors:
            if f.kind == "fs":
                parts.append(rf"H_{{{der.modes[f.a].latex}{der.modes[f.b].latex}}}")
            else:
                parts.append(der.modes[f.a].latex + "'" * f.order)
        names[sym] = rf"\int_{{{a}}}^{{{b}}} " + r"\, ".join(parts) + r"\,ds"
    return names



WIDTH = 100  # columns of the plain-text report; a line up to LONG (a table row) is kept whole
LONG = 120


def plain(expr, width: int = WIDTH) -> str:
    """An expression as plain text, one term of a sum per line, wrapped at `width` columns:
    symbol names are printed as they are (a 2-D pretty print reads 'x^2' in a name as a power
    and runs lines thousands of columns wide)."""
    if isinstance(expr, sp.MatrixBase):
        return "\n".join(f"[{i},{j}] = " + plain(expr[i, j], width).lstrip()
                         for i in range(expr.rows) for j in range(expr.cols) if expr[i, j] != 0) or "0"
    terms = expr.as_ordered_terms() if isinstance(expr, sp.Add) else [expr]
    lines = []
    for k, term in enumerate(terms):
        text = sp.sstr(term)
        if k:
            text = ("- " + sp.sstr(-term)) if text.startswith("-") else "+ " + text
        lines += textwrap.wrap(text, width, initial_indent="  ", subsequent_indent="      ",
                               break_on_hyphens=False) or ["  "]
    return "\n".join(lines)

class Report:
    def __init__(self, spec: VariantSpec, latex: bool = False):
        self.spec = spec
        self.latex = latex
        self.lines: list[str] = []
        if spec.kind == "fe":
            self.der = None  # one element of efbody.py, the same for every ef beam
            self._names = {}
        else:
            self.der = derive(spec)
            self._names = _latex_names(self.der) if latex else {}

    def fmt(self, expr) -> str:
        if self.latex:
            return sp.latex(expr, symbol_names=self._names)
        return plain(expr)

    def title(self, text: str) -> None:
        self.lines += ["", text, "-" * len(text)]

    def add(self, text: str = "") -> None:
        for line in text.split("\n"):
            if len(line) > LONG and not self.latex and not line.lstrip().startswith("|"):
                indent = " " * (len(line) - len(line.lstrip()))
                self.lines += textwrap.wrap(line, WIDTH, initial_indent="", subsequent_indent=indent + "    ",
                                            break_on_hyphens=False, drop_whitespace=True) or [line]
            else:
                self.lines.append(line)

    def render(self, sections=SECTIONS) -> str:
        if self.spec.kind == "fe":
            return self._render_fe(sections)
        d, s = self.der, self.spec
        strain = STRAIN_MODELS[s.strain]
        self.add(f"variant {s.name}" + (f" ({', '.join(s.aliases)})" if s.aliases else ""))
        self.add(f"  {s.description}")
        self.add(f"  strain model '{s.strain}': {strain.description}")
        self.add(f"  manoeuvre '{d.maneuver.name}': theta(t) = {d.maneuver.theta}")
        self.add(f"  fingerprint {fingerprint(s)}")
        if getattr(d, "exact", False):
            return self._render_exact(sections)
        for section in sections:
            getattr(self, f"_{section}")()
        return "\n".join(self.lines) + "\n"

    def _render_exact(self, sections) -> str:
        """Exact kinematics: T, M and f are quadratures (casadi), V is sympy."""
        from flexsym.physics.exact import continuous_formulas

        quad = self.der.quadrature.describe()
        self.add(f"  quadrature: {quad['segments']} segments x {quad['points_per_segment']} Gauss "
                 f"points = {quad['points']} ({quad['check']})")
        if "modes" in sections:
            self._modes()
        if "energy" in sections:
            self.title("Exact kinematics (s = x/L; nothing truncated but the modal expansions)")
            for what, formula in continuous_formulas().items():
                self.add(f"{what:18s} {formula}")
            self.add("")
            self.add("T is evaluated by the quadrature above (positions are cumulative integrals of "
                     "cos/sin of the fields); M(q) = d2T/dq'2 and f follow from d'Alembert's principle "
                     "on the same points")
            for t in self.der.terms:
                self.add(f"V_{t.name} ({t.formula}) =")
                self.add(self.fmt(t.V))
        if "integrals" in sections:
            self._integrals()
        if any(x in sections for x in ("mass", "stiffness", "equations")):
            self.title("Mass matrix and equations (depend on q through cos/sin of the fields)")
            self.add("M(q) = rho A L sum_i w_i J_i^T J_i,  J_i = dr(s_i)/dq  (generated by casadi)")
            self.add("f = -rho A L sum_i w_i J_i^T (J_i' q' + 2w z x r_i' + alpha z x r_i - w^2 r_i) - dV/dq")
            self.add("no K_L/K_G split: the stiffening comes from the exact kinematics")
        if "ops" in sections:
            self._ops()
        return "\n".join(self.lines) + "\n"

    def _modes(self) -> None:
        self.title("Coordinates and mode shapes (s = x/L)")
        for name, m in self.der.modes.items():
            self.add(f"{name} [{self.der.groups[name]}]: {m.description}")
            self.add("  shape = " + (sp.latex(m.expr) if self.latex else str(m.expr)))
            self.add("  boundary conditions: " + ", ".join(bc.describe("phi") for bc in m.bcs))

    def _energy(self) -> None:
        d = self.der
        self.title("Energy terms and the coordinates they are differentiated with respect to")
        for t in d.terms:
            coords = [c for c in d.coords if d.groups[c] in t.wrt]
            self.add(f"{t.name:10s} {t.formula:52s} d/d({', '.join(coords) or '-'})")
        self.add("")
        if d.conservative:
            self.add("every term is differentiated w.r.t. every coordinate it depends on: the "
                     "elastic forces derive from a potential")
        else:
            self.add("NOT a potential force: some term is not differentiated w.r.t. all the "
                     "coordinates it depends on (paper eq. 18-19; see docs/theory/benchmark.md, section 3)")
        self.add("")
        self.add("kinetic energy T =")
        self.add(self.fmt(d.T))
        for t in d.terms:
            self.add(f"V_{t.name} =")
            self.add(self.fmt(t.V))

    def _integrals(self) -> None:
        self.title("Modal integrals (int_0^1 ... ds)")
        for sym in self.der.integrals:
            v = self.der.table.value(sym)
            how = f"exact = {v.exact}" if v.method == "exact" else \
                f"Gauss-Legendre n={v.nodes}{' per element, double' if v.method == 'fe_gauss' else ''}, " \
                f"est. error {v.error:.1e}"
            self.add(f"{str(sym):48s} {mpmath.nstr(v.value, 17):>26s}  {how}")

    def _mass(self) -> None:
        d = self.der
        self.title("Mass matrix M" + (" (constant)" if d.mass_constant else " (depends on q)"))
        self.add(self.fmt(d.M))

    def _stiffness(self) -> None:
        K_L, K_G = self.der.stiffness_split()
        self.title("Linear stiffness K_L = -dQ/dq at q = 0")
        self.add(self.fmt(K_L))
        self.title("Geometric stiffness K_G(q) = -dQ/dq - K_L")
        self.add(self.fmt(K_G) if any(e != 0 for e in K_G) else
                 "zero (any stiffening of this variant comes from the kinetic energy)")

    def _equations(self) -> None:
        d = self.der
        self.title("Equations of motion  M(q) q'' = f(q, q', w, alpha),  w = theta', alpha = theta''")
        for i, c in enumerate(d.coords):
            self.add(f"[{c}]  sum_j M[{i},j] q_j'' = ")
            self.add(self.fmt(d.f[i]))
        for item in d.dropped:
            self.add(f"left out: {item['what']} ({item['why']})")

    def _ops(self) -> None:
        self.title("Generated kernels: operation counts after CSE (add/mul/div/fun/other)")
        for e in variant_kernels(self.spec):
            o = e.ops
            self.add(f"{e.c_name:22s} {e.total_ops:6d}  ({o['add']}/{o['mul']}/{o['div']}/{o['fun']}/{o['other']})")

    # ----- the finite-element reference ------------------------------------------------
    def _render_fe(self, sections) -> str:
        from flexsym.physics.efbody import _ED, generic_element
        from flexsym.physics.fe import hermite, le

        s = self.spec
        T, _, _, _, strain, curvature, _ = generic_element()
        self.add(f"variant {s.name}: {s.description}")
        self.add(f"  {s.elements} planar ANCF cable elements, 8 coordinates each "
                 "(r and r_x = dr/dx at both nodes, in the moving frame)")
        self.add("  root clamp: r = 0, y_x = 0 (x_x, the root stretch, stays free); the frame turns "
                 "at Om_ with its origin at velocity (Vx_, Vy_) in frame axes (the hub: Om_ = w, V = 0)")
        self.add(f"  fingerprint {fingerprint(s)}")
        if "modes" in sections:
            self.title("Element interpolation: r(xi) = N1 r1 + N2 r1_x + N3 r2 + N4 r2_x, x = x1 + l xi")
            for i, n in enumerate(hermite(le), 1):
                self.add(f"N{i} = {n}")
        if "energy" in sections:
            self.title("Element energies (geometrically exact: nothing truncated)")
            self.add("axial strain eps = (r_x . r_x - 1)/2:")
            self.add(self.fmt(sp.simplify(strain)) if not self.latex else sp.latex(strain))
            self.add("curvature kappa = (r_x x r_xx)/|r_x|^2 (material, per reference length):")
            self.add(self.fmt(curvature))
            self.add(f"V^e = int_0^l (EA eps^2/2 + EI kappa^2/2) dx, Gauss-Legendre with {QUAD_POINTS} points")
            self.add("kinetic energy T^e (exact polynomial integration in xi):")
            self.add(self.fmt(T))
        if "mass" in sections:
            self.title("Element mass matrix M^e = d2T^e/de'2 (constant)")
            self.add(self.fmt(sp.hessian(T, list(_ED))))
        if "equations" in sections:
            self.title("Element equations")
            self.add("the inertial forces are Lagrange's of T^e in the frame's actual motion, the elastic "
                     "forces -dV^e/de: both by casadi AD per element in the generated code "
                     "(flexsym/codegen/sysgen.py), assembled by its system.c")
        if "ops" in sections:
            self._ops()
        return "\n".join(self.lines) + "\n"


def variant_kernels(spec) -> list:
    """The emitted C kernels of a variant's generated folder (its S0's, sysgen)."""
    from flexsym.codegen.sysgen import emitted_kernels
    from flexsym.model.library import variant_system

    return emitted_kernels(variant_system(spec))[2]


def op_counts(spec) -> dict[str, int]:
    """Operations per generated kernel of a variant (after CSE)."""
    return {e.kernel.name: e.total_ops for e in variant_kernels(spec)}


def savings(spec, full) -> str:
    """What a scene's model leaves out, and the operations that saves per kernel."""
    mine, base = op_counts(spec), op_counts(full)
    lines = ["", "What this scene's model leaves out", "----------------------------------"]
    notes = [f"{w}: {y}" for w, y in getattr(spec, "left_out", ())]
    if spec.kind == "modal":
        notes += [f"{d['what']}: {d['why']}" for d in derive(spec).dropped]
    unused = [o for o in full.outputs if o not in spec.outputs]
    if unused:
        notes.append(f"outputs {', '.join(unused)}: not requested")
    lines += [f"- {n}" for n in notes] or ["- nothing"]
    lines += ["", f"{'kernel':16s} {'full model':>10s} {'this scene':>10s} {'saved':>8s}"]
    for k in base:
        saved = base[k] - mine.get(k, 0)
        lines.append(f"{k:16s} {base[k]:10d} {mine.get(k, 0):10d} {saved:8d}")
    return "\n".join(lines) + "\n"


def plot_modes(der: Derivation, path) -> None:
    """The mode shapes over s = x/L (a body's: its element interpolation), axial and bending."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from flexsym.model.fedata import BodyMode, evaluate
    from flexsym.model.modes import s

    x = np.linspace(0.0, 1.0, 401)
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharex=True)
    for name, m in der.modes.items():
        if isinstance(m, BodyMode):
            y = evaluate(m.body, m.shape, 0, x)
        else:
            y = np.broadcast_to(sp.lambdify(s, m.expr, "numpy")(x), x.shape)
        axes[0 if der.groups[name] == "axial" else 1].plot(x, y, label=name)
    for ax, title in zip(axes, ("axial modes", "bending modes")):
        ax.set_title(title)
        ax.set_xlabel("s = x/L")
        ax.grid(True, alpha=0.3)
        if ax.lines:
            ax.legend(fontsize=8)
    fig.suptitle(der.spec.name)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
