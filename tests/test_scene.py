"""Scenes: validation of malformed files, the model a scene gets, the shipped scenes, the
Python API and concurrent builds."""
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from flexsym.apps import api
from flexsym.apps.cli import main
from flexsym.core.errors import SpecError
from flexsym.codegen.folder import read_manifest
from flexsym.core.paths import PACKAGE_DIR
from flexsym.scenes.scene import load_scene

SCENES = PACKAGE_DIR.parent / "scenes"

GOOD = """
[beam]
length = 10.0
density = 3000.0
youngs_modulus = 7.0e10
area = 4.0e-4
inertia = 2.0e-7

[maneuver]
kind = "spin-up"
omega = 6.0
duration = 15.0

[model]
variant = "m3"

[solver]
integrator = "genalpha"
dt = 1.0e-3
t_end = 2.0

[output]
file = "OUT"
quantities = ["v_tip", "M(A)", "M(hub)", "M(2.5)"]
positions = { hub = 0.5 }
"""


def write(tmp_path, text, name="scene.toml"):
    out = tmp_path / "result.csv"
    path = tmp_path / name
    path.write_text(text.replace("OUT", str(out)))
    return path, out


BAD = [
    # (replace this, with that, expected message fragment)
    ('length = 10.0', '', "[beam] length: missing"),
    ('length = 10.0', 'length = "ten"', "[beam] length: must be a number, not str"),
    ('length = 10.0', 'length = 0.0', "[beam] length: must be > 0"),
    ('density = 3000.0', 'density = -3000.0', "[beam] density: must be > 0"),
    ('youngs_modulus = 7.0e10', 'youngs_modulus = 0', "[beam] youngs_modulus: must be > 0"),
    ('area = 4.0e-4', 'area = -4.0e-4', "[beam] area: must be > 0"),
    ('inertia = 2.0e-7', 'inertia = 0.0', "[beam] inertia: must be > 0"),
    ('inertia = 2.0e-7', 'inertia = nan', "[beam] inertia: must be finite"),
    ('length = 10.0', 'lenght = 10.0', "[beam] lenght: unknown key"),
    ('[beam]', '[beams]', "beams: unknown table"),
    ('kind = "spin-up"', 'kind = "spin-down"', "[maneuver] kind: unknown kind 'spin-down'"),
    ('omega = 6.0', '', "[maneuver] omega: missing"),
    ('duration = 15.0', 'duration = -1.0', "[maneuver] duration: must be > 0"),
    ('kind = "spin-up"\nomega = 6.0\nduration = 15.0', 'kind = "expression"\ntheta = "6*t +"',
     "[maneuver] theta: cannot parse theta(t)"),
    ('kind = "spin-up"\nomega = 6.0\nduration = 15.0',
     'kind = "expression"\ntheta = "__import__(\'os\').system(\'touch /tmp/pwned\')"',
     "[maneuver] theta: theta(t) = "),
    ('kind = "spin-up"\nomega = 6.0\nduration = 15.0', 'kind = "expression"\ntheta = "x * t"',
     "the name 'x' is not allowed"),
    ('kind = "spin-up"\nomega = 6.0\nduration = 15.0', 'kind = "constant"\nomega = 6.0\nduration = 1.0',
     "[maneuver] duration: does not apply to kind 'constant'"),
    ('variant = "m3"', '', "[model]: needs variant"),
    ('variant = "m3"', 'variant = "m9"', "unknown variant 'm9'"),
    ('variant = "m3"', 'strain = "foreshortening"\nbending = ["static", "xx1"]', "unknown bending mode 'xx1'"),
    ('variant = "m3"', 'strain = "foreshortening"\nbending = ["static", "cp1", "cp1"]',
     "duplicate bending mode 'cp1'"),
    ('variant = "m3"', 'strain = "foreshortening"\nbending = ["cp1", "cp2"]',
     "no bending mode moves the tip"),
    ('variant = "m3"', 'variant = "m3"\nbending = ["static"]', "give either variant or strain"),
    ('variant = "m3"', 'variant = "m3"\nname = "bad name"', "variant name 'bad name'"),
    ('variant = "m3"', 'strain = "nonlinear"\nbending = ["static"]', "unknown strain model 'nonlinear'"),
    ('dt = 1.0e-3', 'dt = 0.0', "[solver] dt: must be > 0"),
    ('dt = 1.0e-3', 'dt = -1.0e-3', "[solver] dt: must be > 0"),
    ('t_end = 2.0', 't_end = 0.0', "[solver] t_end: must be > 0"),
    ('integrator = "genalpha"', 'integrator = "euler"', "[solver] integrator: unknown integrator 'euler'"),
    ('dt = 1.0e-3', 'dt = 1.0e-3\nstep = 0.1', "[solver] step: applies to radau5, not to integrator genalpha"),
    ('integrator = "genalpha"', 'integrator = "radau5"\nstep = 0.0', "[solver] step: must be > 0"),
    ('"M(2.5)"', '"M(12.5)"', "is outside the beam [0, 10] m"),
    ('positions = { hub = 0.5 }', 'positions = { hub = -0.5 }', "[output] positions.hub"),
    ('positions = { hub = 0.5 }', 'positions = { "hub-1" = 0.5 }', "reaches generated C"),
    ('"M(2.5)"', '"X(2.5)"', "unknown quantity 'X(2.5)'"),
    ('"M(2.5)"', '"M(nowhere)"', "'nowhere' is neither a number of metres nor a name"),
    ('"M(2.5)"', '"N(A)"', "N_A is not available"),
    ('"M(2.5)"', '"M(A)"', "'M(A)' is asked for twice"),
    ('quantities = ["v_tip", "M(A)", "M(hub)", "M(2.5)"]', 'quantities = "v_tip"',
     "[output] quantities: must be a list of strings"),
    ('[solver]', '[solver\n', "not valid TOML"),
]


