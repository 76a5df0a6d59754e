"""Constrained integrators ali3p, genalpha3 and rk4p (runtime_c/src/ali3p.c, genalpha3.c, rk4p.c) on
hand-written planar models in relative coordinates with cut joints (tests/c_models: a rigid
slider-crank, a four-bar under gravity, a parallelogram with a redundant bar), built with the
runtime's driver as models that define their accessor fsm_<fixture>_model() themselves, and on a generated
one-beam model without constraints (nc = 0)."""
from __future__ import annotations

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

from flexsym.toolchain.build import find_cmake, find_compiler

C_MODELS = Path(__file__).parent / "c_models"
METHODS = ("ali3p", "genalpha3")  # the second-order ones
ALL_METHODS = METHODS + ("rk4p",)


@pytest.fixture(scope="module")
def runners(tmp_path_factory):
    build = tmp_path_factory.mktemp("c_models")
    for cmd in ([find_cmake(), "-S", str(C_MODELS), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release",
                 f"-DCMAKE_C_COMPILER={find_compiler()}"],
                [find_cmake(), "--build", str(build), "-j", "2"]):
        proc = subprocess.run(cmd, capture_output=True, text=True)
        assert proc.returncode == 0, proc.stdout + proc.stderr
    return build


def run(runners, fixture, out, **opts):
    """Run a fixture's driver; returns (exit code, JSON summary, stderr, rows or None)."""
    cmd = [str(runners / f"flexsym_{fixture}"), "--out", str(out)]
    for key, value in opts.items():
        if key == "energy":
            cmd.append("--energy")
        elif key == "param":
            for name, v in value.items():
                cmd += ["--param", f"{name}={v!r}"]
        else:
            cmd += [f"--{key.replace('_', '-')}", str(value)]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    data = np.genfromtxt(out, delimiter=",", names=True) if out.exists() else None
    return proc.returncode, json.loads(proc.stdout or "{}"), proc.stderr, data


def slider_crank_exact():
    """x_s(t) = r cos(phi) + sqrt(l^2 - r^2 sin^2 phi) and its second derivative, phi the
    paper's profile P(t; 150 rad/s, 0.1 s) (the fixture's defaults)."""
    t = sp.Symbol("t")
    r, l, ws, ts = sp.Rational(15, 100), sp.Rational(3, 10), 150, sp.Rational(1, 10)
    ramp = ws / ts * (t**2 / 2 + (ts / (2 * sp.pi))**2 * (sp.cos(2 * sp.pi * t / ts) - 1))
    funcs = []
    for phi in (ramp, ws * (t - ts / 2)):
        x = r * sp.cos(phi) + sp.sqrt(l**2 - r**2 * sp.sin(phi)**2)
        funcs.append((sp.lambdify(t, x, "numpy"), sp.lambdify(t, sp.diff(x, t, 2), "numpy")))

    def at(tt, k):
        return np.where(tt <= 0.1, funcs[0][k](tt), funcs[1][k](tt))

    return (lambda tt: at(tt, 0)), (lambda tt: at(tt, 1))


@pytest.mark.parametrize("method", ALL_METHODS)
def test_slider_crank_follows_the_closed_form(runners, tmp_path, method):
    """Rigid slider-crank, crank guided through the paper's spin-up to 150 rad/s: the slider
    position is the closed form to the Newton tolerance, the cut joint's violation stays below
    1e-10 of the mechanism's size at every row, and the multiplier of the slider pin's x
    equation is the force that accelerates the slider (m_s x_s''), to the integration error."""
    code, summary, err, d = run(runners, "slider_crank", tmp_path / "sc.csv", integrator=method,
                                dt=1e-4, t_end=0.3, out_every=10)
    assert code == 0, err
    x_exact, a_exact = slider_crank_exact()
    t = d["t"]
    assert len(t) == 301 and t[-1] == pytest.approx(0.3)  # a row every 1 ms
    assert np.abs(d["x_s"] - x_exact(t)).max() < 1e-11  # m; Newton tolerance 4.5e-13 m
    assert d["violation"].max() < 1e-10
    assert d["violation"][1:].max() > 0.0  # computed, not a constant
    force = 0.0334 * a_exact(t)
    peak = np.abs(force).max()
    assert peak == pytest.approx(169.0, rel=0.01)
    # measured at dt = 0.1 ms: ali3p 2.5e-11 (the projection's 1/kappa), genalpha3 7.4e-5 of
    # the peak (integration error), rk4p 1.4e-12 (the multipliers of the index-1 solve)
    tol = {"ali3p": 1e-9, "genalpha3": 3e-4, "rk4p": 1e-10}[method]
    assert np.abs(d["lambda_x"] - force)[1:].max() < tol * peak


