"""The universal (Hooke, Cardan) joint in a spatial tree (Joint.coordinates, assembly.joint_motion:
two turns in series, theta1 about parent_axis a1 in the parent's frame, then theta2 about axis
a2 in the child's: Q = Rot(a1, theta1) Rot(a2, theta2), omega_c = Q^T omega_p + Rot(a2,
theta2)^T a1 theta1' + a2 theta2') against what does not come from that kinematics:

 * pendulum: a rigid body hung from a universal joint under gravity: T + V conserved, rk4p of
   order 4 on it; small swings about each arm at sqrt(m g l / I_pivot) about that arm; the
   joint's reaction moment (the subtree's momentum balance) has no component along either arm
   of the cross (it transmits no torque about them); the start's poses (poses3) as derived;
 * cardan: an input shaft turned at a constant rate drives, through the joint, an output shaft
   bent by beta whose direction a ball joint on its axis holds (the loop closed by a collar
   sliding along the output's axis): the output angle follows tan phi2 = tan phi1 / cos beta and
   its rate omega1 cos beta / (1 - sin^2 beta cos^2 phi1); the assembly at t = 0 places the
   output and sets the joint's rates (the velocity analysis through a tree universal joint);
 * a universal joint between two moving bodies: T + V and Hz conserved, and its C kernels
   against casadi against sympy;
 * malformed scenes, each refused in one line naming the file and the item, exit 2.
"""
import math

import numpy as np
import pytest

from flexsym.scenes.system_scene import system_from_dict
from system_data import built, derivation, edited_scene, refused_in_one_line, run_ok, scene_text_refused, scene_text_runs
from test_spatial import PLANAR, S7, CARDAN_AXIS

G = 9.81
MASS, ELL, INERTIA = 2.0, 0.5, [0.1, 0.3, 0.25]  # the bob: mass, com below the pin, principal moments
A1, A2 = [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]  # the cross: parent_axis (ground's x), axis (bob's y)
TIP = np.array([0.1, 0.05, -0.6])  # a marker on the bob (bob frame)


