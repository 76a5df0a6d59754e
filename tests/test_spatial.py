"""Spatial systems (dimension = 3, flexsym/physics/spatial.py): S5 `flap` and a tilted
flexible pendulum, checked against closed forms, the planar derivation, conservation of energy
and the generated C against casadi against sympy."""
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from flexsym.scenes.system_scene import system_from_dict
from system_data import built, derivation, edited_scene, refused_in_one_line, run_ok, with_model

ROOT = Path(__file__).resolve().parent.parent
FLAP = ROOT / "scenes" / "flap.toml"
RHO, E, A, L, IY, G_ = 3000.0, 7.0e10, 4.0e-4, 10.0, 8.0e-7, 9.81


def _flap_data(**changes) -> dict:
    data = tomllib.loads(FLAP.read_text())
    for key, value in changes.items():
        table, _, field = key.partition(".")
        data[table][field] = value
    return data


@pytest.fixture(scope="module")
def flap_m3():
    return built(_flap_data())


def test_flap_starts_in_the_static_sag(flap_m3):
    """t = 0: the cantilever sagged under gravity. The tip sag is rho A g L^4 / (8 E I_y)
    exactly (to round-off): the static mode is the tip's influence function, so a Ritz basis
    holding it gives the exact tip deflection (Maxwell-Betti), measured 2e-16 relative. The
    root flap moment from equilibrium is rho A g L^2 / 2 less the foreshortened arm: 2.8e-4
    below it; nothing loads the lag plane yet."""
    r = run_ok(flap_m3, t_end=0.05, dt=1e-3)
    sag = RHO * A * G_ * L**4 / (8 * E * IY)
    assert r["w_tip"][0] == pytest.approx(-sag, rel=1e-9)
    root = RHO * A * G_ * L**2 / 2
    assert 0 < (root - r["M_flap_A"][0]) / root < 1e-3
    assert r["v_tip"][0] == 0 and abs(r["M_lag_A"][0]) < 1e-9 * root


def test_flap_is_stiffened_by_the_spin(flap_m3):
    """At 6 rad/s (t > 15 s) the root axial force is the rigid blade's centrifugal load
    rho A w^2 L^2 / 2 (within the lag/flap shortening of the arm, measured 5.6e-4), and the
    centrifugal stiffening lifts the blade to 57 % of its sag. The linear model (m0, no
    geometric stiffening) keeps the sag and diverges in lag once the rate passes the
    blade's buckling speed, about 3.8 rad/s."""
    r = run_ok(flap_m3, t_end=20.0, dt=1e-3)
    late = r.t > 17.0
    n_rigid = RHO * A * 36.0 * L**2 / 2
    assert abs(r["N_A"][late] / n_rigid - 1).max() < 2e-3
    sag = RHO * A * G_ * L**4 / (8 * E * IY)
    assert -0.65 * sag < r["w_tip"][late].min() and r["w_tip"][late].max() < -0.5 * sag
    linear = built(_flap_data(), "m0")
    from flexsym.toolchain.run import run_built

    r0 = run_built(linear, t_end=20.0, dt=1e-3)
    assert not r0.ok and "diverged" in r0.status
    t_stop = r0.t[-1]  # the last row before the run stopped
    ts, ws = 15.0, 6.0
    rate = ws / ts * (t_stop - ts / (2 * np.pi) * np.sin(2 * np.pi * t_stop / ts))
    assert rate > 3.8  # diverged above the buckling speed, not before
    assert abs(r0["w_tip"] / sag + 1).max() < 1e-3  # the flap sag is not lifted


