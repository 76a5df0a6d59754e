"""The spatial geometrically exact beam element (flexsym/physics/rod3d.py) against independent
results: Euler-Bernoulli / Timoshenko statics, the constant-curvature roll-up under an end
moment, a continuum (shooting) solution of the Cosserat rod under a 3D tip load, objectivity,
Euler-Bernoulli and St Venant frequencies, Southwell's rotating-beam coefficient, energy
conservation. The measured numbers are quoted in docs/theory/ef-3d.md."""
from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import eig, eigh
from scipy.optimize import brentq, fsolve
from scipy.spatial.transform import Rotation

from flexsym.physics.rod3d import (ClampedBeam, Section, angular_velocity, element_functions, qmatrix,
                                   quaternion)

# steel, rectangular 20 mm (along y) x 10 mm (along z): I_z = 4 I_y, J by St Venant's series
B, H = 0.02, 0.01
STEEL = Section(E=2.1e11, G=8.1e10, rho=7850.0, A=B * H, Iy=B * H**3 / 12, Iz=H * B**3 / 12,
                J=0.2287 * B * H**3)
SEC = STEEL.vector
L = 1.0


@lru_cache(maxsize=None)
def model(n: int, length: float = L):
    """casadi Functions of one clamped-free beam: energies and their derivatives."""
    beam = ClampedBeam(n, length)
    q, qd = ca.SX.sym("q", 6 * n), ca.SX.sym("qd", 6 * n)
    om, V, g, sec = (ca.SX.sym(s, k) for s, k in (("om", 3), ("V", 3), ("g", 3), ("sec", 7)))
    T, Ve, Vg = beam.energies(q, qd, om, V, g, sec)
    T0 = ca.substitute(T, qd, ca.DM.zeros(6 * n))  # the frame-motion part at rest in the frame
    gyro = ca.substitute(ca.gradient(T, qd), qd, ca.DM.zeros(6 * n))
    f = {
        "Ve": ca.Function("Ve", [q, sec], [Ve]),
        "T": ca.Function("T", [q, qd, om, V, sec], [T]),
        "K": ca.Function("K", [q, sec], [ca.hessian(Ve, q)[0]]),
        "M": ca.Function("M", [q, om, V, sec], [ca.hessian(T, qd)[0]]),
        # the potential of the steady motion: Ve - T0 (centrifugal), its gradient and Hessian
        "grad_eff": ca.Function("ge", [q, om, V, sec], [ca.gradient(Ve - T0, q)]),
        "K_eff": ca.Function("Ke", [q, om, V, sec], [ca.hessian(Ve - T0, q)[0]]),
        "J_gyro": ca.Function("Jg", [q, om, V, sec], [ca.jacobian(gyro, q)]),
    }
    return beam, f


def tip_loaded(n, length=L, force=(0, 0, 0), moment_z=0.0, arm=(0, 0, 0)):
    """Newton function (gradient, Hessian of the total potential) for dead tip loads: a force
    at a point of the tip section at `arm` (section frame) and a moment about the fixed z axis
    (its potential -M psi_z is exact for rotations about z, used for the planar roll-up)."""
    beam, f = model(n, length)
    q, lam, sec = ca.SX.sym("q", 6 * n), ca.SX.sym("lam"), ca.SX.sym("sec", 7)
    tip = q[6 * n - 6:]
    point = tip[0:3] + qmatrix(quaternion(tip[3:6])) @ ca.DM(arm)
    Pi = f["Ve"](q, sec) - lam * (ca.dot(ca.DM(force), point) + moment_z * tip[5])
    return beam, ca.Function("g", [q, lam, sec], [ca.gradient(Pi, q)]), \
        ca.Function("H", [q, lam, sec], [ca.hessian(Pi, q)[0]])


def newton(grad, hess, q, lam, sec=SEC, tol=1e-10, iters=50, max_step=0.1):
    """Newton on the total potential, each increment limited to max_step (m or rad)."""
    for _ in range(iters):
        r = np.array(grad(q, lam, sec)).ravel()
        dq = np.linalg.solve(np.array(hess(q, lam, sec)), -r)
        q = q + dq * min(1.0, max_step / np.abs(dq).max())
        if np.abs(dq).max() < tol:
            return q
    raise AssertionError(f"Newton did not converge: |dq| = {np.abs(dq).max():.2e}")


def solve_path(grad, hess, q0, steps):
    """Load stepping lam = 0 .. 1 with a secant predictor."""
    q, prev = q0.copy(), q0.copy()
    for lam in np.linspace(0, 1, steps + 1)[1:]:
        q, prev = newton(grad, hess, 2 * q - prev, lam), q
    return q


def rates(errors):
    return [np.log2(a / b) for a, b in zip(errors, errors[1:])]


