"""Structural damping of flexible beams in systems (flexsym/model/system.py's Damping; the
derivation in assemble.py, efbody.py and sysgen.py; docs/howto/mechanisms.md, "Structural
damping").

The beam of the checks is an aluminium strip (L = 1 m, 20 x 5 mm: EI = 14.6 N m^2, rho A =
0.27 kg/m; clamped-free omega_1 = 25.8 rad/s, omega_2 = 162 rad/s), clamped to ground and
released undeformed under gravity, or spinning freely on a pin."""
from __future__ import annotations

import math
import re

import numpy as np
import pytest
import sympy as sp

from flexsym.apps import api
from flexsym.apps.cli import main
from flexsym.codegen.sysgen import generate_system_files
from flexsym.model.modes import clamped_free_beta
from flexsym.model.system import Damping, FlexibleBeam
from flexsym.physics.assemble import derive_system
from flexsym.toolchain.pipeline import run_system

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "scenes"
RHO, E, A, I, L = 2700.0, 7.0e10, 1.0e-4, 0.02 * 0.005**3 / 12, 1.0
CF = {"strain": "linear", "axial": [], "bending": ["cf1", "cf2"]}  # natural modes: decoupled
EXACT = {"strain": "exact", "axial": [], "bending": ["cf1", "cf2"]}  # the same modes, exact kinematics


def omega(k: int) -> float:
    return float(clamped_free_beta(k))**2 * math.sqrt(E * I / (RHO * A * L**4))


def beam(model, damping=None) -> dict:
    out = {"name": "beam", "kind": "beam", "length": L, "density": RHO, "youngs_modulus": E,
           "area": A, "inertia": I, "model": model}
    if damping is not None:
        out["damping"] = damping
    return out


def cantilever(model, damping, name="cantilever", columns=None):
    """Clamped to ground, released undeformed under gravity: it rings about its static sag."""
    return api.system({
        "system": {"name": name}, "body": [beam(model, damping)], "gravity": {"g": [0.0, -9.81]},
        "joint": [{"name": "root", "kind": "clamp", "parent": "ground", "point": [0, 0],
                   "child": "beam.root"}],
        "output": {"columns": columns or {"v_tip": "v(beam, tip)", "T": "T", "V": "V",
                                          "P": "dissipation"}}})


def energy_balance(r) -> float:
    """max_t |E(t) - E(0) + int_0^t P dt| / int_0^T P dt: E = T + V from the run's columns, P its
    `dissipation` column, the integral by the trapezoidal rule over the rows."""
    E_ = r["T"] + r["V"]
    P = r["P"]
    W = np.concatenate([[0.0], np.cumsum((P[1:] + P[:-1]) / 2 * np.diff(r.t))])
    assert W[-1] > 0.5 * abs(E_).max()  # most of the energy is dissipated: a real test
    return float(np.max(np.abs(E_ - E_[0] + W)) / W[-1])


def decay_rate(t, q, dt: float) -> float:
    """The fitted rate of q's exponential envelope about its mean: the extremes of the rows
    (parabolic refinement of each), the peak-to-peak of successive ones, a line through their
    logarithm (those above 1e-3 of the first)."""
    k = np.flatnonzero((np.diff(np.sign(np.diff(q))) != 0)) + 1  # extremes
    k = k[k < len(q) - 1]
    a, b, c = q[k - 1], q[k], q[k + 1]
    den = a - 2 * b + c
    shift = np.where(den != 0, 0.5 * (a - c) / np.where(den != 0, den, 1), 0.0)
    tk, qk = t[k] + shift * dt, b - 0.25 * (a - c) * shift
    amp = np.abs(np.diff(qk))
    keep = amp > 1e-3 * amp[0]
    return float(-np.polyfit(tk[1:][keep], np.log(amp[keep]), 1)[0])


