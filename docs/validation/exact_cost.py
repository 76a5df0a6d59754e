"""Cost against error of the `exact` model on the 20 s spin-up at omega_s = 6 (v_tip only, rows
every 10 ms), docs/theory/exact-kinematics.md "Cost":

    python docs/validation/exact_cost.py

Per model, step and Newton tolerance: the integration CPU (median of 11 runs), the integration
error (against the same model by RK4 at 0.1 ms) and the error against the converged reference
(`ef`, 32 elements at 0.5 ms: flexsym.analysis.bench's). Builds the reference and both models
on first use (minutes)."""
import numpy as np

from flexsym.analysis.bench import SPIN, T_END, model_reference
from flexsym.apps import api
from flexsym.toolchain.pipeline import prepare
from flexsym.toolchain.run import run_built

# (integrator, step, --newton-tol): radau5's default tolerance leaves 1e-11 m in each step's
# Newton iterations, 1e-9 leaves 1e-8 m, both far below the step's own error
CASES = (("radau5", 0.25, None), ("radau5", 0.2, None), ("radau5", 0.16, None), ("radau5", 0.125, None),
         ("radau5", 0.1, None), ("radau5", 0.16, 1e-9), ("radau5", 0.125, 1e-9), ("genalpha", 0.005, None))


def main() -> None:
    mref = model_reference()
    for axial in ("ff1", None):
        spec = api.variant("exact", outputs="v_tip", **({"axial": axial} if axial else {}))
        built = prepare(spec)
        iref = run_built(built, t_end=T_END, dt=1e-4, integrator="rk4", params=SPIN, out_every=10)
        for integrator, step, newton_tol in CASES:
            grid = dict(step=step, dt=0.01) if integrator == "radau5" else dict(dt=step, out_every=2)
            if newton_tol is not None:
                grid["newton_tol"] = newton_tol
            r = run_built(built, t_end=T_END, integrator=integrator, params=SPIN, repeat=11, **grid)
            tol = f" --newton-tol {newton_tol:g}" if newton_tol is not None else ""
            print(f"exact{' --axial ' + axial if axial else ''} {integrator} {step:g} s{tol}: "
                  f"CPU {r.summary['cpu_median'] * 1e3:.2f} ms, {r.summary['newton_iterations']} "
                  f"iterations, integration error {np.max(np.abs(r.minus(iref))):.1e} m, "
                  f"against ef {np.max(np.abs(r.minus(mref))):.1e} m", flush=True)


if __name__ == "__main__":
    main()
