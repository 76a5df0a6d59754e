"""Joint reactions of spatial systems, reaction(joint, c) with c in x, y, z (the force) and
mx, my, mz (the moment about the joint's child point), ground components: the load the
parent side exerts on the child side, constraint and drive together (physics/spatial.py
joint_reaction: a tree joint's from the momentum balance of the bodies beyond it, a cut
joint's from its multipliers). Checked against closed forms and against m (a_G - g) from the
run's own marker positions."""
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from system_data import built, edited_scene, refused_in_one_line, run_ok

ROOT = Path(__file__).resolve().parent.parent
G = 9.81
FORCE = ("x", "y", "z")
MOMENT = ("mx", "my", "mz")


def _reaction_columns(*joints) -> dict:
    return {f"{j}_{c}": f"reaction({j}, {c})" for j in joints for c in FORCE + MOMENT}


def _vector(r, joint, comps=FORCE):
    return np.column_stack([r[f"{joint}_{c}"] for c in comps])


def _m_a_minus_g(t, pos, mass, g=(0.0, 0.0, -G)):
    """m (a_G - g) at the inner rows from central differences of the centre of mass's
    positions (rows at a constant interval)."""
    h = t[1] - t[0]
    return mass * ((pos[2:] - 2 * pos[1:-1] + pos[:-2]) / h**2 - np.asarray(g))


# ----- (a) the heavy symmetric top in steady precession (test_rigid_3d's closed form)
I1C, I3, MASS, L_ = 0.02, 0.035, 2.0, 0.1
THETA0, W3 = math.radians(30.0), 50.0
I1P = I1C + MASS * L_**2
_a, _c = I3 * W3, math.cos(THETA0)
OMEGA = (_a - math.sqrt(_a**2 - 4 * I1P * _c * MASS * G * L_)) / (2 * I1P * _c)
N0 = np.array([math.sin(THETA0), 0.0, _c])


@pytest.fixture(scope="module")
def top():
    w0 = OMEGA * np.array([0.0, 0.0, 1.0]) + (W3 - OMEGA * _c) * N0
    return built({
        "system": {"name": "reaction_top", "dimension": 3},
        "body": [{"name": "top", "kind": "rigid", "mass": MASS, "inertia": [I3, I1C, I1C],
                  "com": [L_, 0.0, 0.0], "markers": {"pivot": [0.0, 0.0, 0.0], "g": [L_, 0.0, 0.0]}}],
        "joint": [{"name": "ball", "kind": "spherical", "parent": "ground", "point": [0.0, 0.0, 0.0],
                   "child": "top.pivot", "direction": N0.tolist(), "initial": {"rate": w0.tolist()}}],
        "gravity": {"g": [0.0, 0.0, -G]},
        "output": {"interval": 0.01, "columns": {"x": "x(top.g)", "y": "y(top.g)", "z": "z(top.g)"}
                   | _reaction_columns("ball")},
    })


def test_ball_joint_of_the_heavy_top_carries_weight_and_centripetal_force(top):
    """Steady precession: the centre of mass turns on a horizontal circle of radius l sin(theta0)
    at Omega, so the joint's force is m (a_G - g) = -m Omega^2 r_perp + m g z (closed form, along
    the run's own azimuth), 19.62 N up and 0.066 N inwards; a ball joint carries no moment about
    its point. rk4p at 1 ms over 2 s: the force is the closed form within 1.9e-7 N (measured;
    1.2e-8 N at 0.5 ms, order 4: the run's own departure from the steady precession, whose
    nutation at 42 rad/s turns 1e-9 rad into 2e-7 N), and m (a_G - g) from central differences
    of the centre of mass's positions every 1 ms within 1.1e-7 N (the differences' resolution:
    1e-13 m of position over h^2); the moments are 0 within 4e-14 N m (measured)."""
    r = run_ok(top, t_end=2.0, dt=1e-3, integrator="rk4p", interval=1e-3)
    G_pos = np.column_stack([r["x"], r["y"], r["z"]])
    perp = G_pos * np.array([1.0, 1.0, 0.0])
    want = -MASS * OMEGA**2 * perp + MASS * G * np.array([0.0, 0.0, 1.0])
    F = _vector(r, "ball")
    assert np.abs(F - want).max() < 5e-7, np.abs(F - want).max()
    assert np.abs(F[1:-1] - _m_a_minus_g(r.t, G_pos, MASS)).max() < 3e-7
    assert np.abs(_vector(r, "ball", MOMENT)).max() < 1e-12
    assert np.abs(F[:, 0]).max() > 0.06  # the centripetal part is there


