"""Assembly at t = 0 (flexsym/scenes/assembly.py): the loops of a mechanism are closed on its joint
coordinates with undeformed bodies before anything is generated, so that a run never starts with
strain energy the user did not ask for.

The story (issue 19): a crank-rocker four-bar (scenes/four_bar.toml: ground 0.5 m, crank 0.1 m,
coupler 0.4 m of flexible steel, d = 8 mm, rocker 0.3 m; crank spun up to 60 rad/s) written with
the closing angles rounded to four decimals. Before the assembly the runtime's consistent start
closed the 1e-5 m gap by stretching the coupler (N_mid = -48 N at t = 0, rows 68 % of the N_mid
peak away from the exact-angle run); now the rows are the exact-angle rows.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from flexsym.apps.cli import main
from flexsym.core.errors import SpecError
from flexsym.scenes.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]
FOUR_BAR = (ROOT / "scenes" / "four_bar.toml").read_text()
GROUND, CRANK, COUPLER, ROCKER = 0.5, 0.1, 0.4, 0.3
ROUNDED = {"coupler_pin": "initial = 0.7688 ", "rocker_joint": "initial = 1.9552 "}


def closing_angles(theta: float, sign: float = 1.0, coupler: float = COUPLER) -> tuple[float, float]:
    """(coupler angle relative to the crank, rocker angle) that close the loop at crank angle
    theta, by the triangle crank tip B, coupler tip C, rocker pivot D (sign +1: C to the left of
    B -> D, the branch with C above the ground line at theta = 0)."""
    bx, by = CRANK * math.cos(theta), CRANK * math.sin(theta)
    dx, dy = GROUND - bx, -by
    d = math.hypot(dx, dy)
    a = (coupler**2 - ROCKER**2 + d**2) / (2 * d)  # along B -> D
    h = sign * math.sqrt(coupler**2 - a**2)
    cx, cy = bx + (a * dx - h * dy) / d, by + (a * dy + h * dx) / d
    return math.atan2(cy - by, cx - bx) - theta, math.atan2(cy, cx - GROUND)


def scene_text(coupler=None, rocker=None) -> str:
    """The four-bar with the two angles replaced (None: no initial value at all)."""
    text = FOUR_BAR
    for joint, value in (("coupler_pin", coupler), ("rocker_joint", rocker)):
        line = next(x for x in text.splitlines() if x.startswith(ROUNDED[joint]))
        text = text.replace(line + "\n", "" if value is None else f"initial = {value!r}\n")
    return text


def run(tmp_path, name, text, *flags) -> tuple[np.ndarray, list[str], str]:
    scene = tmp_path / f"{name}.toml"
    scene.write_text(text)
    out = tmp_path / f"{name}.csv"
    assert main(["run", str(scene), "--out", str(out), *flags]) == 0
    lines = out.read_text().splitlines()
    header = [x for x in lines if x.startswith("#") and not x.startswith("# units:")]
    return np.genfromtxt(out, delimiter=",", names=True), header, lines[0]


def test_closing_angles_close_the_loop():
    beta, gamma = closing_angles(0.0)
    c = (CRANK + COUPLER * math.cos(beta), COUPLER * math.sin(beta))
    r = (GROUND + ROCKER * math.cos(gamma), ROCKER * math.sin(gamma))
    assert math.dist(c, r) < 1e-15 and c[1] > 0
    assert (round(beta, 4), round(gamma, 4)) == (0.7688, 1.9552)  # the scene's rounded guesses


def test_four_bar_from_rounded_and_missing_angles_runs_as_from_exact_angles(tmp_path, capsys):
    """Rounded (the shipped scene) and missing angles are moved to the closed position; rows equal
    the exact-angle rows; the run starts undeformed (elastic coordinates and V exactly 0)."""
    beta, gamma = closing_angles(0.0)
    flags = ("--energy", "--t-end", "0.25")
    exact, exact_header, columns = run(tmp_path, "exact", scene_text(beta, gamma), *flags)
    assert len(exact_header) == 1 and "assembly" not in exact_header[0], "closed: nothing moved"
    capsys.readouterr()
    rounded, header, columns_r = run(tmp_path, "rounded", FOUR_BAR, *flags)
    err = capsys.readouterr().err
    missing, _, _ = run(tmp_path, "missing", scene_text(None, None), *flags)
    assert columns_r == columns
    # the report: one line on stderr and in the CSV header, what moved and by how much
    line = next(x for x in err.splitlines() if ": assembly: " in x)  # stderr also shows the build's stages
    assert header[0] == "# " + line.split(": ", 2)[2]
    assert header[0].startswith(f"# assembly: joint coupler_pin moved {beta - 0.7688:+.3g} rad to "
                                f"{beta:.10g}, joint rocker_joint moved {gamma - 1.9552:+.3g} rad to "
                                f"{gamma:.10g} (loop residual ")
    assert "elastic coordinates 0 at t = 0, no initial strain energy" in header[0]
    assert header[1] == exact_header[0] == ("# run options: integrator = genalpha3, t_end = 0.25, dt = 0.0001, "
                                            "interval = 0.001, energy = True (from the command line: "
                                            "--t-end, --energy)")
    elastic = [c for c in exact.dtype.names if c.startswith("coupler_") and c != "coupler_pin"]
    assert len(elastic) == 5
    for rows in (exact, rounded, missing):
        # the start: the closed angles to rounding, the coupler undeformed
        assert abs(rows["coupler_pin"][0] - beta) < 1e-15 and abs(rows["rocker_joint"][0] - gamma) < 1e-15
        assert all(rows[c][0] == 0.0 for c in elastic) and rows["V"][0] == 0.0 and rows["N_mid"][0] == 0.0
        # the rows: within 1e-9 of each column's peak; the coupler's axial force within 5e-9,
        # its floor: a one-ulp change of the exact start angle alone moves N_mid by 1.5e-9 of
        # its peak (the stiff axial mode; docs/howto/assembly.md)
        for col, tol in (("rocker", 1e-9), ("M_mid", 1e-9), ("N_mid", 5e-9)):
            peak = np.max(np.abs(exact[col]))
            assert np.max(np.abs(rows[col] - exact[col])) <= tol * peak, col
    assert np.max(np.abs(exact["N_mid"])) > 10.0  # N_mid peaks near 70 N: the test sees the force


def test_a_length_given_to_the_run_closes_the_loop_by_the_joints_never_by_strain():
    """The coupler's length is a run-time parameter (in-process runs, sweeps, an FMU): the start
    flexsym assembled with the scene's 0.4 m is then open, and the runtime's consistent start
    closes it moving the joints alone (system.h coord_held), at the closed-form angles of the
    new length, the coupler undeformed; a length that cannot close is refused in one line. (It
    used to close a 0.1 mm gap by stretching the coupler, and to end at the first step, Newton
    not converging, for 0.5 m.)"""
    from flexsym.apps import api

    lengths = [COUPLER, COUPLER + 1e-4, 0.5, 0.8]
    batch = api.inprocess(str(ROOT / "scenes" / "four_bar.toml")).batch(
        {"L": lengths}, t_end=0.02, dt=1e-4, integrator="genalpha3", rows=True)
    elastic = [c for c in batch.result(0).columns if c.startswith("coupler_") and c != "coupler_pin"]
    assert len(elastic) == 5
    for i, length in enumerate(lengths[:3]):
        rows = batch.result(i)
        assert rows.status == "ok", (length, rows.message)
        beta, gamma = closing_angles(0.0, coupler=length)
        # the runtime's Newton stops at |Phi| <= 1e-12 x the size (0.5 m): angles to ~1e-12 rad
        assert abs(rows["coupler_pin"][0] - beta) < 1e-10 and abs(rows["rocker_joint"][0] - gamma) < 1e-10
        assert all(rows[c][0] == 0.0 for c in elastic), length  # undeformed: no initial strain
        assert rows["N_mid"][0] == 0.0 and np.max(np.abs(rows["violation"])) < 1e-12
    assert abs(batch.result(2)["rocker_joint"][0] - closing_angles(0.0)[1]) > 0.3  # it moved
    last = batch.result(3)
    assert last.status == "failed" and "\n" not in last.message
    assert last.message.startswith("assembly cannot close at t = 0: constraint loop.")
    assert "moving the joints with the bodies undeformed" in last.message


def refused(tmp_path, capsys, text, *fragments):
    """One line naming the file and what is wrong, exit 2, nothing written."""
    scene = tmp_path / "bad.toml"
    scene.write_text(text)
    out = tmp_path / "bad.csv"
    assert main(["run", str(scene), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(scene) in err[0], err
    for f in fragments:
        assert f in err[0], err
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


def test_a_loop_that_cannot_close_is_refused(tmp_path, capsys):
    """The rocker's pivot 1 m out: the crank tip is 0.9 m from it, beyond coupler + rocker."""
    text = FOUR_BAR.replace("point = [0.5, 0.0]", "point = [1.0, 0.0]")
    refused(tmp_path, capsys, text, "joint 'loop' (cut joint, closes a loop): cannot close at t = 0",
            "free joint coordinates (coupler_pin, rocker_joint; fixed: crank_joint)")


