"""Shear forces Qy, Qz and the normal stress sigma(beam, x, y, z) of spatial beams
(physics/spatial.py: _section, _sigma), each against a closed form or a balance it must meet.

Q of a modal beam is always the force of the part beyond x from equilibrium (the
Euler-Bernoulli beam has no shear strain), turned to the deformed section's axes like the
moments: Q = (S - theta x S)_{y,z}, theta = (phi, -vz_x, v_x). sigma = N/A - Mz y/I_z + My z/I_y.
Three builds: a clamped strip at rest (static start) under gravity and a tip force, the planar
pendulum S3, and its spatial twin (tests/test_planar_as_spatial.py's pair, built once for both)."""
from pathlib import Path

import numpy as np
import pytest

from system_data import built, run_ok
from test_planar_as_spatial import C, H, STEPS, X, open_chain_pair

ROOT = Path(__file__).resolve().parent.parent
RHO, E, A, IZ, IY, L, G = 2700.0, 7.0e10, 1.0e-4, 3.3333e-9, 2.0833e-10, 1.0, 9.81
FX, FZ = 40.0, -0.3  # the tip force (ground axes): a pull along the strip and a push down
W = RHO * A * G  # the weight per metre
Y, Z = 0.004, 0.0012  # a section point (within the 20 mm x 5 mm strip's reach)


def _strip() -> dict:
    """A strip clamped to ground along x, bending along z under gravity (-z) and a tip force
    (FX, 0, FZ); linear strain without axial modes (u = 0: the closed forms below are exact),
    N and the moments from equilibrium; started at rest in static equilibrium."""
    cols = {"N0": "N(strip, root)", "Qy0": "Qy(strip, root)", "Qz0": "Qz(strip, root)",
            "My0": "My(strip, root)", "Mz0": "Mz(strip, root)", "s0": f"sigma(strip, root, {Y}, {Z})",
            "Qy": f"Qy(strip, {X})", "Qz": f"Qz(strip, {X})", "vz_tip": "vz(strip, tip)",
            "My0_eq": "My(strip, root, equilibrium)", "My0_con": "My(strip, root, constitutive)"}
    for k, n in STEPS.items():
        cols |= {f"My_{k}": f"My(strip, {X + n * H:g})", f"vz_{k}": f"vz(strip, {X + n * H:g})"}
    return {
        "system": {"name": "shear_strip", "dimension": 3, "start": "static"},
        "body": [{"name": "strip", "kind": "beam", "length": L, "density": RHO, "youngs_modulus": E,
                  "shear_modulus": 2.6e10, "area": A, "inertia_z": IZ, "inertia_y": IY,
                  "torsion_constant": 7.021e-10, "markers": {"tip": L},
                  "model": {"strain": "linear", "axial": [], "bending": ["cf1", "cf2", "cf3"],
                            "axial_force": "equilibrium", "moment": "equilibrium"}}],
        "joint": [{"name": "root", "kind": "clamp", "parent": "ground", "point": [0.0, 0.0, 0.0],
                   "child": "strip.root"}],
        "load": [{"kind": "force", "name": "push", "marker": "strip.tip", "fx": FX, "fy": 0.0, "fz": FZ}],
        "gravity": {"g": [0.0, 0.0, -G]},
        "output": {"interval": 0.001, "columns": cols},
    }


def d_dx(r, name):
    """d/dx at X of the columns name_m2 .. name_p2 (central, fourth order: error H^4 f^(5)/30)."""
    return (8 * (r[f"{name}_p1"] - r[f"{name}_m1"]) - (r[f"{name}_p2"] - r[f"{name}_m2"])) / (12 * H)


@pytest.fixture(scope="module")
def strip():
    return run_ok(built(_strip()), integrator="genalpha", dt=1e-4, t_end=0.005)


def test_root_shear_is_the_weight_and_the_tip_force(strip):
    """At the clamped root the section's axes are the frame's: N = FX, Qz = FZ - W L (the tip
    force and the weight beyond), Qy = 0, all rows (at rest) to 1e-12 of W L (measured: 0)."""
    for col, want in (("N0", FX), ("Qz0", FZ - W * L), ("Qy0", 0.0)):
        assert np.abs(strip[col] - want).max() <= 1e-12 * W * L, (col, strip[col][0], want)


