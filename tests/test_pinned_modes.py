"""Bending modes for a pinned root (issue 19): pinned-pinned (pp, sin(k pi s)) and pinned-free
(pf) modes leave the root slope free, their frame the chord's (pp) or the one whose turn about
the pin is the beam's rigid rotation (pf). A revolute joint at the root carries that rotation;
whatever would hold the root section instead (a clamp, a prismatic joint, a driver, a fixed
joint, a torque on the frame, a one-beam model's hub) is refused in one line."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from flexsym.apps.cli import main
from flexsym.core.errors import SpecError
from system_data import scene_text_refused

ROOT = Path(__file__).resolve().parent.parent
# S2's steel rod (scenes/slider_crank.toml)
RHO, E, A, I, L, G = 7870.0, 2.0e11, 2.8274333882308137e-05, 6.361725123519332e-11, 0.3, 9.81

PIN_ROLLER = f"""
[system]
name = "pin_roller"
start = "static"

[[body]]
name = "rod"
kind = "beam"
length = {L}
density = {RHO}
youngs_modulus = {E}
area = {A}
inertia = {I}
model = {{ strain = "exact", bending = ["pp1", "pp2", "pp3"], moment = "constitutive" }}
markers = {{ mid = {L / 2} }}

[[body]]
name = "roller"
kind = "rigid"
mass = 0.01
inertia = 1e-6
markers = {{ pin = [0.0, 0.0] }}

[[joint]]
name = "root"
kind = "revolute"
parent = "ground"
point = [0.0, 0.0]
child = "rod.root"

[[joint]]
name = "slide"
kind = "prismatic"
parent = "ground"
point = [0.0, 0.0]
child = "roller.pin"
axis = [1.0, 0.0]
initial = {L}

[[joint]]
name = "tip"
kind = "revolute"
parent = "rod.tip"
child = "roller.pin"

[gravity]
g = [0.0, -{G}]

[solver]
integrator = "ali3p"
dt = 1e-5
t_end = 5e-5

[output]
interval = 1e-5
columns = {{ w_mid = "w(rod, mid)", M_mid = "M(rod, mid)" }}
"""


def test_a_simply_supported_beam_sags_as_the_sine_series(tmp_path, capsys):
    """S2's rod on a pin and a roller under its weight q = rho A g, at rest (start = "static"),
    with exact kinematics on pp1-pp3: mode k carries the uniform load's sine coefficient,
    xi_k = 4 q L^4 / (EI (k pi)^5) for odd k, so w_mid and the constitutive M_mid = EI phi' at
    mid-span are the series truncated after k = 3 (to the exact kinematics' second-order
    terms, (w/L)^2 ~ 4e-9: measured 2e-8), and within the truncation of the closed forms
    5 q L^4 / (384 EI) and q L^2 / 8 (the next term: 1/3125 and 1/125 of the first)."""
    scene = tmp_path / "pin_roller.toml"
    scene.write_text(PIN_ROLLER)
    out = tmp_path / "out.csv"
    assert main(["run", str(scene), "--out", str(out)]) == 0, capsys.readouterr().err
    d = np.genfromtxt(out, delimiter=",", names=True, comments="#")
    q, EI = RHO * A * G, E * I
    terms = [(k, 4 * (-1) ** (k // 2)) for k in (1, 3)]
    w3 = -q * L**4 / EI * sum(c / (k * math.pi) ** 5 for k, c in terms)
    m3 = q * L**2 * sum(c / (k * math.pi) ** 3 for k, c in terms)
    assert np.allclose(d["w_mid"], w3, rtol=1e-7, atol=0)
    assert np.allclose(d["M_mid"], m3, rtol=1e-7, atol=0)
    assert abs(w3 / (-5 * q * L**4 / (384 * EI)) - 1) < 4e-4  # measured 2.7e-4
    assert abs(m3 / (q * L**2 / 8) - 1) < 7e-3  # measured 6.2e-3


def _pendulum(joint_kind="revolute", extra_joint="", extra="", model='["pp1", "pp2"]', body=None):
    section = body or "length = 1.0\ndensity = 2700.0\nyoungs_modulus = 7.0e10\narea = 1.0e-4\ninertia = 2.0833e-10\n"
    axis = 'axis = [1.0, 0.0]\n' if joint_kind == "prismatic" else ""
    return f"""