def _planar_twin(data: dict) -> dict:
    """The same hub and blade as a planar system (the lag plane), no gravity."""
    twin = {k: v for k, v in data.items() if k != "gravity"}
    twin["system"] = {"name": "flap_planar"}
    hub, blade = (dict(b) for b in data["body"])
    hub["inertia"], hub["markers"] = 1.0, {"centre": [0.0, 0.0]}
    for key in ("inertia_y", "torsion_constant", "shear_modulus"):
        blade.pop(key)
    blade["inertia"] = blade.pop("inertia_z")
    twin["body"] = [hub, blade]
    joints = [dict(j) for j in data["joint"]]
    joints[0]["point"] = [0.0, 0.0]
    joints[0].pop("axis")
    twin["joint"] = joints
    twin["output"] = {"interval": 0.01, "columns": {"v_tip": "v(blade, tip)", "N_A": "N(blade, root)",
                                                     "M_lag_A": "M(blade, root)"}}
    return twin


def test_flap_without_gravity_is_the_planar_spin_up():
    """g = 0: the spatial blade moves in its lag plane only, and its rows are the planar
    system's (the paper's spin-up, S0 on a guided hub) to round-off: measured 7e-15, 9e-15
    and 1.4e-14 of the peaks of v_tip, N_A and M_lag_A (the spatial kinetic energy is
    differentiated by casadi, the planar one by sympy); w_tip and the torsion moment stay 0."""
    data = _flap_data()
    data["gravity"] = {"g": [0.0, 0.0, 0.0]}
    data["system"]["start"] = "undeformed"
    kw = dict(t_end=20.0, dt=1e-3)
    spatial = run_ok(built(data, "m2"), **kw)
    planar = run_ok(built(_planar_twin(data), "m2"), **kw)
    for col in ("v_tip", "N_A", "M_lag_A"):
        assert np.abs(spatial[col] - planar[col]).max() <= 1e-9 * np.abs(planar[col]).max(), col
    assert np.abs(spatial["w_tip"]).max() == 0 and np.abs(spatial["T_A"]).max() == 0


def _tilted_pendulum() -> dict:
    """A flexible strip on a revolute joint whose axis is tilted out of every coordinate plane,
    released from rest: the swing bends it in both planes and twists it."""
    return {
        "system": {"name": "tilted", "dimension": 3},
        "body": [{"name": "strip", "kind": "beam", "length": 1.0, "density": 2700.0,
                  "youngs_modulus": 7.0e10, "shear_modulus": 2.6e10, "area": 1.0e-4,
                  "inertia_z": 3.3333e-9, "inertia_y": 2.0833e-10, "torsion_constant": 7.021e-10,
                  "model": "m3", "markers": {"near": 0.99}}],
        "joint": [{"name": "pin", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0, 0.0],
                   "axis": [0.2, 1.0, 0.4], "child": "strip.root"}],
        "gravity": {"g": [0.0, 0.0, -9.81]},
        "solver": {"integrator": "genalpha", "t_end": 1.0},
        "output": {"interval": 0.001, "columns": {"T": "T", "V": "V", "z_tip": "z(strip.tip)",
                                                   "w_mid": "w(strip, 0.5)", "My": "My(strip, root)",
                                                   "Mz": "Mz(strip, root)", "Mx": "Mx(strip, root)",
                                                   "th": "angle(pin)", "Rx": "reaction(pin, mx)",
                                                   "Ry": "reaction(pin, my)", "Rz": "reaction(pin, mz)",
                                                   "Qy": "Qy(strip, 0.5)", "sig": "sigma(strip, root, 0.001, 0.0005)",
                                                   "Rxz": "R(strip.tip, x, z)"}
                   | {f"R{i}{j}": f"R(strip.near, {i}, {j})" for i in "xyz" for j in "xyz"}
                   | {f"{c}_{m}": f"{c}(strip.{m})" for c in "xyz" for m in ("near", "tip")}},
    }


@pytest.fixture(scope="module")
def tilted():
    return built(_tilted_pendulum())