def test_a_loop_singular_at_t0_is_refused(tmp_path, capsys):
    """Coupler and rocker in line at t = 0 (ground pivot at 0.8 m, the rocker pointing back):
    closed, but the loop's Jacobian w.r.t. the free coordinates has rank 1 (a dead point)."""
    text = scene_text(0.0, math.pi).replace("point = [0.5, 0.0]", "point = [0.8, 0.0]")
    refused(tmp_path, capsys, text, "joint 'loop' (cut joint, closes a loop): singular at t = 0",
            "(coupler_pin, rocker_joint) has rank 1 < 2")


def _free_crank(tmp_path, rocker: str):
    """The four-bar without its driver: three joint coordinates, one loop (two rows)."""
    start = FOUR_BAR.index("[[driver]]")
    text = FOUR_BAR[:start] + FOUR_BAR[FOUR_BAR.index("[solver]"):]
    text = text.replace("initial = 1.9552 ", f"initial = {rocker} ")
    (tmp_path / "free.toml").write_text(text)
    return load_scene(tmp_path / "free.toml")


def test_fixed_coordinates_never_move_guesses_do(tmp_path):
    # fixed at 2.0 rad: the crank and the coupler close the loop around it
    scene = _free_crank(tmp_path, "{ value = 2.0, fixed = true }")
    joints = {j.name: j for j in scene.system.joints}
    assert joints["rocker_joint"].initial == 2.0
    assert [m[0] for m in scene.assembly.moved] == ["crank_joint", "coupler_pin"]
    # a guess of 2.0 moves too (the minimum-norm correction spreads over all three)
    guess = _free_crank(tmp_path, "2.0")
    assert [m[0] for m in guess.assembly.moved] == ["crank_joint", "coupler_pin", "rocker_joint"]
    for s in (scene, guess):
        j = {x.name: x.initial for x in s.system.joints}
        b = (CRANK * math.cos(j["crank_joint"]), CRANK * math.sin(j["crank_joint"]))
        phi = j["crank_joint"] + j["coupler_pin"]
        c = (b[0] + COUPLER * math.cos(phi), b[1] + COUPLER * math.sin(phi))
        r = (GROUND + ROCKER * math.cos(j["rocker_joint"]), ROCKER * math.sin(j["rocker_joint"]))
        assert math.dist(c, r) < 1e-15
    assert guess.system.joint("rocker_joint").initial != 2.0
    # every coordinate fixed and not closed: refused, naming the fixed ones
    text = (tmp_path / "free.toml").read_text().replace("initial = 0.7688 ", "initial = { value = 0.7688, fixed = true } ")
    text = text.replace("initial = 2.0 ", "initial = { value = 2.0, fixed = true } ")
    (tmp_path / "free.toml").write_text(text.replace('child = "crank.root"', 'child = "crank.root"\ninitial = { value = 0.0, fixed = true }'))
    with pytest.raises(SpecError, match=r"cannot close at t = 0.*\(none; fixed: crank_joint, coupler_pin, rocker_joint\)"):
        load_scene(tmp_path / "free.toml")