[system]
name = "pinned_bad"

[[body]]
name = "arm"
kind = "beam"
{section}markers = {{ mid = 0.5 }}
model = {{ strain = "exact", bending = {model} }}

[[joint]]
name = "pin"
kind = "{joint_kind}"
parent = "ground"
point = [0.0, 0.0]
child = "arm.root"
{axis}{extra_joint}
[gravity]
g = [0.0, -9.81]
{extra}
[solver]
t_end = 0.01

[output]
columns = {{ w = "w(arm, mid)" }}
"""


FE_BODY = ("elements = 4\nsegments = [{ length = 1.0, density = 2700.0, youngs_modulus = 7.0e10, "
           "area = 1.0e-4, inertia = 2.0833e-10 }]\n")


@pytest.mark.parametrize("text, says", [
    (_pendulum("clamp"), "body 'arm': bending mode pp1 leaves the root slope free (the frame is the "
                         "chord's), so the root must be pinned, not held by a clamp joint"),
    (_pendulum("prismatic"), "not held by a prismatic joint"),
    (_pendulum("clamp", model='["cf1", "pf2"]'), "bending mode pf2 leaves the root slope free"),
    (_pendulum(extra='\n[[driver]]\nname = "d"\nkind = "guided"\njoint = "pin"\ntheta = "t"\n'),
     "driver 'd' on joint 'pin' would turn the chord"),
    (_pendulum(extra='\n[[driver]]\nname = "m"\nkind = "motor"\njoint = "pin"\ntorque = "1.0"\n'),
     "driver 'm' on joint 'pin'"),
    (_pendulum(extra='\n[[load]]\nkind = "torque"\nbody = "arm"\ntorque = "0.1"\n'),
     "a torque on 'arm' would act on the chord frame"),
    (_pendulum(body=FE_BODY), "bending mode family 'pinned_pinned' is not derived for a body from "
                              "finite-element data"),
], ids=["clamp", "prismatic", "pf", "guided", "motor", "torque", "fedata"])
def test_what_would_hold_the_root_section_is_refused(tmp_path, capsys, text, says):
    scene_text_refused(tmp_path, capsys, text, says)


def test_a_spatial_beam_with_pinned_modes_is_refused(tmp_path, capsys):
    text = (ROOT / "scenes" / "spatial_slider_crank.toml").read_text().replace(
        'model = "m2"', 'model = { strain = "geometric_stiffness", axial = ["static", "sin1"], '
                        'bending = ["pp1", "pp2"] }', 1)
    scene_text_refused(tmp_path, capsys, text, "not derived for spatial systems")


@pytest.mark.parametrize("bending", ["pp1,pp2", "cf1,pf1"])
def test_a_one_beam_model_clamps_its_beam(bending):
    from flexsym.model.variant import builtin, customize

    with pytest.raises(SpecError, match=r"leaves the root slope free \(for a pinned root\), but a "
                                        "one-beam model clamps the beam to its hub"):
        customize(builtin("exact"), bending=bending)


def test_one_beam_refusal_is_one_line(capsys):
    code = main(["run", "exact", "--bending", "pp1,pp2,pp3"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "one-beam model clamps the beam" in err, err


def test_a_fixed_pin_is_a_clamp_and_is_refused():
    """The Python API's `fixed` (no scene key): a pin that does not turn holds the root section."""
    from dataclasses import replace

    from flexsym.model.library import pendulum_system
    from flexsym.model.variant import VariantSpec, _refs

    pp = VariantSpec("body", "exact", (), _refs("bending", ["pp1", "pp2"]), outputs=("M_B",),
                     moment="equilibrium", axial_force="equilibrium")
    system = pendulum_system(pp)  # a free pin: valid
    pin = replace(system.joints[0], fixed=True)
    with pytest.raises(SpecError, match="joint 'pin' is fixed, a clamp"):
        replace(system, joints=(pin,)).validate()
