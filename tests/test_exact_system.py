"""A beam with exact kinematics (strain model `exact`) as a body of a planar system
(physics/exact_body.py): the guided hub run as a system equals the one-beam `exact` model to
round-off; the Newton Jacobians (d'Alembert's residual) are the derivatives of Lagrange's
M q'' - f; a free pendulum conserves T + V; what is not derived is refused in one line."""
from __future__ import annotations

import numpy as np
import pytest

from flexsym.codegen.sysgen import build_system_kernels
from flexsym.physics.assemble import derive_system
from flexsym.scenes.system_scene import system_from_dict
from system_data import built, run_ok, scene_text_refused

BENDING = ["cf1", "cf2"]
EXACT = {"strain": "exact", "bending": BENDING}  # N and M from equilibrium (the default)
BLADE = {"name": "blade", "kind": "beam", "length": 10.0, "density": 3000.0, "youngs_modulus": 7.0e10,
         "area": 4.0e-4, "inertia": 2.0e-7, "markers": {"b": 5.0}, "model": EXACT}


def hub(name: str) -> dict:
    return {"system": {"name": name},
            "body": [{"name": "hub", "kind": "rigid", "mass": 1.0, "inertia": 1.0,
                      "markers": {"centre": [0.0, 0.0]}}, BLADE],
            "joint": [{"name": "hub_joint", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0],
                       "child": "hub.centre"},
                      {"name": "clamp", "kind": "clamp", "parent": "hub.centre", "child": "blade.root"}],
            "driver": [{"name": "spin", "kind": "guided", "joint": "hub_joint", "maneuver": "spin-up",
                        "omega": 6.0, "duration": 15.0}],
            "output": {"interval": 0.01, "columns": {
                "v_tip": "v(blade, tip)", "u_tip": "u(blade, tip)", "N_A": "N(blade, root)",
                "M_A": "M(blade, root)", "N_B": "N(blade, b)", "M_B": "M(blade, b)"}}}


def test_the_guided_hub_as_a_system_is_the_one_beam_exact_model():
    """S0's spin-up (omega_s = 6, 15 s) over 8 s: the system's exact body (Lagrange on its
    quadrature T, the frame's motion from the hub joint; N and M from the equilibrium of the
    part beyond, over its quadrature) and the one-beam `exact` model (d'Alembert in the guided
    frame, its own kernels) give the same rows to round-off."""
    from flexsym.apps.api import simulate, variant

    sys_rows = run_ok(built(hub("hub_exact2")), t_end=8.0, dt=5e-3, integrator="genalpha")
    one = simulate(variant("exact", bending=",".join(BENDING), outputs="v_tip,u_tip,N_A,M_A,N_B,M_B"),
                   t_end=8.0, dt=5e-3, integrator="genalpha")
    for c in ("v_tip", "u_tip", "N_A", "M_A", "N_B", "M_B"):
        ref = np.asarray(one[c])
        assert np.abs(sys_rows[c] - ref).max() <= 1e-12 * np.abs(ref).max(), c
    assert np.abs(sys_rows["v_tip"]).max() > 0.1  # it deflects


PENDULUM = {"system": {"name": "exact_pendulum"},
            "body": [{**BLADE, "length": 1.0, "area": 1.0e-4, "inertia": 2.0833e-10, "density": 2700.0,
                      "markers": {"mid": 0.5}, "model": {**EXACT, "axial": ["ff1"]}}],
            "joint": [{"name": "pin", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0],
                       "child": "blade.root", "initial": 0.3}],
            "gravity": {"g": [0.0, -9.81]},
            "output": {"interval": 0.001, "columns": {"T": "T", "V": "V", "x_tip": "x(blade.tip)"}}}


# S4's blade as a pendulum: two sections (modes from 10 elements), a tip mass, gravity
STEPPED = {**PENDULUM, "body": [{"name": "blade", "kind": "beam", "elements": 10, "segments": [
    {"length": 0.5, "density": 2700.0, "youngs_modulus": 7.0e10, "area": 1.0e-4, "inertia": 2.0833e-10},
    {"length": 0.5, "density": 2700.0, "youngs_modulus": 7.0e10, "area": 0.5e-4, "inertia": 0.5e-10}],
    "point_masses": [{"x": 1.0, "mass": 0.05}], "markers": {"mid": 0.5}, "model": {**EXACT, "axial": ["ff1"]}}]}


