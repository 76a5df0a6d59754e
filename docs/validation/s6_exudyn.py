"""S6 `spherical_pendulum` in Exudyn: an independent, geometrically exact reference.

The strip of scenes/spherical_pendulum.toml (L = 1 m, E 7e10, G 2.6e10, rho 2700, A 1e-4,
I_y 2.0833e-10 (weak, deflection along the section's z), I_z 3.3333e-9, J 7.021e-10) hangs by
its root from a ball joint at the origin, starts undeformed along +x turning rigidly about the
vertical at 4 rad/s, and falls under g = (0, 0, -9.81) for 2 s.

Exudyn (third party, `pip install exudyn`; not a flexsym dependency) models it with
ObjectBeamGeometricallyExact: two-node Simo-Reissner elements on rigid-body nodes with Euler
parameters (NodeRigidBodyEP), strains constant per element (the SE(3) logarithm of the two
nodes' relative motion), the consistent mass of linear shape functions (in Exudyn 1.13.6:
rho A h/6 [[2, 1], [1, 2]] per direction, the section inertia likewise on the nodes' angular
velocities). Gravity is rho A g h/2 on each element end (the consistent load). The ball joint
holds the root node's position only. Every node starts with the rigid rotation's velocity
(0, 4x, 0) and angular velocity (0, 0, 4), and with the consistent accelerations in closed form
(unstrained at t = 0: free fall but at the root). The integrator is Exudyn's implicit
generalized-alpha (index 3, fixed step, Newton down to the residual's round-off floor).

Section data: EA, GA (the physical shear stiffness, both directions), GJ, EI_y, EI_z; torsional
mass rho (I_y + I_z) per length; the bending rotary inertias rho I_y, rho I_z are zero by
default (the benchmark's beam leaves them out; `--rotary F` sets them to F times the physical).

Outputs (ground components, the scene's columns): the tip node's position, w_mid = the distance
of the middle node from the chord root-tip (n even), and the section moments at mid-span in the
deformed section's axes, M = diag(GJ, EI_y, EI_z) kappa with kappa = log(R_a^T R_b)/h each
element's curvature (Exudyn's own strain measure), averaged over the two elements next to the
middle node (linear between their midpoints): T_mid (torsion), M_y_mid, M_z_mid. The signs are
flexsym's (docs/theory/spatial.md, Outputs): Mx = GJ phi_x, My = -EI_y vz_xx, Mz = EI_z v_xx to
first order. With --energy the CSV gets T, V (gravity and strain), Hz (the angular momentum
about the vertical through the joint) of the discrete model, and the sections' roll R_zy (the
ground z component of the section's y axis) at mid-span and tip.

    python docs/validation/s6_exudyn.py --elements 16 --dt 1e-4 --out s6_exu16.csv
    python docs/validation/s6_exudyn.py --rigid-rod --out rod.csv       # the rigid limit
    python docs/validation/s6_exudyn.py --compare A.csv B.csv [--peak P.csv] [--until T]

--compare prints, per scene column in both files (this script's or `flexsym run`'s CSVs), the
largest |A - B| over their common output times (up to T) divided by the column's peak |.| in
P (default B). docs/validation/spatial.md, "S6 against a third-party geometrically exact beam
(Exudyn)", has the study's numbers and commands.
"""
from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import time

import numpy as np

# S6's data (scenes/spherical_pendulum.toml)
L, RHO, E, G = 1.0, 2700.0, 7.0e10, 2.6e10
A, IY, IZ, J = 1.0e-4, 2.0833e-10, 3.3333e-9, 7.021e-10
GRAV = np.array([0.0, 0.0, -9.81])
OMEGA0 = 4.0
COLUMNS = ["x_tip", "y_tip", "z_tip", "w_mid", "M_y_mid", "M_z_mid", "T_mid"]
EXTRA = ["T", "V", "Hz", "R_zy_mid", "R_zy_tip"]


def ep_matrix(e):
    """Rotation matrices (..., 3, 3) of Euler parameters e (..., 4), normalised first."""
    e = e / np.linalg.norm(e, axis=-1, keepdims=True)
    e0, v = e[..., 0], e[..., 1:]
    I = np.eye(3)
    skew = np.zeros(e.shape[:-1] + (3, 3))
    skew[..., 0, 1], skew[..., 0, 2], skew[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    skew = skew - np.swapaxes(skew, -1, -2)
    return ((e0**2 - (v * v).sum(-1))[..., None, None] * I + 2 * v[..., :, None] * v[..., None, :]
            + 2 * e0[..., None, None] * skew)


def log_so3(R):
    """Rotation vectors (..., 3) of rotation matrices (..., 3, 3) (angles below pi)."""
    c = np.clip((np.trace(R, axis1=-2, axis2=-1) - 1) / 2, -1, 1)
    th = np.arccos(c)
    w = np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]], -1)
    f = np.where(th < 1e-6, 0.5 + th**2 / 12, th / (2 * np.sin(np.where(th < 1e-6, 1.0, th))))
    return f[..., None] * w


