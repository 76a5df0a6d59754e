"""Revolute, prismatic, cylindrical and clamp joints closing a spatial loop (physics/spatial.py
_cut_rows, SPATIAL_CUT_ROWS: gap rows across the axis or at a point, rotation rows from the
assembled start, scenes/assembly.cut_axes), against what does not come from those rows:

 * the planar slider-crank (rigid bodies, gravity in the plane) run as a spatial system: closed
   by a revolute (about z) or by the slider's prismatic joint (along x), it has the planar tree
   and the planar coordinates, and its out-of-plane rows are identically 0 (the runtime's block
   solve drops them): the rows, the loop's reactions and the multipliers' loads agree with the
   planar run to round-off; with a ball joint at the crank pin and a cylindrical joint (about z)
   at the slider, the coordinates differ (Euler parameters) and the rows agree to the
   integrator's accuracy;
 * an undriven, undamped spatial loop closed by each new kind: T + V conserved by rk4p at its
   order 4, the loop closed (violation);
 * a clamp closing a loop in static equilibrium: its reaction against hand statics;
 * a redundant loop (two bodies on ball joints clamped together: rows of lower rank than their
   number at t = 0, not identically 0): a reaction output is refused by the assembly (the
   multipliers are one solution of many; the motion runs, as the planar loops' identically-0
   rows show); one whose gap rows lose rank on the closed loop is refused by the assembly as
   singular;
 * malformed scenes, each refused in one line naming the file, the system and the joint, exit 2.
"""
import copy
import json
import math

import numpy as np
import pytest

from system_data import built, run_ok, scene_text_refused, scene_text_runs
from test_planar_as_spatial import spatial_twin

G = 9.81


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_value(x)}" for k, x in v.items()) + " }"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, str):
        return json.dumps(v)
    return repr(float(v)) if isinstance(v, float) else str(v)


def toml_text(data: dict) -> str:
    """Scene data as TOML text (tables, arrays of tables, inline tables for nested dicts)."""
    out = []
    for key, val in data.items():
        for item in (val if isinstance(val, list) else [val]):
            out.append(f"[[{key}]]" if isinstance(val, list) else f"[{key}]")
            out += [f"{k} = {_value(x)}" for k, x in item.items()]
            out.append("")
    return "\n".join(out)


# ----- the planar slider-crank run as a spatial one
def slider_crank(cut: str) -> dict:
    """S2's geometry with rigid bodies and gravity along -y: a guided crank (0.15 m), a rod (0.3
    m) pinned to it, a slider on the x axis; the loop closed at the slider by its pin (cut =
    "revolute": the slide is in the tree) or by the slide (cut = "prismatic": the slider hangs
    from the rod's tip by its pin)."""
    crank = [{"name": "crank_joint", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0],
              "child": "crank.root"},
             {"name": "crank_pin", "kind": "revolute", "parent": "crank.tip", "child": "rod.root"}]
    slide = {"name": "slide", "kind": "prismatic", "parent": "ground", "point": [0.0, 0.0],
             "child": "slider.pin", "axis": [1.0, 0.0]}
    pin = {"name": "slider_pin", "kind": "revolute", "parent": "rod.tip", "child": "slider.pin"}
    joints = crank + ([dict(slide, initial=0.45), pin] if cut == "revolute" else [pin, slide])
    closing = joints[-1]["name"]
    return {
        "system": {"name": f"sc_{cut}"},
        "body": [{"name": "crank", "kind": "rigid", "mass": 0.1, "inertia": 1e-4, "com": [0.075, 0.0],
                  "markers": {"root": [0.0, 0.0], "tip": [0.15, 0.0]}},
                 {"name": "rod", "kind": "rigid", "mass": 0.0667, "inertia": 5e-4, "com": [0.15, 0.0],
                  "markers": {"root": [0.0, 0.0], "tip": [0.3, 0.0]}},
                 {"name": "slider", "kind": "rigid", "mass": 0.0334, "inertia": 1e-6,
                  "markers": {"pin": [0.0, 0.0]}}],
        "joint": joints,
        "driver": [{"name": "crank_drive", "kind": "guided", "joint": "crank_joint", "maneuver": "spin-up",
                    "omega": 150.0, "duration": 0.1}],
        "gravity": {"g": [0.0, -G]},
        "solver": {"integrator": "rk4p", "dt": 1e-4, "t_end": 0.1},
        "output": {"interval": 0.001, "columns": {
            "x_s": "x(slider.pin)", "y_s": "y(rod.root)", "th": "angle(crank_pin)",
            "Fx": f"reaction({closing}, x)", "Fy": f"reaction({closing}, y)", "Mz": f"reaction({closing}, moment)",
            "Px": "reaction(crank_pin, x)", "Py": "reaction(crank_pin, y)", "viol": "violation"}},
    }


