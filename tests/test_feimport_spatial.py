"""The spatial finite-element folder (flexsym/scenes/feimport.py, kind = "spatial"): the 6-dof
matrices of fedata.spatial_matrices against closed forms, the unit load cases' geometric
stiffness, the round trip, a permuted dof map, and malformed folders refused in one line."""
import shutil
from pathlib import Path

import numpy as np
import pytest
from scipy.io import mmwrite
from scipy.linalg import eigh

from flexsym.core.errors import SpecError
from flexsym.model import fedata
from flexsym.model.fedata import SPATIAL_DOFS, BeamBody, PointMass, Section
from flexsym.scenes.feimport import read_folder, write_folder

# aluminium: a thin-walled inner section and a smaller outer one (I_y != I_z: the planes differ)
INNER = Section(7.0e10, 2700.0, 4.0e-4, 2.0e-7, Iy=8.0e-8, J=1.5e-7, G=2.6e10)
OUTER = Section(7.0e10, 2700.0, 2.0e-4, 5.0e-8, Iy=3.0e-8, J=6.0e-8, G=2.6e10)
L = 2.0


def uniform(n):
    return BeamBody.from_segments([(L, INNER)], n)


def stepped(n):
    return BeamBody.from_segments([(1.0, INNER), (1.0, OUTER)], n, (PointMass(2.0, 0.5),))


def dofs(body, *names):
    """Indices of the named dofs (SPATIAL_DOFS) of nodes 1..n, node by node."""
    return np.array([6 * i + SPATIAL_DOFS.index(d) for i in range(body.elements) for d in names])


def block(mat, idx):
    return mat[np.ix_(idx, idx)]


# ----- the matrices --------------------------------------------------------------------------

def test_one_element_is_the_documented_spatial_element():
    """A single element: the free node's 6 x 6 blocks are the planar element's (eq. 7-8) in
    both planes, theta_y = -dw/dx, and the torsion bar G J / l, rho I_p l / 3."""
    body = BeamBody((0.0, L), (INNER,))
    M, K = fedata.spatial_matrices(body)
    me, ke, _ = fedata.element_matrices(INNER, L)
    mz, kz, _ = fedata.element_matrices(Section(INNER.E, INNER.rho, INNER.A, INNER.Iy), L)
    u, v, w, phi, ty, tz = range(6)
    for big, y, z in ((M, me, mz), (K, ke, kz)):
        assert big[u, u] == y[3, 3]
        assert np.array_equal(block(big, [v, tz]), block(y, [4, 5]))
        flip = np.diag([1.0, -1.0])
        assert np.array_equal(block(big, [w, ty]), flip @ block(z, [4, 5]) @ flip)
    ip = INNER.Iy + INNER.I
    assert K[phi, phi] == pytest.approx(INNER.G * INNER.J / L, rel=1e-15)
    assert M[phi, phi] == pytest.approx(INNER.rho * ip * L / 3, rel=1e-15)
    coupled = np.ones((6, 6), bool)
    for group in ([u], [v, tz], [w, ty], [phi]):
        coupled[np.ix_(group, group)] = False
    assert not M[coupled].any() and not K[coupled].any()


def test_matrices_symmetric_and_the_point_mass_on_u_v_w_only():
    body = stepped(6)
    M, K = fedata.spatial_matrices(body)
    assert M.shape == K.shape == (36, 36)
    for mat in (M, K):
        assert np.array_equal(mat, mat.T)
        assert np.linalg.eigvalsh(mat).min() > 0
    bare, _ = fedata.spatial_matrices(BeamBody(body.nodes, body.sections))
    extra = M - bare
    tip = 6 * (body.elements - 1)
    assert np.allclose(np.diag(extra)[tip:tip + 6], [0.5, 0.5, 0.5, 0, 0, 0], rtol=1e-12, atol=1e-12)
    extra[tip + np.arange(3), tip + np.arange(3)] = 0.0
    assert np.abs(extra).max() < 1e-12


