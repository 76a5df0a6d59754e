"""Structural damping of spatial modal beams (physics/body_kinds/spatial/modal._dissipation,
the planar body_kinds.modal.damping_dissipation on the 3D fields): the damping matrix against closed forms on
natural modes in both bending planes and torsion, a damped planar system run as a spatial one,
the energy balance and the modal decay rates of a cantilever ringing in both planes; and of
the geometrically exact ef beam (beta: rod3d.strain_rate_energy per element), its energy
balance and its first mode's decay against the modal rate."""
import math

import numpy as np
import pytest
import sympy as sp

from flexsym.model.modes import clamped_free_beta
from flexsym.scenes.system_scene import system_from_dict
from system_data import built, derivation, run_ok
from test_damping import decay_rate, energy_balance
from test_planar_as_spatial import spatial_twin

RHO, E, G, A, L = 2700.0, 7.0e10, 2.6e10, 1.0e-4, 1.0
IZ, IY, J = 0.02 * 0.005**3 / 12, 0.005 * 0.02**3 / 12, 1.0e-9
CF = {"strain": "linear", "axial": [], "bending": ["cf1", "cf2"]}  # natural modes: decoupled
COORDS = ("v_cf1", "v_cf2", "vz_cf1", "vz_cf2", "phi_ff1")


def cantilever(damping, model=CF, g=(0.0, -9.81, -9.81), columns=None) -> dict:
    """Clamped to ground along x, released undeformed under gravity in both bending planes: it
    rings about its static sag."""
    return {"system": {"name": "cantilever3", "dimension": 3},
            "body": [{"name": "beam", "kind": "beam", "length": L, "density": RHO, "youngs_modulus": E,
                      "shear_modulus": G, "area": A, "inertia_z": IZ, "inertia_y": IY,
                      "torsion_constant": J, "model": model, "damping": damping}],
            "joint": [{"name": "root", "kind": "clamp", "parent": "ground", "point": [0.0, 0.0, 0.0],
                       "child": "beam.root"}],
            "gravity": {"g": list(g)},
            "output": {"columns": columns or {"T": "T", "V": "V", "P": "dissipation"}}}


def omega_bending(k: int, I: float) -> float:
    return float(clamped_free_beta(k))**2 * math.sqrt(E * I / (RHO * A * L**4))


def test_spatial_damping_matrix_is_the_analytic_one():
    """D = 1/2 q'^T C q', C = beta K + alpha M + diag(2 zeta_i omega_i m_i): on cf1, cf2 in each
    plane K = E I beta^4 / L^3 and m = rho A L; on the torsion mode sin(pi s / 2), K = G J
    pi^2 / (8 L) and m = rho (Iy + Iz) L / 2 (int sin^2 = 1/2); no coupling; no joint rate."""
    from flexsym.physics.spatial import derive_spatial

    zeta, alpha, beta = (0.02, 0.05, 0.03, 0.04, 0.01), 0.5, 1e-3
    der = derive_spatial(system_from_dict(cantilever({"zeta": list(zeta), "alpha": alpha, "beta": beta}),
                                          name="c3"))
    D = der.dissipation["beam"]
    qd = [sp.Symbol(f"beam_{c}_d", real=True) for c in COORDS]
    C = sp.hessian(D, qd).xreplace({sym: v for _, sym, v in der.params})
    k_m = [(E * I * float(clamped_free_beta(i))**4 / L**3, RHO * A * L) for I in (IZ, IY) for i in (1, 2)]
    k_m.append((G * J * math.pi**2 / (8 * L), RHO * (IY + IZ) * L / 2))
    for i, (k, m) in enumerate(k_m):
        want = beta * k + alpha * m + 2 * zeta[i] * math.sqrt(k / m) * m
        assert abs(float(C[i, i]) - want) < 1e-10 * want, (COORDS[i], float(C[i, i]), want)
    off = max(abs(float(C[i, j])) for i in range(5) for j in range(5) if i != j)
    assert off < 1e-12 * max(abs(float(C[i, i])) for i in range(5))
    assert not D.free_symbols & (set(der.q) | {x for c, x in zip(der.coords, der.qd) if c.group == "joint"})


