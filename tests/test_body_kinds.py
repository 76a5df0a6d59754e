"""Planar body kinds (flexsym/physics/body_kinds/): the registry picks one kind per body from
its data, every kind is one module listed in KINDS and in the generator's fingerprint, and
derive_system reaches a body only through its kind."""
from pathlib import Path

import pytest

from flexsym.core.errors import SpecError
from flexsym.core.versions import GENERATOR_MODULES
from flexsym.model.library import hub_system, pendulum_system, slider_crank_system, spin_up_system
from flexsym.model.variant import builtin
from flexsym.physics import body_kinds
from flexsym.physics.assemble import derive_system
from flexsym.physics.body_kinds import KINDS, kind_of
from flexsym.physics.body_kinds.rigid import Rigid
from flexsym.scenes.system_scene import system_from_dict


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