# --- 1. small-deflection statics ---

def linear_tip(n, node_coord, load):
    """Tip displacement along node_coord under a tip load on it, K at the undeformed state."""
    beam, f = model(n)
    K = np.array(f["K"](beam.q0, SEC))
    rhs = np.zeros(6 * n)
    i = beam.index(n, node_coord)
    rhs[i] = load
    return np.linalg.solve(K, rhs)[i]


def test_small_deflection_statics_converge_to_beam_theory():
    s, P = STEEL, 1.0
    # Euler-Bernoulli, and the rod's own continuum (Timoshenko with the true G A: + P L/(G A))
    eb = {"ry": P * L**3 / (3 * s.E * s.Iz), "rz": P * L**3 / (3 * s.E * s.Iy)}
    shear = P * L / (s.G * s.A)
    for c in ("ry", "rz"):
        err = [(linear_tip(n, c, P) - (eb[c] + shear)) / eb[c] for n in (2, 4, 8, 16)]
        # linear elements with one-point strains: too stiff by exactly 1/(4 n^2) of the
        # bending part (the closed form of this element), O(h^2)
        assert np.allclose(err, [-1 / (4 * n**2) for n in (2, 4, 8, 16)], rtol=1e-6), err
        assert np.allclose(rates(err), 2.0, atol=1e-6)
        # the deviation from Euler-Bernoulli is the shear term, 3 (E/G) (r_g / L)^2 relative
        dev = linear_tip(64, c, P) / eb[c] - 1
        I = s.Iz if c == "ry" else s.Iy
        assert abs(dev - (3 * s.E * I / (s.G * s.A * L**2) - 1 / (4 * 64**2))) < 1e-9
        assert abs(dev) < 3e-4
    # torque and axial load: constant strain, exact with one element
    for n in (1, 4):
        assert linear_tip(n, "px", 1.0) == pytest.approx(L / (s.G * s.J), rel=1e-10)
        assert linear_tip(n, "rx", 1.0) == pytest.approx(L / (s.E * s.A), rel=1e-10)


# --- 2. large deflection ---

def test_end_moment_rolls_the_beam_into_a_half_circle():
    """M = pi E I_z / L: constant curvature pi / L, tip at (0, 2 L / pi), rotated by pi (a
    rotation vector of length pi, inside the parametrisation's regular range |psi| < 2 pi)."""
    M = np.pi * STEEL.E * STEEL.Iz / L
    err = []
    for n in (8, 16, 32):
        beam, g, h = tip_loaded(n, moment_z=M)
        q = solve_path(g, h, beam.q0, 8)
        tip = q[6 * n - 6:]
        assert tip[5] == pytest.approx(np.pi, abs=1e-9)  # moment equilibrium: exact rotation
        assert np.abs(tip[[2, 3, 4]]).max() < 1e-12  # stays planar
        err.append(np.linalg.norm(tip[:3] - [0, 2 * L / np.pi, 0]) / L)
        # every node on the circle of radius L / pi (to the chord's O(h^2))
        r = q.reshape(n, 6)[:, :3] - [0, L / np.pi, 0]
        assert np.abs(np.linalg.norm(r, axis=1) - L / np.pi).max() < 2 * err[-1] + 1e-5
    assert err[-1] < 5e-4
    assert min(rates(err)) > 1.9


def test_end_moment_2pi_closes_the_circle():
    """M = 2 pi E I_z / L: a full circle, the tip back at the root and turned by 2 pi. The tip
    node's rotation vector reaches |psi| = 2 pi, the exponential map's singular point (its
    out-of-plane derivatives vanish there); the bent element's stress keeps the Hessian regular
    (condition ~1e8 here), so Newton still converges. The discrete circle (a regular polygon,
    chords of length le: N = 0) closes exactly; its radius L / (2 pi) is met to O(h^2)."""
    n = 16
    beam, g, h = tip_loaded(n, moment_z=2 * np.pi * STEEL.E * STEEL.Iz / L)
    q = solve_path(g, h, beam.q0, 16)
    tip = q[6 * n - 6:]
    assert tip[5] == pytest.approx(2 * np.pi, abs=1e-9)
    assert np.linalg.norm(tip[:3]) < 1e-12 * L
    # a regular polygon of n chords of length le (Gamma = 0), circumradius R about (0, R)
    R = beam.le / (2 * np.sin(np.pi / n))
    r = np.vstack([[0, 0, 0], q.reshape(n, 6)[:, :3]]) - [0, R, 0]
    assert np.allclose(np.linalg.norm(r, axis=1), R, rtol=1e-9, atol=0)
    assert R / (L / (2 * np.pi)) - 1 == pytest.approx((np.pi / n)**2 / 6, rel=0.01)


