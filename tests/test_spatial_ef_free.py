"""The spatial ef (physics/rod3d.py elements) on a free floating frame: S6's strip on a ball
joint (Euler parameters). The elements' kinetic energy in the frame's quasi-velocities, element
kernels called per element by system.c (sysgen._rod_free_kernels, rod_free_add), against the
whole-system AD path it replaces (derive_spatial(ef_free_ad=True)), conservation of energy and
the rigid limit. The reference study (S6, S7 in elements and step, the modal models against
it) is docs/validation/spatial.md's "S6 and S7 against the spatial ef"."""
import ctypes
import tomllib
from pathlib import Path

import numpy as np
import pytest

from flexsym.scenes.system_scene import system_from_dict
from system_data import built, run_ok, with_model

ROOT = Path(__file__).resolve().parent.parent
S6 = ROOT / "scenes" / "spherical_pendulum.toml"
N = 4  # elements in the default suite's build (one build shared by every test here)
RHO, A, L, IY, IZ, J_ = 2700.0, 1.0e-4, 1.0, 2.0833e-10, 3.3333e-9, 7.021e-10


# the fixture's outputs: energies, the loop, the angular momentum and the ball joint's loads
S6EF_COLUMNS = {"T": "T", "V": "V", "viol": "violation", "Hz": "Hz",
                **{f"B{c}": f"reaction(ball, m{c})" for c in "xyz"}, "Fz": "reaction(ball, z)"}


def _s6_ef(n: int, **columns) -> dict:
    data = tomllib.loads(S6.read_text())
    data["output"]["columns"] |= columns
    return with_model(data, {"variant": "ef", "elements": n})


@pytest.fixture(scope="module")
def s6ef():
    return built(_s6_ef(N, **S6EF_COLUMNS))


def _system_struct():
    P = ctypes.POINTER(ctypes.c_double)
    fn4 = ctypes.CFUNCTYPE(None, P, P, P, P)
    fn5 = ctypes.CFUNCTYPE(None, P, P, P, P, P)
    fn7 = ctypes.CFUNCTYPE(None, P, P, P, P, P, P, P)

    class System(ctypes.Structure):  # flexsym/system.h's fsm_system, up to energy
        _fields_ = ([("s%d" % k, ctypes.c_char_p) for k in range(3)] + [("i%d" % k, ctypes.c_int) for k in range(6)]
                    + [("length_scale", ctypes.c_double)] + [("j%d" % k, ctypes.c_int) for k in range(5)]
                    + [("ptr%d" % k, ctypes.c_void_p) for k in range(7)]
                    + [("drive", ctypes.c_void_p), ("mass", fn4), ("force", fn5), ("residual_jac", fn7)]
                    + [("c%d" % k, ctypes.c_void_p) for k in range(5)] + [("energy", fn5)])
    return System, P




def _c_kernels_agree(s, want, q, qd, qdd, d, p) -> None:
    """The model struct's C mass, force, residual Jacobians and energies at (q, q', q'', d, p)
    equal `want` (the AD path's) to 1e-10 of each result's largest entry."""
    P = ctypes.POINTER(ctypes.c_double)
    ptr = lambda a: a.ctypes.data_as(P)  # noqa: E731
    nq = len(q)
    M, f, Jq, Jv, en = np.zeros(nq * nq), np.zeros(nq), np.zeros(nq * nq), np.zeros(nq * nq), np.zeros(3)
    s.mass(ptr(q), ptr(d), ptr(p), ptr(M))
    s.force(ptr(q), ptr(qd), ptr(d), ptr(p), ptr(f))
    s.residual_jac(ptr(q), ptr(qd), ptr(qdd), ptr(d), ptr(p), ptr(Jq), ptr(Jv))
    s.energy(ptr(q), ptr(qd), ptr(d), ptr(p), ptr(en))
    for name, got, ref_ in zip(("mass", "force", "dr_dq", "dr_dqd", "energy"), (M, f, Jq, Jv, en), want):
        assert np.abs(got - ref_).max() <= 1e-10 * np.abs(ref_).max(), name

