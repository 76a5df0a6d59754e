"""A spatial ef beam's section forces from equilibrium (`moment` / `axial_force` =
"equilibrium": body_kinds/spatial/ef._equilibrium): the part of the beam beyond the station,
its elements' inertia, gravity and alpha damping and its sections' lumped spin momentum, and
the loads on its markers there, in the deformed section's axes. Checked against the clamp's
reaction (the whole beam's momentum balance, another path) and against the statics of a
cantilever, where the elements' own (constitutive) forces are percents off on 4 elements."""
import numpy as np

from system_data import built, run_ok
from test_spatial_damping import cantilever

FORCES = ("N", "Qy", "Qz", "Mx", "My", "Mz")


def _model(n: int, recovery: str) -> dict:
    return {"variant": "ef", "elements": n, "moment": recovery, "axial_force": recovery}


def test_the_root_section_forces_are_the_clamps_reaction():
    """The cantilever of tests/test_spatial_damping.py as 4 ef elements, damped by alpha,
    released under gravity in both planes: N, Qy, Qz, Mx, My, Mz at the root from equilibrium
    (integrated accelerations, lumped spin momenta, the damper's load) equal minus the clamp's
    reaction (the momentum balance of the whole beam through its first moment and angular
    momentum, their time derivatives by casadi) within 1e-12 of each peak (measured 5.7e-16)."""
    columns = {f"{f}_0": f"{f}(beam, root)" for f in FORCES}
    columns |= {f"R_{c}": f"reaction(root, {c})" for c in ("x", "y", "z", "mx", "my", "mz")}
    r = run_ok(built(cantilever({"alpha": 1.0}, model=_model(4, "equilibrium"), columns=columns)),
               t_end=0.5, dt=2.5e-4, integrator="newmark", out_every=20)
    for f, c in zip(FORCES, ("x", "y", "z", "mx", "my", "mz")):
        y, R = r[f"{f}_0"], r[f"R_{c}"]
        assert np.abs(y).max() > 0.05
        assert np.abs(y + R).max() <= 1e-12 * np.abs(R).max(), f


def test_a_cantilevers_static_moments_at_and_between_nodes():
    """The same cantilever, 4 elements, at rest in its static sag (start = "static") under a
    small gravity q = rho A g in both planes: from equilibrium My(x) = q (L - x)^2 / 2,
    Mz = -My and Qz = -q (L - x) at the root, between nodes (0.3 L) and at a node (0.5 L),
    within 1e-6 (measured 2e-8: the sag's own geometry); the elements' strains (linear between
    the element midpoints) give My 3.1 % (root) to 12.5 % (mid-span) off. A beam that names
    no recovery gets equilibrium's, and its outputs that name "constitutive" equal the strains'
    beam's. The recoveries are three such cantilevers in one system (one build)."""
    from test_spatial_damping import A, L, RHO

    q = RHO * A * 0.0981
    stations = (0.0, 0.3, 0.5)
    beams = {"equilibrium": "beam", "constitutive": "own", "auto": "auto"}
    columns = {f"{b}_{f}_{k}": f"{f}({b}, {x})" for b in beams.values()
               for f in ("Qz", "My", "Mz") for k, x in enumerate(stations)}
    # an output's own recovery (tests/test_output_recovery.py): the strains' on the default beam
    columns |= {f"auto_{f}_con_{k}": f"{f}(auto, {x}, constitutive)" for f in ("My", "Mz")
                for k, x in enumerate(stations)}
    data = cantilever({}, model=_model(4, "equilibrium"), g=(0.0, -0.0981, -0.0981), columns=columns)
    data["system"]["start"] = "static"
    del data["body"][0]["damping"]
    for k, (recovery, name) in enumerate(list(beams.items())[1:]):  # in line: x = 2, 4
        model = _model(4, recovery) if recovery != "auto" else {"variant": "ef", "elements": 4}
        data["body"].append(dict(data["body"][0], name=name, model=model))
        data["joint"].append({"name": f"root_{name}", "kind": "clamp", "parent": "ground",
                              "point": [2.0 * (k + 1), 0.0, 0.0], "child": f"{name}.root"})
    r = run_ok(built(data), t_end=0.01, dt=1e-3, integrator="newmark", out_every=1)
    for k, x in enumerate(stations):
        moment = q * (L - x)**2 / 2
        assert np.abs(r[f"beam_My_{k}"] - moment).max() <= 1e-6 * moment
        assert np.abs(r[f"beam_Mz_{k}"] + moment).max() <= 1e-6 * moment
        assert np.abs(r[f"beam_Qz_{k}"] + q * (L - x)).max() <= 1e-6 * q * L
        assert np.abs(r[f"own_My_{k}"][0] - moment) > 0.02 * moment
        for f in ("Qz", "My", "Mz"):
            assert np.abs(r[f"auto_{f}_{k}"] - r[f"beam_{f}_{k}"]).max() <= 1e-12 * moment
        for f in ("My", "Mz"):
            assert np.abs(r[f"auto_{f}_con_{k}"] - r[f"own_{f}_{k}"]).max() <= 1e-12 * moment
