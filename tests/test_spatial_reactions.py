"""Joint reactions of spatial systems, reaction(joint, c) with c in x, y, z (the force) and
mx, my, mz (the moment about the joint's child point), ground components: the load the
parent side exerts on the child side, constraint and drive together (physics/spatial.py
joint_reaction: a tree joint's from the momentum balance of the bodies beyond it, a cut
joint's from its multipliers). Checked against closed forms and against m (a_G - g) from the
run's own marker positions."""
import math

import numpy as np
import pytest

from system_data import built, run_ok

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
    everything else 0, to 1e-12 of the loads."""
    r = run_ok(chain, t_end=0.5, dt=1e-3, integrator="rk4")
    up = np.array([0.0, 0.0, 1.0])
    for j, mass, moment in (("j1", M1 + M2 + M3, 0.0), ("j2", M2 + M3, 0.0), ("j3", M3, 0.2 * M3 * G)):
        assert np.abs(_vector(r, j) - mass * G * up).max() < 1e-12 * mass * G, j
        assert np.abs(_vector(r, j, MOMENT) - moment * np.array([0.0, 1.0, 0.0])).max() < 1e-12 * 40, j