def cosserat_shooting(force, arm, length=L, s=STEEL, guess=None):
    """The continuum Simo-Reissner (Cosserat) rod under a dead tip force at `arm` of the tip
    section, by shooting on the root moment: n = F, m(x) = m0 - r(x) x F, r' = Lambda (Gamma +
    e1), Lambda' = Lambda K~, Gamma = C_G^-1 Lambda^T n, K = C_K^-1 Lambda^T m; the tip needs
    m(L) = (Lambda(L) arm) x F. Returns (r(L), Lambda(L))."""
    F, d = np.asarray(force, float), np.asarray(arm, float)
    cG = np.array([s.E * s.A, s.G * s.A, s.G * s.A])
    cK = np.array([s.G * s.J, s.E * s.Iy, s.E * s.Iz])

    def ode(x, y, m0):
        r, Lam = y[:3], y[3:].reshape(3, 3)
        m = m0 - np.cross(r, F)
        Gam, K = Lam.T @ F / cG, Lam.T @ m / cK
        dL = Lam @ np.array([[0, -K[2], K[1]], [K[2], 0, -K[0]], [-K[1], K[0], 0]])
        return np.concatenate([Lam @ (Gam + [1, 0, 0]), dL.ravel()])

    def tip(m0):
        sol = solve_ivp(ode, (0, length), np.concatenate([np.zeros(3), np.eye(3).ravel()]),
                        args=(m0,), method="DOP853", rtol=1e-12, atol=1e-14)
        return sol.y[:3, -1], sol.y[3:, -1].reshape(3, 3)

    def residual(m0):
        r, Lam = tip(m0)
        return (m0 - np.cross(r + Lam @ d, F)) / np.abs(F).max()

    m0 = fsolve(residual, guess, xtol=1e-13)
    assert np.abs(residual(m0)).max() < 1e-10
    return tip(m0)


def test_3d_tip_load_with_torsion_against_the_continuum_rod():
    """Dead tip force in both bending planes at an arm (torsion): large 3D deflection
    (tip ~ (0.84, 0.40, 0.20) L, twist ~ 0.2 rad) against the shooting solution of the rod's
    own continuum equations; the elements converge to it at O(h^2)."""
    s = STEEL
    force = (0.0, 1.2 * s.E * s.Iz / L**2, 2.0 * s.E * s.Iy / L**2)
    arm = (0.0, 0.0, 0.05)
    err, out, qs = [], {}, {}
    for n in (4, 8, 16, 32):
        beam, g, h = tip_loaded(n, force=force, arm=arm)
        qs[n] = solve_path(g, h, beam.q0, 10)
        out[n] = qs[n][6 * n - 6:]
    ref_r, ref_L = cosserat_shooting(force, arm, guess=np.cross(out[32][:3], force))
    for n, tip in out.items():
        dr = np.linalg.norm(tip[:3] - ref_r) / L
        dth = np.linalg.norm((Rotation.from_matrix(ref_L).inv() * Rotation.from_rotvec(tip[3:])).as_rotvec())
        err.append(max(dr, dth))
    # a large 3D case: tip well off the axis in both planes, twisted
    assert ref_r[1] > 0.3 * L and ref_r[2] > 0.15 * L and ref_r[0] < 0.9 * L
    twist = Rotation.from_matrix(ref_L).as_rotvec()
    assert np.linalg.norm(twist) > 0.5
    assert err[-1] < 1e-3
    assert min(rates(err)) > 1.8, (err, rates(err))
    # the fine mesh (n = 32) against the coarse ones: the same O(h^2) sequence
    assert np.linalg.norm(out[16][:3] - out[32][:3]) < 4 * err[-1]
    # section forces in the deformed sections' frames: at the root (frame axes) n = F and
    # m = (r_L + Lambda_L arm) x F; at the tip Lambda_L^T F and arm x (Lambda_L^T F)
    F = np.array(force)
    root = np.concatenate([F, np.cross(ref_r + ref_L @ arm, F)])
    tipf = np.concatenate([ref_L.T @ F, np.cross(arm, ref_L.T @ F)])
    scale = np.concatenate([np.full(3, np.abs(F).max()), np.full(3, np.abs(root[3:]).max())])
    ferr = []
    for n in (16, 32):
        beam, q = model(n)[0], qs[n]
        ferr.append(max(np.abs((beam.section_forces_at(q, 0.0, SEC) - root) / scale).max(),
                        np.abs((beam.section_forces_at(q, L, SEC) - tipf) / scale).max()))
    assert abs(root[3]) > 0.3 * np.abs(root[4:]).max()  # a real torsion moment
    # O(h^2): measured 8.0e-3 (n = 16), 2.0e-3 (n = 32) of the largest force and moment
    assert ferr[-1] < 5e-3 and ferr[0] / ferr[1] > 3.5, ferr


