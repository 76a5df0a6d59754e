"""The spin-up through the C runtime: divergence of #0, boundedness of #1-#3, integrator
agreement and order."""
import numpy as np
import pytest



def test_linear_variant_diverges_at_6_rad_s_and_says_when(simulate, tmp_path):
    out = tmp_path / "m0.csv"
    r = simulate("m0", t_end=20.0, dt=1e-3, integrator="genalpha", params={"ws": 6, "ts": 15}, out=out)
    assert r.status == "diverged"
    assert "diverged at t = " in r.message and "runaway growth" in r.message
    t_stop = r.summary["t_stop"]
    # theta' passes the first bending frequency (3.8 rad/s) at t ~ 8.6 s; growth follows.
    assert 8.6 < t_stop < 12.0
    # The message names the time of the failed step, one step after the last accepted one.
    t_fail = float(r.message.split("t = ")[1].split(" s")[0])
    assert abs(t_fail - (t_stop + 1e-3)) < 1e-6
    # What was computed up to then is kept in the file.
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert data.shape[0] == r.data.shape[0] > 900
    assert abs(data[-1, 0] - t_stop) < 0.011
    assert np.all(np.isfinite(data))


def test_linear_variant_bounded_at_2_rad_s(simulate):
    r = simulate("m0", t_end=20.0, dt=1e-3, params={"ws": 2, "ts": 15})
    assert r.ok, r.message
    assert np.max(np.abs(r["v_tip"])) < 0.5


@pytest.mark.parametrize("name", ["geometric", "geometric_sine", "foreshortening"])
def test_stiffened_variants_bounded_at_6_rad_s(simulate, name):
    r = simulate(name, t_end=20.0, dt=1e-3, params={"ws": 6, "ts": 15})
    assert r.ok, r.message
    assert r.t[-1] == pytest.approx(20.0)
    v = r["v_tip"]
    assert np.max(np.abs(v)) < 1.0
    # The tip lags during spin-up (negative v) and settles near zero at constant speed.
    assert np.min(v) < -0.3
    assert np.max(np.abs(v[r.t > 15])) < 0.05


def _on_grid(r, every=0.1):
    idx = np.flatnonzero(np.isclose(np.mod(r.t + 1e-9, every), 0, atol=1e-6))
    return r.t[idx], r["v_tip"][idx]


def test_rk4_and_generalized_alpha_agree_on_foreshortening(simulate):
    kw = dict(t_end=20.0, params={"ws": 6, "ts": 15})
    a = simulate("m3", integrator="rk4", dt=1e-3, **kw)
    b = simulate("m3", integrator="genalpha", dt=2.5e-4, out_every=40, **kw)
    ta, va = _on_grid(a)
    tb, vb = _on_grid(b)
    assert np.array_equal(np.round(ta, 6), np.round(tb, 6))
    assert np.max(np.abs(va - vb)) < 1e-6


@pytest.mark.parametrize("integrator,order,steps", [
    ("rk4", 4, (0.005, 0.0025, 0.00125)),  # coarser steps are pre-asymptotic (omega dt ~ 1)
    ("genalpha", 2, (0.01, 0.005, 0.0025)),
    ("newmark", 2, (0.01, 0.005, 0.0025)),
])
def test_convergence_order(simulate, integrator, order, steps):
    kw = dict(t_end=20.0, params={"ws": 6, "ts": 15})
    ref = simulate("m3", integrator="rk4", dt=0.02 / 128, out_every=128, **kw)
    tr, vr = _on_grid(ref)
    errors = []
    for dt in steps:
        r = simulate("m3", integrator=integrator, dt=dt, out_every=int(round(0.02 / dt)), **kw)
        t, v = _on_grid(r)
        assert np.array_equal(np.round(t, 6), np.round(tr, 6))
        errors.append(np.max(np.abs(v - vr)))
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(rates - order) < 0.3), (errors, rates)
