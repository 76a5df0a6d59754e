"""S6 `spherical_pendulum` (a ball joint's Euler parameters, tumbling) and S7
`spatial_slider_crank` (a closed spatial loop): conservation laws, rigid limits, the
constrained integrators, the assembly from rounded values, the 3D picture. A file of its own
so that its builds run beside test_spatial.py's (pytest-xdist hands a file to one process)."""
import subprocess
import sys
import tomllib

import numpy as np
import pytest

from flexsym.scenes.system_scene import system_from_dict
from system_data import built, run_ok
from test_spatial import S6, S7

# ----- S6 spherical_pendulum: a ball joint (Euler parameters on |e| = 1), tumbling
S6_EXTRA = {"T": "T", "V": "V", "Hz": "Hz", "viol": "violation", "w_q": "w(strip, 0.3)"}


def _s6_data(**columns) -> dict:
    data = tomllib.loads(S6.read_text())
    data["output"]["columns"] |= columns
    return data


@pytest.fixture(scope="module")
def s6_with_geometry():
    """S6 with the checks' columns and the picture's (one build shared by every S6 test and by
    the CLI run of the same scene text: S6_EXTRA)."""
    from flexsym.analysis.system_plot import with_plot_outputs
    from flexsym.toolchain.pipeline import prepare_system

    system, geometry = with_plot_outputs(system_from_dict(_s6_data(**S6_EXTRA), name="spherical_pendulum"))
    return prepare_system(system, log=lambda m: None), geometry


@pytest.fixture(scope="module")
def s6(s6_with_geometry):
    return s6_with_geometry[0]


def test_s6_conserves_energy_and_vertical_angular_momentum(s6):
    """Gravity is vertical and the joint force acts at the pivot: T + V and the angular
    momentum about the vertical through the joint are conserved. With genalpha3, T + V keeps
    its start (the spin's 1/2 (m L^2/3) 4^2) to 8.5e-7 and 1.8e-7 of it at 0.1 and 0.05 ms
    (order 2), Hz to 1.9e-7 and 6.2e-8; Hz(0) is the rigid strip's (m L^2/3) 4; |e| = 1 holds
    to round-off."""
    m = 2700 * 1e-4 * 1.0
    T0 = 0.5 * (m / 3) * 4.0**2
    errs = []
    for dt in (1e-4, 5e-5):
        r = run_ok(s6, t_end=2.0, dt=dt, integrator="genalpha3")
        errs.append(np.abs(r["T"] + r["V"] - T0).max() / T0)
        assert np.abs(r["Hz"] - r["Hz"][0]).max() < 5e-7 * r["Hz"][0]
        assert np.abs(r["viol"]).max() < 1e-14
    assert r["Hz"][0] == pytest.approx((m / 3) * 4.0, rel=1e-12)
    assert errs[1] < 5e-7 and 3.0 < errs[0] / errs[1] < 6.0
    assert r["z_tip"].min() < -0.7  # it falls as it swings round


def test_s6_rigid_limit_is_the_spherical_pendulum_of_a_rod(s6):
    """E, G x 100 and x 10^4: the tip follows the rigid uniform rod on a ball joint, n'' =
    (3/2L)(g - (g.n) n) - |n'|^2 n from n = (1, 0, 0), n' = (0, 4, 0) (scipy, 1e-12), within
    1.1e-5 m and 1.1e-7 m over 2 s: the flexible difference falls as 1/E."""
    from scipy.integrate import solve_ivp

    g = np.array([0.0, 0.0, -9.81])

    def rod(t, y):
        n, nd = y[:3], y[3:]
        return np.concatenate([nd, 1.5 * (g - g.dot(n) * n) - nd.dot(nd) * n])

    ref = solve_ivp(rod, (0, 2), [1, 0, 0, 0, 4, 0], rtol=1e-12, atol=1e-12, dense_output=True)
    errs = []
    for k in (1e2, 1e4):
        r = run_ok(s6, t_end=2.0, dt=5e-5, integrator="genalpha3", params={"E": 7e10 * k, "G": 2.6e10 * k})
        tip = np.column_stack([r["x_tip"], r["y_tip"], r["z_tip"]])
        errs.append(np.abs(tip - ref.sol(r.t)[:3].T).max())
    assert errs[1] < 3e-7
    assert 50 < errs[0] / errs[1] < 200