def test_tilted_pendulum_conserves_energy(tilted):
    """Nothing is guided, nothing dissipates and m3's strain model is conservative: T + V
    stays at its start (0: at rest, V = 0 at release) to the integrator's error, falling with
    the step at order 2 (trapezoidal Newmark; measured 3.3e-8 and 8.8e-9 of m g L/2 at 0.2 and
    0.1 ms, with Newton converged to 1e-14: at the default 1e-12 its residue is a floor of
    ~5e-8). The strip swings down (z_tip falls by most of its length), bends in both planes
    and twists."""
    errs = []
    for dt in (2e-4, 1e-4):
        r = run_ok(tilted, t_end=1.0, dt=dt, integrator="newmark", newton_tol=1e-14)
        scale = 2700 * 1e-4 * 1.0 * 9.81 * 0.5
        errs.append(np.abs(r["T"] + r["V"]).max() / scale)
    assert errs[1] < 2e-8
    assert 3.0 < errs[0] / errs[1] < 5.5
    assert r["z_tip"].min() < -0.5
    for col in ("My", "Mz", "Mx", "w_mid"):
        assert np.abs(r[col]).max() > 0, col


def test_root_section_moments_are_the_pin_reaction(tilted):
    """Two recoveries of one load: the root's section moments from the equilibrium of the whole
    strip (frame axes, the root unturned) are minus the pin's reaction moment on the strip
    (from the strip's momentum balance, ground axes, turned into the frame by the pin angle), to
    round-off over a swing that bends and twists the strip (measured 1.1e-14 N m of a 1.3 N m
    peak; 4.9e-5 before the sections' spin momentum had its gyroscopic part in My and Mz)."""
    r = run_ok(tilted, t_end=1.0, dt=1e-4, integrator="rk4p")
    a = np.array([0.2, 1.0, 0.4]) / np.linalg.norm([0.2, 1.0, 0.4])
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    worst = peak = 0.0
    for i, th in enumerate(r["th"]):
        A = np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K  # ground <- strip frame
        section = np.array([r[c][i] for c in ("Mx", "My", "Mz")])
        reaction = A.T @ np.array([r[c][i] for c in ("Rx", "Ry", "Rz")])
        worst, peak = max(worst, np.abs(section + reaction).max()), max(peak, np.abs(section).max())
    assert peak > 1.0 and worst < 1e-12 * peak, (worst, peak)


def test_a_beam_markers_orientation_is_a_rotation_along_the_deformed_axis(tilted):
    """R(strip.near, i, j) at x = 0.99 m: orthonormal with determinant 1 to round-off (the
    section's S = R_z R_y R_x; the first-order I + [theta]x was not, by theta^2), and its x
    axis along the deformed axis there: the chord to the tip, 1 cm on, within 1e-5 (measured:
    orthonormal to 6.7e-16, the axis within 1.3e-6, the chord's own error) while the strip
    swings and bends."""
    r = run_ok(tilted, t_end=1.0, dt=1e-4, integrator="rk4p")
    worst_ortho = worst_axis = 0.0
    for k in range(len(r["t"])):
        R = np.array([[r[f"R{i}{j}"][k] for j in "xyz"] for i in "xyz"])
        worst_ortho = max(worst_ortho, np.abs(R.T @ R - np.eye(3)).max(), abs(np.linalg.det(R) - 1))
        chord = np.array([r[f"{c}_tip"][k] - r[f"{c}_near"][k] for c in "xyz"])
        worst_axis = max(worst_axis, np.linalg.norm(R[:, 0] - chord / np.linalg.norm(chord)))
    assert worst_ortho < 1e-13 and worst_axis < 1e-5, (worst_ortho, worst_axis)


def test_spatial_kernels_c_casadi_sympy(tilted, system_kernels_agree):
    """The tilted pendulum's generated C kernels against casadi against sympy at a random state
    (its outputs: section moments, a shear force, a stress, joint reactions, an orientation)."""
    system_kernels_agree(derivation(_tilted_pendulum()), tilted, t=0.3, seed=5)


