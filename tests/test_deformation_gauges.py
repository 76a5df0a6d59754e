"""A system's bodies held to their models' range along a run (physics/validity.assess_system,
each body kind's `gauges`): what the gauges read is checked against the fields they stand for,
and a driven motion beyond a linkage's reach, which stretches its coupler, is flagged."""
from __future__ import annotations

import math
import re
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
from flexsym.model import fedata
from flexsym.physics.validity import STRAIN_LIMIT, TWIST_LIMIT, VALIDITY_LIMIT
from flexsym.core.errors import SpecError
from flexsym.scenes.scene import load_scene

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


def test_a_spatial_modal_beam_reads_its_twist_bound():
    """3D: sum_j |q_j| max|psi_j| of the torsion coordinates (the bar's shapes), in rad,
    against TWIST_LIMIT; with one mode the twist field's own peak (evaluated numerically)."""
    L, q = 0.4, np.array([0.0, 0.02, -0.3])
    spec = customize(builtin("m3"), bending="cf1", name="bar_m3")
    b = _beam(spec, L)
    g = _only(spatial_kind_of(b).gauges(b, L), "twist")
    [ref] = spec.torsion
    assert g.limit == TWIST_LIMIT and g.unit == " rad"
    want = np.abs(q) * _field_peak(spec.mode(ref).expr, 1.0, L, 0)
    assert np.allclose(g.history({f"bar_phi_{ref.token}": q}), want, rtol=1e-9, atol=0)
    none = replace(spec, torsion=())
    assert not [g for g in spatial_kind_of(b).gauges(replace(b, model=none), L) if "twist" in g.what]


def test_a_body_from_data_is_gauged_on_each_planes_and_its_torsions_own_modes():
    """A stepped spatial blade with a tip mass (tests/test_spatial_fedata.py): its x-z plane's
    modes (I_y) and its torsion modes (G J, no spin inertia of the point mass) are not the
    x-y plane's nor the axial ones; each gauge weight is the peak of its own view's mode."""
    from test_spatial_fedata import stepped

    body = stepped(20)
    spec = replace(customize(builtin("m3"), bending="cf1,cf2", name="blade_m3"), body=body)
    b = FlexibleBeam("blade", 10.0, STEEL, spec)
    gauges = spatial_kind_of(b).gauges(b, 10.0)
    x = np.linspace(0.0, 1.0, 2001)

    def peak(view, ref, order=0):
        return np.max(np.abs(fedata.evaluate(view, view.mode_shape(ref.axis, ref.family, ref.index), order, x)))

    [tw] = spec.torsion
    twist = _only(gauges, "twist")
    assert twist.weights == ((f"blade_phi_{tw.token}", pytest.approx(peak(body.view("torsion"), tw))),)
    assert abs(peak(body.view("torsion"), tw) - peak(body, tw)) > 1e-3 * peak(body, tw)  # not the axial shape
    plane_w = {f"blade_vz_{r.token}": peak(body.view("z"), r) for r in spec.bending}
    plane_v = {f"blade_{r.coordinate}": peak(body, r) for r in spec.bending}
    assert max(abs(plane_w[f"blade_vz_{r.token}"] / plane_v[f"blade_{r.coordinate}"] - 1)
               for r in spec.bending) > 1e-3  # the planes' shapes differ
    deflection = _only(gauges, "|(v, w)|")
    for col, w in plane_w.items():  # each plane alone: its own peak
        cols = {c: np.zeros(1) for c in [*plane_w, *plane_v]} | {col: np.ones(1)}
        assert deflection.history(cols)[0] == pytest.approx(w, rel=1e-12)


def test_exact_kinematics_has_no_deflection_limit_but_its_truncation_share():
    b = _beam(customize(builtin("exact"), bending="cf1,cf2,cf3", name="bar_exact"))
    whats = [g.what for g in kind_of(b).gauges(b, b.length)]
    assert not any("|v|" in w for w in whats) and any("cf3" in w and "share" in w for w in whats)


def _short_four_bar(tmp_path, t_end: str = "0.3") -> Path:
    """The four-bar with its coupler shortened from 0.4 m to 0.25 m: it closes at t = 0 (the
    crank's pin 0.4 m from the rocker's pivot, coupler and rocker 0.55 m), but the crank's half
    turn puts the pin 0.6 m away."""
    text = (SCENES / "four_bar.toml").read_text()
    scene = tmp_path / "short.toml"
    scene.write_text(text.replace("length = 0.4\n", "length = 0.25\n").replace("mid = 0.2 }", "mid = 0.125 }")
                     .replace("t_end = 0.3\n", f"t_end = {t_end}\n"))
    return scene


def test_a_drive_beyond_the_linkages_reach_is_refused_before_any_work(tmp_path):
    """The rigid linkage followed along the crank's motion cannot close past t = 0.1291 s
    (crank at 2.01 rad; m3, whose coupler cannot stretch, stops there): one line, exit 2,
    nothing derived or written. Ended before, the scene loads; a --t-end past it is refused."""
    out = tmp_path / "short.csv"
    run = subprocess.run([sys.executable, "-m", "flexsym.apps.cli", "run", str(_short_four_bar(tmp_path)),
                          "--out", str(out)], capture_output=True, text=True)
    assert run.returncode == 2 and run.stderr.count("\n") == 1 and not out.exists(), run.stderr
    assert "beyond its reach at t = 0.1291 s (crank_joint 2.01 rad): joint 'loop'" in run.stderr
    early = _short_four_bar(tmp_path, "0.12")
    load_scene(early)
    run = subprocess.run([sys.executable, "-m", "flexsym.apps.cli", "run", str(early), "--t-end", "0.2"],
                         capture_output=True, text=True)
    assert run.returncode == 2 and "--t-end 0.2" in run.stderr and "t = 0.1291 s" in run.stderr