RUN = dict(t_end=0.1, dt=1e-4)
COMPARED = ("x_s", "y_s", "Fx", "Fy", "Mz", "Px", "Py")


def _worst(planar, spatial, columns=COMPARED) -> dict:
    """Each column's largest difference relative to its peak (a column that is 0 in the plane,
    as a prismatic joint's force along its axis: relative to 1 N)."""
    return {c: float(np.abs(spatial[c] - planar[c]).max() / max(np.abs(planar[c]).max(), 1.0)) for c in columns}


@pytest.mark.parametrize("cut", ["revolute", "prismatic"])
def test_the_planar_slider_crank_closed_in_3d_reproduces_the_planar_rows(cut):
    """The same tree and coordinates as the planar run, the closing joint's out-of-plane rows
    identically 0 (revolute: z, a1, a2; prismatic: n1 = z, r1, r3; the runtime drops them):
    over 0.1 s of the spin-up, relative to each column's peak, the slider's x and the rod's y
    within 1e-13 (measured 1.1e-16 with rk4p, genalpha3 and ali3p), the reactions of the closing
    joint and of the crank pin within 1e-12 with rk4p and ali3p (measured 3.6e-15) and 1e-7 with
    genalpha3 (4.2e-9: its multipliers are its Newton's, converged on the positions), no force
    along z, the loop closed (violation: measured 8.8e-13 with rk4p)."""
    data = slider_crank(cut)
    twin = spatial_twin(data)
    twin["output"]["columns"] |= {"z_s": "z(slider.pin)", "Fz": f"reaction({twin['joint'][-1]['name']}, z)"}
    planar, spatial = built(data), built(twin)
    for integrator in ("rk4p", "genalpha3", "ali3p"):
        p, s = run_ok(planar, integrator=integrator, **RUN), run_ok(spatial, integrator=integrator, **RUN)
        worst = _worst(p, s)
        loads = 1e-7 if integrator == "genalpha3" else 1e-12  # its Newton's multipliers
        assert max(worst[c] for c in ("x_s", "y_s")) < 1e-13, (integrator, worst)
        assert max(worst[c] for c in COMPARED[2:]) < loads, (integrator, worst)
        assert np.abs(s["viol"]).max() < 1e-11 and np.abs(s["z_s"]).max() == 0
        assert np.abs(s["Fz"]).max() < 1e-12
        assert np.abs(p["Fy"]).max() > 1.0  # the loop does carry loads


@pytest.mark.study  # 47 s (the ball joint's derivation); the closing cylindrical's rows are in the energy test
def test_a_ball_joint_and_a_closing_cylindrical_reproduce_the_planar_rows():
    """The crank pin a ball joint (Euler parameters), the slider's pin a cylindrical joint about z
    closing the loop (its four rows independent: the ball's three turns and the slide against
    two gaps across z and the two axis rows): other coordinates than the plane's, so the runs
    agree to rk4p's accuracy at dt = 1e-4 s: within 1e-9 of each column's peak (measured: x_s
    1.8e-13, the reactions 2.6e-13), the rod stays in the plane (its tip's z 0, its z axis
    along z to 1.3e-12), the loop closed (violation 9.9e-13)."""
    data = slider_crank("revolute")
    twin = spatial_twin(data)
    for j in twin["joint"]:
        if j["name"] == "crank_pin":
            j["kind"], j["direction"] = "spherical", [1.0, 0.0, 0.0]
            del j["axis"]
        elif j["name"] == "slider_pin":
            j["kind"] = "cylindrical"
    cols = twin["output"]["columns"]
    del cols["th"]
    cols |= {"z_t": "z(rod.tip)", "Rzz": "R(rod.tip, z, z)"}
    p, s = run_ok(built(data), integrator="rk4p", **RUN), run_ok(built(twin), integrator="rk4p", **RUN)
    worst = _worst(p, s)
    assert max(worst.values()) < 1e-9, worst
    assert np.abs(s["z_t"]).max() < 1e-13 and np.abs(s["Rzz"] - 1).max() < 1e-11
    assert np.abs(s["viol"]).max() < 1e-11


