"""Body kinds (flexsym/physics/body_kinds/, the spatial ones in its spatial/): the registry
picks one kind per body from its data, every kind is one module listed in KINDS (KINDS of the
spatial package) and in the generator's fingerprint, and derive_system (derive_spatial) reaches
a body only through its kind."""
import tomllib
from pathlib import Path

import pytest

from flexsym.core.errors import SpecError
from flexsym.core.versions import GENERATOR_MODULES
from flexsym.model.library import hub_system, pendulum_system, slider_crank_system, spin_up_system
from flexsym.model.variant import builtin
from flexsym.physics import body_kinds
from flexsym.physics.assemble import derive_system
from flexsym.physics.body_kinds import KINDS, kind_of
from flexsym.physics.body_kinds import spatial
from flexsym.physics.body_kinds.rigid import Rigid
from flexsym.physics.body_kinds.spatial.rigid import Rigid as Rigid3
from flexsym.physics.spatial import derive_spatial
from flexsym.scenes.system_scene import system_from_dict

ROOT = Path(__file__).resolve().parent.parent


def test_every_module_is_a_registered_kind_in_the_fingerprint():
    modules = {p.stem for p in Path(body_kinds.__file__).parent.glob("*.py")} - {"__init__", "base"}
    assert set(KINDS) == modules  # a module not listed in KINDS is no kind: fails here
    for name, kind in KINDS.items():
        assert kind.name == name
        assert f"physics.body_kinds.{name}" in GENERATOR_MODULES  # editing a kind regenerates


@pytest.mark.parametrize("variant, beam", [("m3", "modal"), ("prestress", "modal"), ("exact", "exact"),
                                           ("ef", "ef")])
@pytest.mark.parametrize("make", [spin_up_system, hub_system, pendulum_system, slider_crank_system])
def test_library_bodies_map_to_their_kinds(make, variant, beam):
    system = make(builtin(variant))
    got = {b.name: kind_of(b).name for b in system.bodies}
    assert got == {b.name: beam if b.flexible else "rigid" for b in system.bodies}


def test_a_beam_from_finite_element_data_is_modal_or_ef():
    """S4's stepped blade (sections and a tip mass): the same kinds, another integral table."""
    seg = {"length": 0.5, "density": 2700.0, "youngs_modulus": 7.0e10, "area": 1.0e-4, "inertia": 2.0e-10}
    blade = {"name": "blade", "kind": "beam", "elements": 4, "segments": [seg, seg],
             "point_masses": [{"x": 1.0, "mass": 0.05}]}
    for model, kind in (({"strain": "prestress", "bending": ["cf1"]}, "modal"),
                        ({"strain": "exact", "bending": ["cf1"]}, "exact"),
                        ({"variant": "ef", "elements": 2}, "ef")):
        system = system_from_dict({"body": [{**blade, "model": model}],
                                   "joint": [{"name": "pin", "kind": "revolute", "parent": "ground",
                                              "point": [0.0, 0.0], "child": "blade.root"}],
                                   "output": {"columns": {"a": "angle(pin)"}}})
        assert kind_of(system.bodies[0]).name == kind, model


def test_a_new_kind_registers_in_one_place(monkeypatch):
    """A kind added to KINDS is found by kind_of (two that apply to one body are refused), and
    the derivation goes through its methods: here a rigid kind that counts its calls."""
    calls = []

    class Counted(Rigid):
        name = "counted"

        def contribute(self, der, b, frame, integral_symbols):
            calls.append(b.name)
            super().contribute(der, b, frame, integral_symbols)

    system = system_from_dict({
        "body": [{"name": "bob", "kind": "rigid", "mass": 1.0, "inertia": 0.1,
                  "markers": {"pivot": [0.0, 0.0]}}],
        "joint": [{"name": "pin", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0],
                   "child": "bob.pivot"}],
        "output": {"columns": {"a": "angle(pin)"}}})
    monkeypatch.setitem(KINDS, "counted", Counted())
    with pytest.raises(SpecError, match="2 planar body kinds apply"):
        kind_of(system.bodies[0])
    monkeypatch.delitem(KINDS, "rigid")
    der = derive_system(system)
    assert calls == ["bob"] and der.mass == {"bob": 1}


def test_every_spatial_module_is_a_registered_kind_in_the_fingerprint():
    modules = {p.stem for p in Path(spatial.__file__).parent.glob("*.py")} - {"__init__", "base"}
    assert set(spatial.KINDS) == modules  # a module not listed in KINDS is no kind: fails here
    for name, kind in spatial.KINDS.items():
        assert kind.name == name
        assert f"physics.body_kinds.spatial.{name}" in GENERATOR_MODULES  # editing a kind regenerates


S5_S7 = ("flap", "spherical_pendulum", "spatial_slider_crank")
EF2 = {"variant": "ef", "elements": 2}


@pytest.mark.parametrize("scene, model, beam", [(s, None, "modal") for s in S5_S7 + ("flap_mesh", "slew_arm")]
                         + [(s, EF2, "ef") for s in S5_S7])
def test_spatial_scene_bodies_map_to_their_kinds(scene, model, beam):
    """S5 (from the analytic modes and from a mesh), S6, S7 and the slew arm as their scenes
    give them (modal beams), and S5-S7 with every beam an ef (a uniform, undamped rod: not the
    mesh, nor the slew arm's damped beam): each body's spatial kind."""
    data = tomllib.loads((ROOT / "scenes" / f"{scene}.toml").read_text())
    for b in data["body"]:
        if b["kind"] == "beam" and model is not None:
            b["model"] = model
    system = system_from_dict(data, name=scene, base=ROOT / "scenes")
    got = {b.name: spatial.kind_of(b).name for b in system.bodies}
    assert got == {b.name: beam if b.flexible else "rigid" for b in system.bodies}
    assert beam in got.values()


def test_a_new_spatial_kind_registers_in_one_place(monkeypatch):
    """As in the plane: a kind added to the spatial KINDS is found by kind_of (two that apply to
    one body are refused), and derive_spatial goes through its methods."""
    calls = []

    class Counted(Rigid3):
        name = "counted"

        def contribute(self, der, b, P, fr, motion, gvec):
            calls.append(b.name)
            super().contribute(der, b, P, fr, motion, gvec)

    system = system_from_dict({
        "system": {"name": "top", "dimension": 3},
        "body": [{"name": "top", "kind": "rigid", "mass": 2.0, "inertia": [0.035, 0.02, 0.02],
                  "com": [0.1, 0.0, 0.0], "markers": {"pivot": [0.0, 0.0, 0.0]}}],
        "joint": [{"name": "ball", "kind": "spherical", "parent": "ground", "point": [0.0, 0.0, 0.0],
                   "child": "top.pivot"}],
        "gravity": {"g": [0.0, 0.0, -9.81]},
        "output": {"columns": {"z": "z(top.pivot)", "H": "Hz"}}}, name="top")
    monkeypatch.setitem(spatial.KINDS, "counted", Counted())
    with pytest.raises(SpecError, match="2 spatial body kinds apply"):
        spatial.kind_of(system.bodies[0])
    monkeypatch.delitem(spatial.KINDS, "rigid")
    der = derive_spatial(system)
    assert calls == ["top"] and len(der.frame_T) == 1