def test_self_weight_deflection():
    """Uniform load rho A g (g along -z, frame components): tip w = -q L^4 / (8 E I_y) (+ the
    shear term q L^2 / (2 G A))."""
    s, n = STEEL, 16
    beam = ClampedBeam(n, L)
    q = ca.SX.sym("q", 6 * n)
    _, Ve, Vg = beam.energies(q, ca.DM.zeros(6 * n), ca.DM.zeros(3), ca.DM.zeros(3), ca.DM([0, 0, -9.81]), SEC)
    Pi = ca.Function("Pi", [q], [ca.gradient(Ve + Vg, q), ca.hessian(Ve + Vg, q)[0]])
    grad, hess = (np.array(x) for x in Pi(beam.q0))
    w = (beam.q0 - np.linalg.solve(hess, grad.ravel()))[beam.index(n, "rz")]
    load = s.rho * s.A * 9.81
    ref = -(load * L**4 / (8 * s.E * s.Iy) + load * L**2 / (2 * s.G * s.A))
    # the consistent load (no nodal moments) makes the tip exact here: measured 2e-11
    assert w == pytest.approx(ref, rel=1e-8)


def exudyn_tip(n, force):
    """Tip position of the same cantilever in Exudyn (ObjectBeamGeometricallyExact: SE(3)
    interpolation on Euler-parameter nodes), a cross-check only."""
    exu = pytest.importorskip("exudyn")
    from exudyn.itemInterface import (GenericJoint, LoadForceVector, MarkerNodePosition, MarkerNodeRigid,
                                      NodePointGround, NodeRigidBodyEP, ObjectBeamGeometricallyExact)
    s = STEEL
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    section = exu.BeamSection()
    section.stiffnessMatrix = np.diag([s.E * s.A, s.G * s.A, s.G * s.A, s.G * s.J, s.E * s.Iy, s.E * s.Iz])
    section.inertia = np.diag([s.rho * (s.Iy + s.Iz), s.rho * s.Iy, s.rho * s.Iz])
    section.massPerLength = s.rho * s.A
    nodes = [mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=[L * i / n, 0, 0, 1, 0, 0, 0])) for i in range(n + 1)]
    for i in range(n):
        mbs.AddObject(ObjectBeamGeometricallyExact(nodeNumbers=[nodes[i], nodes[i + 1]], length=L / n,
                                                   sectionData=section))
    mbs.AddObject(GenericJoint(markerNumbers=[mbs.AddMarker(MarkerNodeRigid(nodeNumber=ground)),
                                              mbs.AddMarker(MarkerNodeRigid(nodeNumber=nodes[0]))]))
    mbs.AddLoad(LoadForceVector(markerNumber=mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[-1])),
                                loadVector=list(force)))
    mbs.Assemble()
    settings = exu.SimulationSettings()
    settings.solution.file.write = False  # no solution/ folder in the cwd
    settings.staticSolver.numberOfLoadSteps = 50
    settings.staticSolver.verboseMode = 0
    settings.staticSolver.newton.relativeTolerance = 1e-10
    settings.staticSolver.newton.absoluteTolerance = 1e-6
    settings.staticSolver.stabilizerODE2term = 0
    settings.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    mbs.SolveStatic(settings)
    return np.array(mbs.GetNodeOutput(nodes[-1], exu.OutputVariableType.Position))


def test_3d_tip_force_against_exudyn():
    """Cross-check (runs only where Exudyn is installed; never a dependency): a dead tip force
    in both planes; rod3d and Exudyn's geometrically exact beam converge at O(h^2) to the same
    continuum solution and to each other (measured |rod3d - Exudyn| = 1.9e-4 L at n = 16,
    4.6e-5 L at n = 32; each 2e-4 L from the continuum at n = 32)."""
    s = STEEL
    force = (0.0, 1.2 * s.E * s.Iz / L**2, 2.0 * s.E * s.Iy / L**2)
    ref, _ = cosserat_shooting(force, (0, 0, 0), guess=np.cross([0.8, 0.3, 0.4], force))
    diff = []
    for n in (16, 32):
        exu_tip = exudyn_tip(n, force)
        beam, g, h = tip_loaded(n, force=force)
        tip = solve_path(g, h, beam.q0, 10)[6 * n - 6:6 * n - 3]
        assert np.linalg.norm(exu_tip - ref) < 1e-3 * (32 / n)**2 * L
        diff.append(np.linalg.norm(tip - exu_tip))
    assert diff[1] < 1e-4 * L and diff[0] / diff[1] > 3.5, diff