def test_damped_planar_system_run_as_spatial_reproduces_the_planar_rows():
    """The planar damped cantilever (m3, zeta, alpha and beta) and its spatial twin: every
    column, the dissipated power included, within 1e-9 of its peak (the twin's second bending
    plane and torsion stay at rest, undamped or not)."""
    damping = {"zeta": 0.02, "alpha": 0.5, "beta": 1e-4}
    planar = {"system": {"name": "dcant"},
              "body": [{"name": "beam", "kind": "beam", "length": L, "density": RHO, "youngs_modulus": E,
                        "area": A, "inertia": IZ, "model": "m3", "damping": damping}],
              "joint": [{"name": "root", "kind": "clamp", "parent": "ground", "point": [0.0, 0.0],
                         "child": "beam.root"}],
              "gravity": {"g": [0.0, -9.81]},
              "output": {"columns": {"v_tip": "v(beam, tip)", "N_A": "N(beam, root)", "T": "T", "V": "V",
                                     "P": "dissipation"}}}
    kw = dict(t_end=0.5, dt=1e-4, integrator="genalpha")
    a, b = run_ok(built(planar), **kw), run_ok(built(spatial_twin(planar)), **kw)
    for col in ("v_tip", "N_A", "T", "P"):
        assert np.abs(b[col] - a[col]).max() <= 1e-9 * np.abs(a[col]).max(), col
    assert np.abs(a["P"]).max() > 0


@pytest.fixture(scope="module")
def ringing():
    """cf1, cf2 in both planes with zeta (0.02, 0.05) in the lag plane and (0.03, 0.04) in the
    flap plane, Newmark's trapezoidal rule (no numerical damping), rows at every step."""
    b = built(cantilever({"zeta": [0.02, 0.05, 0.03, 0.04, 0.01]}))
    dt = 2.5e-4
    return run_ok(b, t_end=3.0, dt=dt, integrator="newmark", interval=dt), dt, b


def test_energy_lost_is_the_damping_power_integrated(ringing):
    """E(0) - E(t) = int 2 D dt over the run, within 1e-4 of what was dissipated (the trapezoidal
    quadrature of the power over the rows; measured 2.6e-5)."""
    r, _, _ = ringing
    assert energy_balance(r) < 1e-4


@pytest.mark.parametrize("coordinate,zeta,I,k", [("beam_v_cf1", 0.02, IZ, 1), ("beam_v_cf2", 0.05, IZ, 2),
                                                 ("beam_vz_cf1", 0.03, IY, 1), ("beam_vz_cf2", 0.04, IY, 2)])
def test_each_plane_decays_at_its_modal_rate(ringing, coordinate, zeta, I, k):
    """Each natural mode of each plane rings about its static value with the envelope
    exp(-zeta omega t), omega of that plane's I (log decrement of successive extremes, fitted;
    within 1 %; measured 1e-5 to 4e-4 on the first modes, 6.5e-3 on the flap cf2 at 647
    rad/s, where the trapezoidal rule's own error at omega dt = 0.16 shows)."""
    r, dt, _ = ringing
    rate = decay_rate(r.t, r[coordinate], dt)
    want = zeta * omega_bending(k, I)
    assert abs(rate - want) < 0.01 * want, (coordinate, rate, want)


def test_damped_kernels_c_casadi_sympy(ringing, system_kernels_agree):
    """The damped cantilever's generated C kernels (its force holds -dD/dq', its outputs the
    dissipated power) against casadi against sympy at a random state."""
    data = cantilever({"zeta": [0.02, 0.05, 0.03, 0.04, 0.01]})
    system_kernels_agree(derivation(data), ringing[2], t=0.3, seed=3)


# ----- the geometrically exact ef beam, damped by beta (rod3d.strain_rate_energy) and by
# alpha (rod3d.relative_kinetic_energy): two cantilevers in one system, one build (the
# second's root at x = 2, where gravity does no work)
BETA_EF = 2 * 0.02 / omega_bending(1, IZ)  # 2 % on the first lag mode
ALPHA_EF = 1.0


