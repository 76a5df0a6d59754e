"""Beams from finite-element data in system scenes ([[body]] kind = "beam" with segments or
folder; flexsym/scenes/system_scene.py): the scene equals the Python System, a uniform body equals the
analytic beam in S1 within its discretisation error, and malformed bodies are refused in one
line naming the file and the item, exit 2, nothing written."""
from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from flexsym.apps.cli import main
from flexsym.core.errors import SpecError
from flexsym.scenes.scene import load_scene
from flexsym.scenes.system_scene import system_from_dict

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "scenes"
STEPPED = (SCENES / "stepped_hub.toml").read_text()
HUB = (SCENES / "hub.toml").read_text()
UNIFORM = "length = 10.0\ndensity = 3000.0\nyoungs_modulus = 7.0e10\narea = 4.0e-4\ninertia = 2.0e-7\n"
SEGMENTS = STEPPED[STEPPED.index("segments = ["):STEPPED.index("markers = { step")]


def _hub_with_fe_beam(elements: int, model: str) -> dict:
    """S1 (scenes/hub.toml) with its uniform beam given as one finite-element segment."""
    assert HUB.count(UNIFORM) == 1 and HUB.count('model = "m3"') == 1
    seg = ("segments = [{ length = 10.0, density = 3000.0, youngs_modulus = 7.0e10, "
           f"area = 4.0e-4, inertia = 2.0e-7 }}]\nelements = {elements}\n")
    return tomllib.loads(HUB.replace(UNIFORM, seg).replace('model = "m3"', f"model = {model}"))


def _run(data: dict, name: str = "hub", t_end: float = 20.0):
    from flexsym.toolchain.run import run_built
    from flexsym.toolchain.pipeline import prepare_system

    return run_built(prepare_system(system_from_dict(data, name)), t_end=t_end, dt=1e-3, out_every=10)


def test_scene_equals_the_python_system_row_for_row(tmp_path):
    """scenes/stepped_hub.toml read by the grammar, and the same mechanism built in Python from
    fedata.BeamBody (S4's blade: 100 elements, 0.5 kg at the tip, prestress static/cp1/cp2 with
    N and M from equilibrium): the same System, and the CLI's rows equal run_system's bit for bit."""
    from dataclasses import replace

    from flexsym.model.fedata import BeamBody, PointMass
    from flexsym.model.fedata import Section as FeSection
    from flexsym.model.variant import VariantSpec, _refs
    from flexsym.toolchain.pipeline import run_system
    from flexsym.model.library import hub_system

    body = BeamBody.from_segments([(5.0, FeSection(7e10, 3000.0, 4e-4, 2e-7)),
                                   (5.0, FeSection(7e10, 3000.0, 2e-4, 5e-8))], 100,
                                  (PointMass(10.0, 0.5),))
    model = VariantSpec("body", "prestress", (), _refs("bending", ["static", "cp1", "cp2"]),
                        outputs=("v_tip",), axial_force="equilibrium", moment="equilibrium", body=body)
    s1 = hub_system(model)
    blade = replace(s1.body("beam"), name="blade", markers=(lib_marker("step", 5.0),))
    joints = tuple(replace(j, child="blade.root") if j.name == "clamp" else j for j in s1.joints)
    motor = replace(s1.drivers[0], expression="315.0*ifelse(t <= 15, (6/15)*(1 - cos(2*pi*t/15)), 0)")
    outputs = tuple(lib_output(c, q) for c, q in (
        ("theta_h", "angle(hub_joint)"), ("omega_h", "rate(hub_joint)"), ("v_tip", "v(blade, tip)"),
        ("N_A", "N(blade, root)"), ("M_A", "M(blade, root)"), ("N_step", "N(blade, step)"),
        ("M_step", "M(blade, step)")))
    python = replace(s1, name="stepped_hub", bodies=(s1.body("hub"), blade), joints=joints,
                     drivers=(motor,), outputs=outputs)
    scene = load_scene(SCENES / "stepped_hub.toml")
    assert scene.system == python
    out = tmp_path / "scene.csv"
    assert main(["run", str(SCENES / "stepped_hub.toml"), "--out", str(out)]) == 0
    rows = np.genfromtxt(out, delimiter=",", names=True)
    r = run_system(python, t_end=20.0, dt=1e-3, out_every=10)
    assert len(rows) == 2001
    for c in ("theta_h", "omega_h", "v_tip", "N_A", "M_A", "N_step", "M_step"):
        assert np.array_equal(rows[c], r[c]), c
    # the physics of S4 on a free hub: N at the root and at the step at 6 rad/s are the
    # centrifugal loads Omega^2 (int rho A x dx + m L) beyond them (36 x 42.5 N, 36 x 27.5 N)
    at = np.argmin(np.abs(rows["t"] - 20.0))
    w2 = rows["omega_h"][at] ** 2
    assert rows["N_A"][at] == pytest.approx(w2 * 42.5, rel=2e-4)
    assert rows["N_step"][at] == pytest.approx(w2 * 27.5, rel=2e-4)