# --- 3. invariance ---

def _elements(nodes):
    return [np.concatenate([nodes[k], nodes[k + 1]]) for k in range(len(nodes) - 1)]


def _rigidly(nodes, R, c):
    return [np.concatenate([R.apply(x[:3]) + c, (R * Rotation.from_rotvec(x[3:])).as_rotvec()]) for x in nodes]


def test_objectivity_of_strains_and_energy():
    f = element_functions()
    rng = np.random.default_rng(1)
    n, le = 6, L / 6
    energy = lambda nodes: sum(float(f["elastic"](e, le, SEC)) for e in _elements(nodes))
    forces = lambda nodes: np.array([np.array(f["forces"](e, le, SEC)).ravel() for e in _elements(nodes)])
    straight = [np.array([k * le, 0, 0, 0, 0, 0]) for k in range(n + 1)]
    # a deformed beam: each node displaced by up to 5 cm and turned by up to ~0.6 rad
    deformed = [x + np.concatenate([rng.uniform(-0.05, 0.05, 3), rng.uniform(-0.35, 0.35, 3)]) for x in straight]
    V0, F0 = energy(deformed), forces(deformed)
    assert V0 > 1e2
    for _ in range(5):
        R, c = Rotation.random(random_state=rng), rng.uniform(-2, 2, 3)
        # a rigid motion of the straight beam stores no energy (relative to a unit-scale V0)
        assert energy(_rigidly(straight, R, c)) < 1e-20 * V0
        # and a deformed beam moved rigidly keeps its energy and its section forces
        assert energy(_rigidly(deformed, R, c)) == pytest.approx(V0, rel=1e-12)
        assert np.allclose(forces(_rigidly(deformed, R, c)), F0, rtol=0, atol=1e-9 * np.abs(F0).max())


def test_frame_motion_and_relative_motion_give_the_same_kinetic_energy():
    """T of a (deformed) element at rest in a frame moving with (omega, V) equals T of the same
    element moving rigidly with that velocity in a frame at rest: r' = V + omega x r, and psi'
    such that the section's angular velocity is omega. Checks how the frame's motion enters."""
    f = element_functions()["kinetic"]
    psi, rate = ca.SX.sym("psi", 3), ca.SX.sym("rate", 3)
    Wrel = ca.Function("W", [psi], [ca.jacobian(angular_velocity(psi, rate), rate)])
    Lam = ca.Function("Lam", [psi], [qmatrix(quaternion(psi))])
    rng = np.random.default_rng(2)
    le = 0.3
    for _ in range(5):
        e = np.concatenate([[0, 0, 0], rng.uniform(-1, 1, 3), [le, 0.05, -0.02], rng.uniform(-1, 1, 3)])
        omega, V = rng.uniform(-5, 5, 3), rng.uniform(-3, 3, 3)
        ed = np.zeros(12)
        for k in (0, 6):
            p = e[k + 3:k + 6]
            ed[k:k + 3] = V + np.cross(omega, e[k:k + 3])
            ed[k + 3:k + 6] = np.linalg.solve(np.array(Wrel(p)), np.array(Lam(p)).T @ omega)
        moving_frame = float(f(e, np.zeros(12), omega, V, le, SEC, 1.0))
        fixed_frame = float(f(e, ed, np.zeros(3), np.zeros(3), le, SEC, 1.0))
        assert moving_frame == pytest.approx(fixed_frame, rel=1e-12)
    # and the undeformed element spinning with the frame about z at its root: the slender bar
    # rho A le^3 / 3 plus the sections' rotary inertia rho I_z le (exact)
    e0 = np.array([0, 0, 0, 0, 0, 0, le, 0, 0, 0, 0, 0])
    T = float(f(e0, np.zeros(12), [0, 0, 2.0], np.zeros(3), le, SEC, 1.0))
    s = STEEL
    assert T == pytest.approx(0.5 * 4.0 * (s.rho * s.A * le**3 / 3 + s.rho * s.Iz * le), rel=1e-13)


# --- 4. dynamics ---

def classify(beam, vec):
    """The kind of a mode shape: torsion if its twist dominates (rotation about x, in rad,
    against displacements over L and the other rotations), else the displacement direction
    with the largest share."""
    v = np.abs(vec.reshape(beam.n, 6))
    if v[:, 3].max() > 10 * max(v[:, :3].max() / beam.L, v[:, 4:].max()):
        return "torsion"
    return "xyz"[int(np.argmax(np.linalg.norm(v[:, :3], axis=0)))]


