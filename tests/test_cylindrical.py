"""The cylindrical joint of spatial systems (physics/spatial.axis_motion: a turn theta about the
unit axis a and a slide s along it, the axis fixed in the parent's frame) against closed forms.

 * drop: a rigid body on a vertical cylindrical joint, gravity along the axis, its centre of
   mass off the axis, an initial spin: T = m s'^2/2 + J theta'^2/2 (a . (omega x c) = 0), so
   the slide falls as s0 + v0 t - g t^2/2 and the spin stays (rk4p is exact on both);
 * tilted: the same body on a tilted axis: the slide follows s0 + v0 t + (g.a) t^2/2 while the
   body swings about the axis as a pendulum J theta'' = m g.(a x Rot(a, theta) c) (solved by
   scipy to 1e-13), T + V conserved;
 * bead: a bead on a rod turned at a constant rate W about the vertical (a guided revolute),
   sliding and spinning along the rod: s = s0 cosh(W t) + v0/W sinh(W t), the spin constant
   (an axisymmetric bead: Euler's equation about its axis), rk4p's order 4 on it;
 * coupled: the same with the rod free: T + V and Hz conserved;
 * the assembly at t = 0 closes a loop through a cylindrical joint (both coordinates moved);
 * malformed scenes, each refused in one line naming the file and the item, exit 2.
"""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from system_data import built, run_ok, scene_text_refused, scene_text_runs

G = 9.81
MASS, INERTIA, COM = 2.0, [0.02, 0.03, 0.04], [0.1, 0.05, 0.0]
TH0, W0, S0, V0 = 0.2, 3.0, 0.5, 1.5  # the joint's angle, spin, slide and slide rate at t = 0
HUB = [0.0, 0.0, 1.0]  # the joint's ground point
TIP = np.array([0.3, 0.0, 0.0])  # a marker on the body (body frame)
COLUMNS = {"th": "angle(c)", "w": "rate(c)", "s": "slide(c)", "sd": "slide_rate(c)",
           "x": "x(slider.tip)", "y": "y(slider.tip)", "z": "z(slider.tip)", "T": "T", "V": "V"}


def _slider(name: str, axis) -> dict:
    return {
        "system": {"name": name, "dimension": 3},
        "body": [{"name": "slider", "kind": "rigid", "mass": MASS, "inertia": INERTIA, "com": COM,
                  "markers": {"hole": [0.0, 0.0, 0.0], "tip": [float(v) for v in TIP]}}],
        "joint": [{"name": "c", "kind": "cylindrical", "parent": "ground", "point": HUB,
                   "child": "slider.hole", "axis": [float(v) for v in axis],
                   "initial": {"value": TH0, "rate": W0, "slide": S0, "slide_rate": V0}}],
        "gravity": {"g": [0.0, 0.0, -G]},
        "solver": {"integrator": "rk4p", "dt": 1e-3, "t_end": 1.0},
        "output": {"interval": 0.01, "columns": dict(COLUMNS)},
    }


def _rot(a, angle, v):
    """Rodrigues: v turned by angle about the unit axis a."""
    return v * math.cos(angle) + np.cross(a, v) * math.sin(angle) + a * a.dot(v) * (1 - math.cos(angle))


# ----- drop: the vertical axis
@pytest.fixture(scope="module")
def drop():
    return built(_slider("cyl_drop", [0.0, 0.0, 2.0]))  # not a unit vector: normalised


def test_drop_slides_as_a_free_fall_and_keeps_its_spin(drop):
    """s = s0 + v0 t - g t^2/2 and theta = theta0 + w0 t, the tip at the hub + s e_z + Rot(z,
    theta) tip: rk4p integrates these polynomials exactly, so the errors are round-off (measured
    2.0e-14 m, 7.6e-14 m/s, 0 rad/s, 8.0e-14 rad, tip 2.4e-14 m); T + V against its value at
    t = 0, m v0^2/2 + (Izz + m |c_perp|^2) w0^2/2 + m g z: measured 2.7e-14 relative."""
    r = run_ok(drop, t_end=1.0, dt=1e-3, integrator="rk4p")
    t = r.t
    s = S0 + V0 * t - G * t**2 / 2
    assert np.abs(r["s"] - s).max() < 1e-12
    assert np.abs(r["sd"] - (V0 - G * t)).max() < 1e-12
    assert np.abs(r["w"] - W0).max() < 1e-12
    assert np.abs(r["th"] - (TH0 + W0 * t)).max() < 1e-12
    th = TH0 + W0 * t
    tip = np.column_stack([TIP[0] * np.cos(th), TIP[0] * np.sin(th), HUB[2] + s])
    assert np.abs(np.column_stack([r["x"], r["y"], r["z"]]) - tip).max() < 1e-12
    E = r["T"] + r["V"]
    c_perp2 = COM[0]**2 + COM[1]**2
    E0 = MASS * V0**2 / 2 + (INERTIA[2] + MASS * c_perp2) * W0**2 / 2 + MASS * G * (HUB[2] + S0)
    assert E[0] == pytest.approx(E0, rel=1e-14)
    assert np.abs(E - E0).max() < 1e-12 * abs(E0)