def test_ball_joint_of_the_flexible_strip_carries_no_moment():
    """S6 (a flexible strip on a ball joint, swinging round and falling: it bends in both
    planes and twists), with the linear model m0 (its build is a fifth of m3's): the ball
    joint's moment, dH_O/dt - S x g - P x F with the beam's first moment S and angular
    momentum H (torsion's included) over its modes, is 0 to round-off with rk4p at 20 us over
    0.5 s (measured 1.0e-14 N m; the force is up to 7.4 N): the beam's momenta are those its
    equations of motion balance. (genalpha3 on S6 with m3: 1.4e-6 N m at 0.1 ms and 4.4e-7 at
    0.05 ms, its accelerations satisfying the equations to O(dt^2) only.)"""
    data = tomllib.loads((ROOT / "scenes" / "spherical_pendulum.toml").read_text())
    data["output"]["columns"] = _reaction_columns("ball") | {"w_mid": "w(strip, mid)"}
    r = run_ok(built(data, "m0"), t_end=0.5, dt=2e-5, interval=1e-3, integrator="rk4p")
    assert np.abs(_vector(r, "ball", MOMENT)).max() < 1e-13
    assert np.abs(_vector(r, "ball")).max() > 5.0
    assert np.abs(r["w_mid"]).max() > 1e-3  # it bends (1.24 mm from its chord at mid-span)


# ----- (b) a chain hanging at rest: each joint carries the weight beyond it
M1, M2, M3 = 1.0, 2.0, 1.0


@pytest.fixture(scope="module")
def chain():
    """ground -revolute(x)- b1 -revolute(y)- b2 -clamp- b3: b2's centre of mass 0.1 m to +x of
    the vertical through its joint, b3's (cantilevered on the clamp) 0.2 m to -x: the pair's
    balances under that joint, so the chain hangs at rest."""
    return built({
        "system": {"name": "reaction_chain", "dimension": 3},
        "body": [{"name": "b1", "kind": "rigid", "mass": M1, "inertia": [0.01, 0.01, 0.002],
                  "com": [0.0, 0.0, -0.2], "markers": {"top": [0.0, 0.0, 0.0], "bottom": [0.0, 0.0, -0.4]}},
                 {"name": "b2", "kind": "rigid", "mass": M2, "inertia": [0.02, 0.02, 0.004],
                  "com": [0.1, 0.0, -0.3], "markers": {"top": [0.0, 0.0, 0.0], "end": [0.0, 0.0, -0.5]}},
                 {"name": "b3", "kind": "rigid", "mass": M3, "inertia": [0.001, 0.01, 0.01],
                  "com": [-0.2, 0.0, 0.0], "markers": {"root": [0.0, 0.0, 0.0]}}],
        "joint": [{"name": "j1", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0, 0.0],
                   "axis": [1.0, 0.0, 0.0], "child": "b1.top"},
                  {"name": "j2", "kind": "revolute", "parent": "b1.bottom", "axis": [0.0, 1.0, 0.0],
                   "child": "b2.top"},
                  {"name": "j3", "kind": "clamp", "parent": "b2.end", "child": "b3.root"}],
        "gravity": {"g": [0.0, 0.0, -G]},
        "output": {"interval": 0.01, "columns": _reaction_columns("j1", "j2", "j3")},
    })


def test_hanging_chain_joints_carry_the_weight_beyond_them(chain):
    """At rest (rk4, 1 ms, 0.5 s): j1 carries (m1 + m2 + m3) g = 39.24 N, j2 (m2 + m3) g, the
    clamp j3 m3 g and the moment of b3's weight about its root, 0.2 m3 g = 1.962 N m about +y;
    everything else 0, within 1e-12 of the loads (measured: exact, but 2.2e-16 N m on j3's
    moment; the run stays at rest, q'' = 0)."""
    r = run_ok(chain, t_end=0.5, dt=1e-3, integrator="rk4")
    up = np.array([0.0, 0.0, 1.0])
    for j, mass, moment in (("j1", M1 + M2 + M3, 0.0), ("j2", M2 + M3, 0.0), ("j3", M3, 0.2 * M3 * G)):
        assert np.abs(_vector(r, j) - mass * G * up).max() < 1e-12 * mass * G, j
        assert np.abs(_vector(r, j, MOMENT) - moment * np.array([0.0, 1.0, 0.0])).max() < 1e-12 * 40, j


