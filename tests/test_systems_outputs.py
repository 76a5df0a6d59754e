"""Outputs of systems: joint reactions (cut joints from lambda, tree joints from the subtree's
momentum balance) and the violation as an output, against independent checks."""
import math
from dataclasses import replace

import numpy as np
import pytest

from flexsym.spec import builtin
from flexsym.system import Gravity, Joint, Marker, Output, RigidBody, System
from flexsym.systems_library import slider_crank_system

JOINTS = ("slider_pin", "slide", "crank_pin", "crank_joint")


@pytest.fixture(scope="module")
def slider_crank_run():
    from flexsym.run import run_built
    from flexsym.sysgen import prepare_system

    system = slider_crank_system(builtin("m3"))
    extra = tuple(Output(f"R_{j}_{c}", f"reaction({j}, {c})") for j in JOINTS
                  for c in ("x", "y", "moment"))
    extra += (Output("viol", "violation"), Output("tau", "torque(crank_drive)"))
    built = prepare_system(replace(system, outputs=system.outputs + extra))
    return system, run_built(built, t_end=0.3, dt=1e-4, integrator="ali3p", interval=1e-4)


def test_s2_slider_pin_force_is_slider_mass_times_acceleration(slider_crank_run):
    """The cut pin's reaction (from lambda) on the slider = m_s x_s'' (x_s'' by finite
    differences of the x_s column: 1.5e-4 of the peak measured, the differences' error); the
    slide's axial reaction (tree joint, momentum balance) is zero: 6e-8 of the peak."""
    system, r = slider_crank_run
    m_s = system.body("slider").mass
    acc = np.gradient(np.gradient(r["x_s"], r.t), r.t)
    peak = np.abs(r["R_slider_pin_x"]).max()
    assert peak > 100.0
    assert np.abs(m_s * acc - r["R_slider_pin_x"])[2:-2].max() < 1e-3 * peak
    assert np.abs(r["R_slide_x"]).max() < 1e-6 * peak
    # no gravity, no vertical motion: the slide holds the pin's normal force
    assert np.abs(r["R_slider_pin_y"]).max() > 10.0
    assert np.abs(r["R_slide_y"] + r["R_slider_pin_y"]).max() < 1e-6 * peak


def test_s2_tree_reactions_agree_with_the_lagrangian_torque(slider_crank_run):
    """The guided crank joint's moment from the momentum balance of crank + rod (with the cut
    pin's lambda) equals torque(crank_drive) from Lagrange's equations (measured 1.5e-13 N m
    of 30 N m); the pins transmit no moment."""
    _, r = slider_crank_run
    tau = np.abs(r["tau"]).max()
    assert tau > 10.0
    assert np.abs(r["R_crank_joint_moment"] - r["tau"]).max() < 1e-9 * tau
    assert np.abs(r["R_crank_pin_moment"]).max() < 1e-6 * tau
    assert np.all(r["R_slider_pin_moment"] == 0.0)


def test_violation_output_is_the_runtime_column(slider_crank_run):
    _, r = slider_crank_run
    assert r["violation"].max() > 0.0
    assert np.abs(r["viol"] - r["violation"]).max() <= 1e-15


def test_rigid_pendulum_pin_force_at_the_bottom_is_m_g_plus_centripetal():
    """A rigid bar on a pin (tree joint): at the bottom the pin pulls up with m (g + omega^2 r)
    (Newton, omega from the run) and has no horizontal component. (The flexible S3 bar rings
    from its undeformed release: its pin force carries the modes' inertia, O(1) at any E.)"""
    from flexsym.run import run_built
    from flexsym.sysgen import prepare_system

    m, r_g, g = 2.0, 0.4, 9.81
    system = System("bar", bodies=(RigidBody("bar", m, 0.1, com=(r_g, 0.0),
                                             markers=(Marker("root", 0.0),)),),
                    joints=(Joint("pin", "revolute", "ground", "bar.root"),),
                    loads=(Gravity((0.0, -g)),),
                    outputs=(Output("theta", "angle(pin)"), Output("omega", "rate(pin)"),
                             Output("Rx", "reaction(pin, x)"), Output("Ry", "reaction(pin, y)"),
                             Output("Rm", "reaction(pin, moment)")))
    r = run_built(prepare_system(system), t_end=1.0, dt=1e-4, interval=1e-4)
    y = r["theta"] + np.pi / 2
    k = np.nonzero(np.sign(y[:-1]) != np.sign(y[1:]))[0][0]
    s = -y[k] / (y[k + 1] - y[k])

    def at(c):
        return r[c][k] + s * (r[c][k + 1] - r[c][k])
    expected = m * (g + at("omega")**2 * r_g)
    assert expected > 1.5 * m * g
    assert at("Ry") == pytest.approx(expected, rel=1e-6)
    assert abs(at("Rx")) < 1e-6 * expected
    assert np.abs(r["Rm"]).max() < 1e-9 * expected
