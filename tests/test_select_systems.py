"""`flexsym select` on a mechanism (issue 19, item 6): the cheapest model and step whose error
against a converged ef stays under the tolerance in every column of the scene."""
from __future__ import annotations

import math
from pathlib import Path

import pytest

from flexsym.analysis.system_select import _reference, _run, choose, errors, select_system, table, with_model
from flexsym.apps.cli import main
from flexsym.core.errors import SpecError
from flexsym.physics.assemble import check_derivable
from flexsym.scenes.scene import load_scene
from flexsym.model.variant import builtin
from flexsym.scenes.system_scene import checked_system

SCENES = Path(__file__).resolve().parent.parent / "scenes"


@pytest.fixture(scope="module")
def four_bar():
    scene = load_scene(SCENES / "four_bar.toml")
    return scene, select_system(scene, 0.01, repeat=1, log=lambda m: None)


def test_four_bar_candidates_against_ef(four_bar):
    """Every modal model runs at 1, 2 and 5 times the step (4 does not divide the 1 ms rows);
    prestress is refused (the coupler is held by its far pin). The reference is ef-16 with N
    and M from equilibrium: the modal errors are those of an independent comparison (m2
    against ef-32 at a quarter step: N_mid 2.7e-4, M_mid 2.0e-4 of the peaks,
    docs/validation/user-mechanisms.md; against the elements' curvature, select's earlier
    reference, M_mid read 6.7e-4) and grow little with the step; the reference's own error is
    well under the tolerance."""
    scene, (results, best, ref_error) = four_bar
    ran = [(c.model, round(c.dt / scene.options.dt)) for c in results if c.status == "ok"]
    assert ran == [(m, k) for m in ("m1", "m2", "m3") for k in (1, 2, 5)]
    refused = [c for c in results if c.status.startswith("refused")]
    assert [c.model for c in refused] == ["prestress"] and "joint 'loop'" in refused[0].status
    assert ref_error < 0.01 / 3
    for c in results:
        if c.model in ("m2", "m3") and c.status == "ok":
            assert 1e-4 < c.error < 6e-4, (c.model, c.dt, c.error)
    m2 = next(c for c in results if c.model == "m2" and c.dt == scene.options.dt)
    assert 2.3e-4 < m2.error < 3.1e-4 and m2.worst == "N_mid"
    assert best is not None and best.error <= 0.01
    assert best.cost <= min(c.cost for c in results if c.error <= 0.01) * 1.5  # the cheapest, within timing noise
    text = table(results, best, 0.01)
    assert text.count("**chosen**") == 1 and "| prestress | – |" in text
    assert choose(results, 1e-5) is None and choose(results, math.inf) is not None


