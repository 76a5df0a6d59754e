"""Is a result inside the range of validity of its model, and if a run stopped, why?

Criterion for the modal (floating frame) variants: |v| <= 0.1 L everywhere. Their strain
measures keep terms of second order in v' only, so their error grows like (v/L)^2: on the
spin-up beam against `ef` it is 0.4 % of the peak deflection at v/L = 0.057 (omega_s = 6),
1 % at 0.087 (omega_s = 10) and 3 % at 0.137 (omega_s = 20) (tests/test_hard_cases.py).
`ef` is geometrically exact and has no such limit (only its mesh and step).

Every flexible body of a system is held to its model's range in the same way
(assess_system): its kind gives the gauges read off the run's coordinate columns (body_kinds,
`gauges`): a modal beam's bound on |v| against 0.1 L (both bending planes in 3D) and on its
axial strain; an `ef` beam's axial strain at its nodes (planar) or over its elements (3D); an
exact-kinematics beam's truncation share. The axial strain is held to STRAIN_LIMIT in every
model: the sections' law is linear elastic (sigma = E eps), which no metal is beyond a few
tenths of a per cent, and the modal strain measures drop terms of order eps^2. A driven
motion beyond the reach of a linkage is absorbed by stretching its bodies: this is where it
shows.

The exact-kinematics model (strain model `exact`) truncates no strain, only modes: its
criterion is the share of the last bending mode in the curvature field,
||xi_n Phi_n''|| / ||sum_k xi_k Phi_k''|| (L2 norms along the beam), over the rows where the
curvature is at least SIGNIFICANT of its peak. A share above TRUNCATION_LIMIT says the mode
set does not resolve the deformation: add modes.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
import sympy as sp

from flexsym.model.modes import Mode

VALIDITY_LIMIT = 0.1  # |v| / L
TRUNCATION_LIMIT = 0.25  # share of the last mode in the curvature (exact kinematics; exact_study)
SIGNIFICANT = 0.1  # rows with curvature norm >= this fraction of its peak are judged
STRAIN_LIMIT = 0.01  # |axial strain| of a system's flexible body, in every model
DEFLECTION_ADVICE = "second-order strains: errors grow like (v/L)^2, use ef"
# |twist| of a spatial modal beam, rad: its section turns to first order, I + [theta]x, and
# its twist does not turn the bending planes (a flat section's moments mix between them by sin
# phi); 0.1 rad is the rotation the deflection limit allows a slope (0.15 at a cantilever's tip)
TWIST_LIMIT = 0.1
TWIST_ADVICE = "the sections turn to first order and the twist does not turn the bending planes, use ef"
STRAIN_ADVICE = ("the sections' law is linear elastic and small-strain; a driven motion beyond the "
                 "reach of a linkage stretches its bodies: check its lengths and drives")


@dataclass
class Assessment:
    valid: bool
    notes: list[str] = field(default_factory=list)

    @property
    def status(self) -> str:
        return "ok" if self.valid and not self.notes else "; ".join(self.notes)


@dataclass(frozen=True)
class Gauge:
    """One measure of a body's deformation along a run, read off its coordinate columns, and
    the limit of what its model is derived for (assess_system). weights: ((column, w), ...)
    when the measure is sum_j w_j |y_j| (a bound); else measure(columns) -> its history."""

    body: str
    what: str
    limit: float
    advice: str
    weights: tuple = ()
    measure: Callable | None = None
    unit: str = ""  # of the measure, in the message
    limit_text: str = ""  # the limit as the message says it (default: its value)

    def history(self, columns) -> np.ndarray:
        if self.measure is not None:
            return self.measure(columns)
        return sum(w * np.abs(columns[c]) for c, w in self.weights)


def mode_peak(m, derivative: int = 0) -> float:
    """max over the beam (s in [0, 1], 2001 points) of |d^k phi / ds^k| of a mode: the
    library's (modes.Mode: sympy, once per mode), or a body's from finite-element data
    (fedata.BodyMode, the plane's or the torsion's: their interpolation)."""
    if isinstance(m, Mode):
        return _library_peak(m.ref, derivative)
    from flexsym.model.fedata import evaluate

    return float(np.max(np.abs(evaluate(m.body, m.shape, derivative, np.linspace(0.0, 1.0, 2001)))))


@lru_cache(maxsize=None)
def _library_peak(ref, derivative: int) -> float:
    from flexsym.model.modes import mode, s

    x = np.linspace(0.0, 1.0, 2001)
    return float(np.max(np.abs(np.broadcast_to(sp.lambdify(s, mode(ref).derivative(derivative), "numpy")(x), x.shape))))


def modal_gauges(beam, L: float, axial: list, planes: list, torsion: list = ()) -> list[Gauge]:
    """A modal beam's gauges: its axial strain (sum_j |q_j| max|psi_j'| / L, a bound), but for
    the exact kinematics its deflection, and in 3D its twist. axial, torsion: [(column, mode),
    ...] of its axial and torsion coordinates (the modes its derivation uses); planes: such a
    list per bending plane (one in 2D, two in 3D)."""
    spec, out = beam.model, []
    if axial:
        out.append(Gauge(beam.name, "a bound on |axial strain|", STRAIN_LIMIT, STRAIN_ADVICE,
                         tuple((c, mode_peak(m, 1) / L) for c, m in axial)))
    if torsion:
        out.append(Gauge(beam.name, "a bound on |twist|", TWIST_LIMIT, TWIST_ADVICE,
                         tuple((c, mode_peak(m)) for c, m in torsion), unit=" rad"))
    planes = [[(c, mode_peak(m)) for c, m in plane] for plane in planes]
    planes = [p for p in planes if p]
    if not planes or spec.strain == "exact":
        return out
    if len(planes) == 1:
        return out + [Gauge(beam.name, "a bound on |v|", VALIDITY_LIMIT * L, DEFLECTION_ADVICE, tuple(planes[0]),
                            unit=" m", limit_text=f"{VALIDITY_LIMIT:g} L = {VALIDITY_LIMIT * L:.4g} m")]
    def magnitude(cols):
        return np.sqrt(sum(sum(w * np.abs(cols[c]) for c, w in p) ** 2 for p in planes))
    return out + [Gauge(beam.name, "a bound on |(v, w)|", VALIDITY_LIMIT * L, DEFLECTION_ADVICE,
                        measure=magnitude, unit=" m", limit_text=f"{VALIDITY_LIMIT:g} L = {VALIDITY_LIMIT * L:.4g} m")]


def first_over(history, limit: float) -> int | None:
    """The first row at which a measure's history exceeds its limit (nan never does), or None:
    the one decision of every note here."""
    over = np.asarray(history, dtype=float) > limit
    return int(np.argmax(over)) if np.any(over) else None


class Prefixed:
    """A body's columns by its own coordinate names (its body's prefix added)."""

    def __init__(self, columns, body: str):
        self.columns, self.body = columns, body

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[f"{self.body}_{name}"]


def truncation_gauge(beam) -> list[Gauge]:
    """An exact-kinematics beam's: the last bending mode's share of its curvature."""
    spec = beam.model
    if len(spec.bending) < 2 or spec.body is not None:  # the library modes' curvature norm
        return []
    return [Gauge(beam.name, f"the last bending mode's ({spec.bending[-1].token}) share of the curvature",
                  TRUNCATION_LIMIT, "modal truncation: add modes",
                  measure=lambda cols: truncation_share(spec, Prefixed(cols, beam.name)))]


def strain_gauge(beam, measure) -> Gauge:
    """An ef beam's: measure(columns) -> max over the beam of its axial strain's magnitude."""
    return Gauge(beam.name, "|axial strain|", STRAIN_LIMIT, STRAIN_ADVICE, measure=measure)


def system_range_notes(system, result, params: dict | None = None) -> list[str]:
    """Why a system's result is outside its models' range: every flexible body's gauges (its
    kind's) over the rows, at the run's lengths (params: the run-time values given, else the
    run's own, result.options["params"]); empty when inside."""
    from flexsym.physics.body_kinds import kind_of
    from flexsym.physics.body_kinds.spatial import kind_of as spatial_kind_of

    given = (result.options.get("params") or {}) if params is None else params
    notes = []
    kind = spatial_kind_of if system.dimension == 3 else kind_of
    for b in [b for b in system.bodies if b.flexible] if len(result.t) else ():
        for g in kind(b).gauges(b, float(given.get(system.beam_param(b.name, "L"), b.length))):
            h = np.asarray(g.history(result), dtype=float)
            i = first_over(h, g.limit)
            if i is not None:
                notes.append(f"body '{g.body}' left the range of validity of its model at t = "
                             f"{result.t[i]:.4g} s: {g.what} = {h[i]:.4g}{g.unit} > "
                             f"{g.limit_text or format(g.limit, 'g')} (peak {np.nanmax(h):.4g}{g.unit}); {g.advice}")
    return notes


def assess_system(system, result) -> Assessment:
    """What `flexsym run` says of a system's run: its range notes, then why it stopped."""
    notes = system_range_notes(system, result)
    return Assessment(not notes and result.ok, notes + ([] if result.ok else [result.message]))


def deflection_bound(spec, result) -> tuple[np.ndarray, str]:
    """|v| along the run: v_tip when it is an output, else sum_j |q_j| max_s |phi_j(s)|, a bound."""
    if "v_tip" in result.columns:
        return np.abs(result["v_tip"]), "|v_tip|"
    bound = sum(np.abs(result[m.coordinate]) * mode_peak(spec.mode(m)) for m in spec.bending)
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
    peaks = {m.coordinate: mode_peak(spec.mode(m)) for m in spec.bending}
    return [peaks.get(c, 0.0) for c in columns]


def range_notes(spec, result, params: dict | None = None) -> list[str]:
    """Why a one-beam result is outside its model's range (|v| <= 0.1 L, or the exact
    kinematics' truncation share); empty when inside."""
    length = (params or {}).get("L", 10.0)
    notes = []
    exact = getattr(spec, "strain", None) == "exact"
    if exact and len(result.t) and len(spec.bending) > 1:
        share = truncation_share(spec, result)
        i = first_over(share, TRUNCATION_LIMIT)
        if i is not None:
            notes.append(f"modal truncation: the last bending mode ({spec.bending[-1].token}) carries "
                         f"{share[i]:.1%} of the curvature at t = {result.t[i]:.3g} s (peak "
                         f"{np.nanmax(share):.1%}) > {TRUNCATION_LIMIT:.0%}; add modes")
    elif spec.kind == "modal" and len(result.t):
        v, what = deflection_bound(spec, result)
        i = first_over(v, VALIDITY_LIMIT * length)
        if i is not None:
            notes.append(f"deformation left the range of validity of the modal model at t = "
                         f"{result.t[i]:.3g} s: {what} = {v[i]:.3g} m > {VALIDITY_LIMIT:g} L "
                         f"(peak {np.max(v):.3g} m); {DEFLECTION_ADVICE}")
    return notes


def assess(spec, result, params: dict | None = None) -> Assessment:
    """What `flexsym run` says of a one-beam run: its range notes, then why it stopped (with
    why a known model collapses, for a run that went some way)."""
    notes = range_notes(spec, result, params)
    if not result.ok:
        hint = diagnose(spec, result) if len(result.t) > 1 else ""
        notes.append(result.message + (f" -- {hint}" if hint else ""))
    return Assessment(not notes, notes)


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
