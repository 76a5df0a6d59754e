"""start = "static" (issue 19, item 1): the flexible bodies start in static equilibrium under
the loads at t = 0, the joints held; a run from there stays at rest. Checked against the
cantilever's closed forms, for a modal model and for ef."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from flexsym.apps.cli import main

ROOT = Path(__file__).resolve().parent.parent
RHO, E, A, I, L, G = 7850.0, 2.1e11, 5.026548245743669e-05, 2.0106192982974676e-10, 0.4, 9.81

SCENE = f"""
[system]
name = "{{name}}"
start = "static"

[[body]]
name = "rod"
kind = "beam"
length = {L}
density = {RHO}
youngs_modulus = {E}
area = {A}
inertia = {I}
model = "{{model}}"

[[joint]]
name = "root"
kind = "clamp"
parent = "ground"
point = [0.0, 0.0]
child = "rod.root"
{{offset}}

[gravity]
g = [0.0, -{G}]

[solver]
integrator = "genalpha"
dt = 1e-4
t_end = 0.05

[output]
interval = 1e-3
columns = {{{{ v_tip = "v(rod, tip)", N_root = "N(rod, root)", M_root = "M(rod, root)" }}}}
"""


def run(tmp_path, capsys, text, *flags):
    scene = tmp_path / "s.toml"
    scene.write_text(text)
    out = tmp_path / "s.csv"
    code = main(["run", str(scene), "--out", str(out), *flags])
    err = capsys.readouterr().err
    assert code == 0, err
    return np.genfromtxt(out, delimiter=",", names=True, comments="#"), out.read_text().splitlines()


@pytest.mark.parametrize("model, angle", [("m3", 0.0), ("m2", 30.0)])
def test_a_cantilever_starts_sagged_and_stays_at_rest(tmp_path, capsys, model, angle):
    """A cantilever clamped at `angle` above the horizontal: the tip deflects by the load
    across it, q L^4 / (8 EI) with q = rho A g cos(angle) (the modes hold the uniform load's
    deflection exactly: measured to 1e-15 with m3); the root carries N = -rho A g L sin(angle)
    (compression) along it and M = -q L^2 / 2 (from equilibrium, exact at rest); and the run stays there:
    nothing moves over 50 ms (the Newton tolerance, 1e-12 of the size)."""
    a = math.radians(angle)
    offset = f"offset = {a!r}" if angle else ""
    d, lines = run(tmp_path, capsys, SCENE.format(name="cantilever", model=model, offset=offset))
    q = RHO * A * G * math.cos(a)
    sag = -q * L**4 / (8 * E * I)
    assert d["v_tip"][0] == pytest.approx(sag, rel=2e-3 if model == "m2" else 1e-9)
    assert np.abs(d["v_tip"] - d["v_tip"][0]).max() <= 1e-9 * abs(sag)
    # tilted, the axial load's lever arm on the sagged shape adds (a second-order term: 3e-4)
    assert np.allclose(d["M_root"], -q * L**2 / 2, rtol=1e-6 if angle == 0 else 1e-3)
    # tilted up, its weight along it compresses the root (tension > 0)
    assert np.allclose(d["N_root"], -RHO * A * G * L * math.sin(a), rtol=1e-6, atol=1e-9 * RHO * A * G * L)
    assert lines[1].startswith("# start: the flexible bodies in static equilibrium")


def test_ef_starts_in_the_same_equilibrium(tmp_path, capsys):
    """ef (16 ANCF elements): the same sag within 1e-4 (geometric nonlinearity and the mesh), at
    rest over the run."""
    d, _ = run(tmp_path, capsys, SCENE.format(name="cantilever_ef", model="ef", offset=""))
    sag = -RHO * A * G * L**4 / (8 * E * I)
    assert d["v_tip"][0] == pytest.approx(sag, rel=1e-4)
    assert np.abs(d["v_tip"] - d["v_tip"][0]).max() <= 1e-8 * abs(sag)


RIGID = """
[system]
name = "rigid"
start = "static"

[[body]]
name = "bar"
kind = "rigid"
mass = 1.0
inertia = 0.01
markers = { pivot = [0.0, 0.0] }

[[joint]]
name = "pin"
kind = "revolute"
parent = "ground"
point = [0.0, 0.0]
child = "bar.pivot"

[solver]
t_end = 0.1

[output]
columns = { phi = "angle(pin)" }
"""


@pytest.mark.parametrize("text, says", [
    (SCENE.format(name="bad", model="m3", offset="").replace('start = "static"', 'start = "sagged"'),
     "start 'sagged' must be one of undeformed, static"),
    (RIGID, "puts the flexible bodies in equilibrium, and there is none"),
])
def test_bad_start_is_refused_in_one_line(tmp_path, capsys, text, says):
    scene = tmp_path / "s.toml"
    scene.write_text(text)
    assert main(["run", str(scene), "--out", str(tmp_path / "s.csv")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err and "s.toml" in err
    assert not (tmp_path / "s.csv").exists()


PARALLELOGRAM = """
[system]
name = "{name}"
start = "static"

[[body]]
name = "crank"
kind = "rigid"
mass = 0.1
inertia = 1.0e-4
com = [0.05, 0.0]
markers = {{ root = [0.0, 0.0], tip = [0.1, 0.0] }}