# ----- tilted: the axis across gravity
A_TILT = np.array([1.0, 0.0, 2.0]) / math.sqrt(5.0)


@pytest.fixture(scope="module")
def tilted():
    return built(_slider("cyl_tilted", [1.0, 0.0, 2.0]))


def _pendulum(t):
    """theta(t) of J theta'' = m g.(a x Rot(a, theta) c): V = -m g.Rot(a, theta) c with J the
    inertia about the axis through the joint (a rotation about a keeps it)."""
    c, g = np.array(COM), np.array([0.0, 0.0, -G])
    J = A_TILT @ np.diag(INERTIA) @ A_TILT + MASS * np.cross(A_TILT, c).dot(np.cross(A_TILT, c))

    def f(_, y):
        return [y[1], MASS * g.dot(np.cross(A_TILT, _rot(A_TILT, y[0], c))) / J]
    sol = solve_ivp(f, (0.0, t[-1]), [TH0, W0], t_eval=t, rtol=1e-13, atol=1e-13, method="DOP853")
    return sol.y[0]


def test_tilted_axis_slides_with_gravity_along_it_and_swings_about_it(tilted):
    """The slide is exact again, s0 + v0 t + (g.a) t^2/2 (measured 1.8e-14 m); the angle against
    the pendulum's (measured 4.1e-12 rad at dt = 1e-3, 4.1e-13 at 5e-4: rk4p's error, down to
    the reference's); the tip at hub + s a + Rot(a, theta) tip (measured 8.4e-13 m); T + V
    within 1e-12 relative (measured 5.7e-14)."""
    r = run_ok(tilted, t_end=1.0, dt=1e-3, integrator="rk4p")
    t = r.t
    ga = -G * A_TILT[2]
    s = S0 + V0 * t + ga * t**2 / 2
    assert np.abs(r["s"] - s).max() < 1e-12
    theta = _pendulum(t)
    assert np.abs(r["th"] - theta).max() < 2e-11
    assert abs(r["th"][-1] - (TH0 + W0 * t[-1])) > 0.01  # it does swing: gravity turns it
    tip = np.array([np.array(HUB) + sk * A_TILT + _rot(A_TILT, th, TIP) for sk, th in zip(s, theta)])
    assert np.abs(np.column_stack([r["x"], r["y"], r["z"]]) - tip).max() < 3e-12
    E = r["T"] + r["V"]
    assert np.abs(E - E[0]).max() < 1e-12 * abs(E[0])


def test_the_assembly_places_the_body_as_the_derivation_does(tilted):
    """poses3 (the numeric start, scenes/assembly.py) against the run's first row (the
    generated kinematics of physics/spatial.py): the tip marker at t = 0 (measured 4.4e-16 m),
    both at hub + s0 a + Rot(a, theta0) tip."""
    from flexsym.scenes.assembly import poses3, start3
    from flexsym.scenes.system_scene import system_from_dict

    system = system_from_dict(_slider("cyl_tilted", [1.0, 0.0, 2.0]), name="cyl_tilted")
    A, R = poses3(system, start3(system))["slider"]
    tip0 = np.array((R + A * TIP.reshape(3, 1)).evalf(), dtype=float).ravel()
    r = run_ok(tilted, t_end=0.01, dt=1e-3, integrator="rk4p")
    assert np.abs(np.array([r["x"][0], r["y"][0], r["z"][0]]) - tip0).max() < 1e-14
    expect = np.array(HUB) + S0 * A_TILT + _rot(A_TILT, TH0, TIP)
    assert np.abs(tip0 - expect).max() < 1e-14


