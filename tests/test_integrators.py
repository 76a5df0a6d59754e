"""Integrators of the C runtime beyond the spin-up physics: dopri5 (order, error control,
dense output on the output grid), refusal of unstable explicit steps, modified Newton
against full Newton, and radau5 (order, agreement with RK4, its Newton stopping test, stiff
modes at large steps)."""
import numpy as np
import pytest

from flexsym.apps.cli import main

SPIN = dict(params={"ws": 6, "ts": 15})


@pytest.fixture(scope="module")
def m3_reference(simulate):
    """#3 with RK4 at dt = 0.02/128: error ~1e-15 m (RK4 is at 2e-8 m for dt = 0.01)."""
    return simulate("m3", integrator="rk4", dt=0.02 / 128, out_every=64, t_end=20.0, **SPIN)


def _error(r, ref):
    """max |v_tip - v_tip(ref)| over the rows of r (all on the reference's grid)."""
    return np.max(np.abs(r.minus(ref)))


def test_dopri5_fixed_steps_have_order_5(simulate, m3_reference):
    errors = []
    for dt in (0.01, 0.005, 0.0025):
        r = simulate("m3", integrator="dopri5", tol=0, dt=dt, out_every=int(round(0.02 / dt)),
                     t_end=20.0, **SPIN)
        assert r.ok and r.summary["rejected_steps"] == 0 and r.summary["steps"] == round(20 / dt)
        errors.append(_error(r, m3_reference))
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(rates - 5) < 0.3), (errors, rates)


def test_dopri5_error_follows_tolerance_and_agrees_with_rk4(simulate, m3_reference):
    """Adaptive steps: the error falls in proportion to tol; rows stay on the output grid
    (dense output between steps); accepted and rejected steps are reported."""
    errors = []
    for tol in (1e-6, 1e-8):
        r = simulate("m3", integrator="dopri5", tol=tol, dt=0.01, out_every=1, t_end=20.0, **SPIN)
        assert r.ok, r.message
        assert np.allclose(r.t, np.linspace(0, 20, 2001), atol=1e-12, rtol=0)
        s = r.summary
        assert s["accepted_steps"] == s["steps"] > 0 and s["rejected_steps"] >= 0
        assert s["h_max"] > 0.01  # steps longer than the output interval: rows interpolated
        errors.append(_error(r, m3_reference))
    assert errors[1] < 1e-6  # agrees with RK4 (dt = 0.02/128)
    decades = np.log10(errors[0] / errors[1]) / 2
    assert 0.7 < decades < 1.3, errors


def test_dopri5_gives_up_clearly(simulate, tmp_path):
    out = tmp_path / "m1.csv"
    r = simulate("m1", integrator="dopri5", tol=1e-6, dt=0.01, t_end=20.0, max_steps=200, out=out, **SPIN)
    assert r.status == "failed"
    assert "dopri5 gave up at t = " in r.message and "after 200 steps" in r.message
    assert "omega_max = 836.7 rad/s" in r.message  # the axial mode limits the step
    assert r.summary["accepted_steps"] + r.summary["rejected_steps"] == 200
    rows = np.loadtxt(out, delimiter=",", skiprows=1, ndmin=2)
    assert rows.shape[0] == r.data.shape[0] >= 1 and rows[-1, 0] <= r.summary["t_stop"] + 1e-12


def test_rk4_above_the_stability_limit_is_refused(simulate):
    r = simulate("m1", integrator="rk4", dt=5e-3, t_end=20.0, **SPIN)
    assert r.status == "failed"
    assert r.message == ("rk4 step 5 ms exceeds the stability limit 3.33 ms of this model "
                         "(omega_max = 836.7 rad/s); use --dt <= 3.3e-3 or an implicit integrator")
    assert r.summary["steps"] == 0
    ok = simulate("m1", integrator="rk4", dt=3e-3, t_end=20.0, **SPIN)
    assert ok.ok, ok.message
    assert ok.summary["omega_max"] == pytest.approx(836.66, abs=0.01)
    assert np.max(np.abs(ok["v_tip"])) < 1.0


def test_stability_limit_includes_centrifugal_stiffening(simulate):
    """#3: 68.7 rad/s at rest, 72.8 rad/s at 6 rad/s; dt = 0.04 s is stable only at rest."""
    r = simulate("m3", integrator="rk4", dt=0.04, t_end=20.0, **SPIN)
    assert r.status == "failed" and "omega_max = 72.8 rad/s" in r.message
    slow = simulate("m3", integrator="rk4", dt=0.04, t_end=1.0, params={"ws": 0.0, "ts": 15})
    assert slow.ok and slow.summary["omega_max"] == pytest.approx(68.73, abs=0.01)


