"""A section's side, x- or x+ (system.station_side): where N, M or sigma jump along a beam
(a step of the section, a point mass, a load at a marker), a station names the side it reads.

The scene: S4's stepped blade on S1's free hub (scenes/stepped_hub.toml) with a second point
mass, 0.3 kg at the step (x = 5 m), spun up for 16 s. From equilibrium, N(step-) carries the
point mass and N(step+) does not, so their difference is the mass's centripetal load
m omega^2 x (to the deflection's and the hub's angular acceleration's share: measured 4.5e-5
with m3, 2.1e-5 with `ef` on 4 elements); N without a side is the part beyond, N(step+); N at
the tip carries the tip mass, m omega^2 L (measured 1.1e-4 and 1.0e-4). The constitutive
moment at a node is the element's on that side, and without a side the mean of both. sigma reads N, M and the section
of the side named; without a side at a step of the section it is refused."""
from __future__ import annotations

import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from flexsym.apps.cli import main
from system_data import built, run_ok

ROOT = Path(__file__).resolve().parents[1]
STEPPED = (ROOT / "scenes" / "stepped_hub.toml").read_text()
MASSES = "point_masses = [ { x = 5.0, mass = 0.3 }, { x = 10.0, mass = 0.5 } ]"
COLUMNS = {
    "omega": "rate(hub_joint)",
    "Nl": "N(blade, step-)", "Nr": "N(blade, step+)", "N0": "N(blade, step)", "Ntip": "N(blade, tip)",
    "Ml": "M(blade, step-)", "Mr": "M(blade, step+)",
    "Mcl": "M(blade, step-, constitutive)", "Mcr": "M(blade, step+, constitutive)",
    "Mc0": "M(blade, step, constitutive)",
    "sl": "sigma(blade, step-, 0.01)", "sr": "sigma(blade, 5.0+, 0.01)",
}
# the constitutive moment 1 mm before and beyond the step, inside one element each
NEAR = {"Mcm": "M(blade, 4.999, constitutive)", "Mcp": "M(blade, 5.001, constitutive)"}
SECTIONS = {"l": (4.0e-4, 2.0e-7), "r": (2.0e-4, 5.0e-8)}  # (A, I) before and beyond the step


def _scene(model: str) -> dict:
    text = STEPPED.replace("point_masses = [ { x = 10.0, mass = 0.5 } ]", MASSES)
    text = text.replace("elements = 100 ", "elements = 20 ")
    text = re.sub(r"\nmodel = .*\n", f"\nmodel = {model}\n", text)
    data = tomllib.loads(text)
    data["system"]["name"] = "stepped_sides"
    data["output"]["columns"] = COLUMNS | NEAR
    return data


M3 = '{ variant = "m3", axial_force = "equilibrium", moment = "equilibrium" }'
KW = dict(t_end=16.0, dt=1e-3)


@pytest.mark.parametrize("model,tol", [(M3, 1e-3), ('{ variant = "ef", elements = 4 }', 1e-3)],
                         ids=["m3", "ef"])
def test_each_side_of_a_node_with_a_point_mass_and_a_step(model, tol):
    r = run_ok(built(_scene(model)), **KW)
    k = -1
    w2 = r["omega"][k] ** 2
    assert w2 > 30  # spun up
    assert np.array_equal(r["N0"], r["Nr"])  # no side: the part beyond
    jump = r["Nl"][k] - r["Nr"][k]
    assert abs(jump - 0.3 * w2 * 5.0) <= tol * 0.3 * w2 * 5.0, jump
    assert abs(r["Ntip"][k] - 0.5 * w2 * 10.0) <= tol * 0.5 * w2 * 10.0, r["Ntip"][k]
    # no couple at the step: the equilibrium moment is continuous there
    assert np.abs(r["Ml"] - r["Mr"]).max() <= 1e-9 * np.abs(r["Ml"]).max()
    # the constitutive moment on a side is its element's end: 1 mm inside that element it is
    # closer to it than to the other side's (m3: 4.1e-4 against 1.0e-3 of the peak; ef: 4.9e-4
    # against 2.2e-2); without a side, the mean of the two
    gap = lambda a, b: np.abs(r[a] - r[b]).max()  # noqa: E731
    assert gap("Mcm", "Mcl") < 0.5 * gap("Mcm", "Mcr") and gap("Mcp", "Mcr") < 0.5 * gap("Mcp", "Mcl")
    mean = (r["Mcl"] + r["Mcr"]) / 2
    assert np.abs(r["Mc0"] - mean).max() <= 1e-12 * np.abs(mean).max()
    for side, (A, I) in SECTIONS.items():
        want = r[f"N{side}"] / A - r[f"M{side}"] * 0.01 / I
        assert np.abs(r[f"s{side}"] - want).max() <= 1e-12 * np.abs(want).max(), side


def test_sigma_at_a_step_without_a_side_is_refused(tmp_path, capsys):
    """Exit 2, one line naming the file and the output, nothing written."""
    path, out = tmp_path / "bad.toml", tmp_path / "out.csv"
    text = re.sub(r"columns = \{.*\}", 'columns = { s = "sigma(blade, step, 0.01)" }', STEPPED)
    path.write_text(text)
    assert main(["run", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(path) in err and "'sigma(blade, step, 0.01)'" in err, err
    assert "the section steps at x = 5 m, so sigma has a value on either side: name one, step- or step+" in err
    assert not out.exists()


def test_the_sides_in_3d_are_the_planar_ones():
    """The same scene as a spatial system (tests/test_planar_as_spatial.py's twin: motion in
    the plane), m3: every sided column within 1e-9 of its peak of the planar one (measured
    4.7e-15 and below; the constitutive moment at the node 3.2e-11: the element recovery in
    the plane, EI v'' of the element on that side in 3D)."""
    from test_planar_as_spatial import spatial_twin

    data = _scene(M3)
    twin = spatial_twin(data)
    for side in ("l", "r"):
        twin["output"]["columns"][f"s{side}"] = COLUMNS[f"s{side}"].replace(")", ", 0.0)")
    planar, spatial = run_ok(built(data), **KW), run_ok(built(twin), **KW)
    worst = {c: np.abs(spatial[c] - planar[c]).max() / np.abs(planar[c]).max() for c in COLUMNS}
    assert max(worst.values()) <= 1e-9, worst
