"""`flexsym select MECHANISM.toml --tol TOL`: the cheapest model and step of a mechanism whose
error against the geometrically exact `ef` stays under TOL in every output the scene names.

Candidates: every flexible body of the scene given the same built-in modal model (m1, m2, m3,
prestress; a body from finite-element data keeps its data), each at STEP_FACTORS times the
scene's step (those that divide the row interval), with the scene's integrator and its
settings; a model the mechanism refuses (prestress on a beam held beyond its root, ...) is
listed with its reason. Reference: every flexible body as REFERENCE_ELEMENTS ANCF elements at
half the scene's step; its own error is estimated by halving its step and its elements, and
printed (it should be well under TOL).
Error of a candidate: the largest over the scene's columns of max_t |y - y_ef| / max_t |y_ef|.
Cost: CPU time of the integration (median of --repeat runs); costs within the timing noise
band of the cheapest passing candidate (model_select.NOISE_FLOOR at least) count as equal, and
of those the fewest coordinates, then the larger step, wins.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace

from flexsym.analysis.model_select import NOISE_FLOOR
from flexsym.analysis.system_bench import column_errors, ef_system, run_rows
from flexsym.core.errors import SpecError
from flexsym.model.variant import builtin
from flexsym.scenes.system_scene import checked_system
from flexsym.codegen.generate import MANIFEST
from flexsym.toolchain.pipeline import prepare_system, system_folder

MODELS = ("m1", "m2", "m3", "prestress")
STEP_FACTORS = (1, 2, 4, 5)
REFERENCE_ELEMENTS = 32  # ef's M from the element curvature: 16 elements are 2e-3 of the peak off


@dataclass
class SystemCandidate:
    model: str
    dt: float
    coordinates: int = 0
    cost: float = math.inf  # s of CPU, integration alone
    spread: float = 0.0
    error: float = math.inf
    worst: str = ""  # the column with the largest error
    status: str = "ok"


def with_model(system, name: str):
    """Every flexible body with the built-in model `name` (a body's finite-element data kept)."""
    base = builtin(name)
    return replace(system, bodies=tuple(
        replace(b, model=replace(base, body=b.model.body) if getattr(b.model, "body", None) is not None
                else base) if b.flexible else b for b in system.bodies))


TUNING = ("newton_tol", "rho_inf", "penalty", "newmark_beta", "newmark_gamma")


def _run(system, scene, dt: float, repeat: int = 1):
    """system_bench's run of a scene's rows, at step dt, with the scene's integrator settings."""
    o = scene.options
    tuning = tuple((k, getattr(o, k)) for k in TUNING if getattr(o, k) is not None)
    return run_rows(prepare_system(system), scene, o.integrator, dt, repeat, tuning)


def coordinates(system) -> int:
    manifest = json.loads((system_folder(system) / MANIFEST).read_text(encoding="utf-8"))
    return len(manifest["coordinates"])


def errors(r, ref, columns) -> tuple[float, str]:
    """(largest error, its column): system_bench's per-column max |y - y_ref| / peak |y_ref|."""
    per = column_errors(r, ref, columns, "e")
    worst = max(columns, key=lambda c: per[f"e_{c}"])
    return per[f"e_{worst}"], worst


def check_selectable(scene) -> None:
    """Refuse, before any line is printed or any work done, what select cannot score."""
    system = scene.system
    free = [b.name for b in system.bodies if b.flexible and not system.frame_driven(b.name)]
    if system.dimension == 3 and free:
        raise SpecError(f"{scene.path}: select needs the ef reference, and a spatial ef beam on a "
                        f"joint that moves freely ('{free[0]}') is not a reference select can use "
                        "yet: it carries the sections' bending rotary inertia the modal beams leave "
                        "out, and converges in minutes (see docs/validation/spatial.md; its frame "
                        "must move by guided drivers and clamps alone)")


def select_system(scene, tol: float, repeat: int = 3, log=print):
    """(candidates, chosen or None, reference's own step error)."""
    check_selectable(scene)
    columns = list(scene.columns)
    o = scene.options
    steps = [o.dt * k for k in STEP_FACTORS if o.out_every % k == 0]
    log(f"reference: ef with {REFERENCE_ELEMENTS} elements per beam, {o.integrator} at dt = {o.dt / 2:g} s")
    ef = ef_system(scene.system, REFERENCE_ELEMENTS)
    ref = _run(ef, scene, o.dt / 2)
    if not ref.ok:
        raise SpecError(f"{scene.path}: the ef reference stopped ({ref.message}); select needs a "
                        "reference: try a smaller [solver] dt")
    # its own error, estimated by halving the step and the elements
    half_step = _run(ef, scene, o.dt)
    half_mesh = _run(ef_system(scene.system, REFERENCE_ELEMENTS // 2), scene, o.dt / 2)
    own = [errors(r, ref, columns)[0] if r.ok else math.inf for r in (half_step, half_mesh)]
    log(f"  the reference's own error, estimated: step (dt against dt/2) {own[0]:.1e}, elements "
        f"({REFERENCE_ELEMENTS // 2} against {REFERENCE_ELEMENTS}) {own[1]:.1e} of the peaks")
    ref_error = max(own)
    results = []
    for name in MODELS:
        try:
            system = checked_system(with_model(scene.system, name), o.t_end)[0]
            prepare_system(system)
        except SpecError as exc:  # what this mechanism cannot take from that model
            results.append(SystemCandidate(name, o.dt, status="refused: " + str(exc).split(": ", 2)[-1]))
            log(f"  {name}: refused")
            continue
        size = coordinates(system)
        for dt in steps:
            c = SystemCandidate(name, dt)
            r = _run(system, scene, dt)
            if not r.ok:
                c.status = r.message
            else:
                timed = _run(system, scene, dt, repeat).summary
                c.cost, c.spread = timed["cpu_median"], timed["cpu_max"] / max(timed["cpu_min"], 1e-300) - 1
                c.error, c.worst = errors(r, ref, columns)
                c.coordinates = size
            results.append(c)
            log(f"  {name} dt = {dt:g} s: {c.cost * 1e3:.3f} ms, error {c.error:.2e} ({c.worst or c.status})")
    return results, choose(results, tol), ref_error


def choose(results, tol: float):
    passing = [c for c in results if c.error <= tol]
    if not passing:
        return None
    cheapest = min(passing, key=lambda c: c.cost)
    band = max(NOISE_FLOOR, cheapest.spread)
    tied = [c for c in passing if c.cost <= cheapest.cost * (1 + band)]
    return min(tied, key=lambda c: (c.coordinates, -c.dt, c.cost))


def table(results, best, tol: float) -> str:
    rows = ["| model | dt [s] | CPU [ms] | error | worst column | within tol |", "|---|---|---|---|---|---|"]
    for c in sorted(results, key=lambda c: (c.cost, c.model)):
        if c.status.startswith("refused"):
            why = c.status if len(c.status) <= 100 else c.status[:99] + "…"
            rows.append(f"| {c.model} | – | – | – | {why} | no |")
            continue
        mark = "**chosen**" if c is best else ("yes" if c.error <= tol else "no")
        cost = f"{c.cost * 1e3:.3f}" if math.isfinite(c.cost) else "–"
        rows.append(f"| {c.model} | {c.dt:g} | {cost} | {c.error:.2e} | {c.worst or c.status} | {mark} |")
    return "\n".join(rows)
