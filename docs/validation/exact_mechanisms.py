"""Errors of `exact` runs of a system scene against `ef` extrapolated in elements and step
(docs/theory/exact-kinematics.md, "In a mechanism"):

    python docs/validation/exact_mechanisms.py [--mesh-order P] FINE.csv MESH.csv STEP.csv RUN.csv ...

FINE: ef on n elements at step h; MESH: n/2 elements at h; STEP: n elements at 2h (both
converge at order 2: the curvature's and the axial strain's O(h^2), generalized-alpha's and
ali3p's order), so the reference is FINE + (FINE - MESH)/3 + (FINE - STEP)/3 (--mesh-order P: (FINE - MESH)
/ (2^P - 1), for an output that converges faster in the mesh). With --half-step the three
files are HALF FINE MESH, HALF being FINE at h/2, and the reference HALF + (FINE - MESH)/(2^P - 1)
(no extrapolation in the step, for an output whose step convergence is not yet at its order:
S3's M_mid). Per RUN and scene column: max |y - y_ref| over the rows / peak |y_ref|, and the
error of the peak."""
import csv
import sys

import numpy as np


def read(path: str) -> dict[str, np.ndarray]:
    """The scene's columns (those the '# units:' line names, t first) of a `flexsym run` CSV."""
    with open(path) as f:
        rows = list(csv.reader(f))
    units = next(",".join(r) for r in rows if r and r[0].startswith("# units:"))  # after any '# assembly:'
    names = [x.split(" [")[0].strip() for x in units.removeprefix("# units:").split(",")]
    data = [r for r in rows[2:] if r and not r[0].startswith("#")]
    return {c: np.array([float(r[rows[0].index(c)]) for r in data]) for c in names}


def main(fine: str, mesh: str, step: str, *runs: str, mesh_order: int = 2, half_step: bool = False) -> None:
    F, M, S = read(fine), read(mesh), read(step)
    cols = [c for c in F if c not in ("t", "violation")]
    if half_step:  # fine = HALF, mesh = FINE, step = MESH
        ref = {c: F[c] + (M[c] - S[c]) / (2**mesh_order - 1) for c in cols}
    else:
        ref = {c: F[c] + (F[c] - M[c]) / (2**mesh_order - 1) + (F[c] - S[c]) / 3 for c in cols}
    for path in runs:
        r = read(path)
        out = []
        for c in cols:
            peak = np.abs(ref[c]).max()
            out.append(f"{c} {np.abs(r[c] - ref[c]).max() / peak:.1e} ({(np.abs(r[c]).max() - peak) / peak:+.1e})")
        print(path, "  ".join(out))


if __name__ == "__main__":
    args, order, half = sys.argv[1:], 2, False
    while args[0].startswith("--"):
        if args[0] == "--mesh-order":
            order, args = int(args[1]), args[2:]
        elif args[0] == "--half-step":
            half, args = True, args[1:]
        else:
            sys.exit(f"exact_mechanisms.py: unknown option {args[0]}")
    main(*args, mesh_order=order, half_step=half)
