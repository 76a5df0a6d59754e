"""`flexsym select scene.toml --tol TOL`: the cheapest modal model whose error on the scene's
outputs, against the geometrically exact reference, stays under TOL.

Candidates: strain models prestress, foreshortening and geometric_stiffness (with axial
modes {static} or {static, sin1}), each with the bending sets {static}, {static, cp1}, ...,
up to --max-bending modes; with --exact also the exact kinematics (strain `exact`,
inextensible, stresses from equilibrium) with {cf1}, {cf1, cf2}, ... (opt-in: their larger
kernels take tens of seconds each to compile). Cost: CPU time of the integration with the scene's solver
(median of repeats). Error: the largest over the outputs of max_t |y - y_ref| divided by a
scale: the output's peak |y_ref| for v_tip and u_tip; for N and M the largest peak of that
quantity over the requested points (M at the free end is zero in every modal model and not
quite zero in the reference, whose own error there must not decide the choice).

Choice, robust to timing noise: among the candidates within TOL, costs within the noise
band of the cheapest (its measured relative spread max/min - 1 over the repeats, at least
NOISE_FLOOR) count as equal, and of those the model with the fewest coordinates wins (then
the cheaper one). A 4 % jitter in the timings therefore cannot flip the choice between
models of similar cost.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from flexsym.core.errors import SpecError
from flexsym.toolchain.pipeline import prepare
from flexsym.core.progress import Progress
from flexsym.toolchain.run import RunResult, run_built
from flexsym.model.variant import BUILTIN, VariantSpec, _refs

BENDING = ("static", "cp1", "cp2", "cp3", "cp4")
STRAINS = (("prestress", ((),)), ("foreshortening", ((),)),
           ("geometric_stiffness", (("static",), ("static", "sin1"))))
REFERENCE_ELEMENTS = 32
NOISE_FLOOR = 0.10  # relative: repeated timings of one case on a shared machine vary by 4-8 %


@dataclass
class Candidate:
    spec: VariantSpec
    cost: float  # s of CPU, integration alone
    error: float  # relative, see module docstring
    status: str
    spread: float = 0.0  # relative spread of the repeated timings, max / min - 1

    @property
    def size(self) -> int:
        return len(self.spec.axial) + len(self.spec.bending)

    @property
    def label(self) -> str:
        s = self.spec
        axial = ",".join(m.token for m in s.axial) or "-"
        return f"{s.strain:20s} axial {axial:11s} bending {','.join(m.token for m in s.bending)}"


def candidates(scene, max_bending: int = 4, exact: bool = False) -> list[VariantSpec]:
    base = scene.spec
    wants_n = any(o.startswith("N_") for o in base.outputs)
    out = []
    for strain, axial_sets in STRAINS:
        for axial in axial_sets:
            for k in range(1, max_bending + 1):
                tag = {"prestress": "ps", "foreshortening": "fs", "geometric_stiffness": "gs"}[strain]
                name = f"sel_{tag}_a{len(axial)}_b{k}"
                spec = VariantSpec(name, strain, _refs("axial", list(axial)), _refs("bending", list(BENDING[:k])),
                                   maneuver=base.maneuver, outputs=base.outputs, points=base.points,
                                   axial_force="equilibrium" if wants_n and strain == "foreshortening"
                                   else "constitutive", body=getattr(base, "body", None))
                out.append(spec.validate())
    if exact and getattr(base, "body", None) is not None:
        raise SpecError("--exact: the exact kinematics integrates a uniform beam; this scene's "
                        "[body] from finite-element data needs the other candidates")
    for k in range(1, max_bending + 1 if exact else 1):
        out.append(VariantSpec(f"sel_ex_b{k}", "exact", (), _refs("bending", [f"cf{i}" for i in range(1, k + 1)]),
                               maneuver=base.maneuver, outputs=base.outputs, points=base.points,
                               moment="equilibrium", axial_force="equilibrium").validate())
    return out


def reference_spec(scene):
    ef = next(b for b in BUILTIN if b.kind == "fe")
    body = getattr(scene.spec, "body", None)  # a body from finite-element data: the same beam
    if body is not None:
        body = body.remeshed(REFERENCE_ELEMENTS)
    return replace(ef, name=f"sel_ref_ef{REFERENCE_ELEMENTS}", body=body,
                   elements=body.elements if body is not None else REFERENCE_ELEMENTS,
                   outputs=scene.spec.outputs, points=scene.spec.points, maneuver=scene.spec.maneuver,
                   aliases=()).validate()


def error(r: RunResult, ref: RunResult, outputs) -> float:
    if not r.ok:
        return math.inf
    peaks = {o: float(np.max(np.abs(ref[o]))) for o in outputs}
    worst = 0.0
    for o in outputs:
        family = [p for k, p in peaks.items() if k[:2] == o[:2]] if o[:2] in ("N_", "M_") else [peaks[o]]
        scale = max(max(family), 1e-300)
        n = min(len(r.t), len(ref.t))
        worst = max(worst, float(np.max(np.abs(r[o][:n] - ref[o][:n]))) / scale)
    return worst


def select(scene, tol: float, max_bending: int = 4, repeat: int = 3, log=print, exact: bool = False):
    specs = candidates(scene, max_bending, exact)  # checked before any run
    interval = scene.dt * scene.out_every
    ref_dt = interval / max(1, math.ceil(interval / min(scene.dt, 5e-4)))
    log(f"reference: ef with {REFERENCE_ELEMENTS} elements, dt = {ref_dt:g} s ...")
    ref = run_built(prepare(reference_spec(scene), log=lambda m: None), t_end=scene.t_end, dt=ref_dt,
                    params=scene.params, out_every=round(interval / ref_dt), raise_on_failure=True)
    results = []
    bar = Progress(len(specs), "select")
    log = bar.wrap(log)
    for spec in specs:
        built = prepare(spec, log=lambda m: None)
        kw = dict(t_end=scene.t_end, dt=scene.dt, integrator=scene.integrator, params=scene.params,
                  out_every=scene.out_every, tol=scene.tol, step=scene.step)
        r = run_built(built, **kw)
        timed = run_built(built, repeat=repeat, **kw).summary if r.ok else None
        cost = timed["cpu_median"] if timed else math.inf
        spread = timed["cpu_max"] / timed["cpu_min"] - 1.0 if timed and timed["cpu_min"] > 0 else 0.0
        c = Candidate(spec, cost, error(r, ref, scene.spec.outputs), "ok" if r.ok else r.message, spread)
        results.append(c)
        log(f"  {c.label}  {c.cost * 1e3:8.3f} ms  error {c.error:.2e}")
        bar.update()
    bar.close()
    return results, choose(results, tol)


def noise_band(c: Candidate) -> float:
    return max(NOISE_FLOOR, c.spread)


def choose(results, tol: float):
    """Within tol: the fewest coordinates among the candidates whose cost is within the noise
    band of the cheapest (then the cheapest of those); None when no candidate is within tol."""
    passing = [c for c in results if c.error <= tol]
    if not passing:
        return None
    cheapest = min(passing, key=lambda c: c.cost)
    tied = [c for c in passing if c.cost <= cheapest.cost * (1.0 + noise_band(cheapest))]
    return min(tied, key=lambda c: (c.size, c.cost))


def table(results, best, tol) -> str:
    rows = ["| strain | axial | bending | CPU [ms] | spread | error | within tol |",
            "|---|---|---|---|---|---|---|"]
    for c in sorted(results, key=lambda c: c.cost):
        s = c.spec
        mark = "**chosen**" if c is best else ("yes" if c.error <= tol else "no")
        rows.append(f"| {s.strain} | {','.join(m.token for m in s.axial) or '-'} | "
                    f"{','.join(m.token for m in s.bending)} | {c.cost * 1e3:.3f} | {c.spread:.0%} | "
                    f"{c.error:.2e} | {mark} |")
    passing = [c for c in results if c.error <= tol]
    if passing:
        band = noise_band(min(passing, key=lambda c: c.cost))
        rows.append(f"\nRule: costs within {band:.0%} of the cheapest within tolerance (the "
                    "timing noise band: the measured spread, at least "
                    f"{NOISE_FLOOR:.0%}) count as equal; of those, the fewest coordinates wins.")
    return "\n".join(rows)
