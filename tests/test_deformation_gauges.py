"""A system's bodies held to their models' range along a run (physics/validity.assess_system,
each body kind's `gauges`): what the gauges read is checked against the fields they stand for,
and a driven motion beyond a linkage's reach, which stretches its coupler, is flagged."""
from __future__ import annotations

import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from flexsym.model.modes import s
from flexsym.model.system import FlexibleBeam, Section
from flexsym.model.variant import builtin, customize
from flexsym.physics.body_kinds import kind_of
from flexsym.physics.body_kinds.spatial import kind_of as spatial_kind_of
from flexsym.physics.validity import STRAIN_LIMIT, VALIDITY_LIMIT

SCENES = Path(__file__).resolve().parent.parent / "scenes"
STEEL = Section(rho=7850.0, E=2.1e11, A=5e-5, I=2e-10, Iy=2e-10, J=4e-10, G=8e10)


def _beam(model, length=0.4) -> FlexibleBeam:
    return FlexibleBeam("bar", length, STEEL, model)


def _only(gauges, what):
    [g] = [g for g in gauges if what in g.what]
    return g


def test_planar_ef_reads_the_stretch_of_its_nodes_and_not_their_turn():
    """|r'| - 1 at the nodes, r' = (1 + dx, dy): a uniform stretch e reads e; slopes turned
    by 0.7 rad with no stretch read nothing (a rigid turn is no strain)."""
    n = 4
    b = _beam(replace(builtin("ef"), elements=n))
    g = _only(kind_of(b).gauges(b, b.length), "axial strain")
    e = np.array([0.0, 0.004, 0.02])
    cols = {"bar_dx0": e} | {f"bar_{c}{k}": v for k in range(1, n + 1)
                             for c, v in (("ux", 9 * e), ("uy", e), ("dx", e), ("dy", 0 * e))}
    assert np.allclose(g.history(cols), e, rtol=0, atol=1e-15) and g.limit == STRAIN_LIMIT
    th = np.array([0.0, 0.3, 0.7])
    turned = cols | {f"bar_dx{k}": np.cos(th) - 1 for k in range(1, n + 1)} | {
        f"bar_dy{k}": np.sin(th) for k in range(1, n + 1)} | {"bar_dx0": 0 * th}
    assert np.max(g.history(turned)) < 1e-15


def test_spatial_ef_reads_the_stretch_of_its_elements_and_not_their_turn():
    """The chord of each element: a uniform stretch e (u_x = e x) reads e; the beam turned as
    a whole about the root (nodes at R (x, 0, 0)) reads nothing."""
    n, L = 3, 0.4
    b = _beam(replace(builtin("ef"), elements=n), L)
    g = _only(spatial_kind_of(b).gauges(b, b.length), "axial strain")
    e = np.array([0.0, 0.01, 0.05])
    x = [k * L / n for k in range(1, n + 1)]
    cols = {f"bar_{c}{k}": (e * x[k - 1] if c == "ux" else 0 * e) for k in range(1, n + 1)
            for c in ("ux", "uy", "uz", "px", "py", "pz")}
    assert np.allclose(g.history(cols), e, rtol=0, atol=1e-14)
    a = np.array([0.0, 0.4, 1.2])  # about an axis in the x-y plane's normal, then tilted
    d = np.array([np.cos(a) * np.cos(0.3), np.sin(a) * np.cos(0.3), np.full_like(a, np.sin(0.3))])
    turned = {f"bar_{c}{k}": (x[k - 1] * (d[i] - (i == 0)) if i < 3 else 0 * a)
              for k in range(1, n + 1) for i, c in enumerate(("ux", "uy", "uz", "px", "py", "pz"))}
    assert np.max(g.history(turned)[1:]) < 1e-14


def _field_peak(expr, q, L, derivative):
    """max |d^k (q phi(x / L)) / dx^k| on a grid of its own, by np.gradient (not the mode's
    sympy derivative that the gauge reads)."""
    x = np.linspace(0.0, L, 40001)
    f = q * np.broadcast_to(sp.lambdify(s, expr, "numpy")(x / L), x.shape)
    for _ in range(derivative):
        f = np.gradient(f, x)
    return np.max(np.abs(f))


