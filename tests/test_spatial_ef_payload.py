"""A body hung from a spatial ef beam's node (physics/body_kinds/spatial/ef.Ef.hang: the section's
frame Lambda = exp(psi) at the node, its entries functions of psi that sympy differentiates and
casadi evaluates): its frame's kinematics against finite differences and an independent
rotation vector formula, a payload on a stiffened strip against the rigid body, and against the
modal beam carrying the same payload."""
import casadi as ca
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from system_data import built, derivation, run_ok
from test_spatial_payload import A, G, IY, IZ, L, M, RHO, strip_with_payload

PIN = {"name": "pin", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0, 0.0],
       "axis": [0.2, 1.0, 0.4], "child": "strip.root"}
COM, INERTIA = (0.02, 0.01, -0.01), (2e-5, 1e-5, 3e-5)


def _swinging_ef(n: int, name: str) -> dict:
    """The modal payload test's swinging strip (tilted pin, payload's centre of mass off the
    tip), its strip an ef beam of n elements, released undeformed."""
    data = strip_with_payload(name, PIN, start="undeformed", com=COM, model={"variant": "ef", "elements": n})
    data["output"]["columns"] = {"zp": "z(payload.c)", "xt": "x(strip.tip)",
                                 "yt": "y(strip.tip)", "zt": "z(strip.tip)", "T": "T", "V": "V"}
    data["output"]["columns"] |= {f"{m}{i}{j}": f"R({m}.{k}, {i}, {j})" for m, k in (("strip", "tip"), ("payload", "c"))
                                  for i in "xyz" for j in "xyz"}
    return data


def _casadi(der, exprs):
    """exprs (sympy, the applied functions R_ij(psi) of the ef nodes included) as a casadi
    function of (q, qd, p), as sysgen translates them (a matrix row by row)."""
    from flexsym.codegen.sysgen import placeholder_values
    from flexsym.emit.kernels import SympyToCasadi

    n = len(der.q)
    x = {"q": ca.SX.sym("q", n), "qd": ca.SX.sym("qd", n), "p": ca.SX.sym("p", len(der.params))}
    symbols = {s: x["p"][i] for i, (_, s, _) in enumerate(der.params)}
    symbols |= {s: x["q"][i] for i, s in enumerate(der.q)} | {s: x["qd"][i] for i, s in enumerate(der.qd)}
    tr = SympyToCasadi(symbols, dict.fromkeys(symbols, 0))
    tr.resolve = placeholder_values(der.casadi_functions, tr, x)
    out = [ca.vertcat(*[tr(e) for e in m]) for m in exprs]
    return ca.Function("f", [x["q"], x["qd"], x["p"]], out)


def test_the_frame_hung_from_an_ef_node_is_the_nodes_section_and_moves_with_it():
    """At a random deformed state (rotation vectors of 0.4-0.9 rad, displacements of 5 cm) and
    random rates: the payload's frame is the pin's turn times exp(psi) of the tip node (scipy's
    rotation vector formula, independent of rod3d's quaternion) within 1e-14, its origin the
    tip node; its angular velocity is A^T A' and its origin's velocity A^T R' by central
    differences along the rates (within 1e-7: the differences' own error at h = 1e-5)."""
    from flexsym.physics.spatial import derive_spatial
    from flexsym.scenes.system_scene import system_from_dict

    der = derive_spatial(system_from_dict(_swinging_ef(2, "payload_ef_kinematics"), name="payload_ef_kinematics"))
    fr = der.spatial["frames"]
    f = _casadi(der, [fr["payload"].A, fr["payload"].R, fr["payload"].omega, fr["payload"].V,
                      fr["strip"].A, fr["strip"].R])
    names = [c.name for c in der.coords]
    p = np.array([v for _, _, v in der.params])
    rnd = np.random.default_rng(11)
    for _ in range(3):
        q = rnd.uniform(-0.05, 0.05, len(names))
        psi = rnd.uniform(0.4, 0.9, 3) * rnd.choice([-1, 1], 3)
        for c, v in zip("xyz", psi):
            q[names.index(f"strip_p{c}2")] = v
        q[names.index("pin")] = rnd.uniform(-2, 2)
        qd = rnd.uniform(-3, 3, len(names))
        Ap, Rp, w, V, Ab, Rb = (np.array(v) for v in f(q, qd, p))
        Ap, Ab = Ap.reshape(3, 3), Ab.reshape(3, 3)
        assert np.abs(Ap - Ab @ Rotation.from_rotvec(psi).as_matrix()).max() < 1e-14
        tip = np.array([L + q[names.index("strip_ux2")], q[names.index("strip_uy2")], q[names.index("strip_uz2")]])
        assert np.abs(Rp.ravel() - (Rb.ravel() + Ab @ tip)).max() < 1e-14
        h = 1e-5
        Apl, Rpl = (np.array(v) for v in f(q + h * qd, qd, p)[:2])
        Amn, Rmn = (np.array(v) for v in f(q - h * qd, qd, p)[:2])
        Ad = (Apl - Amn).reshape(3, 3) / (2 * h)
        W = Ap.T @ Ad
        assert np.abs(W + W.T).max() < 1e-7  # skew: A stays a rotation
        assert np.abs(np.array([W[2, 1], W[0, 2], W[1, 0]]) - w.ravel()).max() < 1e-7
        assert np.abs(Ap.T @ ((Rpl - Rmn).ravel() / (2 * h)) - V.ravel()).max() < 1e-7