@pytest.fixture(scope="module")
def two_ef_cantilevers():
    """The cantilever as an ef beam of 8 elements with beta for 2 % on its first lag mode (the
    flap plane's first mode then has 8 %, the second lag mode 12.5 %), and beside it the same
    cantilever as 4 ef elements damped by alpha alone: D = alpha T_rel, the kinetic energy of
    the rates relative to the frame (translation and the sections' rotary inertia), so
    C = alpha M and every mode decays at alpha / 2, on any mesh."""
    data = cantilever({"beta": BETA_EF}, model={"variant": "ef", "elements": 8},
                      columns={"T": "T", "V": "V", "P": "dissipation", "v": "v(beam, tip)",
                               "v_a": "v(alpha, tip)", "vz_a": "vz(alpha, tip)"})
    data["body"].append(dict(data["body"][0], name="alpha", damping={"alpha": ALPHA_EF},
                             model={"variant": "ef", "elements": 4}))
    data["joint"].append({"name": "root_alpha", "kind": "clamp", "parent": "ground",
                          "point": [2.0, 0.0, 0.0], "child": "alpha.root"})
    return built(data)


@pytest.fixture(scope="module")
def ringing_ef(two_ef_cantilevers):
    """Both ringing for 3 s, Newmark's trapezoidal rule, rows at every step."""
    dt = 2.5e-4
    return run_ok(two_ef_cantilevers, t_end=3.0, dt=dt, integrator="newmark", interval=dt), dt


def test_a_run_time_parameter_of_one_of_two_beams_reaches_that_beam_alone(two_ef_cantilevers):
    """A system with several beams names each one's section values body_<name> (alpha_E): given
    as a run option, alpha_E = 4 E moves the second cantilever's tip by more than 0.1 of its
    peak and the first's by the shared Newton solve's tolerance alone (1e-7 of its peak;
    measured 3.5e-9 over the 1200 steps); a body the system does not have is refused in one
    line."""
    from flexsym.core.errors import SpecError

    kw = dict(t_end=0.3, dt=2.5e-4, integrator="newmark", out_every=40)
    base = run_ok(two_ef_cantilevers, **kw)
    stiff = run_ok(two_ef_cantilevers, params={"alpha_E": 4 * E}, **kw)
    assert np.abs(stiff["v"] - base["v"]).max() <= 1e-7 * np.abs(base["v"]).max()
    assert np.abs(stiff["v_a"] - base["v_a"]).max() > 0.1 * np.abs(base["v_a"]).max()
    with pytest.raises(SpecError, match="nobody_E") as exc:
        run_ok(two_ef_cantilevers, params={"nobody_E": E}, **kw)
    assert "\n" not in str(exc.value)


def test_damped_ef_beams_dissipate_their_damping_power(ringing_ef):
    """E(0) - E(t) = int 2 D dt, D = beta times the elements' strain-rate energy plus alpha
    times their relative kinetic energy (the dissipation output, casadi), the forces -dD/de'
    (system.c, per element): within 1e-3 of what was dissipated (measured 3.0e-5 for the two
    together, as for each alone)."""
    r, _ = ringing_ef
    assert energy_balance(r) < 1e-3


def test_a_damped_ef_beam_decays_as_the_modal_beam(ringing_ef):
    """After the second lag mode has died out (0.3 s), the tip's lag deflection rings about its
    sag with the envelope exp(-beta omega_1^2 t / 2), the rate a modal beam with the same beta
    has on its natural mode (omega_1 of the Euler-Bernoulli cantilever; the rod's own first
    frequency on 8 elements is close to it): within 1 % (measured 3.8e-3)."""
    r, dt = ringing_ef
    m = r.t >= 0.3
    rate = decay_rate(r.t[m], r["v"][m], dt)
    want = BETA_EF * omega_bending(1, IZ)**2 / 2
    assert abs(rate - want) < 0.01 * want, (rate, want)


@pytest.mark.parametrize("column", ["v_a", "vz_a"])
def test_an_alpha_damped_ef_beam_decays_at_half_alpha_in_both_planes(ringing_ef, column):
    """C = alpha M: the tip rings about its sag in both planes with the envelope
    exp(-alpha t / 2), whatever its modes: within 1 % (measured on 4 elements 2.6e-3 in the
    lag plane, where two modes beat, and 1.9e-4 in the flap plane)."""
    r, dt = ringing_ef
    rate = decay_rate(r.t, r[column], dt)
    assert abs(rate - ALPHA_EF / 2) < 0.01 * ALPHA_EF / 2, rate


