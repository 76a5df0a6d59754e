"""The built-in `exact`'s bending modes from a beam's end joints (flexsym/model/end_modes.py):
pinned at both ends pp, pinned with a free tip pf, else cf; kept cf wherever the scene reads the
frame those modes move (docs/theory/exact-kinematics.md, "Which modes by default")."""
from pathlib import Path

import pytest

from flexsym.codegen.sysgen import fingerprint
from flexsym.scenes.scene import load_scene

SCENES = Path(__file__).resolve().parents[1] / "scenes"


def bending(path, model="exact") -> dict:
    system = load_scene(path, model=model).system
    return {b.name: [m.token for m in b.model.bending] for b in system.bodies if b.flexible}


def five(family: str) -> list:
    return [f"{family}{k}" for k in range(1, 6)]


@pytest.mark.parametrize("scene, beam, family", [
    ("slider_crank", "rod", "pp"),          # pinned to the crank, and to the slider by a cut pin
    ("four_bar", "coupler", "pp"),
    ("offset_slider_crank", "rod", "pp"),
    ("flex_rocker", "rocker", "pp"),        # pinned to ground, the loop closed at its tip
    ("pendulum", "beam", "pf"),             # pinned to ground, free tip
    ("hub", "beam", "cf"),                  # clamped to the hub
    ("stepped_hub", "blade", "cf"),         # clamped, and from finite-element data
    ("double_pendulum", "strip", "cf"),     # pinned, free tip, but angle(elbow) reads its frame
])
def test_the_shipped_scenes_take_their_ends_modes(scene, beam, family):
    assert bending(SCENES / f"{scene}.toml")[beam] == five(family)


def _edited(tmp_path, scene: str, old: str, new: str) -> Path:
    text = (SCENES / f"{scene}.toml").read_text()
    assert text.count(old) == 1, old
    path = tmp_path / f"{scene}.toml"
    path.write_text(text.replace(old, new))
    return path


def test_what_reads_or_holds_the_frame_keeps_clamped_modes(tmp_path):
    # a column that reads the rod's frame: v (its deflection in the frame), or the root pin's angle
    cols = 'columns = { x_s = "x(slider.pin)"'
    for extra in ('v_mid = "v(rod, mid)", ', 'a = "angle(crank_pin)", '):
        path = _edited(tmp_path, "slider_crank", cols, 'columns = { ' + extra + 'x_s = "x(slider.pin)"')
        assert bending(path)["rod"] == five("cf"), extra
    # the loop closed at an inner marker, not at the tip: neither end condition holds
    path = _edited(tmp_path, "slider_crank", 'parent = "rod.tip"', 'parent = "rod.mid"')
    assert bending(path)["rod"] == five("cf")


def test_a_named_mode_set_is_kept(tmp_path):
    path = _edited(tmp_path, "slider_crank", 'model = "m2"',
                   'model = { strain = "exact", bending = ["cf1", "cf2", "cf3"] }')
    assert bending(path, model=None)["rod"] == ["cf1", "cf2", "cf3"]


@pytest.mark.parametrize("scene, model, family", [("slider_crank", 'model = "m2"', "pp"),
                                                  ("pendulum", 'model = "m3"', "pf")])
def test_the_default_is_the_named_set_it_stands_for(tmp_path, scene, model, family):
    """`--model exact` on S2 (S3) is the same model, fingerprint and generated code, as naming
    pp1-pp5 (pf1-pf5)."""
    modes = ", ".join(f'"{m}"' for m in five(family))
    named = _edited(tmp_path, scene, model, f'model = {{ strain = "exact", bending = [{modes}] }}')
    a = load_scene(SCENES / f"{scene}.toml", model="exact").system
    b = load_scene(named).system
    assert fingerprint(a) == fingerprint(b)
