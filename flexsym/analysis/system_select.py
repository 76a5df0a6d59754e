"""`flexsym select MECHANISM.toml --tol TOL [--exact]`: the cheapest model and step of a
mechanism whose error against the geometrically exact `ef` stays under TOL in every output the
scene names.

Candidates: every flexible body of the scene given the same built-in modal model (m1, m2, m3,
prestress; with --exact also `exact`, its bending modes chosen from each beam's ends by
end_modes as `--model exact` does; a body from finite-element data keeps its data), each at
STEP_FACTORS times the scene's step (those that divide the row interval), with the scene's
integrator and its settings; a model the mechanism refuses (prestress on a beam held beyond its
root, exact where the scene reads the momentum, ...) is listed with its reason.

Reference: every flexible body as `ef` elements at half the scene's step, N and M from the
equilibrium of the part beyond the station: in a planar mechanism 16 ANCF elements (order 4
in the elements: on scenes/four_bar.toml ef-8 and ef-16 at dt/2 are within 3.0e-6 and 3.3e-6
of each peak of ef-64 at dt/4, both mostly their step's error; the elements' curvature, which
converges at order 2, left ef-32 6.5e-4 off in M_mid), in a spatial one 32 rod elements
(order 2 with the motion: on scenes/flap.toml 9.4e-5 of the peaks off ef-64 in v_tip, 6.2e-5
in T_A, where the elements' strains left T_A 6.1e-3 off). A spatial rod that a free joint
moves (a ball joint, a loop's coupler) has its sections' bending rotary inertia scaled to
FREE_FRAME_ROTARY of the physical, as the modal beams have none (on a ball joint it rolls a
strip at O(1)). Its own error is estimated by doubling its step and, apart, halving its
elements (and doubling that rotary inertia), and printed (it should be well under TOL); it
judges --exact's 1e-5 to 1e-4 of the peaks as it is (an earlier reference extrapolated the
curvature's M in the elements).

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
from flexsym.physics.spatial_ef import bending_inertia_param
from flexsym.physics.validity import system_range_notes
from flexsym.scenes.system_scene import checked_system
from flexsym.codegen.folder import MANIFEST
from flexsym.toolchain.pipeline import prepare_system, system_folder

MODELS = ("m1", "m2", "m3", "prestress")
STEP_FACTORS = (1, 2, 4, 5)
REFERENCE_ELEMENTS = {2: 16, 3: 32}  # by the system's dimension (ANCF / rod elements), N and M from equilibrium
# A free frame's rod keeps its sections' bending rotary inertia rho b (I_y, I_z) (a run-time
# factor b, 1 physical); the modal beams have none, so the reference scales it down to theirs.
# b = 0 makes the rod's mass matrix singular; its effect is linear in b (docs/validation/spatial.md)
FREE_FRAME_ROTARY = 1e-4


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


# A modal body's choices that are not its strain model: a modal candidate keeps them (a scene
# that drops the torsion modes or asks for constitutive N is scored as it runs).
KEPT = ("torsion", "axial_force", "moment")


def _floating_modal(model) -> bool:
    return model.kind == "modal" and not model.exact_kinematics


def with_model(system, name: str):
    """Every flexible body with the built-in model `name` (a body's finite-element data kept,
    and a modal body's KEPT choices when `name` is modal)."""
    base = builtin(name)

    def model(old):
        new = base if getattr(old, "body", None) is None else replace(base, body=old.body)
        if _floating_modal(base) and _floating_modal(old):
            new = replace(new, **{k: getattr(old, k) for k in KEPT})
        return new

    return replace(system, bodies=tuple(replace(b, model=model(b.model)) if b.flexible else b
                                        for b in system.bodies))


TUNING = ("newton_tol", "rho_inf", "penalty", "newmark_beta", "newmark_gamma")


def _run(system, scene, dt: float, repeat: int = 1, params=None):
    """system_bench's run of a scene's rows, at step dt, with the scene's integrator settings
    (and run-time parameters `params`)."""
    o = scene.options
    tuning = tuple((k, getattr(o, k)) for k in TUNING if getattr(o, k) is not None)
    return run_rows(prepare_system(system), scene, o.integrator, dt, repeat,
                    tuning + ((("params", params),) if params else ()))


def _rotary(system, b: float) -> dict:
    """The bending rotary inertia factor b for every spatial ef beam a free joint moves."""
    names = (bending_inertia_param(system, x.name) for x in system.bodies if x.flexible)
    return {n: b for n in names if n is not None} if system.dimension == 3 else {}


def coordinates(system) -> int:
    manifest = json.loads((system_folder(system) / MANIFEST).read_text(encoding="utf-8"))
    return len(manifest["coordinates"])


def errors(r, ref, columns) -> tuple[float, str]:
    """(largest error, its column): system_bench's per-column max |y - y_ref| / peak |y_ref|."""
    per = column_errors(r, ref, columns, "e")
    worst = max(columns, key=lambda c: per[f"e_{c}"])
    return per[f"e_{worst}"], worst


def _reference(scene, columns, log):
    """(reference rows, its own error estimated: the largest over the columns of its changes
    when its step and, apart, its elements are doubled, and, for a beam a free joint moves,
    when its sections' bending rotary inertia is doubled)."""
    o = scene.options
    n = REFERENCE_ELEMENTS[scene.system.dimension]
    ef = ef_system(scene.system, n, "equilibrium")
    rotary = _rotary(ef, FREE_FRAME_ROTARY)
    log(f"reference: ef with {n} elements per beam (N and M from equilibrium), {o.integrator} at "
        f"dt = {o.dt / 2:g} s" + (f"; the sections' bending rotary inertia {FREE_FRAME_ROTARY:g} of the "
                                 "physical on the beams a free joint moves, as the modal beams' (none)"
                                 if rotary else ""))
    ref = _run(ef, scene, o.dt / 2, params=rotary)
    if not ref.ok:
        raise SpecError(f"{scene.path}: the ef reference stopped ({ref.message}); select needs a "
                        "reference: try a smaller [solver] dt")
    outside = system_range_notes(ef, ref)
    if outside:  # no model is derived for this motion: nothing to select
        raise SpecError(f"{scene.path}: the ef reference {outside[0]}")
    half_step = _run(ef, scene, o.dt, params=rotary)
    half_mesh = _run(ef_system(scene.system, n // 2, "equilibrium"), scene, o.dt / 2, params=rotary)
    more_rotary = [_run(ef, scene, o.dt / 2, params=_rotary(ef, 2 * FREE_FRAME_ROTARY))] if rotary else []
    own = [errors(r, ref, columns) if r.ok else (math.inf, "its run stopped")
           for r in [half_step, half_mesh] + more_rotary]
    log(f"  the reference's own error, estimated: step (dt against dt/2) {own[0][0]:.1e} ({own[0][1]}), "
        f"elements ({n // 2} against {n}) {own[1][0]:.1e} ({own[1][1]})"
        + (f", rotary inertia ({2 * FREE_FRAME_ROTARY:g} against {FREE_FRAME_ROTARY:g}) {own[2][0]:.1e} "
           f"({own[2][1]})" if rotary else "") + " of the peaks")
    return ref, max(e for e, _ in own)


def exact_modes(system) -> str:
    """The bending modes end_modes gave each flexible body: 'coupler pp1-pp5'."""
    out = []
    for b in system.bodies:
        if b.flexible and getattr(b.model, "bending", None):
            tokens = [m.token for m in b.model.bending]
            out.append(f"{b.name} " + (f"{tokens[0]}-{tokens[-1]}" if len(tokens) > 2 else ", ".join(tokens)))
    return "; ".join(out)


def select_system(scene, tol: float, repeat: int = 3, log=print, exact: bool = False):
    """(candidates, chosen or None, reference's own error); exact: also the built-in `exact`."""
    columns = list(scene.columns)
    o = scene.options
    steps = [o.dt * k for k in STEP_FACTORS if o.out_every % k == 0]
    ref, ref_error = _reference(scene, columns, log)
    results = []
    for name in MODELS + (("exact",) if exact else ()):
        try:
            system = checked_system(with_model(scene.system, name), o.t_end)[0]
            if name == "exact":
                log(f"  exact: bending {exact_modes(system)} (a build takes a minute or more)")
            prepare_system(system)
        except SpecError as exc:  # what this mechanism cannot take from that model
            results.append(SystemCandidate(name, o.dt, status="refused: " + str(exc).split(": ", 2)[-1]))
            log(f"  {name}: refused")
            continue
        size = coordinates(system)
        for dt in steps:
            c = SystemCandidate(name, dt)
            r = _run(system, scene, dt)
            outside = system_range_notes(system, r) if r.ok else []
            if not r.ok or outside:  # not scored: a run that stopped, or left its model's range
                c.status = r.message if not r.ok else outside[0]
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