# ----- (c) a motor's torque is in its joint's reaction
AXIS = np.array([0.0, 0.6, 0.8])
TAU = "0.5*cos(3*t)"
PUSH, K_SPRING, ANCHOR = np.array([0.5, -0.3, 1.0]), 20.0, np.array([0.4, 0.3, 0.0])
BASE = {"name": "base", "kind": "rigid", "mass": 1.0, "inertia": [1.0, 1.0, 1.0],
        "markers": {"o": [0.0, 0.0, 0.0], "anchor": ANCHOR.tolist()}}  # clamped to ground by FIX
FIX = {"name": "fix", "kind": "clamp", "parent": "ground", "point": [0.0, 0.0, 0.0], "child": "base.o"}


def _loads(body: str, at: str) -> list:
    """A torque on `body` (ground axes), a point force at the marker `at` (ground axes) and a
    spring (l0 = 0) from the base's anchor to it."""
    return [{"kind": "torque", "body": body, "torque": ["0.3", "-0.2", "0.4"], "frame": "ground"},
            {"kind": "force", "name": "push", "marker": at, "fx": PUSH[0], "fy": PUSH[1], "fz": PUSH[2]},
            {"kind": "spring", "name": "s", "a": "base.anchor", "b": at, "k": K_SPRING, "l0": 0.0}]


@pytest.fixture(scope="module")
def motored():
    """A block on a revolute joint to ground about the tilted axis a, its centre of mass off
    the axis, under gravity, a motor on the joint and, on the block, an external torque, a
    point force (ground axes) and a spring (l0 = 0) to an anchor on a clamped base."""
    return built({
        "system": {"name": "reaction_motor", "dimension": 3},
        "body": [{"name": "block", "kind": "rigid", "mass": 1.5, "inertia": [0.01, 0.02, 0.025],
                  "com": [0.2, 0.1, 0.05],
                  "markers": {"pin": [0.0, 0.0, 0.0], "g": [0.2, 0.1, 0.05], "tip": [0.3, -0.1, 0.0]}},
                 BASE],
        "joint": [{"name": "j", "kind": "revolute", "parent": "ground", "point": [0.1, 0.0, 0.3],
                   "axis": AXIS.tolist(), "child": "block.pin"},
                  FIX],
        "driver": [{"name": "m", "kind": "motor", "joint": "j", "torque": TAU}],
        "load": _loads("block", "block.tip"),
        "gravity": {"g": [0.0, 0.0, -G]},
        "output": {"interval": 0.01, "columns": {f"{c}{w}": f"{c}(block.{w})" for c in "xyz" for w in ("g", "tip")}
                   | _reaction_columns("j")},
    })


def test_motor_torque_is_the_reaction_moment_about_its_axis(motored):
    """The joint's moment about its (ground-fixed) axis is the motor's torque, 0.5 cos(3 t), to
    round-off (measured 5e-15 N m): gravity's, the external torque's, the point force's and the
    spring's moments about the axis move the block, the motor's is transmitted by the joint.
    Its force (up to 35 N) plus the point force and the spring's, -k (tip - anchor), is
    m (a_G - g) from the centre of mass's positions by central differences every 0.2 ms within
    3.0e-5 N (measured; 1.9e-4 N every 0.5 ms, 7.5e-4 N every 1 ms: the differences'
    truncation, h^2). rk4, 0.1 ms, 2 s."""
    r = run_ok(motored, t_end=2.0, dt=1e-4, integrator="rk4", interval=2e-4)
    M = _vector(r, "j", MOMENT)
    assert np.abs(M @ AXIS - 0.5 * np.cos(3 * r.t)).max() < 1e-13
    tip = np.column_stack([r[f"{c}tip"] for c in "xyz"])
    net = _vector(r, "j") + PUSH - K_SPRING * (tip - ANCHOR)
    G_pos = np.column_stack([r[f"{c}g"] for c in "xyz"])
    assert np.abs(net[1:-1] - _m_a_minus_g(r.t, G_pos, 1.5)).max() < 6e-5
    assert np.abs(np.linalg.norm(M, axis=1)).max() > 1.0  # the joint carries bending moments too


