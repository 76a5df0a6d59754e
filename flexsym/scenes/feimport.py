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
from flexsym.model.fedata import BeamBody, PointMass, Section, check_mesh_keys

FORMAT = "flexsym-beam-fe-1"
DOF_NAMES = ("u", "v", "theta")
MAX_ELEMENTS = 2000  # as a scene's elements (fedata.check_mesh_keys)
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
    known = {"format", "nodes", "dofs", "elements", "point_masses", "matrices"}
    unknown = sorted(set(data) - known)
    if unknown:
        _fail(path, f"unknown key '{unknown[0]}' (known: {', '.join(sorted(known))})")
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
        sections.append(Section(*(_number(path, f"elements[{e}].{k}", el.get(k))
                                  for k in ("youngs_modulus", "density", "area", "inertia"))))
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
    if not isinstance(mats, dict) or "M" not in mats or "K" not in mats or set(mats) - {"M", "K", "KG"}:
        _fail(path, "matrices must be a table with M, K and optionally KG (file names)")
    perm = _dof_permutation(path, data.get("dofs"), n)
    own = body.assembled
    read = []
    for key, ref in zip(("M", "K", "KG"), own):
        if key not in mats:
            read.append(ref)
            continue
        if not isinstance(mats[key], str):
            _fail(path, f"matrices.{key} must be a file name")
        mat = _read_mtx(folder / mats[key], 3 * n)
        mat = mat[np.ix_(perm, perm)]  # to flexsym's order (u, v, theta of nodes 1..n)
        _check(folder / mats[key], key, mat, ref)
        read.append(mat)
    return BeamBody(body.nodes, body.sections, body.masses, tuple(read))


def _dof_permutation(path, dofs, n) -> np.ndarray:
    """perm[i] = the matrix row of flexsym's dof i (u, v, theta of nodes 1..n)."""
    if not isinstance(dofs, list) or not all(isinstance(d, str) for d in dofs):
        _fail(path, "dofs must list the dof of every matrix row as \"node:u|v|theta\"")
    if len(dofs) != 3 * n:
        _fail(path, f"dofs has {len(dofs)} entries; {n} free nodes have {3 * n} dofs")
    row = {}
    for i, d in enumerate(dofs):
        node, _, name = d.partition(":")
        if not node.isdigit() or name not in DOF_NAMES:
            _fail(path, f"dofs[{i}] = {d!r}: expected node:u, node:v or node:theta")
        k = int(node)
        if not 1 <= k <= n:
            _fail(path, f"dofs[{i}] = {d!r}: node {k} is missing (free nodes are 1..{n}; "
                  "node 0 is clamped)")
        key = 3 * (k - 1) + DOF_NAMES.index(name)
        if key in row:
            _fail(path, f"dofs[{i}] = {d!r} appears twice")
        row[key] = i
    return np.array([row[i] for i in range(3 * n)])


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


def _check(path: Path, key: str, mat: np.ndarray, ref: np.ndarray) -> None:
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
    diff = np.linalg.norm(mat - ref) / (np.linalg.norm(ref) or 1.0)
    if diff > MATCH_TOL:
        _fail(path, f"differs from the matrix of the element table by {diff:.1e} (relative); the "
              "invariants are computed from the table, so the two must describe the same beam "
              "(planar element of eq. 7-8, consistent mass)")


# ----- writing -----------------------------------------------------------------------------

def _mtx(mat: np.ndarray) -> str:
    """Symmetric coordinate Matrix Market, lower triangle, every double as repr (exact)."""
    n = mat.shape[0]
    rows = [(i, j, mat[i, j]) for j in range(n) for i in range(j, n) if mat[i, j] != 0.0]
    lines = ["%%MatrixMarket matrix coordinate real symmetric", f"{n} {n} {len(rows)}"]
    lines += [f"{i + 1} {j + 1} {float(v)!r}" for i, j, v in rows]
    return "\n".join(lines) + "\n"


def body_toml(body: BeamBody) -> str:
    n = body.elements
    out = [f'format = "{FORMAT}"',
           "nodes = [" + ", ".join(repr(float(x)) for x in body.nodes) + "]",
           "dofs = [" + ", ".join(f'"{k}:{d}"' for k in range(1, n + 1) for d in DOF_NAMES) + "]",
           'matrices = { M = "M.mtx", K = "K.mtx", KG = "KG.mtx" }', ""]
    for e, s in enumerate(body.sections):
        out += ["[[elements]]", f"nodes = [{e}, {e + 1}]", f"youngs_modulus = {s.E!r}",
                f"density = {s.rho!r}", f"area = {s.A!r}", f"inertia = {s.I!r}", ""]
    for m in body.masses:
        out += ["[[point_masses]]", f"node = {body.node_index(m.x)}", f"mass = {m.mass!r}",
                f"rotary = {m.rotary!r}", ""]
    return "\n".join(out)


def write_folder(body: BeamBody, folder) -> Path:
    """Export a body (its element table and assembled matrices) as a new folder, filled in a
    temporary sibling and renamed: a failure (the disk full: OutputError, one line naming the
    file) leaves nothing half-written."""
    from flexsym.core.files import atomic_folder, write_new, writing

    folder = Path(folder)
    if folder.exists():
        raise SpecError(f"{folder}: already exists (choose a new folder)")
    with writing(folder):
        folder.parent.mkdir(parents=True, exist_ok=True)
    with atomic_folder(folder) as tmp:
        write_new(tmp / "body.toml", body_toml(body), folder / "body.toml")
        for name, mat in zip(("M", "K", "KG"), body.assembled):
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
