"""System scenes (flexsym/scenes/system_scene.py): the grammar, the shipped scenes S1-S3, and
malformed systems refused in one line naming the file and the item, exit 2, nothing written."""
from __future__ import annotations

import math

import numpy as np
from pathlib import Path

import pytest

from flexsym.model import library as lib
from flexsym.apps.cli import main
from flexsym.core.errors import SpecError
from flexsym.scenes.scene import load_scene
from flexsym.model.variant import builtin
from flexsym.scenes.system_scene import check_assembly, initial_poses, system_from_dict

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "scenes"
BASE = (SCENES / "slider_crank.toml").read_text()
EXTRA_BODY = '\n[[body]]\nname = "wheel"\nkind = "rigid"\nmass = 1.0\ninertia = 1.0\n'
MOTOR = '[[driver]]\nname = "crank_drive"\nkind = "motor"\njoint = "crank_joint"\ntorque = "{}"\n'
GUIDED = ('[[driver]]\nname = "crank_drive"\nkind = "guided"\njoint = "crank_joint"\n'
          'maneuver = "spin-up"   # P(t; 150 rad/s, 0.1 s)\nomega = 150.0\nduration = 0.1\n')


@pytest.mark.parametrize("name, builder, model", [
    ("hub", lib.hub_system, "m3"), ("slider_crank", lib.slider_crank_system, "m2"),
    ("pendulum", lib.pendulum_system, "m3")])
def test_scenes_are_the_library_systems(name, builder, model):
    """One grammar: each shipped scene reads into exactly the System the Python library builds."""
    scene = load_scene(SCENES / f"{name}.toml")
    assert scene.system == builder(builtin(model))


def test_scene_columns_rows_and_model_override():
    """Column names, t_end and row intervals of mechanisms S1-S3; --model replaces every beam."""
    expect = {"hub": (["theta_h", "omega_h", "v_tip", "M_A"], 20.0, 0.01),
              "slider_crank": (["x_s", "w_mid", "N_mid"], 0.3, 0.001),
              "pendulum": (["x_tip", "y_tip", "w_mid", "M_mid"], 2.0, 0.001)}
    for name, (columns, t_end, interval) in expect.items():
        scene = load_scene(SCENES / f"{name}.toml")
        assert list(scene.columns) == columns
        assert scene.options.t_end == t_end
        assert math.isclose(scene.options.out_every * scene.options.dt, interval, rel_tol=1e-12)
        ef = load_scene(SCENES / f"{name}.toml", model="ef")
        assert all(b.model.kind == "fe" for b in ef.system.bodies if b.flexible)
    # a model without axial modes gives the rod's N from the axial inertial forces
    rod = load_scene(SCENES / "slider_crank.toml", model="m3").system.body("rod")
    assert rod.model.strain == "foreshortening" and rod.model.axial_force == "equilibrium"


def test_initial_assembly_and_tolerance():
    """The slider-crank closes at t = 0 (rod from (0.15, 0) to (0.45, 0)): nothing moves. A
    slider guess 1 mm or 5 cm off is moved back to 0.45 (the assembly on the joint coordinates,
    flexsym/scenes/assembly.py); the same value fixed cannot close and is refused."""
    scene = load_scene(SCENES / "slider_crank.toml")
    system, report = check_assembly(scene.system)
    assert system == scene.system and report.line() is None
    poses = initial_poses(system)
    assert poses["rod"] == pytest.approx((0.15, 0.0, 0.0)) and poses["slider"] == pytest.approx((0.45, 0, 0))
    from dataclasses import replace

    for shift in (1e-3, -0.05):
        for fixed in (False, True):
            joints = tuple(replace(j, initial=0.45 + shift, fixed=fixed) if j.name == "slide" else j
                           for j in scene.system.joints)
            moved = replace(scene.system, joints=joints)
            if fixed:
                with pytest.raises(SpecError, match="slider_pin.*cannot close at t = 0"):
                    check_assembly(moved)
                continue
            system, report = check_assembly(moved)
            assert system.joint("slide").initial == pytest.approx(0.45, abs=1e-15)
            assert system.joint("crank_pin").initial == 0.0  # the minimum-norm correction
            assert f"joint slide moved {-shift:+.3g} m" in report.line()


def test_python_api_dict_uses_the_same_checks():
    import tomllib

    data = tomllib.loads(BASE)
    assert system_from_dict(data, "slider_crank") == load_scene(SCENES / "slider_crank.toml").system
    data["joint"][2]["initial"] = {"value": 0.3, "fixed": True}
    with pytest.raises(SpecError, match="joint 'slider_pin'.*cannot close"):
        system_from_dict(data, "slider_crank")