def frequencies(n, sec=SEC, length=L):
    """Natural frequencies (rad/s) of the clamped-free beam about the undeformed state, frame
    at rest, by kind: {"y": [...], "z": [...], "x": [...], "torsion": [...]}, ascending."""
    beam, f = model(n, length)
    K = np.array(f["K"](beam.q0, sec))
    M = np.array(f["M"](beam.q0, np.zeros(3), np.zeros(3), sec))
    lam, vec = eigh(K, M)
    out = {"x": [], "y": [], "z": [], "torsion": []}
    for k in range(len(lam)):
        out[classify(beam, vec[:, k])].append(np.sqrt(lam[k]))
    return out


def timoshenko_cantilever(EI, GA, rhoA, rhoI, length, guess):
    """A clamped-free Timoshenko beam's natural frequency near `guess` (shear stiffness GA,
    rotary inertia rhoI: the rod's linearisation), by shooting on the continuum equations
    EI th'' + GA (v' - th) + rhoI w^2 th = 0, GA (v'' - th') + rhoA w^2 v = 0;
    v = th = 0 at the root, th' = v' - th = 0 at the tip."""
    def det(w):
        def ode(x, y):
            v, dv, th, dth = y
            return [dv, dth - rhoA * w**2 * v / GA, dth, -(GA * (dv - th) + rhoI * w**2 * th) / EI]
        ends = []
        for y0 in ([0, 1, 0, 0], [0, 0, 0, 1]):
            y = solve_ivp(ode, (0, length), y0, method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1]
            ends.append([y[3], y[1] - y[2]])
        return np.linalg.det(np.array(ends))
    ws = np.linspace(0.9 * guess, 1.0001 * guess, 12)
    d = [det(w) for w in ws]
    k = next(i for i in range(len(d) - 1) if d[i] * d[i + 1] < 0)
    return brentq(det, ws[k], ws[k + 1], xtol=1e-13 * guess)


def test_natural_frequencies_converge_to_euler_bernoulli_and_st_venant():
    """Bending in both planes (I_z = 4 I_y), torsion and axial, n = 8 .. 64: O(h^2), and the
    Richardson limit is the rod's continuum (Timoshenko with G A and rho I: below Euler-
    Bernoulli by O((r_g/L)^2), measured -2.78e-4 and -1.93e-3 for the first two modes along y,
    -6.96e-5 and -4.85e-4 along z) and exactly St Venant's torsion and the axial rod."""
    s = STEEL
    eb = lambda I, bl: bl**2 * np.sqrt(s.E * I / (s.rho * s.A * L**4))
    ref = {("y", 0): eb(s.Iz, 1.87510407), ("y", 1): eb(s.Iz, 4.69409113),
           ("z", 0): eb(s.Iy, 1.87510407), ("z", 1): eb(s.Iy, 4.69409113),
           ("torsion", 0): np.pi / 2 * np.sqrt(s.G * s.J / (s.rho * (s.Iy + s.Iz) * L**2)),
           ("x", 0): np.pi / 2 * np.sqrt(s.E / s.rho) / L}
    runs = {n: frequencies(n) for n in (8, 16, 32, 64)}
    for (kind, k), w in ref.items():
        seq = [runs[n][kind][k] for n in (8, 16, 32, 64)]
        d = np.diff(seq)
        rate = np.log2(d[:-1] / d[1:])
        assert np.all(np.abs(rate - 2) < 0.05), (kind, k, seq, rate)  # O(h^2)
        limit = seq[-1] + d[-1] / 3  # Richardson
        if kind in ("y", "z"):
            I = s.Iz if kind == "y" else s.Iy
            timo = timoshenko_cantilever(s.E * I, s.G * s.A, s.rho * s.A, s.rho * I, L, w)
            assert -70 * I / s.A / L**2 < timo / w - 1 < 0  # O((r_g/L)^2) below EB
            w = timo
        # the Richardson remainder is O(h^4): measured below 1e-6 of the frequency
        assert abs(limit / w - 1) < 3e-6, (kind, k, limit / w - 1)


def test_deviation_from_euler_bernoulli_is_order_slenderness_squared():
    """Halving the section's size (r_g / L halved) divides the first bending frequency's
    deviation from Euler-Bernoulli by 4: it is the O((r_g/L)^2) of shear and rotary inertia."""
    s = STEEL
    devs = []
    for scale in (2.0, 1.0):
        b, h = scale * B, scale * H
        sec = Section(E=s.E, G=s.G, rho=s.rho, A=b * h, Iy=b * h**3 / 12, Iz=h * b**3 / 12, J=0.2287 * b * h**3)
        seq = [frequencies(n, sec.vector)["y"][0] for n in (16, 32)]
        limit = seq[1] + (seq[1] - seq[0]) / 3
        devs.append(limit / (1.87510407**2 * np.sqrt(sec.E * sec.Iz / (sec.rho * sec.A * L**4))) - 1)
    assert devs[0] / devs[1] == pytest.approx(4.0, rel=0.02), devs


