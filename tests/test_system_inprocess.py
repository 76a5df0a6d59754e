"""In-process batches and sweeps of system scenes (issue 13 for the mechanisms of issue 10):
a tree system (hub, nc = 0) and a closed loop (slider-crank, nc > 0, ali3p, a violation
column). Rows bit for bit those of `flexsym run SCENE`; a failed run leaves the others alone;
the sweep table's summaries are those of the rows; unknown names refused in one line."""
import dataclasses
from pathlib import Path

import numpy as np
import pytest

from flexsym.apps.cli import main
from flexsym.sim.inprocess import load_system
from flexsym.toolchain.run import run_built
from flexsym.scenes.scene import load_scene
from flexsym.sim.inprocess import settings_of
from flexsym.sim.sweep import read_table
from flexsym.toolchain.pipeline import prepare_system

SCENES = Path(__file__).resolve().parents[1] / "scenes"


@pytest.fixture(scope="module")
def system(isolated_cache):
    loaded = {}

    def get(name):
        if name not in loaded:
            scene = load_scene(SCENES / f"{name}.toml")
            loaded[name] = scene, load_system(scene.system), prepare_system(scene.system)
        return loaded[name]
    return get


@pytest.mark.parametrize("name, changed", [
    ("hub", {"E": 0.7, "rho": 1.1}),
    ("slider_crank", {"ws": 0.7, "E": 3.0}),
])
def test_system_batch_rows_equal_flexsym_run_bit_for_bit(system, name, changed):
    """Run 0 has the scene's own values: its rows are `flexsym run SCENE`'s; run 1 scales them."""
    scene, model, built = system(name)
    defaults = model.params | model.maneuver_params
    runs = {k: [defaults[k], f * defaults[k]] for k, f in changed.items()}
    b = model.batch(runs, rows=True, **settings_of(scene.options, True))
    assert b.status == ["ok", "ok"]
    for i in range(2):
        params = {k: v[i] for k, v in runs.items()}
        ref = run_built(built, dataclasses.replace(scene.options, params=params))
        assert b.row_columns == ref.columns
        assert np.array_equal(b.result(i).data, ref.data)  # bit for bit
        for j, c in enumerate(b.columns):  # summaries in C are those of the rows
            assert b.summary(c, "min")[i] == ref[c].min() and b.summary(c, "final")[i] == ref[c][-1]
    assert not np.array_equal(b.rows[0], b.rows[1])
    assert ("violation" in b.columns) == (name == "slider_crank")
    default = run_built(built, scene.options)
    assert np.array_equal(b.rows[0], default.data)


def test_constrained_batch_isolates_a_failed_run_and_keeps_the_initial_assembly(system):
    """A huge initial modal rate makes ali3p's Newton fail in run 1 only; naming one
    coordinate's initial value keeps the others at the joints' initial values (the scene's
    assembly), so runs 0 and 2 are the scene's run exactly."""
    scene, model, built = system("slider_crank")
    b = model.batch({"qd0_rod_v_cp1": [0.0, 1e9, 0.0]}, rows=True, **settings_of(scene.options, True))
    assert b.status == ["ok", "failed", "ok"]
    assert "Newton" in b.messages[1] and b.messages[0] == b.messages[2] == ""
    ref = run_built(built, scene.options)
    assert np.array_equal(b.rows[0], ref.data) and np.array_equal(b.rows[2], ref.data)
    assert np.isnan(b.summary("x_s", "min")[1]) or b.stats["rows"][1] >= 1
    # the loop stays closed: the violation (max |Phi| / size) is at round-off
    assert b.summary("violation", "max")[0] < 1e-12


def test_cli_sweep_of_a_system_scene_names_the_violation_column(system, tmp_path, capsys):
    scene, _, built = system("slider_crank")
    out = tmp_path / "sc.csv"
    assert main(["sweep", str(SCENES / "slider_crank.toml"), "--vary", "ws=100,150", "--at", "0.1",
                 "--out", str(out), "--workers", "1"]) == 0
    table = read_table(out)
    assert list(table["status"]) == ["ok", "ok"]
    for i, ws in enumerate((100.0, 150.0)):
        ref = run_built(built, dataclasses.replace(scene.options, params={"ws": ws}))
        k = int(np.flatnonzero(np.isclose(ref.t, 0.1, rtol=0, atol=1e-12))[0])
        for c in ("x_s", "N_mid", "violation"):
            assert table[f"{c}_min"][i] == ref[c].min() and table[f"{c}_max"][i] == ref[c].max()
        assert table["x_s_at_0.1"][i] == pytest.approx(ref["x_s"][k], rel=1e-12)


def test_system_sweep_refuses_an_unknown_name_in_one_line(system, tmp_path, capsys):
    out = tmp_path / "t.csv"
    assert main(["sweep", str(SCENES / "hub.toml"), "--vary", "BEAM_E=1,2", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--vary BEAM_E: unknown parameter" in err[0] and "E, " in err[0]
    assert main(["sweep", str(SCENES / "hub.toml"), "--vary", "E=-1,2", "--out", str(out)]) == 2
    assert "--vary E=-1" in capsys.readouterr().err
    assert not out.exists()


def test_api_sweep_and_inprocess_take_a_system_scene(system, tmp_path):
    """The pendulum (a tree under gravity): api.sweep over a shortened scene equals the batch of
    api.inprocess, whose run at the scene's values is `flexsym run SCENE`'s."""
    from flexsym.apps import api

    scene, _, built = system("pendulum")
    model = api.inprocess(SCENES / "pendulum.toml")
    e = model.params["E"]
    table = api.sweep(SCENES / "pendulum.toml", {"E": [e, 2 * e]}, tmp_path / "p.csv", workers=1)
    b = model.batch({"E": [e, 2 * e]}, rows=True, **settings_of(scene.options, True))
    assert list(table["status"]) == ["ok", "ok"]
    assert np.array_equal(table["x_tip_min"], b.summary("x_tip", "min"))
    assert np.array_equal(b.rows[0], run_built(built, scene.options).data)


@pytest.mark.parametrize("integrator", ["genalpha", "ali3p"])
def test_blowup_bounds_lengths_not_the_angle_of_a_revolute_joint(system, integrator):
    """The blow-up limit is blowup x the length scale (1 m for S3) on coordinates that are
    lengths: the pendulum thrown over the top (q'(0) = 20 rad/s) turns past 10 rad and runs to
    the end with both families of integrators (the angle has no such bound), while a limit at
    half the peak of the beam's modal coordinates stops the same run at one of them."""
    scene, model, _ = system("pendulum")
    opts = settings_of(scene.options, True) | {"integrator": integrator, "t_end": 0.6}
    turned = model.batch({"qd0_pin": [20.0]}, rows=True, **opts)
    assert turned.status == ["ok"], turned.messages
    r = turned.result(0)
    assert r["pin"][-1] > 10.0  # rad: beyond blowup x L = 10, were it a length
    modal = [c for c in model.coordinates if c != "pin"]
    peak = max(np.abs(r[c]).max() for c in modal)
    stopped = model.batch({"qd0_pin": [20.0]}, **(opts | {"blowup": 0.5 * peak}))
    assert stopped.status == ["diverged"]
    assert any(f"|{c}| =" in stopped.messages[0] for c in modal), stopped.messages[0]
    assert f"exceeds {0.5 * peak:g} x L" in stopped.messages[0]
