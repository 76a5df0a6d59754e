"""S6 and S7 with the spatial `ef` (rod3d elements on the beam's free floating frame): runs of
the reference study, a Richardson extrapolation of two of them.

A scene's beam gets `model = { variant = "ef", elements = n }` (its section forces from its
strains, `moment` = `axial_force` = "constitutive", as the tables were measured) and the run-time parameter
bending_inertia (the factor b of the sections' bending rotary inertia rho b (I_y, I_z), 1 the
physical; the modal models and S6's benchmark beam have none, and b = 0 makes the mass matrix
singular: the study takes b = 1e-4). `flexsym run` does not combine --param with a scene file,
so this script builds and runs through the Python API (the same driver, the same CSV).

    python docs/validation/spatial_ef.py scenes/spherical_pendulum.toml --elements 16 --dt 1e-4 --out s6_ef16.csv
    python docs/validation/spatial_ef.py --richardson A.csv B.csv --order 2 --out R.csv
    python docs/validation/spatial_ef.py --compare A.csv B.csv [--peak P.csv] [--until T]

The run prints the integration CPU from the run summary. docs/validation/spatial.md, "S6 and S7
against the spatial ef", has the numbers and the commands.
"""
from __future__ import annotations

import argparse
import sys
import tomllib
from pathlib import Path

import numpy as np


def run(scene: str, n: int, dt: float, out: str, b: float, t_end: float | None, integrator: str | None) -> int:
    from flexsym.scenes.system_scene import system_from_dict
    from flexsym.toolchain.pipeline import prepare_system
    from flexsym.toolchain.run import run_built

    data = tomllib.loads(Path(scene).read_text())
    for body in data["body"]:
        if body["kind"] == "beam":
            # the section forces from the elements' strains, as the study's tables were measured
            # (a scene's ef beam takes them from equilibrium unless it says so)
            body["model"] = {"variant": "ef", "elements": n, "moment": "constitutive",
                             "axial_force": "constitutive"}
    system = system_from_dict(data, name=data["system"]["name"], base=Path(scene).parent)
    built = prepare_system(system, log=lambda m: print(m, file=sys.stderr))
    given = {"dt": dt, "params": {"bending_inertia": b},  # rows on the scene's output grid
             "out_every": max(1, round(data.get("output", {}).get("interval", dt) / dt))}
    if t_end is not None:
        given["t_end"] = t_end
    if integrator is not None:
        given["integrator"] = integrator
    r = run_built(built, out=Path(out), **given)
    s = r.summary
    print(f"{system.name} ef n = {n}, dt = {dt:g}: {r.status} ({s.get('steps')} steps, integration "
          f"CPU {s.get('cpu_median', float('nan')):.2f} s)")
    return 0 if r.ok else 1


def richardson(a: str, b: str, order: float, out: str) -> int:
    """B + (B - A) / (2^order - 1) on the common rows (A coarse, B fine), for the columns both
    have before the coordinates (t, the scene's outputs, violation: the coordinates' names
    mean other nodes at another n)."""
    cols = []
    for path in (a, b):
        with open(path) as fh:
            names = fh.readline().strip().split(",")
        cols.append(names[:names.index("violation") + 1] if "violation" in names else names)
    keep = [c for c in cols[1] if c in cols[0]]
    A = np.loadtxt(a, delimiter=",", skiprows=1, comments="#", ndmin=2)[:, [cols[0].index(c) for c in keep]]
    B = np.loadtxt(b, delimiter=",", skiprows=1, comments="#", ndmin=2)[:, [cols[1].index(c) for c in keep]]
    k = min(len(A), len(B))
    R = B[:k] + (B[:k] - A[:k]) / (2.0**order - 1)
    R[:, 0] = B[:k, 0]
    np.savetxt(out, R, delimiter=",", header=",".join(keep), comments="", fmt="%.17g")
    return 0


def _outputs(path: str) -> dict:
    """{column: array} of a flexsym CSV's time and output columns (before the coordinates)."""
    with open(path) as fh:
        names = fh.readline().strip().split(",")
    names = names[:names.index("violation")] if "violation" in names else names
    data = np.loadtxt(path, delimiter=",", skiprows=1, comments="#", ndmin=2)
    return {c: data[:, i] for i, c in enumerate(names)}


def compare(a: str, b: str, peak: str | None, until: float) -> int:
    """Per output column of both: max |A - B| over their common rows up to `until`, divided by
    the column's peak |.| in `peak` (default B) over its whole run."""
    A, B = _outputs(a), _outputs(b)
    P = _outputs(peak) if peak else B
    ka, kb = (np.round(d["t"] * 1e9).astype(np.int64) for d in (A, B))
    common, ia, ib = np.intersect1d(ka, kb, return_indices=True)
    keep = common <= until * 1e9 * (1 + 1e-12)
    ia, ib = ia[keep], ib[keep]
    cols = [c for c in B if c != "t" and c in A and c in P]
    print(f"{a} vs {b}" + (f" (until {until:g} s)" if np.isfinite(until) else "") + ": " + ", ".join(
        f"{c} {np.abs(A[c][ia] - B[c][ib]).max() / np.abs(P[c]).max():.2e}" for c in cols))
    return 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene", nargs="?", help="scene file (its beam becomes ef)")
    p.add_argument("--elements", type=int, default=16)
    p.add_argument("--dt", type=float, help="step (default: the scene's)")
    p.add_argument("--t-end", type=float)
    p.add_argument("--integrator")
    p.add_argument("--bending-inertia", type=float, default=1e-4,
                   help="factor of the sections' bending rotary inertia (default 1e-4)")
    p.add_argument("--richardson", nargs=2, metavar="CSV", help="coarse and fine run")
    p.add_argument("--order", type=float, default=2.0)
    p.add_argument("--compare", nargs=2, metavar="CSV",
                   help="A and B: max |A - B| per output column / its peak in --peak (default B)")
    p.add_argument("--peak")
    p.add_argument("--until", type=float, default=np.inf)
    p.add_argument("--out")
    a = p.parse_args(argv)
    if a.compare:
        return compare(*a.compare, a.peak, a.until)
    if a.out is None:
        p.error("--out is required")
    if a.richardson:
        return richardson(*a.richardson, a.order, a.out)
    if a.scene is None:
        p.error("a scene file, or --richardson")
    solver = tomllib.loads(Path(a.scene).read_text())["solver"]  # the scene's, unless given
    return run(a.scene, a.elements, a.dt if a.dt is not None else solver["dt"], a.out, a.bending_inertia,
               a.t_end if a.t_end is not None else solver["t_end"], a.integrator or solver["integrator"])


if __name__ == "__main__":
    sys.exit(main())
