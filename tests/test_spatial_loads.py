"""Loads of spatial systems beyond gravity and point forces.

Spring-dampers (the planar grammar's `kind = "spring"`, the same V and Q as in the plane,
flexsym/physics/assemble.add_spring): a slider on a tilted axis against its closed form, and a
flexible strip pulled by a spring at its tip, whose equilibrium section moments take the
spring force. Torques (three expressions, in the ground's or the body's axes): a body spun
about a tilted revolute axis and about its own axis on a ball joint, against closed forms."""
import numpy as np
import pytest
import sympy as sp

from flexsym.scenes.system_scene import system_from_dict
from system_data import built, run_ok

AXIS = np.array([1.0, 2.0, 2.0]) / 3.0  # unit
M, K, C, G = 0.5, 200.0, 0.8, 9.81
ANCHOR = [0.3, -0.2, 0.4]  # the spring's fixed end (a marker on a body clamped to ground)


def _slider(c: float, l0: float) -> dict:
    return {
        "system": {"name": f"spring_slider_{'damped' if c else 'free'}{'_l0' if l0 else ''}", "dimension": 3},
        "body": [{"name": "base", "kind": "rigid", "mass": 1.0, "inertia": [1.0, 1.0, 1.0],
                  "markers": {"o": [0.0, 0.0, 0.0], "anchor": ANCHOR}},
                 {"name": "mass", "kind": "rigid", "mass": M, "inertia": [1e-3, 1e-3, 1e-3],
                  "markers": {"pin": [0.0, 0.0, 0.0]}}],
        "joint": [{"name": "fix", "kind": "clamp", "parent": "ground", "point": [0.0, 0.0, 0.0], "child": "base.o"},
                  {"name": "slide", "kind": "prismatic", "parent": "ground", "point": [0.0, 0.0, 0.0],
                   "axis": AXIS.tolist(), "child": "mass.pin", "initial": 0.1}],
        "load": [{"kind": "spring", "name": "s", "a": "base.anchor", "b": "mass.pin", "k": K, "c": c, "l0": l0}],
        "gravity": {"g": [0.0, 0.0, -G]},
        "solver": {"integrator": "rk4", "t_end": 1.0},
        "output": {"interval": 0.001, "columns": {"x": "angle(slide)", "T": "T", "V": "V"}},
    }


def test_spring_on_a_tilted_slider_is_the_damped_oscillator():
    """l0 = 0: the spring pulls with -k (r - anchor) - c r', whose part along the axis gives
    m x'' + c x' + k (x - x_eq) = 0 with x_eq = anchor.a + m g.a / k: the closed form of the
    underdamped oscillator, matched by rk4 at dt = 1e-4 to 1e-10 of the amplitude (measured
    1.1e-12); with c = 0 and l0 > 0 (a nonlinear spring), T + V stays constant (measured
    4.5e-14 of V's range)."""
    r = run_ok(built(_slider(C, 0.0)), integrator="rk4", dt=1e-4, t_end=1.0)
    x_eq = np.dot(ANCHOR, AXIS) + M * np.dot([0.0, 0.0, -G], AXIS) / K
    wn, zeta = np.sqrt(K / M), C / (2 * np.sqrt(K * M))
    wd = wn * np.sqrt(1 - zeta**2)
    a0 = 0.1 - x_eq
    t = r.t
    want = x_eq + np.exp(-zeta * wn * t) * (a0 * np.cos(wd * t) + zeta * wn * a0 / wd * np.sin(wd * t))
    assert np.abs(r["x"] - want).max() < 1e-10 * abs(a0), np.abs(r["x"] - want).max()
    r = run_ok(built(_slider(0.0, 0.25)), integrator="rk4", dt=1e-4, t_end=1.0)
    E = r["T"] + r["V"]
    assert np.ptp(E) < 1e-11 * np.ptp(r["V"]) and np.ptp(r["V"]) > 0.1, (np.ptp(E), np.ptp(r["V"]))


def _strip_on_a_spring() -> dict:
    """An aluminium strip clamped to ground along x, its tip pulled by a spring towards an
    anchor below and beside it; no gravity; started in static equilibrium."""
    return {
        "system": {"name": "strip_spring", "dimension": 3, "start": "static"},
        "body": [{"name": "base", "kind": "rigid", "mass": 1.0, "inertia": [1.0, 1.0, 1.0],
                  "markers": {"o": [0.0, 0.0, 0.0], "anchor": [0.9, 0.03, -0.05]}},
                 {"name": "strip", "kind": "beam", "length": 1.0, "density": 2700.0,
                  "youngs_modulus": 7.0e10, "shear_modulus": 2.6e10, "area": 1.0e-4,
                  "inertia_z": 3.3333e-9, "inertia_y": 2.0833e-10, "torsion_constant": 7.021e-10,
                  "model": "m3", "markers": {"tip": 1.0}}],
        "joint": [{"name": "fix", "kind": "clamp", "parent": "ground", "point": [0.0, 0.0, 0.0], "child": "base.o"},
                  {"name": "root", "kind": "clamp", "parent": "base.o", "child": "strip.root"}],
        "load": [{"kind": "spring", "name": "s", "a": "base.anchor", "b": "strip.tip", "k": 50.0, "l0": 0.0}],
        "gravity": {"g": [0.0, 0.0, 0.0]},
        "output": {"interval": 0.001, "columns": {
            "x": "x(strip.tip)", "y": "y(strip.tip)", "z": "z(strip.tip)", "N": "N(strip, root)",
            "My": "My(strip, root)", "Mz": "Mz(strip, root)", "N_mid": "N(strip, 0.5)",
            "My_mid": "My(strip, 0.5)"}},
    }


