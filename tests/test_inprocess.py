"""In-process batch runs (runtime_c/src/batch.c, flexsym/sim/inprocess.py): the same rows, bit for
bit, as the driver behind `flexsym run`; summaries computed in C equal numpy's over those rows;
one failing run of a batch leaves the others untouched; validity per run as validity.assess."""
import numpy as np
import pytest

from flexsym.apps import api
from flexsym.core.errors import SpecError
from flexsym.toolchain.pipeline import prepare
from flexsym.toolchain.run import run_built
from flexsym.model.variant import builtin
from flexsym.physics.validity import assess

# variant, run options, parameter sets: every integrator, modal and finite elements
CASES = [
    ("m3", dict(integrator="radau5", dt=0.01, step=0.25, t_end=20.0), {"ws": [6.0, 4.0], "L": [10.0, 9.0]}),
    ("m1", dict(integrator="genalpha", dt=0.005, t_end=6.0), {"ws": [6.0, 3.0], "E": [7e10, 5e10]}),
    ("prestress", dict(integrator="rk4", dt=0.02, t_end=8.0, out_every=3), {"ws": [6.0, 5.0]}),
    ("m2", dict(integrator="dopri5", dt=0.01, tol=1e-7, t_end=3.0), {"ts": [15.0, 5.0]}),
    ("ef", dict(integrator="newmark", dt=0.01, t_end=2.0, newmark_gamma=0.5, newmark_beta=0.5625), {"ws": [6.0, 8.0]}),
    ("m3", dict(integrator="ali3p", dt=0.01, t_end=3.0, penalty=1e6, newton="full"), {"ws": [6.0, 4.0]}),
    ("m1", dict(integrator="genalpha3", dt=0.01, t_end=3.0, rho_inf=0.7), {"ts": [15.0, 5.0]}),
]


@pytest.mark.parametrize("variant,options,runs", CASES, ids=[c[0] + "-" + c[1]["integrator"] for c in CASES])
def test_batch_rows_equal_flexsym_run_bit_for_bit(isolated_cache, variant, options, runs):
    spec = builtin(variant)
    b = api.inprocess(spec).batch(runs, rows=True, **options)
    built = prepare(spec)
    for i in range(len(b)):
        params = {k: float(v[i]) for k, v in runs.items()}
        ref = run_built(built, params=params, **options)
        got = b.result(i)
        assert ref.ok and got.ok
        assert got.columns == ref.columns
        assert got.data.shape == ref.data.shape and np.array_equal(got.data, ref.data)  # bit for bit
        for key in ("steps", "newton_iterations", "jacobian_evaluations", "force_evaluations"):
            assert got.summary[key] == ref.summary[key], key
    # the parameter sets differ, so must the runs
    assert not np.array_equal(b.rows[0], b.rows[1])


def test_summaries_in_c_equal_numpy_over_the_rows(isolated_cache):
    at = [0.0, 7.5, 15.0, 19.999, 12.3456, 25.0]  # unsorted; 25 s is past the last row
    b = api.inprocess("m3").batch({"ws": [6.0, 3.0]}, rows=True, at=at, integrator="radau5", dt=0.01,
                                  step=0.25, t_end=20.0)
    for i in range(len(b)):
        r = b.result(i)
        for col in b.columns:
            y = r[col]
            assert b.summary(col, "min")[i] == y.min() and b.summary(col, "max")[i] == y.max()
            assert b.summary(col, "t_min")[i] == r.t[np.argmin(y)]
            assert b.summary(col, "t_max")[i] == r.t[np.argmax(y)]
            assert b.summary(col, "t_peak")[i] == r.t[np.argmax(np.abs(y))]
            assert b.summary(col, "final")[i] == y[-1]
            for t in at[:-1]:
                assert b.summary(col, f"at:{t}")[i] == pytest.approx(np.interp(t, r.t, y), rel=1e-12, abs=1e-15)
            assert np.isnan(b.summary(col, "at:25.0")[i])
    # a time on a row is that row's value exactly
    r = b.result(0)
    k = int(np.flatnonzero(r.t == 15.0)[0])
    assert b.summary("v_tip", "at:15.0")[0] == r["v_tip"][k]


def test_a_diverging_run_does_not_lose_the_others(isolated_cache):
    """#0 diverges at ws = 6 (no stiffening) and not at ws = 2: in one batch, each run is
    what it is alone, including the failed run's message and the rows it computed."""
    spec = builtin("m0")
    built = prepare(spec)
    options = dict(integrator="genalpha", dt=0.005, t_end=20.0)
    b = api.inprocess(spec).batch({"ws": [2.0, 6.0, 2.5]}, rows=True, **options)
    assert b.status == ["ok", "diverged", "ok"]
    assert b.valid.tolist() == [True, False, True]
    for i, ws in enumerate((2.0, 6.0, 2.5)):
        ref = run_built(built, params={"ws": ws}, **options)
        assert ref.status == b.status[i] and ref.message == b.messages[i]
        assert np.array_equal(b.result(i).data, ref.data)
    assert "diverged at t = " in b.messages[1] and b.stats["t_stop"][1] < 20.0
    assert b.stats["t_stop"][0] == 20.0
    # summaries of the failed run cover the rows it computed
    assert b.summary("v_tip", "final")[1] == b.rows[1][-1, 1]


def test_bad_options_fail_their_run_only(isolated_cache):
    b = api.inprocess("m3").batch({"L": [10.0, -1.0, 10.0]}, integrator="rk4", dt=0.02, t_end=1.0)
    assert b.status == ["ok", "failed", "ok"]
    assert "beam parameter L must be a positive number" in b.messages[1]
    assert np.isnan(b.summary("v_tip", "min")[1]) and not np.isnan(b.summary("v_tip", "min")[0])


