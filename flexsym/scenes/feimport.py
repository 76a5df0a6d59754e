"""Beam finite-element data from other programs: a documented folder format, read and written.

    body.toml   format = "flexsym-beam-fe-1"
                nodes = [x0 = 0.0, x1, ..., xn]          metres along the axis; node 0 is the
                                                          clamped interface (the root)
                dofs = ["1:u", "1:v", "1:theta", ...]     the row/column of every matrix entry:
                                                          node:u|v|theta (theta = dv/dx), the free
                                                          dofs of nodes 1..n in any order
                [[elements]] nodes = [i, i+1], youngs_modulus, density, area, inertia
                [[point_masses]] node, mass, rotary (optional)
                matrices = { M = "M.mtx", K = "K.mtx", KG = "KG.mtx" }   (optional; KG optional)
    M.mtx, K.mtx, KG.mtx   Matrix Market (coordinate or array, real, general or symmetric):
                the consistent mass with the point masses, the linear stiffness, the geometric
                stiffness for a unit axial load in every element, over the dofs above.

The modes are computed from the matrices (the element table builds them when they are
absent); the invariants use the element table for the distribution of mass and stiffness
along the axis, so the matrices must be those of the table (checked: the element of
fedata.element_matrices, consistent mass). Every problem is one line naming the file.

A spatial body (fedata.Section with Iy, J, G) says so and gives the spatial keys instead:

    body.toml   kind = "spatial"                          (absent: "planar", the format above)
                dofs = ["1:u", "1:v", "1:w", "1:phi", "1:theta_y", "1:theta_z", ...]
                                                          node:u|v|w|phi|theta_y|theta_z: u axial,
                                                          v, w the deflections along y and z, phi
                                                          the twist, theta_y = -dw/dx, theta_z =
                                                          dv/dx (rotations about the axes)
                [[elements]] nodes, youngs_modulus, shear_modulus, density, area, inertia_y,
                             inertia_z, torsion_constant   (every element; no inertia)
                [[point_masses]] node, mass               (on the axis: no rotary inertia)
                matrices = { M = "M.mtx", K = "K.mtx", KG_a_x = "KG_a_x.mtx", ... }
                                                          (optional; every KG_<case> optional)
    M.mtx, K.mtx   over those dofs (6 per free node): fedata.spatial_matrices, the planar
                element in both bending planes (I = inertia_z along y, inertia_y along z), the
                axial bar, the torsion bar (G J / l [1 -1; -1 1], rho I_p l / 6 [2 1; 1 2],
                I_p = inertia_y + inertia_z), consistent mass, point masses on u, v and w.
    KG_<case>.mtx  the geometric stiffness of a unit inertial load case (fedata.LOAD_CASES:
                ww_xx..ww_zz the products omega_i omega_j, al_x..al_z the angular accelerations,
                a_x..a_z the acceleration minus gravity) over the same dofs: sum_e N_e K_G,e in
                both bending planes, N_e the element's axial force in that case
                (fedata.spatial_load_case_geometric); written for the cases with an axial force
                (ww_yy, ww_zz, a_x), zero for the others.

A spatial folder's matrices are checked against the table the same way and not kept: the
modes come from the element table (its planar views), as a folder's M and K agree with it.
A folder's matrices (dense in memory) have at most MAX_DOFS dofs: 2000 planar elements, 1000
spatial ones; a finer spatial mesh is read from its table alone (no matrices).
"""
from __future__ import annotations

import io
import math
import tomllib
from pathlib import Path

import numpy as np

from flexsym.core.errors import SpecError
from flexsym.core.files import read_limited
from flexsym.model.limits import MAX_FILE_BYTES, MAX_MAGNITUDE, MIN_POSITIVE
from flexsym.model.fedata import (LOAD_CASES, SPATIAL_DOFS, BeamBody, PointMass, Section,
                                  check_mesh_keys, spatial_load_case_geometric, spatial_matrices)