S6 = ROOT / "scenes" / "spherical_pendulum.toml"
S7 = ROOT / "scenes" / "spatial_slider_crank.toml"
PLANAR = ROOT / "scenes" / "double_pendulum.toml"
CARDAN_AXIS = "axis = [1.0, 0.0, 0.0]           # e1, the slider's axis (slider's frame)"
SLIDE_AXIS = 'axis = [1.0, 0.0, 0.0]\nchild = "slider.pin"'
HANGING = ('[[body]]\nname = "bob"\nkind = "rigid"\nmass = 0.1\ninertia = [1e-5, 1e-5, 1e-5]\n'
           'markers = { pin = [0.0, 0.0, 0.0] }\n\n[[joint]]\nname = "hinge"\nkind = "revolute"\n'
           'parent = "strip.tip"\nchild = "bob.pin"\n\n[gravity]')
BAD = [  # (what, scene, edits of its text, what the one line says)
    ("planar inertia on a spatial beam", FLAP, [("inertia_z = 2.0e-7", "inertia = 2.0e-7")],
     "inertia: a spatial beam has inertia_z"),
    ("missing torsion constant", FLAP, [("torsion_constant = 4.0e-7\n", "")], "torsion_constant: missing"),
    ("two-number point", FLAP, [("point = [0.0, 0.0, 0.0]", "point = [0.0, 0.0]")],
     "point: must be three finite numbers"),
    ("no gravity vector", FLAP, [("g = [0.0, 0.0, -9.81]", "")], "[gravity] g: missing"),
    ("planar moment output", FLAP, [('M_flap_A = "My(blade, root)"', 'M_flap_A = "M(blade, root)"')],
     "M is not derived for spatial systems yet (use Mx, My or Mz"),
    ("a universal joint in the tree", FLAP, [('kind = "revolute"', 'kind = "universal"')],
     "joint 'hub_joint': a universal joint in the tree needs parent_axis"),
    ("dimension 4", FLAP, [("dimension = 3", "dimension = 4")], "dimension: must be 2 (planar) or 3"),
    ("an orientation with one axis", FLAP, [('v_tip = "v(blade, tip)"', 'v_tip = "R(blade.tip, x)"')],
     "needs ('body.marker', i, j) with i, j each x, y or z"),
    ("an orientation about w", FLAP, [('v_tip = "v(blade, tip)"', 'v_tip = "R(blade.tip, x, w)"')],
     "needs ('body.marker', i, j) with i, j each x, y or z"),
    ("an ef beam's orientation between its nodes", FLAP,
     [('model = "m3"', 'model = { variant = "ef", elements = 4 }\nmarkers = { near = 3.3 }'),
      ('v_tip = "v(blade, tip)"', 'v_tip = "R(blade.near, x, y)"')],
     "output 'R(blade.near, x, y)': marker 'blade.near' at x = 3.3 m is not on a node of the ef beam's 4 "
     "elements (every 2.5 m)"),
    ("modal damping ratios on a spatial ef beam", FLAP,
     [('model = "m3"', 'model = { variant = "ef", elements = 4 }\ndamping = { zeta = 0.02 }')],
     "damping zeta applies to modal models (a ratio per mode); ef has no modes: give beta (and alpha)"),
    ("a zeta per planar coordinate", FLAP, [('model = "m3"', 'model = "m3"\ndamping = { zeta = [0.01, 0.02, 0.03] }')],
     "damping zeta has 3 values, model 'foreshortening' has 7 coordinates (v_static, v_cp1, v_cp2, vz_static, vz_cp1, "
     "vz_cp2, phi_ff1)"),
    # joints: axes, directions and rates
    ("revolute axis of zero length", FLAP, [("axis = [0.0, 0.0, 1.0]", "axis = [0.0, 0.0, 0.0]")],
     "joint 'hub_joint': a revolute joint needs an axis (three finite numbers, not all 0)"),
    ("revolute axis nearly zero", FLAP, [("axis = [0.0, 0.0, 1.0]", "axis = [0.0, 0.0, 1e-9]")],
     "joint 'hub_joint': axis [0.0, 0.0, 1e-09] is shorter than 1e-06"),
    ("non-finite axis", FLAP, [("axis = [0.0, 0.0, 1.0]", "axis = [0.0, nan, 1.0]")],
     "[[joint]] 'hub_joint' axis: must be three finite numbers [x, y, z] (got [0.0, nan, 1.0])"),
    ("prismatic axis of zero length", S7, [(SLIDE_AXIS, SLIDE_AXIS.replace("1.0", "0.0"))],
     "joint 'slide': a prismatic joint needs an axis (three finite numbers, not all 0)"),
    ("universal axis of zero length", S7, [(CARDAN_AXIS, "axis = [0.0, 0.0, 0.0]")],
     "joint 'cardan': a universal joint needs an axis (three finite numbers, not all 0) in the child's frame"),
    ("universal axis along the rod", S7, [(CARDAN_AXIS, "axis = [0.25495097567963926, 0.05, 0.15]")],
     "joint 'cardan': axis [0.25495097567963926, 0.05, 0.15] lies along the x axis of 'rod.tip' at t = 0"),
    ("universal without an axis", S7, [(CARDAN_AXIS, "")], "joint 'cardan': a universal joint needs its child's axis"),
    ("spherical joint with an axis", S6, [('child = "strip.root"', 'child = "strip.root"\naxis = [0.0, 0.0, 1.0]')],
     "joint 'ball': axis applies to revolute, prismatic, cylindrical and universal joints only"),
    ("spherical joint with an initial angle", S6, [("initial = { rate = [0.0, 0.0, 4.0] }", "initial = 0.3")],
     "[[joint]] 'ball' initial: a spherical joint starts with the child's frame parallel to the parent's"),
    ("spherical joint with an offset", S6, [('child = "strip.root"', 'child = "strip.root"\noffset = 0.5')],
     "joint 'ball': offset (a planar angle) does not apply to spatial joints"),
    ("direction on a revolute joint", FLAP, [("axis = [0.0, 0.0, 1.0]", "direction = [1.0, 0.0, 0.0]")],
     "joint 'hub_joint': direction applies to spatial spherical joints only"),
    ("direction of zero length", S7, [("direction = [0.25495097567963926, 0.05, 0.15]", "direction = [0.0, 0.0, 0.0]")],
     "joint 'ball': direction (0.0, 0.0, 0.0) must be three finite numbers, not all 0"),
    ("non-finite direction", S7, [("direction = [0.25495097567963926, 0.05, 0.15]", "direction = [nan, 0.05, 0.15]")],
     "[[joint]] 'ball' direction: must be three finite numbers [x, y, z] (got [nan, 0.05, 0.15])"),
    ("rate of two entries", S6, [("rate = [0.0, 0.0, 4.0]", "rate = [0.0, 4.0]")],
     "[[joint]] 'ball' initial rate: must be three finite numbers [x, y, z] (got [0.0, 4.0])"),
    ("rate of one number on a spherical joint", S6, [("rate = [0.0, 0.0, 4.0]", "rate = 4.0")],
     "[[joint]] 'ball' initial rate: must be three finite numbers [x, y, z] (got 4.0)"),
    ("rate vector on a revolute joint", FLAP, [('child = "hub.centre"', 'child = "hub.centre"\ninitial = { rate = [0.0, 0.0, 1.0] }')],
     "[[joint]] 'hub_joint' initial rate: must be a finite number (got [0.0, 0.0, 1.0])"),
    ("a body hung between an ef beam's nodes", S6,
     [('model = "m3"', 'model = { variant = "ef", elements = 3 }'), ("[gravity]", HANGING.replace("strip.tip", "strip.mid"))],
     "joint 'hinge': marker 'strip.mid' at x = 0.5 m is not on a node of the ef beam's 3 elements (every 0.333333 m)"),
    # bodies: inertia, sections, com, markers
    ("zero principal moment", FLAP, [("inertia = [1.0, 1.0, 1.0]", "inertia = [1.0, 0.0, 1.0]")],
     "body 'hub': inertia (1.0, 0.0, 1.0) must be three finite numbers > 0"),
    ("negative principal moment", FLAP, [("inertia = [1.0, 1.0, 1.0]", "inertia = [1.0, -1.0, 1.0]")],
     "body 'hub': inertia (1.0, -1.0, 1.0) must be three finite numbers > 0"),
    ("inertia breaking the triangle inequality", FLAP, [("inertia = [1.0, 1.0, 1.0]", "inertia = [1.0, 1.0, 3.0]")],
     "body 'hub': inertia [1.0, 1.0, 3.0] breaks the triangle inequality"),
    ("inertia as a full tensor", FLAP, [("inertia = [1.0, 1.0, 1.0]", "inertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]")],
     "[[body]] 'hub' inertia: must be three finite numbers [x, y, z]"),
    ("zero torsion constant", FLAP, [("torsion_constant = 4.0e-7", "torsion_constant = 0.0")],
     "[[body]] 'blade' torsion_constant: must be > 0 (got 0.0)"),
    ("negative shear modulus", FLAP, [("shear_modulus = 2.7e10", "shear_modulus = -2.7e10")],
     "[[body]] 'blade' shear_modulus: must be > 0 (got -27000000000.0)"),
    ("zero inertia_y", FLAP, [("inertia_y = 8.0e-7", "inertia_y = 0.0")], "[[body]] 'blade' inertia_y: must be > 0 (got 0.0)"),
    ("inertia_y below the smallest", FLAP, [("inertia_y = 8.0e-7", "inertia_y = 1e-30")],
     "body 'blade': section Iy = 1e-30 must be >= 1e-20"),
    ("section orientation (no such key)", FLAP, [("torsion_constant = 4.0e-7", "torsion_constant = 4.0e-7\norientation = [0.0, 1.0, 0.0]")],
     "[[body]] 'blade' orientation: unknown key"),
    ("two-entry com on a spatial body", S7, [("com = [0.05, 0.0, 0.0]", "com = [0.05, 0.0]")],
     "[[body]] 'crank' com: must be three finite numbers [x, y, z] (got [0.05, 0.0])"),
    ("three-entry com on a planar body", PLANAR, [("com = [0.15, 0.0]", "com = [0.15, 0.0, 0.0]")],
     "[[body]] 'upper' com: must be two finite numbers [x, y] (got [0.15, 0.0, 0.0])"),
    ("marker off a beam's axis", S6, [("markers = { mid = 0.5 }", "markers = { mid = [0.5, 0.0, 0.01] }")],
     "[[body]] 'strip' markers mid: a beam's marker is its distance x along the axis (m), one number"),
    # the rest of the file
    ("fz in a planar system", PLANAR, [("[gravity]", '[[load]]\nname = "push"\nkind = "force"\nmarker = "strip.tip"\n'
                                                     'fx = 0.0\nfy = 1.0\nfz = 2.0\n\n[gravity]')],
     "[[load]] 'push' fz: applies to spatial systems ([system] dimension = 3) only"),
    ("two-entry gravity", FLAP, [("g = [0.0, 0.0, -9.81]", "g = [0.0, -9.81]")],
     "[gravity] g: must be three finite numbers [x, y, z] (got [0.0, -9.81])"),
    ("dimension 3.0", FLAP, [("dimension = 3", "dimension = 3.0")],
     "[system] dimension: must be 2 (planar) or 3 (spatial) (got 3.0)"),
]