@pytest.mark.parametrize("outputs", [None, "M_A"])
def test_validity_per_run_matches_assess(isolated_cache, outputs):
    """|v| > 0.1 L flagged per run from C's bound, as validity.assess flags the full rows
    (v_tip when an output, else the bound from the bending coordinates)."""
    spec = builtin("m3") if outputs is None else api.variant("m3", outputs=outputs, name="m3_root")
    options = dict(integrator="radau5", dt=0.01, step=0.25, t_end=20.0)
    ws = [6.0, 20.0, 12.0]
    b = api.inprocess(spec).batch({"ws": ws}, **options)
    built = prepare(spec)
    verdicts = [assess(spec, run_built(built, params={"ws": w}, **options)) for w in ws]
    assert b.valid.tolist() == [v.valid for v in verdicts]
    assert b.valid.tolist()[:2] == [True, False]
    for note, v in zip(b.validity_notes, verdicts):
        if not v.valid:  # same first time over the limit
            assert note.split(":")[0] == v.notes[0].split(":")[0]


def test_unknown_parameter_and_mismatched_lengths_are_refused(isolated_cache):
    m = api.inprocess("m3")
    with pytest.raises(SpecError, match="unknown parameter 'omega'"):
        m.batch({"omega": [1.0]})
    with pytest.raises(SpecError, match="same number of values"):
        m.batch({"ws": [1.0, 2.0], "ts": [3.0]})
    with pytest.raises(SpecError, match="unknown integrator"):
        m.batch({"ws": [1.0]}, integrator="euler")


# ali3p (the trapezoidal rule here: no constraints): phase error (w dt)^2 / 12 per radian
@pytest.mark.parametrize("integrator,dt", [("rk4", 1e-3), ("radau5", 0.01), ("ali3p", 2e-4)])
def test_initial_state_gives_free_vibration_in_one_mode(isolated_cache, integrator, dt):
    """q0_*/qd0_* start a run away from rest. #0 without rotation (ws = 0) is a linear system
    M q'' + K q = 0: started on an eigenvector of (K, M) it stays in that mode, so
    v_tip(t) = v0 cos(w t) from a displacement, and (vd0 / w) sin(w t) from a velocity."""
    spec = builtin("m0")
    k = api.kernels(spec)
    n = k.nq
    z = np.zeros(n)
    M = k.mass(z)
    K = k.residual_jac(z, z, z, 0.0)[0]  # dr/dq of r = M q'' - f at rest, no rotation
    w2, vecs = np.linalg.eig(np.linalg.solve(M, K))
    j = int(np.argmin(w2.real))
    omega, phi = float(np.sqrt(w2[j].real)), vecs[:, j].real
    assert 3.7 < omega < 3.9  # the first bending frequency, 3.80 rad/s
    phi *= 0.05 / k.outputs(phi)["v_tip"]  # tip amplitude 5 cm
    coords = [c["name"] for c in k.manifest["coordinates"]]
    runs = {"ws": [0.0, 0.0]}
    runs |= {f"q0_{c}": [phi[i], 0.0] for i, c in enumerate(coords)}
    runs |= {f"qd0_{c}": [0.0, phi[i]] for i, c in enumerate(coords)}
    b = api.inprocess(spec).batch(runs, rows=True, integrator=integrator, dt=dt, t_end=5.0)
    assert b.status == ["ok", "ok"]
    shifted, kicked = b.result(0), b.result(1)
    assert np.array_equal(shifted.data[0, -n:], phi) and np.all(kicked.data[0, -n:] == 0)
    t = shifted.t
    assert np.max(np.abs(shifted["v_tip"] - 0.05 * np.cos(omega * t))) < 1e-7
    assert np.max(np.abs(kicked["v_tip"] - 0.05 / omega * np.sin(omega * t))) < 1e-7


def test_non_finite_initial_state_fails_its_run(isolated_cache):
    b = api.inprocess("m3").batch({"q0_v_cp1": [0.0, np.inf]}, integrator="rk4", dt=0.02, t_end=1.0)
    assert b.status == ["ok", "failed"] and "initial value of v_cp1 is not finite" in b.messages[1]


def test_a_scene_loaded_in_process_runs_as_the_scene_says(tmp_path):
    """api.inprocess(scene): a batch call that gives no option or value runs as `flexsym run
    SCENE` does, bit for bit: a one-beam scene's beam (here 8 m of density 2700, not the
    variant's 10 m of 3000) and step, and a mechanism's integrator (genalpha3: its loop). An
    option given to the call wins. (Before, both ran with the option table's defaults and the
    one-beam scene with its variant's beam.)"""
    from pathlib import Path

    from flexsym.apps.cli import main

    scenes = Path(__file__).resolve().parents[1] / "scenes"
    text = (scenes / "constant_speed.toml").read_text()
    short = tmp_path / "short.toml"
    short.write_text(text.replace("length = 10.0", "length = 8.0").replace("density = 3000.0", "density = 2700.0"))
    for scene, flags, columns in ((short, (), ("u_tip", "N_A")),
                                  (scenes / "four_bar.toml", ("--t-end", "0.02"), ("rocker", "N_mid", "M_mid"))):
        out = tmp_path / f"{scene.stem}.csv"
        assert main(["run", str(scene), "--out", str(out), *flags]) == 0
        want = np.genfromtxt(out, delimiter=",", names=True, comments="#")
        model = api.inprocess(str(scene))
        got = model.batch({}, rows=True, **({"t_end": 0.02} if flags else {})).result(0)
        assert got.ok, got.message
        assert len(got["t"]) == len(want["t"]) > 20
        for c in columns:
            assert np.array_equal(got[c], want[c]), (scene.name, c)
    assert model.batch({}, t_end=0.01).status == ["ok"]  # the call's own t_end