# ----- a pair of bodies closed by each kind
M_A, D_A, L_A = 1.5, 0.1, 0.3  # body a: its mass, its centre of mass's y and depth below the pivot


def pair(kind: str, outputs: dict, hinge=None) -> dict:
    """Body a on a ball joint at the origin, body b on a revolute joint `hinge` about y at the
    same point, a closed to b there by a joint of `kind` (its gap rows are identically 0: the
    ball holds the point). A clamp or a prismatic joint (along b's x) locks a's turn to b's: one
    freedom, b's turn; a revolute or cylindrical joint (about b's x) leaves a its turn about
    b's x: two. a's centre of mass is (0, D_A, -L_A), b's (0, 0, -0.2), gravity along -z."""
    close = {"name": "weld", "kind": kind, "parent": "b.pin", "child": "a.pin"}
    if kind != "clamp":
        close["axis"] = [1.0, 0.0, 0.0]
    return {
        "system": {"name": f"pair_{kind}", "dimension": 3},
        "body": [{"name": "a", "kind": "rigid", "mass": M_A, "inertia": [0.02, 0.03, 0.01],
                  "com": [0.0, D_A, -L_A], "markers": {"pin": [0.0, 0.0, 0.0]}},
                 {"name": "b", "kind": "rigid", "mass": 0.8, "inertia": [0.01, 0.01, 0.005],
                  "com": [0.0, 0.0, -0.2], "markers": {"pin": [0.0, 0.0, 0.0]}}],
        "joint": [{"name": "ball", "kind": "spherical", "parent": "ground", "point": [0.0, 0.0, 0.0], "child": "a.pin"},
                  {"name": "hinge", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0, 0.0],
                   "child": "b.pin", "axis": [0.0, 1.0, 0.0], **({"initial": hinge} if hinge else {})},
                  close],
        "gravity": {"g": [0.0, 0.0, -G]},
        "solver": {"integrator": "rk4p", "dt": 1e-3, "t_end": 0.1},
        "output": {"interval": 0.01, "columns": outputs},
    }


@pytest.mark.parametrize("kind", [pytest.param("revolute", marks=pytest.mark.study), "cylindrical", "prismatic",
                                  pytest.param("clamp", marks=pytest.mark.study)])
def test_an_undriven_loop_conserves_energy_at_rk4ps_order(kind):
    """b started at 0.8 rad and 2 rad/s about y (a with it, the ball's rates from the velocity
    analysis), undamped, undriven: over 1 s, T + V's drift (relative to the range of V) falls by
    about 2^4 per halving of the step and the loop stays closed (violation below 1e-11 m).
    Measured at dt = 10, 5, 2.5 ms: revolute and cylindrical (a free to turn about b's x: the
    same motion) 1.1e-7, 7.4e-9, 4.7e-10 (orders 3.93, 3.96); prismatic and clamp (a locked to
    b) 2.6e-8, 1.4e-9, 8.9e-11 (orders 4.24, 3.94). The revolute's and the clamp's (the same
    motions again; a minute to build each) are a study."""
    cols = {"T": "T", "V": "V", "viol": "violation", "th": "angle(hinge)", "ax": "R(a.pin, y, y)"}
    b = built(pair(kind, cols, hinge={"value": 0.8, "rate": 2.0}))
    drifts = []
    for dt in (1e-2, 5e-3, 2.5e-3):
        r = run_ok(b, t_end=1.0, dt=dt, integrator="rk4p")
        E = r["T"] + r["V"]
        drifts.append(np.abs(E - E[0]).max() / np.ptp(r["V"]))
        assert np.abs(r["viol"]).max() < 1e-11, (dt, np.abs(r["viol"]).max())
    orders = [math.log2(x / y) for x, y in zip(drifts, drifts[1:])]
    assert np.ptp(r["th"]) > 0.5  # it does swing
    assert all(3.5 < p < 4.7 for p in orders), (drifts, orders)


