"""The prestress strain model on a beam whose frame a joint's rate spins (not a guided drive),
in 3D and in the plane: its centrifugal stiffening V_p = 1/2 int N(omega) v_x^2, N = rho A
omega^2 (L^2 - x^2)/2 (in 3D omega_y^2 + omega_z^2 and both planes' slopes), is minus the part
of T that the foreshortening gives (m3), so it is written into T (body_kinds/modal.py,
body_kinds/spatial/modal.py) and Lagrange's equations take its dependence on the joint's rate.
The rest of that part of T, and gravity's on the foreshortening, load the beam axially as its
root's acceleration and gravity do (root_load_density): a root off the axis, a pendulum.
As a potential read at the current spin, the joint's equation missed d/dt dV_p/dtheta': on a
tilted hinge T + V drifted by 47 % of V's peak and the mid-span moment rang up to 11 times
m3's. Its sections, momentum and reactions then take the foreshortening's inertia, as m3's
do, so a section balances the motion T gives."""
import copy

import numpy as np
import pytest

from system_data import built, run_ok

STRIP = {"name": "strip", "kind": "beam", "length": 1.0, "density": 2700.0, "youngs_modulus": 7.0e10,
         "shear_modulus": 2.6e10, "area": 1.0e-4, "inertia_z": 3.3333e-9, "inertia_y": 2.0833e-10,
         "torsion_constant": 7.021e-10, "markers": {"mid": 0.5}}
AXIS = np.array([0.0, 0.5, 0.866])


def tilted_hinge(model: str) -> dict:
    """A strip (1 m, 20 x 5 mm aluminium) on a hinge whose axis leans 30 degrees from the
    vertical, released horizontal and at rest: it swings down and bends in both planes."""
    return {"system": {"name": "tilted_hinge", "dimension": 3},
            "body": [STRIP | {"model": model}],
            "joint": [{"name": "hinge", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0, 0.0],
                       "axis": list(AXIS), "child": "strip.root"}],
            "gravity": {"g": [0.0, 0.0, -9.81]},
            "output": {"columns": {"T": "T", "V": "V", "My_mid": "My(strip, mid)", "th": "angle(hinge)"}
                       | {f"M{c}": f"M{c}(strip, root)" for c in "xyz"}
                       | {f"R{c}": f"reaction(hinge, m{c})" for c in "xyz"}}}


@pytest.fixture(scope="module")
def hinge_run():
    """Over 1 s, generalized-alpha at 0.1 ms, rows every ms."""
    return run_ok(built(tilted_hinge("prestress")), t_end=1.0, dt=1e-4, integrator="genalpha", out_every=10)


def test_prestress_on_a_hinge_conserves_energy(hinge_run):
    """T + V holds to 1e-6 of V's peak (measured 3.2e-8, m3 6.2e-9; 0.47 as a potential), and
    the mid-span flap moment stays at the size m3 gives it (its peak 0.607 N m against m3's
    0.610, measured once; 6.65 as a potential): under 1 N m."""
    r = hinge_run
    E = r["T"] + r["V"]
    assert np.abs(r["V"]).max() > 0.5  # m g (L/2) sin 30°: 0.66 J
    assert np.abs(E - E[0]).max() <= 1e-6 * np.abs(r["V"]).max()
    assert 0.3 < np.abs(r["My_mid"]).max() < 1.0


def test_a_mesh_on_the_hinge_conserves_energy():
    """The strip from a 20-element mesh (its prestress from the unit load cases): gravity's
    case along the strip is in V and the acceleration cases in T, as m3 holds them
    (_load_case_energy), so T + V holds to 1e-6 of V's peak over 0.5 s (measured 2e-8 over
    1 s; 1.4e-4 over 0.5 s while those cases were a potential read with the frame's actual q'')."""
    data = tilted_hinge("prestress")
    strip = data["body"][0]
    strip["segments"] = [{k: strip.pop(k) for k in ("length", "density", "youngs_modulus", "shear_modulus",
                                                    "area", "inertia_z", "inertia_y", "torsion_constant")}]
    strip["elements"] = 20
    data["system"]["name"] = "tilted_hinge_mesh"
    data["output"] = {"columns": {"T": "T", "V": "V"}}  # (the sections cost most of a build)
    r = run_ok(built(data), t_end=0.5, dt=1e-4, integrator="genalpha", out_every=10)
    E = r["T"] + r["V"]
    assert np.abs(r["V"]).max() > 0.3
    assert np.abs(E - E[0]).max() <= 1e-6 * np.abs(r["V"]).max()


