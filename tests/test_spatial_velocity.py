"""The velocity analysis of a spatial loop at t = 0 (flexsym/scenes/assembly.py rates3): S7's
slider-crank started with its crank at a constant 150 rad/s. The slider's rate has a closed
form; the ball joint's three turn rates and the universal joint's cross axis are checked
against the derivation's own constraint rows, and a rigid twin runs along the closed form."""
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from flexsym.scenes.system_scene import system_from_dict
from system_data import built, run_ok
from test_cylindrical import cylinder_loop

S7 = Path(__file__).resolve().parent.parent / "scenes" / "spatial_slider_crank.toml"
R, L, Y, Z, W = 0.1, 0.3, 0.05, 0.15, 150.0  # crank, rod, the slider axis' offsets, crank speed
M_ROD = 7870.0 * 2.827433388230814e-05 * 0.3


def closed_form(t):
    """x_s and x_s' of the rigid loop |P_s - P_c| = L, P_c = R (cos th, sin th, 0),
    P_s = (x_s, Y, Z), th = W t."""
    th = W * np.asarray(t)
    s, c = np.sin(th), np.cos(th)
    root = np.sqrt(L**2 - (Y - R * s)**2 - Z**2)
    return R * c + root, W * (-R * s + (Y - R * s) * R * c / root)


def _s7(rigid: bool = False) -> dict:
    data = tomllib.loads(S7.read_text())
    data["driver"][0] = {"name": "crank_drive", "kind": "guided", "joint": "crank_joint",
                         "theta": f"{W}*t"}
    if rigid:  # the rod as a slender rigid body: the closed form holds for all t
        k = next(i for i, b in enumerate(data["body"]) if b["name"] == "rod")
        data["body"][k] = {"name": "rod", "kind": "rigid", "mass": M_ROD,
                           "inertia": [1e-7, M_ROD * L**2 / 12, M_ROD * L**2 / 12], "com": [L / 2, 0.0, 0.0],
                           "markers": {"root": [0.0, 0.0, 0.0], "tip": [L, 0.0, 0.0], "mid": [L / 2, 0.0, 0.0]}}
        data["output"]["columns"] = {"x_s": "x(slider.pin)", "v_s": "rate(slide)"}
    return data


@pytest.mark.parametrize("rigid", [False, True])
def test_the_slider_rate_at_t0_is_the_closed_form(rigid):
    """The scene reader's assembly sets the free rates: the slide's to the closed form's
    x_s'(0) = Y R W / (x_s - R) (2.94 m/s) to 1e-14, the ball joint's to a turn (parent's
    axes), both in the report's line; elastic rates stay 0 (a beam's start is undeformed)."""
    system = system_from_dict(_s7(rigid), name="s7")
    joints = {j.name: j for j in system.joints}
    x0, v0 = closed_form(0.0)
    assert abs(joints["slide"].initial - x0) < 1e-15
    assert abs(joints["slide"].rate - v0) <= 1e-14 * v0
    assert len(joints["ball"].rate) == 3 and max(map(abs, joints["ball"].rate)) > W / 2
    assert joints["crank_joint"].rate is None  # the driver's


def test_the_rates_satisfy_the_derivations_constraint_rows():
    """Independent of the assembly's kinematics (poses3, small turns): d/dt of every constraint
    row of the derivation (the ball joint's |e| = 1, the loop's three points, the universal
    joint's cross axis e1 . e2) at the start's q, q' and theta'(0) is 0 to round-off. Without
    the cross axis' row in the velocity analysis, d/dt (e1 . e2) is 0.23 (checked)."""
    from flexsym.physics.spatial import _start_values, derive_spatial

    der = derive_spatial(system_from_dict(_s7(rigid=True), name="s7"))
    start = _start_values(der)
    rows = {name: float(der.ddt(phi).xreplace(start)) for name, phi in der.constraints}
    assert set(rows) == {"ball.norm", "cardan.x", "cardan.y", "cardan.z", "cardan.cross"}
    assert max(abs(v) for v in rows.values()) < 1e-12 * R * W, rows


@pytest.fixture(scope="module")
def rigid_s7():
    return built(_s7(rigid=True))


@pytest.mark.parametrize("integrator,dt,tol_x,tol_v", [
    ("genalpha3", 1e-5, 1e-13, 1e-12), ("ali3p", 1e-5, 1e-13, 1e-10), ("rk4p", 1e-5, 1e-12, 1e-10)])
def test_the_rigid_loop_started_moving_follows_the_closed_form(rigid_s7, integrator, dt, tol_x, tol_v):
    """50 ms (1.2 crank turns) from the assembled moving start: x_s and x_s' on the closed form
    (measured genalpha3 1e-16 m, 9e-15 m/s; ali3p 2e-16, 7.7e-12; rk4p 1.7e-14, 8.8e-13), the
    first row's rate the assembly's."""
    r = run_ok(rigid_s7, t_end=0.05, dt=dt, integrator=integrator)
    x, v = closed_form(r["t"])
    assert abs(r["v_s"][0] - v[0]) <= 1e-14 * abs(v[0])
    assert np.abs(r["x_s"] - x).max() <= tol_x
    assert np.abs(r["v_s"] - v).max() <= tol_v


def test_rates_the_loop_cannot_take_are_refused(tmp_path):
    """A ball joint given a rate the loop cannot take (a turn about the crank's z with the crank
    at rest: only the slide is free to follow, and it cannot): one line naming the given
    joints, exit 2, before anything is derived, nothing written."""
    text = S7.read_text()
    old = "direction = [0.25495097567963926, 0.05, 0.15]"
    assert text.count(old) == 1
    scene = tmp_path / "s7.toml"
    scene.write_text(text.replace(old, old + "\ninitial = { rate = [0.0, 0.0, 1.0] }"))
    out = tmp_path / "out.csv"
    r = subprocess.run([sys.executable, "-m", "flexsym.apps.cli", "run", str(scene), "--out", str(out)],
                       capture_output=True, text=True)
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert "the joints' rates at t = 0 cannot satisfy the loops: crank_joint, ball are given" in r.stderr
    assert not out.exists()


def test_a_cylindrical_joint_in_a_loop_takes_both_rates():
    """A body on a vertical cylindrical joint whose marker meets (ball joint) a post that a
    guided prismatic joint lifts along z at 0.5 m/s while turning nothing: the slide's rate is
    0.5 m/s, written as slide_rate, and the angle's 0 (not written)."""
    from flexsym.scenes.system_scene import checked_system, system_from_data

    data = cylinder_loop({"name": "lift", "kind": "prismatic", "axis": [0.0, 0.0, 1.0]},
                         [{"name": "up", "kind": "guided", "joint": "lift", "theta": "0.5*t"}])
    system, _, _ = system_from_data(data, "", "cyl_loop")
    assembled, report = checked_system(system)
    j = assembled.joint("c")
    assert j.slide == pytest.approx(0.3, abs=1e-12) and abs(j.slide_rate - 0.5) < 1e-14
    assert j.rate is None
    assert "joint c slide rate set to 0.5 m/s" in report.line()