def test_spring_on_a_beam_enters_its_equilibrium_section_forces():
    """Started in static equilibrium and left alone, the strip stays there, and its section
    forces from equilibrium are the spring's force and moment about the section: at the root
    (clamped, so the section's axes are the ground's) N = F_x, My = [(r_tip - r_root) x F]_y,
    Mz = [...]_z, with F = k (anchor - r_tip) from the run's own tip position (measured: 2e-15
    of the moment; without the spring's term in the equilibrium, N is off by 5 N)."""
    data = _strip_on_a_spring()
    r = run_ok(built(data), integrator="genalpha", dt=1e-4, t_end=0.01)
    tip = np.array([r["x"][0], r["y"][0], r["z"][0]])
    F = 50.0 * (np.array([0.9, 0.03, -0.05]) - tip)
    moment = np.cross(tip, F)
    assert abs(tip[2]) > 0.01  # the spring bends the strip
    for col, want in (("N", F[0]), ("My", moment[1]), ("Mz", moment[2])):
        assert abs(r[col][0] - want) <= 1e-9 * np.abs(moment).max(), (col, r[col][0], want)
    for col in ("x", "y", "z", "My"):
        assert np.ptp(r[col]) <= 1e-9 * np.abs(r[col]).max(), col  # at rest


def test_a_ground_end_needs_a_point_in_space():
    """In Python a spring may end on ground at point_a/point_b: in 3D that point has three
    numbers (the planar default (0, 0) is refused, not padded)."""
    from dataclasses import replace

    from flexsym.core.errors import SpecError
    from flexsym.model.system import GROUND, SpringDamper

    system = system_from_dict(_slider(0.0, 0.0), name="s")
    ok = replace(system, loads=system.loads[:1] + (SpringDamper(GROUND, "mass.pin", 1.0, point_a=(0.0, 0.0, 1.0)),))
    ok.validate()
    bad = replace(system, loads=system.loads[:1] + (SpringDamper(GROUND, "mass.pin", 1.0),))
    with pytest.raises(SpecError, match=r"point_a \(0.0, 0.0\) \(its ground end\) must be three finite numbers"):
        bad.validate()


I_BODY = [0.2, 0.5, 0.6]  # principal moments (body axes = ground axes at t = 0)


def _torqued(joint: dict, torque: list, frame: str, name: str) -> dict:
    return {
        "system": {"name": name, "dimension": 3},
        "body": [{"name": "wheel", "kind": "rigid", "mass": 3.0, "inertia": I_BODY,
                  "markers": {"c": [0.0, 0.0, 0.0], "rim": [0.0, 0.4, 0.0]}}],
        "joint": [joint | {"name": "j", "parent": "ground", "point": [0.0, 0.0, 0.0], "child": "wheel.c"}],
        "load": [{"kind": "torque", "body": "wheel", "torque": torque, "frame": frame}],
        "gravity": {"g": [0.0, 0.0, 0.0]},
        "output": {"interval": 0.01, "columns": {"y": "y(wheel.rim)", "z": "z(wheel.rim)", "T": "T"}},
    }


def test_torque_about_a_tilted_revolute_axis_and_in_the_body_axes():
    """(1) A ground torque tau = (2, -1, 3*sin(t)) on a body turning about the unit axis a =
    (1, 2, 2)/3 through its centre: theta'' = tau.a / (a.I.a) (a.I.a is constant: the body
    turns about a), integrated in closed form; T = int tau.a theta' dt checks the power.
    (2) A body-axes torque (0.3 t, 0, 0) on a ball joint at the centre, from rest: it spins
    about its own x axis only (no gyroscopic moment), alpha = 0.05 t^3 / I_xx, so the rim
    marker at (0, 0.4, 0) is at 0.4 (cos alpha, sin alpha) in y, z. rk4 (rk4p) at 1 ms:
    measured 4.5e-15 m (T: 1.3e-14) and 2e-13 m."""
    a = np.array([1.0, 2.0, 2.0]) / 3
    r = run_ok(built(_torqued({"kind": "revolute", "axis": a.tolist()}, ["2.0", "-1.0", "3*sin(t)"], "ground",
                             "torque_axis")), integrator="rk4", dt=1e-3, t_end=2.0)
    Ia = float(a @ np.diag(I_BODY) @ a)
    t = r.t
    theta = (2 * a[0] - a[1]) * t**2 / 2 + 3 * a[2] * (t - np.sin(t))  # double integral of tau.a
    theta /= Ia
    rim = np.array([0.0, 0.4, 0.0])  # turned about a by theta (Rodrigues)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    want = np.array([(np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K) @ rim for th in theta])
    err = max(np.abs(r["y"] - want[:, 1]).max(), np.abs(r["z"] - want[:, 2]).max())
    assert err < 1e-10, err
    rate = ((2 * a[0] - a[1]) * t + 3 * a[2] * (1 - np.cos(t))) / Ia
    assert np.abs(r["T"] - Ia * rate**2 / 2).max() < 1e-9 * (Ia * rate**2 / 2).max()

    r = run_ok(built(_torqued({"kind": "spherical"}, ["0.3*t", "0.0", "0.0"], "body", "torque_ball")),
             integrator="rk4p", dt=1e-3, t_end=2.0)
    alpha = 0.05 * r.t**3 / I_BODY[0]
    assert np.abs(r["y"] - 0.4 * np.cos(alpha)).max() < 1e-10
    assert np.abs(r["z"] - 0.4 * np.sin(alpha)).max() < 1e-10