def test_inspect_shows_the_system(capsys):
    assert main(["inspect", str(SCENES / "slider_crank.toml"), "--section", "system"]) == 0
    out = capsys.readouterr().out
    assert "slider_pin: revolute rod.tip -> slider.pin [cut]" in out
    assert "joint coordinates: crank_pin (angle), slide (displacement); guided" in out
    assert "constraint equations: slider_pin: 2 (position)" in out


def test_inspect_shows_a_spatial_ef_beam(capsys, tmp_path):
    """A spatial system whose beam is ef: its nodes' coordinates (a traceback before: the list
    read the modal models' modes)."""
    scene = tmp_path / "arm_ef.toml"
    scene.write_text((SCENES / "spatial_arm.toml").read_text().replace(
        'model = "m3"\n', 'model = { variant = "ef", elements = 4, moment = "equilibrium" }\n'))
    assert main(["inspect", str(scene), "--section", "system"]) == 0
    out = capsys.readouterr().out
    assert "elastic coordinates: link: ux, uy, uz, px, py, pz of nodes 1..4 (ef)" in out


# (case, text replaced, replacement, what the one line must say besides the file name)
MALFORMED = [
    ("unknown_body", 'child = "rod.root"', 'child = "bar.root"', "joint 'crank_pin': child 'bar.root' names an unknown body 'bar'"),
    ("unknown_marker", 'parent = "crank.tip"', 'parent = "crank.end"', "joint 'crank_pin': parent 'crank.end'"),
    ("connected_to_nothing", "\n[[joint]]\nname = \"crank_joint\"", EXTRA_BODY + "\n[[joint]]\nname = \"crank_joint\"",
     "body 'wheel' is connected to nothing"),
    ("driver_unknown_joint", 'joint = "crank_joint"', 'joint = "crank_axle"', "driver 'crank_drive': joint 'crank_axle' does not exist"),
    ("driver_on_cut_joint", 'joint = "crank_joint"', 'joint = "slider_pin"', "driver 'crank_drive': joint 'slider_pin' is a cut joint"),
    ("loop_cannot_close", "initial = 0.45", "initial = { value = 0.40, fixed = true }", "joint 'slider_pin' (cut joint, closes a loop): cannot close at t = 0"),
    ("zero_mass", "mass = 0.1 ", "mass = 0.0 ", "body 'crank': mass 0.0 must be a finite number > 0"),
    ("negative_inertia", "inertia = 1.0e-6 ", "inertia = -1.0e-6 ", "body 'slider': inertia -1e-06"),
    ("negative_section", "area = 2.8274333882308137e-5", "area = -1.0", "[[body]] 'rod' area: must be > 0"),
    ("motor_unsafe", GUIDED, MOTOR.format("__import__('os').system('true')"), "driver 'crank_drive' torque"),
    ("motor_unknown_name", GUIDED, MOTOR.format("-kp*(crank_joint - 1)"), "driver 'crank_drive' torque = '-kp*(crank_joint - 1)': the name 'kp' is not allowed"),
    ("motor_force_on_revolute", GUIDED, MOTOR.format("1").replace("torque =", "force ="), "a motor on the revolute joint 'crank_joint' gives a torque"),
    ("duplicate_names", 'name = "slide"', 'name = "rod"', "duplicate name 'rod'"),
    ("no_mode_carries_N", 'model = "m2"', 'model = { variant = "m3", axial_force = "constitutive" }',
     "output N_mid = 'N(rod, mid)': model 'foreshortening'"),
    ("w_at_end", 'w_mid = "w(rod, mid)"', 'w_mid = "w(rod, tip)"', "distance from the chord is zero at the beam's ends"),
    ("marker_off_beam", "markers = { mid = 0.15 }", "markers = { mid = 0.5 }", "marker 'mid' at x = 0.5 is outside the beam"),
    ("prismatic_without_axis", "axis = [1.0, 0.0]\n", "", "joint 'slide': a prismatic joint needs an axis"),
    ("two_guided_drivers", GUIDED, GUIDED + "\n" + GUIDED.replace('"crank_drive"', '"crank_drive2"'), "joint 'crank_joint' already has a guided driver"),
    ("unknown_output_function", 'x_s = "x(slider.pin)"', 'x_s = "q(slider.pin)"', "output 'q(slider.pin)': unknown function 'q'"),
    ("spatial_output_in_plane", 'x_s = "x(slider.pin)"', 'x_s = "z(slider.pin)"', "output 'z(slider.pin)': z applies to spatial systems (dimension = 3) only"),
    ("output_unknown_body", 'x_s = "x(slider.pin)"', 'x_s = "x(wheel.pin)"', "output 'x(wheel.pin)'"),
    ("beam_not_hung_at_root", 'child = "rod.root"', 'child = "rod.mid"', "flexible body 'rod' is not reached from ground"),
    ("theta_jump", GUIDED, GUIDED.replace('maneuver = "spin-up"   # P(t; 150 rad/s, 0.1 s)\nomega = 150.0\nduration = 0.1',
                                          'theta = "ifelse(t < 0.1, 0, 10*(t - 0.1))"'), "driver 'crank_drive': theta(t)"),
    ("unknown_key", "com = [0.075, 0.0]", "centre = [0.075, 0.0]", "[[body]] 'crank' centre: unknown key"),
    ("unknown_table", "[solver]", "[solvers]", "solvers: unknown table"),
    ("ground_joint_without_point", 'parent = "ground"\npoint = [0.0, 0.0]\nchild = "crank.root"',
     'parent = "ground"\nchild = "crank.root"', "[[joint]] 'crank_joint' point: missing"),
    ("bad_run_option", "dt = 1e-4", "dt = -1e-4", "[solver] dt"),
    ("elements_on_modal", 'model = "m2"', 'model = { variant = "m2", elements = 4 }', "[[body]] 'rod' model elements: applies to variant = \"ef\" only"),
    ("model_not_a_name", 'model = "m2"', 'model = 2', "[[body]] 'rod' model: must be a variant name or a table"),
    ("maneuver_unknown", 'maneuver = "spin-up"', 'maneuver = "spin-down"', "maneuver: unknown manoeuvre 'spin-down'"),
]