@pytest.mark.parametrize("old,new,msg", BAD, ids=[m for _, _, m in BAD])
def test_malformed_scene_is_refused(tmp_path, capsys, old, new, msg):
    assert old in GOOD
    path, out = write(tmp_path, GOOD.replace(old, new, 1))
    code = main(["run", str(path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and str(path) in err[0] and msg in err[0], err
    assert not out.exists(), "nothing may be written for a malformed scene"
    assert not Path("/tmp/pwned").exists()


def test_malformed_scene_does_not_overwrite(tmp_path, capsys):
    path, out = write(tmp_path, GOOD.replace("dt = 1.0e-3", "dt = -1.0"))
    out.write_text("earlier results\n")
    assert main(["run", str(path)]) == 2
    assert out.read_text() == "earlier results\n"
    assert main(["run", str(tmp_path / "missing.toml")]) == 2
    assert "no such scene file" in capsys.readouterr().err


def test_good_scene_runs_and_matches_the_variant(tmp_path, capsys):
    path, out = write(tmp_path, GOOD)
    assert main(["run", str(path)]) == 0, capsys.readouterr().err
    header = out.read_text().splitlines()[0].split(",")
    assert header[:5] == ["t", "v_tip", "M_A", "M_hub", "M_x2p5"]
    scene = load_scene(path)
    assert dict(scene.spec.points) == {"hub": "1/20", "x2p5": "1/4"}
    # The same dynamics as the built-in #3: only the outputs differ.
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    ref = api.simulate("m3", t_end=2.0)
    assert np.max(np.abs(data[:, 1] - ref["v_tip"])) < 1e-12
    assert np.max(np.abs(data[:, 2] - ref["M_A"])) < 1e-9


def test_radau5_scene_with_its_own_step(tmp_path, capsys):
    """[solver] step: radau5 takes 8 steps of 0.25 s and writes rows every 10 ms (the scene's
    interval) that follow genalpha at 1 ms within the 1e-4 m of the step's error."""
    text = GOOD.replace('integrator = "genalpha"\ndt = 1.0e-3', 'integrator = "radau5"\nstep = 0.25\ndt = 1.0e-2')
    path, out = write(tmp_path, text)
    assert main(["run", str(path)]) == 0, capsys.readouterr().err
    r = api.run(load_scene(path))
    assert r.summary["steps"] == 8 and len(r.t) == 201
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert np.array_equal(data[:, 1], r["v_tip"])
    ref = api.simulate("m3", t_end=2.0)
    assert np.max(np.abs(r["v_tip"] - ref["v_tip"])) < 1e-4


def test_constant_speed_scene_drops_alpha_terms_and_keeps_physics(tmp_path):
    scene = load_scene(SCENES / "constant_speed.toml")
    r = api.run(scene, out=tmp_path / "c.csv")
    assert r.ok
    manifest = read_manifest(api.generate(scene))
    assert any("theta''" in x["what"] for x in manifest["left_out"])
    full = read_manifest(api.generate(scene.full_spec))
    assert manifest["kernels"]["force"]["total_ops"] < full["kernels"]["force"]["total_ops"]
    assert manifest["kernels"]["outputs"]["total_ops"] < full["kernels"]["outputs"]["total_ops"]
    # Suddenly applied centrifugal load: the axial mode oscillates between 0 and twice the static
    # elongation rho Omega^2 L^3 / (3E) (slightly less: generalized-alpha damps a little).
    static = 3000.0 * 36.0 * 1000.0 / (3 * 7.0e10)
    assert 1.9 * static < np.max(r["u_tip"]) < 2.01 * static


def test_expression_scene(tmp_path):
    scene = load_scene(SCENES / "custom_manoeuvre.toml")
    assert scene.spec.maneuver.startswith("expression:")
    kern = api.kernels(scene)
    for t in (2.0, 5.0, 7.0):  # theta, theta', theta'' of the generated kernel
        tau = min(t / 5, 1.0)
        rate = 2 * (3 * tau**2 - 2 * tau**3)
        assert abs(kern.maneuver(t, [])[1] - rate) < 1e-12
    r = api.run(scene, out=tmp_path / "e.csv")
    assert r.ok and "N_sensor" in r.columns and np.max(np.abs(r["v_tip"])) < 1.0


def test_unused_axial_modes_are_left_out_with_a_note(tmp_path):
    text = GOOD.replace('variant = "m3"', 'strain = "prestress"\naxial = ["static"]\n'
                        'bending = ["static", "cp1", "cp2"]').replace("t_end = 2.0", "t_end = 20.0")
    path, _ = write(tmp_path, text, "lean.toml")
    lean = load_scene(path)
    assert lean.spec.axial == () and "Coriolis" in lean.spec.left_out[0][1]
    path2, _ = write(tmp_path, text.replace('axial = ["static"]', 'axial = ["static"]\nkeep_axial = true'),
                     "kept.toml")
    kept = load_scene(path2)
    assert len(kept.spec.axial) == 1
    a, b = api.run(lean, out=tmp_path / "a.csv"), api.run(kept, out=tmp_path / "b.csv")
    peak = np.max(np.abs(b["v_tip"]))
    assert np.max(np.abs(a["v_tip"] - b["v_tip"])) < 2e-4 * peak  # the stated ~1e-4 of v_tip


def test_shipped_scenes_are_valid():
    names = sorted(p.name for p in SCENES.glob("*.toml"))
    assert len(names) >= 4
    for p in SCENES.glob("*.toml"):
        load_scene(p)


def test_inspect_scene_shows_savings(capsys):
    assert main(["inspect", str(SCENES / "constant_speed.toml"), "--section", "ops"]) == 0
    out = capsys.readouterr().out
    assert "What this scene's model leaves out" in out and "theta'' (alpha) terms" in out
    assert "full model" in out and "saved" in out


def test_python_api_mirrors_cli(tmp_path):
    r = api.simulate("m1", ws=2.0, t_end=1.0)
    assert r.ok and isinstance(r["v_tip"], np.ndarray) and r.t[-1] == pytest.approx(1.0)
    spec = api.variant("m1", bending="static,cp1", name="api_test")
    assert api.build(spec).executable.exists()
    assert "energy" in api.inspect("m1", sections="energy").lower()
    with pytest.raises(SpecError):
        api.simulate("m1", dt=-1)


def test_concurrent_builds_of_one_variant_are_safe(tmp_path):
    """Two processes generate and build the same new variant at once into one cache: both
    succeed with identical binaries, and no temporary or half-built directory remains."""
    env = dict(os.environ, FLEXSYM_CACHE=str(tmp_path / "cache"))
    cmd = [sys.executable, "-m", "flexsym.apps.cli", "build", "m1", "--bending", "static,cp1,cp2,cp3",
           "--name", "race"]
    procs = [subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for _ in range(2)]
    outs = [p.communicate(timeout=300) for p in procs]
    assert all(p.returncode == 0 for p in procs), outs
    exes = {o[0].strip().split(": ")[-1] for o in outs}
    assert len(exes) == 1
    builds = [d for d in (tmp_path / "cache" / "build").iterdir() if d.is_dir()]
    # the model, .kernels (its kernels' objects, kept for its derivation), .runtime
    assert sorted(d.name for d in builds if d.name.startswith(".")) == [".kernels", ".runtime"]
    assert len(builds) == 3
    runtimes = [d for d in (tmp_path / "cache" / "build" / ".runtime").iterdir() if d.is_dir()]
    assert len(runtimes) == 1 and not runtimes[0].name.startswith(".")  # the runtime's objects
    variants = [d for d in (tmp_path / "cache" / "variants").iterdir() if d.is_dir()]
    assert len(variants) == 1 and json.loads((variants[0] / "manifest.json").read_text())


def test_select_picks_the_cheapest_model_within_tolerance(tmp_path, capsys):
    from flexsym.analysis.model_select import choose, noise_band, select, table

    path, _ = write(tmp_path, GOOD.replace("t_end = 2.0", "t_end = 8.0").replace(
        'quantities = ["v_tip", "M(A)", "M(hub)", "M(2.5)"]', 'quantities = ["v_tip", "M(A)"]'))
    scene = load_scene(path)
    results, best = select(scene, 0.05, max_bending=2, repeat=1, log=lambda m: None)
    assert len(results) == 8  # 3 strain models (2 axial sets for #1/#2) x 2 bending sets
    assert all(np.isfinite(c.error) and c.cost > 0 for c in results)
    passing = [c for c in results if c.error <= 0.05]
    cheapest = min(passing, key=lambda c: c.cost)
    tied = [c for c in passing if c.cost <= cheapest.cost * (1 + noise_band(cheapest))]
    assert best in tied and best.size == min(c.size for c in tied)
    # One static bending mode cannot give the root moment within 5 % (modal truncation).
    assert all(len(c.spec.bending) == 2 for c in passing)
    assert choose(results, 1e-9) is None
    text = table(results, best, 0.05)
    assert text.count("**chosen**") == 1 and len(text.splitlines()) == 4 + len(results)
    assert "fewest coordinates wins" in text