# ----- the damping the derivation builds ------------------------------------------------------
def test_modal_dissipation_is_the_analytic_damping_matrix():
    """D = 1/2 q'^T C q' with C = beta K + alpha M + diag(2 zeta_i omega_i m_i) on cf1, cf2: for
    the natural modes K_ii = EI beta_i^4 / L^3, m_ii = rho A L (int phi^2 = 1), no coupling."""
    zeta, alpha, beta = (0.02, 0.05), 0.5, 1e-3
    der = derive_system(cantilever(CF, {"zeta": list(zeta), "alpha": alpha, "beta": beta}))
    D = der.dissipation["beam"]
    qd = [sp.Symbol("beam_v_cf1_d", real=True), sp.Symbol("beam_v_cf2_d", real=True)]
    values = {sym: v for _, sym, v in der.params}
    C = sp.hessian(D, qd).xreplace(values)
    m = RHO * A * L
    for i in range(2):
        k = E * I * float(clamped_free_beta(i + 1))**4 / L**3
        want = beta * k + alpha * m + 2 * zeta[i] * omega(i + 1) * m
        assert abs(float(C[i, i]) - want) < 1e-10 * want
    assert abs(float(C[0, 1])) < 1e-10 * float(C[0, 0])
    # damping acts on the elastic coordinates only: f's joint rows never see it
    assert not any(x in D.free_symbols for x in der.q)


def test_zero_damping_adds_nothing():
    """All-zero damping generates the same kernels and system.c as none (fingerprints aside),
    for a modal and an ef body, and an undamped system has no damping kernel."""
    for model in ("m3", {"variant": "ef", "elements": 2}):
        files = [generate_system_files(cantilever(model, d, columns={"v_tip": "v(beam, tip)"}))
                 for d in (None, {"zeta": 0.0, "alpha": 0.0, "beta": 0.0})]
        for name in ("kernels.c", "system.c", "fsm_cantilever.h"):
            a, b = (re.sub(r"[0-9a-f]{64}", "FP", f[name]) for f in files)
            assert a == b, (model, name)
        assert "ef_damping" not in files[0]["kernels.c"] + files[0]["system.c"]


def test_zero_damping_runs_bit_for_bit(tmp_path):
    """A scene with damping = { beta = 0 } writes the same CSV as the scene without it."""
    text = (SCENES / "pendulum.toml").read_text()
    plain, zero = tmp_path / "plain.toml", tmp_path / "zero.toml"
    plain.write_text(text)
    assert text.count('kind = "beam"') == 1
    zero.write_text(text.replace('kind = "beam"', 'kind = "beam"\ndamping = { beta = 0.0 }'))
    for scene in (plain, zero):
        assert main(["run", str(scene), "--t-end", "0.2", "--out", str(tmp_path / f"{scene.stem}.csv")]) == 0
    assert (tmp_path / "plain.csv").read_bytes() == (tmp_path / "zero.csv").read_bytes()


# ----- energy: dE/dt = -P -----------------------------------------------------------------------
@pytest.mark.parametrize("model, damping, dt, tol", [
    (CF, {"zeta": [0.02, 0.05], "alpha": 0.5, "beta": 1e-3}, 5e-4, 1e-4),
    ("m3", {"beta": 1e-3, "zeta": 0.01}, 5e-4, 1e-4),
    ({"variant": "ef", "elements": 4}, {"beta": 1e-3, "alpha": 0.5}, 2.5e-4, 1e-4),
    (EXACT, {"zeta": [0.02, 0.05], "alpha": 0.5, "beta": 1e-3}, 5e-4, 1e-4),
], ids=["cf-zeta-alpha-beta", "m3-beta-zeta", "ef-alpha-beta", "exact-zeta-alpha-beta"])
def test_energy_lost_is_the_damping_power_integrated(model, damping, dt, tol):
    """E(0) - E(t) = int_0^t P dt over 2 s of a cantilever released under gravity (newmark, which
    adds no numerical damping; P = 2 D, the `dissipation` output, from the same D as the
    damping force for modal bodies and by a separate casadi sum of the elements' D for ef).
    Measured: 5.5e-5, 6.0e-5, 1.6e-5, 5.4e-5 of the energy dissipated (order 2 in the step)."""
    r = run_system(cantilever(model, damping), t_end=2.0, dt=dt, integrator="newmark", interval=dt)
    assert r.status == "ok", r.message
    assert energy_balance(r) < tol


