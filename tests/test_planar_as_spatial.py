"""A planar system run as a spatial one (dimension = 3, every axis along z, every point in the
x-y plane) moves in its plane and reproduces the planar rows (issue 20, item 7).

The twin is made from the planar scene by one rule (`spatial_twin`), so the check covers the
scene as the user wrote it. Open chains (S1 `hub`, S3 `pendulum`) have the same coordinates in
both derivations: the rows agree to round-off, the casadi-differentiated spatial kinetic energy
against the sympy-differentiated planar one. S0 is checked in test_spatial.py (the flap scene
without gravity)."""
import copy
import tomllib
from pathlib import Path

import numpy as np
import pytest

from system_data import built, run_ok

ROOT = Path(__file__).resolve().parent.parent
PLANAR_ONLY_OUTPUTS = ("sigma(", "momentum")


def spatial_twin(data: dict) -> dict:
    """The planar scene `data` as a spatial one: points get z = 0, revolute axes are z, beams
    get a second bending plane (the same I: motion stays in the plane) and torsion, a rigid
    body's polar inertia I becomes [I/2, I/2, I] (a plate in the plane), g gets g_z = 0, a
    bending moment M is Mz and a joint's reaction moment is its mz."""
    data = copy.deepcopy(data)
    twin = {k: v for k, v in data.items() if k not in ("body", "joint", "gravity", "output")}
    twin["system"] = dict(data["system"], name=data["system"]["name"] + "_3d", dimension=3)
    bodies = []
    for b in data["body"]:
        b = dict(b)
        if b["kind"] == "beam":  # a uniform beam's section, or each segment's
            for sec in b.get("segments", [b]):
                sec["inertia_z"] = sec["inertia_y"] = sec.pop("inertia")
                sec["torsion_constant"], sec["shear_modulus"] = 2 * sec["inertia_z"], 0.4 * sec["youngs_modulus"]
        else:
            b["inertia"] = [b["inertia"] / 2, b["inertia"] / 2, b["inertia"]]
            for key in ("com",):
                if key in b:
                    b[key] = [*b[key], 0.0]
            b["markers"] = {name: [*p, 0.0] for name, p in b.get("markers", {}).items()}
        bodies.append(b)
    twin["body"] = bodies
    joints = []
    for j in data["joint"]:
        j = dict(j)
        if "point" in j:
            j["point"] = [*j["point"], 0.0]
        if j["kind"] == "revolute":
            j["axis"] = [0.0, 0.0, 1.0]
        elif j["kind"] == "prismatic":
            j["axis"] = [*j["axis"], 0.0]
        joints.append(j)
    twin["joint"] = joints
    if "gravity" in data:
        twin["gravity"] = {"g": [*data["gravity"]["g"], 0.0]}
    columns = {c: q for c, q in data["output"]["columns"].items() if not q.startswith(PLANAR_ONLY_OUTPUTS)}
    twin["output"] = dict(data["output"], columns={c: _spatial_quantity(q) for c, q in columns.items()})
    return twin


def _spatial_quantity(q: str) -> str:
    if q.startswith("M("):
        return "Mz" + q[1:]
    if q.startswith("reaction(") and q.replace(" ", "").endswith(",moment)"):
        return q[:q.rindex(",")] + ", mz)"
    return q


# S3's section stations (tests/test_spatial_sections.py): a stress at X, moments and
# deflections at X + k H for fourth-order differences
X, H, C = 0.3, 0.01, 0.0025  # m; C: the outer fibre of the 5 mm strip in its plane of motion
STEPS = {"m2": -2, "m1": -1, "p1": 1, "p2": 2}
HUB_JOINTS = ("hub_joint", "clamp")  # S1's, whose reactions test_spatial_reactions.py checks