FORMAT = "flexsym-beam-fe-1"
DOF_NAMES = ("u", "v", "theta")
KINDS = {"planar": DOF_NAMES, "spatial": SPATIAL_DOFS}  # kind -> the dofs of a node
ELEMENT_KEYS = {  # kind -> {body.toml key: Section field}, in the order written
    "planar": {"youngs_modulus": "E", "density": "rho", "area": "A", "inertia": "I"},
    "spatial": {"youngs_modulus": "E", "shear_modulus": "G", "density": "rho", "area": "A",
                "inertia_y": "Iy", "inertia_z": "I", "torsion_constant": "J"}}
MAX_ELEMENTS = 2000  # as a scene's elements (fedata.check_mesh_keys)
MAX_DOFS = 3 * MAX_ELEMENTS  # a folder's (dense) matrices: a planar body's, or 1000 spatial elements
MATCH_TOL = 1e-8  # relative (Frobenius) difference allowed between the matrices and the table


def _fail(path: Path, msg: str):
    raise SpecError(f"{path}: {msg}")


def _number(path, where, v, positive=True):
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
            or (v < MIN_POSITIVE if positive else v < 0) or v > MAX_MAGNITUDE:
        _fail(path, f"{where} must be a {'positive' if positive else 'non-negative'} number, "
              f"{MIN_POSITIVE if positive else 0:g} <= x <= {MAX_MAGNITUDE:g} (got {v!r})")
    return float(v)