def _rot(axis, angle):
    """Rodrigues: the rotation by angle about the unit axis."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def _pendulum(name: str, start: dict) -> dict:
    return {
        "system": {"name": name, "dimension": 3},
        "body": [{"name": "bob", "kind": "rigid", "mass": MASS, "inertia": INERTIA, "com": [0.0, 0.0, -ELL],
                  "markers": {"pin": [0.0, 0.0, 0.0], "tip": [float(v) for v in TIP]}}],
        "joint": [{"name": "u", "kind": "universal", "parent": "ground", "point": [0.0, 0.0, 1.0],
                   "child": "bob.pin", "parent_axis": A1, "axis": A2, "initial": start}],
        "gravity": {"g": [0.0, 0.0, -G]},
        "solver": {"integrator": "rk4p", "dt": 1e-3, "t_end": 1.0},
        "output": {"interval": 0.01, "columns": {
            "th1": "angle(u)", "th2": "angle2(u)", "w1": "rate(u)", "w2": "rate2(u)", "T": "T", "V": "V",
            "x": "x(bob.tip)", "y": "y(bob.tip)", "z": "z(bob.tip)",
            "Mx": "reaction(u, mx)", "My": "reaction(u, my)", "Mz": "reaction(u, mz)",
            "Axy": "R(bob.pin, x, y)", "Ayy": "R(bob.pin, y, y)", "Azy": "R(bob.pin, z, y)"}},
    }


SWING = {"value": 0.8, "rate": 1.0, "angle2": -0.5, "rate2": 2.0}  # a large 2D swing


@pytest.fixture(scope="module")
def swinging():
    return built(_pendulum("uj_swing", SWING))


def test_the_swing_conserves_energy_at_rk4ps_order(swinging):
    """T + V over 2 s of a large swing about both arms: its drift falls by 2^4 per halving of the
    step (measured 1.2e-8, 6.6e-10, 3.9e-11 relative at dt = 0.01, 0.005, 0.0025 s: orders 4.16,
    4.09, nearing 4 from 4.4 at 0.04 s) and is within 1e-10 at dt = 1e-3 (measured 9.6e-13)."""
    drifts = []
    for dt in (0.01, 0.005, 0.0025, 0.001):
        r = run_ok(swinging, t_end=2.0, dt=dt, integrator="rk4p")
        E = r["T"] + r["V"]
        drifts.append(np.abs(E - E[0]).max() / abs(E[0]))
    orders = [math.log2(a / b) for a, b in zip(drifts[:2], drifts[1:3])]
    assert all(3.8 < p < 4.3 for p in orders), (drifts, orders)
    assert drifts[-1] < 1e-10, drifts


def test_the_cross_transmits_no_torque_about_its_arms(swinging):
    """The joint's reaction moment about the pin (physics/spatial.joint_reaction: the bob's
    momentum balance, nothing of the joint's kinematics) along the arm a1 (ground's x) and the
    arm a2 (the bob's y, R(bob.pin, ., y)): zero to round-off (measured 2.7e-15 and 3.1e-15 N m
    of a 3.6 N m peak, which is across both)."""
    r = run_ok(swinging, t_end=2.0, dt=1e-3, integrator="rk4p")
    M = np.column_stack([r["Mx"], r["My"], r["Mz"]])
    a2 = np.column_stack([r["Axy"], r["Ayy"], r["Azy"]])
    peak = np.abs(M).max()
    assert peak > 1.0
    assert np.abs(M[:, 0]).max() < 1e-12 * peak
    assert np.abs(np.sum(M * a2, axis=1)).max() < 1e-12 * peak


def test_the_start_places_the_bob_as_the_derivation_does(swinging):
    """poses3 (the numeric start, scenes/assembly.py) against the run's first row (the generated
    kinematics of physics/spatial.py) and against Rot(a1, theta1) Rot(a2, theta2): the tip at
    t = 0 (measured 1.1e-16 m and 5.6e-17 m)."""
    from flexsym.scenes.assembly import poses3, start3

    system = system_from_dict(_pendulum("uj_swing", SWING), name="uj_swing")
    A, R = poses3(system, start3(system))["bob"]
    tip0 = np.array((R + A * TIP.reshape(3, 1)).evalf(), dtype=float).ravel()
    r = run_ok(swinging, t_end=0.01, dt=1e-3, integrator="rk4p")
    assert np.abs(np.array([r["x"][0], r["y"][0], r["z"][0]]) - tip0).max() < 1e-14
    expect = np.array([0.0, 0.0, 1.0]) + _rot(A1, SWING["value"]) @ _rot(A2, SWING["angle2"]) @ TIP
    assert np.abs(tip0 - expect).max() < 1e-14
    assert r["w1"][0] == SWING["rate"] and r["w2"][0] == SWING["rate2"]


def _frequency(t, x):
    """The mean angular frequency between the first and the last upward zero crossing."""
    k = np.nonzero((x[:-1] < 0) & (x[1:] >= 0))[0]
    up = t[k] - x[k] * (t[k + 1] - t[k]) / (x[k + 1] - x[k])
    return 2 * math.pi * (len(up) - 1) / (up[-1] - up[0])


def test_small_swings_about_each_arm():
    """Started 1e-3 rad off about both arms at rest: each angle swings at sqrt(m g l / I) with I
    the bob's moment about that arm through the pin, I_xx + m l^2 (4.04 rad/s) and I_yy + m l^2
    (3.50 rad/s); measured -3.9e-8 and -4.1e-8 relative over 20 s (the amplitude's own shift,
    -a^2/16, is -6e-8)."""
    r = run_ok(built(_pendulum("uj_small", {"value": 1e-3, "angle2": 1e-3})), t_end=20.0, dt=1e-3,
               integrator="rk4p", interval=1e-3)
    for col, I in (("th1", INERTIA[0]), ("th2", INERTIA[1])):
        want = math.sqrt(MASS * G * ELL / (I + MASS * ELL**2))
        assert abs(_frequency(r.t, r[col]) / want - 1) < 1e-6, col


# ----- cardan: the velocity ratio of a Hooke joint
BETA, W1, D, FORK = math.radians(30.0), 2.0, 0.4, 0.2  # bend, input rate, ball's distance, fork
N_OUT = [math.cos(BETA), 0.0, -math.sin(BETA)]  # the output's axis: x turned by beta about y
CARDAN_COLUMNS = {"th1": "angle(u)", "th2": "angle2(u)", "w1": "rate(u)", "w2": "rate2(u)",
                  "phi": "angle(input)", "s": "angle(guide)", "viol": "violation",
                  "Axy": "R(outshaft.m, x, y)", "Ayy": "R(outshaft.m, y, y)", "Azy": "R(outshaft.m, z, y)"}


def cardan(guess: float = 0.3) -> dict:
    """The input shaft turns about ground's x at W1 (a guided revolute); its fork at x = FORK
    carries the cross's arm a1 = z, the output shaft's its arm a2 = y (both shafts' frames start
    parallel, their axes along their x). The ball joint `ball` ties the output's point at D on
    its axis to a collar sliding along N_OUT through the cross's centre: the output's axis stays
    N_OUT (the collar's slide takes the sphere's radius, so the ball's three rows are
    independent). theta2 starts at the guess, the assembly moves it to beta."""
    return {
        "system": {"name": "cardan", "dimension": 3},
        "body": [{"name": "inshaft", "kind": "rigid", "mass": 1.0, "inertia": [0.002, 0.01, 0.01],
                  "com": [0.1, 0.0, 0.0], "markers": {"o": [0.0, 0.0, 0.0], "fork": [FORK, 0.0, 0.0]}},
                 {"name": "outshaft", "kind": "rigid", "mass": 1.0, "inertia": [0.002, 0.01, 0.01],
                  "com": [0.2, 0.0, 0.0], "markers": {"m": [0.0, 0.0, 0.0], "end": [D, 0.0, 0.0]}},
                 {"name": "collar", "kind": "rigid", "mass": 0.5, "inertia": [0.001, 0.001, 0.001],
                  "markers": {"c": [0.0, 0.0, 0.0]}}],
        "joint": [{"name": "input", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0, 0.0],
                   "child": "inshaft.o", "axis": [1.0, 0.0, 0.0]},
                  {"name": "u", "kind": "universal", "parent": "inshaft.fork", "child": "outshaft.m",
                   "parent_axis": [0.0, 0.0, 1.0], "axis": [0.0, 1.0, 0.0], "initial": {"angle2": guess}},
                  {"name": "guide", "kind": "prismatic", "parent": "ground", "point": [FORK, 0.0, 0.0],
                   "child": "collar.c", "axis": N_OUT, "initial": 0.3},
                  {"name": "ball", "kind": "spherical", "parent": "outshaft.end", "child": "collar.c"}],
        "driver": [{"name": "drive", "kind": "guided", "joint": "input", "maneuver": "constant", "omega": W1}],
        "solver": {"integrator": "rk4p", "dt": 1e-3, "t_end": 1.0},
        "output": {"interval": 0.01, "columns": dict(CARDAN_COLUMNS)},
    }


def test_the_assembly_bends_the_output_and_sets_the_joints_rates():
    """Positions: theta2 moves from its guess to beta, the collar to D, theta1 stays 0 (to
    1e-15; measured 1.1e-16); velocities (rates3 through the tree universal joint): the output
    turns about N_OUT at W1 / cos beta, so theta1' = -W1 tan beta (measured 4.4e-16) and
    theta2' = 0, in the report."""
    from flexsym.scenes.system_scene import checked_system, system_from_data

    system, _, _ = system_from_data(cardan(), "", "cardan")
    assembled, report = checked_system(system)
    u, guide = assembled.joint("u"), assembled.joint("guide")
    assert abs(u.angle2 - BETA) < 1e-15 and abs(u.initial) < 1e-15 and abs(guide.initial - D) < 1e-15
    assert abs(u.rate + W1 * math.tan(BETA)) < 1e-14 and abs(u.rate2 or 0.0) < 1e-14
    assert "joint u angle2 moved" in report.line() and "joint u rate set to" in report.line()