[[body]]
name = "coupler"
kind = "beam"
length = 0.4
density = 7850.0
youngs_modulus = 2.1e11
area = 5.026548245743669e-05
inertia = 2.0106192982974676e-10
model = "{model}"
markers = {{ mid = 0.2 }}

[[body]]
name = "rocker"
kind = "rigid"
mass = 0.2
inertia = 1.5e-3
com = [0.05, 0.0]
markers = {{ pivot = [0.0, 0.0], tip = [0.1, 0.0] }}

[[joint]]
name = "crank_joint"
kind = "revolute"
parent = "ground"
point = [0.0, 0.0]
child = "crank.root"

[[joint]]
name = "coupler_pin"
kind = "revolute"
parent = "crank.tip"
child = "coupler.root"
initial = -1.5708

[[joint]]
name = "rocker_joint"
kind = "revolute"
parent = "ground"
point = [0.4, 0.0]
child = "rocker.pivot"
initial = 1.5708

[[joint]]
name = "loop"
kind = "revolute"
parent = "coupler.tip"
child = "rocker.tip"
{driver}
[gravity]
g = [0.0, -9.81]

[solver]
integrator = "genalpha3"
dt = 1e-4
t_end = 0.02

[output]
interval = 0.001
columns = {{ rocker = "angle(rocker_joint)", N_mid = "N(coupler, mid)", M_mid = "M(coupler, mid)", w_mid = "w(coupler, mid)" }}
"""
HOLD = """
[[driver]]
name = "hold"
kind = "guided"
joint = "crank_joint"
theta = "pi/2"
"""


@pytest.mark.parametrize("model", ["m3", "ef"])
def test_a_closed_loop_starts_in_equilibrium_with_the_loop_following(tmp_path, capsys, model):
    """A parallelogram four-bar under gravity, its crank held upright, the rocker upright and the
    steel coupler level between their tips: the coupler is a simply supported beam (the rocker,
    free on its pivot and loaded along itself, takes no force along the coupler), so it starts
    at the sag 5 q L^4 / (384 EI) from its chord, with M = q L^2 / 8 and N = 0 at mid-span, the
    coupler's pin and the rocker turning to follow its ends (the header names them); and the
    run stays there. m3 recovers M from equilibrium (exact at rest) and its three modes hold the
    pinned sag to 0.29 %; ef's 16 elements the sag to 3e-8 and the moment, from the elements'
    curvature, to 0.26 %."""
    d, lines = run(tmp_path, capsys, PARALLELOGRAM.format(name=f"parallelogram_{model}", model=model,
                                                          driver=HOLD))
    q = RHO * A * G
    sag, moment = 5 * q * L**4 / (384 * E * I), q * L**2 / 8
    assert -d["w_mid"][0] == pytest.approx(sag, rel=3e-3 if model == "m3" else 1e-7)
    assert d["M_mid"][0] == pytest.approx(moment, rel=1e-7 if model == "m3" else 3e-3)
    assert abs(d["N_mid"][0]) <= 3e-5 * q * L / 2
    for c, size in (("w_mid", sag), ("M_mid", moment), ("rocker", 1.0)):
        assert np.abs(d[c] - d[c][0]).max() <= 1e-9 * size, c
    assert d["violation"].max() <= 1e-12
    start = next(x for x in lines if x.startswith("# start: "))
    assert "(joints held but rocker_joint, coupler_pin, which follow the loop;" in start


def test_an_undriven_loop_holds_its_first_joint(tmp_path, capsys):
    """Without a driver the loop's one degree of freedom is held at the joint farthest from the
    cut (the crank): the same equilibrium as with the crank guided."""
    text = PARALLELOGRAM.format(name="parallelogram_free", model="m3", driver="")
    text = text.replace('child = "crank.root"', 'child = "crank.root"\ninitial = 1.5708')
    d, lines = run(tmp_path, capsys, text.replace("t_end = 0.02", "t_end = 0.001"))
    q = RHO * A * G
    assert d["M_mid"][0] == pytest.approx(q * L**2 / 8, rel=1e-7)
    start = next(x for x in lines if x.startswith("# start: "))
    assert "(joints held but rocker_joint, coupler_pin, which follow the loop;" in start


@pytest.mark.study  # 14 s; the planar loops above run the same KKT start
def test_a_spatial_loop_starts_in_equilibrium(tmp_path, capsys):
    """S7's spatial slider-crank under gravity across its plane, its crank held: the rod starts
    sagged, the slider and the ball joint following the loop, and stays there (started
    undeformed, the same rod swings between 0 and twice that sag)."""
    text = (ROOT / "scenes" / "spatial_slider_crank.toml").read_text()
    text = text.replace('name = "spatial_slider_crank"', 'name = "s7_static"\nstart = "static"')
    text = text.replace('maneuver = "spin-up"\nomega = 150.0\nduration = 0.1', 'theta = "0"')
    text = text.replace("[solver]", "[gravity]\ng = [0.0, 0.0, -9.81]\n\n[solver]")
    d, lines = run(tmp_path, capsys, text, "--t-end", "0.005")
    assert d["w_mid"][0] > 1e-5
    for c in ("x_s", "w_mid"):
        assert np.abs(d[c] - d[c][0]).max() <= 1e-9 * abs(d["w_mid"][0]), c
    assert d["violation"].max() <= 1e-12
    start = next(x for x in lines if x.startswith("# start: "))
    assert "but slide, ball_e0, ball_e1, ball_e2, ball_e3, which follow the loop" in start