@pytest.mark.parametrize("case, old, new, says", MALFORMED, ids=[m[0] for m in MALFORMED])
def test_malformed_system(tmp_path, capsys, case, old, new, says):
    assert BASE.count(old) == 1, case
    scene = tmp_path / f"{case}.toml"
    scene.write_text(BASE.replace(old, new))
    out, plot = tmp_path / "out.csv", tmp_path / "p.png"
    out.write_bytes(b"t,x_s\n0,1\n")
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    rc = main(["run", str(scene), "--out", str(out), "--plot", str(plot)])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.count("\n") == 1 and err.startswith(f"flexsym: error: {scene}: "), err
    assert says in err, err
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def test_model_override_refused_in_one_line(tmp_path, capsys):
    assert main(["run", str(SCENES / "hub.toml"), "--model", "m9"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "hub.toml: --model: unknown variant 'm9'" in err, err


def test_exaggerate_scales_only_the_distance_from_the_chord():
    from flexsym.analysis.system_plot import chord_distance, exaggerate

    rng = np.random.default_rng(3)
    p = np.column_stack([np.linspace(0, 1, 7), 0.01 * rng.standard_normal(7)]) @ [[0.6, 0.8], [-0.8, 0.6]]
    p[0], p[-1] = (0.0, 0.0), (0.6, 0.8)
    q = exaggerate(p, 50.0)
    assert np.allclose(chord_distance(q), 50.0 * chord_distance(p), rtol=1e-12, atol=1e-15)
    e = np.array([0.6, 0.8])
    assert np.allclose(q @ e, p @ e, atol=1e-14)  # positions along the chord kept


def test_plot_of_a_system_from_synthetic_rows(tmp_path):
    """The slider-crank's picture from rows of a known motion (crank turning, rod bent by a
    sine of amplitude 0.2 mm): every extra column is a marker position, the scale is stated."""
    from flexsym.analysis.system_plot import plot_system, with_plot_outputs

    base = load_scene(SCENES / "slider_crank.toml").system
    system, geometry = with_plot_outputs(base)
    system.validate()
    assert [o.column for o in system.outputs[:3]] == ["x_s", "w_mid", "N_mid"]
    assert len(geometry["rod"]) == 11 and len(geometry["crank"]) == 2
    t = np.linspace(0, 0.05, 51)
    r, l = 0.15, 0.3
    phi = 150 * t
    cols = {"t": t}
    crank_tip = np.column_stack([r * np.cos(phi), r * np.sin(phi)])
    xs = r * np.cos(phi) + np.sqrt(l**2 - (r * np.sin(phi))**2)
    slider = np.column_stack([xs, 0 * xs])
    for k, (cx, cy) in enumerate(geometry["rod"]):
        s = k / 10
        chord = crank_tip + s * (slider - crank_tip)
        normal = np.column_stack([-(slider - crank_tip)[:, 1], (slider - crank_tip)[:, 0]]) / l
        p = chord + 2e-4 * np.sin(np.pi * s) * np.sin(800 * t)[:, None] * normal
        cols[cx], cols[cy] = p[:, 0], p[:, 1]
    for (cx, cy), p in zip(geometry["crank"], (0 * crank_tip, crank_tip)):
        cols[cx], cols[cy] = p[:, 0], p[:, 1]
    (cx, cy), = geometry["slider"]
    cols[cx], cols[cy] = slider[:, 0], slider[:, 1]
    cols.update(x_s=xs, w_mid=2e-4 * np.sin(800 * t), N_mid=np.cos(800 * t))
    factor = plot_system(system, geometry, cols, tmp_path / "s2.png")
    assert factor == 100.0  # 0.08 x the extent (~0.6 m) / the largest distance (<= 0.2 mm), as 10^k
    assert (tmp_path / "s2.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_documented_example_is_the_slider_crank_scene_and_its_pd_law_reads():
    import re
    import tomllib

    text = (ROOT / "docs/howto/mechanisms.md").read_text()
    block = text.split("## Describing a system", 1)[1].split("```toml\n", 1)[1].split("```", 1)[0]
    data = tomllib.loads(block)
    assert system_from_dict(data, "slider_crank") == load_scene(SCENES / "slider_crank.toml").system
    law = re.search(r'a PD law `torque = "([^"]+)"`', text).group(1)
    data["driver"] = [{"name": "pd", "kind": "motor", "joint": "crank_joint", "torque": law}]
    assert system_from_dict(data, "slider_crank").drivers[0].expression == law


def test_pendulum_scene_runs_with_csv_and_plot(tmp_path, capsys):
    """S3 end to end (derivation and generation by flexsym/physics/assemble.py, sysgen.py): the CSV
    has the benchmark's columns at 1 ms rows and none of the picture's; the picture's columns
    (the same system with its stations as outputs) agree with the run's own outputs: the tip
    station is (x_tip, y_tip) and the mid station's distance from the chord is w_mid (sign
    included), computed independently from the station positions."""
    from flexsym.analysis.system_plot import chord_distance, with_plot_outputs
    from flexsym.toolchain.pipeline import run_system

    out, plot = tmp_path / "s3.csv", tmp_path / "s3.png"
    assert main(["run", str(SCENES / "pendulum.toml"), "--out", str(out), "--plot", str(plot)]) == 0
    assert "beam deflection from the chord scaled x" in capsys.readouterr().out
    header = out.read_text().splitlines()[0].split(",")
    assert header[:5] == ["t", "x_tip", "y_tip", "w_mid", "M_mid"]
    assert not any(c.startswith(("px_", "py_")) for c in header)
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    col = {name: data[:, k] for k, name in enumerate(header)}
    assert len(data) == 2001 and np.allclose(np.diff(col["t"]), 1e-3, atol=1e-12)
    scene = load_scene(SCENES / "pendulum.toml")
    pic = run_system(with_plot_outputs(scene.system)[0], t_end=scene.options.t_end, dt=scene.options.dt,
                     integrator=scene.options.integrator, interval=1e-3)
    assert all(np.array_equal(pic[c], col[c]) for c in ("x_tip", "y_tip", "w_mid", "M_mid"))
    assert np.array_equal(pic["px_beam_tip"], col["x_tip"]) and np.array_equal(pic["py_beam_tip"], col["y_tip"])
    stations = np.stack([np.column_stack([pic[f"px_beam_{m}"], pic[f"py_beam_{m}"]])
                         for m in ["root"] + [f"plot{k}" for k in range(1, 10)] + ["tip"]], axis=1)
    w = np.array([chord_distance(p)[5] for p in stations])
    assert np.abs(col["w_mid"]).max() > 1e-4  # the strip does bend
    assert np.abs(w - col["w_mid"]).max() <= 1e-9 * np.abs(col["w_mid"]).max() + 1e-15
    assert plot.read_bytes()[:4] == b"\x89PNG"


def test_api_system_checks_python_systems_like_scenes():
    from dataclasses import replace

    from flexsym.apps import api

    good = lib.pendulum_system(builtin("m3"))
    assert api.system(good) == good
    bad = replace(good, outputs=good.outputs + (lib.Output("w_tip", "w(beam, tip)"),))
    with pytest.raises(SpecError, match="output w_tip = 'w\\(beam, tip\\)': the distance from the chord is zero"):
        api.system(bad)


def test_bad_run_flags_and_bad_system_scenes_are_refused(tmp_path, capsys):
    scene = str(SCENES / "pendulum.toml")
    assert main(["run", scene, "--dt=-1e-3"]) == 2
    assert "pendulum.toml: --dt: must be > 0 (got -0.001)" in capsys.readouterr().err
    assert main(["build", scene, "--strain", "linear"]) == 2  # build takes the scene, not one-beam flags
    assert "--strain does not combine with a scene file" in capsys.readouterr().err
    (tmp_path / "s.toml").write_text('[system]\nname = "x"\n')
    assert main(["inspect", str(tmp_path / "s.toml")]) == 2
    assert "s.toml: [[body]]: a system scene needs [[body]] entries" in capsys.readouterr().err
    assert load_scene(SCENES / "stepped_blade.toml").spec.body is not None  # [body]: one beam, as before


def test_bench_systems_quick(tmp_path):
    """flexsym bench-systems --quick: the pendulum at two generalized-alpha steps and with
    Fox-Goodwin's Newmark (beta = 1/12) against its own reference step; every output's
    integration error shrinks when the step is halved, and at the same step the fourth-order
    period error of beta = 1/12 is well below generalized-alpha's in every output (measured
    77-340x in the motion; 9.5x in M_mid, which comes from equilibrium and so reads the
    accelerations and the velocities' Coriolis terms as well: 16x when it was the modes'
    curvature)."""
    from flexsym.analysis.system_bench import run_system_bench

    rows = run_system_bench(tmp_path, quick=True, log=lambda m: None)
    assert [(r["integrator"], r["dt"]) for r in rows] == [
        ("genalpha", 1e-3), ("genalpha", 5e-4), ("newmark newmark_beta=0.08333", 5e-4)]
    assert all(r["status"] == "ok" and r["cpu_s"] > 0 for r in rows)
    for c in ("x_tip", "y_tip", "w_mid", "M_mid"):
        assert 0 < rows[1][f"err_{c}"] < 0.75 * rows[0][f"err_{c}"], c
        assert 0 < rows[2][f"err_{c}"] < (0.2 if c == "M_mid" else 0.02) * rows[1][f"err_{c}"], c
    assert (tmp_path / "bench_systems.csv").read_text().startswith("system,model,integrator,dt,cpu_s,err_max")
    assert "| pendulum | m3 | genalpha | 0.001 s |" in (tmp_path / "bench_systems.md").read_text()


def test_a_zero_written_as_a_float_is_an_expression():
    """'0.0' (a free-wheeling motor, a torque component that is off) parses to zero: sympy's
    Float(0.0) == 0 is False, and the magnitude check took its log (it was refused with
    'cannot be built (TypeError: Cannot convert complex to float)')."""
    from flexsym.model.maneuver import parse_expression, parse_theta, t

    for text in ("0.0", "-0.0", "0.0*t", "0e5"):
        assert parse_expression(text, (("t", t),), "torque").is_zero, text
    assert parse_theta("0.0").is_zero


def test_bench_systems_on_a_spatial_scene(tmp_path, monkeypatch):
    """bench-systems on S5 (flap, prestress), with a system-level reference integrator and no ef
    reference: genalpha's error falls at second order (10 -> 5 -> 2 ms: measured 1.0e-4,
    2.6e-5, 4.3e-6), rk4 at 1 ms is far below, and the table has no ef column."""
    from flexsym.analysis import system_bench as sb

    monkeypatch.setitem(sb.SYSTEMS, "flap", sb.SystemCases(
        ("prestress",), tuple(sb.Case("genalpha", dt) for dt in (0.01, 0.005, 0.002)) + (sb.Case("rk4", 0.001),),
        reference="rk4"))
    monkeypatch.delitem(sb.EF_REFERENCE, "flap")
    rows = sb.run_system_bench(tmp_path, systems=["flap"], repeat=1, log=lambda m: None)
    err = [r["err_max"] for r in rows]
    assert all(r["status"] == "ok" for r in rows) and "ef_max" not in rows[0]
    assert 3.5 < err[0] / err[1] < 4.5 and 5.5 < err[1] / err[2] < 6.8 and err[3] < 1e-3 * err[2], err


def test_a_planar_torque_has_no_frame(tmp_path, capsys):
    """frame is a spatial torque's axes: in a planar scene (a torque about z) it is refused in
    one line naming the file, by the one check in System.validate."""
    from flexsym.apps.cli import main

    scene = tmp_path / "pendulum_torque.toml"
    scene.write_text((ROOT / "scenes" / "pendulum.toml").read_text()
                     + '\n[[load]]\nkind = "torque"\nbody = "beam"\ntorque = "0.1"\nframe = "body"\n')
    out = tmp_path / "out.csv"
    assert main(["run", str(scene), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(scene) in err, err
    assert "frame applies to spatial torques" in err and not out.exists()
