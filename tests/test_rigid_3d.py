"""The spatial rotation parameterisation (physics/spatial.py: a spherical joint's Euler parameters
on |e| = 1, a constraint row) against closed forms, on an all-rigid spatial system: one
axisymmetric rigid body on a ball joint to the ground, no beam.

The body's x axis is its symmetry axis: inertia = [I3, I1, I1] about the centre of mass, the
joint's `direction` puts that axis at n0 at t = 0 and its `rate` is the body's angular velocity
w0 (ground components). Marker `tip` is on the axis at D from the pivot, `side` at D across it.

 * torque-free (pivot at the centre of mass, g = 0): the whole attitude in closed form;
 * the heavy symmetric top in steady precession (pivot at l from the centre of mass);
 * the same top nudged off it: the nutation frequency;
 * the convergence order of rk4p and genalpha3, the error against the closed form.
"""
import math

import numpy as np
import pytest

from system_data import built, run_ok

D = 0.5  # the markers' distance from the pivot [m]
I1C, I3, MASS = 0.02, 0.035, 2.0  # about the centre of mass [kg m^2], [kg]
Z = np.array([0.0, 0.0, 1.0])
COLUMNS = {"x": "x(top.tip)", "y": "y(top.tip)", "z": "z(top.tip)", "xs": "x(top.side)",
           "ys": "y(top.side)", "zs": "z(top.side)", "T": "T", "V": "V", "Hx": "Hx", "Hy": "Hy",
           "Hz": "Hz", "viol": "violation"} | {f"R{i}{j}": f"R(top.pivot, {i}, {j})" for i in "xyz" for j in "xyz"}


def _top(name: str, l: float, g: float, n0, w0) -> dict:
    return {
        "system": {"name": name, "dimension": 3},
        "body": [{"name": "top", "kind": "rigid", "mass": MASS, "inertia": [I3, I1C, I1C],
                  "com": [l, 0.0, 0.0],
                  "markers": {"pivot": [0.0, 0.0, 0.0], "tip": [D, 0.0, 0.0], "side": [0.0, D, 0.0]}}],
        "joint": [{"name": "ball", "kind": "spherical", "parent": "ground", "point": [0.0, 0.0, 0.0],
                   "child": "top.pivot", "direction": [float(v) for v in n0],
                   "initial": {"rate": [float(v) for v in w0]}}],
        "gravity": {"g": [0.0, 0.0, -g]},
        "solver": {"integrator": "rk4p", "dt": 1e-3, "t_end": 2.0},
        "output": {"interval": 0.01, "columns": COLUMNS},
    }


def _turn(k, angle, v):
    """Rodrigues, row-wise: v (n x 3) turned by angle (n) about the unit axis k (n x 3 or 3)."""
    k = np.broadcast_to(k, v.shape)
    c, s_ = np.cos(angle)[:, None], np.sin(angle)[:, None]
    return v * c + np.cross(k, v) * s_ + k * np.sum(k * v, axis=1)[:, None] * (1 - c)


def _points(r, which=""):
    return np.column_stack([r["x" + which], r["y" + which], r["z" + which]])


# ----- torque-free: pivot at the centre of mass, no gravity
FREE_N0 = np.array([0.6, 0.0, 0.8])
FREE_W0 = np.array([1.0, 2.0, 5.0])
FREE_H = I1C * FREE_W0 + (I3 - I1C) * FREE_W0.dot(FREE_N0) * FREE_N0  # H = I1 w + (I3 - I1) w3 n
FREE_T = 0.5 * (I1C * FREE_W0.dot(FREE_W0) + (I3 - I1C) * FREE_W0.dot(FREE_N0)**2)


@pytest.fixture(scope="module")
def free():
    return built(_top("free_top", 0.0, 0.0, FREE_N0, FREE_W0))


