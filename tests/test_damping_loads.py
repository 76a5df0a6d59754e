"""The loads of a beam's mass-proportional (alpha) and modal (zeta) dampers in its section forces
from equilibrium and in its joints' reactions. Those dampers act on the beam's motion relative
to its frame (a generalised force -dD/dq' on its elastic coordinates), so the part of the beam
beyond a section, and the beam as a whole, carry their load -rho A (u_w, v_w): for a modal beam
the one load in its modes' span that does that virtual work (w = M^-1 dD/dq'), for ef the
force -alpha rho A r'. Before, both left it out: on a damped cantilever the root moment and the
clamp's reaction were 4-5 % of their peaks off (zeta = 0.05)."""
import random

import numpy as np
import pytest
import sympy as sp

from flexsym.core.errors import SpecError
from flexsym.model.system import FlexibleBeam, Section
from flexsym.model.variant import builtin, customize
from flexsym.physics.efbody import ef_part
from flexsym.physics.energy import A, I, L, E, rho
from flexsym.scenes.system_scene import system_from_dict
from system_data import built, run_ok

STRIP = {"name": "strip", "kind": "beam", "length": 0.5, "density": 7850.0,
         "youngs_modulus": 2.1e11, "area": 4.0e-5, "inertia": 1.3333e-11}


def _cantilever(model, damping: dict) -> dict:
    """A strip clamped to ground, released undeformed under gravity (every mode rings)."""
    return {"system": {"name": "damped_cantilever"},
            "body": [STRIP | {"model": model, "damping": damping}],
            "joint": [{"name": "fix", "kind": "clamp", "parent": "ground", "point": [0.0, 0.0],
                       "child": "strip.root"}],
            "gravity": {"g": [0.0, -9.81]},
            "output": {"interval": 1e-3, "columns": {
                "M_root": "M(strip, root)", "M_mid": "M(strip, 0.25)", "N_mid": "N(strip, 0.25)",
                "M_c": "reaction(fix, moment)", "Fy": "reaction(fix, y)"}}}


@pytest.mark.parametrize("damping", [{"zeta": 0.05}, {"alpha": 4.2}], ids=["zeta", "alpha"])
def test_a_one_mode_cantilevers_loads_follow_its_coordinate(damping):
    """One natural mode (cf1, the linear strain model): m q'' + c q' + k q = f_g, and every
    section force and reaction is then an affine function of q alone (the modal inertia and
    damping add up to f_g - k q): the damper's load belongs in the balance. Measured: affine
    within 5e-16 of each peak; without the dampers' load the root moment was 4.5e-2 of its peak
    away from affine, with zeta = 0.05 and alpha = 4.2 1/s (2 zeta omega_1) alike."""
    model = {"strain": "linear", "axial": ["sin1"], "bending": ["cf1"]}
    r = run_ok(built(_cantilever(model, damping)), integrator="genalpha", dt=1e-4, t_end=0.3,
               out_every=10)
    q = r["strip_v_cf1"]
    fit = np.vstack([q, np.ones_like(q)]).T
    assert np.ptp(q) > 0.5 * np.abs(q).max()  # it rings
    for column in ("M_root", "M_mid", "M_c", "Fy"):
        y = r[column]
        coef = np.linalg.lstsq(fit, y, rcond=None)[0]
        assert np.abs(fit @ coef - y).max() <= 1e-12 * np.abs(y).max(), column
    assert np.abs(r["M_root"] + r["M_c"]).max() <= 1e-12 * np.abs(r["M_c"]).max()