def _output_rate(r) -> np.ndarray:
    """The output shaft's angular velocity about its axis (its x) from the joint's coordinates
    and rates: Q^T (W1 e_x) + Rot(a2, theta2)^T a1 theta1' + a2 theta2', x component."""
    out = []
    for th1, th2, w1, w2 in zip(r["th1"], r["th2"], r["w1"], r["w2"]):
        R2 = _rot([0, 1, 0], th2)
        omega = (_rot([0, 0, 1], th1) @ R2).T @ [W1, 0, 0] + R2.T @ [0, 0, w1] + np.array([0, w2, 0])
        out.append(omega[0])
    return np.array(out)


@pytest.fixture(scope="module")
def hooke():
    return built(cardan())


@pytest.mark.parametrize("dt", [1e-3, 5e-4])
def test_the_output_follows_the_cardan_joints_closed_form(hooke, dt):
    """Over 2 s (1.3 input turns): the output's angle phi2 (its arm a2 = y measured from ground's
    y about N_OUT, from R(outshaft.m, ., y)) against atan2(sin phi1, cos phi1 cos beta) (measured
    1.5e-13 rad at dt = 1e-3, 8.9e-15 at 5e-4), its rate about N_OUT against W1 cos beta / (1 -
    sin^2 beta cos^2 phi1) (3.8e-13, 2.3e-14 rad/s), the collar at D (1.1e-16 m), the loop
    closed (3.2e-13, 1.9e-14 m)."""
    r = run_ok(hooke, t_end=2.0, dt=dt, integrator="rk4p")
    phi1 = r["phi"]
    assert np.abs(phi1 - W1 * r.t).max() < 1e-13
    m = np.cross(N_OUT, [0.0, 1.0, 0.0])  # the output's arm at phi2 = 90 degrees
    phi2 = np.arctan2(m[0] * r["Axy"] + m[2] * r["Azy"], r["Ayy"])
    want = np.arctan2(np.sin(phi1), np.cos(phi1) * math.cos(BETA))
    assert np.abs(np.angle(np.exp(1j * (phi2 - want)))).max() < 1e-9
    rate = W1 * math.cos(BETA) / (1 - math.sin(BETA)**2 * np.cos(phi1)**2)
    assert np.abs(_output_rate(r) - rate).max() < 1e-9
    assert rate.max() / rate.min() > 1.3  # the ratio does vary: 1/cos^2 beta
    assert np.abs(r["s"] - D).max() < 1e-12 and np.abs(r["viol"]).max() < 1e-9