def test_fox_goodwin_newmark_is_checked_against_its_stability_limit(simulate, m3_reference):
    """Newmark beta = 1/12 (below gamma/2 = 1/4: stable for omega_max dt <= sqrt(6)) is refused
    above its limit like rk4, from the same omega_max (#3 spinning: 72.8 rad/s, limit 33.7 ms);
    below it, its fourth-order period error makes it far more accurate than the trapezoidal
    beta = 1/4 (measured 7.8e-8 m at 20 ms against 1.1e-5 m at 5 ms)."""
    r = simulate("m3", integrator="newmark", newmark_beta=1 / 12, dt=0.04, t_end=20.0, **SPIN)
    assert r.status == "failed" and r.summary["steps"] == 0
    assert r.message == ("newmark step 40 ms exceeds the stability limit 33.7 ms of this model "
                         "(omega_max = 72.8 rad/s); use --dt <= 3.3e-2 or a larger --newmark-beta")
    fg = simulate("m3", integrator="newmark", newmark_beta=1 / 12, dt=0.02, out_every=1, t_end=20.0, **SPIN)
    trap = simulate("m3", integrator="newmark", dt=0.005, out_every=4, t_end=20.0, **SPIN)
    assert fg.ok and trap.ok, (fg.message, trap.message)
    assert _error(fg, m3_reference) < 1e-2 * _error(trap, m3_reference)
    assert trap.summary["omega_max"] == 0  # not estimated for an unconditionally stable method


def test_cli_refuses_unstable_rk4_with_exit_code_3(capsys):
    code = main(["run", "m1", "--integrator", "rk4", "--dt", "5e-3", "--t-end", "1"])
    err = capsys.readouterr().err
    assert code == 3
    assert "rk4 step 5 ms exceeds the stability limit 3.33 ms" in err and "--dt <= 3.3e-3" in err