def read_folder(folder) -> BeamBody:
    folder = Path(folder)
    path = folder / "body.toml"
    try:
        data = tomllib.loads(read_limited(path, MAX_FILE_BYTES, "body.toml").decode("utf-8"))
    except FileNotFoundError:
        _fail(path, "no such file (an imported body is a folder with body.toml)")
    except (OSError, UnicodeDecodeError) as exc:
        _fail(path, f"cannot read: {exc}")
    except tomllib.TOMLDecodeError as exc:
        _fail(path, f"not valid TOML: {exc}")
    if data.get("format") != FORMAT:
        _fail(path, f"format must be \"{FORMAT}\" (got {data.get('format')!r})")
    known = {"format", "kind", "nodes", "dofs", "elements", "point_masses", "matrices"}
    unknown = sorted(set(data) - known)
    if unknown:
        _fail(path, f"unknown key '{unknown[0]}' (known: {', '.join(sorted(known))})")
    kind = data.get("kind", "planar")
    if kind not in KINDS:
        _fail(path, f"kind must be \"planar\" (the default) or \"spatial\" (got {kind!r})")
    keys = ELEMENT_KEYS[kind]
    other = {k: o for o in KINDS if o != kind for k in ELEMENT_KEYS[o] if k not in keys}
    nodes = data.get("nodes")
    if not isinstance(nodes, list) or len(nodes) < 2:
        _fail(path, "nodes must be a list of at least two x coordinates [m]")
    if len(nodes) > MAX_ELEMENTS + 1:
        _fail(path, f"{len(nodes)} nodes: more than the limit of {MAX_ELEMENTS + 1} ({MAX_ELEMENTS} elements)")
    nodes = [_number(path, f"nodes[{i}]", x, positive=i > 0) for i, x in enumerate(nodes)]
    n = len(nodes) - 1
    elems = data.get("elements")
    if not isinstance(elems, list) or not all(isinstance(e, dict) for e in elems):
        _fail(path, "elements must be a list of tables [[elements]]")
    if len(elems) != n:
        _fail(path, f"{len(elems)} elements for {len(nodes)} nodes (a beam of n elements has n + 1 nodes)")
    sections = []
    for e, el in enumerate(elems):
        en = el.get("nodes")
        if not (isinstance(en, list) and len(en) == 2 and all(isinstance(k, int) and not isinstance(k, bool) for k in en)):
            _fail(path, f"elements[{e}].nodes must be two node numbers")
        if not all(0 <= k <= n for k in en):
            _fail(path, f"elements[{e}] refers to node {max(en) if max(en) > n else min(en)}, "
                  f"which is missing (nodes are 0..{n})")
        if en != [e, e + 1]:
            _fail(path, f"elements[{e}] joins nodes {en}: elements must follow the axis, element e "
                  "joining nodes e and e + 1")
        mixed = [k for k in el if k in other]
        if mixed:
            _fail(path, f"elements[{e}] gives {mixed[0]}, a {other[mixed[0]]} element's key, in a "
                  f"{kind} body (a spatial body says kind = \"spatial\" and every element gives "
                  f"{', '.join(ELEMENT_KEYS['spatial'])}; a planar one's give "
                  f"{', '.join(ELEMENT_KEYS['planar'])})")
        sections.append(Section(**{f: _number(path, f"elements[{e}].{k}", el.get(k))
                                   for k, f in keys.items()}))
    masses = []
    for i, pm in enumerate(data.get("point_masses", [])):
        if not isinstance(pm, dict) or not isinstance(pm.get("node"), int) or not 0 <= pm["node"] <= n:
            _fail(path, f"point_masses[{i}].node must be a node number 0..{n}")
        masses.append(PointMass(nodes[pm["node"]], _number(path, f"point_masses[{i}].mass",
                                                           pm.get("mass", 0.0), False),
                                _number(path, f"point_masses[{i}].rotary", pm.get("rotary", 0.0), False)))
    try:
        body = BeamBody(tuple(nodes), tuple(sections), tuple(masses)).validate(str(path))
    except SpecError as exc:
        raise SpecError(str(exc)) from None
    mats = data.get("matrices")
    if mats is None:
        return body
    names = matrix_names(kind)
    optional = "KG" if kind == "planar" else "KG_<case>"
    if not isinstance(mats, dict) or "M" not in mats or "K" not in mats:
        _fail(path, f"matrices must be a table with M, K and optionally {optional} (file names)")
    for key in (k for k in mats if k not in names):
        if kind == "spatial" and key.startswith("KG_"):
            _fail(path, f"matrices.{key}: unknown load case '{key[3:]}' (the cases: "
                  f"{', '.join(LOAD_CASES)})")
        _fail(path, f"matrices must be a table with M, K and optionally {optional} (file names; "
              f"unknown: {key})")
    size = matrix_size(path, kind, n)
    perm = _dof_permutation(path, data.get("dofs"), n, KINDS[kind])
    own = matrices(body)
    read = {}
    for key in (k for k in names if k in mats):
        if not isinstance(mats[key], str):
            _fail(path, f"matrices.{key} must be a file name")
        mat = _read_mtx(folder / mats[key], size)
        mat = mat[np.ix_(perm, perm)]  # to flexsym's order (the dofs of node 1, 2, ..., n)
        _check(folder / mats[key], key, mat, own.pop(key, np.zeros_like(mat)), kind)
        if kind == "planar":  # a spatial folder's are checked, not kept (module docstring)
            read[key] = mat
    if kind == "spatial":
        return body
    own |= read
    return BeamBody(body.nodes, body.sections, body.masses, tuple(own[k] for k in names))


def _kind(body: BeamBody) -> str:
    return "spatial" if body.spatial else "planar"


def matrix_names(kind: str) -> tuple[str, ...]:
    """The matrices a folder may give (every one but M and K optional)."""
    return ("M", "K", "KG") if kind == "planar" else ("M", "K") + tuple(f"KG_{c}" for c in LOAD_CASES)


def matrix_size(where, kind: str, n: int) -> int:
    """The size of the matrices of a folder of n elements, within MAX_DOFS."""
    size = len(KINDS[kind]) * n
    if size > MAX_DOFS:
        _fail(where, f"{n} {kind} elements have {size} dofs: a folder's matrices (dense in "
              f"memory) have at most {MAX_DOFS}, {MAX_DOFS // len(KINDS[kind])} {kind} elements "
              "(remesh the body, or give no matrices: the element table alone is the body)")
    return size


