"""Is a result inside the range of validity of its model, and if a run stopped, why?

Criterion for the modal (floating frame) variants: |v| <= 0.1 L everywhere. Their strain
measures keep terms of second order in v' only, so their error grows like (v/L)^2: on the
spin-up beam against `ef` it is 0.4 % of the peak deflection at v/L = 0.057 (omega_s = 6),
1 % at 0.087 (omega_s = 10) and 3 % at 0.137 (omega_s = 20) (tests/test_hard_cases.py).
`ef` is geometrically exact and has no such limit (only its mesh and step).

The exact-kinematics model (strain model `exact`) truncates no strain, only modes: its
criterion is the share of the last bending mode in the curvature field,
||xi_n Phi_n''|| / ||sum_k xi_k Phi_k''|| (L2 norms along the beam), over the rows where the
curvature is at least SIGNIFICANT of its peak. A share above TRUNCATION_LIMIT says the mode
set does not resolve the deformation: add modes.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
import sympy as sp

VALIDITY_LIMIT = 0.1  # |v| / L
TRUNCATION_LIMIT = 0.25  # share of the last mode in the curvature (exact kinematics; exact_study)
SIGNIFICANT = 0.1  # rows with curvature norm >= this fraction of its peak are judged


@dataclass
class Assessment:
    valid: bool
    notes: list[str] = field(default_factory=list)

    @property
    def status(self) -> str:
        return "ok" if self.valid and not self.notes else "; ".join(self.notes)


@lru_cache(maxsize=None)
def _mode_peak(ref) -> float:
    from flexsym.model.modes import mode, s

    fn = sp.lambdify(s, mode(ref).expr, "numpy")
    return float(np.max(np.abs(fn(np.linspace(0.0, 1.0, 2001)))))


def deflection_bound(spec, result) -> tuple[np.ndarray, str]:
    """|v| along the run: v_tip when it is an output, else sum_j |q_j| max_s |phi_j(s)|, a bound."""
    if "v_tip" in result.columns:
        return np.abs(result["v_tip"]), "|v_tip|"
    bound = sum(np.abs(result[m.coordinate]) * _mode_peak(m) for m in spec.bending)
    return bound, "a bound on |v|"


@lru_cache(maxsize=None)
def _curvature_gram(refs: tuple) -> np.ndarray:
    """G_ij = int_0^1 Phi_i'' Phi_j'' ds (Simpson on 2001 points: a norm, not a kernel value)."""
    from flexsym.model.modes import mode, s

    x = np.linspace(0.0, 1.0, 2001)
    vals = np.array([np.broadcast_to(sp.lambdify(s, sp.diff(mode(r).expr, s, 2), "numpy")(x), x.shape)
                     for r in refs])
    w = np.full(x.size, 2.0)
    w[1::2], w[0], w[-1] = 4.0, 1.0, 1.0
    return (vals * w) @ vals.T * (x[1] - x[0]) / 3


def truncation_share(spec, result) -> np.ndarray:
    """Share of the last bending mode in the curvature field at every row (nan at rest)."""
    refs = tuple(spec.bending)
    G = _curvature_gram(refs)
    xi = np.column_stack([result[m.coordinate] for m in refs])
    total = np.sqrt(np.maximum(np.einsum("ti,ij,tj->t", xi, G, xi), 0.0))
    last = np.abs(xi[:, -1]) * np.sqrt(G[-1, -1])
    with np.errstate(invalid="ignore", divide="ignore"):
        share = last / total
    share[total < SIGNIFICANT * np.max(total, initial=0.0)] = np.nan
    return share


def deflection_weights(spec, columns) -> list[float] | None:
    """Weights w over `columns` with sum_j w_j |y_j| = the quantity deflection_bound() uses
    (for the C batch, which has no rows to hand back); None when the model has no limit (ef; the
    exact kinematics, whose truncation share needs the rows: assess() on a run with rows)."""
    if spec.kind != "modal" or getattr(spec, "strain", None) == "exact":
        return None
    if "v_tip" in columns:
        return [float(c == "v_tip") for c in columns]
    peaks = {m.coordinate: _mode_peak(m) for m in spec.bending}
    return [peaks.get(c, 0.0) for c in columns]


def assess(spec, result, params: dict | None = None) -> Assessment:
    length = (params or {}).get("L", 10.0)
    a = Assessment(True)
    exact = getattr(spec, "strain", None) == "exact"
    if exact and len(result.t) and len(spec.bending) > 1:
        share = truncation_share(spec, result)
        if np.any(share > TRUNCATION_LIMIT):
            i = int(np.nanargmax(share > TRUNCATION_LIMIT))
            a.valid = False
            a.notes.append(f"modal truncation: the last bending mode ({spec.bending[-1].token}) carries "
                           f"{share[i]:.1%} of the curvature at t = {result.t[i]:.3g} s (peak "
                           f"{np.nanmax(share):.1%}) > {TRUNCATION_LIMIT:.0%}; add modes")
    elif spec.kind == "modal" and len(result.t):
        v, what = deflection_bound(spec, result)
        over = v > VALIDITY_LIMIT * length
        if np.any(over):
            i = int(np.argmax(over))
            a.valid = False
            a.notes.append(f"deformation left the range of validity of the modal model at t = "
                           f"{result.t[i]:.3g} s: {what} = {v[i]:.3g} m > {VALIDITY_LIMIT:g} L "
                           f"(peak {np.max(v):.3g} m); second-order strains: errors grow like (v/L)^2, "
                           "use ef")
    if not result.ok:
        a.valid = False
        # why a model collapses, for a run that went some way (not for a step refused up front)
        hint = diagnose(spec, result) if len(result.t) > 1 else ""
        a.notes.append(result.message + (f" -- {hint}" if hint else ""))
    return a


BETA1 = 1.8751040687119611  # first root of 1 + cos(b) cosh(b) = 0 (clamped-free beam)


def first_bending_frequency(params: dict) -> float:
    """omega_1 = beta_1^2 sqrt(EI / (rho A L^4)) of the clamped-free Euler-Bernoulli beam with
    the run's parameters (defaults: the paper's beam, 3.798 rad/s)."""
    from flexsym.model.parameters import BEAM_PARAMS

    p = {q.name: q.default for q in BEAM_PARAMS} | dict(params)
    return BETA1**2 * (p["E"] * p["I"] / (p["rho"] * p["A"] * p["L"] ** 4)) ** 0.5


def diagnose(spec, result) -> str:
    """Why a known model collapses, stated with the numbers of this run."""
    strain = getattr(spec, "strain", None)
    if strain == "cubic_energy":
        axial = [m.coordinate for m in spec.axial]
        last = {c: float(result[c][-1]) for c in axial}
        compressed = [f"{c} = {v:.3g} m" for c, v in last.items() if v < 0]
        return ("strain model 'cubic_energy' differentiates the truncated energy (5) w.r.t. the axial "
                "coordinates too: that energy is unbounded below, bending drives the axial coordinate "
                "into compression" + (f" ({', '.join(compressed)} at the end)" if compressed else "")
                + "; the paper's #1/#2 use eq. (18)-(19) instead (strain model geometric_stiffness)")
    if strain == "linear":
        w1 = first_bending_frequency(result.options.get("params") or {})
        return (f"no geometric stiffening: above the first bending frequency of this beam ({w1:.3g} "
                "rad/s, clamped-free) centrifugal softening makes the bending stiffness negative")
    if strain == "geometric_stiffness":
        return ("the elastic force of eq. (18)-(19) is not a potential force (the axial equation does "
                "not see the bending): at large deflection it can feed energy into the motion")
    return ""