@pytest.mark.parametrize("model", [CF, EXACT], ids=["linear", "exact"])
def test_free_vibration_decays_at_the_modal_rate(model):
    """zeta_i on the natural modes cf1, cf2: each coordinate rings about its static value with
    the envelope exp(-zeta_i omega_i t) (log decrement of successive extremes, fitted). With the
    exact kinematics (a 2.3 cm static sag on the 1 m strip) the rates are within 0.2 % too
    (measured: +0.003 % and -0.16 %; the linear model -0.001 % and -0.04 %)."""
    zeta = (0.02, 0.05)
    dt = 2.5e-4
    r = run_system(cantilever(model, {"zeta": list(zeta)}), t_end=3.0, dt=dt, integrator="newmark",
                   interval=dt)
    assert r.status == "ok", r.message
    for i, name in enumerate(("beam_v_cf1", "beam_v_cf2")):
        rate = decay_rate(r.t, r[name], dt)
        want = zeta[i] * omega(i + 1)
        assert abs(rate - want) < 0.01 * want, (name, rate, want)


@pytest.mark.parametrize("model", ["m3", {"variant": "ef", "elements": 4}], ids=["m3", "ef"])
def test_free_spin_keeps_its_angular_momentum(model):
    """A beam on a frictionless pin, spun by a smooth torque pulse (0.1 N m s over 0.1 s) and
    then free: its bending ringing dies out under alpha and beta, but its rigid rotation is
    not damped (alpha acts on the motion relative to the frame): the angular momentum stays
    0.1 N m s, the spin rate settles at H/J (J = rho A L^3 / 3) and T + V at H^2 / (2 J).
    alpha = 0.5 /s on the absolute motion would have lost 1 - exp(-1.45) = 77 % of H."""
    data = {"system": {"name": "spinner"},
            "body": [beam(model, {"alpha": 0.5, "beta": 1e-3})],
            "joint": [{"name": "pin", "kind": "revolute", "parent": "ground", "point": [0, 0],
                       "child": "beam.root"}],
            "driver": [{"name": "kick", "kind": "motor", "joint": "pin",
                        "torque": "ifelse(t < 0.1, 1 - cos(20*pi*t), 0)"}],
            "output": {"columns": {"H": "momentum", "w": "rate(pin)", "v_tip": "v(beam, tip)",
                                   "T": "T", "V": "V"}}}
    r = run_system(api.system(data), t_end=3.0, dt=5e-4, integrator="newmark", interval=5e-4)
    assert r.status == "ok", r.message
    free = r.t > 0.1 + 1e-9
    H, J = 0.1, RHO * A * L**3 / 3
    assert np.max(np.abs(r["H"][free] - H)) < 1e-6 * H  # measured 1e-8 (m3), 6e-8 (ef)
    assert abs(r["w"][-1] - H / J) < 1e-6 * H / J
    assert abs((r["T"] + r["V"])[-1] - H**2 / (2 * J)) < 1e-6 * H**2 / (2 * J)
    ring = lambda a: np.ptp(r["v_tip"][(r.t >= a) & (r.t < a + 0.1)]) / 2
    assert ring(2.8) < 1e-6 * ring(0.1)


# ----- the four-bar: a modal body and its ef reference damp alike -------------------------------
def _ringing(r, period: float) -> np.ndarray:
    """M_mid minus its periodic response to the guided crank (the run's last crank period,
    by phase): what is left of the start's ringing."""
    t, y = r.t, r["M_mid"]
    last = t >= t[-1] - period - 1e-9
    ph = np.mod(t[last], period)
    o = np.argsort(ph)
    return y - np.interp(np.mod(t, period), ph[o], y[last][o], period=period)