def simulate(n: int, dt: float, t_end: float = 2.0, interval: float = 1e-3, rho_inf: float = 0.9,
             rotary: float = 0.0, shear: float = 1.0, tol: float = 1e-10, energy: bool = False,
             exudyn_accelerations: bool = False, stiffen: float = 1.0, verbose: bool = False) -> dict:
    """Run S6 in Exudyn; returns {'t': ..., column: ...} on the output grid and 'cpu' [s]."""
    import exudyn as exu
    from exudyn.itemInterface import (LoadForceVector, MarkerNodePosition, NodePointGround, NodeRigidBodyEP,
                                      ObjectBeamGeometricallyExact, ObjectJointSpherical)
    from exudyn.utilities import LoadSolutionFile

    if n % 2:
        raise SystemExit("s6_exudyn: the number of elements must be even (a node at mid-span)")
    h = L / n
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    section = exu.BeamSection()
    stiff = stiffen * np.array([E * A, shear * G * A, shear * G * A, G * J, E * IY, E * IZ])
    section.stiffnessMatrix = np.diag(stiff)
    section.inertia = np.diag([RHO * (IY + IZ), rotary * RHO * IY, rotary * RHO * IZ])
    section.massPerLength = RHO * A
    x = h * np.arange(n + 1)
    nodes = []
    for xi in x:
        # rigid rotation about the vertical: v = omega x r, e' = G^T omega / 2 = (0, omega/2) at e = (1, 0, 0, 0)
        nodes.append(mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=[xi, 0, 0, 1, 0, 0, 0],
                                                 initialVelocities=[0, OMEGA0 * xi, 0, 0, 0, 0, 0.5 * OMEGA0])))
    for i in range(n):
        mbs.AddObject(ObjectBeamGeometricallyExact(nodeNumbers=[nodes[i], nodes[i + 1]], length=h,
                                                   sectionData=section))
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    mbs.AddObject(ObjectJointSpherical(markerNumbers=[mbs.AddMarker(MarkerNodePosition(nodeNumber=ground)),
                                                      mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[0]))]))
    mass = np.full(n + 1, RHO * A * h)
    mass[[0, -1]] /= 2
    for node, m in zip(nodes, mass):
        mbs.AddLoad(LoadForceVector(markerNumber=mbs.AddMarker(MarkerNodePosition(nodeNumber=node)),
                                    loadVector=list(m * GRAV)))
    mbs.Assemble()
    if not exudyn_accelerations:
        # the consistent initial accelerations, in closed form: at t = 0 the strip is unstrained
        # (no tension yet, no bending), so every node but the root (held by the joint) falls
        # freely, a = g, and turns without angular acceleration: e'' = -|e'|^2 e = -(Omega/2)^2 e
        # (the Euler parameters' constraint e.e = 1 twice differentiated)
        acc = np.zeros(mbs.systemData.ODE2Size())
        for i, (node, xi) in enumerate(zip(nodes, x)):
            ltg = mbs.systemData.GetNodeLTGODE2(node)
            a = np.zeros(7)
            if i > 0:
                a[:3] = GRAV
            a[3] = -(OMEGA0 / 2) ** 2
            acc[ltg] = a
        for config in (exu.ConfigurationType.Initial, exu.ConfigurationType.Current):
            mbs.systemData.SetODE2Coordinates_tt(list(acc), configuration=config)

    steps = int(round(t_end / dt))
    every = int(round(interval / dt))
    if abs(steps * dt - t_end) > 1e-9 * t_end or abs(every * dt - interval) > 1e-9 * interval:
        raise SystemExit("s6_exudyn: dt must divide t_end and the output interval")
    folder = tempfile.mkdtemp(prefix="s6_exudyn_")
    solfile = os.path.join(folder, "coordinates.sol")
    s = exu.SimulationSettings()
    s.timeIntegration.numberOfSteps = steps
    s.timeIntegration.endTime = t_end
    s.timeIntegration.verboseMode = 1 if verbose else 0
    s.timeIntegration.adaptiveStep = False
    s.timeIntegration.generalizedAlpha.spectralRadius = rho_inf
    s.timeIntegration.generalizedAlpha.computeInitialAccelerations = exudyn_accelerations
    s.timeIntegration.newton.relativeTolerance = tol
    # the residual (forces, N) stagnates at a few eps * EA/h (round-off in the axial stiffness)
    s.timeIntegration.newton.absoluteTolerance = 10 * np.finfo(float).eps * max(stiff[:3]) / h
    s.timeIntegration.newton.useModifiedNewton = True
    s.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    s.solution.file.write = True
    s.solution.file.binary = True
    s.solution.file.name = solfile
    s.solution.file.writePeriod = interval
    s.solution.file.export.velocities = True
    s.solution.file.export.accelerations = False
    s.solution.file.export.algebraicCoordinates = False
    s.solution.file.export.dataCoordinates = False
    s.solution.file.writeInitialValues = True
    s.solution.sensors.active = False
    s.solution.solverInformationFileName = os.path.join(folder, "solverInformation.txt")
    s.show.statistics = verbose
    s.show.computationTime = verbose
    try:
        cpu = time.process_time()
        try:
            ok = exu.SolveDynamic(mbs, s)
        except exu.SolverError:
            ok = False
        cpu = time.process_time() - cpu
        if not ok:
            raise SystemExit(f"s6_exudyn: Exudyn's solver failed (n = {n}, dt = {dt})")
        sol = LoadSolutionFile(solfile, safeMode=True, verbose=False)
    finally:
        shutil.rmtree(folder, ignore_errors=True)

    t = sol["data"][:, 0]
    nc = 7 * (n + 1)
    q = sol["data"][:, 1:1 + nc].reshape(len(t), n + 1, 7)
    qd = sol["data"][:, 1 + nc:1 + 2 * nc].reshape(len(t), n + 1, 7)
    ref = np.zeros((n + 1, 7))
    ref[:, 0], ref[:, 3] = x, 1.0
    q = q + ref
    pos, ep = q[..., :3], q[..., 3:]
    R = ep_matrix(ep)
    out = {"t": t, "cpu": cpu, "steps": steps}
    tip, mid, root = pos[:, -1], pos[:, n // 2], pos[:, 0]
    out["x_tip"], out["y_tip"], out["z_tip"] = tip.T
    chord = tip - root
    out["w_mid"] = (np.linalg.norm(np.cross(mid - root, chord), axis=1) / np.linalg.norm(chord, axis=1))
    # curvature of each element in its own (deformed) section axes: log(R_a^T R_b)/h
    kappa = log_so3(np.einsum("tnji,tnjk->tnik", R[:, :-1], R[:, 1:])) / h
    moment = kappa * stiff[3:]
    m_mid = 0.5 * (moment[:, n // 2 - 1] + moment[:, n // 2])
    out["T_mid"], out["M_y_mid"], out["M_z_mid"] = m_mid.T
    out["violation"] = np.abs(np.linalg.norm(ep, axis=-1) - 1).max()
    out["root_drift"] = np.abs(root).max()
    if energy:
        vel = qd[..., :3]
        ep_t = qd[..., 3:]
        e0, ev = ep[..., :1], ep[..., 1:]
        # angular velocity in the node's axes: omega_local = 2 (e0 e'_v - e'_0 e_v - e_v x e'_v)
        omega_loc = 2 * (e0 * ep_t[..., 1:] - ep_t[..., :1] * ev - np.cross(ev, ep_t[..., 1:]))
        Jsec = np.array([RHO * (IY + IZ), rotary * RHO * IY, rotary * RHO * IZ])
        # Exudyn 1.13.6's element mass is the consistent one of its linear shape functions
        # (rho A h/6 [[2, 1], [1, 2]] per direction, likewise J h/6 on the angular velocities;
        # read from ComputeLinearizedSystem), so the discrete T and H are sums over elements
        va, vb = vel[:, :-1], vel[:, 1:]
        wa, wb = omega_loc[:, :-1], omega_loc[:, 1:]
        T = (RHO * A * h / 6) * ((va * va).sum(-1) + (va * vb).sum(-1) + (vb * vb).sum(-1)).sum(-1) \
            + (h / 6) * (Jsec * (wa * wa + wa * wb + wb * wb)).sum((-1, -2))
        Vg = -(mass * (pos @ GRAV)).sum(-1)
        # strain energy: Exudyn's element strains, SE(3) log of the relative motion
        Ve = 0.5 * h * (stiff[3:] * kappa**2).sum((-1, -2))
        Ve = Ve + 0.5 * h * _translational_strain_energy(pos, R, kappa, h, stiff[:3])
        xa, xb = pos[:, :-1], pos[:, 1:]
        Hz = (RHO * A * h / 6) * (np.cross(xa, 2 * va + vb) + np.cross(xb, va + 2 * vb))[..., 2].sum(-1)
        Hz = Hz + (h / 6) * (np.einsum("tni,tni->tn", R[:, :-1, 2, :], Jsec * (2 * wa + wb))
                             + np.einsum("tni,tni->tn", R[:, 1:, 2, :], Jsec * (wa + 2 * wb))).sum(-1)
        out["T"], out["V"], out["Hz"] = T, Vg + Ve, Hz
        # the roll of the sections: the ground z component of the section's y axis
        out["R_zy_mid"], out["R_zy_tip"] = R[:, n // 2, 2, 1], R[:, -1, 2, 1]
    return out


def _translational_strain_energy(pos, R, kappa, h, k):
    """Sum over elements of Gamma^T diag(EA, GA, GA) Gamma, Gamma = the SE(3) log's translational part / h - e1."""
    # SE(3) log: d = R_a^T (x_b - x_a); translational part of log = V(theta)^-1 d with theta = h kappa
    d = np.einsum("tnji,tnj->tni", R[:, :-1], pos[:, 1:] - pos[:, :-1])
    th = h * kappa
    a = np.linalg.norm(th, axis=-1, keepdims=True)
    safe = np.where(a < 1e-2, 1.0, a)
    # V^-1 = I - 1/2 [th]x + (1/a^2)(1 - a sin a / (2 (1 - cos a))) [th]x^2 (a series below 1e-2)
    c = np.where(a < 1e-2, 1.0 / 12 + a**2 / 720, (1 - safe * np.sin(safe) / (2 * (1 - np.cos(safe)))) / safe**2)
    thxd = np.cross(th, d)
    u = d - 0.5 * thxd + c * np.cross(th, thxd)
    gamma = u / h - np.array([1.0, 0, 0])
    return (k * gamma**2).sum((-1, -2))


def write_csv(path: str, out: dict, energy: bool = False) -> None:
    cols = COLUMNS + (EXTRA if energy else [])
    data = np.column_stack([out["t"]] + [out[c] for c in cols])
    np.savetxt(path, data, delimiter=",", header=",".join(["t"] + cols), comments="", fmt="%.12e")


def rigid_rod(t_end: float = 2.0, interval: float = 1e-3) -> dict:
    """The rigid limit: a uniform rod on a ball joint, n'' = (3/2L)(g - (g.n) n) - |n'|^2 n from
    n = (1, 0, 0), n' = (0, Omega0, 0) (scipy, tolerances 1e-12); its tip L n on the output grid."""
    from scipy.integrate import solve_ivp

    def rod(_, y):
        n, nd = y[:3], y[3:]
        return np.concatenate([nd, 1.5 / L * (GRAV - GRAV.dot(n) * n) - nd.dot(nd) * n])

    t = interval * np.arange(int(round(t_end / interval)) + 1)
    sol = solve_ivp(rod, (0, t_end), [1, 0, 0, 0, OMEGA0, 0], t_eval=t, rtol=1e-12, atol=1e-12)
    return {"t": t, "x_tip": L * sol.y[0], "y_tip": L * sol.y[1], "z_tip": L * sol.y[2]}


def read_csv(path: str) -> dict:
    """A CSV of this script or of `flexsym run` (its '#' lines skipped): {column: array}."""
    with open(path, encoding="utf-8") as fh:
        names = fh.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1, comments="#", ndmin=2)
    return {c: data[:, i] for i, c in enumerate(names)}


def compare(a: dict, b: dict, peak: dict | None = None, until: float = np.inf) -> dict:
    """Per S6 column present in both: (max |a - b| over the common output times up to `until`,
    divided by the peak |.| of that column in `peak` (default b), and the time of the max)."""
    ka, kb = (np.round(np.asarray(d["t"]) * 1e9).astype(np.int64) for d in (a, b))
    common, ia, ib = np.intersect1d(ka, kb, return_indices=True)
    keep = common <= until * 1e9 * (1 + 1e-12)
    ia, ib, common = ia[keep], ib[keep], common[keep]
    peak = b if peak is None else peak
    out = {}
    for c in COLUMNS:
        if c in a and c in b:
            d = np.abs(a[c][ia] - b[c][ib])
            out[c] = (d.max() / np.abs(peak[c]).max(), common[d.argmax()] / 1e9)
    return out


def main(argv=None) -> int:
    if argv is None:
        argv = sys.argv[1:]
    if argv[:1] == ["--compare"]:
        q = argparse.ArgumentParser(prog="s6_exudyn.py --compare",
                                    description="largest |A - B| over the run per column, relative to its peak")
        q.add_argument("files", nargs=2, metavar="CSV", help="A and B (this script's or flexsym run's)")
        q.add_argument("--peak", help="the CSV whose column peaks normalise (default B)")
        q.add_argument("--until", type=float, default=np.inf, help="compare up to this time [s]")
        c = q.parse_args(argv[1:])
        a, b = (read_csv(f) for f in c.files)
        res = compare(a, b, read_csv(c.peak) if c.peak else None, c.until)
        print(f"{c.files[0]} vs {c.files[1]}: " + ", ".join(f"{k} {v:.2e}" for k, (v, _) in res.items()))
        return 0
    p = argparse.ArgumentParser(description="S6 spherical_pendulum in Exudyn (geometrically exact beam); "
                                "--compare A.csv B.csv [--peak P.csv] [--until T] compares two runs")
    p.add_argument("--elements", type=int, default=16, help="number of elements (even; default 16)")
    p.add_argument("--dt", type=float, default=1e-4, help="time step [s] (default 1e-4)")
    p.add_argument("--t-end", type=float, default=2.0, help="end time [s] (default 2)")
    p.add_argument("--interval", type=float, default=1e-3, help="output interval [s] (default 1e-3)")
    p.add_argument("--rho-inf", type=float, default=0.9, help="generalized-alpha spectral radius (default 0.9)")
    p.add_argument("--rotary", type=float, default=0.0,
                   help="bending rotary inertias as a multiple of the physical rho I_y, rho I_z (default 0)")
    p.add_argument("--shear", type=float, default=1.0, help="shear stiffness as a multiple of G A (default 1)")
    p.add_argument("--stiffen", type=float, default=1.0,
                   help="multiply E and G by this (the rigid limit; default 1)")
    p.add_argument("--tol", type=float, default=1e-10, help="Newton's relative tolerance (default 1e-10)")
    p.add_argument("--exudyn-accelerations", action="store_true",
                   help="let Exudyn compute the initial accelerations (needs --rotary > 0; default: the closed form)")
    p.add_argument("--energy", action="store_true", help="add the columns T, V, Hz, R_zy_mid, R_zy_tip")
    p.add_argument("--verbose", action="store_true")
    p.add_argument("--out", required=True, help="CSV file")
    p.add_argument("--rigid-rod", action="store_true",
                   help="write the rigid limit instead (a uniform rod on a ball joint; tip columns only)")
    a = p.parse_args(argv)
    if a.rigid_rod:
        rod = rigid_rod(a.t_end, a.interval)
        cols = ["t", "x_tip", "y_tip", "z_tip"]
        np.savetxt(a.out, np.column_stack([rod[c] for c in cols]), delimiter=",", header=",".join(cols),
                   comments="", fmt="%.15e")
        print(f"s6_exudyn: the rigid rod on a ball joint -> {a.out}")
        return 0
    try:
        import exudyn  # noqa: F401
    except ImportError:
        print("s6_exudyn: needs Exudyn (pip install exudyn)", file=sys.stderr)
        return 2
    out = simulate(a.elements, a.dt, a.t_end, a.interval, a.rho_inf, a.rotary, a.shear, a.tol, a.energy,
                   a.exudyn_accelerations, a.stiffen, a.verbose)
    write_csv(a.out, out, a.energy)
    print(f"s6_exudyn: n = {a.elements}, dt = {a.dt:g} s, {out['steps']} steps, CPU {out['cpu']:.2f} s, "
          f"|e| - 1 within {out['violation']:.1e}, root within {out['root_drift']:.1e} m -> {a.out}")
    if a.energy:
        e = out["T"] + out["V"]
        print(f"s6_exudyn: T + V within {np.abs(e - e[0]).max() / e[0]:.1e} of its start ({e[0]:.6g} J), "
              f"Hz within {np.abs(out['Hz'] - out['Hz'][0]).max() / out['Hz'][0]:.1e} of its start "
              f"({out['Hz'][0]:.6g} kg m^2/s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