@pytest.mark.parametrize("kind", ["revolute", "cylindrical", "prismatic", "clamp"])
def test_the_velocity_analysis_holds_the_rotation_rows(kind):
    """b given 2 rad/s about y: the assembly's velocity analysis (rates3, with the closing
    joint's rotation rows) turns a with it, the ball's rate (0, 2, 0) (locked, or the
    minimum-norm rates when a may also turn about b's x; the gap rows alone would leave it 0)."""
    from flexsym.scenes.system_scene import checked_system, system_from_data

    system, _, _ = system_from_data(pair(kind, {"T": "T"}, hinge={"value": 0.8, "rate": 2.0}), "", "pair")
    rate = checked_system(system)[0].joint("ball").rate
    assert np.abs(np.array(rate) - [0.0, 2.0, 0.0]).max() < 1e-14, rate


# ----- a clamp closing a loop, in static equilibrium
def test_a_closing_clamp_carries_the_moment_of_hand_statics():
    """pair("clamp") at rest: a's centre of mass hangs in the y-z plane below the pivot, so
    gravity's moment on a about x, -M_A D_A g, goes through the clamp to b and through b's
    revolute joint (its axis y) to ground. The clamp's reaction on a is the moment (M_A D_A g, 0, 0) and no force (the
    ball carries a's weight, M_A g up), the hinge's moment about x the same (about y: none, its
    axis), nothing moves (measured: exact, 0 in every column that should be 0)."""
    cols = {f"W{c}": f"reaction(weld, {c})" for c in ("x", "y", "z", "mx", "my", "mz")}
    cols |= {f"B{c}": f"reaction(ball, {c})" for c in ("x", "y", "z")}
    cols |= {"Hmx": "reaction(hinge, mx)", "Hmy": "reaction(hinge, my)", "th": "angle(hinge)", "viol": "violation"}
    r = run_ok(built(pair("clamp", cols)), t_end=0.1, dt=1e-3, integrator="rk4p")
    m = M_A * D_A * G
    assert np.abs(r["Wmx"] - m).max() < 1e-9 * m
    for c in ("Wx", "Wy", "Wz", "Wmy", "Wmz", "Bx", "By", "Hmy"):
        assert np.abs(r[c]).max() < 1e-9, c
    assert np.abs(r["Bz"] - M_A * G).max() < 1e-9 * M_A * G
    assert np.abs(r["Hmx"] - m).max() < 1e-9 * m
    assert np.abs(r["th"]).max() < 1e-12 and np.abs(r["viol"]).max() < 1e-12


# ----- malformed scenes
def _twin_closed_by(kind: str = "revolute") -> dict:
    twin = spatial_twin(slider_crank("revolute"))
    twin["joint"][-1]["kind"] = kind
    twin["output"]["columns"] = {"x_s": "x(slider.pin)", "viol": "violation"}
    return twin


def _edited(data: dict, edit) -> str:
    data = copy.deepcopy(data)
    edit(data)
    return toml_text(data)


def _joint(data, name):
    return next(j for j in data["joint"] if j["name"] == name)


def hinged_pair(outputs: dict) -> dict:
    """Two rigid bodies on revolute joints about the same line (ground's x, at the origin and at
    (0.4, 0, 0)) clamped together at P = (0.2, 0, -0.3), b started at 1 rad/s: one body turning
    about x. Of the clamp's six rows the gap along x and the turns about y and z are identically
    0; the other three (the gap along y and z, the turn about x) hold one freedom of two
    coordinates: they are dependent (rank 1), a redundant loop."""
    return {
        "system": {"name": "hinged_pair", "dimension": 3},
        "body": [{"name": "a", "kind": "rigid", "mass": 1.0, "inertia": [0.02, 0.03, 0.01],
                  "com": [0.1, 0.05, -0.2], "markers": {"o": [0.0, 0.0, 0.0], "p": [0.2, 0.0, -0.3]}},
                 {"name": "b", "kind": "rigid", "mass": 0.6, "inertia": [0.01, 0.01, 0.005],
                  "com": [-0.1, 0.0, -0.1], "markers": {"o": [0.0, 0.0, 0.0], "p": [-0.2, 0.0, -0.3]}}],
        "joint": [{"name": "ha", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0, 0.0],
                   "child": "a.o", "axis": [1.0, 0.0, 0.0]},
                  {"name": "hb", "kind": "revolute", "parent": "ground", "point": [0.4, 0.0, 0.0],
                   "child": "b.o", "axis": [1.0, 0.0, 0.0], "initial": {"rate": 1.0}},
                  {"name": "weld", "kind": "clamp", "parent": "a.p", "child": "b.p"}],
        "gravity": {"g": [0.0, 0.0, -G]},
        "solver": {"integrator": "rk4p", "dt": 1e-3, "t_end": 0.5},
        "output": {"interval": 0.01, "columns": outputs},
    }