def _free_closed_form(r):
    """Markers' ground positions in closed form. With the axis n and w3 = w.n,
    H = I1 w + (I3 - I1) w3 n, so w = H/I1 + (1 - I3/I1) w3 n. Torque-free H is fixed, and
    Euler's third equation (I1 = I2) keeps w3. The attitude R(t) = P(t) R0 S(t) with
    P = Rot(H/|H|, |H| t/I1) (ground) and S = Rot(e_x, beta t) (body) has the angular
    velocity (|H|/I1) h + beta n(t), which is w for beta = (1 - I3/I1) w3: the axis precesses
    about H at |H|/I1 with a constant nutation angle, and the body turns about its axis at beta
    relative to the precessing plane. So tip(t) = P(t) D n0 and side(t) = P(t) D (cos(beta t) u
    + sin(beta t) n0 x u), u = R0 e_y: the side marker's direction at t = 0 (taken from the run,
    whatever rotation the joint's start chose to turn x to n0)."""
    h = FREE_H / np.linalg.norm(FREE_H)
    alpha, beta = np.linalg.norm(FREE_H) / I1C, (1 - I3 / I1C) * FREE_W0.dot(FREE_N0)
    n = len(r.t)
    u = _points(r, "s")[0] / D
    assert abs(u.dot(FREE_N0)) < 1e-15 and abs(u.dot(u) - 1) < 1e-15
    tip = _turn(h, alpha * r.t, np.tile(D * FREE_N0, (n, 1)))
    body = D * (np.cos(beta * r.t)[:, None] * u + np.sin(beta * r.t)[:, None] * np.cross(FREE_N0, u))
    return tip, _turn(h, alpha * r.t, body)


def test_torque_free_precession_is_the_closed_form(free):
    """rk4p at 1 ms over 2 s (2.7 precessions about H at |H|/I1 = 8.58 rad/s; the body turns at
    beta = -2.76 rad/s relative to the precessing plane): the tip and side markers follow the
    closed form within 5e-11 m (measured 1.7e-11 m, D = 0.5 m; the method's order 4, see the
    convergence test); T and H keep their closed-form starts, 1/2 (I1 |w|^2 + (I3 - I1)
    w3^2) and I1 w + (I3 - I1) w3 n0, to round-off (2e-16 relative, measured: the joint's
    start, e' from `rate`, is exact), T and H over the run within 2e-13 and 1e-12 (measured
    1e-13, 3.8e-13), and the Euler parameters stay on |e| = 1 (violation 2.5e-14 m; the
    projection's tolerance is 1e-12)."""
    r = run_ok(free, t_end=2.0, dt=1e-3, integrator="rk4p")
    tip, side = _free_closed_form(r)
    assert np.abs(_points(r) - tip).max() < 5e-11
    assert np.abs(_points(r, "s") - side).max() < 5e-11
    H = np.column_stack([r["Hx"], r["Hy"], r["Hz"]])
    assert r["T"][0] == pytest.approx(FREE_T, rel=1e-14)
    assert np.abs(H[0] - FREE_H).max() < 1e-14 * np.linalg.norm(FREE_H)
    assert np.abs(r["T"] / FREE_T - 1).max() < 2e-13
    assert np.abs(H - FREE_H).max() < 1e-12 * np.linalg.norm(FREE_H)
    assert np.abs(r["viol"]).max() < 1e-12
    assert np.all(r["V"] == 0)
    # the axis really moves: its circle about H (nutation angle 20.3 deg) is 0.35 m across
    assert np.linalg.norm(tip - tip[0], axis=1).max() > 0.3


def test_marker_orientation_is_the_closed_form_attitude(free):
    """R(top.pivot, i, j), the ground axis i's component of the marker's axis j: its x and y
    columns are the closed form's tip and side directions (within 1e-10, as the markers), its
    z column their cross product, and it stays a rotation: R^T R - I is 2 (|e|^2 - 1) of the
    Euler parameters, which the projection holds to its tolerance 1e-12 (measured 1.0e-13)."""
    r = run_ok(free, t_end=2.0, dt=1e-3, integrator="rk4p")
    tip, side = _free_closed_form(r)
    R = np.stack([np.column_stack([r[f"R{i}{j}"] for j in "xyz"]) for i in "xyz"], axis=1)  # n x 3 x 3
    for k, want in enumerate((tip / D, side / D, np.cross(tip, side) / D**2)):
        assert np.abs(R[:, :, k] - want).max() < 1e-10, k
    assert np.abs(np.einsum("nij,nik->njk", R, R) - np.eye(3)).max() < 1e-12


