"""Cost against error of the `exact` model on the 20 s spin-up at omega_s = 6 (v_tip only, rows
every 10 ms), docs/theory/exact-kinematics.md "Cost":

    python docs/validation/exact_cost.py

Per model and step: the integration CPU (median of 11 runs), the integration error (against the
same model by RK4 at 0.1 ms) and the error against the converged reference (`ef`, 32 elements at
0.5 ms: flexsym.analysis.bench's). Builds the reference and both models on first use (minutes)."""
import numpy as np

from flexsym.analysis.bench import SPIN, T_END, model_reference
from flexsym.apps import api
from flexsym.toolchain.pipeline import prepare
from flexsym.toolchain.run import run_built

CASES = (("radau5", 0.25), ("radau5", 0.2), ("radau5", 0.125), ("radau5", 0.1), ("genalpha", 0.005))


def main() -> None:
    mref = model_reference()
    for axial in ("ff1", None):
        spec = api.variant("exact", outputs="v_tip", **({"axial": axial} if axial else {}))
        built = prepare(spec)
        iref = run_built(built, t_end=T_END, dt=1e-4, integrator="rk4", params=SPIN, out_every=10)
        for integrator, step in CASES:
            grid = dict(step=step, dt=0.01) if integrator == "radau5" else dict(dt=step, out_every=2)
            r = run_built(built, t_end=T_END, integrator=integrator, params=SPIN, repeat=11, **grid)
            print(f"exact{' --axial ' + axial if axial else ''} {integrator} {step:g} s: "
                  f"CPU {r.summary['cpu_median'] * 1e3:.2f} ms, integration error "
                  f"{np.max(np.abs(r.minus(iref))):.1e} m, against ef {np.max(np.abs(r.minus(mref))):.1e} m",
                  flush=True)


if __name__ == "__main__":
    main()