def _redundant_reaction(d):
    """Two bodies, each on a ball joint (at the origin and at (0.4, 0, 0)), clamped together at
    P = (0.2, 0, -0.3): one body turning about the balls' line, its six clamp rows and two
    rows of rank 5 on the balls' six turn rates: a redundant loop (refused by the assembly,
    before any work, when a reaction is asked for)."""
    d.clear()
    d.update({
        "system": {"name": "balls", "dimension": 3},
        "body": [{"name": "a", "kind": "rigid", "mass": 1.0, "inertia": [0.01, 0.02, 0.015], "com": [0.1, 0.1, -0.2],
                  "markers": {"o": [0.0, 0.0, 0.0], "p": [0.2, 0.0, -0.3]}},
                 {"name": "b", "kind": "rigid", "mass": 0.7, "inertia": [0.012, 0.008, 0.01], "com": [-0.05, -0.08, -0.25],
                  "markers": {"o": [0.0, 0.0, 0.0], "p": [-0.2, 0.0, -0.3]}}],
        "joint": [{"name": "ball_a", "kind": "spherical", "parent": "ground", "point": [0.0, 0.0, 0.0], "child": "a.o"},
                  {"name": "ball_b", "kind": "spherical", "parent": "ground", "point": [0.4, 0.0, 0.0], "child": "b.o"},
                  {"name": "weld", "kind": "clamp", "parent": "a.p", "child": "b.p"}],
        "gravity": {"g": [0.0, 0.0, -G]},
        "solver": {"integrator": "rk4p", "dt": 1e-3, "t_end": 0.5},
        "output": {"interval": 0.01, "columns": {"W": "reaction(weld, mx)"}}})


def _hinged_pair(d):
    """Two bodies on revolute joints about ground's x (at the origin, at (0.4, 0, 0)) clamped
    together at P: the clamp's gap along y and z and its turn about x hold one freedom of two
    coordinates. The assembly sees the gap rows' rank fall on the closed loop (1 against 2 at a
    generic configuration) and refuses it as singular."""
    _redundant_reaction(d)
    d["system"]["name"] = "hinged_pair"
    for j in d["joint"][:2]:
        j.update(kind="revolute", axis=[1.0, 0.0, 0.0])


EF_ROD = {"name": "rod", "kind": "beam", "length": 0.3, "density": 7870.0, "youngs_modulus": 2.0e11,
          "shear_modulus": 7.7e10, "area": 2.8e-5, "inertia_z": 6.4e-11, "inertia_y": 6.4e-11,
          "torsion_constant": 1.28e-10, "model": {"variant": "ef", "elements": 4}}


def _ef_rod(d):
    """The rod an ef beam whose closing joint sits at a marker between its nodes (every 0.075 m)."""
    d["body"][1] = dict(EF_ROD, markers={"near": 0.2})
    _joint(d, "slider_pin").update(parent="rod.near")


