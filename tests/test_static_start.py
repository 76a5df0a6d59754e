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


def test_static_start_on_a_closed_loop_is_refused(tmp_path, capsys):
    text = (ROOT / "scenes" / "four_bar.toml").read_text().replace('name = "four_bar"', 'name = "four_bar"\nstart = "static"')
    scene = tmp_path / "fb.toml"
    scene.write_text(text)
    assert main(["run", str(scene)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "open chains only" in err and "loop" in err