def rotating_ritz(eta, lag=False, terms=10):
    """First bending frequency (in sqrt(EI / (rho A L^4))) of a uniform Euler-Bernoulli
    cantilever rotating about its root at eta sqrt(EI / (rho A L^4)), perpendicular to the
    beam: Rayleigh-Ritz with x^2 .. x^(terms+1) (L = EI = rho A = 1), centrifugal tension
    N = eta^2 (1 - x^2) / 2; in the plane of rotation (lag) the centrifugal softening
    -eta^2 int phi^2 is added. An independent reference for Southwell's coefficient."""
    from numpy.polynomial import polynomial as P
    basis = [np.eye(k + 2)[k + 1] for k in range(1, terms + 1)]
    N = np.array([0.5, 0, -0.5]) * eta**2
    integral = lambda c: P.polyval(1.0, P.polyint(c))
    K = np.array([[integral(P.polymul(P.polyder(a, 2), P.polyder(b, 2)))
                   + integral(P.polymul(N, P.polymul(P.polyder(a), P.polyder(b))))
                   - (eta**2 * integral(P.polymul(a, b)) if lag else 0) for b in basis] for a in basis])
    M = np.array([[integral(P.polymul(a, b)) for b in basis] for a in basis])
    return np.sqrt(eigh(K, M, eigvals_only=True)[0])


def rotating_frequencies(n, Omega, sec=SEC):
    """Frequencies about the steady state of the beam in a frame rotating at Omega about z
    (centrifugal stretch solved for by Newton): the gyroscopic quadratic eigenproblem
    M x'' + G x' + (K - d2 T0/dq2) x = 0, by kind as frequencies()."""
    beam, f = model(n)
    om, V = np.array([0, 0, Omega]), np.zeros(3)
    grad = lambda q, lam, s: f["grad_eff"](q, om, V, s)
    hess = lambda q, lam, s: f["K_eff"](q, om, V, s)
    q = newton(grad, hess, beam.q0, 1.0, sec)
    M = np.array(f["M"](q, om, V, sec))
    K = np.array(f["K_eff"](q, om, V, sec))
    Jg = np.array(f["J_gyro"](q, om, V, sec))
    G = Jg - Jg.T
    m = 6 * n
    A = np.block([[np.zeros((m, m)), np.eye(m)], [-np.linalg.solve(M, K), -np.linalg.solve(M, G)]])
    lam, vec = eig(A)
    out = {"x": [], "y": [], "z": [], "torsion": []}
    for k in np.argsort(lam.imag):
        if lam[k].imag > 0:
            assert abs(lam[k].real) < 1e-6 * lam[k].imag  # undamped, stable
            out[classify(beam, vec[:m, k])].append(lam[k].imag)
    return q, out


def test_southwell_stiffening_from_the_frames_rotation():
    """A frame spinning about z at the beam's root: the first flap (z) frequency rises as
    omega^2 = omega_0^2 + K_s Omega^2, K_s = 1.193 (Southwell's coefficient of a uniform
    cantilever), the first lag (y) one by (K_s - 1) Omega^2. The rod, linearised about the
    rotating steady state (centrifugal stretch, gyroscopic terms), against the Ritz solution
    of the rotating inextensible Euler-Bernoulli beam at eta = Omega sqrt(rho A L^4 / E I_y)
    = 1 (3.6816 against 3.5160): O(h^2), and the rest is O((r_g/L)^2) (rotary inertia and
    shear in flap; Coriolis coupling with the finite axial stiffness in lag), a 16th for a
    section of a quarter the size. Measured (steel, Richardson from n = 16, 32): flap
    K_s - Ritz = -2.1e-4, lag -1.15e-3; quarter section -1.1e-5 and -7.1e-5."""
    assert rotating_ritz(0.1)**2 / 0.01 - rotating_ritz(0.0)**2 / 0.01 == pytest.approx(1.193, abs=5e-4)
    assert rotating_ritz(0.0) == pytest.approx(1.87510407**2, rel=1e-7)  # the basis has converged
    flap0 = rotating_ritz(0.0)**2
    dev = []
    for scale in (1.0, 0.25):
        b, h = scale * B, scale * H
        s = Section(E=STEEL.E, G=STEEL.G, rho=STEEL.rho, A=b * h, Iy=b * h**3 / 12, Iz=h * b**3 / 12,
                    J=0.2287 * b * h**3)
        unit_f = np.sqrt(s.E * s.Iy / (s.rho * s.A * L**4))  # flap bends about y: E I_y
        unit_l = np.sqrt(s.E * s.Iz / (s.rho * s.A * L**4))  # lag: E I_z = 4 E I_y
        Omega = 1.0 * unit_f
        eta_l = Omega / unit_l
        ritz = (rotating_ritz(1.0)**2 - flap0, (rotating_ritz(eta_l, lag=True)**2 - flap0) / eta_l**2)
        K = []
        for n in (16, 32):
            q, rot = rotating_frequencies(n, Omega, s.vector)
            still = frequencies(n, s.vector)
            # the steady state is stretched by the centrifugal force: u(L) = rho Omega^2 L^3 / (3 E)
            assert q[-6] - L == pytest.approx(s.rho * Omega**2 * L**3 / (3 * s.E), rel=1e-4)
            K.append([(rot[k][0]**2 - still[k][0]**2) / Omega**2 for k in ("z", "y")])
        K = np.array(K)
        assert np.all(np.abs(K[1] - K[0]) < 2e-3)  # O(h^2): n = 16 to 32 moves K by 5e-4
        limit = K[1] + (K[1] - K[0]) / 3
        d = limit - ritz
        rg2 = np.array([s.Iy, s.Iz]) / s.A / L**2
        assert np.all(np.abs(d) < 50 * rg2), (scale, limit, ritz)
        dev.append(d)
    assert dev[0] / dev[1] == pytest.approx([16, 16], rel=0.25)  # O((r_g/L)^2)