def _ad_path(system, beam: str, n: int):
    """The whole-system AD path's derivation (derive_spatial(ef_free_ad=True)) and a casadi
    function (q, q', q'', d, p) -> [M, f, dr/dq, dr/dq', (T, V, h)] of it, with the rod
    elements' elastic energy (which system.c adds on both paths) added here by casadi."""
    import casadi as ca

    from flexsym.codegen.sysgen import build_system_kernels
    from flexsym.physics.rod3d import element_functions
    from flexsym.physics.spatial import derive_spatial
    from flexsym.physics.spatial_ef import rod_nodes, rod_section

    der = derive_spatial(system, ef_free_ad=True)
    kernels = {k.name: k.function for k in build_system_kernels(der)}
    nq, npar, nd = len(der.q), len(der.params), len(der.drive_symbols)
    q, qd, qdd = ca.SX.sym("q", nq), ca.SX.sym("qd", nq), ca.SX.sym("qdd", nq)
    p, d = ca.SX.sym("p", npar), ca.SX.sym("d", nd)
    info = der.spatial[beam]
    nodes = rod_nodes(info, q, p)
    le, sec = p[info["pidx"]["L"]] / n, rod_section(info, p)
    Ve = sum((element_functions()["elastic"](ca.vertcat(nodes[k], nodes[k + 1]), le, sec)
              for k in range(n)), ca.SX(0))
    M, = kernels["mass"].call([q, d, p])
    f, = kernels["force"].call([q, qd, d, p])
    Jq, Jv = kernels["residual_jac"].call([q, qd, qdd, d, p])
    en, = kernels["energy"].call([q, qd, d, p])
    return der, ca.Function("ref", [q, qd, qdd, d, p], [M, f - ca.gradient(Ve, q), Jq + ca.hessian(Ve, q)[0],
                                                         Jv, en + ca.vertcat(0, Ve, Ve)])

def test_s6_ef_c_path_against_the_whole_system_ad_path(s6ef):
    """M, f, dr/dq, dr/dq' and [T, V, h] of the generated C (the elements' kinetic energy in the
    frame's quasi-velocities, assembled per element) against the old formulation, the elements'
    T_e(e, e'; omega(q, q'), V) summed and differentiated by casadi AD over the whole system
    (derive_spatial(ef_free_ad=True); the rod elements' elastic energy, which system.c adds on
    both paths, added here by casadi) at random states, to 1e-10 of each result's largest
    entry (the bending rotary inertia at 0.37 of the physical). Measured at n = 2: 4e-17 .. 3e-16."""

    from flexsym.codegen.folder import model_accessor

    system = system_from_dict(_s6_ef(N, **S6EF_COLUMNS), name="spherical_pendulum")
    der, ad = _ad_path(system, "strip", N)
    assert not der.rod_bodies[0]["free_c"] and len(der.casadi_T) == 1
    nq, npar = len(der.q), len(der.params)
    ref = lambda q_, qd_, qdd_, p_: ad(q_, qd_, qdd_, np.zeros(0), p_)  # noqa: E731

    System, _ = _system_struct()
    lib = ctypes.CDLL(str(s6ef.library))
    acc = getattr(lib, model_accessor("spherical_pendulum"))
    acc.restype = ctypes.POINTER(System)
    s = acc().contents
    assert s.i0 == nq and s.i4 == npar
    pv = np.array([v for _, _, v in der.params], dtype=float)
    names = [name for name, _, _ in der.params]
    pv[names.index("bending_inertia")] = 0.37  # the run-time factor of the bending rotary inertia
    rnd = np.random.default_rng(7)
    for _ in range(3):
        qv, qdv, qddv = rnd.uniform(-0.2, 0.2, nq), rnd.uniform(-2, 2, nq), rnd.uniform(-5, 5, nq)
        qv[:4] = rnd.normal(size=4)  # the Euler parameters (any: the equations hold off |e| = 1)
        qv[4::6] += np.arange(1, N + 1) * L / N  # the nodes near their places
        want = [np.array(x).reshape(-1) for x in ref(qv, qdv, qddv, pv)]
        _c_kernels_agree(s, want, qv, qdv, qddv, np.zeros(1), pv)