@pytest.mark.parametrize("dimension", [2, 3])
def test_a_modal_beam_reads_its_axial_strain_and_deflection_bounds(dimension):
    """One mode each: the axial bound is the strain field's peak, the deflection bound the
    deflection's (both tight for one mode); two bending planes combine as |(v, w)|. Against
    the field evaluated and differentiated numerically."""
    L = 0.4
    spec = customize(builtin("m2"), axial="ff1", bending="cf1", name="bar_m2")
    b = _beam(spec, L)
    kind = (kind_of if dimension == 2 else spatial_kind_of)(b)
    gauges = kind.gauges(b, L)
    qa, qv, qw = 3e-4, 0.01, 0.02
    cols = {f"bar_{spec.axial[0].coordinate}": np.array([qa]), f"bar_{spec.bending[0].coordinate}": np.array([qv])}
    if dimension == 3:
        cols[f"bar_vz_{spec.bending[0].token}"] = np.array([qw])
    strain = _only(gauges, "axial strain").history(cols)[0]
    assert strain == pytest.approx(_field_peak(spec.mode(spec.axial[0]).expr, qa, L, 1), rel=1e-6)
    g = _only(gauges, "|v|" if dimension == 2 else "|(v, w)|")
    assert g.limit == pytest.approx(VALIDITY_LIMIT * L)
    peak = _field_peak(spec.mode(spec.bending[0]).expr, 1.0, L, 0)
    want = peak * (qv if dimension == 2 else np.hypot(qv, qw))
    assert g.history(cols)[0] == pytest.approx(want, rel=1e-9)


def test_exact_kinematics_has_no_deflection_limit_but_its_truncation_share():
    b = _beam(customize(builtin("exact"), bending="cf1,cf2,cf3", name="bar_exact"))
    whats = [g.what for g in kind_of(b).gauges(b, b.length)]
    assert not any("|v|" in w for w in whats) and any("cf3" in w and "share" in w for w in whats)


def test_a_drive_beyond_the_linkages_reach_is_flagged(tmp_path):
    """The four-bar with a 0.25 m coupler closes at t = 0 (crank tip 0.4 m from the rocker's
    pivot, coupler and rocker 0.55 m), but the crank's half turn puts its tip 0.6 m away: the
    coupler's axial mode absorbs the gap, 20 % strain before Newton gives up at 0.17 s. Run to
    0.15 s, the run completes: exit 4, the coupler named, its strain and the first time over
    1 %; the CSV is written. In-process, the scene's own four-bar run with L = 0.25 m (a
run-time parameter) says the same. The same scene with its
    own 0.4 m coupler is inside."""
    text = (SCENES / "four_bar.toml").read_text()
    scene = tmp_path / "short.toml"
    scene.write_text(text.replace("length = 0.4\n", "length = 0.25\n").replace("mid = 0.2 }", "mid = 0.125 }"))
    out = tmp_path / "short.csv"
    run = subprocess.run([sys.executable, "-m", "flexsym.apps.cli", "run", str(scene), "--t-end", "0.15",
                          "--out", str(out)], capture_output=True, text=True)
    assert run.returncode == 4, run.stderr
    [note] = [line for line in run.stderr.splitlines() if "range of validity" in line]
    assert "body 'coupler'" in note and "axial strain" in note and "t = 0.13 s" in note
    assert "outside its model's range" in run.stdout and out.exists()
    from flexsym.apps import api  # in-process, the same gauges on each run's rows, at its L

    b = api.inprocess(SCENES / "four_bar.toml").batch({"L": [0.4, 0.25]}, t_end=0.15)
    assert b.status == ["ok", "ok"] and list(b.valid) == [True, False]
    assert "body 'coupler'" in b.validity_notes[1] and "|axial strain| = 0.0155 > 0.01" in b.validity_notes[1]
    assert "t = 0.13 s" in b.validity_notes[1] and "|axial strain| = 0.0155 > 0.01" in note
    own = subprocess.run([sys.executable, "-m", "flexsym.apps.cli", "run", str(SCENES / "four_bar.toml"),
                          "--t-end", "0.15"], capture_output=True, text=True)
    assert own.returncode == 0 and "range of validity" not in own.stderr, own.stderr


@pytest.mark.study  # about a minute: ef on 32 and 16 elements at two steps
def test_select_refuses_a_mechanism_whose_reference_leaves_its_range(tmp_path):
    """select scores models against ef; the short four-bar run to 0.135 s completes, but its ef
    reference's coupler is stretched past 1 %: one line, exit 2, no table."""
    text = (SCENES / "four_bar.toml").read_text()
    scene = tmp_path / "short.toml"
    scene.write_text(text.replace("length = 0.4\n", "length = 0.25\n").replace("mid = 0.2 }", "mid = 0.125 }")
                     .replace("t_end = 0.3", "t_end = 0.135"))
    run = subprocess.run([sys.executable, "-m", "flexsym.apps.cli", "select", str(scene), "--tol", "0.01"],
                         capture_output=True, text=True)
    assert run.returncode == 2, run.stderr
    assert run.stderr.count("\n") == 1 and "the ef reference body 'coupler' left the range" in run.stderr
