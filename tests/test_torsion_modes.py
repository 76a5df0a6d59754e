"""A spatial beam's torsion modes as a model choice: model = { ..., torsion = [...] }, the bar's
shapes (default: ff1 alone), none where nothing reads the twist and its stiff mode would only
cap the step (S7: docs/validation/spatial.md). Checked against the Ritz solution of a shaft
twisted by a tip torque, in closed form, and the refusals."""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from flexsym.apps.cli import main
from flexsym.model.system import beam_coordinates
from flexsym.model.variant import TORSION_MODES, builtin
from flexsym.scenes.scene import load_scene

TORQUE = 3.0  # N m about the shafts' axis, on a cap clamped to each tip

# Four steel shafts clamped to ground, each twisted by TORQUE on a cap clamped to its tip,
# started in static equilibrium (start = "static"): one system, one build, four torsion sets.
SETS = {"s": '["static"]', "f1": '["ff1"]', "f2": '["ff1", "ff2"]', "f3": '["ff1", "ff2", "ff3"]'}


def _scene(moment: str = "constitutive") -> str:
    parts = ['[system]\nname = "shafts"\ndimension = 3\nstart = "static"\n']
    columns = []
    for k, (name, torsion) in enumerate(SETS.items()):
        parts.append(f"""
[[body]]
name = "shaft_{name}"
kind = "beam"
length = 0.5
density = 7850.0
youngs_modulus = 2.1e11
shear_modulus = 8.1e10
area = 3.0e-4
inertia_z = 2.5e-9
inertia_y = 1.0e-8
torsion_constant = 5.0e-9
model = {{ strain = "linear", bending = ["cf1"], moment = "{moment}", torsion = {torsion} }}

[[body]]
name = "cap_{name}"
kind = "rigid"
mass = 0.1
inertia = [1e-5, 1e-5, 1e-5]
markers = {{ c = [0.0, 0.0, 0.0] }}

[[joint]]
name = "root_{name}"
kind = "clamp"
parent = "ground"
point = [0.0, {0.2 * k}, 0.0]
child = "shaft_{name}.root"

[[joint]]
name = "tip_{name}"
kind = "clamp"
parent = "shaft_{name}.tip"
child = "cap_{name}.c"

[[load]]
kind = "torque"
body = "cap_{name}"
torque = ["{TORQUE}", "0", "0"]
""")
        columns.append(f'T_{name} = "Mx(shaft_{name}, root)"')
    parts.append(f"""
[solver]
integrator = "genalpha"
dt = 1e-3
t_end = 0.002

[output]
interval = 1e-3
columns = {{ {", ".join(columns)} }}
""")
    return "".join(parts)


def _ritz(n: int) -> float:
    """Mx(0) / T of the Ritz solution on the fixed-free shapes sin((2k - 1) pi s / 2), k <= n:
    q_k = T phi_k(1) / K_kk, K_kk = GJ/L int phi_k'^2 = GJ/L ((2k - 1) pi / 2)^2 / 2, and
    Mx(0) = GJ/L sum q_k phi_k'(0) = T (4/pi) sum (-1)^(k+1) / (2k - 1): the Leibniz series,
    so it tends to T."""
    return 4 / math.pi * sum((-1) ** (k + 1) / (2 * k - 1) for k in range(1, n + 1))