def test_inspect_and_the_units_name_both_angles():
    """`flexsym inspect`'s system section lists the joint's two coordinates with their arms, and
    the outputs' units follow each coordinate's motion (Joint.coordinates)."""
    from flexsym.model.system import output_unit
    from flexsym.scenes.system_scene import summary

    system = system_from_dict(cardan(), name="cardan")
    text = summary(system)
    assert "  u: universal inshaft.fork -> outshaft.m, u: turn about (0, 0, 1), u_angle2: turn about (0, 1, 0)\n" in text
    assert "  ball: spherical outshaft.end -> collar.c [closes a loop]\n" in text
    assert [output_unit(system, q) for q in ("angle(u)", "rate(u)", "angle2(u)", "rate2(u)", "angle(guide)")] == \
        ["rad", "rad/s", "rad", "rad/s", "m"]


# ----- a universal joint between two moving bodies
def _chain() -> dict:
    """An arm free about the vertical (revolute hub) and a bob on a universal joint at its end
    (arms: the arm's x, the bob's y), started swinging and turning."""
    return {
        "system": {"name": "uj_chain", "dimension": 3},
        "body": [{"name": "arm", "kind": "rigid", "mass": 1.5, "inertia": [0.01, 0.08, 0.08],
                  "com": [0.25, 0.0, 0.0], "markers": {"hub": [0.0, 0.0, 0.0], "end": [0.5, 0.0, 0.0]}},
                 {"name": "bob", "kind": "rigid", "mass": MASS, "inertia": INERTIA,
                  "com": [0.05, 0.02, -ELL], "markers": {"pin": [0.0, 0.0, 0.0], "tip": [0.1, 0.05, -0.6]}}],
        "joint": [{"name": "hub", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0, 0.0],
                   "child": "arm.hub", "axis": [0.0, 0.0, 1.0], "initial": {"rate": 1.5}},
                  {"name": "u", "kind": "universal", "parent": "arm.end", "child": "bob.pin",
                   "parent_axis": A1, "axis": A2, "initial": SWING}],
        "gravity": {"g": [0.0, 0.0, -G]},
        "solver": {"integrator": "rk4p", "dt": 1e-3, "t_end": 1.0},
        "output": {"interval": 0.01, "columns": {
            "th1": "angle(u)", "th2": "angle2(u)", "w1": "rate(u)", "w2": "rate2(u)", "T": "T", "V": "V",
            "Hz": "Hz", "z": "z(bob.tip)", "Rzx": "R(bob.tip, z, x)", "Fz": "reaction(u, z)",
            "Mx": "reaction(u, mx)", "Mz": "reaction(u, mz)"}},
    }