def test_ef_damping_load_is_the_elements_damping_force_on_rigid_motions():
    """ef: the force -alpha int rho A r' and its moment about the root (EfPart.damping_load,
    sympy, exact per element) against the element dissipation sysgen generates (casadi:
    g = dD/de' per element) on a rigid translation and a rigid rotation of every node, at
    random states of a 3-element beam: F . d = -sum g . de (d a translation), M = -sum g . de
    (de the rotation's: (-y, x, -y_x, x_x) per node)."""
    import casadi as ca

    from flexsym.codegen.sysgen import _ef_damping_element

    beam = FlexibleBeam("b", 0.5, Section(rho=7850.0, E=2.1e11, A=4.0e-5, I=1.3333e-11),
                        customize(builtin("ef"), elements=3))
    part = ef_part(beam, {})
    alpha = sp.Rational(7, 2)
    F, M = part.damping_load(alpha)
    e, ed, pe, c, D = _ef_damping_element()
    g = ca.Function("g", [e, ed, pe, c], [ca.gradient(D, ed)])
    rng = random.Random(3)
    values = {rho: 7850.0, A: 4.0e-5, L: 0.5, E: 2.1e11, I: 1.3333e-11}
    for _ in range(3):
        values |= {s: rng.uniform(-0.05, 0.05) for s in list(part.q.values()) + list(part.qd.values())}
        nodes = [[float(sp.sympify(v).xreplace(values)) for v in n] for n in part.nodes(part.q)]
        rates = [[float(sp.sympify(v).xreplace(values)) for v in n] for n in part.rates()]
        force, moment = np.zeros(2), 0.0
        for k in range(part.n):
            ge = np.array(g(nodes[k] + nodes[k + 1], rates[k] + rates[k + 1],
                            [0.5 / part.n, 7850.0 * 4.0e-5, 0.0, 0.0], [float(alpha), 0.0])).ravel()
            ends = nodes[k] + nodes[k + 1]
            force -= [ge[0::4].sum(), ge[1::4].sum()]
            turn = [v for j in (0, 4) for v in (-ends[j + 1], ends[j], -ends[j + 3], ends[j + 2])]
            moment -= float(np.dot(ge, turn))
        got = [float(v.xreplace(values)) for v in F]
        assert np.allclose(got, force, rtol=1e-12, atol=1e-15)
        assert abs(float(M.xreplace(values)) - moment) <= 1e-12 * abs(moment)


def test_ef_root_moment_from_equilibrium_equals_the_damped_clamps_reaction():
    """S1's beam as 4 ef elements damped by alpha = 5 1/s: the root moment from equilibrium is
    minus the clamp's reaction moment and N minus its force along the root's tangent, both now
    with the damping's load (measured 1.7e-15 and 1.0e-15 of their peaks over 5 s)."""
    import tomllib
    from pathlib import Path

    with open(Path(__file__).resolve().parent.parent / "scenes" / "hub.toml", "rb") as f:
        data = tomllib.load(f)
    beam = next(b for b in data["body"] if b["kind"] == "beam")
    beam |= {"model": {"variant": "ef", "elements": 4}, "damping": {"alpha": 5.0}}
    data["output"]["columns"] = {"th": "angle(hub_joint)", "M_A": "M(beam, root)",
                                 "N_A": "N(beam, root)", "M_c": "reaction(clamp, moment)",
                                 "Rx": "reaction(clamp, x)", "Ry": "reaction(clamp, y)"}
    r = run_ok(built(data), t_end=3.0, dt=1e-3, out_every=10)
    assert np.abs(r["M_A"] + r["M_c"]).max() <= 1e-12 * np.abs(r["M_A"]).max()
    along = r["Rx"] * np.cos(r["th"]) + r["Ry"] * np.sin(r["th"])
    assert np.abs(r["N_A"] + along).max() <= 1e-12 * np.abs(r["N_A"]).max()


def test_exact_refuses_a_damped_equilibrium_it_does_not_derive():
    """The exact kinematics' equilibrium section forces do not carry the dampers' load yet: a
    damped (zeta) exact beam's M from equilibrium is refused in one line, before any work."""
    data = _cantilever({"strain": "exact", "axial": ["sin1"], "bending": ["cf1", "cf2"]},
                       {"zeta": 0.02})
    from flexsym.physics.assemble import derive_system

    with pytest.raises(SpecError, match="alpha / zeta loads"):
        derive_system(system_from_dict(data, name="damped_cantilever"))