def test_max_bending_on_a_mechanism_is_refused(capsys):
    assert main(["select", str(SCENES / "four_bar.toml"), "--tol", "0.01", "--exact", "--max-bending", "2"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--max-bending" in err and "one-beam scenes" in err


@pytest.mark.parametrize("args, words", [
    (["scenes/four_bar.toml", "--tol", "0", "--exact"], "--tol"),
    (["scenes/four_bar.toml", "--tol", "1e-4", "--exact", "--repeat", "0"], "--repeat"),
    (["scenes/no_such.toml", "--tol", "1e-4", "--exact"], "no_such.toml")])
def test_bad_input_with_exact_is_one_line(capsys, args, words):
    """Refused in one line, exit 2, before any build (--exact changes nothing there)."""
    args[0] = str(SCENES.parent / args[0])
    assert main(["select", *args]) == 2
    out, err = capsys.readouterr()
    assert err.count("\n") == 1 and words in err and out == ""


def test_exact_is_refused_with_its_reason_where_the_scene_reads_the_beams_momentum(tmp_path):
    """The mechanism's momentum as an output: exact refuses it in prepare_system's first check,
    before any derivation (its momentum is not derived), so select lists it as refused with
    that reason."""
    scene = tmp_path / "momentum.toml"
    scene.write_text((SCENES / "four_bar.toml").read_text().replace(
        'M_mid = "M(coupler, mid)" }', 'M_mid = "M(coupler, mid)", H = "momentum" }'))
    s = load_scene(scene)
    system = checked_system(with_model(s.system, "exact"), s.options.t_end)[0]
    with pytest.raises(SpecError, match="needs its momentum"):
        check_derivable(system)


@pytest.mark.study  # two minutes: ef on 64 elements at a quarter of the step, and on 32
def test_the_reference_against_a_finer_ef(four_bar):
    """select's reference, ef-16 from equilibrium at half the step, is within 3.3e-6 of each
    peak of ef-64 at a quarter of the step (M_mid; mostly the step's error: ef-8 at half the
    step is 3.0e-6 off), under its own error as select estimates it (step 1.4e-5, elements
    8.6e-7): it judges 1e-4. Against it m3 at the scene's step is 1.5e-4 off (N_mid); against
    ef-32 from its elements' curvature, select's earlier reference, it read 6.6e-4 (M_mid),
    which was that reference's error (6.5e-4 of the peak)."""
    from flexsym.analysis.system_bench import ef_system

    scene, _ = four_bar
    columns, dt = list(scene.columns), scene.options.dt
    lines = []
    ref, own = _reference(scene, columns, lines.append)
    assert "16 elements per beam (N and M from equilibrium)" in lines[0]
    assert 1e-5 < own < 2e-5  # step 1.4e-5 (M_mid), elements 8.6e-7
    fine = _run(ef_system(scene.system, 64, "equilibrium"), scene, dt / 4)
    actual, _ = errors(ref, fine, columns)
    assert 1e-6 < actual < 5e-6 < own
    m3 = checked_system(with_model(scene.system, "m3"), scene.options.t_end)[0]
    error, worst = errors(_run(m3, scene, dt), ref, columns)
    assert 1.2e-4 < error < 1.8e-4 and worst == "N_mid"
    curvature = _run(ef_system(scene.system, 32), scene, dt / 2)
    assert errors(curvature, fine, columns) == (pytest.approx(6.5e-4, rel=0.05), "M_mid")


@pytest.mark.study  # 5.6 minutes from a fresh cache on 2 loaded cores (exact's build 2-3 min, ef, m1-m3)
def test_exact_on_the_four_bar(capsys):
    """--exact on a mechanism: the built-in exact on the coupler (pp1-pp5 from its pinned ends)
    is a candidate with an error and a cost, against the same reference as the default's (ef-16
    from equilibrium, 3.3e-6 off ef-64): exact 4.9e-5 at the scene's step and at twice it, as
    against ef-32 extrapolated in the elements before (5.3e-5, 4.8e-5,
    docs/howto/choose-model-and-step.md); m3 at 1.5e-4 (N_mid) misses 1e-4."""
    assert main(["select", str(SCENES / "four_bar.toml"), "--tol", "1e-4", "--exact", "--repeat", "1"]) == 0
    out = capsys.readouterr().out
    assert "ef with 16 elements per beam (N and M from equilibrium)" in out
    assert "note:" not in out  # the reference's own error is well under 1e-4
    rows = {tuple(cell.strip() for cell in line.split("|")[1:3]): line.split("|")
            for line in out.splitlines() if line.startswith("| exact |")}
    assert set(rows) == {("exact", "0.0001"), ("exact", "0.0002"), ("exact", "0.0005")}
    for key, cells in rows.items():
        assert float(cells[3]) > 0 and math.isfinite(float(cells[4]))  # a cost and an error
    assert 3e-5 < float(rows[("exact", "0.0001")][4]) < 8e-5
    assert 3e-5 < float(rows[("exact", "0.0002")][4]) < 8e-5
    assert "chosen: model = \"exact\"" in out  # the only model within 1e-4 (which step: timing)


@pytest.mark.study  # about 3 minutes: eight builds and the 20 s spin-up 17 times
def test_select_on_the_spatial_flap():
    """S5 (the hub is guided, so the spatial ef reference is a C kernel): the models' errors
    against ef-32 with N and the moments from equilibrium are those of docs/validation/spatial.md's
    independent comparison against the extrapolated ef-64 (prestress 4.43e-3 in M_lag_A, m3
    3.46e-3 in T_A, m2 2.15e-2 in T_A, m1 0.186 in v_tip: no foreshortening; measured here
    4.41e-3, 3.47e-3, 2.15e-2, 0.186); the chosen one is within the tolerance (which is
    cheapest is timing), and the reference's own error, 3.7e-4 (v_tip, 16 against 32 elements),
    is well under it (from the elements' strains it was 1.6e-2, in T_A)."""
    scene = load_scene(SCENES / "flap.toml")
    results, best, ref_error = select_system(scene, 0.01, repeat=1, log=lambda m: None)
    worst = {c.model: (c.error, c.worst) for c in results if c.status == "ok"}
    assert 4.0e-3 < worst["prestress"][0] < 4.8e-3 and worst["prestress"][1] == "M_lag_A"
    assert 3.1e-3 < worst["m3"][0] < 3.9e-3 and worst["m3"][1] == "T_A"
    assert 0.15 < worst["m1"][0] < 0.25 and worst["m1"][1] == "v_tip"
    assert best.model in ("prestress", "m3") and best.error <= 0.01
    assert 1e-4 < ref_error < 1e-3


@pytest.mark.study  # about 5 minutes: S6's ef on 32 and 16 elements at 50 us, and m1-m3, prestress
def test_select_on_s6_says_its_reference_is_not_converged(capsys):
    """S6's strip on a ball joint, released undeformed, rings in all its modes: 16 and 32 rod
    elements differ by 0.77 of T_mid's peak over the 2 s (as the strains' study found, 0.67),
    so select scores the candidates (0.37 to 1.5) and ends saying the reference is not within
    the tolerance either, exit 1; the rotary inertia's scale moves it by 3.3e-3."""
    assert main(["select", str(SCENES / "spherical_pendulum.toml"), "--tol", "0.01"]) == 1
    out = capsys.readouterr().out
    assert "rotary inertia (0.0002 against 0.0001)" in out
    assert "neither is the reference" in out and "chosen" not in out


def test_the_reference_scales_a_free_beams_rotary_inertia_to_the_modal_beams():
    """A spatial ef beam that a free joint moves keeps its sections' bending rotary inertia (a
    run-time factor, 1 physical), which rolls a strip on a ball joint at O(1) and which the
    modal beams leave out: select's reference runs it at FREE_FRAME_ROTARY (S6's ball joint,
    S7's rod), a guided frame's beam (S5's blade) has no such parameter, and a system with
    several beams names each one's."""
    from dataclasses import replace

    from flexsym.analysis.system_bench import ef_system
    from flexsym.analysis.system_select import FREE_FRAME_ROTARY, _rotary

    def rotary(name):
        return _rotary(ef_system(load_scene(SCENES / name).system, 4, "equilibrium"), FREE_FRAME_ROTARY)

    assert rotary("spherical_pendulum.toml") == {"bending_inertia": FREE_FRAME_ROTARY}
    assert rotary("spatial_slider_crank.toml") == {"bending_inertia": FREE_FRAME_ROTARY}
    assert rotary("flap.toml") == {} and rotary("pendulum.toml") == {}
    s6 = ef_system(load_scene(SCENES / "spherical_pendulum.toml").system, 4, "equilibrium")
    rod = next(b for b in s6.bodies if b.flexible)
    ball = next(j for j in s6.joints if j.child == f"{rod.name}.root")
    two = replace(s6, bodies=s6.bodies + (replace(rod, name="twin"),),
                  joints=s6.joints + (replace(ball, name="twin_ball", child="twin.root"),))
    assert _rotary(two, 1.0) == {f"{rod.name}_bending_inertia": 1.0, "twin_bending_inertia": 1.0}


def test_modal_candidates_keep_the_scenes_torsion_and_recovery(tmp_path):
    """A candidate changes a body's strain model only: a scene that drops the torsion modes and
    asks for constitutive axial forces is scored with them (they change the rows: S7 without torsion
    runs at twice the step), exact and ef candidates take their own, and a body from
    finite-element data keeps its data."""
    scene = tmp_path / "flap.toml"
    scene.write_text((SCENES / "flap.toml").read_text().replace(
        'model = "m3" ', 'model = { variant = "m2", torsion = [], axial_force = "constitutive" }'))
    system = load_scene(scene).system
    for name in ("m1", "m2", "prestress"):
        blade = with_model(system, name).body("blade").model
        assert (blade.strain, blade.torsion, blade.axial_force) == (builtin(name).strain, (), "constitutive")
    default = with_model(load_scene(SCENES / "flap.toml").system, "m2").body("blade").model
    assert default.torsion != () and default.axial_force == "equilibrium"  # a mechanism's default
    assert with_model(system, "ef").body("blade").model.kind == "fe"
    exact = with_model(system, "exact").body("blade").model
    assert exact.axial_force == "equilibrium" and exact.torsion == default.torsion
    mesh = load_scene(SCENES / "flap_mesh.toml").system
    assert with_model(mesh, "m1").body("blade").model.body is mesh.body("blade").model.body is not None