def test_velocity_analysis_gives_the_rigid_joint_rates(tmp_path):
    """A crank at constant 10 rad/s from t = 0: the coupler's and rocker's rates at t = 0 are the
    rigid four-bar's (the closed form, differentiated); elastic rates stay 0 (not unknowns)."""
    text = FOUR_BAR.replace('maneuver = "spin-up"   # P(t; 60 rad/s, 0.2 s)\nomega = 60.0\nduration = 0.2',
                            'maneuver = "constant"\nomega = 10.0')
    (tmp_path / "c.toml").write_text(text)
    scene = load_scene(tmp_path / "c.toml")
    h = 1e-6
    (b1, g1), (b0, g0) = closing_angles(h), closing_angles(-h)
    rates = {j.name: j.rate for j in scene.system.joints}
    assert rates["coupler_pin"] == pytest.approx(10.0 * (b1 - b0) / (2 * h), rel=1e-8)
    assert rates["rocker_joint"] == pytest.approx(10.0 * (g1 - g0) / (2 * h), rel=1e-8)
    assert "joint rocker_joint rate set to" in scene.assembly.line()
    # the run starts with these rates and a coupler at rest in its frame: T(0) is the rigid
    # four-bar's (crank and rocker about their pivots, the coupler as a rigid bar; an elastic
    # rate would add to it) and V(0) = 0
    (tmp_path / "c.toml").write_text(text.replace("t_end = 0.3", "t_end = 0.01").replace(
        "interval = 0.001", "interval = 0.001\nenergy = true"))
    assert main(["run", str(tmp_path / "c.toml"), "--out", str(tmp_path / "c.csv")]) == 0
    first = np.genfromtxt(tmp_path / "c.csv", delimiter=",", names=True)[0]
    beta, gamma = closing_angles(0.0)
    rate = 10.0 + rates["coupler_pin"]  # the coupler's absolute angle rate
    mass = 7850.0 * 5.026548245743669e-05 * COUPLER
    vg = (-rate * COUPLER / 2 * math.sin(beta), 10.0 * CRANK + rate * COUPLER / 2 * math.cos(beta))
    T = (0.5 * (1.0e-4 + 0.1 * 0.05**2) * 10.0**2 + 0.5 * (1.5e-3 + 0.2 * 0.15**2) * rates["rocker_joint"]**2
         + 0.5 * mass * (vg[0]**2 + vg[1]**2) + 0.5 * mass * COUPLER**2 / 12 * rate**2)
    assert first["T"] == pytest.approx(T, rel=1e-12) and first["V"] == 0.0
    # a rate given for the rocker fixes it: the loop then cannot take the crank's 10 rad/s
    (tmp_path / "c.toml").write_text(text.replace("initial = 1.9552 ", "initial = { value = 1.9552, rate = 0.0 } "))
    with pytest.raises(SpecError, match="rates at t = 0 cannot satisfy the loops: crank_joint, rocker_joint are given"):
        load_scene(tmp_path / "c.toml")


def test_a_loop_without_joint_coordinates():
    """A beam clamped to ground with its tip pinned to ground: nothing to move. Closed, it is a
    statically indeterminate structure (not singular: its Jacobian has no column anywhere);
    0.1 mm off, it would start pre-stressed: refused."""
    from flexsym.scenes.system_scene import system_from_dict

    data = {"body": [{"name": "b", "kind": "beam", "length": 1.0, "density": 7800.0, "youngs_modulus": 2e11,
                      "area": 1e-4, "inertia": 1e-9, "model": "m2"}],
            "joint": [{"name": "c", "kind": "clamp", "parent": "ground", "point": [0.0, 0.0], "child": "b.root"},
                      {"name": "p", "kind": "revolute", "parent": "ground", "point": [1.0, 0.0], "child": "b.tip"}],
            "output": {"columns": {"N": "N(b, root)"}}}
    assert system_from_dict(data, "cc").joints[1].point == (1.0, 0.0)
    data["joint"][1]["point"] = [1.0001, 0.0]
    with pytest.raises(SpecError, match="joint 'p' .*cannot close at t = 0: 'ground' and 'b.tip' stay "
                                        "0.0001 m apart at best, with no joint coordinate to move"):
        system_from_dict(data, "cc")
