"""Bodies from finite-element data: element matrices, modes, invariants, import/export, S4."""
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from flexsym.model import fedata
from flexsym.apps.cli import main
from flexsym.codegen.derive import derive
from flexsym.core.errors import SpecError
from flexsym.model.fedata import BeamBody, PointMass, Section
from flexsym.scenes.feimport import read_folder, write_folder
from flexsym.model.modes import ModeRef, clamped_free_beta, clamped_pinned_beta
from flexsym.model.variant import builtin, customize

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "stepped_blade.toml"
PAPER = Section(7.0e10, 3000.0, 4.0e-4, 2.0e-7)
OUTER = Section(7.0e10, 3000.0, 2.0e-4, 5.0e-8)


def uniform(n):
    return BeamBody.from_segments([(10.0, PAPER)], n)


def stepped(n):
    return BeamBody.from_segments([(5.0, PAPER), (5.0, OUTER)], n, (PointMass(10.0, 0.5),))


def test_element_matrices_are_the_papers_eq_7_8_and_the_consistent_mass():
    from flexsym.physics.outputs import element_matrices

    l = 0.7
    M, K, KG = fedata.element_matrices(PAPER, l)
    from flexsym.physics.energy import A, E, I

    KL_s, KG_s = element_matrices(sp.Float(l))
    subs = {E: PAPER.E, A: PAPER.A, I: PAPER.I}
    assert np.allclose(K, np.array(KL_s.subs(subs), dtype=float), rtol=1e-14, atol=0)
    assert np.allclose(KG, np.array(KG_s, dtype=float), rtol=1e-14, atol=1e-16)
    assert KG[2, 5] == pytest.approx(-l / 30)  # the paper prints +l/30
    # consistent mass = int rho A N^T N over the element (linear axial, Hermite bending)
    xi = sp.Symbol("xi")
    H = [1 - 3 * xi**2 + 2 * xi**3, l * (xi - 2 * xi**2 + xi**3), 3 * xi**2 - 2 * xi**3, l * (-xi**2 + xi**3)]
    Nu = [1 - xi, 0, 0, xi, 0, 0]
    Nv = [0, H[0], H[1], 0, H[2], H[3]]
    ref = np.array([[float(sp.integrate(PAPER.rho * PAPER.A * l * (Nu[i] * Nu[j] + Nv[i] * Nv[j]), (xi, 0, 1)))
                     for j in range(6)] for i in range(6)])
    assert np.allclose(M, ref, rtol=1e-13, atol=1e-15)


def test_static_modes_of_a_uniform_beam_are_the_papers_exactly():
    body = uniform(7)
    s = body.s_nodes
    ax = body.mode_shape("axial", "static", 1)
    be = body.mode_shape("bending", "static", 1)
    assert np.allclose(ax.values, s, rtol=0, atol=2e-16)  # exact rationals, rounded once
    assert np.allclose(be.values, 1.5 * s**2 - 0.5 * s**3, rtol=0, atol=5e-16)
    assert np.allclose(be.slopes, 3 * s - 1.5 * s**2, rtol=0, atol=1e-15)
    # ... and the finite-element solution of K x = 0 with a unit tip value, for a stepped body
    body = stepped(10)
    n = body.elements
    M, K, _ = body.assembled
    for axis, dofs, tip in (("axial", [3 * i for i in range(n)], n - 1),
                            ("bending", [3 * i + c for i in range(n) for c in (1, 2)], 2 * n - 2)):
        Ka = K[np.ix_(dofs, dofs)]
        inner = [i for i in range(len(dofs)) if i != tip]
        x = np.zeros(len(dofs))
        x[tip] = 1.0
        x[inner] = np.linalg.solve(Ka[np.ix_(inner, inner)], -Ka[inner, tip])
        exact = _dofs(body, body.mode_shape(axis, "static", 1))[dofs]
        assert np.allclose(x, exact, rtol=1e-12, atol=1e-14)


