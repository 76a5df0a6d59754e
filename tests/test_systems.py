"""Systems (issue 10): derivation of tree systems against today's one-beam derivation, physics of
S1 (hub) and S3 (pendulum), generated C against casadi against sympy."""
import random

import pytest

from flexsym.physics.assemble import derive_system
from flexsym.codegen.derive import derive
from flexsym.physics.energy import BEAM_PARAMS, alpha, w
from dataclasses import replace

from flexsym.model.variant import builtin, customize
from flexsym.model.library import spin_up_system

PARAMS = {p.symbol: p.default for p in BEAM_PARAMS}


@pytest.mark.parametrize("variant", ["m3", "prestress"])
def test_s0_equations_equal_todays_variant(variant):
    """S0 (one beam, root revolute guided by the spin-up) gives today's M, f and outputs: the
    generalised kinetic density with a frame at rest in translation reduces to today's."""
    spec = builtin(variant)  # the one-beam variant: M from the modes' curvature (the paper's)
    old = derive(spec)
    new = derive_system(spin_up_system(replace(spec, moment="constitutive")))
    theta, rate, acc = new.guided[0].symbols
    rnd = random.Random(7)
    vals = dict(PARAMS)
    for a, b in zip(list(old.q) + list(old.qd) + list(old.qdd), list(new.q) + list(new.qd) + list(new.qdd)):
        vals[a] = vals[b] = rnd.uniform(-0.5, 0.5)
    vals |= {w: 1.3, rate: 1.3, alpha: 0.7, acc: 0.7, theta: 0.2}
    for a, b in ((old.numeric(old.M), new.M), (old.numeric(old.f), new.f)):
        a, b = a.xreplace(vals), b.xreplace(vals)
        scale = max(abs(float(x)) for x in a)
        assert max(abs(float(x - y)) for x, y in zip(a, b)) <= 1e-14 * scale
    for name in ("v_tip", "M_A"):
        a = float(old.numeric(old.outputs[name]).xreplace(vals))
        assert float(new.outputs[name].xreplace(vals)) == pytest.approx(a, rel=1e-14)
    # a mechanism's default, M from equilibrium (assemble._equilibrium_stress: the frame's
    # motion read from the system's kinematics) against the one-beam --moment equilibrium
    # (outputs._equilibrium_M, written for the guided hub): two derivations, one value
    old_eq = derive(customize(spec, moment="equilibrium", outputs="v_tip,M_A"))
    new_eq = derive_system(spin_up_system(spec))
    assert new_eq.system.bodies[0].model.moment == "equilibrium"
    for name in ("M_A",):
        a = float(old_eq.numeric(old_eq.outputs[name]).xreplace(vals))
        assert abs(a) > 1.0
        assert float(new_eq.outputs[name].xreplace(vals)) == pytest.approx(a, rel=1e-12)


def test_s0_generated_system_runs_as_todays_m3():
    """The one-body system through system.h (generated fsm_system struct) against today's
    generated m3 through the adapter: the same rows (20 s spin-up, generalized-alpha)."""
    from flexsym.toolchain.pipeline import prepare
    from flexsym.toolchain.run import run_built
    from flexsym.toolchain.pipeline import prepare_system

    spec = builtin("m3")
    kw = dict(t_end=20.0, dt=1e-3)
    today = run_built(prepare(spec, log=lambda m: None), **kw)
    system = run_built(prepare_system(spin_up_system(replace(spec, moment="constitutive"))), **kw)
    assert today.ok and system.ok
    assert abs(today["v_tip"] - system["v_tip"]).max() <= 1e-9
    assert abs(today["M_A"] - system["M_A"]).max() <= 1e-9 * abs(today["M_A"]).max()


# ----- S1 hub (motor torque on a free hub) and S3 pendulum (gravity), with today's integrators
import math
from dataclasses import replace

import numpy as np

from flexsym.model.system import Output
from flexsym.model.library import hub_system, pendulum_system

J_TOTAL = 40.0 + 3000 * 4e-4 * 10.0**3 / 3  # J_h + rho A L^3 / 3 (hub + rigid beam)


def _spin_up(t, ws=6.0, ts=15.0):
    """theta_P and its rate, mechanisms.md's profile P(t; 6 rad/s, 15 s)."""
    ramp = t <= ts
    theta = np.where(ramp, ws / ts * (t**2 / 2 + (ts / (2 * np.pi))**2 * (np.cos(2 * np.pi * t / ts) - 1)),
                     ws * (t - ts / 2))
    rate = np.where(ramp, ws / ts * (t - ts / (2 * np.pi) * np.sin(2 * np.pi * t / ts)), ws)
    return theta, rate