@pytest.fixture(scope="module")
def chain():
    return built(_chain())


def test_the_chain_conserves_energy_and_momentum_about_the_vertical(chain):
    """Nothing acts about z, nothing dissipates: T + V and Hz within 1e-10 relative over 2 s at
    dt = 1e-3 (measured 2.0e-11, 3.6e-12), the bob exchanging momentum with the arm (the arm's
    rate is not constant)."""
    r = run_ok(chain, t_end=2.0, dt=1e-3, integrator="rk4p")
    E = r["T"] + r["V"]
    assert np.abs(E - E[0]).max() < 1e-10 * abs(E[0])
    assert np.abs(r["Hz"] - r["Hz"][0]).max() < 1e-10 * abs(r["Hz"][0])
    assert np.ptp(r["th1"]) > 0.5 and np.ptp(r["th2"]) > 0.5


def test_universal_kernels_c_casadi_sympy(chain, system_kernels_agree):
    """The chain's generated C kernels against casadi against sympy at a random state (its
    outputs: both angles and rates, a marker, an orientation, the joint's reaction, Hz)."""
    system_kernels_agree(derivation(_chain()), chain, t=0.3, seed=11)


# ----- malformed scenes
GOOD = '''[system]
name = "ujoint"
dimension = 3

[[body]]
name = "bob"
kind = "rigid"
mass = 2.0
inertia = [0.1, 0.3, 0.25]
com = [0.0, 0.0, -0.5]
markers = { pin = [0.0, 0.0, 0.0], tip = [0.0, 0.0, -0.6] }

[[body]]
name = "arm"
kind = "rigid"
mass = 1.0
inertia = [0.01, 0.01, 0.01]
markers = { pin = [0.0, 0.0, 0.0] }

[[joint]]
name = "u"
kind = "universal"
parent = "ground"
point = [0.0, 0.0, 1.0]
child = "bob.pin"
parent_axis = [1.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
initial = { value = 0.2, rate = 0.5, angle2 = -0.1, rate2 = 0.3 }

[[joint]]
name = "hinge"
kind = "revolute"
parent = "bob.tip"
child = "arm.pin"
axis = [0.0, 1.0, 0.0]

[gravity]
g = [0.0, 0.0, -9.81]

[solver]
t_end = 0.01

[output]
columns = { b = "angle2(u)", w = "rate2(u)" }
'''
PARENT_AXIS = "parent_axis = [1.0, 0.0, 0.0]\n"
GUIDED = '\n[[driver]]\nname = "d"\nkind = "guided"\njoint = "u"\nmaneuver = "constant"\nomega = 1.0\n'
BAD = [  # (what, scene text, what the one line says)
    ("parallel axes", GOOD.replace(PARENT_AXIS, "parent_axis = [0.0, 2.0, 0.0]\n"),
     "joint 'u': parent_axis [0.0, 2.0, 0.0] and axis [0.0, 1.0, 0.0] are 0 degrees apart: a universal "
     "joint's two axes cross at right angles"),
    ("axes 45 degrees apart", GOOD.replace(PARENT_AXIS, "parent_axis = [1.0, 1.0, 0.0]\n"),
     "joint 'u': parent_axis [1.0, 1.0, 0.0] and axis [0.0, 1.0, 0.0] are 45 degrees apart"),
    ("no parent_axis in the tree", GOOD.replace(PARENT_AXIS, "").replace(
        "initial = { value = 0.2, rate = 0.5, angle2 = -0.1, rate2 = 0.3 }\n", ""),
     "joint 'u': a universal joint in the tree needs parent_axis (three numbers, the first turn's axis "
     "in the parent's frame"),
    ("parent_axis of zero length", GOOD.replace(PARENT_AXIS, "parent_axis = [0.0, 0.0, 0.0]\n"),
     "joint 'u': parent_axis (0.0, 0.0, 0.0) must be three finite numbers, not shorter than 1e-06"),
    ("parent_axis of two numbers", GOOD.replace(PARENT_AXIS, "parent_axis = [1.0, 0.0]\n"),
     "[[joint]] 'u' parent_axis: must be three finite numbers [x, y, z] (got [1.0, 0.0])"),
    ("parent_axis on a revolute joint", GOOD.replace('axis = [0.0, 1.0, 0.0]\n\n[gravity]',
                                                     'axis = [0.0, 1.0, 0.0]\nparent_axis = [1.0, 0.0, 0.0]\n\n[gravity]'),
     "joint 'hinge': parent_axis applies to universal joints of spatial systems only"),
    # drivers on it: tests/test_spatial_cuts.py (a motor on its second angle)
    ("a guided driver on its first angle, its rate given", GOOD + GUIDED,
     "driver 'd': joint 'u' is guided: its coordinate and rate at t = 0 are the driver's"),
    ("a motor on its slide", GOOD + '\n[[driver]]\nname = "d"\nkind = "motor"\njoint = "u"\ncoordinate = "slide"\n'
     'torque = "0.1"\n', "driver 'd': joint 'u' (universal) has no coordinate 'slide' (its coordinates: 'u', 'u_angle2'"),
    ("a non-finite angle2", GOOD.replace("angle2 = -0.1", "angle2 = nan"),
     "[[joint]] 'u' initial angle2: must be a finite number"),
    ("a string rate2", GOOD.replace("rate2 = 0.3", 'rate2 = "fast"'),
     "[[joint]] 'u' initial rate2: must be a finite number"),
    ("angle2 on a revolute joint", GOOD.replace('axis = [0.0, 1.0, 0.0]\n\n[gravity]',
                                                'axis = [0.0, 1.0, 0.0]\ninitial = { value = 0.1, angle2 = 0.2 }\n\n[gravity]'),
     "[[joint]] 'hinge' initial angle2: unknown key"),
    ("angle2 of a revolute joint", GOOD.replace('b = "angle2(u)"', 'b = "angle2(hinge)"'),
     "output 'angle2(hinge)': angle2(J) is a universal joint's second angle (in the tree), and 'hinge' is a "
     "revolute joint"),
    ("an output column named after the second angle", GOOD.replace('w = "rate2(u)"', 'u_angle2 = "rate2(u)"'),
     "output column 'u_angle2' is already the name of the second angle of joint 'u'"),
]
# in other scenes: a planar system, a universal joint that closes a loop (S7's)
ELSEWHERE = [  # (what, scene, edits of its text, what the one line says)
    ("parent_axis in a planar system", PLANAR, [('child = "upper.pivot"', 'child = "upper.pivot"\n'
                                                                          'parent_axis = [1.0, 0.0, 0.0]')],
     "parent_axis applies to universal joints of spatial systems only"),
    ("parent_axis on a loop-closing universal joint", S7, [(CARDAN_AXIS, CARDAN_AXIS + "\nparent_axis = [0.0, 1.0, 0.0]")],
     "joint 'cardan': closes a loop: parent_axis applies to a universal joint in the tree"),
    ("angle2 on a loop-closing universal joint", S7, [(CARDAN_AXIS, CARDAN_AXIS + "\ninitial = { angle2 = 0.1 }")],
     "joint 'cardan': angle2 and rate2 apply to universal joints only in the tree (with parent_axis)"),
    ("initial on a loop-closing universal joint", S7, [(CARDAN_AXIS, CARDAN_AXIS + "\ninitial = 0.1")],
     "joint 'cardan': initial, rate and fixed apply to a universal joint in the tree (with parent_axis); one "
     "closing a loop has no coordinate"),
    ("angle2 of a loop-closing universal joint", S7, [('x_s = "x(slider.pin)"', 'x_s = "angle2(cardan)"')],
     "angle2(J) is a universal joint's second angle (in the tree), and 'cardan' is a universal joint closing a loop"),
]


def test_the_good_scene_runs(tmp_path, capsys):
    """The malformed scenes' base runs (so each refusal below is its edit's)."""
    scene_text_runs(tmp_path, capsys, GOOD)


@pytest.mark.parametrize("what,text,says", BAD, ids=[b[0] for b in BAD])
def test_bad_universal_scenes_are_refused(tmp_path, capsys, what, text, says):
    """Refused in one line naming the file and the item, exit 2, nothing written."""
    assert text != GOOD, what
    scene_text_refused(tmp_path, capsys, text, says)


@pytest.mark.parametrize("what,scene,edits,says", ELSEWHERE, ids=[b[0] for b in ELSEWHERE])
def test_universal_keys_elsewhere_are_refused(tmp_path, capsys, what, scene, edits, says):
    refused_in_one_line(capsys, edited_scene(tmp_path, what, scene, edits), says)