def test_four_bar_m3_and_ef_decay_alike():
    """scenes/four_bar_damped.toml (crank at 60 rad/s from t = 0, beta = 1e-4 here) with m3 and
    with ef (8 elements): the envelope of M_mid's ringing (its largest |.| per 50 ms) decays at
    the same rate, about beta omega^2 / 2 = 21 /s (omega ~ 650 rad/s, the coupler's first mode
    in the mechanism): the fitted rates agree within 5 % and each window's envelope within
    10 % (measured: 1.3 % and 3 %)."""
    text = (SCENES / "four_bar_damped.toml").read_text().replace("beta = 6e-5", "beta = 1e-4")
    text = text.replace("t_end = 0.3", "t_end = 0.6")
    assert "beta = 1e-4" in text and "t_end = 0.6" in text
    from flexsym.scenes.system_scene import load_system_scene
    import tomllib

    period = 2 * math.pi / 60.0
    env, rates = {}, {}
    for model in ("m3", "ef"):
        data = tomllib.loads(text)
        if model == "ef":
            data["body"][1]["model"] = {"variant": "ef", "elements": 8}
        scene = load_system_scene(SCENES / "four_bar_damped.toml", data, "four_bar_damped",
                                  None if model == "ef" else model)
        r = api.run(scene)
        assert r.status == "ok", r.message
        g = _ringing(r, period)
        starts = np.arange(0.0, 0.25, 0.05)
        env[model] = np.array([np.abs(g[(r.t >= a) & (r.t < a + 0.05)]).max() for a in starts])
        rates[model] = -np.polyfit(starts, np.log(env[model]), 1)[0]
    assert 15 < rates["m3"] < 30, rates
    assert abs(rates["m3"] - rates["ef"]) < 0.05 * rates["ef"], rates
    assert np.max(np.abs(env["m3"] / env["ef"] - 1)) < 0.10, env


# ----- bad input ---------------------------------------------------------------------------------
BAD = [
    ("negative", "damping = { beta = -1e-4 }", "damping beta = -0.0001 must be a finite number >= 0"),
    ("nan", "damping = { alpha = nan }", "damping alpha must be finite"),
    ("zeta_negative", "damping = { zeta = [0.02, -0.01, 0.02, 0.02, 0.02] }",
     "damping zeta = [0.02, -0.01, 0.02, 0.02, 0.02] must be a finite number >= 0"),
    ("zeta_length", "damping = { zeta = [0.02, 0.03] }",
     "damping zeta has 2 values, model 'geometric_sine' has 5 coordinates (u_static, u_sin1, "
     "v_static, v_cp1, v_cp2)"),
    ("zeta_empty", "damping = { zeta = [] }", "damping zeta has 0 values, model 'geometric_sine'"),
    ("zeta_ef", 'model = { variant = "ef", elements = 4 }\ndamping = { zeta = 0.02 }',
     "damping zeta applies to modal models (a ratio per mode); ef has no modes"),
    ("unknown_key", "damping = { gamma = 0.1 }", "[[body]] 'coupler' damping gamma: unknown key"),
    ("not_a_table", "damping = 0.02", "[[body]] 'coupler' damping: must be a table"),
    ("text", 'damping = { beta = "1e-4" }', "damping beta = '1e-4' must be a finite number >= 0"),
]


@pytest.mark.parametrize("case, line, says", BAD, ids=[b[0] for b in BAD])
def test_bad_damping_refused_in_one_line(tmp_path, capsys, case, line, says):
    text = (SCENES / "four_bar_damped.toml").read_text()
    old = [ln for ln in text.splitlines() if ln.startswith("damping = ")]
    assert len(old) == 1
    if case == "zeta_ef":
        text = text.replace('model = "m2"', "#")
    scene = tmp_path / f"{case}.toml"
    scene.write_text(text.replace(old[0], line))
    rc = main(["run", str(scene), "--out", str(tmp_path / "out.csv")])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.count("\n") == 1 and err.startswith(f"flexsym: error: {scene}: "), err
    assert says in err, err
    assert not (tmp_path / "out.csv").exists()


def test_damping_in_python_is_checked_the_same():
    """FlexibleBeam(..., damping=Damping(...)) goes through the same check as a scene's key."""
    from dataclasses import replace

    from flexsym.core.errors import SpecError
    from flexsym.model.library import pendulum_system
    from flexsym.model.variant import builtin

    s = pendulum_system(builtin("m3"))
    b = s.bodies[0]
    assert isinstance(b, FlexibleBeam) and b.damping is None
    ok = replace(s, bodies=(replace(b, damping=Damping(zeta=(0.01, 0.02, 0.03), beta=1e-5)),))
    api.system(ok)
    with pytest.raises(SpecError, match="damping zeta has 2 values, model 'foreshortening' has 3"):
        api.system(replace(s, bodies=(replace(b, damping=Damping(zeta=(0.01, 0.02))),)))
    with pytest.raises(SpecError, match=r"damping alpha = -1.0 must be a finite number >= 0"):
        api.system(replace(s, bodies=(replace(b, damping=Damping(alpha=-1.0)),)))