def test_prestress_hinge_reaction_is_its_sections_and_nearly_free_about_the_axis(hinge_run):
    """The root's section moments (the equilibrium of the whole strip, frame axes) are minus
    the hinge's reaction moment on the strip (its momentum balance, ground axes turned into
    the frame by the hinge angle) to round-off (measured 3e-15 of the peak): both read the
    foreshortening's inertia that prestress's T holds. About the free hinge's own axis the
    reaction is 2.0e-3 of its peak (m3: 1.1e-6): the recoveries read the whole foreshortened
    strip's momentum, the model's equations its T to second order in the deflection: a
    residue of third order (not gravity's: 2.1e-3 before V held it); 7.3e-3 while the
    recoveries read the strip without its foreshortening."""
    r = hinge_run
    a = AXIS / np.linalg.norm(AXIS)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    R = np.array([r[f"R{c}"] for c in "xyz"])
    worst = peak = 0.0
    for i, th in enumerate(r["th"]):
        A = np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K  # ground <- strip frame
        section = np.array([r[f"M{c}"][i] for c in "xyz"])
        worst, peak = max(worst, np.abs(section + A.T @ R[:, i]).max()), max(peak, np.abs(section).max())
    assert peak > 0.5 and worst < 1e-12 * peak, (worst, peak)
    assert np.abs(a @ R).max() < 4e-3 * np.abs(R).max()


PENDULUM = {"system": {"name": "prestress_pendulum"},
            "body": [{"name": "beam", "kind": "beam", "length": 1.0, "density": 2700.0,
                      "youngs_modulus": 7e10, "area": 1e-4, "inertia": 2.0833333333333336e-10,
                      "model": "prestress", "markers": {"mid": 0.5}}],
            "joint": [{"name": "pin", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0],
                       "child": "beam.root"}],
            "gravity": {"g": [0.0, -9.81]},
            "output": {"columns": {"T": "T", "V": "V", "w_mid": "w(beam, mid)", "M_mid": "M(beam, mid)",
                                   "N_A": "N(beam, root, constitutive)", "N_mid": "N(beam, mid, constitutive)",
                                   "Neq_A": "N(beam, root, equilibrium)", "Neq_mid": "N(beam, mid, equilibrium)"}}}


def test_prestress_on_a_planar_pendulum_conserves_energy_and_its_N_carries_gravity():
    """S3's strip (thin in the plane of motion) on a pin under gravity, released horizontal,
    2 s at 0.1 ms: T + V holds to 1e-7 of V's peak (measured 1.3e-8, m3 1.7e-8; 1.4e-6 as a
    potential read at the current spin). Its own N is the rigid strip's axial load with
    gravity's along it (root_load_density): against N from equilibrium, 5.7e-2 and 7.5e-2 of
    the peak at the root and at mid-span (0.46 and 0.38 with the centrifugal N-hat alone),
    and on a strip 100 times stiffer 5.2e-3 and 7.0e-3 (0.40, 0.31): the rest is the relative
    motion's axial inertia (Coriolis, 2 omega v'), which equilibrium holds and the model's N
    does not. Its spatial twin reproduces the planar rows to 1e-9 of each peak: the 3D root
    load and N against the planar ones."""
    from test_planar_as_spatial import spatial_twin

    run = dict(t_end=2.0, dt=1e-4, integrator="genalpha", out_every=10)
    r = run_ok(built(PENDULUM), **run)
    E = r["T"] + r["V"]
    assert np.abs(r["V"]).max() > 1.0  # m g L/2: 1.3 J
    assert np.abs(E - E[0]).max() <= 1e-7 * np.abs(r["V"]).max()
    stiff = copy.deepcopy(PENDULUM)
    stiff["body"][0]["youngs_modulus"] *= 100  # a run-time parameter: the same derivation
    for run_, tol in ((r, 0.1), (run_ok(built(stiff), **run), 1.5e-2)):
        for x in ("A", "mid"):
            N, Neq = run_[f"N_{x}"], run_[f"Neq_{x}"]
            assert np.abs(N - Neq).max() <= tol * np.abs(Neq).max(), (x, tol)
    twin = run_ok(built(spatial_twin(PENDULUM)), **run)
    for c in r.columns:
        want = np.abs(r[c]) if c == "w_mid" else r[c]  # 3D w: a distance
        assert np.abs(twin[c] - want).max() <= 1e-9 * np.abs(want).max(), c


