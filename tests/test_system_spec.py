"""The system spec layer: structure checks (one line naming the item) and the spanning tree."""
from dataclasses import replace

import pytest

from flexsym.core.errors import SpecError
from flexsym.model.variant import builtin
from flexsym.model.system import (Driver, FlexibleBeam, Joint, Marker, Output, RigidBody, System,
                             spanning_tree)
from flexsym.model.library import (PAPER_SECTION, hub_system, pendulum_system,
                                      slider_crank_system, spin_up_system)

M3 = builtin("m3")


def test_library_systems_validate_and_trees():
    assert spin_up_system(M3).tree().cut == ()
    hub = hub_system(M3).tree()
    assert hub.order == ("hub", "beam") and hub.joint_of("beam") == "clamp" and hub.cut == ()
    sc = slider_crank_system(M3).tree()
    assert sc.order == ("crank", "slider", "rod")
    assert sc.cut == ("slider_pin",)  # the loop closes at the rod tip
    assert pendulum_system(M3).tree().order == ("beam",)


def _bad(system, match):
    with pytest.raises(SpecError, match=match) as exc:
        system.validate()
    assert "\n" not in str(exc.value)


BASE = hub_system(M3)


@pytest.mark.parametrize("change, match", [
    (dict(joints=(Joint("hub_joint", "revolute", "ground", "hubx.centre"),
                  Joint("clamp", "clamp", "hub.centre", "beam.root"))), "unknown body 'hubx'"),
    (dict(joints=(Joint("hub_joint", "revolute", "ground", "hub.middle"),
                  Joint("clamp", "clamp", "hub.centre", "beam.root"))), "no marker 'middle'"),
    (dict(bodies=BASE.bodies + (RigidBody("extra", 1.0, 1.0),)), "'extra' is connected to nothing"),
    (dict(bodies=(RigidBody("hub", 0.0, 40.0, markers=(Marker("centre", 0.0),)),) + BASE.bodies[1:]),
     "body 'hub': mass 0.0"),
    (dict(bodies=(RigidBody("hub", 1.0, -1.0, markers=(Marker("centre", 0.0),)),) + BASE.bodies[1:]),
     "body 'hub': inertia -1.0"),
    (dict(drivers=(Driver("motor", "motor", "nojoint", expression="1"),)), "joint 'nojoint' does not exist"),
    (dict(drivers=(Driver("motor", "motor", "clamp", expression="1"),)), "clamp \\(no coordinate"),
    (dict(drivers=BASE.drivers + (Driver("motor", "guided", "hub_joint", maneuver="spin_up"),)),
     "duplicate name 'motor'"),
    (dict(joints=(Joint("hub_joint", "revolute", "ground", "hub.centre"),
                  Joint("clamp", "clamp", "hub.centre", "beam.tip"))), "flexible body 'beam' is not reached"),
    (dict(outputs=(Output("a", "angle(nope)"),)), "output 'angle\\(nope\\)'"),
    (dict(outputs=(Output("a", "v(hub, tip)"),)), "'hub' is not a flexible body"),
])
def test_malformed_systems_one_line(change, match):
    _bad(replace(BASE, **change), match)


def test_driver_on_cut_joint_refused():
    sc = slider_crank_system(M3)
    _bad(replace(sc, drivers=(Driver("d", "motor", "slider_pin", expression="0"),)), "cut joint")


def test_beam_marker_outside_refused():
    beam = FlexibleBeam("beam", 10.0, PAPER_SECTION, M3, markers=(Marker("far", 11.0),))
    _bad(replace(spin_up_system(M3), bodies=(beam,)), "marker 'far' at x = 11.0 is outside")


def test_spanning_tree_prefers_root_of_flexible_body():
    # the rod is reached first through its tip joint in file order, but hangs from its root
    sys = slider_crank_system(M3)
    j = sys.joints
    reordered = replace(sys, joints=(j[0], j[2], j[3], j[1]))
    tree = spanning_tree(reordered)
    assert tree.joint_of("rod") == "crank_pin" and tree.cut == ("slider_pin",)


def test_describe_shows_tree_coordinates_terms_and_ops():
    from flexsym.codegen.sysgen import describe

    text = describe(pendulum_system(builtin("m1")))
    assert "tree beam <- pin" in text and "pin (joint)" in text and "beam_u_static (axial)" in text
    assert "body beam: cubic acts on bending" in text  # #1: the cubic term on bending only
    assert "kernel fsm_pendulum_force:" in text and "constraint" not in text


def test_system_generation_is_deterministic_across_hash_seeds():
    """The generated folder of a system is byte-identical whatever Python's hash seed (a
    one-block oscillator: the whole pipeline, kept small for time)."""
    import os
    import subprocess
    import sys

    code = ("import hashlib, json; from flexsym.codegen.sysgen import generate_system_files; "
            "from flexsym.model.system import *; "
            "s = System('osc', bodies=(RigidBody('block', 2.0, 0.01, markers=(Marker('c', 0.0),)),), "
            "joints=(Joint('slide', 'prismatic', 'ground', 'block.c', axis=(1.0, 0.0), initial=0.1),), "
            "loads=(SpringDamper('ground', 'block.c', 50.0, 2.0, 1.0, point_a=(-1.0, 0.0)), Gravity()), "
            "outputs=(Output('x', 'x(block.c)'), Output('T', 'T'))); "
            "f = generate_system_files(s); "
            "print(hashlib.sha256(json.dumps(f, sort_keys=True).encode()).hexdigest())")
    digests = {subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                              env=dict(os.environ, PYTHONHASHSEED=seed)).stdout for seed in ("1", "2")}
    assert len(digests) == 1