# ----- bead: a rod turned at a constant rate, the bead on it sliding and spinning
W_ROD = 2.0
BEAD_I = [0.004, 0.01, 0.01]  # axisymmetric about its x, the rod's axis


def _bead(name: str, guided: bool) -> dict:
    data = {
        "system": {"name": name, "dimension": 3},
        "body": [{"name": "rod", "kind": "rigid", "mass": 1.0, "inertia": [0.001, 0.05, 0.05],
                  "com": [0.3, 0.0, 0.0], "markers": {"pin": [0.0, 0.0, 0.0], "base": [0.0, 0.0, 0.1]}},
                 {"name": "bead", "kind": "rigid", "mass": 0.5, "inertia": BEAD_I, "com": [0.0, 0.0, 0.0],
                  "markers": {"hole": [0.0, 0.0, 0.0], "mark": [0.0, 0.05, 0.0]}}],
        "joint": [{"name": "hub", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0, 0.0],
                   "child": "rod.pin", "axis": [0.0, 0.0, 1.0]},
                  {"name": "c", "kind": "cylindrical", "parent": "rod.base", "child": "bead.hole",
                   "axis": [1.0, 0.0, 0.0], "initial": {"value": 0.0, "rate": 5.0, "slide": 0.1,
                                                         "slide_rate": 0.2}}],
        "gravity": {"g": [0.0, 0.0, -G]},
        "solver": {"integrator": "rk4p", "dt": 1e-3, "t_end": 1.0},
        "output": {"interval": 0.01, "columns": {"th": "angle(c)", "w": "rate(c)", "s": "slide(c)",
                                                 "sd": "slide_rate(c)", "phi": "angle(hub)",
                                                 "z": "z(bead.hole)", "T": "T", "V": "V", "Hz": "Hz"}},
    }
    if guided:
        data["driver"] = [{"name": "turn", "kind": "guided", "joint": "hub", "maneuver": "constant",
                           "omega": W_ROD}]
    else:
        data["joint"][0]["initial"] = {"rate": W_ROD}
    return data


@pytest.fixture(scope="module")
def bead():
    return built(_bead("cyl_bead", guided=True))


def _bead_closed_form(t):
    return 0.1 * np.cosh(W_ROD * t) + 0.2 / W_ROD * np.sinh(W_ROD * t)


def test_bead_on_a_turning_rod(bead):
    """s'' = W^2 s on the rod (gravity across it), s = s0 cosh(W t) + v0/W sinh(W t): measured
    2.0e-13 m at dt = 1e-3 (s = 0.74 m at t = 1 s); the spin about the rod stays 5 rad/s (its
    axisymmetric inertia: no torque about the axis; measured 0) and the bead stays at the
    rod's height (0.1 m)."""
    r = run_ok(bead, t_end=1.0, dt=1e-3, integrator="rk4p")
    assert np.abs(r["s"] - _bead_closed_form(r.t)).max() < 1e-12
    assert np.abs(r["w"] - 5.0).max() < 1e-12
    assert np.abs(r["phi"] - W_ROD * r.t).max() < 1e-13
    assert np.abs(r["z"] - 0.1).max() < 1e-13


def test_rk4p_is_of_order_4_on_the_bead(bead):
    """The error at t = 1 s against the closed form falls by 2^4 per halving of the step
    (measured: 3.0e-8, 1.9e-9, 1.2e-10 m at dt = 0.02, 0.01, 0.005 s: orders 3.98, 3.99)."""
    errors = []
    for dt in (0.02, 0.01, 0.005):
        r = run_ok(bead, t_end=1.0, dt=dt, integrator="rk4p")
        errors.append(abs(r["s"][-1] - _bead_closed_form(r.t[-1:])[0]))
    orders = [math.log2(a / b) for a, b in zip(errors, errors[1:])]
    assert all(3.8 < p < 4.2 for p in orders), (errors, orders)


@pytest.fixture(scope="module")
def coupled():
    return built(_bead("cyl_coupled", guided=False))