def off_axis_blade(model: str) -> dict:
    """A blade (0.8 m aluminium strip) clamped to the end of a rigid link, 0.5 m off the pin's
    axis; a motor spins the link up for 1 s, then lets it run free."""
    return {"system": {"name": f"off_axis_blade_{model}"},
            "body": [{"name": "link", "kind": "rigid", "mass": 2.0, "inertia": 0.05, "com": [0.25, 0.0],
                      "markers": {"pin": [0.0, 0.0], "end": [0.5, 0.0]}},
                     {"name": "blade", "kind": "beam", "length": 0.8, "density": 2700.0,
                      "youngs_modulus": 7e10, "area": 1.2e-4, "inertia": 2.5e-10, "model": model,
                      "markers": {"mid": 0.4}}],
            "joint": [{"name": "pin", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0],
                       "child": "link.pin"},
                      {"name": "weld", "kind": "clamp", "parent": "link.end", "child": "blade.root"}],
            "driver": [{"name": "motor", "kind": "motor", "joint": "pin", "torque": "3.0*ifelse(t <= 1, 1, 0)"}],
            "output": {"columns": {"w_mid": "w(blade, mid)", "M_A": "M(blade, root)"}}}


def test_prestress_off_the_axis_stiffens_as_m3():
    """The blade's root moves on a circle of 0.5 m: the centripetal acceleration of its root
    loads it axially as much as its own spin does (rho A omega^2 (L^2/2 + r L): r L = 0.4 m^2
    against L^2/2 = 0.32 m^2). Prestress takes it (root_load_density) and follows m3 within
    2e-2 of the peaks over 1.5 s (measured: w_mid 5.9e-3, M_A 6.1e-3; with the centrifugal
    N-hat alone 0.37 and 0.31, and 0.54 of w_mid's peak off ef on 8 elements). Its spatial
    twin reproduces the planar rows to 1e-9 of each peak (measured 4e-15): the 3D root load
    of a moving root against the planar one."""
    from test_planar_as_spatial import spatial_twin

    run = dict(t_end=1.5, dt=2e-4, integrator="genalpha", out_every=10)
    m3, pre = (run_ok(built(off_axis_blade(m)), **run) for m in ("m3", "prestress"))
    twin = run_ok(built(spatial_twin(off_axis_blade("prestress"))), **run)
    for c in ("w_mid", "M_A"):
        assert np.abs(pre[c] - m3[c]).max() <= 2e-2 * np.abs(m3[c]).max(), c
        want = np.abs(pre[c]) if c == "w_mid" else pre[c]  # 3D w: a distance
        assert np.abs(twin[c] - want).max() <= 1e-9 * np.abs(want).max(), c


def shaken_strip(model: str) -> dict:
    """S3's strip clamped along x to a carriage (1 kg) that a motor force pushes to and fro
    along x at 10 Hz on a prismatic joint, sagging under gravity from its static start: the
    root's acceleration along the beam, a free coordinate's x'', stiffens and softens it."""
    return {"system": {"name": f"shaken_strip_{model}", "start": "static"},
            "body": [{"name": "cart", "kind": "rigid", "mass": 1.0, "inertia": 0.01,
                      "markers": {"top": [0.0, 0.0]}},
                     PENDULUM["body"][0] | {"model": model}],
            "joint": [{"name": "slide", "kind": "prismatic", "parent": "ground", "point": [0.0, 0.0],
                       "axis": [1.0, 0.0], "child": "cart.top"},
                      {"name": "clamp", "kind": "clamp", "parent": "cart.top", "child": "beam.root"}],
            "driver": [{"name": "push", "kind": "motor", "joint": "slide", "force": "300*cos(2*pi*10*t)"}],
            "gravity": {"g": [0.0, -9.81]},
            "output": {"columns": {"w_tip": "v(beam, tip)", "M_A": "M(beam, root)"}}}


def test_prestress_carried_along_its_axis_stiffens_as_m3():
    """The strip's root accelerates along the beam (300 N on the 1.27 kg of carriage and strip:
    +-240 m/s^2): the axial load rho A a_x (L - x) stiffens and softens the sagging strip. Prestress
    takes it (root_load_density's V_x du' term) and follows m3 within 5e-3 of the peaks over
    0.3 s (measured: w_tip 6.5e-4, M_A 1.6e-3; with the centrifugal N-hat alone 0.25 and
    0.57); its spatial twin reproduces the planar rows to 1e-9 of each peak (measured 2e-15)."""
    from test_planar_as_spatial import spatial_twin

    run = dict(t_end=0.3, dt=2e-5, integrator="genalpha", out_every=50)
    m3, pre = (run_ok(built(shaken_strip(m)), **run) for m in ("m3", "prestress"))
    twin = run_ok(built(spatial_twin(shaken_strip("prestress"))), **run)
    for c in ("w_tip", "M_A"):
        assert np.abs(pre[c] - m3[c]).max() <= 5e-3 * np.abs(m3[c]).max(), c
        assert np.abs(twin[c] - pre[c]).max() <= 1e-9 * np.abs(pre[c]).max(), c