def test_convergence_order_against_the_closed_form(free):
    """The tip's largest error over 2 s against the closed form, steps 2 and 1 ms: rk4p
    2.78e-10 and 1.74e-11 m (ratio 15.9: order 4), genalpha3 2.57e-5 and 6.38e-6 m (ratio 4.02:
    order 2). genalpha3's Euler parameters stay on |e| = 1 to round-off (1.4e-16)."""
    errs = {}
    for integrator in ("rk4p", "genalpha3"):
        for dt in (2e-3, 1e-3):
            r = run_ok(free, t_end=2.0, dt=dt, integrator=integrator)
            tip, _ = _free_closed_form(r)
            errs[integrator, dt] = np.abs(_points(r) - tip).max()
            if integrator == "genalpha3":
                assert np.abs(r["viol"]).max() < 1e-15
    rk, ga = (errs[i, 2e-3] / errs[i, 1e-3] for i in ("rk4p", "genalpha3"))
    assert 14 < rk < 18, errs  # 2^4
    assert 3.6 < ga < 4.4, errs  # 2^2
    assert errs["rk4p", 1e-3] < 2e-11 and errs["genalpha3", 1e-3] < 7e-6, errs


# ----- the heavy symmetric top: pivot at L_ from the centre of mass, on the axis
L_, G_ = 0.1, 9.81
I1P = I1C + MASS * L_**2  # I1' about the pivot
THETA0, W3 = math.radians(30.0), 50.0  # nutation angle from the upward vertical, spin w.n
_a, _c = I3 * W3, math.cos(THETA0)
OMEGA = (_a - math.sqrt(_a**2 - 4 * I1P * _c * MASS * G_ * L_)) / (2 * I1P * _c)  # slow root
TOP_N0 = np.array([math.sin(THETA0), 0.0, _c])


def _top_start(omega):
    return omega * Z + (W3 - omega * _c) * TOP_N0


@pytest.fixture(scope="module")
def heavy():
    return built(_top("heavy_top", L_, G_, TOP_N0, _top_start(OMEGA)))


def test_heavy_top_in_steady_precession(heavy):
    """Steady precession. The top's axis n at the polar angle theta0 turns about the vertical z
    at Omega; the angular velocity is w = Omega z + psi' n, its spin w3 = w.n = Omega cos(theta0)
    + psi' constant. About the pivot (fixed: the joint's force has no moment there) the body's
    inertia is I1' = I1 + m l^2 across the axis (parallel axes: the centre of mass is at l n)
    and I3 along it, so H = I1' (w - w3 n) + I3 w3 n = I1' Omega (z - cos(theta0) n) + I3 w3 n.
    In steady precession everything turns rigidly about z at Omega, so dH/dt = Omega z x H =
    Omega (I3 w3 - I1' Omega cos(theta0)) z x n (z x z = 0). The moment of gravity about the
    pivot is (l n) x (-m g z) = m g l z x n. Equal: m g l = Omega (I3 w3 - I1' Omega
    cos(theta0)), a quadratic in Omega; its slow root is
        Omega = (I3 w3 - sqrt((I3 w3)^2 - 4 I1' cos(theta0) m g l)) / (2 I1' cos(theta0)),
    1.1472 rad/s here (w3 = 50 rad/s, theta0 = 30 deg; with I1 about the centre of mass
    instead of I1' it would be 1.1336, the azimuth 0.027 rad off after 2 s). The start:
    direction n0, rate w0 = Omega z + (w3 - Omega cos(theta0)) n0.
    rk4p at 1 ms over 2 s: theta stays theta0 within 1.1e-9 rad and the azimuth is Omega t within
    2.6e-8 rad (order 4: 2.5e-8 and 4.9e-7 at 2 ms); a start off the steady precession by a
    fraction eps of Omega nutates by 0.014 eps rad, so theta detects eps ~ 1e-7. T + V and Hz
    (about the vertical through the pivot) keep their closed-form starts, 1/2 (I1' Omega^2
    sin^2 + I3 w3^2), m g l cos(theta0) and I1' Omega sin^2 + I3 w3 cos(theta0) (to round-off
    at t = 0), over the run within 6.5e-9 and 3.6e-9 (relative, measured). Each bound is about 3x
    the measured error at 1 ms (the error at 2 ms is 16-30x larger: the bound sits well inside
    one halving of the step)."""
    r = run_ok(heavy, t_end=2.0, dt=1e-3, integrator="rk4p")
    theta = np.arccos(r["z"] / D)
    azimuth = np.unwrap(np.arctan2(r["y"], r["x"]))
    assert np.abs(theta - THETA0).max() < 3e-9
    assert np.abs(azimuth - OMEGA * r.t).max() < 8e-8
    assert azimuth[-1] > 2.2  # it does precess
    s2 = math.sin(THETA0)**2
    T0 = 0.5 * (I1P * OMEGA**2 * s2 + I3 * W3**2)
    V0, Hz0 = MASS * G_ * L_ * _c, I1P * OMEGA * s2 + I3 * W3 * _c
    assert r["T"][0] == pytest.approx(T0, rel=1e-14) and r["V"][0] == pytest.approx(V0, rel=1e-14)
    assert r["Hz"][0] == pytest.approx(Hz0, rel=1e-14)
    E = r["T"] + r["V"]
    assert np.abs(E / (T0 + V0) - 1).max() < 2e-8
    assert np.abs(r["Hz"] / Hz0 - 1).max() < 1e-8
    assert np.abs(r["viol"]).max() < 1e-12