def test_an_ef_beams_alpha_load_is_its_elements_damping_force_on_rigid_motions():
    """The load a tree joint's reaction takes from the alpha damper (the kind's damping_load:
    -alpha times the momentum of the rates relative to the frame; sympy, the nodes' quaternion
    functions written out) against the element dissipation system.c assembles (casadi: g =
    dD/de' per element, D = alpha rod3d.relative_kinetic_energy) on a rigid virtual translation
    and a rigid virtual rotation of every node and section, at random states of a 3-element
    beam clamped at the origin: F . d = -sum g . de and M . d = -sum g . de, with de of a
    rotation d about the origin d x r on the positions and d/de log(exp(e d) exp(psi)) on the
    rotation vectors (measured within 3.4e-16 of the largest term; without the sections' rotary
    part of the momentum the test fails)."""
    import random

    import casadi as ca

    from flexsym.physics.body_kinds.spatial import kind_of
    from flexsym.physics.rod3d import qlog, qmul, quaternion, relative_kinetic_energy
    from flexsym.physics.spatial_ef import rod_nodes, rod_section

    data = cantilever({"alpha": ALPHA_EF}, model={"variant": "ef", "elements": 3},
                      columns={"Rz": "reaction(root, z)"})
    der = derivation(data)
    beam = der.system.body("beam")
    loads = kind_of(beam).damping_load(der, beam)
    info = der.spatial["beam"]

    def explicit(f):  # node k's quaternion function e_c(psi), written out
        psi = f.args
        t = sp.sqrt(sum(x**2 for x in psi))
        return ([sp.cos(t / 2)] + [sp.sin(t / 2) * x / t for x in psi])[int(f.func.__name__[-1])]
    loads = [sp.Matrix(v).replace(lambda e: isinstance(e, sp.core.function.AppliedUndef)
                                  and e.func.__name__.startswith("rod_beam_e"), explicit).doit()
             for v in loads]
    params = {sym: value for _, sym, value in der.params}
    pvec = ca.DM([value for _, _, value in der.params])
    e, ed = ca.SX.sym("e", 12), ca.SX.sym("ed", 12)
    le, sec = pvec[info["pidx"]["L"]] / info["n"], rod_section(info, pvec)
    g = ca.Function("g", [e, ed], [ca.gradient(ALPHA_EF * relative_kinetic_energy(e, ed, le, sec), ed)])
    eps, d, psi = ca.SX.sym("eps"), ca.SX.sym("d", 3), ca.SX.sym("psi", 3)
    dpsi = ca.jacobian(qlog(qmul(quaternion(eps * d), quaternion(psi))), eps)
    turn = ca.Function("turn", [psi, d], [ca.substitute(dpsi, eps, 0)])
    rng = random.Random(5)
    for _ in range(3):
        q = [rng.uniform(-0.2, 0.2) for _ in der.q]
        qd = [rng.uniform(-1.0, 1.0) for _ in der.q]
        at = params | dict(zip(der.q, q)) | dict(zip(der.qd, qd))
        F, M = (np.array([float(c.xreplace(at)) for c in v]) for v in loads)
        nodes, rates = rod_nodes(info, ca.DM(q), pvec), rod_nodes(info, ca.DM(qd), None)
        for d_ in np.eye(3):
            work_t = work_r = 0.0
            for k in range(info["n"]):
                ek, edk = (ca.evalf(ca.vertcat(v[k], v[k + 1])) for v in (nodes, rates))
                gk = np.array(g(ek, edk)).ravel()
                ends = np.array(ek).ravel()
                shift = np.concatenate([d_, np.zeros(3), d_, np.zeros(3)])
                rot = np.concatenate([np.cross(d_, ends[0:3]), np.array(turn(ends[3:6], d_)).ravel(),
                                      np.cross(d_, ends[6:9]), np.array(turn(ends[9:12], d_)).ravel()])
                work_t -= gk @ shift
                work_r -= gk @ rot
            scale = max(abs(F).max(), abs(M).max())
            assert abs(F @ d_ - work_t) <= 1e-12 * scale and abs(M @ d_ - work_r) <= 1e-12 * scale