@pytest.mark.parametrize("system", [PENDULUM, STEPPED], ids=["uniform", "stepped_tip_mass"])
def test_newton_jacobians_are_the_derivatives_of_lagrange_equations(system):
    """A free pendulum under gravity (frame moved by its pin, exact bending and an axial mode;
    uniform, or S4's stepped section with a tip mass from finite-element data): the residual
    Jacobian kernel, built from d'Alembert's residual on the quadrature points (and the point
    mass), against central differences of Lagrange's M(q) q'' - f(q, q') at random states; the
    one-pass residual kernel against that M q'' - f itself."""
    der = derive_system(system_from_dict(system, name="exact_pendulum"))
    k = {kk.name: kk.function for kk in build_system_kernels(der)}
    n = len(der.q)
    p = np.array([v for _, _, v in der.params])
    rnd = np.random.default_rng(3)
    for _ in range(3):
        q, qd, qdd = rnd.uniform(-0.3, 0.3, n), rnd.uniform(-2, 2, n), rnd.uniform(-5, 5, n)
        q[1:] *= 0.05  # elastic amplitudes (m) on a 1 m beam: rotations of ~0.3 rad

        def r(q_, qd_):
            M = np.array(k["mass"](q_, [0.0], p))
            return M @ qdd - np.array(k["force"](q_, qd_, [0.0], p)).ravel()
        dq, dqd = (np.array(v) for v in k["residual_jac"](q, qd, qdd, [0.0], p))
        one_pass = np.array(k["residual"](q, qd, qdd, [0.0], p)).ravel()  # what genalpha iterates on
        assert np.abs(one_pass - r(q, qd)).max() <= 1e-10 * np.abs(r(q, qd)).max()
        h = 1e-5  # the axial stiffness (EA/L ~ 7e6) puts f's rounding at 1e-16 |f| / h
        fd_q = np.column_stack([(r(q + h * e, qd) - r(q - h * e, qd)) / (2 * h) for e in np.eye(n)])
        fd_qd = np.column_stack([(r(q, qd + h * e) - r(q, qd - h * e)) / (2 * h) for e in np.eye(n)])
        assert np.abs(dq - fd_q).max() <= 1e-6 * np.abs(fd_q).max()
        assert np.abs(dqd - fd_qd).max() <= 1e-6 * np.abs(fd_qd).max()


def test_a_free_exact_pendulum_conserves_energy():
    """Released at 0.3 rad, nothing dissipates: T + V (the quadrature T and gravity of the
    deformed beam) keeps its start to rk4's error, falling at order 4 with the step."""
    b = built(PENDULUM)
    errs = []
    for dt in (2e-5, 1e-5):
        r = run_ok(b, t_end=0.2, dt=dt, integrator="rk4")
        E = r["T"] + r["V"]
        errs.append(np.abs(E - E[0]).max() / (2700.0 * 1e-4 * 9.81 * 0.5))
    assert errs[1] < 1e-9 and errs[0] / errs[1] > 10
    assert np.ptp(r["x_tip"]) > 0.01  # it swings


SCENE = """
[system]
name = "exact_bad"

[[body]]
name = "arm"
kind = "beam"
length = 1.0
density = 2700.0
youngs_modulus = 7.0e10
area = 1.0e-4
inertia = 2.0833e-10
markers = {{ mid = 0.5 }}
model = {model}
{damping}
[[body]]
name = "bob"
kind = "rigid"
mass = 0.1
inertia = 1e-4
markers = {{ c = [0.0, 0.0] }}

[[joint]]
name = "pin"
kind = "revolute"
parent = "ground"
point = [0.0, 0.0]
child = "arm.root"
{joint}
[solver]
t_end = 0.01

[output]
columns = {{ y = "{output}" }}
"""
OK_MODEL = '{ strain = "exact", bending = ["cf1"], moment = "constitutive" }'
HANG = '\n[[joint]]\nname = "hang"\nkind = "revolute"\nparent = "arm.tip"\nchild = "bob.c"\n'
ELSEWHERE = '\n[[joint]]\nname = "hang"\nkind = "revolute"\nparent = "ground"\npoint = [2.0, 0.0]\nchild = "bob.c"\n'


FORCE = '\n[[load]]\nkind = "force"\nmarker = "arm.mid"\nfx = 1.0\nfy = 0.0\n'


@pytest.mark.parametrize("model, damping, joint, output, says", [
    (OK_MODEL, "", ELSEWHERE, "momentum", "output 'momentum' needs its momentum"),
    (OK_MODEL, "", ELSEWHERE, "reaction(pin, x)", "output 'reaction(pin, x)' needs its momentum"),
    # a body hanging from it and a force on it are derived (test_exact_hanging.py), not these
    (OK_MODEL, "", HANG + FORCE, "momentum", "output 'momentum' needs its momentum"),
    (OK_MODEL, "", HANG + FORCE, "reaction(pin, y)", "output 'reaction(pin, y)' needs its momentum"),
])
def test_what_is_not_derived_is_refused_in_one_line(tmp_path, capsys, model, damping, joint, output, says):
    scene_text_refused(tmp_path, capsys, SCENE.format(model=model, damping=damping, joint=joint, output=output),
                       says)


def test_a_point_mass_with_rotary_inertia_is_refused(tmp_path, capsys):
    """A body from finite-element data runs with exact kinematics, but not a point mass's
    rotary inertia (its section's rotation rate is not in T yet)."""
    text = SCENE.format(model=OK_MODEL, damping="", joint=ELSEWHERE, output="v(arm, tip)")
    text = text.replace("length = 1.0\ndensity = 2700.0\nyoungs_modulus = 7.0e10\narea = 1.0e-4\n"
                        "inertia = 2.0833e-10\n",
                        "elements = 4\nsegments = [{ length = 1.0, density = 2700.0, youngs_modulus = 7.0e10, "
                        "area = 1.0e-4, inertia = 2.0833e-10 }]\n"
                        "point_masses = [{ x = 1.0, mass = 0.01, rotary = 1e-6 }]\n")
    scene_text_refused(tmp_path, capsys, text, "nor with a point mass's rotary inertia")