def lib_marker(name, x):
    from flexsym.model.system import Marker

    return Marker(name, x)


def lib_output(column, quantity):
    from flexsym.model.system import Output

    return Output(column, quantity)


def test_uniform_body_equals_the_analytic_beam_in_s1():
    """S1 with its beam as finite-element data against the analytic beam (20 s, 1 ms).
    The static (constraint) mode is a cubic, which the Hermite element reproduces exactly, so
    a static-only model differs only by the invariants' rounding to 13 digits: within 1e-10 of
    each peak (measured 1.4e-13 for v_tip, at any mesh). The normal modes (cp1, cp2 of m3)
    converge at O(h^4): v_tip 4.9e-5 -> 2.8e-6 m (4 -> 8 elements, ratio 17.5), theta_h
    3.8e-6 -> 2.2e-7 rad; halving h must divide the error by more than 12."""
    static = '{ strain = "foreshortening", bending = ["static"] }'
    ref = _run(tomllib.loads(HUB.replace('model = "m3"', f"model = {static}")))
    fe = _run(_hub_with_fe_beam(2, static))
    for c in ("theta_h", "omega_h", "v_tip", "M_A"):
        assert np.abs(fe[c] - ref[c]).max() <= 1e-10 * np.abs(ref[c]).max(), c
    ref = _run(tomllib.loads(HUB))
    err = {n: {c: np.abs(_run(_hub_with_fe_beam(n, '"m3"'))[c] - ref[c]).max()
               for c in ("theta_h", "v_tip")} for n in (4, 8)}
    assert np.abs(ref["v_tip"]).max() > 0.5
    for c in ("theta_h", "v_tip"):
        assert err[4][c] / err[8][c] > 12, (c, err)
    assert err[8]["v_tip"] < 1e-5 * np.abs(ref["v_tip"]).max()


def test_folder_body_reads_like_its_segments(tmp_path):
    """A body exported with `flexsym fe-export` and named by folder = "..." (relative to the
    scene file) gives the same System as the segments it was written from."""
    assert main(["fe-export", str(SCENES / "stepped_blade.toml"), "--out", str(tmp_path / "blade_fe")]) == 0
    scene = tmp_path / "hub_folder.toml"
    scene.write_text(STEPPED.replace(SEGMENTS, 'folder = "blade_fe"\n').replace("elements = 100 ", "#"))
    got = load_scene(scene).system
    assert got == load_scene(SCENES / "stepped_hub.toml").system
    assert got.body("blade").model.body.matrices is not None  # the folder's matrices


def _bad_folder(tmp_path: Path, what: str) -> None:
    from flexsym.model.fedata import BeamBody
    from flexsym.model.fedata import Section as FeSection
    from flexsym.scenes.feimport import write_folder

    folder = write_folder(BeamBody.from_segments([(10.0, FeSection(7e10, 3000.0, 4e-4, 2e-7))], 4),
                          tmp_path / "fe")
    if what == "garbled":
        (folder / "K.mtx").write_text("%%MatrixMarket matrix coordinate real symmetric\n12 12 1\n1 1 x\n")
    elif what == "overlap":
        text = (folder / "body.toml").read_text()
        (folder / "body.toml").write_text(text.replace("nodes = [0.0, 2.5, 5.0", "nodes = [0.0, 5.0, 5.0"))