def test_a_revolute_closing_the_loop_at_an_ef_rods_tip_meets_the_rigid_limit():
    """The twin slider-crank's rod a spatial ef beam (4 elements), the loop closed at its tip node
    by the slider's revolute pin (5 rows: the gap and the axes parallel, the tip section's axes
    exp(psi)): over 0.1 s of the spin-up, the slider's x against the rigid slider-crank's
    r cos(theta) + sqrt(l^2 - r^2 sin^2(theta)), with E, G x 100 and x 10^4 within 1.6e-7 and
    1.6e-9 m (measured; 6.8e-5 m at the rod's own stiffness): the flexible difference falls as
    1/E. The loop holds to round-off (measured 4e-16 m) and nothing leaves the plane."""
    d = _twin_closed_by("revolute")
    d["body"][1] = dict(EF_ROD)
    d["system"]["name"] = "sc_ef_closed"
    d["output"]["columns"] |= {"z_s": "z(slider.pin)", "th": "angle(crank_joint)"}
    b = built(d)
    errs = []
    for k in (1e2, 1e4):
        r = run_ok(b, t_end=0.1, dt=1e-4, integrator="genalpha3", params={"E": 2e11 * k, "G": 7.7e10 * k})
        rigid = 0.15 * np.cos(r["th"]) + np.sqrt(0.3**2 - (0.15 * np.sin(r["th"]))**2)
        errs.append(np.abs(r["x_s"] - rigid).max())
        assert np.abs(r["viol"]).max() < 1e-12 and np.abs(r["z_s"]).max() == 0
    assert r["th"][-1] > 7 and errs[1] < 1e-8, errs
    assert 30 < errs[0] / errs[1] < 300, errs


BAD = [  # (what, edit of the good scene's data, what the one line says)
    ("a closing joint between an ef beam's nodes", _ef_rod,
     "joint 'slider_pin': marker 'rod.near' at x = 0.2 m is not on a node of the ef beam's 4 elements (every 0.075 m)"),
    ("a closing revolute with a zero axis", lambda d: _joint(d, "slider_pin").update(axis=[0.0, 0.0, 0.0]),
     "joint 'slider_pin': a revolute joint needs an axis (three finite numbers, not all 0)"),
    ("a closing revolute on a loop that does not close",
     lambda d: _joint(d, "slide").update(initial={"value": 0.5, "fixed": True}),
     "joint 'slider_pin' (cut joint, closes a loop): cannot close at t = 0"),
    ("an initial angle of a closing revolute", lambda d: _joint(d, "slider_pin").update(initial=0.2),
     "joint 'slider_pin' closes a loop: initial applies to joints in the tree"),
    ("a slide of a closing cylindrical", lambda d: _joint(d, "slider_pin").update(kind="cylindrical", initial={"slide_rate": 1.0}),
     "joint 'slider_pin' closes a loop: slide_rate applies to joints in the tree"),
    ("a fixed closing prismatic", lambda d: _joint(d, "slider_pin").update(kind="prismatic", initial={"value": 0.0, "fixed": True}),
     "joint 'slider_pin' closes a loop: fixed applies to joints in the tree"),
    ("a closing clamp with an axis", lambda d: _joint(d, "slider_pin").update(kind="clamp"),
     "joint 'slider_pin': axis applies to revolute, prismatic, cylindrical and universal joints only"),
    ("a driver on a joint that does not exist",
     lambda d: d["driver"][0].update(joint="crank"), "driver 'crank_drive': joint 'crank' does not exist"),
    ("a driver on a revolute joint's slide",
     lambda d: d["driver"][0].update(coordinate="slide"),
     "driver 'crank_drive': joint 'crank_joint' (revolute) has no coordinate 'slide' (its coordinates: 'crank_joint'; it has one"),
    ("a driver on the closing joint",
     lambda d: d["driver"][0].update(joint="slider_pin"), "joint 'slider_pin' is a cut joint (it closes a loop)"),
    ("a driver on a coordinate that does not exist",
     lambda d: d["driver"][0].update(joint="crank_joint_slide"), "joint 'crank_joint_slide' does not exist"),
    ("a reaction of a redundant loop", _redundant_reaction,
     "system 'balls': joint(s) weld: the loops' constraints are redundant at t = 0 (6 rows of rank 5)"),
    ("a loop redundant in its gap rows", _hinged_pair,
     "system 'hinged_pair': joint 'weld' (cut joint, closes a loop): singular at t = 0"),
]


def test_the_good_scene_runs(tmp_path, capsys):
    scene_text_runs(tmp_path, capsys, toml_text(_twin_closed_by()))


@pytest.mark.parametrize("what,edit,says", BAD, ids=[b[0] for b in BAD])
def test_bad_closing_joints_are_refused(tmp_path, capsys, what, edit, says):
    scene_text_refused(tmp_path, capsys, _edited(_twin_closed_by(), edit), says)