def _rsur_reach(L: float) -> float:
    """The crank angle beyond which scenes/spatial_four_bar.toml's rigid RSUR linkage with a
    coupler of length L cannot close: the crank pin (0.05 cos th, 0.05 sin th, 0), the rocker's
    tip (0.2 + 0.12 sin ph, 0.12, 0.12 cos ph); the nearest tip moves beyond L."""
    from scipy.optimize import brentq, minimize_scalar

    def nearest(th):
        def dist(ph):
            return math.dist((0.2 + 0.12 * math.sin(ph), 0.12, 0.12 * math.cos(ph)),
                             (0.05 * math.cos(th), 0.05 * math.sin(th), 0.0))
        grid = np.linspace(-math.pi, math.pi, 2001)
        ph = grid[int(np.argmin([dist(g) for g in grid]))]
        return minimize_scalar(dist, bracket=(ph - 0.01, ph, ph + 0.01), tol=1e-12).fun
    return brentq(lambda th: nearest(th) - L, 1.0, math.pi, xtol=1e-10)


def test_a_spatial_drive_beyond_reach_is_refused_at_the_closed_form_angle(tmp_path):
    """3D: the ball joint turns freely along the drive (a turn of its orientation, started
    again from where it is). S7 and the RSUR four-bar follow their cranks' full turns, though
    their ball joints' directions sweep a full turn in the cranks' frames (the start's two tilts
    of the direction could not pass 90 degrees and refused both at a quarter turn). The RSUR
    with its coupler made 0.15 m long still closes at t = 0 and is refused where the rigid
    linkage stops closing, at the closed-form crank angle (2.4981 rad)."""
    load_scene(SCENES / "spatial_slider_crank.toml")
    load_scene(SCENES / "spatial_four_bar.toml")
    text = (SCENES / "spatial_four_bar.toml").read_text()
    scene = tmp_path / "short_rsur.toml"
    scene.write_text(text.replace("length = 0.2265\n", "length = 0.15\n").replace("mid = 0.113 }", "mid = 0.075 }"))
    with pytest.raises(SpecError, match="beyond its reach") as refused:
        load_scene(scene)
    angle = float(re.search(r"crank_joint ([0-9.]+) rad", str(refused.value)).group(1))
    assert abs(angle - _rsur_reach(0.15)) < 1e-3 and "joint 'cardan'" in str(refused.value)


def test_a_body_stretched_by_a_run_time_length_is_flagged_per_run():
    """The four-bar's coupler made 0.25 m long at run time (in-process, no reach check): its
    axial mode takes up the gap, 20 % strain by 0.15 s; the run says so from t = 0.13 s, at
    the run's L (the scene's 0.4 m would read 0.0097 there). The scene's own L is inside."""
    from flexsym.apps import api

    b = api.inprocess(SCENES / "four_bar.toml").batch({"L": [0.4, 0.25]}, t_end=0.15)
    assert b.status == ["ok", "ok"] and list(b.valid) == [True, False]
    note = b.validity_notes[1]
    assert "body 'coupler'" in note and "t = 0.13 s" in note and "|axial strain| = 0.01553 > 0.01" in note


def test_a_deflection_beyond_a_tenth_of_the_length_exits_4(tmp_path):
    """S1 (hub.toml, m3) with 2.5 times the motor's torque: the hub spins to about 15 rad/s and
    the beam's deflection bound passes 0.1 L = 1 m at t = 4.47 s. The run completes: exit 4,
    the body named on stderr and in the status, the CSV written."""
    scene = tmp_path / "hub_fast.toml"
    scene.write_text((SCENES / "hub.toml").read_text().replace('torque = "440.0*', 'torque = "1100.0*'))
    out = tmp_path / "hub.csv"
    run = subprocess.run([sys.executable, "-m", "flexsym.apps.cli", "run", str(scene), "--out", str(out)],
                         capture_output=True, text=True)
    assert run.returncode == 4, run.stderr
    [note] = [line for line in run.stderr.splitlines() if "range of validity" in line]
    assert "body 'beam'" in note and "t = 4.47 s: a bound on |v| = " in note and "> 0.1 L = 1 m" in note
    assert "outside its model's range" in run.stdout and out.exists()


@pytest.mark.study  # minutes: select's ef reference on 32 and 16 elements
def test_select_scores_no_candidate_outside_its_range(tmp_path):
    """S1 with 2.5 times the torque, to 6 s: m2's and m3's deflection bounds pass 0.1 L at
    4.47 s, so they are not scored (their status says why), whatever their error against ef;
    m1 stays under it and is scored (22 % off ef's peak in v_tip)."""
    from flexsym.analysis.system_select import select_system

    scene = tmp_path / "hub_fast.toml"
    scene.write_text((SCENES / "hub.toml").read_text().replace('torque = "440.0*', 'torque = "1100.0*')
                     .replace("t_end = 20.0", "t_end = 6.0"))
    results, best, _ = select_system(load_scene(scene), 0.1, repeat=1, log=lambda m: None)
    flagged = [c for c in results if c.model in ("m2", "m3")]
    assert flagged and all(c.status.startswith("body 'beam' left the range") and c.error == float("inf")
                           for c in flagged)
    assert all(c.status == "ok" and c.error > 0.2 for c in results if c.model == "m1")
    assert best is None