@pytest.mark.parametrize("damping", [{"zeta": 0.05}, {"alpha": 4.2}], ids=["zeta", "alpha"])
def test_a_spatial_one_mode_cantilevers_loads_follow_its_coordinate(damping):
    """The same in 3D, the strip sagging along z (its vz plane): My at the root and at a
    quarter span, the clamp's moment about y and its force along z, each an affine function of
    the flap coordinate within 1e-12 of its peak (measured 5e-16; before, the dampers' load was
    left out here too)."""
    strip = STRIP | {"shear_modulus": 8.1e10, "inertia_z": 1.3333e-11, "inertia_y": 1.3333e-11,
                     "torsion_constant": 2.6e-11}
    del strip["inertia"]
    data = {"system": {"name": "damped_cantilever_3d", "dimension": 3},
            "body": [strip | {"model": {"strain": "linear", "axial": [], "bending": ["cf1"],
                                        "torsion": []}, "damping": damping}],
            "joint": [{"name": "fix", "kind": "clamp", "parent": "ground",
                       "point": [0.0, 0.0, 0.0], "child": "strip.root"}],
            "gravity": {"g": [0.0, 0.0, -9.81]},
            "output": {"interval": 1e-3, "columns": {
                "My_root": "My(strip, root)", "My_mid": "My(strip, 0.25)",
                "R_my": "reaction(fix, my)", "R_z": "reaction(fix, z)"}}}
    r = run_ok(built(data), integrator="genalpha", dt=1e-4, t_end=0.3, out_every=10)
    q = r["strip_vz_cf1"]
    fit = np.vstack([q, np.ones_like(q)]).T
    assert np.ptp(q) > 0.5 * np.abs(q).max()
    for column in ("My_root", "My_mid", "R_my", "R_z"):
        y = r[column]
        coef = np.linalg.lstsq(fit, y, rcond=None)[0]
        assert np.abs(fit @ coef - y).max() <= 1e-12 * np.abs(y).max(), column


@pytest.mark.parametrize("damping", [{"zeta": 0.05}, {"alpha": 900.0}], ids=["zeta", "alpha"])
def test_a_spatial_torsion_modes_damping_torque_is_in_the_twist_balance(damping):
    """One torsion mode (ff1) of a strip whose root a guided revolute about its own axis turns
    by theta = 0.05 (1 - cos 300 t): the twist rings, and Mx at the root and at a quarter span
    and the root joint's moment about x are each an affine function of the twist coordinate and
    the root's angular acceleration within 1e-12 of their peaks (m q'' + c q' + k q = -S theta''
    leaves no q'): the dampers' torque -rho (I_y + I_z) phi_w (w = M^-1 dD/dq') is in the
    balance (measured 1.0e-15; left out, Mx_root is 1.6e-2 of its peak away, with zeta = 0.05
    and alpha = 900 1/s alike)."""
    strip = STRIP | {"shear_modulus": 8.1e10, "inertia_z": 1.3333e-11, "inertia_y": 1.3333e-11,
                     "torsion_constant": 2.6e-11}
    del strip["inertia"]
    data = {"system": {"name": "damped_twist_3d", "dimension": 3},
            "body": [strip | {"model": {"strain": "linear", "axial": [], "bending": ["cf1"],
                                        "torsion": ["ff1"]}, "damping": damping}],
            "joint": [{"name": "spin", "kind": "revolute", "parent": "ground", "axis": [1.0, 0.0, 0.0],
                       "point": [0.0, 0.0, 0.0], "child": "strip.root"}],
            "driver": [{"name": "turn", "kind": "guided", "joint": "spin",
                        "theta": "0.05*(1 - cos(300*t))"}],
            "output": {"interval": 1e-3, "columns": {
                "Mx_root": "Mx(strip, root)", "Mx_mid": "Mx(strip, 0.25)", "R_mx": "reaction(spin, mx)"}}}
    r = run_ok(built(data), integrator="genalpha", dt=2e-5, t_end=0.05, out_every=50)
    q = next(r[c] for c in r.columns if c.startswith("strip_") and c.endswith("ff1"))
    fit = np.vstack([q, 0.05 * 300**2 * np.cos(300 * r["t"]), np.ones_like(q)]).T
    assert np.ptp(q) > 0.5 * np.abs(q).max()  # it rings
    for column in ("Mx_root", "Mx_mid", "R_mx"):
        y = r[column]
        coef = np.linalg.lstsq(fit, y, rcond=None)[0]
        assert np.abs(fit @ coef - y).max() <= 1e-12 * np.abs(y).max(), column