def test_s6_ef_conserves_energy_with_genalpha3_ali3p_and_rk4p(s6ef):
    """Gravity is vertical and the joint force acts at the pivot: T + V is conserved. n = 4,
    0.2 s: genalpha3 keeps it to 7.6e-8 and 1.5e-8 at 0.1 and 0.05 ms (order 2), ali3p to
    9.8e-8 at 0.1 ms; rk4p (explicit: the rod's rotation-against-shear mode, 2e7 rad/s here,
    limits it to 1.3e-7 s) to round-off over 2 ms and the same motion. T + V at t = 0 is the
    rigid strip's spin, 1/2 (m L^2/3 + rho I_z L) 4^2 (the sections' rotary inertia, lumped at
    the nodes); |e| = 1 holds to round-off."""
    T0 = 0.5 * (RHO * A * L**3 / 3 + RHO * IZ * L) * 16
    errs = []
    for dt in (1e-4, 5e-5):
        r = run_ok(s6ef, t_end=0.2, dt=dt, integrator="genalpha3")
        E = r["T"] + r["V"]
        errs.append(np.abs(E - T0).max() / T0)
        assert np.abs(r["viol"]).max() < 1e-14
    assert E[0] == pytest.approx(T0, rel=1e-12)
    assert errs[1] < 3e-8 and 3.0 < errs[0] / errs[1] < 7.0, errs
    a = run_ok(s6ef, t_end=0.2, dt=1e-4, integrator="ali3p")
    assert np.abs(a["T"] + a["V"] - T0).max() < 2e-7 * T0
    assert np.abs(a["z_tip"] - r["z_tip"]).max() < 1e-5
    g = run_ok(s6ef, t_end=0.002, dt=1e-5, integrator="genalpha3")
    k = run_ok(s6ef, t_end=0.002, dt=1.25e-7, integrator="rk4p")
    assert np.abs(k["T"] + k["V"] - T0).max() < 1e-10 * T0
    assert np.abs(k["z_tip"] - g["z_tip"]).max() < 1e-8


def test_s6_ef_keeps_its_vertical_angular_momentum_and_its_ball_joint_carries_no_moment(s6ef):
    """Hz, the ef beam's angular momentum (its elements' consistent mass and its nodes' lumped
    rotary inertia, conjugate to rod3d's T: spatial/ef.Ef.momentum), starts at the rigid strip's
    spin (m L^2/3 + rho I_z L) 4 to round-off and is conserved (gravity is vertical, the joint's
    force acts at the pivot): genalpha3 keeps it to 2.0e-8 and 4.7e-9 at 0.1 and 0.05 ms (order
    2), rk4p to 2e-14 over 2 ms. The ball joint's moment, from the momentum balance (dH/dt less
    gravity's moment and P x F: joint_reaction, H's rate by the chain rule through the nodes'
    quaternions), is 0: 1.1e-15 N m with rk4p; 2.8e-7 and 1.3e-8 N m with genalpha3, whose
    multipliers and accelerations agree to O(dt^2) only."""
    H0 = (RHO * A * L**3 / 3 + RHO * IZ * L) * 4
    errs = []
    for dt in (1e-4, 5e-5):
        r = run_ok(s6ef, t_end=0.2, dt=dt, integrator="genalpha3")
        errs.append(np.abs(r["Hz"] - H0).max() / H0)
    assert r["Hz"][0] == pytest.approx(H0, rel=1e-12)
    assert errs[1] < 1e-8 and 3.0 < errs[0] / errs[1] < 7.0, errs
    assert max(np.abs(r[f"B{c}"]).max() for c in "xyz") < 1e-7
    k = run_ok(s6ef, t_end=0.002, dt=1.25e-7, integrator="rk4p")
    assert np.abs(k["Hz"] - H0).max() < 1e-12 * H0
    assert max(np.abs(k[f"B{c}"]).max() for c in "xyz") < 1e-12
    assert np.abs(k["Fz"]).max() > 0.1  # the joint does carry a load