@pytest.fixture(scope="module")
def hub_built():
    from flexsym.toolchain.pipeline import prepare_system

    system = hub_system(builtin("m3"))
    return prepare_system(replace(system, outputs=system.outputs + (Output("H", "momentum"),)))


@pytest.fixture(scope="module")
def pendulum_built():
    from flexsym.toolchain.pipeline import prepare_system

    system = pendulum_system(builtin("m3"))
    extra = (Output("T", "T"), Output("V", "V"), Output("theta", "angle(pin)"))
    return prepare_system(replace(system, outputs=system.outputs + extra))


def test_s1_angular_momentum_equals_torque_impulse(hub_built):
    """H (angular momentum about the axis, integrated over the bodies independently of the
    equations of motion) = int tau dt = J_total theta_P'(t); 2.4e-9 of the peak measured at
    dt = 1 ms, 5.9e-10 at 0.5 ms (order 2)."""
    from flexsym.toolchain.run import run_built

    errs = []
    for dt in (1e-3, 5e-4):
        r = run_built(hub_built, t_end=20.0, dt=dt)
        assert r.ok
        errs.append(np.abs(r["H"] - J_TOTAL * _spin_up(r.t)[1]).max() / (J_TOTAL * 6.0))
    assert errs[0] < 1e-8
    assert 3.0 < errs[0] / errs[1] < 5.0


def test_s1_rigid_limit_follows_theta_p(hub_built):
    """EI -> infinity: the hub follows the manoeuvre the torque was designed for; the lag falls
    as 1/E (measured 4.9e-4 rad at 100 E, 5.0e-6 rad at 10^4 E)."""
    from flexsym.toolchain.run import run_built

    lag = []
    for E in (7e12, 7e14):
        r = run_built(hub_built, t_end=20.0, dt=1e-3, params={"E": E})
        assert r.ok
        lag.append(np.abs(r["theta_h"] - _spin_up(r.t)[0]).max())
    assert lag[1] < 1e-5
    assert 80 < lag[0] / lag[1] < 120


def test_s3_energy_conserved(pendulum_built):
    """Pendulum released horizontal: T + V = 0 (V = 0 at release); measured 1.7e-8 of m g L/2
    at dt = 0.1 ms with generalized-alpha (1.3e-6 at 1 ms: order 2)."""
    from flexsym.toolchain.run import run_built

    r = run_built(pendulum_built, t_end=2.0, dt=1e-4)
    assert r.ok
    scale = 2700 * 1e-4 * 1.0 * 9.81 / 2
    assert np.abs(r["T"] + r["V"]).max() < 1e-7 * scale
    assert r["V"].min() < -0.9 * scale  # it really swings through the bottom


def test_s3_rigid_limit_is_the_compound_pendulum(pendulum_built):
    """EI -> infinity: period 4 sqrt(2L/3g) K(1/2) of a 90-degree release (1.93333 s); from the
    two passages through the bottom. Measured -1.8e-7 relative at 10^4 E (7.6e-5 at E)."""
    from scipy.special import ellipk

    from flexsym.toolchain.run import run_built

    r = run_built(pendulum_built, t_end=2.0, dt=1e-4, params={"E": 7e14})
    y, t = r["theta"] + np.pi / 2, r.t
    k = np.nonzero(np.sign(y[:-1]) != np.sign(y[1:]))[0]
    crossings = t[k] - y[k] * (t[k + 1] - t[k]) / (y[k + 1] - y[k])
    period = 2 * (crossings[1] - crossings[0])
    reference = 4 * math.sqrt(2 * 1.0 / (3 * 9.81)) * ellipk(0.5)
    assert period == pytest.approx(reference, rel=1e-6)


def test_system_kernels_c_casadi_sympy(hub_built, system_kernels_agree):
    """S1's generated C kernels against their casadi functions against the sympy expressions."""
    from flexsym.physics.assemble import derive_system

    system = hub_system(builtin("m3"))
    system = replace(system, outputs=system.outputs + (Output("H", "momentum"),))
    system_kernels_agree(derive_system(system), hub_built, t=1.7, seed=3)