def test_cli_runs_dopri5_with_tol(capsys, tmp_path):
    out = tmp_path / "m3.csv"
    code = main(["run", "m3", "--integrator", "dopri5", "--tol", "1e-7", "--dt", "0.05",
                 "--t-end", "2", "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert np.allclose(data[:, 0], np.linspace(0, 2, 41))


@pytest.mark.parametrize("integrator,name,dt,t_end,fewer", [
    ("genalpha", "m1", 5e-3, 2.0, 20), ("genalpha", "ef", 1e-3, 1.0, 20),
    ("radau5", "m3", 0.25, 20.0, 3), ("radau5", "m1", 0.2, 20.0, 3), ("radau5", "ef", 0.1, 20.0, 3)])
def test_modified_newton_matches_full_newton(simulate, integrator, name, dt, t_end, fewer):
    """The stopping test of modified Newton delivers the tolerance (1e-11 m per step): it stays
    within 1e-9 m of Newton with the exact matrix at every iteration (radau5 over the whole
    spin-up), on the configuration-dependent mass (#3), the stiff axial mode (#1) and the
    banded ef, with far fewer iteration matrices."""
    kw = dict(integrator=integrator, dt=dt, t_end=t_end, out_every=1, **SPIN)
    full = simulate(name, newton="full", **kw)
    mod = simulate(name, newton="modified", **kw)
    assert full.ok and mod.ok
    # displacements and coordinates (m, or slopes); not the stress resultants (N, N m)
    for c in [c for c in full.columns[1:] if not c.startswith(("N_", "M_"))]:
        assert np.max(np.abs(mod[c] - full[c])) < 1e-9, c
    assert mod.summary["jacobian_evaluations"] < full.summary["jacobian_evaluations"] / fewer


# ------------------------------------------------------------------------------- radau5

@pytest.mark.parametrize("name", ["m3", "m1"])
def test_radau5_has_order_5(simulate, name):
    """Halving the step. A short horizon (2 s) and steps with omega h <= 1.5 for the bending
    modes (73 rad/s): at 0.04 s and above the rates are pre-asymptotic (3-4). Newton is
    converged far below the errors (newton_tol 1e-15), the reference is RK4 at 1e-4 s."""
    kw = dict(t_end=2.0, **SPIN)
    ref = simulate(name, integrator="rk4", dt=1e-4, out_every=200, **kw)
    errors = []
    for dt in (0.02, 0.01, 0.005):
        r = simulate(name, integrator="radau5", dt=dt, out_every=round(0.02 / dt), newton_tol=1e-15, **kw)
        assert r.ok, r.message
        errors.append(_error(r, ref))
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(rates - 5) < 0.3), (errors, rates)


def test_radau5_agrees_with_rk4_on_foreshortening(simulate, m3_reference):
    """#3 (configuration-dependent mass) over the whole spin-up: radau5 at 50 ms against RK4
    at 0.16 ms; at 250 ms it is still within 1e-4 m, with 80 steps."""
    r = simulate("m3", integrator="radau5", dt=0.05, out_every=1, t_end=20.0, **SPIN)
    assert r.ok and r.summary["steps"] == 400
    assert _error(r, m3_reference) < 1e-6
    coarse = simulate("m3", integrator="radau5", dt=0.25, out_every=1, t_end=20.0, **SPIN)
    assert coarse.ok and _error(coarse, m3_reference) < 1e-4


def test_radau5_damps_the_stiff_axial_modes(simulate):
    """#2's axial modes (762 and 2660 rad/s) at steps of 0.5 and 1 s (omega dt up to 2660):
    L-stability damps them, the axial stretch follows its quasi-static value, the run stays
    bounded. Reference: RK4 at 0.5 ms (its stability limit is 1.05 ms)."""
    ref = simulate("m2", integrator="rk4", dt=5e-4, out_every=1000, t_end=20.0, **SPIN)
    for dt in (0.5, 1.0):
        r = simulate("m2", integrator="radau5", dt=dt, out_every=1, t_end=20.0, **SPIN)
        assert r.ok, r.message
        assert np.max(np.abs(r["v_tip"])) < 1.0
        assert np.max(np.abs(r.minus(ref, "u_tip"))) < 2e-6  # of 5.2e-4 m
        if dt == 0.5:
            assert np.max(np.abs(r.minus(ref, "v_tip"))) < 5e-3
            assert np.max(np.abs(r.minus(ref, "N_A"))) < 2.0  # of 2000 N


def test_radau5_dense_output_between_steps(simulate, m3_reference):
    """--step sets radau5's step, rows stay every dt, from the collocation polynomial: at the
    steps they are the rows of the plain run, in between the error of the 20 s spin-up at
    0.25 s steps stays at the 1e-4 m level it has at the steps (5.1e-5 m measured)."""
    kw = dict(integrator="radau5", t_end=20.0, out_every=1, **SPIN)
    at_steps = simulate("m3", dt=0.25, **kw)
    dense = simulate("m3", step=0.25, dt=0.01, **kw)
    assert dense.ok and dense.summary["steps"] == 80 and len(dense.t) == 2001
    assert np.allclose(dense.t, np.linspace(0.0, 20.0, 2001), atol=1e-12, rtol=0)
    assert np.max(np.abs(dense["v_tip"][::25] - at_steps["v_tip"])) < 1e-14
    assert _error(dense, m3_reference) < 1e-4


@pytest.mark.parametrize("name", ["m3", "m1"])
def test_radau5_dense_output_has_order_4(simulate, name):
    """Between steps the polynomial of degree 3 through the stage points: error O(h^4) (stage
    order 3, plus one for the interpolation). Rows every 1 ms, the steps' own rows left out;
    measured rates 3.8 and 4.5."""
    kw = dict(t_end=2.0, **SPIN)
    ref = simulate(name, integrator="rk4", dt=1e-4, out_every=10, **kw)
    errors = []
    for h in (0.04, 0.02, 0.01):
        r = simulate(name, integrator="radau5", step=h, dt=1e-3, out_every=1, newton_tol=1e-15, **kw)
        between = np.abs(r.t / h - np.round(r.t / h)) > 1e-6
        errors.append(np.max(np.abs(r.minus(ref))[between]))
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(rates > 3.5), (errors, rates)


def test_step_is_refused_for_other_integrators(capsys):
    code = main(["run", "m3", "--integrator", "genalpha", "--step", "0.1", "--t-end", "1"])
    assert code == 2
    assert "--step: applies to radau5, not to integrator genalpha" in capsys.readouterr().err


def test_cli_runs_radau5(capsys, tmp_path):
    out = tmp_path / "m3.csv"
    code = main(["run", "m3", "--integrator", "radau5", "--dt", "0.25", "--t-end", "2", "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert np.allclose(data[:, 0], np.linspace(0, 2, 9))
    code = main(["run", "m3", "--integrator", "radau5", "--step", "0.25", "--dt", "0.05",
                 "--t-end", "2", "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert np.allclose(data[:, 0], np.linspace(0, 2, 41))