# ----- (d) a closed loop: S7's spatial slider-crank with a rigid rod, under gravity
M_CRANK, M_ROD, M_SLIDER = 0.1, 0.0668, 0.0334
X_S0 = 0.1 + math.sqrt(0.3**2 - 0.05**2 - 0.15**2)


@pytest.fixture(scope="module")
def loop():
    """A guided crank (r = 0.1 m) about the ground's z, a rigid rod on a ball joint at its pin,
    a universal joint (cut: closing the loop) from the rod's tip to a slider on a prismatic
    joint along x; gravity along -z."""
    rod_dir = [X_S0 - 0.1, 0.05, 0.15]
    return built({
        "system": {"name": "reaction_loop", "dimension": 3},
        "body": [{"name": "crank", "kind": "rigid", "mass": M_CRANK, "inertia": [1e-4, 1e-4, 1e-4],
                  "com": [0.05, 0.0, 0.0],
                  "markers": {"axis": [0.0, 0.0, 0.0], "pin": [0.1, 0.0, 0.0], "g": [0.05, 0.0, 0.0]}},
                 {"name": "rod", "kind": "rigid", "mass": M_ROD, "inertia": [1e-6, 5e-4, 5e-4],
                  "com": [0.15, 0.0, 0.0],
                  "markers": {"root": [0.0, 0.0, 0.0], "tip": [0.3, 0.0, 0.0], "g": [0.15, 0.0, 0.0]}},
                 {"name": "slider", "kind": "rigid", "mass": M_SLIDER, "inertia": [1e-6, 1e-6, 1e-6],
                  "markers": {"pin": [0.0, 0.0, 0.0]}}],
        "joint": [{"name": "crank_joint", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0, 0.0],
                   "axis": [0.0, 0.0, 1.0], "child": "crank.axis"},
                  {"name": "slide", "kind": "prismatic", "parent": "ground", "point": [0.0, 0.05, 0.15],
                   "axis": [1.0, 0.0, 0.0], "child": "slider.pin", "initial": X_S0},
                  {"name": "ball", "kind": "spherical", "parent": "crank.pin", "child": "rod.root",
                   "direction": rod_dir},
                  {"name": "cardan", "kind": "universal", "parent": "rod.tip", "child": "slider.pin",
                   "axis": [1.0, 0.0, 0.0]}],
        "driver": [{"name": "drive", "kind": "guided", "joint": "crank_joint", "maneuver": "spin-up",
                    "omega": 20.0, "duration": 0.2}],
        "gravity": {"g": [0.0, 0.0, -G]},
        "output": {"interval": 0.01, "columns": {
            f"{b}_{c}": f"{c}({b}.{'pin' if b == 'slider' else 'g'})" for b in ("crank", "rod", "slider")
            for c in "xyz"} | _reaction_columns("crank_joint", "slide", "ball", "cardan")
            | {"tau": "torque(drive)"}},
    })


def _positions(r, body):
    return np.column_stack([r[f"{body}_{c}"] for c in "xyz"])


