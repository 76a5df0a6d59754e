"""Systems (issue 10): derivation of tree systems against today's one-beam derivation, physics of
S1 (hub) and S3 (pendulum), generated C against casadi against sympy."""
import random

import pytest
import sympy as sp

from flexsym.assemble import derive_system
from flexsym.derive import derive
from flexsym.energy import BEAM_PARAMS, alpha, w
from flexsym.spec import builtin
from flexsym.systems_library import spin_up_system

PARAMS = {p.symbol: p.default for p in BEAM_PARAMS}


@pytest.mark.parametrize("variant", ["m0", "m2", "m3", "prestress"])
def test_s0_equations_equal_todays_variant(variant):
    """S0 (one beam, root revolute guided by the spin-up) gives today's M, f and outputs: the
    generalised kinetic density with a frame at rest in translation reduces to today's."""
    spec = builtin(variant)
    old, new = derive(spec), derive_system(spin_up_system(spec))
    theta, rate, acc = new.guided[0].symbols
    rnd = random.Random(7)
    vals = dict(PARAMS)
    for a, b in zip(list(old.q) + list(old.qd), list(new.q) + list(new.qd)):
        vals[a] = vals[b] = rnd.uniform(-0.5, 0.5)
    vals |= {w: 1.3, rate: 1.3, alpha: 0.7, acc: 0.7, theta: 0.2}
    for a, b in ((old.numeric(old.M), new.M), (old.numeric(old.f), new.f)):
        a, b = a.xreplace(vals), b.xreplace(vals)
        scale = max(abs(float(x)) for x in a)
        assert max(abs(float(x - y)) for x, y in zip(a, b)) <= 1e-14 * scale
    for name in ("v_tip", "M_A"):
        a = float(old.numeric(old.outputs[name]).xreplace(vals))
        assert float(new.outputs[name].xreplace(vals)) == pytest.approx(a, rel=1e-14)


def test_s0_generated_system_runs_as_todays_m3():
    """The one-body system through system.h (generated fsm_system struct) against today's
    generated m3 through the adapter: the same rows (20 s spin-up, generalized-alpha)."""
    from flexsym.pipeline import prepare
    from flexsym.run import run_built
    from flexsym.sysgen import prepare_system

    spec = builtin("m3")
    kw = dict(t_end=20.0, dt=1e-3)
    today = run_built(prepare(spec, log=lambda m: None), **kw)
    system = run_built(prepare_system(spin_up_system(spec)), **kw)
    assert today.ok and system.ok
    assert abs(today["v_tip"] - system["v_tip"]).max() <= 1e-9
    assert abs(today["M_A"] - system["M_A"]).max() <= 1e-9 * abs(today["M_A"]).max()