# (case, text replaced, replacement, what the one line must say besides the file name)
MALFORMED = [
    ("folder_missing", SEGMENTS, 'folder = "no_such_folder"\n', "[[body]] 'blade' folder: "),
    ("folder_bad_matrix", SEGMENTS, 'folder = "fe"\n', "K.mtx: not a readable Matrix Market file"),
    ("folder_nodes_overlap", SEGMENTS, 'folder = "fe"\n', "node 2 at x = 5.0 does not follow node 1"),
    ("segment_zero_area", "area = 2.0e-4", "area = 0.0", "[[body]] 'blade' segments[1] area: must be a positive number"),
    ("segment_negative_length", "{ length = 5.0, density = 3000.0, youngs_modulus = 7.0e10, area = 2.0e-4",
     "{ length = -5.0, density = 3000.0, youngs_modulus = 7.0e10, area = 2.0e-4", "segments[1] length: must be a positive number"),
    ("no_segments", SEGMENTS, "segments = []\n", "[[body]] 'blade' segments: must be a non-empty list"),
    ("point_mass_off_the_beam", "{ x = 10.0, mass = 0.5 }", "{ x = 12.0, mass = 0.5 }",
     "[[body]] 'blade' point_masses[0] x: x = 12 m must be a segment end"),
    ("negative_point_mass", "{ x = 10.0, mass = 0.5 }", "{ x = 10.0, mass = -0.5 }", "point_masses[0] mass: must be a number >= 0"),
    ("uniform_and_fe_keys", 'kind = "beam"\n', 'kind = "beam"\nlength = 10.0\n', "[[body]] 'blade' length: give either"),
    ("folder_and_segments", "segments = [", 'folder = "fe"\nsegments = [', "'blade' folder: an imported body brings its own"),
    ("marker_off_the_body", "markers = { step = 5.0 }", "markers = { step = 12.0 }", "marker 'step' at x = 12.0 is outside the beam"),
    # cp1, cp2 are zero at the tip: a model for a beam whose tip nothing reads; here v_tip is read
    ("no_mode_carries_v_tip", '"static", "cp1", "cp2"', '"cp1", "cp2"', "output v_tip = 'v(blade, tip)': no bending mode of model 'body' has deflection at x = 10 m"),
    ("no_mode_carries_N", 'strain = "prestress", bending = ["static", "cp1", "cp2"], axial_force = "equilibrium"',
     'strain = "foreshortening", bending = ["static", "cp1", "cp2"], axial_force = "constitutive"', "output N_A = 'N(blade, root)': model 'body' (strain foreshortening) has no axial mode"),
    ("more_modes_than_elements", '"static", "cp1", "cp2"', '"static", "cp1", "cp2", "cp3", "cp4"', "the body's 2 elements have only 3 such modes"),
    ("elements_not_an_integer", "elements = 100", "elements = 1.5", "[[body]] 'blade' elements: must be an integer"),
]


@pytest.mark.parametrize("case, old, new, says", MALFORMED, ids=[m[0] for m in MALFORMED])
def test_malformed_fe_body(tmp_path, capsys, case, old, new, says):
    assert STEPPED.count(old) == 1, case
    text = STEPPED.replace(old, new)
    if case.startswith("folder_") and case != "folder_missing":
        _bad_folder(tmp_path, {"folder_bad_matrix": "garbled", "folder_nodes_overlap": "overlap"}.get(case, ""))
        text = text.replace("elements = 100 ", "#")
    if case == "more_modes_than_elements":
        text = text.replace("elements = 100", "elements = 2")
    scene = tmp_path / f"{case}.toml"
    scene.write_text(text)
    out, plot = tmp_path / "out.csv", tmp_path / "p.png"
    out.write_bytes(b"t,v_tip\n0,1\n")
    before = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    rc = main(["run", str(scene), "--out", str(out), "--plot", str(plot)])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.count("\n") == 1 and err.startswith(f"flexsym: error: {scene}: "), err
    assert says in err, err
    assert {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()} == before


def test_python_dict_reads_a_folder_relative_to_base(tmp_path):
    _bad_folder(tmp_path, "")
    data = tomllib.loads(STEPPED.replace(SEGMENTS, 'folder = "fe"\n').replace("elements = 100 ", "#"))
    assert system_from_dict(data, "stepped_hub", base=tmp_path).body("blade").model.body.elements == 4
    with pytest.raises(SpecError, match=r"^system data: \[\[body\]\] 'blade' folder: .*body.toml: no such file"):
        system_from_dict(data, "stepped_hub", base=tmp_path / "elsewhere")


STEPPED_MODEL = ('model = { strain = "prestress", bending = ["static", "cp1", "cp2"], '
                 'axial_force = "equilibrium", moment = "equilibrium" }')


def _stepped(model: str, elements: int = 100) -> dict:
    assert STEPPED.count(STEPPED_MODEL) == 1
    return tomllib.loads(STEPPED.replace(STEPPED_MODEL, f"model = {model}")
                         .replace("elements = 100 ", f"elements = {elements} "))


def test_body_mass_moves_the_frame():
    """The stepped blade (9.5 kg: 6 + 3 kg of sections, 0.5 kg at the tip; the root section
    alone would say 12 kg) on a prismatic joint along its axis with gravity along it falls
    freely, undeformed: x = -g t^2/2 (the frame's gravity term takes the body's own mass;
    measured 6e-14 m over 1 s; 1.29 m off with the root section's rho A L)."""
    data = _stepped('{ strain = "prestress", bending = ["static"] }', elements=8)
    data["body"] = [data["body"][1]]
    data["joint"] = [{"name": "slide", "kind": "prismatic", "parent": "ground", "point": [0.0, 0.0],
                      "child": "blade.root", "axis": [1.0, 0.0]}]
    data["driver"] = []
    data["gravity"] = {"g": [-9.81, 0.0]}
    data["output"]["columns"] = {"x": "angle(slide)", "v_tip": "v(blade, tip)"}
    r = _run(data, "fall", t_end=1.0)
    assert r.ok and len(r["t"]) == 101
    assert np.abs(r["x"] + 9.81 * r["t"] ** 2 / 2).max() < 1e-12 and r["x"][-1] < -4.9