# ----- S2 slider-crank: a cut joint (the rod's tip pinned to the slider), ali3p and genalpha3
def _x_rigid(t, r=0.15, l=0.3):
    phi = np.where(t <= 0.1, 150 / 0.1 * (t**2 / 2 + (0.1 / (2 * np.pi))**2 * (np.cos(2 * np.pi * t / 0.1) - 1)),
                   150 * (t - 0.05))
    return r * np.cos(phi) + np.sqrt(l**2 - r**2 * np.sin(phi)**2)


@pytest.fixture(scope="module")
def slider_crank_built():
    from flexsym.toolchain.pipeline import prepare_system
    from flexsym.model.library import slider_crank_system

    system = slider_crank_system(builtin("m3"))
    extra = (Output("T", "T"), Output("V", "V"), Output("tau", "torque(crank_drive)"),
             Output("omega", "rate(crank_joint)"))
    return prepare_system(replace(system, outputs=system.outputs + extra))


def test_s2_constrained_integrators_agree_and_hold_the_loop(slider_crank_built):
    """ali3p and genalpha3 on the flexible slider-crank (#3 rod): constraint violation at
    round-off (max |Phi| / length_scale 5e-15 measured), the two methods within 6.6e-9 m (x_s) and 1.6e-7 m (w_mid)
    at 0.1 ms, 4x closer at half the step (order 2)."""
    from flexsym.toolchain.run import run_built

    diffs = []
    for dt in (1e-4, 5e-5):
        a = run_built(slider_crank_built, t_end=0.3, dt=dt, integrator="ali3p")
        b = run_built(slider_crank_built, t_end=0.3, dt=dt, integrator="genalpha3")
        assert a.ok and b.ok
        for r in (a, b):
            assert r["violation"].max() <= 1e-10  # max |Phi| / length_scale (0.3 m, the rod)
        diffs.append(np.abs(a["w_mid"] - b["w_mid"]).max())
        assert np.abs(a["x_s"] - b["x_s"]).max() < 1e-8
    assert np.abs(a["w_mid"]).max() > 3e-3  # the rod really bends (peak 3.9 mm)
    assert 3.0 < diffs[0] / diffs[1] < 5.0


def test_s2_rk4p_agrees_with_ali3p(slider_crank_built):
    """rk4p (fourth order, index-1 form with projections) at 0.2 ms, below its stability limit
    (0.241 ms: omega_max 1.15e4 rad/s, the rod's highest mode) against ali3p: the difference
    falls 4x with ali3p's step (ali3p's order-2 error), and against ali3p extrapolated from 0.1
    and 0.05 ms (Richardson, order 2) it is 2.4e-7 m of w_mid (peak 3.9 mm) and 5.8e-9 m of x_s
    (measured); the violation stays below 1e-10 of the size at every row."""
    from flexsym.toolchain.run import run_built

    r = run_built(slider_crank_built, t_end=0.3, dt=2e-4, integrator="rk4p")
    a = [run_built(slider_crank_built, t_end=0.3, dt=dt, integrator="ali3p") for dt in (1e-4, 5e-5)]
    assert r.ok and all(x.ok for x in a), r.message
    assert r["violation"].max() <= 1e-10
    for col, tol in (("w_mid", 4e-7), ("x_s", 2e-8)):
        d = [np.abs(r[col] - x[col]).max() for x in a]
        assert 3.5 < d[0] / d[1] < 5.0, (col, d)
        assert np.abs(r[col] - (4 * a[1][col] - a[0][col]) / 3).max() < tol, col


def test_s2_rigid_limit_is_the_closed_form(slider_crank_built):
    """EI -> infinity: x_s = r cos(phi) + sqrt(l^2 - r^2 sin^2 phi) (1.4e-4 m away at the real
    E, 1.2e-8 m at 100 E: the slider feels the rod's shortening, quadratic in its bending)."""
    from flexsym.toolchain.run import run_built

    r = run_built(slider_crank_built, t_end=0.3, dt=1e-4, integrator="ali3p", params={"E": 2e13})
    assert r.ok
    assert np.abs(r["x_s"] - _x_rigid(r.t)).max() < 1e-7


def test_s2_energy_balance_with_the_drivers_work(slider_crank_built):
    """T + V - (T + V)(0) = int tau theta' dt, tau = torque(crank_drive): the generalised force
    the guided crank needs (with the cut joint's multipliers). The mismatch is the step's and
    the trapezoidal quadrature's: measured 4.3e-5 of max(T + V) at 0.1 ms, 4x less at 0.05 ms."""
    from flexsym.toolchain.run import run_built

    errs = []
    for dt in (1e-4, 5e-5):
        r = run_built(slider_crank_built, t_end=0.3, dt=dt, integrator="ali3p", interval=dt)
        assert r.ok
        energy, power = r["T"] + r["V"], r["tau"] * r["omega"]
        work = np.concatenate([[0.0], np.cumsum((power[1:] + power[:-1]) / 2 * np.diff(r.t))])
        errs.append(np.abs(energy - energy[0] - work).max() / np.abs(energy).max())
    assert errs[0] < 1e-4
    assert 3.0 < errs[0] / errs[1] < 5.0