def test_torsion_frequencies_are_the_clamped_free_shaft_to_the_mesh_accuracy():
    """Linear elements with consistent mass: omega_h / omega - 1 = (k h)^2 / 24 + O(h^4),
    k = (2j - 1) pi / (2 L), for w_j = (2j - 1) pi / 2 sqrt(G J / (rho I_p)) / L."""
    errs = {}
    for n in (20, 40):
        body = uniform(n)
        M, K = fedata.spatial_matrices(body)
        idx = dofs(body, "phi")
        w = np.sqrt(eigh(block(K, idx), block(M, idx), eigvals_only=True)[:3])
        ip = INNER.Iy + INNER.I
        for j in (1, 2, 3):
            exact = (2 * j - 1) * np.pi / 2 * np.sqrt(INNER.G * INNER.J / (INNER.rho * ip)) / L
            kh = (2 * j - 1) * np.pi / 2 / n
            err = w[j - 1] / exact - 1
            assert err == pytest.approx(kh**2 / 24, rel=0.05), (n, j, err)
            errs[n, j] = err
    assert errs[20, 1] / errs[40, 1] == pytest.approx(4.0, rel=0.01)  # second order


@pytest.mark.parametrize("plane, names, inertia", [("y", ("v", "theta_z"), "I"), ("z", ("w", "theta_y"), "Iy")])
def test_bending_blocks_first_frequency_is_the_cantilevers_in_each_plane(plane, names, inertia):
    body = uniform(20)
    M, K = fedata.spatial_matrices(body)
    idx = dofs(body, *names)
    w1 = np.sqrt(eigh(block(K, idx), block(M, idx), eigvals_only=True)[0])
    exact = 1.875104068711961**2 * np.sqrt(INNER.E * getattr(INNER, inertia) / (INNER.rho * INNER.A * L**4))
    assert w1 == pytest.approx(exact, rel=1e-7)  # Hermite cubics: O(h^4)
    assert w1 == pytest.approx(1.8751**2 * np.sqrt(INNER.E * getattr(INNER, inertia) / (INNER.rho * INNER.A * L**4)), rel=1e-5)


def test_the_whole_spectrum_is_the_four_decoupled_problems():
    body = stepped(8)
    M, K = fedata.spatial_matrices(body)
    parts = [eigh(block(K, i), block(M, i), eigvals_only=True)
             for i in (dofs(body, "u"), dofs(body, "v", "theta_z"), dofs(body, "w", "theta_y"), dofs(body, "phi"))]
    assert np.allclose(eigh(K, M, eigvals_only=True), np.sort(np.concatenate(parts)), rtol=1e-9)


def test_rotations_follow_the_right_hand_rule():
    """A tip force along y turns the tip about +z (theta_z = dv/dx > 0), one along z about -y
    (theta_y = -dw/dx < 0): the cantilever's F L^2 / (2 E I) with the signs FE programs write."""
    body = uniform(4)
    _, K = fedata.spatial_matrices(body)
    tip = 6 * (body.elements - 1)
    for force, (defl, rot), inertia, sign in (("v", ("v", "theta_z"), INNER.I, 1.0),
                                              ("w", ("w", "theta_y"), INNER.Iy, -1.0)):
        f = np.zeros(K.shape[0])
        f[tip + SPATIAL_DOFS.index(force)] = 10.0
        q = np.linalg.solve(K, f)
        ei = INNER.E * inertia
        assert q[tip + SPATIAL_DOFS.index(defl)] == pytest.approx(10.0 * L**3 / (3 * ei), rel=1e-12)
        assert q[tip + SPATIAL_DOFS.index(rot)] == pytest.approx(sign * 10.0 * L**2 / (2 * ei), rel=1e-12)