@pytest.fixture(scope="module")
def shafts(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("shafts")
    scene, out = tmp / "shafts.toml", tmp / "shafts.csv"
    scene.write_text(_scene())
    assert main(["run", str(scene), "--out", str(out)]) == 0
    return np.genfromtxt(out, delimiter=",", names=True, comments="#")


def test_the_twist_of_a_tip_torque_is_the_ritz_solution_of_each_mode_set(shafts):
    # the linear shape s is the exact twist of a uniform torque; ff1..ffn are Ritz's partial sums
    assert np.allclose(shafts["T_s"], TORQUE, rtol=1e-9, atol=0)
    for name, n in (("f1", 1), ("f2", 2), ("f3", 3)):
        assert np.allclose(shafts[name.replace("f", "T_f")], TORQUE * _ritz(n), rtol=1e-9, atol=0), name
    assert abs(_ritz(1) - 1.27324) < 1e-5 and abs(_ritz(2) - 0.84883) < 1e-5  # not all alike


def test_the_coordinates_follow_the_mode_set(tmp_path):
    path = tmp_path / "shafts.toml"
    path.write_text(_scene())
    scene = load_scene(path)
    coords = {b.name: [n for n, _, _ in beam_coordinates(b)] for b in scene.system.bodies if b.flexible}
    assert [n for n in coords["shaft_s"] if n.startswith("phi_")] == ["phi_static"]
    assert [n for n in coords["shaft_f3"] if n.startswith("phi_")] == ["phi_ff1", "phi_ff2", "phi_ff3"]


def test_the_default_is_one_mode_and_leaves_fingerprints_alone():
    m2 = builtin("m2")
    assert m2.torsion == TORSION_MODES and "torsion" not in m2.to_dict()
    assert replace(m2, torsion=()).to_dict()["torsion"] == []


@pytest.mark.parametrize("model, expected", [
    ('{ variant = "m2", torsion = ["cf1"] }', "unknown torsion mode 'cf1'"),
    ('{ variant = "m2", torsion = ["ff1", "ff1"] }', "duplicate torsion mode 'ff1'"),
    ('{ variant = "m2", torsion = "ff1" }', "model torsion: must be a list of mode names"),
    ('{ variant = "ef", torsion = [] }', "torsion to modal variants only"),
    ('{ variant = "ef", stress = "element:4" }', "and stress too"),
    ('{ variant = "m2", stress = "element:4" }', "the element stress method ('element:4') is the plane's"),
    ('{ variant = "m2", moment = "constitutive", torsion = [] }', "has no torsion modes (torsion = [])"),
])
def test_bad_torsion_sets_are_refused_in_one_line(tmp_path, capsys, model, expected):
    text = _scene().replace('model = { strain = "linear", bending = ["cf1"], moment = "constitutive", '
                            'torsion = ["static"] }', f"model = {model}")
    scene = tmp_path / "bad.toml"
    scene.write_text(text)
    out = tmp_path / "bad.csv"
    assert main(["run", str(scene), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and expected in err[0], err
    assert not out.exists()


def test_a_constitutive_moment_where_no_mode_twists_is_refused(tmp_path, capsys):
    scene = tmp_path / "tip.toml"  # ff modes are free at the tip: their twist rate is zero there
    scene.write_text(_scene().replace('"Mx(shaft_f2, root)"', '"Mx(shaft_f2, tip)"'))
    assert main(["run", str(scene), "--out", str(tmp_path / "t.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "the twist rate of every torsion mode" in err[0] and "T_f2" in err[0], err


def test_a_planar_beam_takes_no_torsion_modes(tmp_path, capsys):
    text = (Path(__file__).resolve().parent.parent / "scenes" / "four_bar.toml").read_text()
    text = "\n".join('model = { variant = "m3", torsion = [] }' if line.startswith("model =") else line
                     for line in text.splitlines())
    scene = tmp_path / "planar.toml"
    scene.write_text(text)
    assert main(["run", str(scene), "--out", str(tmp_path / "p.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "torsion modes apply to spatial beams" in err[0], err


def test_a_twist_beyond_the_models_range_is_flagged(tmp_path, capsys):
    """The shafts with G / 40 (a run-time parameter: the fixture's kernels are reused) twist
    by T L / (G J) = 0.15 rad in their static start, beyond the 0.1 rad a modal beam's first-
    order section rotations are held to: `flexsym run` exits with 4, one line per shaft. The
    linear shape's bound is the tip's twist itself, in closed form."""
    G = 8.1e10 / 40
    scene = tmp_path / "soft.toml"
    scene.write_text(_scene().replace("shear_modulus = 8.1e10", f"shear_modulus = {G:g}"))
    assert main(["run", str(scene), "--out", str(tmp_path / "soft.csv")]) == 4
    err = [line for line in capsys.readouterr().err.splitlines() if "left the range" in line]
    assert len(err) == len(SETS) and all("a bound on |twist|" in line for line in err), err
    [static] = [line for line in err if "'shaft_s'" in line]
    twist = TORQUE * 0.5 / (G * 5.0e-9)
    assert f"peak {twist:.4g} rad" in static and "at t = 0 s" in static, static