@pytest.mark.parametrize("what,scene,edits,says", BAD, ids=[b[0] for b in BAD])
def test_bad_spatial_scenes_are_refused(tmp_path, capsys, what, scene, edits, says):
    """Refused in one line naming the file and the item, exit 2, nothing written (in-process:
    the CLI's own main, as the command runs it)."""
    refused_in_one_line(capsys, edited_scene(tmp_path, what, scene, edits), says)


def test_a_bad_spatial_scene_is_refused_by_the_command(tmp_path):
    """The same through the installed command's process: exit code 2, one line on stderr."""
    what, scene, edits, says = next(b for b in BAD if b[0] == "universal axis along the rod")
    path, out = edited_scene(tmp_path, what, scene, edits), tmp_path / "out.csv"
    r = subprocess.run([sys.executable, "-m", "flexsym.apps.cli", "run", str(path), "--out", str(out)],
                       capture_output=True, text=True)
    assert r.returncode == 2, r.stderr
    assert r.stdout == "" and r.stderr.count("\n") == 1 and str(path) in r.stderr, r.stderr
    assert says in r.stderr, r.stderr
    assert not out.exists()


def test_spatial_outputs_are_refused_in_a_planar_system():
    data = _planar_twin(_flap_data())
    data["output"]["columns"]["w_tip"] = "vz(blade, tip)"
    with pytest.raises(Exception, match="vz applies to spatial systems"):
        system_from_dict(data, name="planar")