def test_normal_modes_orthogonality_boundary_conditions_and_frequencies():
    body = stepped(40)
    M, K, _ = body.assembled
    ref = body.reference
    for axis, fam in (("bending", "clamped_pinned"), ("bending", "clamped_free"),
                      ("axial", "sine"), ("axial", "fixed_free")):
        shapes = [body.mode_shape(axis, fam, k) for k in (1, 2, 3)]
        X = np.array([_dofs(body, sh) for sh in shapes]).T
        G = X.T @ M @ X / (ref.rho * ref.A * body.length)
        assert np.allclose(G, np.eye(3), atol=1e-10), (axis, fam)  # mass-normalised, orthogonal
        Kr = X.T @ K @ X
        assert np.abs(Kr - np.diag(np.diag(Kr))).max() <= 1e-9 * np.abs(Kr).max()
        for sh in shapes:
            bm = fedata.BodyMode(ModeRef(axis, fam, 1), body, sh)
            assert sh.values[0] == 0.0 and (axis == "axial" or sh.slopes[0] == 0.0)
            if fam in ("clamped_pinned", "sine"):
                assert sh.values[-1] == 0.0  # the interface (tip) dof is fixed
            assert bm.value_at(0, 0) == 0
    # uniform beam: frequencies converge to the analytic ones at O(h^4) (Hermite) / O(h^2) (bar)
    c = np.sqrt(PAPER.E * PAPER.I / (PAPER.rho * PAPER.A))
    exact_cp = float(clamped_pinned_beta(1))**2 * c / 100.0
    exact_cf = float(clamped_free_beta(2))**2 * c / 100.0
    errs = [(uniform(n).mode_shape("bending", "clamped_pinned", 1).frequency / exact_cp - 1,
             uniform(n).mode_shape("bending", "clamped_free", 2).frequency / exact_cf - 1) for n in (4, 8)]
    for k in range(2):
        assert 0 < errs[1][k] < errs[0][k] / 12  # rate >= 3.6: O(h^4)


def _dofs(body, sh):
    """Nodal values of a shape as free dofs (u, v, theta) of nodes 1..n."""
    n = body.elements
    x = np.zeros(3 * n)
    if sh.axis == "axial":
        x[0::3] = sh.values[1:]
    else:
        x[1::3] = sh.values[1:]
        x[2::3] = np.array(sh.slopes[1:]) / body.length
    return x


def _normalised(table, sym, norms):
    """An invariant divided by the norms of the modes it contains (shape scaling drops out)."""
    key = table.monomial(sym)
    value = float(table.value(sym).value)
    for f in key[3]:
        if f.kind == "mode":
            value /= norms[f.a]
        elif f.kind == "fs":
            value /= norms[f.a] * norms[f.b]
    return value


def test_invariants_from_the_discretisation_converge_to_the_analytic_ones():
    """Every invariant of #2 (normalised by its modes' norms) against the analytic one: those of
    bending modes only converge at O(h^4) (Hermite cubics), those with the axial sine mode at
    O(h^2) (linear axial elements: the paper's element)."""
    spec = builtin("m2")
    exact = derive(spec).table
    norms0 = {n: float(sp.sqrt(exact.value(exact.monomial_symbol([(exact.mode_value(n), 2)])).value))
              for n in spec.coordinates}
    worst = []
    for ne in (8, 16):
        t = derive(replace(spec, body=uniform(ne))).table
        norms = {n: float(sp.sqrt(t.value(t.monomial_symbol([(t.weight("mu"), 1), (t.mode_value(n), 2)])).value))
                 for n in spec.coordinates}
        by_label = {str(sym).replace("*mu", "").replace("*ei", "").replace("*ea", ""): sym for sym in t.symbols}
        err = {"bending": 0.0, "axial": 0.0}
        for sym in exact.symbols:
            a = _normalised(exact, sym, norms0)
            b = _normalised(t, by_label[str(sym)], norms)
            kind = "axial" if "sin1" in str(sym) else "bending"
            err[kind] = max(err[kind], abs(a - b) / max(1.0, abs(a)))
        worst.append(err)
    assert worst[1]["bending"] < 1e-4 and worst[0]["bending"] / worst[1]["bending"] > 12
    assert 3.5 < worst[0]["axial"] / worst[1]["axial"] < 4.5


def test_modal_mass_and_stiffness_with_point_inertia_reproduce_the_fe_frequencies():
    """With a tip mass, a rotary inertia and a mid-span mass, the derived M and K_L of one
    clamped-free mode give exactly its finite-element frequency (mu, rot and ei weights)."""
    from flexsym.physics.energy import A, E, I, L, rho

    body = BeamBody.from_segments([(5.0, PAPER), (5.0, OUTER)], 10,
                                  (PointMass(10.0, 0.5, 0.3), PointMass(5.0, 0.2)))
    for k in (1, 2):
        der = derive(customize(replace(builtin("m0"), body=body), strain="linear", axial="",
                               bending=f"cf{k}", outputs="v_tip"))
        vals = {rho: PAPER.rho, E: PAPER.E, A: PAPER.A, I: PAPER.I, L: 10.0}
        m = float(der.numeric(der.M)[0, 0].subs(vals))
        kk = float(der.numeric(der.stiffness_split()[0])[0, 0].subs(vals))
        assert np.sqrt(kk / m) == pytest.approx(body.mode_shape("bending", "clamped_free", k).frequency,
                                                rel=1e-11)