# ----- drivers on a cylindrical joint's slide and a universal joint's second angle
M_S, SLIDE_V, SPIN = 2.0, 0.5, 3.0  # the slider's mass, its guided slide's speed, its start spin


def screw(driver: dict) -> dict:
    """A rigid slider on a cylindrical joint about ground's z (its centre of mass 0.2 m off the
    axis), spinning at SPIN, under gravity along -z, with `driver` on the joint."""
    return {
        "system": {"name": "screw", "dimension": 3},
        "body": [{"name": "slider", "kind": "rigid", "mass": M_S, "inertia": [0.02, 0.03, 0.04],
                  "com": [0.2, 0.0, 0.0], "markers": {"hole": [0.0, 0.0, 0.0]}}],
        "joint": [{"name": "c", "kind": "cylindrical", "parent": "ground", "point": [0.0, 0.0, 1.0],
                   "child": "slider.hole", "axis": [0.0, 0.0, 1.0], "initial": {"value": 0.0, "rate": SPIN}}],
        "driver": [driver],
        "gravity": {"g": [0.0, 0.0, -G]},
        "solver": {"integrator": "rk4", "dt": 1e-3, "t_end": 1.0},
        "output": {"interval": 0.01, "columns": {
            "phi": "angle(c)", "w": "rate(c)", "s": "slide(c)", "v": "slide_rate(c)", "Fz": "reaction(c, z)",
            "Mz": "reaction(c, mz)", "T": "T", "V": "V"}},
    }


def test_a_guided_slide_of_a_cylindrical_joint():
    """coordinate = "slide": the slide is theta(t) = SLIDE_V t, the turn stays free (it keeps its
    spin: nothing turns it about z), the joint carries the weight (the guide's force, M g along
    z, with the slide at constant speed) and no moment about its axis (measured: round-off)."""
    d = screw({"name": "lift", "kind": "guided", "joint": "c", "coordinate": "slide", "theta": f"{SLIDE_V}*t"})
    r = run_ok(built(d), t_end=1.0, dt=1e-3, integrator="rk4")
    assert np.abs(r["s"] - SLIDE_V * r.t).max() < 1e-14 and np.abs(r["v"] - SLIDE_V).max() < 1e-14
    assert np.abs(r["w"] - SPIN).max() < 1e-12 and np.abs(r["phi"] - SPIN * r.t).max() < 1e-11
    assert np.abs(r["Fz"] - M_S * G).max() < 1e-10 and np.abs(r["Mz"]).max() < 1e-10


def test_a_motor_on_a_cylindrical_joints_turn():
    """A motor (no coordinate: the turn) of torque tau0: the spin's rate grows as tau0 / I_z,O
    (I_z + m 0.2^2), the slide falls freely (s = -g t^2 / 2)."""
    tau0 = 0.3
    d = screw({"name": "m", "kind": "motor", "joint": "c", "torque": str(tau0)})
    r = run_ok(built(d), t_end=1.0, dt=1e-3, integrator="rk4")
    I_O = 0.04 + M_S * 0.2**2
    assert np.abs(r["w"] - (SPIN + tau0 / I_O * r.t)).max() < 1e-11
    assert np.abs(r["s"] + G * r.t**2 / 2).max() < 1e-11


def test_a_motor_on_a_universal_joints_second_angle():
    """test_universal_tree's bob on a cross, a constant torque tau0 about its second arm: the
    work it does is the energy's change, T + V - E(0) = tau0 (theta2 - theta2(0)) (rk4p at 1 ms
    over 1 s: measured 1e-11 J of 0.2 J)."""
    from test_universal_tree import SWING, _pendulum

    tau0 = 0.4
    d = _pendulum("uj_motor", SWING)
    d["driver"] = [{"name": "m", "kind": "motor", "joint": "u", "coordinate": "angle2", "torque": str(tau0)}]
    r = run_ok(built(d), t_end=1.0, dt=1e-3, integrator="rk4p")
    work = tau0 * (r["th2"] - r["th2"][0])
    E = r["T"] + r["V"]
    assert np.abs(work).max() > 0.1
    assert np.abs(E - E[0] - work).max() < 1e-8 * np.abs(work).max()