def test_assembly_that_cannot_close_is_refused(runners, tmp_path):
    """Crank at 90 degrees and a rod shorter than the crank: the rod's end cannot reach the
    slider's guide. One line naming the constraint, exit 2, no rows."""
    code, summary, err, d = run(runners, "slider_crank", tmp_path / "bad.csv",
                                param={"l": 0.1, "phi0": np.pi / 2}, integrator="ali3p")
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1
    # the rod's end stays 0.05 m (r - l) from the guide at best
    assert lines[0] == ("flexsym runtime: assembly cannot close at t = 0: constraint slider_pin.y is "
                        "off by 0.0503 at best (0.112 x the length scale 0.45 m) after 50 Newton "
                        "iterations")
    assert summary == {} and d is None  # refused before any work: no summary, no file
    # the same rod at phi0 = 0 closes
    code, _, err, d = run(runners, "slider_crank", tmp_path / "ok.csv", param={"l": 0.1}, t_end=0.01,
                          integrator="ali3p")
    assert code == 0, err
    assert d["x_s"][0] == pytest.approx(0.25, abs=1e-13)


def test_todays_integrators_refuse_a_model_with_constraints(runners, tmp_path):
    code, summary, err, d = run(runners, "fourbar", tmp_path / "x.csv", integrator="genalpha", t_end=0.1)
    assert code == 2 and d is None
    assert err.strip() == ("flexsym runtime: genalpha: this model has 2 constraint equations: use ali3p, "
                           "genalpha3 or rk4p")


@pytest.mark.parametrize("method", METHODS)
def test_fourbar_conserves_energy(runners, tmp_path, method):
    """A four-bar falling under gravity (its crank turns over): total energy is conserved to the
    integration error, which falls as dt^2; the violation stays below 1e-10 of the size."""
    drift = []
    for dt in (1e-3, 5e-4):
        code, _, err, d = run(runners, "fourbar", tmp_path / "fb.csv", integrator=method, dt=dt,
                              t_end=2.0, out_every=round(0.01 / dt), energy=True)
        assert code == 0, err
        assert d["violation"].max() < 1e-10
        assert np.ptp(d["psi1"]) > 5.0  # it moves: the crank turns over
        drift.append(np.abs(d["h"] - d["h"][0]).max())
    scale = np.ptp(d["V"])  # 0.6 J exchanged between V and T
    assert scale > 0.5
    assert drift[1] < 1e-4 * scale  # measured 2.3e-5 J at 0.5 ms (both methods)
    assert 3.0 < drift[0] / drift[1] < 5.5  # order 2


def parallelogram_reference(t, psi0, a=0.4, l=0.2, rho=1.0, g=9.81):
    """The parallelogram's one degree of freedom: three cranks (pinned at an end) and a
    translating coupler, (3 m_k l^2 / 3 + m_c l^2) psi'' = -g cos(psi) (3 m_k l / 2 + m_c l)."""
    mk, mc = rho * l, rho * a
    inertia, moment = 3 * mk * l**2 / 3 + mc * l**2, g * (1.5 * mk * l + mc * l)
    sol = solve_ivp(lambda _, y: [y[1], -moment / inertia * np.cos(y[0])], (0.0, t[-1]), [psi0, 0.0],
                    t_eval=t, method="DOP853", rtol=1e-12, atol=1e-12)
    return sol.y[0]


@pytest.mark.parametrize("method", ALL_METHODS)
def test_redundant_closed_loop(runners, tmp_path, method):
    """Parallelogram with a redundant middle bar (4 constraint equations of rank 3): it runs,
    the violation stays below 1e-10, and the motion is the one-degree-of-freedom pendulum it
    must be (all cranks parallel, the coupler level)."""
    code, summary, err, d = run(runners, "parallelogram", tmp_path / "pg.csv", integrator=method,
                                dt=5e-4, t_end=2.0, out_every=20)
    assert code == 0, err
    assert d["violation"].max() < 1e-10
    ref = parallelogram_reference(d["t"], d["psi1"][0])
    assert np.ptp(ref) > 0.9  # swings +-0.5 rad about hanging
    assert np.abs(d["psi1"] - ref).max() < 1e-5  # rad, O(dt^2); measured 8.2e-6 (both methods)
    for col in ("psi2", "psi3"):
        assert np.abs(d[col] - d["psi1"]).max() < 1e-11
    assert np.abs(d["psi1"] + d["beta"]).max() < 1e-11