def matrices(body: BeamBody) -> dict[str, np.ndarray]:
    """The element table's matrices by name, over the folder's dofs in flexsym's order: a
    planar body's M, K, KG (BeamBody.assembled), a spatial body's M, K and KG_<case> of every
    load case with an axial force (fedata.spatial_matrices, spatial_load_case_geometric)."""
    if not body.spatial:
        return dict(zip(("M", "K", "KG"), body.assembled))
    M, K = spatial_matrices(body)
    return {"M": M, "K": K} | {f"KG_{c}": kg for c, kg in spatial_load_case_geometric(body).items()}


def _dof_permutation(path, dofs, n, names) -> np.ndarray:
    """perm[i] = the matrix row of flexsym's dof i (names of node 1, ..., names of node n)."""
    if not isinstance(dofs, list) or not all(isinstance(d, str) for d in dofs):
        _fail(path, f"dofs must list the dof of every matrix row as \"node:{'|'.join(names)}\"")
    size = len(names) * n
    if len(dofs) != size:
        _fail(path, f"dofs has {len(dofs)} entries; {n} free nodes have {size} dofs")
    row = {}
    for i, d in enumerate(dofs):
        node, _, name = d.partition(":")
        if not node.isdigit() or name not in names:
            _fail(path, f"dofs[{i}] = {d!r}: expected "
                  f"{', '.join(f'node:{x}' for x in names[:-1])} or node:{names[-1]}")
        k = int(node)
        if not 1 <= k <= n:
            _fail(path, f"dofs[{i}] = {d!r}: node {k} is missing (free nodes are 1..{n}; "
                  "node 0 is clamped)")
        key = len(names) * (k - 1) + names.index(name)
        if key in row:
            _fail(path, f"dofs[{i}] = {d!r} appears twice")
        row[key] = i
    return np.array([row[i] for i in range(size)])


def _read_mtx(path: Path, size: int) -> np.ndarray:
    from scipy.io import mminfo, mmread

    try:
        data = read_limited(path, MAX_FILE_BYTES, "Matrix Market file")
    except FileNotFoundError:
        _fail(path, "no such file")
    try:  # the header's size before anything is allocated: a 10^6 x 10^6 claim is refused here
        rows, cols, entries, fmt = mminfo(io.BytesIO(data))[:4]
    except Exception as exc:  # scipy raises ValueError/IndexError/... for malformed files
        _fail(path, f"not a readable Matrix Market file ({type(exc).__name__}: {exc})".replace("\n", " "))
    if (rows, cols) != (size, size):
        _fail(path, f"is {rows} x {cols}; the dof map has {size} dofs")
    if entries > size * size:
        _fail(path, f"declares {entries} entries; a {size} x {size} matrix has at most {size * size}")
    try:
        mat = mmread(io.BytesIO(data))
    except Exception as exc:  # scipy raises ValueError/IndexError/... for malformed files
        _fail(path, f"not a readable Matrix Market file ({type(exc).__name__}: {exc})".replace("\n", " "))
    mat = mat.toarray() if hasattr(mat, "toarray") else np.asarray(mat)
    if mat.dtype.kind not in "fi":
        _fail(path, f"entries must be real numbers (got {mat.dtype})")
    mat = mat.astype(float)
    if mat.shape != (size, size):
        _fail(path, f"is {mat.shape[0]} x {mat.shape[1]}; the dof map has {size} dofs")
    return mat


_SOURCES = {"planar": "planar element of eq. 7-8, consistent mass",
            "spatial": "fedata.spatial_matrices: eq. 7-8 in both planes with theta_y = -dw/dx, "
                       "the torsion bar, consistent mass",
            "case": "fedata.spatial_load_case_geometric: the case's element axial forces times "
                    "eq. 8's K_G in both planes, theta_y = -dw/dx; zero without axial force"}


