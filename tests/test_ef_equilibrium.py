"""N and M of a planar ef beam in a system from equilibrium (the default, as for a modal beam;
the elements' strain and curvature with moment / axial_force = "constitutive"): the inertial loads
and gravity on the elements beyond the station (efbody's EfPart.inertial: the elements' shapes
integrated exactly) with the frame's actual motion, and the loads on the markers beyond it.
Against an independent path (the clamp's reaction: the momentum balance of the whole beam
from efbody's generic element), and in the mesh: the elements' curvature converges as h^2,
the equilibrium as h^4."""
import tomllib
from pathlib import Path

import numpy as np
import pytest

from flexsym.core.errors import SpecError
from flexsym.scenes.system_scene import system_from_dict
from system_data import built, run_ok, with_model

ROOT = Path(__file__).resolve().parent.parent
EQUILIBRIUM = {"moment": "equilibrium", "axial_force": "equilibrium"}


def _scene(name: str, model: dict, columns: dict | None = None) -> dict:
    with open(ROOT / "scenes" / f"{name}.toml", "rb") as f:
        data = tomllib.load(f)
    if columns is not None:
        data["output"]["columns"] = columns
    return with_model(data, {"variant": "ef"} | model)


def _rel(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


def test_root_resultants_equal_the_clamps_reaction():
    """S1 (the hub's beam, 4 elements) over the spin-up's first 3 s: M at the root from the
    elements' inertial loads is minus the clamp's reaction moment, N minus its force along the
    frame's x axis (the root's tangent), both to round-off (measured 4e-15 and 2e-15 of their
    peaks over 20 s with 8 elements)."""
    data = _scene("hub", {"elements": 4} | EQUILIBRIUM, {
        "th": "angle(hub_joint)", "M_A": "M(beam, root)", "N_A": "N(beam, root)",
        "M_c": "reaction(clamp, moment)", "Rx": "reaction(clamp, x)", "Ry": "reaction(clamp, y)"})
    r = run_ok(built(data), t_end=3.0, dt=1e-3, out_every=10)
    assert np.abs(r["M_A"]).max() > 50 and np.abs(r["N_A"]).max() > 1  # the spin-up loads it
    assert _rel(r["M_A"], -r["M_c"]) <= 1e-12
    along = r["Rx"] * np.cos(r["th"]) + r["Ry"] * np.sin(r["th"])
    assert _rel(r["N_A"], -along) <= 1e-12


@pytest.fixture(scope="module")
def four_bar_runs():
    """The user's four-bar (rounded closing angles, coupler pinned at both ends: the rocker's
    pin loads it at its tip) with 4 and 8 ef elements, N and M from equilibrium."""
    return {n: run_ok(built(_scene("four_bar", {"elements": n} | EQUILIBRIUM)),
                      integrator="genalpha3", dt=1e-4, t_end=0.3, out_every=10)  # the scene's
            for n in (4, 8)}


def test_four_bar_mid_resultants_converge_at_order_four(four_bar_runs):
    """Mid-span N and M of the coupler: 4 against 8 elements within 1e-5 and 1e-4 of their
    peaks (measured 2.0e-6 and 1.3e-5; against 64 elements: 2.2e-6 and 1.4e-5 at 4, 1.9e-7 and 8.9e-7 at 8, 1.8e-8
    and 5.6e-8 at 16: order 4; the elements' curvature at 16 is 2.6e-3 off, at 64 1.6e-4)."""
    coarse, fine = four_bar_runs[4], four_bar_runs[8]
    assert np.abs(fine["M_mid"]).max() > 1.0 and np.abs(fine["N_mid"]).max() > 10.0
    assert _rel(coarse["N_mid"], fine["N_mid"]) <= 1e-5
    assert _rel(coarse["M_mid"], fine["M_mid"]) <= 1e-4


def test_torsion_modes_on_ef_are_refused():
    """Torsion modes on ef: one line, before any work (a spatial ef beam twists through its
    nodes' rotations; its N and moments from equilibrium: tests/test_spatial_ef_equilibrium.py)."""
    planar = _scene("four_bar", {"elements": 4, "torsion": []})
    with pytest.raises(SpecError, match="torsion to modal variants only"):
        system_from_dict(planar, name="four_bar")