def test_load_case_geometric_stiffness_in_both_planes_is_the_projected_one():
    """KG_<case> for the cases with an axial force (a_x, ww_yy, ww_zz), bending blocks only, the
    z plane's with theta_y flipped; projected on modes it is load_case_stiffness's."""
    body = stepped(8)
    kgs = fedata.spatial_load_case_geometric(body)
    assert set(kgs) == {"ww_yy", "ww_zz", "a_x"}
    assert np.array_equal(kgs["ww_yy"], kgs["ww_zz"])
    shapes = [body.mode_shape("bending", f, i) for f, i in (("static", 0), ("clamped_pinned", 1), ("clamped_pinned", 2))]
    D = fedata.load_case_stiffness(body, shapes)
    r, n = body.reference, body.elements
    Phi_y, Phi_z = (np.zeros((6 * n, len(shapes))) for _ in range(2))
    for k, sh in enumerate(shapes):
        slopes = np.array(sh.slopes[1:]) / body.length
        Phi_y[dofs(body, "v"), k], Phi_y[dofs(body, "theta_z"), k] = sh.values[1:], slopes
        Phi_z[dofs(body, "w"), k], Phi_z[dofs(body, "theta_y"), k] = sh.values[1:], -slopes
    for case, KG in kgs.items():
        assert np.array_equal(KG, KG.T)
        assert not KG[dofs(body, "u", "phi")].any()
        scale = r.rho * r.A * body.length**(fedata.load_case_scale(case) - 1)
        for Phi in (Phi_y, Phi_z):
            assert np.allclose(Phi.T @ KG @ Phi / scale, D[case], rtol=1e-10, atol=1e-12)
    N = fedata.load_case_forces(body)["a_x"]
    assert (N < 0).all()  # the frame accelerating along +x presses the body on its root
    assert np.trace(kgs["a_x"]) < 0


# ----- the folder ----------------------------------------------------------------------------

def test_round_trip_gives_an_equal_body_and_the_same_digest(tmp_path):
    body = stepped(6)
    folder = write_folder(body, tmp_path / "fe")
    assert sorted(p.name for p in folder.iterdir()) == ["K.mtx", "KG_a_x.mtx", "KG_ww_yy.mtx", "KG_ww_zz.mtx",
                                                        "M.mtx", "body.toml"]
    back = read_folder(folder)
    assert back == body and back.spatial and back.digest == body.digest
    assert back.matrices is None  # checked, and the table's: the modes come from the table
    again = write_folder(back, tmp_path / "again")
    for p in folder.iterdir():
        assert (again / p.name).read_bytes() == p.read_bytes()
    # a case without axial force may be given: its KG is zero
    toml = (folder / "body.toml").read_text()
    n = 6 * body.elements
    (folder / "KG_al_z.mtx").write_text(f"%%MatrixMarket matrix coordinate real symmetric\n{n} {n} 0\n")
    (folder / "body.toml").write_text(toml.replace('KG_a_x = "KG_a_x.mtx"', 'KG_a_x = "KG_a_x.mtx", KG_al_z = "KG_al_z.mtx"'))
    assert read_folder(folder) == body
    # without matrices the table alone is the body
    toml = (folder / "body.toml").read_text()
    (folder / "body.toml").write_text("\n".join(l for l in toml.splitlines()
                                                if not l.startswith(("matrices", "dofs"))))
    assert read_folder(folder).digest == body.digest


def test_a_permuted_dof_map_reads_the_same(tmp_path):
    """A program that numbers its dofs otherwise (here: every node's dofs reversed, nodes from
    the tip, dense array files) gives the same body; the same matrices under the original map
    are refused."""
    body = stepped(5)
    folder = write_folder(body, tmp_path / "fe")
    toml = (folder / "body.toml").read_text()
    names = [f"{k}:{d}" for k in range(1, body.elements + 1) for d in SPATIAL_DOFS]
    order = [f"{k}:{d}" for k in range(body.elements, 0, -1) for d in SPATIAL_DOFS[::-1]]
    perm = np.array([names.index(d) for d in order])  # file row i is flexsym's dof perm[i]
    old_dofs = next(l for l in toml.splitlines() if l.startswith("dofs"))
    new_dofs = "dofs = [" + ", ".join(f'"{d}"' for d in order) + "]"
    from flexsym.scenes.feimport import matrices

    for name, mat in matrices(body).items():
        (folder / f"{name}.mtx").unlink()
        mmwrite(str(folder / f"{name}.mtx"), mat[np.ix_(perm, perm)], symmetry="general")
    with pytest.raises(SpecError, match="M.mtx: differs from the matrix of the element table"):
        read_folder(folder)
    (folder / "body.toml").write_text(toml.replace(old_dofs, new_dofs))
    back = read_folder(folder)
    assert back == body and back.digest == body.digest