TORQUE_SCENE = """[system]
name = "bad_torque"
dimension = 3

[[body]]
name = "wheel"
kind = "rigid"
mass = 3.0
inertia = [0.2, 0.5, 0.6]
markers = { c = [0.0, 0.0, 0.0] }

[[joint]]
name = "j"
kind = "spherical"
parent = "ground"
point = [0.0, 0.0, 0.0]
child = "wheel.c"

[[load]]
kind = "torque"
body = "wheel"
torque = ["0.3*t", "0.0", "0.0"]
frame = "body"

[gravity]
g = [0.0, 0.0, 0.0]

[output]
columns = { T = "T" }
"""


@pytest.mark.parametrize("edit,says", [
    (('torque = ["0.3*t", "0.0", "0.0"]', 'torque = ["1.0", "2.0"]'),
     'torque: must be three expressions ["tx", "ty", "tz"]'),
    (('torque = ["0.3*t", "0.0", "0.0"]', 'torque = "0.3*t"'), 'torque: must be three expressions'),
    (('frame = "body"', 'frame = "wheel"'), "frame 'wheel' must be 'ground' or 'body'"),
    (('torque = ["0.3*t", "0.0", "0.0"]', 'torque = ["1.0", "", "0.0"]'), "empty torque expression"),
    (('torque = ["0.3*t", "0.0", "0.0"]', 'torque = ["1.0", "q_unknown", "0.0"]'), "the name 'q_unknown' is not allowed"),
])
def test_bad_spatial_torques_are_refused_in_one_line(tmp_path, capsys, edit, says):
    from flexsym.apps.cli import main

    assert TORQUE_SCENE.count(edit[0]) == 1
    scene, out = tmp_path / "bad.toml", tmp_path / "out.csv"
    scene.write_text(TORQUE_SCENE.replace(edit[0], edit[1]))
    assert main(["run", str(scene), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(scene) in err and says in err, err
    assert not out.exists()


def test_a_torque_on_a_beam_acts_on_its_frame():
    """A torque on a beam acts on its floating frame (its root section, as in the plane): on a
    strip on a revolute joint about z, tau_z = 2 t gives the generalised forces of a motor of
    2 t on the joint, and a torque about the frame's x (body axes) none at all (the pin takes
    it); the section forces beyond the root do not see it (derivation only)."""
    from flexsym.physics.spatial import derive_spatial

    data = _strip_on_a_spring()
    data["system"]["start"] = "undeformed"
    data["body"] = data["body"][1:]
    data["body"][0]["model"] = {"strain": "linear", "axial": [], "bending": ["cf1"]}
    data["joint"] = [{"name": "pin", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0, 0.0],
                      "axis": [0.0, 0.0, 1.0], "child": "strip.root"}]
    data["output"]["columns"] = {"My_mid": "My(strip, 0.5)", "Mz_mid": "Mz(strip, 0.5)"}
    loads = {"motor": [], "torque": [{"kind": "torque", "body": "strip", "torque": ["0.0", "0.0", "2*t"]}],
             "twist": [{"kind": "torque", "body": "strip", "torque": ["5.0", "0.0", "0.0"], "frame": "body"}],
             "none": []}
    der = {}
    for case, load in loads.items():
        d = dict(data, load=load, driver=[{"name": "m", "kind": "motor", "joint": "pin", "torque": "2*t"}]
                 if case == "motor" else [])
        d["system"] = dict(data["system"], name=f"beam_torque_{case}")
        der[case] = derive_spatial(system_from_dict(d, name=d["system"]["name"]))
    assert sp.simplify(der["torque"].Q - der["motor"].Q) == sp.zeros(len(der["motor"].Q), 1)
    assert sp.simplify(der["twist"].Q - der["none"].Q) == sp.zeros(len(der["none"].Q), 1)
    for col in ("My_mid", "Mz_mid"):
        assert sp.simplify(der["torque"].outputs[col] - der["none"].outputs[col]) == 0