def _theta_p(t):
    """The rigid hub + blade's spin-up P(t; 6 rad/s, 15 s) that the motor law is made for."""
    w, T = 6.0, 15.0
    tt = np.minimum(t, T)
    return (w / T) * (tt**2 / 2 + (T / (2 * np.pi))**2 * (np.cos(2 * np.pi * tt / T) - 1)) + w * np.maximum(t - T, 0)


def test_ef_body_rigid_limit_momentum_and_element_table():
    """`ef` with the stepped blade (4 elements, the step at a node, the tip mass at the last):
    (1) the motor law assumes J_h + J_blade = 40 + 275 kg m^2, so at 10^4 E the hub follows
    P(t) (measured 3.9e-6 rad, 0.035 rad at E: the lag is the blade's flexibility, ~ 1/E) and
    the angular momentum after the spin-up is 315 x 6 (1.7e-9); (2) the elastic energy that
    system.c assembles per element from sysgen.ef_elements (lengths and EA, EI ratios) equals
    the body's symbolic energy at a random state (1e-10)."""
    import casadi as ca

    from flexsym.codegen import sysgen
    from flexsym.toolchain import pipeline
    from flexsym.emit.kernels import SympyToCasadi
    from flexsym.toolchain.run import run_built

    data = _stepped('{ variant = "ef", elements = 4 }')
    data["output"]["columns"] = {"theta_h": "angle(hub_joint)", "H": "momentum"}
    system = system_from_dict(data, "stepped_hub")
    assert system.body("blade").model.body.nodes == (0.0, 2.5, 5.0, 7.5, 10.0)
    r = run_built(pipeline.prepare_system(system), t_end=20.0, dt=1e-3, out_every=10, params={"E": 7e14})
    assert np.abs(r["theta_h"] - _theta_p(r["t"])).max() < 1e-5
    assert abs(r["H"][-1] - 315 * 6) < 1e-6 * 1890

    der = sysgen.derive_system(system)
    kernel = next(k for k in sysgen.build_system_kernels(der) if k.name == "ef_elastic").function
    (body,) = sysgen.ef_elements(der)
    n = len(der.q)
    qs, ps = ca.SX.sym("q", n), ca.SX.sym("p", len(der.params))
    symbols = {s: qs[i] for i, s in enumerate(der.q)} | {s: ps[i] for i, (_, s, _) in enumerate(der.params)}
    dense = ca.Function("dense", [qs, ps], [SympyToCasadi(symbols, {s: 0 for s in symbols})(der.elastic[0].elastic_energy())])
    q = np.random.default_rng(5).uniform(-1e-3, 1e-3, n)
    p = np.array([v for _, _, v in der.params])
    L_, E_, A_, I_ = (p[i] for i in body["params"])
    V = 0.0
    for el, (ds, ea, ei) in zip(body["elements"], body["sections"]):
        e = [(q[i] if i >= 0 else 0.0) + float(a) * L_ + float(b) for i, a, b in el]
        V += float(kernel(e, [L_ * float(ds), E_, A_ * float(ea), I_ * float(ei)])[0])
    Vd = float(dense(q, p))
    assert [float(x[1]) for x in body["sections"]] == [1.0, 1.0, 0.5, 0.5]
    assert [float(x[2]) for x in body["sections"]] == [1.0, 1.0, 0.25, 0.25]
    assert abs(V - Vd) <= 1e-10 * abs(Vd)


def test_uniform_ef_body_is_the_analytic_ef():
    """`ef` with a uniform body (one segment, 2 elements: lengths, EA/EI ratios and node
    positions through the body's element table) gives S1's analytic `ef` rows bit for bit."""
    ef = '{ variant = "ef", elements = 2 }'
    ref = _run(tomllib.loads(HUB.replace('model = "m3"', f"model = {ef}")))
    assert system_from_dict(_hub_with_fe_beam(100, ef), "hub").body("beam").model.body.elements == 2
    fe = _run(_hub_with_fe_beam(100, ef))
    for c in ("theta_h", "omega_h", "v_tip", "M_A"):
        assert np.array_equal(fe[c], ref[c]), c
    assert np.abs(ref["v_tip"]).max() > 0.4