def _rigid_tip(t_end: float, times):
    """The rigid strip on the ball joint: a body with the rod3d beam's inertia about the pivot
    (m L^2/3 across the axis, plus the sections' rotary inertia rho (I_y + I_z, I_y, I_z) L),
    its centre of mass at L/2; Euler's equations in body axes and R' = R [Omega]x (scipy,
    1e-12). Tip = R (L, 0, 0)."""
    from scipy.integrate import solve_ivp

    m = RHO * A * L
    I = np.diag([RHO * (IY + IZ) * L, m * L**2 / 3 + RHO * IY * L, m * L**2 / 3 + RHO * IZ * L])
    Ii = np.linalg.inv(I)
    c, g = np.array([L / 2, 0.0, 0.0]), np.array([0.0, 0.0, -9.81])

    def rhs(t, y):
        R, W = y[:9].reshape(3, 3), y[9:]
        tau = np.cross(c, m * R.T @ g)
        Wx = np.array([[0, -W[2], W[1]], [W[2], 0, -W[0]], [-W[1], W[0], 0]])
        return np.concatenate([(R @ Wx).ravel(), Ii @ (tau - np.cross(W, I @ W))])

    sol = solve_ivp(rhs, (0, t_end), np.concatenate([np.eye(3).ravel(), [0, 0, 4.0]]), rtol=1e-12,
                    atol=1e-12, dense_output=True)
    return np.array([sol.sol(t)[:9].reshape(3, 3) @ [L, 0, 0] for t in times])


def test_s6_ef_rigid_limit_is_the_rigid_strip_on_a_ball_joint(s6ef):
    """E, G x 100 and x 10^4: the tip follows the rigid strip (with the rod3d beam's inertia,
    its sections' rotary inertia included) over 0.5 s within 9.2e-6 m and 9.5e-8 m: the flexible
    difference falls as 1/E."""
    errs = []
    for k in (1e2, 1e4):
        r = run_ok(s6ef, t_end=0.5, dt=5e-5, integrator="genalpha3", params={"E": 7e10 * k, "G": 2.6e10 * k})
        tip = np.column_stack([r["x_tip"], r["y_tip"], r["z_tip"]])
        errs.append(np.abs(tip - _rigid_tip(0.5, r.t)).max())
    assert errs[1] < 1e-7, errs
    assert 30 < errs[0] / errs[1] < 300, errs


@pytest.mark.study
def test_s7_ef_c_path_against_the_whole_system_ad_path():
    """S7's rod (2 elements) on its ball joint at the guided crank's pin: the frame's motion reads
    the drive d = (t, phi, phi', phi'') as well (c = dw/dq q' + dw/dd d', B's dJ/dt), and the
    loop's cut universal joint sits on the tip node's section. M, f, dr/dq, dr/dq' and the
    energies of the C path against the whole-system AD path at random states and drives, as
    for S6. Measured: 3e-18 .. 2.6e-16 (a build of about 2 minutes)."""

    from flexsym.codegen.folder import model_accessor

    n = 2
    data = with_model(tomllib.loads((ROOT / "scenes" / "spatial_slider_crank.toml").read_text()),
                      {"variant": "ef", "elements": n})
    system = system_from_dict(data, name=data["system"]["name"])
    der, ref = _ad_path(system, "rod", n)
    nq, nd = len(der.q), len(der.drive_symbols)
    lib = ctypes.CDLL(str(built(data).library))
    System, _ = _system_struct()
    acc = getattr(lib, model_accessor(system.name))
    acc.restype = ctypes.POINTER(System)
    s = acc().contents
    pv = np.array([v for _, _, v in der.params], dtype=float)
    pv[[name for name, _, _ in der.params].index("bending_inertia")] = 0.37
    rnd = np.random.default_rng(3)
    for _ in range(3):
        qv, qdv, qddv = rnd.uniform(-0.2, 0.2, nq), rnd.uniform(-2, 2, nq), rnd.uniform(-5, 5, nq)
        dv = rnd.uniform(-3, 3, nd)
        want = [np.array(x).reshape(-1) for x in ref(qv, qdv, qddv, dv, pv)]
        _c_kernels_agree(s, want, qv, qdv, qddv, dv, pv)