# --- 5. conservation ---

def free_vibration(n, length, tol, periods=1.5):
    """A free run (frame at rest, no gravity) from the undeformed state with the velocities of
    the first y, z and torsion modes (tip amplitudes 0.1 L, 0.1 L, 0.1 rad): casadi's CVODES
    (Adams) on M(q) q'' = dT/dq - (d/dq dT/dq') q' - dV/dq. Returns (energies, states)."""
    beam, fm = model(n, length)
    q, v = ca.SX.sym("q", 6 * n), ca.SX.sym("v", 6 * n)
    T, Ve, _ = beam.energies(q, v, ca.DM.zeros(3), ca.DM.zeros(3), ca.DM.zeros(3), SEC)
    M = ca.hessian(T, v)[0]
    f = ca.gradient(T, q) - ca.jtimes(ca.gradient(T, v), q, v) - ca.gradient(Ve, q)
    H = ca.Function("H", [q, v], [T + Ve])
    lam, vec = eigh(np.array(fm["K"](beam.q0, SEC)), np.array(fm["M"](beam.q0, np.zeros(3), np.zeros(3), SEC)))
    v0 = np.zeros(6 * n)
    for kind, c, amp in (("y", "ry", 0.1 * length), ("z", "rz", 0.1 * length), ("torsion", "px", 0.1)):
        k = next(i for i in range(len(lam)) if classify(beam, vec[:, i]) == kind)
        v0 += amp * np.sqrt(lam[k]) * vec[:, k] / vec[beam.index(n, c), k]
    grid = np.linspace(0, periods * 2 * np.pi / np.sqrt(lam[0]), 31)
    F = ca.integrator("F", "cvodes", {"x": ca.vertcat(q, v), "ode": ca.vertcat(v, ca.solve(M, f))}, 0, grid,
                      {"reltol": tol, "abstol": tol * 1e-3, "max_num_steps": 10**6,
                       "linear_multistep_method": "adams", "nonlinear_solver_iteration": "functional"})
    X = np.array(F(x0=np.concatenate([beam.q0, v0]))["xf"])
    E = np.array([float(H(X[:6 * n, k], X[6 * n:, k])) for k in range(X.shape[1])])
    return np.concatenate([[float(H(beam.q0, v0))], E]), X


def test_free_vibration_conserves_energy_and_is_deterministic():
    """A stubby beam (L = 0.1 m, 2 elements) keeps the run short: explicit Adams must resolve
    the rotation-against-shear modes of the bending rotary inertia (~1e6 rad/s, against the
    first bending mode's 5.3e3). The energy error follows the tolerance (measured 7e-9 at
    1e-7, 3e-11 at 1e-9): the equations conserve energy; the same run twice is bit-identical."""
    E7, X7 = free_vibration(2, 0.1, 1e-7)
    E9, _ = free_vibration(2, 0.1, 1e-9)
    assert np.abs(X7[2 * 6 - 5]).max() > 0.009  # tip y ~ 0.1 L: a nonlinear motion
    err7, err9 = (np.abs(E / E[0] - 1).max() for E in (E7, E9))
    assert err7 < 1e-7 and err9 < 1e-9 and err9 < err7 / 20, (err7, err9)
    E7b, X7b = free_vibration(2, 0.1, 1e-7)
    assert np.array_equal(X7, X7b) and np.array_equal(E7, E7b)