def test_geometric_stiffness_and_foreshortening_are_the_papers_element_sums():
    """K_G of #1 on a body is eq. (28)-(29): sum_e P_e X^T K_G^e X with P_e from the axial
    mode in each element; the foreshortening kernel at a node is the nodal sum of eq. (34)-(38),
    H_ab(x_n) = sum_{e < n} X_a^T K_G^e X_b."""
    from flexsym.physics.energy import A, E, L, w

    body = stepped(10)
    der = derive(customize(replace(builtin("m1"), body=body), outputs="v_tip"))
    KG = der.numeric(der.stiffness_split()[1])
    q_u = der.q[0]
    names = der.coords[1:]
    X = np.array([_dofs(body, der.modes[n].shape) for n in names]).T
    u = np.array(der.modes[der.coords[0]].shape.values)
    total = np.zeros((3 * body.elements, 3 * body.elements))
    per_element = []
    for e, sec in enumerate(body.sections):
        l = body.nodes[e + 1] - body.nodes[e]
        ke = np.zeros_like(total)
        idx = np.arange(3 * e - 3, 3 * e + 3)
        keep = idx >= 0
        ke[np.ix_(idx[keep], idx[keep])] = fedata.element_matrices(sec, l)[2][np.ix_(keep, keep)]
        per_element.append(ke)
        total += sec.E * sec.A * (u[e + 1] - u[e]) / l * ke  # P_e per unit amplitude
    vals = {E: PAPER.E, A: PAPER.A, L: body.length, w: 0}
    ours = np.array([[float(sp.diff(KG[1 + i, 1 + j], q_u).subs(vals)) for j in range(3)] for i in range(3)])
    assert np.allclose(ours, X.T @ total @ X, rtol=1e-11, atol=0)
    # H_ab at node n from the element sums, against the invariant on [0, s_n]
    t = der.table
    n = 7
    partial = sum(per_element[:n])
    for i, a in enumerate(names):
        for j, b in enumerate(names):
            sym = t.monomial_symbol([(t.mode_value(a, 1), 1), (t.mode_value(b, 1), 1)], 0, sp.Rational(n, 10))
            ref = X[:, i] @ partial @ X[:, j] * body.length  # d/dx -> d/ds
            assert float(t.value(sym).value) == pytest.approx(ref, rel=1e-11, abs=1e-12)


def test_prestress_distribution_of_a_body_includes_the_tip_mass():
    body = stepped(20)
    s = np.array([0.0, 0.25, 0.5, 0.75, 0.999])
    x = 10 * s
    # N/w^2 = int_x^L rho A xb dxb + m L, analytic for the two halves
    N = np.where(x <= 5, 1.2 * (25 - x**2) / 2 + 0.6 * (100 - 25) / 2, 0.6 * (100 - x**2) / 2) + 0.5 * 10
    assert np.allclose(fedata.nhat(body, s), N / (1.2 * 100 / 2), rtol=1e-12)
    assert np.allclose(fedata.nhat(uniform(5), s), 1 - s**2, atol=1e-14)


def test_a_mode_set_that_cannot_carry_v_tip_is_refused():
    base = replace(builtin("prestress"), body=stepped(10))
    with pytest.raises(SpecError, match="no bending mode moves the tip"):
        customize(base, bending="cp1,cp2", outputs="v_tip")
    with pytest.raises(SpecError, match="have only 3 such modes"):
        customize(replace(base, body=stepped(2)), bending="static,cp4", outputs="v_tip")
    customize(base, bending="cf1,cf2", outputs="v_tip")  # clamped-free modes move the tip


def test_round_trip_export_import_gives_identical_equations(tmp_path):
    body = stepped(12)
    write_folder(body, tmp_path / "fe")
    back = read_folder(tmp_path / "fe")
    assert back.nodes == body.nodes and back.sections == body.sections and back.masses == body.masses
    for a, b in zip(back.assembled, body.assembled):
        assert np.array_equal(a, b)
    d1 = derive(replace(builtin("m2"), body=body))
    d2 = derive(replace(builtin("m2"), body=back))
    assert d1.numeric(d1.M) == d2.numeric(d2.M)
    assert d1.numeric(d1.f) == d2.numeric(d2.f)
    assert {k: d1.numeric(v) for k, v in d1.outputs.items()} == {k: d2.numeric(v) for k, v in d2.outputs.items()}


