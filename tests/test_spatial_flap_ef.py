"""S5 `flap` on the spatial geometrically exact reference `ef` (physics/rod3d.py elements): its
static sag, the hub's torque against the energy the system gains, the generated C against an
independent casadi assembly. A file of its own so that its build runs beside test_spatial.py's
(pytest-xdist hands a file to one process)."""
import numpy as np
import pytest

from system_data import built, run_ok, with_model
from test_spatial import A, E, G_, IY, L, RHO, _flap_data

# ----- the spatial geometrically exact reference ef (physics/rod3d.py elements)
def _flap_ef(n: int, **changes) -> dict:
    return with_model(_flap_data(**changes), {"variant": "ef", "elements": n})


@pytest.fixture(scope="module")
def flap_ef8():
    data = _flap_ef(8)
    data["output"]["columns"] |= {"tau": "torque(spin)", "rate": "rate(hub_joint)", "T": "T", "V": "V"}
    return built(data)


def test_flap_ef_starts_in_the_static_sag(flap_ef8):
    """t = 0, 8 rod elements: the static sag under gravity. With E and G x 100 (the linear
    limit) the tip sag is rho A g L^4 / (8 E I_y) times 1 + 4 E I_y / (G A L^2) (the rod's
    shear, 2.07e-4) to 1e-6; at the scene's E it is less than that by the geometric
    nonlinearity (the sagged beam's foreshortened arm; -5.5e-4 measured at n = 4, the bound
    here is -1e-3 .. -1e-4). The root flap moment
    (rod3d's midpoint section forces extrapolated to the root) is rho A g L^2 / 2 within the
    extrapolation's O(h^2)."""
    sag = RHO * A * G_ * L**4 / (8 * E * IY)
    shear = 4 * E * IY / (2.7e10 * A * L**2)
    r = run_ok(flap_ef8, t_end=0.002, dt=1e-3)
    stiff = run_ok(flap_ef8, t_end=0.002, dt=1e-3, params={"E": 7e12, "G": 2.7e12})
    linear = -stiff["w_tip"][0] * 100 / (sag * (1 + shear)) - 1
    assert abs(linear) < 1e-6, linear
    nonlinear = -r["w_tip"][0] / (sag * (1 + shear)) - 1
    assert -1e-3 < nonlinear < -1e-4, nonlinear
    assert abs(r["v_tip"][0]) < 1e-12 and abs(r["M_lag_A"][0]) < 1e-9
    root = RHO * A * G_ * L**2 / 2
    assert abs(r["M_flap_A"][0] / root - 1) < 0.01


def test_flap_ef_hub_torque_does_the_work_the_system_gains(flap_ef8):
    """The guided hub's torque with an ef beam, from the hub joint's reaction moment about its
    axis (spatial._drive_load: the momentum balance of the hub and the beam, the beam's angular
    momentum conjugate to rod3d's T), times the hub's rate, integrated over the first 3 s of the
    spin-up (trapezoidal rule over the rows), is the gain of T + V (the hub's and the beam's
    kinetic, gravity and elastic energy): within 1e-6 of the work (16.7 J), measured 2.5e-7 and
    6.3e-8 at 1 and 0.5 ms (order 2: the step and the quadrature)."""
    errs = []
    for dt in (1e-3, 5e-4):
        r = run_ok(flap_ef8, t_end=3.0, dt=dt, integrator="genalpha", interval=dt)
        P = r["tau"] * r["rate"]
        W = np.concatenate([[0.0], np.cumsum((P[1:] + P[:-1]) / 2 * np.diff(r.t))])
        errs.append(np.abs(r["T"] + r["V"] - (r["T"] + r["V"])[0] - W).max() / W[-1])
    assert W[-1] > 10.0 and errs[1] < 1e-6 and 3.0 < errs[0] / errs[1] < 5.0, errs