def test_shear_along_the_strip_is_the_load_beyond_turned_to_the_section(strip):
    """At X the force of the part beyond is S = (FX, 0, FZ - W (L - X)) (linear in X), and the
    section is turned by its slope vz_x: Qz = S_z - vz_x S_x, vz_x from the run's own vz at
    X + k H (fourth-order differences; second-order ones were off by H^2 vz''' FX / 6, 9e-5 of
    Qz). Measured 4.6e-9 of |Qz|; without the turn (Qz = S_z) the error
    would be vz_x FX = 1.0 N, 88 % of Qz."""
    slope = d_dx(strip, "vz")[0]
    assert abs(slope * FX) > 0.1 * abs(FZ - W * (L - X))  # the turn matters here
    want = FZ - W * (L - X) - slope * FX
    err = abs(strip["Qz"][0] - want) / abs(want)
    assert err < 1e-6, (strip["Qz"][0], want, err)
    assert np.abs(strip["Qy"]).max() == 0.0  # nothing bends the strip along y


def test_the_moment_changes_by_the_shear(strip):
    """dMy/dx = Qz (M: the loads beyond x on the part before it; r' x S gives (1 + u') S_z -
    vz_x S_x, u' = 0 here): differences of My at X + k H against Qz at X. Measured 4.6e-9, the
    error of the differences of vz above (My = W (L - x)^2/2 - (L - x) FZ + (vz_tip - vz) FX)."""
    dM = d_dx(strip, "My")[0]
    err = abs(dM - strip["Qz"][0]) / abs(strip["Qz"][0])
    assert err < 1e-6, (dM, strip["Qz"][0], err)


def test_an_outputs_own_recovery_at_a_station_its_beam_recovers_otherwise(strip):
    """My at the root from the modes' curvature next to the beam's own (equilibrium) in one
    derivation: each is computed once per station and recovery (the sections' memo holds the
    recovery in its key), so the constitutive column is its own and the equilibrium one is My0
    (exactly). The constitutive one equals a model-level "constitutive" run's My0 (measured
    once, to 0): 1.61 N m, near the linear beam's W L^2/2 - L FZ = 1.62 N m, since its strain
    does not see the pull's moment FX vz_tip, which equilibrium takes (0.442 N m)."""
    assert np.array_equal(strip["My0_eq"], strip["My0"])
    assert np.abs(strip["My0_con"] - strip["My0"]).max() > 1e-2 * np.abs(strip["My0"]).max()


def test_root_stress_against_its_columns_and_the_closed_form(strip):
    """sigma(root, Y, Z) = N/A - Mz Y/I_z + My Z/I_y from the run's own columns (measured 3e-16),
    and the cantilever's closed form with My = W L^2/2 - L FZ + vz_tip FX (u = 0: the tip is at
    (L, 0, vz_tip)): sigma = FX/A + My Z/I_y, to 1e-12 (measured 0)."""
    cols = strip["N0"] / A - strip["Mz0"] * Y / IZ + strip["My0"] * Z / IY
    assert np.abs(strip["s0"] - cols).max() <= 1e-13 * np.abs(cols).max()
    My = W * L**2 / 2 - L * FZ + strip["vz_tip"][0] * FX
    want = FX / A + My * Z / IY
    assert abs(strip["s0"][0] - want) <= 1e-12 * abs(want), (strip["s0"][0], want)


def test_planar_sigma_is_the_spatial_sigma_at_z_0_and_the_moment_changes_by_the_shear():
    """S3 (the pendulum falling from horizontal, 0.5 s) run planar and as its spatial twin:
    sigma(beam, X, C) planar = sigma(beam, X, C, 0) spatial to 1e-9 of the peak (the open
    chain's rows agree to round-off: measured 2.8e-14). In the twin (dynamic: the swing's
    centrifugal S_x, the released strip's vibration), dMz/dx = -Qy: -r' x S gives
    -(1 + u') S_y + v_x S_x = -Qy - u' S_y, with u' = -v_x^2/2 (foreshortening), by
    fourth-order differences at X + k H; measured 2.6e-6 of the peak |Qy| (second-order
    differences: 8e-4, H^2 S_y''/6 of the vibration's higher modes). The turn of Q, v_x S_x from
    the run's own v and N, is 2.6e-2 of the peak: the check sees it. The pair is
    test_planar_as_spatial's (one twin build for both files)."""
    data, twin = open_chain_pair("pendulum")
    kw = dict(integrator="genalpha", dt=1e-4, t_end=0.5)
    planar, spatial = run_ok(built(data), **kw), run_ok(built(twin), **kw)
    peak = np.abs(planar["s"]).max()
    assert peak > 1e6
    assert np.abs(spatial["s"] - planar["s"]).max() <= 1e-9 * peak
    assert np.abs(spatial["s_z"] - spatial["s"]).max() <= 1e-9 * peak  # My = 0 in the plane
    Qmax = np.abs(spatial["Qy"]).max()
    assert np.abs(spatial["Qz"]).max() <= 1e-12 * Qmax
    err = np.abs(d_dx(spatial, "Mz") + spatial["Qy"]).max() / Qmax
    turn = np.abs(d_dx(spatial, "v") * spatial["N"]).max() / Qmax
    assert err < 1e-5 and turn > 10 * err, (err, turn)


