"""The plot of a system run: every output against time, and the mechanism at a few instants
with each beam's deflection from its chord (root to tip) scaled and labelled as such.

A spatial system is drawn in a 3D view (equal scales on the three axes).
The picture is drawn from output columns only: `with_plot_outputs` adds the ground positions
x(B.m), y(B.m) (and z(B.m) in 3D) of every marker of every body and of STATIONS evenly spaced
stations along each beam (markers plot1, plot2, ...) as extra columns (px_..., py_..., pz_...),
so it needs nothing from the derivation beyond what the run writes.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from flexsym.model.system import Marker, Output, System, output_unit

STATIONS = 11  # points along a beam, root and tip included


def _columns(body: str, marker: str, index: int, dimension: int = 2) -> tuple[str, ...]:
    name = f"{body}_{marker}"
    name = name if len(name) <= 45 else f"m{index}"
    return tuple(f"p{c}_{name}" for c in "xyz"[:dimension])


def with_plot_outputs(system: System) -> tuple[System, dict]:
    """(the system with the picture's stations and columns added, {body: [(x column, y column)]})
    in order along each body (a beam from root to tip)."""
    bodies, outputs, geometry, index = [], list(system.outputs), {}, 0
    taken = {o.column for o in system.outputs}
    for b in system.bodies:
        if b.flexible:
            names = {m.name for m in b.all_markers}
            extra = tuple(Marker(f"plot{k}", b.length * k / (STATIONS - 1)) for k in range(1, STATIONS - 1)
                          if f"plot{k}" not in names)
            b = replace(b, markers=b.markers + extra)
            refs = ["root"] + [f"plot{k}" for k in range(1, STATIONS - 1)] + ["tip"]
        else:
            refs = [m.name for m in b.all_markers]
        bodies.append(b)
        pairs = []
        for ref in refs:
            index += 1
            cols = _columns(b.name, ref, index, system.dimension)
            if cols[0] not in taken:
                outputs += [Output(c, f"{a}({b.name}.{ref})") for c, a in zip(cols, "xyz")]
                taken |= set(cols)
            pairs.append(cols)
        geometry[b.name] = pairs
    return replace(system, bodies=tuple(bodies), outputs=tuple(outputs)), geometry


def exaggerate(points: np.ndarray, factor: float) -> np.ndarray:
    """Points along a beam (n x 2, root first, tip last) with their distance from the chord
    root-tip multiplied by factor (the position along the chord kept)."""
    a, b = points[0], points[-1]
    chord = b - a
    length = math.hypot(*chord)
    if length == 0:
        return points.copy()
    e = chord / length
    rel = points - a
    along = rel @ e
    foot = a + np.outer(along, e)
    return foot + factor * (points - foot)


def chord_distance(points: np.ndarray) -> np.ndarray:
    """Signed distance of each point from the chord root-tip, positive to the left of root ->
    tip (the output w(B, x)); in 3D (n x 3 points) the distance, unsigned."""
    if points.shape[1] == 3:
        return np.linalg.norm(points - exaggerate(points, 0.0), axis=1)
    a, b = points[0], points[-1]
    e = (b - a) / max(math.hypot(*(b - a)), 1e-300)
    rel = points - a
    return e[0] * rel[:, 1] - e[1] * rel[:, 0]


def plot_system(system: System, geometry: dict, columns: dict, path, instants: int = 4,
                title: str | None = None) -> float:
    """Write the figure; returns the deflection scale factor used. columns: name -> array
    (with 't'); geometry as given by with_plot_outputs."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.asarray(columns["t"], dtype=float)
    shown = [o for o in system.outputs if not o.column.startswith(("px_", "py_", "pz_"))]
    picks = np.unique(np.round(np.linspace(0, len(t) - 1, instants)).astype(int))
    dim = system.dimension
    pts = {b: np.stack([np.column_stack([columns[c] for c in cols]) for cols in pairs], axis=1)
           for b, pairs in geometry.items()}  # body -> (rows, points, dimension)
    every = np.concatenate([p[picks].reshape(-1, dim) for p in pts.values()])
    size = float(np.max(np.ptp(every, axis=0))) or 1.0
    flex = [b.name for b in system.bodies if b.flexible]
    wmax = max((float(np.max(np.abs(chord_distance(pts[b][k])))) for b in flex for k in picks), default=0.0)
    factor = 1.0 if wmax == 0 else max(1.0, 10 ** math.floor(math.log10(0.08 * size / wmax)))

    fig = plt.figure(figsize=(12, max(4.0, 2.2 * len(shown))))
    grid = fig.add_gridspec(max(1, len(shown)), 2)
    for k, o in enumerate(shown):
        ax = fig.add_subplot(grid[k, 0])
        ax.plot(t, columns[o.column], lw=1)
        ax.set_ylabel(f"{o.column} [{output_unit(system, o.quantity)}]")
        ax.set_title(o.quantity, fontsize=8, loc="right")
        ax.grid(alpha=0.3)
        if k == len(shown) - 1:
            ax.set_xlabel("t [s]")
    ax = fig.add_subplot(grid[:, 1], **({"projection": "3d"} if dim == 3 else {}))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for n, k in enumerate(picks):
        c = colours[n % len(colours)]
        for b in system.bodies:
            p = pts[b.name][k]
            if b.flexible:
                ax.plot(*exaggerate(p, factor).T, "-", color=c, lw=2)
            elif len(p) > 1:
                ax.plot(*p.T, "-o", color=c, lw=3, ms=3)
            else:
                ax.plot(*p.T, "s", color=c, ms=6)
        ax.plot([], [], color=c, label=f"t = {t[k]:.4g} s")
    for j in system.joints:
        if j.parent == "ground":
            ax.plot(*([c] for c in j.point), "k^", ms=8)
    if dim == 3:  # equal scales: a cube around the drawn points (set_aspect("equal") in 3D)
        centre, half = (every.max(0) + every.min(0)) / 2, max(size, 1e-9) / 2
        for k, setter in enumerate((ax.set_xlim, ax.set_ylim, ax.set_zlim)):
            setter(centre[k] - half, centre[k] + half)
        ax.set_box_aspect((1, 1, 1))
        ax.set_zlabel("z [m]")
    else:
        ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    view = "mechanism"
    ax.set_title(f"{view}; beam deflection from its chord scaled x{factor:g}" if flex
                 else view, fontsize=9)
    fig.suptitle(title or system.name)
    fig.tight_layout()
    from flexsym.core.files import atomic_write

    try:
        with atomic_write(path, "wb") as fh:  # complete or absent, an earlier plot kept until then
            fig.savefig(fh, dpi=110, format=Path(path).suffix.lstrip(".").lower() or "png")
    finally:
        plt.close(fig)
    return factor