def test_orders_and_agreement(runners, tmp_path):
    """Both methods converge at order 2 in the step on the four-bar (crank angle over 0.5 s,
    against each method's own run at dt = 1/16000 s) and agree with each other there."""
    def psi(method, dt):
        code, _, err, d = run(runners, "fourbar", tmp_path / "o.csv", integrator=method, dt=dt,
                              t_end=0.5, out_every=round(0.01 / dt))
        assert code == 0, err
        return d["psi1"]

    refs = {}
    for method in METHODS:
        refs[method] = psi(method, 1 / 16000)
        errs = np.array([np.abs(psi(method, dt) - refs[method]).max()
                         for dt in (5e-3, 2.5e-3, 1.25e-3, 6.25e-4)])
        orders = np.log2(errs[:-1] / errs[1:])
        assert np.all((orders > 1.8) & (orders < 2.4)), (method, errs, orders)
    # at 1/16000 s each is within ~5e-7 rad of the limit (order 2 from the errors above)
    assert np.abs(refs["ali3p"] - refs["genalpha3"]).max() < 2e-7


def test_rk4p_is_of_order_four_and_agrees_with_ali3p(runners, tmp_path):
    """rk4p (RK4 on the index-1 form, positions and velocities projected after each step)
    converges at order 4 on the four-bar (crank angle over 0.5 s against its own run at
    dt = 1/16000 s), keeps the violation below 1e-10 of the size at every row, and agrees with
    ali3p at the small step to ali3p's own error (order 2: ~5e-7 rad there)."""
    def run_fb(method, dt):
        code, _, err, d = run(runners, "fourbar", tmp_path / "o4.csv", integrator=method, dt=dt,
                              t_end=0.5, out_every=round(0.01 / dt))
        assert code == 0, err
        assert d["violation"].max() < 1e-10
        return d["psi1"]

    ref = run_fb("rk4p", 1 / 16000)
    errs = np.array([np.abs(run_fb("rk4p", dt) - ref).max() for dt in (1e-2, 5e-3, 2.5e-3, 1.25e-3)])
    orders = np.log2(errs[:-1] / errs[1:])  # measured 4.26, 4.35, 4.23
    assert np.all((orders > 3.7) & (orders < 4.6)), (errs, orders)
    assert np.abs(ref - run_fb("ali3p", 1 / 16000)).max() < 2e-6  # measured 7.6e-7 rad


def test_rk4p_refuses_a_step_above_its_stability_limit(runners, tmp_path):
    """An explicit method: a step above 2.785 / omega_max (omega_max on the constraint manifold
    at t = 0: 10.0 rad/s for the four-bar under gravity) is refused with the largest step that
    is not."""
    code, _, err, _ = run(runners, "fourbar", tmp_path / "u.csv", integrator="rk4p", dt=0.5, t_end=1.0)
    assert code == 3
    assert ("rk4p step 500 ms exceeds the stability limit 277 ms of this model (omega_max = 10.0 "
            "rad/s on the constraint manifold at t = 0); use --dt <= 2.7e-1 or ali3p") in err


def test_tree_model_runs_with_every_integrator(runners, tmp_path):
    """A model given as a struct without constraints or guided joints (nc = 0, nd = 1: the
    rigid compound pendulum released horizontally) runs with today's integrators too. At a
    quarter of the period from the complete elliptic integral, T = 4 sqrt(2 l / 3 g) K(1/2),
    the bar hangs straight down: psi = -pi/2."""
    from scipy.special import ellipk

    quarter = float(np.sqrt(2 * 1.0 / (3 * 9.81)) * ellipk(0.5))
    psi = {}
    for method, dt in (("rk4", 1e-3), ("dopri5", 1e-3), ("radau5", 1e-2), ("genalpha", 1e-3),
                       ("genalpha3", 1e-3), ("newmark", 1e-3), ("ali3p", 1e-3),
                       ("rk4p", 1e-3)):
        code, summary, err, d = run(runners, "pendulum", tmp_path / "p.csv", integrator=method, dt=dt,
                                    t_end=repr(quarter), tol=1e-10 if method == "dopri5" else 1e-6)
        assert code == 0, err
        assert d["t"][-1] == quarter
        psi[method] = d["psi"]
        # measured: 2e-12 (rk4), 4e-12 (dopri5), 1.3e-11 (radau5); 2.2e-6 rad (second order)
        assert abs(d["psi"][-1] + np.pi / 2) < (1e-10 if method in ("rk4", "dopri5", "radau5", "rk4p") else 3e-6)
    assert np.abs(psi["genalpha"] - psi["genalpha3"]).max() < 1e-10
    assert np.abs(psi["newmark"] - psi["ali3p"]).max() < 1e-10
    assert np.abs(psi["rk4"] - psi["rk4p"]).max() < 1e-12  # nc = 0: rk4p is RK4