@pytest.fixture(scope="module")
def swinging_ef():
    return built(_swinging_ef(4, "payload_ef_swing"))


def _rigid_swing(times) -> np.ndarray:
    """The strip and its payload as one rigid body on the tilted pin (scipy, 1e-12): the rod3d
    strip's inertia about the pin (rho A L^3/3 across its axis, its sections' rotary inertia
    rho (I_y + I_z, I_y, I_z) L) and the payload's (its own about its centre, off the tip);
    I_a theta'' = a . (R(theta) s) x m g, s the first moment about the pin."""
    from scipy.integrate import solve_ivp

    a = np.array(PIN["axis"]) / np.linalg.norm(PIN["axis"])
    ms, c = RHO * A * L, np.array([L, 0.0, 0.0]) + COM
    I = np.diag([RHO * (IY + IZ) * L, ms * L**2 / 3 + RHO * IY * L, ms * L**2 / 3 + RHO * IZ * L])
    I += np.diag(INERTIA) + M * (c @ c * np.eye(3) - np.outer(c, c))
    s, g = ms * np.array([L / 2, 0.0, 0.0]) + M * c, np.array([0.0, 0.0, -G])

    def rhs(t, y):
        R = Rotation.from_rotvec(a * y[0]).as_matrix()
        return [y[1], a @ np.cross(R @ s, g) / (a @ I @ a)]
    sol = solve_ivp(rhs, (0, times[-1]), [0.0, 0.0], rtol=1e-12, atol=1e-12, dense_output=True)
    return sol.sol(times)[0]


def test_a_payload_on_a_stiffened_ef_strip_swings_as_the_rigid_body(swinging_ef):
    """E, G x 100 and x 10^4: the pin's angle (1.39 rad at most) follows the rigid body (strip
    and payload, the payload's own inertia and its centre off the tip included) over 0.5 s,
    within 1.1e-4 and 1.1e-6 rad (measured): the flexible difference falls as 1/E. The
    generated C with the payload's mass, inertia and offset carried through the tip's section
    frame; that frame's rate, which a stiff strip hardly turns, is checked by the test above.
    The tip section's orientation output R(strip.tip, i, j) is the payload's, a rotation, to
    round-off."""
    errs = []
    for k in (1e2, 1e4):
        r = run_ok(swinging_ef, t_end=0.5, dt=5e-5, integrator="genalpha", params={"E": 7e10 * k, "G": 2.6e10 * k})
        errs.append(np.abs(r["pin"] - _rigid_swing(r.t)).max())
        for k_ in range(0, len(r.t), 50):  # the tip section's axes are the payload's (a clamp)
            tip, load = ([[r[f"{m}{i}{j}"][k_] for j in "xyz"] for i in "xyz"] for m in ("strip", "payload"))
            assert np.abs(np.array(tip) - load).max() < 1e-14
            assert np.abs(np.array(tip).T @ tip - np.eye(3)).max() < 1e-14
    assert errs[1] < 1e-5, errs
    assert 30 < errs[0] / errs[1] < 300, errs