def open_chain_pair(scene: str) -> tuple[dict, dict]:
    """A shipped open chain and its twin, with the out-of-plane columns (w_out, T_root, z_tip:
    zero in the plane) and the outputs the other files check on it: S3's sections
    (test_spatial_sections.py), S1's joint reactions (test_spatial_reactions.py). One twin build
    serves them all (a spatial beam's outputs cost most of its derivation)."""
    data = tomllib.loads((ROOT / "scenes" / f"{scene}.toml").read_text())
    beam = next(b["name"] for b in data["body"] if b["kind"] == "beam")
    if scene == "pendulum":
        data["output"]["columns"]["s"] = f"sigma({beam}, {X}, {C})"
    if scene == "hub":
        data["output"]["columns"] |= {f"{j}_{c}": f"reaction({j}, {c})" for j in HUB_JOINTS
                                      for c in ("x", "y", "moment")}
    twin = spatial_twin(data)  # reaction(J, moment) -> reaction(J, mz)
    cols = twin["output"]["columns"]
    cols |= {"w_out": f"vz({beam}, tip)", "T_root": f"Mx({beam}, root)", "z_tip": f"z({beam}.tip)"}
    if scene == "hub":
        cols |= {f"{j}_{c}": f"reaction({j}, {c})" for j in HUB_JOINTS for c in ("z", "mx", "my")}
    if scene == "pendulum":
        cols |= {"s": f"sigma({beam}, {X}, {C}, 0.0)", "s_z": f"sigma({beam}, {X}, {C}, 0.001)",
                 "N": f"N({beam}, {X})", "Qy": f"Qy({beam}, {X})", "Qz": f"Qz({beam}, {X})"}
        for k, n in STEPS.items():
            cols |= {f"Mz_{k}": f"Mz({beam}, {X + n * H:g})", f"v_{k}": f"v({beam}, {X + n * H:g})"}
    return data, twin


@pytest.mark.parametrize("scene,kw", [
    ("pendulum", dict(t_end=1.0, dt=1e-4)),
    ("hub", dict(t_end=20.0, dt=1e-3)),
])
def test_open_chain_run_as_spatial_reproduces_the_planar_rows(scene, kw):
    """S3 and S1: every column within 1e-9 of its peak (measured: 1e-14 to 3e-14 for S3,
    2.5e-15 to 4.3e-15 for S1); the out-of-plane deflection and the torsion stay exactly 0."""
    data, twin = open_chain_pair(scene)
    planar, spatial = run_ok(built(data), **kw), run_ok(built(twin), **kw)
    worst = {}
    for col, q in data["output"]["columns"].items():
        if col in twin["output"]["columns"]:
            want = np.abs(planar[col]) if q.startswith("w(") else planar[col]  # 3D w: a distance
            worst[col] = np.abs(spatial[col] - want).max() / np.abs(want).max()
    assert worst and max(worst.values()) <= 1e-9, worst
    for col in ("w_out", "T_root", "z_tip"):
        assert np.abs(spatial[col]).max() == 0, col


@pytest.mark.study  # two minutes, most of it building the spatial twin
def test_slider_crank_run_as_spatial_reproduces_the_planar_rows():
    """S2: the crank pin becomes a ball joint (Euler parameters) and the slider pin a universal
    joint that closes the loop, so the two runs integrate different coordinates and agree to
    the integrators' accuracy, not to round-off. Both run rk4p at dt = 1e-5 with the projection
    at its default tolerance; measured: x_s 2.5e-11, w_mid 6.6e-9 and N_mid 2.2e-7 of their
    peaks. That is the planar run's own floor: with its projection tolerance 3e-12 instead of
    1e-12 it moves by 3.5e-11, 1.3e-8 and 3.6e-7 (N_mid is the stiff axial strain, EA/L =
    1.9e7 N/m), and halving dt does not bring the two closer."""
    data = tomllib.loads((ROOT / "scenes" / "slider_crank.toml").read_text())
    twin = spatial_twin(data)
    for j in twin["joint"]:
        if j["name"] == "crank_pin":
            j["kind"], j["direction"] = "spherical", [1.0, 0.0, 0.0]
            del j["axis"]
        elif j["name"] == "slider_pin":
            j["kind"], j["axis"] = "universal", [0.0, 0.0, 1.0]
    twin["output"]["columns"] |= {"z_mid": "vz(rod, mid)", "viol": "violation"}
    kw = dict(integrator="rk4p", dt=1e-5)
    planar, spatial = run_ok(built(data), **kw), run_ok(built(twin), **kw)
    for col, tol in (("x_s", 1e-9), ("w_mid", 3e-8), ("N_mid", 1e-6)):
        want = np.abs(planar[col]) if col == "w_mid" else planar[col]
        assert np.abs(spatial[col] - want).max() <= tol * np.abs(want).max(), col
    assert np.abs(spatial["z_mid"]).max() == 0 and np.abs(spatial["viol"]).max() < 1e-11