@pytest.mark.parametrize("method", ALL_METHODS)
def test_stepper_rows_equal_the_run(runners, method):
    """fsr_stepper (an FMU's doStep) gives fsr_simulate's rows bit for bit, advanced one grid
    point at a time and three at a time (tests/c_models/stepper_check.c)."""
    proc = subprocess.run([str(runners / "stepper_check_fourbar"), method, "0.001", "0.5"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert json.loads(proc.stdout) == {"rows": 501, "compared": 668, "differ": 0}


@pytest.mark.parametrize("method,plain", [("ali3p", "newmark"), ("genalpha3", "genalpha")])
def test_without_constraints_the_methods_are_the_plain_ones(simulate, method, plain):
    """On a generated one-beam model (nc = 0, through the runtime's adapter) ali3p is the
    trapezoidal rule (Newmark 1/2, 1/4) and genalpha3 is generalized-alpha: with full Newton
    they give the same v_tip to rounding, and the rows have no violation column."""
    kw = dict(t_end=20.0, dt=0.01, out_every=10, newton="full")
    a, b = simulate("m3", integrator=method, **kw), simulate("m3", integrator=plain, **kw)
    assert a.ok and b.ok, (a.message, b.message)
    assert a.columns == b.columns and "violation" not in a.columns
    assert np.abs(a["v_tip"]).max() > 0.5
    assert np.abs(a["v_tip"] - b["v_tip"]).max() < 1e-12


@pytest.mark.parametrize("method", ALL_METHODS)
def test_blowup_bounds_a_constrained_run_at_lengths_not_angles(runners, tmp_path, method):
    """--blowup stops ali3p and genalpha3 too, at blowup x the length scale (0.45 m) on the
    coordinates that are lengths: the slider's s (0.45 m at t = 0) beyond 0.5 x 0.45 m; the rod
    angle beta, exempt, passes 4.5 rad in the run of the default limit (the closed-form test)."""
    code, _, err, d = run(runners, "slider_crank", tmp_path / "b.csv", integrator=method,
                          dt=1e-4, t_end=0.01, blowup=0.5)
    assert code == 3, err
    assert "|s| = 0.45" in err and "exceeds 0.5 x L = 0.225 m" in err


def test_fox_goodwin_newmark_has_fourth_order_on_the_pendulum(runners, tmp_path):
    """Newmark with beta = 1/12 (Fox-Goodwin; its position recursion is Numerov's) is of order
    4 for M q'' = f(q) such as the compound pendulum, against order 2 for beta = 1/4; both end at
    0.48 s (a whole number of each step) against rk4 at 0.1 ms (error ~1e-15 rad)."""
    def psi_end(dt, **opts):
        code, _, err, d = run(runners, "pendulum", tmp_path / "p.csv", dt=dt, t_end=0.48, **opts)
        assert code == 0, err
        return d["psi"][-1]

    ref = psi_end(1e-4, integrator="rk4")
    errs = {beta: np.array([abs(psi_end(dt, integrator="newmark", newmark_beta=beta) - ref)
                            for dt in (0.04, 0.02, 0.01)])
            for beta in (repr(1 / 12), "0.25")}
    fg, trap = np.log2(errs[repr(1 / 12)][:-1] / errs[repr(1 / 12)][1:]), np.log2(errs["0.25"][:-1] / errs["0.25"][1:])
    assert np.all(np.abs(fg - 4) < 0.3) and np.all(np.abs(trap - 2) < 0.3), (errs, fg, trap)
