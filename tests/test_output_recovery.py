"""An output may name its own recovery, N(B, x, equilibrium) or M(B, x, constitutive) (Mx, My,
Mz in 3D), over its beam model's axial_force / moment (system.output_beam): one run carries
both, e.g. the curvature's root moment next to the equilibrium one. Each such column equals
the same output of a model that takes that recovery for the whole beam."""
import numpy as np

from system_data import built, run_ok

STRIP = {"name": "beam", "kind": "beam", "length": 1.0, "density": 2700.0, "youngs_modulus": 7e10,
         "area": 1e-4, "inertia": 2.0833333333333336e-10, "markers": {"mid": 0.5}}


def _pendulum(model, columns: dict) -> dict:
    """S3's strip on a pin under gravity, released horizontal."""
    return {"system": {"name": "recovery_pendulum"}, "body": [STRIP | {"model": model}],
            "joint": [{"name": "pin", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0],
                       "child": "beam.root"}],
            "gravity": {"g": [0.0, -9.81]}, "output": {"columns": columns}}


def test_a_named_recovery_is_the_models_own():
    """m2 (axial modes: both N's exist) over 0.3 s: with the model's default (equilibrium) a
    column naming "constitutive" equals the same column of a model whose moment and axial force
    are "constitutive", and the other way round, to 1e-12 of the peak (measured: 0; two
    builds); naming the model's own recovery changes nothing (exactly). The two recoveries
    differ by 2.8 % to 7.5 % of the peak (checked: more than 1 %), so equal columns are not an
    accident."""
    at = ("mid", "0.25")
    same = {f"{f}{k}": f"{f}(beam, {x})" for f in "NM" for k, x in enumerate(at)}
    eq = {f"{f}{k}_eq": f"{f}(beam, {x}, equilibrium)" for f in "NM" for k, x in enumerate(at)}
    con = {f"{f}{k}_con": f"{f}(beam, {x}, constitutive)" for f in "NM" for k, x in enumerate(at)}
    own = {"variant": "m2", "moment": "constitutive", "axial_force": "constitutive"}
    kw = dict(t_end=0.3, dt=1e-4, integrator="genalpha", out_every=10)
    r_eq = run_ok(built(_pendulum("m2", same | eq | con)), **kw)
    r_con = run_ok(built(_pendulum(own, same | eq)), **kw)
    for c in same:
        peak = np.abs(r_eq[c]).max()
        assert np.array_equal(r_eq[c], r_eq[f"{c}_eq"]), c
        assert np.abs(r_eq[f"{c}_con"] - r_con[c]).max() <= 1e-12 * peak, c
        assert np.abs(r_con[f"{c}_eq"] - r_eq[c]).max() <= 1e-12 * peak, c
        assert np.abs(r_eq[c] - r_con[c]).max() > 1e-2 * peak, c


def test_a_reference_takes_its_own_recovery():
    """select's and bench-systems' ef reference (system_bench.ef_system) takes N and M by its
    own recovery: a candidate's M(B, x, constitutive) is measured against the reference's
    moment, not against the reference's elements' curvature; "auto" keeps the output's."""
    from flexsym.analysis.system_bench import ef_system
    from flexsym.scenes.system_scene import system_from_dict

    system = system_from_dict(_pendulum("m3", {"M_con": "M(beam, root, constitutive)", "M": "M(beam, mid)",
                                               "N_eq": "N(beam, mid, equilibrium)"}))
    quantities = {o.column: o.quantity for o in ef_system(system, 4, "equilibrium").outputs}
    assert quantities == {"M_con": "M(beam, root)", "M": "M(beam, mid)", "N_eq": "N(beam, mid)"}
    kept = {o.column: o.quantity for o in ef_system(system, 4, "auto").outputs}
    assert kept == {o.column: o.quantity for o in system.outputs}