def test_nudged_top_nutates_at_the_linearised_frequency():
    """Started with the precession rate 5 % above the steady one, the top nutates about the new
    equilibrium angle. With p_phi = I1' phi' sin^2 + I3 w3 cos and w3 conserved, the nutation
    angle obeys I1' theta'' = I1' phi'^2 sin cos - I3 w3 phi' sin + m g l sin,
    phi' = (p_phi - I3 w3 cos) / (I1' sin^2); linearised about a steady precession (Omega,
    theta0) its frequency is exactly
        w_n^2 = ((I3 w3 - 2 I1' Omega cos(theta0)) / I1')^2 + Omega^2 sin^2(theta0)
    (checked with sympy), 41.77 rad/s here: the fast top's I3 w3 / I1' = 43.75 rad/s is 4.5 %
    above it (the term 2 I1' Omega cos / (I3 w3)). A sinusoid fitted to theta(t) over 2 s
    (rk4p, 1 ms; amplitude 6.9e-4 rad) has the linearised frequency of the nudged start's
    equilibrium within 3e-7 (relative, measured; 1.1e-6 at twice the amplitude: the O(amp^2)
    of the nonlinearity) and its mean angle within 6e-7 rad of that equilibrium."""
    from scipy.optimize import brentq, curve_fit

    nudged = built(_top("nudged_top", L_, G_, TOP_N0, _top_start(1.05 * OMEGA)))
    r = run_ok(nudged, t_end=2.0, dt=1e-3, integrator="rk4p", interval=0.002)
    theta = np.arccos(r["z"] / D)
    # the nudged start's equilibrium angle and its steady precession rate (same p_phi)
    s0 = math.sin(THETA0)
    p_phi = I1P * 1.05 * OMEGA * s0**2 + _a * _c
    phi_d = lambda th: (p_phi - _a * math.cos(th)) / (I1P * math.sin(th)**2)
    accel = lambda th: phi_d(th)**2 * math.sin(th) * math.cos(th) \
        - (_a * phi_d(th) - MASS * G_ * L_) * math.sin(th) / I1P
    th_e = brentq(accel, THETA0 - 0.1, THETA0 + 0.1)
    om_e = phi_d(th_e)
    w_n = math.sqrt(((_a - 2 * I1P * om_e * math.cos(th_e)) / I1P)**2 + (om_e * math.sin(th_e))**2)
    wave = lambda t, m0, A, B, w: m0 + A * np.cos(w * t) + B * np.sin(w * t)
    (m0, A, B, w), _ = curve_fit(wave, r.t, theta, p0=[THETA0, THETA0 - theta.mean(), 0.0, 43.0])
    assert 5e-4 < math.hypot(A, B) < 1e-3
    assert abs(w / w_n - 1) < 1e-6, (w, w_n)
    assert abs(m0 - th_e) < 2e-6
    assert abs(w / (_a / I1P) - 1) > 0.04  # the fast-top estimate is the limit only