def _check(path: Path, key: str, mat: np.ndarray, ref: np.ndarray, kind: str) -> None:
    if not np.all(np.isfinite(mat)):
        i, j = np.argwhere(~np.isfinite(mat))[0]
        _fail(path, f"entry ({i + 1}, {j + 1}) is not finite ({mat[i, j]})")
    scale = np.abs(mat).max() or 1.0
    asym = np.abs(mat - mat.T).max()
    if asym > 1e-12 * scale:
        _fail(path, f"is not symmetric (largest |A - A^T| = {asym:.3g}, {asym / scale:.1e} of the largest entry)")
    if key in ("M", "K"):
        try:
            np.linalg.cholesky(mat)
        except np.linalg.LinAlgError:
            what = "mass" if key == "M" else "stiffness of the clamped body"
            _fail(path, f"is not positive definite (a {what} must be)")
    norm = np.linalg.norm(ref)
    diff = np.linalg.norm(mat - ref) / (norm or 1.0)
    if diff > MATCH_TOL:
        _fail(path, f"differs from the matrix of the element table by {diff:.1e} "
              f"({'relative' if norm else 'absolute: the table gives zero'}); the invariants are "
              "computed from the table, so the two must describe the same beam "
              f"({_SOURCES['case' if key.startswith('KG_') else kind]})")


# ----- writing -----------------------------------------------------------------------------

def _mtx(mat: np.ndarray) -> str:
    """Symmetric coordinate Matrix Market, lower triangle, every double as repr (exact)."""
    n = mat.shape[0]
    j, i = np.nonzero(np.tril(mat).T)  # column by column, rows from the diagonal down
    lines = ["%%MatrixMarket matrix coordinate real symmetric", f"{n} {n} {len(i)}"]
    lines += [f"{a + 1} {b + 1} {float(v)!r}" for a, b, v in zip(i, j, mat[i, j])]
    return "\n".join(lines) + "\n"


def body_toml(body: BeamBody, names: tuple[str, ...]) -> str:
    """body.toml of a body whose folder holds the matrices `names` (of matrices(body))."""
    n, kind = body.elements, _kind(body)
    out = [f'format = "{FORMAT}"'] + (['kind = "spatial"'] if body.spatial else []) + [
           "nodes = [" + ", ".join(repr(float(x)) for x in body.nodes) + "]",
           "dofs = [" + ", ".join(f'"{k}:{d}"' for k in range(1, n + 1) for d in KINDS[kind]) + "]",
           "matrices = { " + ", ".join(f'{k} = "{k}.mtx"' for k in names) + " }", ""]
    for e, s in enumerate(body.sections):
        out += ["[[elements]]", f"nodes = [{e}, {e + 1}]"]
        out += [f"{k} = {getattr(s, f)!r}" for k, f in ELEMENT_KEYS[kind].items()] + [""]
    for m in body.masses:
        out += ["[[point_masses]]", f"node = {body.node_index(m.x)}", f"mass = {m.mass!r}"]
        out += [] if body.spatial else [f"rotary = {m.rotary!r}"]
        out += [""]
    return "\n".join(out)


def write_folder(body: BeamBody, folder) -> Path:
    """Export a body (its element table and its matrices: matrices(body)) as a new folder, filled in a
    temporary sibling and renamed: a failure (the disk full: OutputError, one line naming the
    file) leaves nothing half-written."""
    from flexsym.core.files import atomic_folder, write_new, writing

    folder = Path(folder)
    if folder.exists():
        raise SpecError(f"{folder}: already exists (choose a new folder)")
    matrix_size(folder, _kind(body), body.elements)
    with writing(folder):
        folder.parent.mkdir(parents=True, exist_ok=True)
    mats = matrices(body)
    with atomic_folder(folder) as tmp:
        write_new(tmp / "body.toml", body_toml(body, tuple(mats)), folder / "body.toml")
        for name, mat in mats.items():
            write_new(tmp / f"{name}.mtx", _mtx(mat), folder / f"{name}.mtx")
    return folder


def scene_folder(r) -> BeamBody:
    """The [body] table of a scene that names an imported folder (r: scene._Reader)."""
    tab = r.data["body"]
    check_mesh_keys(r)
    if "segments" in tab or "point_masses" in tab or "elements" in tab:
        r.fail("[body] folder", "an imported body brings its own elements and masses: "
               "drop segments, point_masses and elements (its mesh is the folder's)")
    return read_folder(r.path.parent / r.string("body", "folder"))