def test_flap_ef_c_kernels_against_casadi(flap_ef8):
    """The generated C (mass, force, residual_jac, energy; rod3d elements assembled per element
    in system.c) against an independent casadi assembly of the same beam (rod3d.ClampedBeam's
    energies in the guided hub's frame, Lagrange by casadi AD) at a random state and drive,
    to 1e-11 of each result."""
    import ctypes

    import casadi as ca

    from flexsym.physics.lagrange import equations_of_motion_sx
    from flexsym.physics.rod3d import ClampedBeam, Section

    n = 8
    beam = ClampedBeam(n=n, L=L)
    sec = Section(E=E, G=2.7e10, rho=RHO, A=A, Iy=IY, Iz=2e-7, J=4e-7).vector
    q, qd, qdd, d = ca.SX.sym("q", 6 * n), ca.SX.sym("qd", 6 * n), ca.SX.sym("qdd", 6 * n), ca.SX.sym("d", 4)
    T, Ve, Vg = beam.energies(q + beam.q0, qd, ca.vertcat(0, 0, d[2]), ca.DM.zeros(3),
                              ca.DM([0, 0, -G_]), sec)
    Vt = Ve + Vg
    M, f = equations_of_motion_sx(T, -ca.gradient(Vt, q), q, qd, [(d[1], d[2], d[3])])
    r = ca.mtimes(M, qdd) - f
    M2 = ca.mtimes(qd.T, ca.mtimes(M, qd)) / 2
    hub = d[2]**2 / 2  # the guided hub's T (I_z = 1): in T, and -T0 in h
    ref = ca.Function("ref", [q, qd, qdd, d], [M, f, ca.jacobian(r, q), ca.jacobian(r, qd),
                                               ca.vertcat(T + hub, Vt, M2 - ca.substitute(T, qd, 0 * qd) - hub + Vt)])
    rnd = np.random.default_rng(3)
    qv, qdv, qddv = rnd.uniform(-0.1, 0.1, 6 * n), rnd.uniform(-0.5, 0.5, 6 * n), rnd.uniform(-1, 1, 6 * n)
    dv = np.array([0.3, 0.7, 2.1, 0.4])
    want = [np.array(x) for x in ref(qv, qdv, qddv, dv)]

    lib = ctypes.CDLL(str(flap_ef8.library))
    P = ctypes.POINTER(ctypes.c_double)
    fn4 = ctypes.CFUNCTYPE(None, P, P, P, P)
    fn5 = ctypes.CFUNCTYPE(None, P, P, P, P, P)
    fn7 = ctypes.CFUNCTYPE(None, P, P, P, P, P, P, P)

    class System(ctypes.Structure):
        _fields_ = ([("s%d" % k, ctypes.c_char_p) for k in range(3)] + [("i%d" % k, ctypes.c_int) for k in range(6)]
                    + [("length_scale", ctypes.c_double)] + [("j%d" % k, ctypes.c_int) for k in range(5)]
                    + [("ptr%d" % k, ctypes.c_void_p) for k in range(7)]
                    + [("drive", ctypes.c_void_p), ("mass", fn4), ("force", fn5), ("residual_jac", fn7)]
                    + [("c%d" % k, ctypes.c_void_p) for k in range(5)] + [("energy", fn5)])

    from flexsym.codegen.folder import model_accessor
    acc = getattr(lib, model_accessor("flap"))
    acc.restype = ctypes.POINTER(System)
    s = acc().contents
    assert s.i0 == 6 * n
    p = np.array([RHO, E, A, 2e-7, L, IY, 4e-7, 2.7e10])  # rho E A I L Iy J G
    arr = lambda a: np.ascontiguousarray(a, dtype=float)
    qv, qdv, qddv, dv, p = map(arr, (qv, qdv, qddv, dv, p))
    ptr = lambda a: a.ctypes.data_as(P)
    N = 6 * n
    Mc, fc, Jq, Jv, en = np.zeros(N * N), np.zeros(N), np.zeros(N * N), np.zeros(N * N), np.zeros(3)
    s.mass(ptr(qv), ptr(dv), ptr(p), ptr(Mc))
    s.force(ptr(qv), ptr(qdv), ptr(dv), ptr(p), ptr(fc))
    s.residual_jac(ptr(qv), ptr(qdv), ptr(qddv), ptr(dv), ptr(p), ptr(Jq), ptr(Jv))
    s.energy(ptr(qv), ptr(qdv), ptr(dv), ptr(p), ptr(en))
    for name, got, ref_ in (("mass", Mc, want[0]), ("force", fc, want[1]), ("dr_dq", Jq, want[2]),
                            ("dr_dqd", Jv, want[3]), ("energy", en, want[4])):
        ref_ = ref_.reshape(-1)  # row by row, as the C writes it
        assert np.abs(got - ref_).max() <= 1e-11 * np.abs(ref_).max(), name