def test_spring_damper_on_a_prismatic_joint():
    """A block on a prismatic joint to ground with a spring-damper (both forms: l0 = 0, and
    l0 > 0 from a ground point one length away) against the damped oscillator's closed form
    x = x0 e^(-z w t) (cos w_d t + z / sqrt(1 - z^2) sin w_d t); 7.6e-9 m measured (0.1 ms)."""
    from flexsym.toolchain.pipeline import run_system
    from flexsym.model.system import Joint, Marker, RigidBody, SpringDamper, System

    m, k, c, x0 = 2.0, 50.0, 2.0, 0.1
    wn = math.sqrt(k / m)
    z = c / (2 * math.sqrt(k * m))
    wd = wn * math.sqrt(1 - z * z)
    for spring in (SpringDamper("ground", "block.c", k, c, 0.0),
                   SpringDamper("ground", "block.c", k, c, 1.0, point_a=(-1.0, 0.0))):
        system = System("oscillator", bodies=(RigidBody("block", m, 0.01, markers=(Marker("c", 0.0),)),),
                        joints=(Joint("slide", "prismatic", "ground", "block.c", axis=(1.0, 0.0),
                                      initial=x0),),
                        loads=(spring,), outputs=(Output("x", "x(block.c)"),))
        r = run_system(system, t_end=2.0, dt=1e-4)
        exact = x0 * np.exp(-z * wn * r.t) * (np.cos(wd * r.t) + z / math.sqrt(1 - z * z) * np.sin(wd * r.t))
        assert r.ok and np.abs(r["x"] - exact).max() < 1e-7


# ----- ef bodies in systems (ANCF in the floating frame of the tree joint)
def test_s0_ef_system_equals_todays_ef():
    """The one-body system with an ef beam (4 elements) against today's ef_n4 on the spin-up:
    max |dv_tip| 1.0e-11 m measured (different assembly and rounding of the stiff axial dofs)."""
    from flexsym.toolchain.pipeline import prepare
    from flexsym.toolchain.run import run_built
    from flexsym.model.variant import customize
    from flexsym.toolchain.pipeline import prepare_system

    ef = customize(builtin("ef"), elements=4)
    kw = dict(t_end=20.0, dt=1e-3)
    today = run_built(prepare(ef, log=lambda m: None), **kw)
    curvature = replace(ef, moment="constitutive")  # the one-beam ef's M_A; a system's: equilibrium
    system = run_built(prepare_system(spin_up_system(curvature)), **kw)
    assert today.ok and system.ok
    assert abs(today["v_tip"] - system["v_tip"]).max() <= 1e-9
    assert abs(today["M_A"] - system["M_A"]).max() <= 1e-8 * abs(today["M_A"]).max()


def test_s3_ef_conserves_energy_and_agrees_with_m3(pendulum_built):
    """S3 with a 4-element ef beam: T + V conserved (2.0e-8 of m g L/2 measured at 0.1 ms); its
    w_mid peak within 5 % of #3's (measured 0.1 % with 4 elements; with 8 and 16 elements ef's
    peak settles 1.9 % above #3's. The vibration's phase drifts apart over 2 s, so only peaks
    are compared)."""
    from flexsym.toolchain.run import run_built
    from flexsym.model.variant import customize
    from flexsym.toolchain.pipeline import prepare_system

    system = pendulum_system(customize(builtin("ef"), elements=4))
    system = replace(system, outputs=system.outputs + (Output("T", "T"), Output("V", "V")))
    ef = run_built(prepare_system(system), t_end=2.0, dt=1e-4)
    m3 = run_built(pendulum_built, t_end=2.0, dt=1e-4)
    assert ef.ok and m3.ok
    scale = 2700 * 1e-4 * 1.0 * 9.81 / 2
    assert np.abs(ef["T"] + ef["V"]).max() < 1e-7 * scale
    assert np.abs(ef["w_mid"]).max() == pytest.approx(np.abs(m3["w_mid"]).max(), rel=0.05)