def test_free_rod_and_bead_conserve_energy_and_momentum(coupled):
    """The rod free: the bead sliding out slows it (Hz = (I_rod + m s^2 + ...) W), nothing acts
    about z, nothing dissipates: T + V and Hz within 1e-12 relative (measured 4.1e-15,
    3.5e-14), and the rod does slow down (turned 1.59 rad in 1 s, not 2)."""
    r = run_ok(coupled, t_end=1.0, dt=1e-3, integrator="rk4p")
    E = r["T"] + r["V"]
    assert np.abs(E - E[0]).max() < 1e-12 * abs(E[0])
    assert np.abs(r["Hz"] - r["Hz"][0]).max() < 1e-12 * abs(r["Hz"][0])
    assert r["phi"][-1] < 0.9 * W_ROD * r.t[-1]
    assert np.abs(r["w"] - 5.0).max() < 1e-12  # the spin: still no torque about the rod


# ----- the assembly at t = 0 moves both coordinates to close a loop
def cylinder_loop(post: dict, drivers=()) -> dict:
    """A body on a vertical cylindrical joint whose marker at 0.5 m on its x meets (a spherical
    cut joint) the point (0, 0.5, 0.3) of a post held by the joint `post` (to its base)."""
    return {"system": {"name": "cyl_loop", "dimension": 3},
            "body": [{"name": "arm", "kind": "rigid", "mass": 1.0, "inertia": [0.01, 0.01, 0.01],
                      "markers": {"hole": [0.0, 0.0, 0.0], "end": [0.5, 0.0, 0.0]}},
                     {"name": "post", "kind": "rigid", "mass": 1.0, "inertia": [0.01, 0.01, 0.01],
                      "markers": {"base": [0.0, 0.0, 0.0], "top": [0.0, 0.5, 0.3]}}],
            "joint": [{"name": "c", "kind": "cylindrical", "parent": "ground", "point": [0.0, 0.0, 0.0],
                       "child": "arm.hole", "axis": [0.0, 0.0, 1.0],
                       "initial": {"value": 1.2, "slide": 0.1}},
                      dict(post, parent="ground", point=[0.0, 0.0, 0.0], child="post.base"),
                      {"name": "ball", "kind": "spherical", "parent": "post.top", "child": "arm.end"}],
            "driver": list(drivers),
            "output": {"columns": {"s": "slide(c)"}}}


def test_assembly_closes_a_loop_through_a_cylindrical_joint():
    """The post clamped to ground: theta = pi/2, s = 0.3."""
    from flexsym.scenes.system_scene import checked_system, system_from_data

    system, _, _ = system_from_data(cylinder_loop({"name": "fix", "kind": "clamp"}), "", "cyl_loop")
    assembled, report = checked_system(system)
    j = assembled.joint("c")
    assert j.initial == pytest.approx(math.pi / 2, abs=1e-12) and j.slide == pytest.approx(0.3, abs=1e-12)
    assert "joint c slide moved" in report.line()


# ----- malformed scenes
GOOD = '''[system]
name = "cyl"
dimension = 3

[[body]]
name = "slider"
kind = "rigid"
mass = 2.0
inertia = [0.02, 0.03, 0.04]
markers = { hole = [0.0, 0.0, 0.0], end = [0.5, 0.0, 0.0] }

[[body]]
name = "arm"
kind = "rigid"
mass = 1.0
inertia = [0.01, 0.01, 0.01]
markers = { pin = [0.0, 0.0, 0.0] }

[[joint]]
name = "c"
kind = "cylindrical"
parent = "ground"
point = [0.0, 0.0, 1.0]
child = "slider.hole"
axis = [0.0, 0.0, 1.0]
initial = { value = 0.2, rate = 3.0, slide = 0.5, slide_rate = 1.5 }

[[joint]]
name = "hinge"
kind = "revolute"
parent = "slider.end"
child = "arm.pin"
axis = [0.0, 1.0, 0.0]

[gravity]
g = [0.0, 0.0, -9.81]

[solver]
t_end = 0.01

[output]
columns = { s = "slide(c)", w = "rate(c)" }
'''
PLANAR = (GOOD.replace("dimension = 3", "dimension = 2").replace("[0.02, 0.03, 0.04]", "0.02")
          .replace("[0.01, 0.01, 0.01]", "0.01").replace("[0.0, 0.0, 1.0]", "[0.0, 1.0]")
          .replace("[0.0, 1.0, 0.0]", "[0.0, 1.0]").replace("[0.0, 0.0, 0.0]", "[0.0, 0.0]")
          .replace("[0.5, 0.0, 0.0]", "[0.5, 0.0]").replace("[0.0, 0.0, -9.81]", "[0.0, -9.81]")
          .replace('\naxis = [0.0, 1.0]\n\n[gravity]', '\n\n[gravity]'))