def test_loop_reactions_balance_each_body(loop):
    """Every body's momentum balance from its joints' reactions (tree joints: the subtree's
    momentum; the universal joint, cut: its multipliers), against m (a_G - g) from central
    differences of its centre of mass's positions every 0.2 ms: the crank between its guided
    joint and the ball joint, the rod between the ball joint and the cardan, the slider between
    its slide and the cardan (it is the cardan's child). Measured 5.9e-6, 9.6e-6 and 5.7e-6 N
    of forces up to 6.6 N (the differences' truncation: 1.5e-4, 2.4e-4, 1.4e-4 N every 1 ms,
    25x less at 5x the rate). About the crank's axis, its guided joint's moment (the drive's
    torque, up to 0.28 N m) minus the ball joint's force's moment is I_O theta'' (theta'' by
    differences; up to 0.07 N m, measured 1.2e-7 N m off). A prismatic joint without a drive
    carries no force along its axis (round-off: the slider's equation of motion), a ball joint
    no moment (1.4e-14 N m: the rod's angular momentum balance with the universal joint's
    torque). rk4p at 0.1 ms, 0.4 s, a spin-up to 20 rad/s (genalpha3's ball joint moment is
    5.9e-7 N m at 0.1 ms, 1.5e-7 at 0.05 ms: its multipliers and accelerations agree to O(dt^2)
    only)."""
    r = run_ok(loop, t_end=0.4, dt=1e-4, integrator="rk4p", interval=2e-4)
    F = {j: _vector(r, j) for j in ("crank_joint", "slide", "ball", "cardan")}
    for body, mass, net in (("crank", M_CRANK, F["crank_joint"] - F["ball"]),
                            ("rod", M_ROD, F["ball"] - F["cardan"]),
                            ("slider", M_SLIDER, F["slide"] + F["cardan"])):
        assert np.abs(net[1:-1] - _m_a_minus_g(r.t, _positions(r, body), mass)).max() < 2e-5, body
    assert min(np.abs(f).max() for f in F.values()) > 2.0
    crank = _positions(r, "crank")
    theta = np.unwrap(np.arctan2(crank[:, 1], crank[:, 0]))
    h = r.t[1] - r.t[0]
    theta_dd = (theta[2:] - 2 * theta[1:-1] + theta[:-2]) / h**2
    pin = 2 * crank
    about_axis = r["crank_joint_mz"] - np.cross(pin, F["ball"])[:, 2]
    I_O = 1e-4 + M_CRANK * 0.05**2
    assert np.abs(about_axis[1:-1] - I_O * theta_dd).max() < 5e-7
    assert np.abs(r["crank_joint_mz"]).max() > 0.2
    assert np.abs(F["slide"][:, 0]).max() < 1e-14
    assert np.abs(_vector(r, "ball", MOMENT)).max() < 1e-13


def test_a_guided_cranks_torque_is_its_joints_moment_about_the_axis(loop):
    """torque(drive) by Lagrange's equation of the guided angle (the bodies' T in casadi, the
    loop's multipliers through Phi_theta^T lambda) against the guided joint's moment about its
    axis from the momentum balance of the bodies beyond it (joint_reaction): two derivations,
    within 1e-12 of the torque's peak, 0.28 N m (measured 7.7e-15 N m)."""
    r = run_ok(loop, t_end=0.4, dt=1e-4, integrator="rk4p")
    assert np.abs(r["tau"] - r["crank_joint_mz"]).max() < 1e-12 * np.abs(r["tau"]).max()
    assert np.abs(r["tau"]).max() > 0.2


@pytest.fixture(scope="module")
def guided_hub():
    """A hub turned by a guided spin-up about the tilted axis a, carrying a strip clamped to it
    (one mode per bending plane and the torsion mode), under gravity, a torque on the hub, a
    point force (ground axes) at the strip's tip and a spring (l0 = 0) from its tip to an anchor
    on a clamped base."""
    return built({
        "system": {"name": "reaction_guided", "dimension": 3},
        "body": [{"name": "hub", "kind": "rigid", "mass": 1.5, "inertia": [0.01, 0.02, 0.025],
                  "com": [0.05, 0.02, 0.0], "markers": {"pin": [0.0, 0.0, 0.0], "flange": [0.1, 0.0, 0.0]}},
                 {"name": "strip", "kind": "beam", "length": 0.6, "density": 2700.0, "youngs_modulus": 7.0e10,
                  "shear_modulus": 2.6e10, "area": 1.0e-4, "inertia_z": 3.3333e-9, "inertia_y": 2.0833e-10,
                  "torsion_constant": 7.021e-10,
                  "model": {"strain": "linear", "axial": [], "bending": ["cf1"]}},
                 BASE],
        "joint": [{"name": "j", "kind": "revolute", "parent": "ground", "point": [0.1, 0.0, 0.3],
                   "axis": AXIS.tolist(), "child": "hub.pin"},
                  {"name": "c", "kind": "clamp", "parent": "hub.flange", "child": "strip.root"},
                  FIX],
        "driver": [{"name": "spin", "kind": "guided", "joint": "j", "maneuver": "spin-up", "omega": 8.0,
                    "duration": 0.5}],
        "load": _loads("hub", "strip.tip"),
        "gravity": {"g": [0.0, 0.0, -G]},
        "output": {"interval": 0.01, "columns": {"tau": "torque(spin)", "w": "vz(strip, tip)"}
                   | _reaction_columns("j")},
    })