def test_frame_driven_is_the_derivations_decision():
    """System.frame_driven (a structural decision: clamps and guided joints to ground) says
    which spatial ef beams get their element kinetic energy in C: the frame's motion of those
    and only those is free of the coordinates in the derivation."""
    from flexsym.physics.spatial import derive_spatial

    for path, model in ((FLAP, {"variant": "ef", "elements": 2}), (S6, {"variant": "ef", "elements": 1})):
        data = with_model(tomllib.loads(path.read_text()), model)
        system = system_from_dict(data, name=data["system"]["name"])
        der = derive_spatial(system)
        for body in der.rod_bodies:
            fr = der.spatial["frames"][body["name"]]
            moved = sp.Matrix([*fr.omega, *fr.V]).free_symbols & (set(der.q) | set(der.qd))
            assert body["kinetic_in_c"] == (not moved) == system.frame_driven(body["name"])
        assert [b["kinetic_in_c"] for b in der.rod_bodies] == [path == FLAP]


def test_a_ball_joint_pointing_back_along_x_starts_turned_half_about_z():
    """A ball joint's start is the shortest turn of x to its direction, one decision
    (scenes/assembly.shortest_turn) for the assembly's frames and the Euler parameters: at
    -x, where that turn has no unique axis, both take the half turn about z (no nan)."""
    import sympy as sp

    from flexsym.physics.spatial import euler_rotation, initial_euler
    from flexsym.scenes.assembly import rotations3
    from flexsym.scenes.system_scene import system_from_data

    data = tomllib.loads(S6.read_text())
    ball = next(j for j in data["joint"] if j["kind"] == "spherical")
    ball["direction"] = [-2.0, 0.0, 0.0]
    frames = rotations3(system_from_data(data, "s6: ", "s6")[0])
    body = ball["child"].partition(".")[0]
    assert np.allclose(frames[body], np.diag([-1.0, -1.0, 1.0]), atol=1e-15)
    e, _ = initial_euler(ball["direction"], None)
    assert np.allclose(np.array(euler_rotation(sp.Matrix(e)).evalf(), dtype=float), frames[body], atol=1e-15)