# ----- malformed folders ----------------------------------------------------------------------

def _element(text: str, e: int, old: str, new: str) -> str:
    """Replace old by new in the e-th [[elements]] table of body.toml."""
    parts = text.split("[[elements]]")
    assert old in parts[e + 1], (old, parts[e + 1])
    parts[e + 1] = parts[e + 1].replace(old, new, 1)
    return "[[elements]]".join(parts)


def _scale_entries(path: Path, factor: float) -> None:
    lines = path.read_text().splitlines()
    out = lines[:2] + [f"{i} {j} {float(v) * factor!r}" for i, j, v in (l.split() for l in lines[2:])]
    path.write_text("\n".join(out) + "\n")


def _corrupt(folder: Path, case: str) -> tuple[str, str]:
    """Apply one defect to an exported spatial folder; (the file named, a fragment of the line)."""
    toml = folder / "body.toml"
    text = toml.read_text()
    if case == "mixed_element":  # element 2 written as a planar one
        text = _element(text, 2, "inertia_z", "inertia")
        toml.write_text(text)
        return "body.toml", "elements[2] gives inertia, a planar element's key, in a spatial body"
    if case == "spatial_keys_unannounced":  # no kind = "spatial": a planar body with spatial keys
        toml.write_text(text.replace('kind = "spatial"\n', ""))
        return "body.toml", "elements[0] gives shear_modulus, a spatial element's key, in a planar body"
    if case == "missing_torsion_constant":
        toml.write_text(_element(text, 3, "torsion_constant = 6e-08\n", ""))
        return "body.toml", "elements[3].torsion_constant must be a positive number"
    if case == "negative_shear_modulus":
        toml.write_text(_element(text, 1, "shear_modulus = 26000000000.0", "shear_modulus = -26000000000.0"))
        return "body.toml", "elements[1].shear_modulus must be a positive number"
    if case == "rotary_point_mass":
        toml.write_text(text.replace("mass = 0.5\n", "mass = 0.5\nrotary = 0.01\n"))
        return "body.toml", "rotary inertia is planar only"
    if case == "bad_kind":
        toml.write_text(text.replace('kind = "spatial"', 'kind = "3d"'))
        return "body.toml", "kind must be \"planar\" (the default) or \"spatial\" (got '3d')"
    if case == "wrong_dof_name":
        toml.write_text(text.replace('"2:theta_y"', '"2:theta"'))
        return "body.toml", "dofs[10] = '2:theta': expected node:u, node:v, node:w, node:phi, node:theta_y or node:theta_z"
    if case == "planar_dof_map":
        names = ", ".join(f'"{k}:{d}"' for k in range(1, 5) for d in ("u", "v", "theta"))
        old = next(l for l in text.splitlines() if l.startswith("dofs"))
        toml.write_text(text.replace(old, f"dofs = [{names}]"))
        return "body.toml", "dofs has 12 entries; 4 free nodes have 24 dofs"
    if case == "wrong_size":  # the planar body's M: 3 dofs per node
        lines = (folder / "M.mtx").read_text().splitlines()
        kept = [l for l in lines[2:] if max(map(int, l.split()[:2])) <= 12]
        (folder / "M.mtx").write_text("\n".join([lines[0], f"12 12 {len(kept)}"] + kept) + "\n")
        return "M.mtx", "is 12 x 12; the dof map has 24 dofs"
    if case == "theta_y_as_dw_dx":  # a program writing theta_y = +dw/dx: not the table's K
        lines = (folder / "K.mtx").read_text().splitlines()
        ty = {6 * k + 5 for k in range(4)}  # 1-based rows of theta_y
        out = lines[:2]
        for l in lines[2:]:
            i, j, v = l.split()
            s = (-1) ** ((int(i) in ty) + (int(j) in ty))
            out.append(f"{i} {j} {float(v) * s!r}")
        (folder / "K.mtx").write_text("\n".join(out) + "\n")
        return "K.mtx", "differs from the matrix of the element table"
    if case == "kg_disagrees":
        _scale_entries(folder / "KG_a_x.mtx", 2.0)
        return "KG_a_x.mtx", "differs from the matrix of the element table"
    if case == "kg_of_a_case_without_axial_force":  # al_z has none: its KG is zero
        shutil.copy(folder / "KG_a_x.mtx", folder / "KG_al_z.mtx")
        toml.write_text(text.replace('KG_a_x = "KG_a_x.mtx"', 'KG_a_x = "KG_a_x.mtx", KG_al_z = "KG_al_z.mtx"'))
        return "KG_al_z.mtx", "differs from the matrix of the element table"
    if case == "unknown_case":
        toml.write_text(text.replace("KG_ww_zz = ", "KG_ww_zq = "))
        return "body.toml", "matrices.KG_ww_zq: unknown load case 'ww_zq'"
    if case == "planar_kg_key":
        toml.write_text(text.replace('M = "M.mtx"', 'M = "M.mtx", KG = "KG_a_x.mtx"'))
        return "body.toml", "matrices must be a table with M, K and optionally KG_<case> (file names; unknown: KG)"
    if case == "kg_asymmetric":
        lines = (folder / "KG_ww_yy.mtx").read_text().splitlines()
        lines[0] = lines[0].replace("symmetric", "general")
        (folder / "KG_ww_yy.mtx").write_text("\n".join(lines) + "\n")
        return "KG_ww_yy.mtx", "is not symmetric"
    if case == "missing_kg_file":
        (folder / "KG_ww_zz.mtx").unlink()
        return "KG_ww_zz.mtx", "no such file"
    raise AssertionError(case)