LOOP = GOOD.replace('''child = "arm.pin"
axis = [0.0, 1.0, 0.0]
''', '''child = "arm.pin"
axis = [0.0, 1.0, 0.0]

[[joint]]
name = "closing"
kind = "cylindrical"
parent = "ground"
point = [0.5, 0.0, 1.5]
child = "slider.end"
axis = [0.0, 0.0, 1.0]
''')
BAD = [  # (what, scene text, what the one line says)
    ("axis of zero length", GOOD.replace("axis = [0.0, 0.0, 1.0]", "axis = [0.0, 0.0, 0.0]"),
     "joint 'c': a cylindrical joint needs an axis (three finite numbers, not all 0)"),
    ("no axis", GOOD.replace("axis = [0.0, 0.0, 1.0]\n", ""),
     "joint 'c': a cylindrical joint needs an axis (three finite numbers, not all 0)"),
    ("in a planar system", PLANAR,
     "joint 'c': a cylindrical joint applies to spatial systems (dimension = 3) only"),
    ("closing a loop the given rates cannot keep", LOOP,  # a closing cylindrical is derived
     "the joints' rates at t = 0 cannot satisfy the loops: c are given"),  # (test_spatial_cuts.py)
    # drivers on it: tests/test_spatial_cuts.py (a guided slide, a motor on the turn)
    ("a guided driver on its turn, its rate given", GOOD + '\n[[driver]]\nname = "d"\nkind = "guided"\njoint = "c"\n'
     'maneuver = "constant"\nomega = 1.0\n',
     "driver 'd': joint 'c' is guided: its coordinate and rate at t = 0 are the driver's"),
    ("a torque on its slide", GOOD + '\n[[driver]]\nname = "d"\nkind = "motor"\njoint = "c"\ncoordinate = "slide"\n'
     'torque = "0.1"\n', "a motor on slide of the cylindrical joint 'c' gives a force (write force = \"...\")"),
    ("a driver on its second angle", GOOD + '\n[[driver]]\nname = "d"\nkind = "motor"\njoint = "c"\n'
     'coordinate = "angle2"\ntorque = "0.1"\n',
     "driver 'd': joint 'c' (cylindrical) has no coordinate 'angle2' (its coordinates: 'c', 'c_slide'; "
     "coordinate = \"slide\" drives its second, none its first)"),
    ("slide of a revolute joint", GOOD.replace('s = "slide(c)"', 's = "slide(hinge)"'),
     "output 'slide(hinge)': slide(J) is a cylindrical joint's slide, and 'hinge' is a revolute joint"),
    ("an unknown coordinate function", GOOD.replace('s = "slide(c)"', 's = "slide_velocity(c)"'),
     "output 'slide_velocity(c)': unknown function 'slide_velocity'"),
    ("a slide on a revolute joint", GOOD.replace('axis = [0.0, 1.0, 0.0]', 'axis = [0.0, 1.0, 0.0]\n'
                                                  'initial = { value = 0.1, slide = 0.2 }'),
     "[[joint]] 'hinge' initial slide: unknown key"),
    ("a non-finite slide rate", GOOD.replace("slide_rate = 1.5", "slide_rate = nan"),
     "[[joint]] 'c' initial slide_rate: must be a finite number"),
    ("an output column named after the slide", GOOD.replace('w = "rate(c)"', 'c_slide = "rate(c)"'),
     "output column 'c_slide' is already the name of the slide of joint 'c'"),
]


def test_the_good_scene_runs(tmp_path, capsys):
    """The malformed scenes' base runs (so each refusal below is its edit's)."""
    scene_text_runs(tmp_path, capsys, GOOD)


@pytest.mark.parametrize("what,text,says", BAD, ids=[b[0] for b in BAD])
def test_bad_cylindrical_scenes_are_refused(tmp_path, capsys, what, text, says):
    """Refused in one line naming the file and the item, exit 2, nothing written."""
    assert text != GOOD, what
    scene_text_refused(tmp_path, capsys, text, says)