def test_a_spatial_four_bar_written_with_a_rounded_length_assembles():
    """scenes/spatial_four_bar.toml (an RSUR four-bar as a user writes it: the coupler's length
    0.2265 m where the loop closes at 0.226495 m) assembles at t = 0 by turning the rocker and
    the ball joint's direction; independently of the assembly, the coupler's tip, L along the
    found direction from the crank pin, is then the rocker's tip to 1e-12 m."""
    from flexsym.scenes.system_scene import checked_system, system_from_data

    data = tomllib.loads((ROOT / "scenes" / "spatial_four_bar.toml").read_text())
    system, report = checked_system(system_from_data(data, "four-bar: ", "spatial_four_bar")[0])
    joints = {j.name: j for j in system.joints}
    theta = joints["rocker_joint"].initial
    d = np.array(joints["ball"].direction)
    tip = np.array([0.05, 0.0, 0.0]) + 0.2265 * d / np.linalg.norm(d)
    rocker_tip = np.array([0.2 + 0.12 * np.sin(theta), 0.12, 0.12 * np.cos(theta)])
    assert np.linalg.norm(tip - rocker_tip) < 1e-12
    assert 1e-5 < abs(theta) < 1e-3
    line = report.line()
    assert line.startswith("assembly: joint rocker_joint moved") and "joint ball direction turned" in line