FLAP = (ROOT / "scenes" / "flap.toml").read_text()
PLANAR = (ROOT / "scenes" / "pendulum.toml").read_text()
FLAP_N_CONSTITUTIVE = FLAP.replace('model = "m3"', 'model = { variant = "m3", axial_force = "constitutive" }')
FLAP_COLUMNS = FLAP[FLAP.index("columns = {"):].splitlines()[0]
PLANAR_COLUMNS = PLANAR[PLANAR.index("columns = {"):].splitlines()[0]


BAD = [  # (scene, output, what the one line says)
    (PLANAR, "Qy(beam, mid)", "Qy applies to spatial systems (dimension = 3) only"),
    (PLANAR, "sigma(beam, mid, 0.001, 0.0)", "needs (beam, x, y):"),
    (FLAP, "sigma(blade, 1.0, 0.01)", "needs (beam, x, y, z) in a spatial system"),
    (FLAP, "sigma(blade, 1.0, 0.0, 0.5)", "z = 0.5 m is farther from the axis than any section"),
    (FLAP, "sigma(blade, 1.0, 0.3, 0.0)", "y = 0.3 m is farther from the axis than any section"),
    (FLAP, "sigma(blade, 1.0, 0.0, top)", "z = 'top' is not a number"),
    (FLAP, "Qz(blade, 1.0, 0.0)", "needs (beam, x) with x a marker name"),
    (FLAP, "Qy(hub, 1.0)", "'hub' is not a flexible body"),
    (FLAP_N_CONSTITUTIVE, "sigma(blade, 1.0, 0.0, 0.01)", "has no axial mode to carry N"),
    # an output's own recovery (tests/test_output_recovery.py)
    (PLANAR, "M(beam, mid, curvature)", "the recovery 'curvature' must be one of equilibrium, constitutive"),
    (PLANAR, "N(beam, mid, constitutive)", "has no axial mode to carry N"),
    (PLANAR, "w(beam, mid, equilibrium)", "needs (beam, x) with x a marker name"),
    (FLAP, "Qy(blade, 1.0, constitutive)", "needs (beam, x) with x a marker name"),
    (FLAP, "My(blade, 1.0, equilibrium, 2)", "needs (beam, x) or (beam, x, recovery)"),
    # a station's side (tests/test_station_sides.py)
    (PLANAR, "v(beam, mid-)", "a side of the station (mid-) applies to section forces, moments and stresses"),
    (FLAP, "vz(blade, 1.0+)", "a side of the station (1.0+) applies to section forces"),
    (PLANAR, "N(beam, 0.0-)", "no beam on that side of x = 0 m"),
    (PLANAR, "M(beam, tip+, constitutive)", "no beam on that side of x = 1 m"),
    (PLANAR, "M(beam, mid*)", "'mid*' is neither a marker of 'beam' nor a number"),
    (FLAP, "Qz(blade, 0.0-)", "no beam on that side of x = 0 m"),
]


@pytest.mark.parametrize("scene,quantity,says", BAD,
                         ids=[("planar " if b[0] is PLANAR else "spatial ") + b[1] for b in BAD])
def test_bad_section_outputs_are_refused_in_one_line(tmp_path, capsys, scene, quantity, says):
    """Exit 2, one line naming the file and the output, nothing written, before any work (sigma
    in 3D needs N: a model without axial modes whose N is constitutive cannot give it)."""
    from flexsym.apps.cli import main

    columns = PLANAR_COLUMNS if scene is PLANAR else FLAP_COLUMNS
    path, out = tmp_path / "bad.toml", tmp_path / "out.csv"
    path.write_text(scene.replace(columns, f'columns = {{ q = "{quantity}" }}'))
    assert main(["run", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(path) in err and f"'{quantity}'" in err and says in err, err
    assert not out.exists()