def test_s6_bends_and_twists_and_runs_with_the_other_constrained_integrators(s6):
    """The strip bends across its thickness (My, w_mid) far more than across its width and
    twists a little; rk4p and ali3p (with full Newton: its modified Newton crawls near the
    tolerance here with a stale matrix, docs/theory/spatial.md) give the same motion."""
    r = run_ok(s6, t_end=0.5, dt=1e-4, integrator="genalpha3")
    assert np.abs(r["M_y_mid"]).max() > np.abs(r["M_z_mid"]).max() > 0
    assert 0 < np.abs(r["T_mid"]).max() < 0.01 * np.abs(r["M_y_mid"]).max()
    for integrator, extra in (("rk4p", {}), ("ali3p", {"newton": "full"})):
        o = run_ok(s6, t_end=0.5, dt=1e-4, integrator=integrator, **extra)
        assert np.abs(o["z_tip"] - r["z_tip"]).max() < 1e-4, integrator


def test_spatial_plot_is_a_3d_view_of_the_run(s6_with_geometry, tmp_path):
    """--plot on a spatial scene: the stations' ground x, y, z become columns, and the chord
    distance the picture scales is the output w(B, x) at the same station (3D, unsigned)."""
    from flexsym.analysis.system_plot import chord_distance

    s6, geometry = s6_with_geometry
    assert all(len(cols) == 3 and cols[2].startswith("pz_") for cols in geometry["strip"])
    r = run_ok(s6, t_end=0.2, dt=1e-4, integrator="genalpha3")
    k = len(r.t) // 2
    stations = np.array([[r[c][k] for c in cols] for cols in geometry["strip"]])
    assert chord_distance(stations)[3] == pytest.approx(r["w_q"][k], rel=1e-9)
    assert r["w_q"][k] > 0
    scene, png = tmp_path / "s6.toml", tmp_path / "s6.png"
    extra = "".join(f', {c} = "{q}"' for c, q in S6_EXTRA.items())
    text = S6.read_text().replace('T_mid = "Mx(strip, mid)" }', 'T_mid = "Mx(strip, mid)"' + extra + " }")
    assert extra in text  # the same system as the fixture's: its build is reused
    scene.write_text(text.replace("t_end = 2.0", "t_end = 0.2"))
    run = subprocess.run([sys.executable, "-m", "flexsym.apps.cli", "run", str(scene), "--out",
                          str(tmp_path / "s6.csv"), "--plot", str(png)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# ----- S7 spatial_slider_crank: a closed spatial loop (ball joint, universal joint, slider)


@pytest.fixture(scope="module")
def s7():
    data = tomllib.loads(S7.read_text())
    data["output"]["columns"] |= {"viol": "violation", "phi": "angle(crank_joint)"}
    return built(data)


def _x_rigid(phi, r=0.1, L=0.3):
    return r * np.cos(phi) + np.sqrt(L**2 - (0.05 - r * np.sin(phi))**2 - 0.15**2)


def test_s7_holds_its_loop_and_tends_to_the_rigid_slider_crank(s7):
    """The loop (ball joint at the crank pin, universal joint at the slider, |e| = 1) holds to
    round-off (violation 6e-16 of the size); stiffened (E, G x 100, x 10^4) the slider follows
    the rigid closed form x_s = r cos(phi) + sqrt(L^2 - (0.05 - r sin(phi))^2 - 0.15^2) within
    1.6e-7 m and 1.5e-9 m (1/E), and the rod's axial force at mid-span, set by the rigid
    motion's inertia, no longer changes (3e-5 of its 237 N peak between the two)."""
    errs, N = [], []
    for k in (1e2, 1e4):
        r = run_ok(s7, t_end=0.3, dt=1e-5, integrator="genalpha3", params={"E": 2e11 * k, "G": 7.7e10 * k})
        assert np.abs(r["viol"]).max() < 1e-13
        errs.append(np.abs(r["x_s"] - _x_rigid(r["phi"])).max())
        N.append(r["N_mid"])
    assert errs[1] < 1e-8 and 50 < errs[0] / errs[1] < 200
    assert np.abs(N[0] - N[1]).max() < 1e-3 * np.abs(N[1]).max()
    assert np.abs(N[1]).max() > 100  # the slider's inertia really loads the rod


def test_s7_violation_output_is_the_largest_constraint_row():
    """The violation output (assemble.violation: a nest of Piecewise built on placeholders,
    then the rows put in) is max_i |Phi_i| / L at states off the loop, its rows those of the
    derivation: sympy evaluates both at random states, independently of casadi and the C."""
    from flexsym.physics.spatial import derive_spatial

    data = tomllib.loads(S7.read_text())
    data["output"]["columns"] = {"viol": "violation"}
    der = derive_spatial(system_from_dict(data, name="s7"))
    rows = [phi for _, phi in der.constraints]
    assert len(rows) == 5
    rng = np.random.default_rng(7)
    scale = next(v for n, _, v in der.params if n == "L")
    for _ in range(4):
        state = {x: rng.uniform(-0.5, 0.5) for x in sorted(set().union(*(r.free_symbols for r in rows)), key=str)}
        state |= {sym: v for _, sym, v in der.params}  # the coordinates random, the parameters the scene's
        values = [abs(float(r.xreplace(state))) for r in rows]
        assert max(values) > 1e-3  # off the loop: the rows are not all zero
        assert float(der.outputs["viol"].xreplace(state)) == pytest.approx(max(values) / scale, rel=1e-13)


def test_s7_constrained_integrators_agree(s7):
    """genalpha3, rk4p and ali3p give the same slider motion and axial force: measured 8.5e-9 m
    and 5e-4 of the peak N (rk4p), 5.8e-10 m and 3.5e-5 (ali3p). ali3p failed at t = 0.25 s
    (Newton) when its recursion's velocity defect, a mode at -1 of the trapezoidal rule, was
    left undamped: it grew like exp(100 t/s) here (docs/theory/spatial.md)."""
    ref = run_ok(s7, t_end=0.3, dt=1e-5, integrator="genalpha3")
    assert np.abs(ref["viol"]).max() < 1e-13
    for integrator, tol_x, tol_n in (("rk4p", 1e-7, 2e-3), ("ali3p", 1e-8, 2e-4)):
        r = run_ok(s7, t_end=0.3, dt=1e-5, integrator=integrator)
        assert r.t[-1] == pytest.approx(0.3)
        assert np.abs(r["viol"]).max() < 1e-12, integrator
        assert np.abs(r["x_s"] - ref["x_s"]).max() < tol_x, integrator
        assert np.abs(r["N_mid"] - ref["N_mid"]).max() < tol_n * np.abs(ref["N_mid"]).max(), integrator


def _s7_rounded() -> dict:
    """S7 as a user writes it: the slider's start and the rod's direction rounded."""
    data = tomllib.loads(S7.read_text())
    for j in data["joint"]:
        if j["name"] == "slide":
            j["initial"] = 0.355
        elif j["name"] == "ball":
            j["direction"] = [0.255, 0.05, 0.15]
    data["output"]["columns"] |= {"viol": "violation", "phi": "angle(crank_joint)"}
    return data


def test_s7_assembles_from_rounded_values():
    """The assembly at t = 0 closes the loop on the slider and the ball joint's direction (two
    tilts across it), bodies undeformed: from 0.355 m and [0.255, 0.05, 0.15] it finds the
    closed start to 2e-16 (m, and in the unit direction), and says what it moved."""
    from flexsym.scenes.system_scene import checked_system, system_from_data

    system, report = checked_system(system_from_data(_s7_rounded(), "s7: ", "spatial_slider_crank")[0])
    joints = {j.name: j for j in system.joints}
    assert abs(joints["slide"].initial - 0.3549509756796393) < 1e-15
    d = np.array(joints["ball"].direction)
    assert np.linalg.norm(d / np.linalg.norm(d) - np.array([0.25495097567963926, 0.05, 0.15]) / 0.3) < 1e-15
    assert report.line().startswith("assembly: joint slide moved -4.9e-05 m to 0.3549509757, joint ball "
                                    "direction turned 8.61e-05 rad to [0.2549863831, 0.05000694396, "
                                    "0.1500208319] (loop residual ")


@pytest.mark.study  # a second S7 build (its start is compiled in)
def test_s7_from_rounded_values_gives_the_same_rows(s7):
    """The rows of the assembled rounded start are the exact start's: x_s and w_mid within 1e-9
    of their peaks (measured 2e-12, 7.5e-11), N_mid within 1e-6 (4.4e-8: the stiff axial
    force at the Newton tolerance's floor)."""
    kw = dict(t_end=0.3, dt=1e-5, integrator="genalpha3")
    ref, rounded = run_ok(s7, **kw), run_ok(built(_s7_rounded()), **kw)
    for col, tol in (("x_s", 1e-9), ("w_mid", 1e-9), ("N_mid", 1e-6)):
        assert np.abs(rounded[col] - ref[col]).max() <= tol * np.abs(ref[col]).max(), col


def test_s7_loop_that_cannot_close_is_refused(tmp_path):
    """A slider axis out of the rod's reach: one line naming the joint, before anything is
    derived, nothing written (rates a loop cannot take: tests/test_spatial_velocity.py)."""
    text = S7.read_text()
    assert text.count("point = [0.0, 0.05, 0.15]") == 1
    scene = tmp_path / "s7.toml"
    scene.write_text(text.replace("point = [0.0, 0.05, 0.15]", "point = [0.0, 0.5, 0.15]"))
    out = tmp_path / "out.csv"
    r = subprocess.run([sys.executable, "-m", "flexsym.apps.cli", "run", str(scene), "--out", str(out)],
                       capture_output=True, text=True)
    assert r.returncode == 2, r.stderr
    assert r.stderr.count("\n") == 1, r.stderr
    assert "joint 'cardan' (cut joint, closes a loop): cannot close at t = 0" in r.stderr
    assert not out.exists()