def _corrupt(folder: Path, case: str) -> str:
    """Apply one defect to an exported folder; return a fragment of the expected message."""
    toml = folder / "body.toml"
    text = toml.read_text()
    if case == "missing_M":
        (folder / "M.mtx").unlink()
        return "M.mtx: no such file"
    if case == "wrong_size":
        lines = (folder / "K.mtx").read_text().splitlines()
        n = int(lines[1].split()[0])
        kept = [l for l in lines[2:] if max(map(int, l.split()[:2])) <= n - 3]
        (folder / "K.mtx").write_text("\n".join([lines[0], f"{n - 3} {n - 3} {len(kept)}"] + kept) + "\n")
        return "dof map has"
    if case == "asymmetric":
        lines = (folder / "K.mtx").read_text().splitlines()
        lines[0] = lines[0].replace("symmetric", "general")
        (folder / "K.mtx").write_text("\n".join(lines) + "\n")
        return "not symmetric"
    if case == "indefinite":
        lines = (folder / "M.mtx").read_text().splitlines()
        i, j, v = lines[2].split()
        lines[2] = f"{i} {j} {-float(v)!r}"
        (folder / "M.mtx").write_text("\n".join(lines) + "\n")
        return "not positive definite"
    if case == "nan":
        lines = (folder / "KG.mtx").read_text().splitlines()
        i, j, _ = lines[3].split()
        lines[3] = f"{i} {j} nan"
        (folder / "KG.mtx").write_text("\n".join(lines) + "\n")
        return "not finite"
    if case == "missing_node":
        toml.write_text(text.replace('"3:u"', '"99:u"'))
        return "node 99 is missing"
    if case == "element_node":
        toml.write_text(text.replace("nodes = [2, 3]", "nodes = [2, 30]"))
        return "missing"
    if case == "garbage_mtx":
        (folder / "KG.mtx").write_text("this is not a matrix\n")
        return "not a readable Matrix Market file"
    if case == "not_the_table":
        toml.write_text(text.replace("area = 0.0004", "area = 0.0005", 1))
        return "differs from the matrix of the element table"
    if case == "bad_toml":
        toml.write_text(text + "\n[[[\n")
        return "not valid TOML"
    raise AssertionError(case)


CASES = ("missing_M", "wrong_size", "asymmetric", "indefinite", "nan", "missing_node",
         "element_node", "garbage_mtx", "not_the_table", "bad_toml")


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    folder = tmp_path_factory.mktemp("fe") / "blade"
    write_folder(stepped(6), folder)
    return folder


@pytest.mark.parametrize("case", CASES)
def test_malformed_fe_folders_are_refused_with_one_line(case, exported, tmp_path, capsys, monkeypatch):
    folder = tmp_path / "blade"
    shutil.copytree(exported, folder)
    expected = _corrupt(folder, case)
    scene = tmp_path / "scene.toml"
    text = SCENE.read_text()
    start, end = text.index("[body]"), text.index("[maneuver]")
    scene.write_text(text[:start] + '[body]\nfolder = "blade"\n\n' + text[end:])
    monkeypatch.chdir(tmp_path)
    code = main(["run", str(scene), "--out", "out.csv"])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1 and expected in err and "blade" in err, err
    assert not (tmp_path / "out.csv").exists()


def test_generation_from_fe_data_is_deterministic_and_records_its_tools():
    import json

    from flexsym.codegen.generate import generate_files

    spec = customize(replace(builtin("m2"), body=stepped(12)), name="fe_det")
    first = generate_files(spec)
    fedata._SHAPES.clear()  # recompute the eigenvectors
    assert generate_files(spec) == first
    manifest = json.loads(first["manifest.json"])
    assert {"numpy", "scipy"} <= set(manifest["versions"])
    assert manifest["params"][0]["default"] == PAPER.rho and manifest["variant"]["body"]["masses"]