CASES = ("mixed_element", "spatial_keys_unannounced", "missing_torsion_constant", "negative_shear_modulus",
         "rotary_point_mass", "bad_kind", "wrong_dof_name", "planar_dof_map", "wrong_size", "theta_y_as_dw_dx",
         "kg_disagrees", "kg_of_a_case_without_axial_force", "unknown_case", "planar_kg_key", "kg_asymmetric",
         "missing_kg_file")


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    return write_folder(stepped(4), tmp_path_factory.mktemp("fe") / "arm")


@pytest.mark.parametrize("case", CASES)
def test_malformed_spatial_folders_are_refused_with_one_line(case, exported, tmp_path):
    folder = tmp_path / "arm"
    shutil.copytree(exported, folder)
    assert read_folder(folder) == stepped(4)  # the copy reads before the defect
    name, expected = _corrupt(folder, case)
    with pytest.raises(SpecError) as exc:
        read_folder(folder)
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(f"{folder / name}: ") and expected in msg, msg


def test_matrices_beyond_the_dof_limit_are_refused_before_they_are_built(tmp_path):
    """A folder's matrices are dense: at most MAX_DOFS (6000) dofs, 1000 spatial elements, as
    2000 planar ones. A finer spatial mesh is refused with its matrices (read or written), and
    read without them."""
    from flexsym.scenes.feimport import MAX_DOFS, body_toml

    body = uniform(1001)
    folder = tmp_path / "fine"
    folder.mkdir()
    (folder / "body.toml").write_text(body_toml(body, ("M", "K")))  # no M.mtx: never read
    with pytest.raises(SpecError, match=f"body.toml: 1001 spatial elements have 6006 dofs: "
                                        f"a folder's matrices .* at most {MAX_DOFS}") as exc:
        read_folder(folder)
    assert "\n" not in str(exc.value)
    with pytest.raises(SpecError, match="out: 1001 spatial elements have 6006 dofs"):
        write_folder(body, tmp_path / "out")
    assert not (tmp_path / "out").exists()
    toml = (folder / "body.toml").read_text()
    (folder / "body.toml").write_text("\n".join(l for l in toml.splitlines() if not l.startswith(("matrices", "dofs"))))
    assert read_folder(folder) == body