def test_a_guided_hubs_torque_is_its_joints_moment_about_the_axis(guided_hub):
    """The same two derivations on a flexible body (its T in its frame's motion, by casadi),
    with gravity, a torque, a point force and a spring acting on what the guided joint turns:
    the torque (up to 13.9 N m) within 1e-10 of its peak of the joint's moment about its axis
    (measured 5e-15 N m), while the strip bends (its tip across its weak plane by 5.5 cm)."""
    r = run_ok(guided_hub, t_end=1.0, dt=1e-4, integrator="genalpha")
    M = _vector(r, "j", MOMENT)
    assert np.abs(r["tau"] - M @ AXIS).max() < 1e-10 * np.abs(r["tau"]).max()
    assert np.abs(r["tau"]).max() > 1.0 and np.abs(r["w"]).max() > 1e-3


# ----- (e) a planar system run as a spatial one: the same reactions
def test_planar_reactions_are_the_spatial_twins():
    """S1 (the motor-driven hub with a flexible m3 beam clamped to it, 5 s of its spin-up) and
    its spatial twin (test_planar_as_spatial.spatial_twin): reaction(j, x), (j, y), (j, moment)
    of the planar system are the twin's reaction(j, x), (j, y), (j, mz), at the motored hub
    joint (the motor's torque, up to 264 N m) and at the clamp (the beam's root: its first
    moment and angular momentum, up to 83 N and 240 N m), within 1e-12 of each column's peak
    (measured 4e-16 to 1.1e-15: sympy's planar derivation against the spatial one, casadi's T);
    the out-of-plane z, mx, my are exactly 0."""
    from test_planar_as_spatial import open_chain_pair

    data, twin = open_chain_pair("hub")  # the twin test_planar_as_spatial.py runs too
    assert twin["output"]["columns"]["clamp_moment"] == "reaction(clamp, mz)"
    kw = dict(t_end=5.0, dt=1e-3)
    planar, spatial = run_ok(built(data), **kw), run_ok(built(twin), **kw)
    for j in ("hub_joint", "clamp"):
        for c in ("x", "y", "moment"):
            want = planar[f"{j}_{c}"]
            assert np.abs(spatial[f"{j}_{c}"] - want).max() < 1e-12 * np.abs(want).max(), (j, c)
            assert np.abs(want).max() > 50.0
        for c in ("z", "mx", "my"):
            assert np.all(spatial[f"{j}_{c}"] == 0), (j, c)


# ----- (f) malformed reactions: one line naming the output, exit 2, before any work
S6 = ROOT / "scenes" / "spherical_pendulum.toml"
PLANAR = ROOT / "scenes" / "double_pendulum.toml"
S6_COLUMNS = 'T_mid = "Mx(strip, mid)" }'
PLANAR_COLUMNS = 'M_mid = "M(strip, mid)" }'
BAD = [  # (what, scene, edits of its text, what the one line says)
    ("a spatial component in a planar system", PLANAR,
     [(PLANAR_COLUMNS, PLANAR_COLUMNS[:-1] + ', R = "reaction(elbow, z)" }')],
     "output 'reaction(elbow, z)': needs (joint, component) with component one of x, y, moment "
     "(dimension = 2)"),
    ("moment in a spatial system", S6, [(S6_COLUMNS, S6_COLUMNS[:-1] + ', R = "reaction(ball, moment)" }')],
     "output 'reaction(ball, moment)': needs (joint, component) with component one of x, y, z, mx, my, "
     "mz (dimension = 3)"),
    ("no component", S6, [(S6_COLUMNS, S6_COLUMNS[:-1] + ', R = "reaction(ball)" }')],
     "output 'reaction(ball)': needs (joint, component)"),
    ("an unknown joint", S6, [(S6_COLUMNS, S6_COLUMNS[:-1] + ', R = "reaction(hinge, mx)" }')],
     "output 'reaction(hinge, mx)': 'hinge' is not a joint of the system"),
]


@pytest.mark.parametrize("what,scene,edits,says", BAD, ids=[b[0] for b in BAD])
def test_bad_reactions_are_refused(tmp_path, capsys, what, scene, edits, says):
    refused_in_one_line(capsys, edited_scene(tmp_path, what, scene, edits), says)