def test_model_option_needs_a_scene_and_a_known_variant(capsys):
    assert main(["run", "m1", "--model", "m2"]) == 2
    assert "--model replaces the model of a scene file" in capsys.readouterr().err
    assert main(["run", str(SCENE), "--model", "m9"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--model" in err and "unknown variant 'm9'" in err


def test_fe_data_variant_c_matches_casadi_and_sympy(s0_kernels):
    from test_codegen import check_c_casadi_sympy

    from flexsym.toolchain.pipeline import compiled

    body = BeamBody.from_segments([(5.0, PAPER), (5.0, OUTER)], 6,
                                  (PointMass(10.0, 0.5, 0.02), PointMass(5.0, 0.3)))
    spec = customize(replace(builtin("m2"), body=body), name="fe_codegen",
                     outputs="v_tip,u_tip,N_A,M_A,M@0.5,N@0.25")
    der = derive(spec)
    assert any(str(sym).startswith("J[rot") or "rot" in str(sym) for sym in der.table.symbols)
    check_c_casadi_sympy(der, compiled(spec), s0_kernels(spec), np.random.default_rng(11), 3)


def _run(spec, t_end, dt=1e-3):
    from flexsym.toolchain.pipeline import prepare
    from flexsym.toolchain.run import run_built

    return run_built(prepare(spec, log=lambda m: None), t_end=t_end, dt=dt)


def test_ef_on_a_uniform_body_is_ef():
    """The per-element tables of a body reduce to ef's uniform mesh exactly."""
    plain = customize(builtin("ef"), elements=4, name="ef_plain4", outputs="v_tip,M_A,N@0.5,N_A_clamp")
    body = replace(plain, body=uniform(4), name="ef_body4").validate()
    a, b = _run(plain, 2.0), _run(body, 2.0)
    for c in ("v_tip", "M_A", "N_s0p5", "N_A_clamp"):
        assert np.array_equal(a[c], b[c])


def test_uniform_body_converges_to_the_analytic_variant_at_fourth_order():
    ref = _run(builtin("m3"), 8.0)
    errs = []
    for n in (8, 16):
        spec = customize(replace(builtin("m3"), body=uniform(n)), name=f"m3_fe{n}", outputs="v_tip")
        errs.append(np.abs(_run(spec, 8.0).minus(ref)).max())
    assert errs[1] < 3e-7 and errs[0] / errs[1] > 12  # measured 2.99e-6 -> 1.83e-7 over 20 s


def test_s4_modal_against_ef_on_a_short_spin_up():
    """S4 for 8 s (through the largest deflection at t = 6.5 s): the default model (prestress,
    static, cp1, cp2 from 100 elements, N and M from equilibrium) against ef on 32 elements
    (within 3e-7 m and 1.3 N of 64 elements, README study). Measured: 4.5e-4 m, 4.7 N,
    0.57 N m, 0.31 N m."""
    from flexsym.scenes.scene import load_scene

    modal = load_scene(SCENE).spec
    ef = load_scene(SCENE, model="ef").spec
    assert ef.elements == 32 and modal.moment == "equilibrium"
    a, b = _run(modal, 8.0), _run(ef, 8.0)
    peak = {c: np.abs(b[c]).max() for c in ("v_tip", "N_A", "M_A", "M_step")}
    assert 0.47 < peak["v_tip"] < 0.49
    assert np.abs(a.minus(b, "v_tip")).max() < 0.002 * peak["v_tip"]
    assert np.abs(a.minus(b, "N_A")).max() < 0.02 * peak["N_A"]
    assert np.abs(a.minus(b, "M_A")).max() < 0.005 * peak["M_A"]
    assert np.abs(a.minus(b, "M_step")).max() < 0.01 * peak["M_step"]


BAD_BODIES = [
    ("segments = []", "[body] segments"),
    ("segments = [ { length = 5.0, density = 3000.0, youngs_modulus = 7.0e10, area = -4.0e-4, inertia = 2.0e-7 } ]",
     "[body] segments[0] area"),
    ("segments = [ { length = 5.0, density = 3000.0, youngs_modulus = 7.0e10, area = 4.0e-4, inertia = 2.0e-7, colour = 1 } ]",
     "[body] segments[0] colour"),
    ("point_masses = [ { x = 7.0, mass = 0.5 } ]\nsegments = [ { length = 10.0, density = 3000.0, youngs_modulus = 7.0e10, area = 4.0e-4, inertia = 2.0e-7 } ]",
     "must be a segment end"),
    ("elements = 0\nsegments = [ { length = 10.0, density = 3000.0, youngs_modulus = 7.0e10, area = 4.0e-4, inertia = 2.0e-7 } ]",
     "[body] elements"),
    ('folder = "nowhere"', "no such file"),
]


@pytest.mark.parametrize("body, expected", BAD_BODIES)
def test_malformed_body_tables_are_refused_with_one_line(body, expected, tmp_path):
    from flexsym.scenes.scene import load_scene

    text = SCENE.read_text()
    start, end = text.index("[body]"), text.index("[maneuver]")
    scene = tmp_path / "scene.toml"
    scene.write_text(text[:start] + "[body]\n" + body + "\n\n" + text[end:])
    with pytest.raises(SpecError) as exc:
        load_scene(scene)
    assert expected in str(exc.value) and "\n" not in str(exc.value)
    both = tmp_path / "both.toml"
    both.write_text("[beam]\nlength = 10.0\n" + text)
    with pytest.raises(SpecError, match="either"):
        load_scene(both)
