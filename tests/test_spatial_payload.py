"""A body hung from a spatial modal beam's marker (physics/body_kinds/spatial/modal._section_frame: the deformed
section's frame at the marker, S = R_z R_y R_x of the section's rotation): a payload clamped to
a strip's tip, at rest against the cantilever formulas, swinging on a tilted pin against the
conservation of energy, run in a plane against the planar derivation, and its C kernels
against casadi against sympy."""
import numpy as np
import pytest

from system_data import built, derivation, run_ok
from test_planar_as_spatial import spatial_twin

RHO, E, A, L, IY, IZ, M, G = 2700.0, 7.0e10, 1.0e-4, 1.0, 2.0833e-10, 3.3333e-9, 0.05, 9.81


def strip_with_payload(name: str, joint: dict, start="static", com=(0.0, 0.0, 0.0), model="m3") -> dict:
    return {"system": {"name": name, "dimension": 3, "start": start},
            "body": [{"name": "strip", "kind": "beam", "length": L, "density": RHO, "youngs_modulus": E,
                      "shear_modulus": 2.6e10, "area": A, "inertia_z": IZ, "inertia_y": IY,
                      "torsion_constant": 7.021e-10, "model": model},
                     {"name": "payload", "kind": "rigid", "mass": M, "inertia": [2e-5, 1e-5, 3e-5],
                      "com": list(com), "markers": {"c": [0.0, 0.0, 0.0]}}],
            "joint": [joint, {"name": "grip", "kind": "clamp", "parent": "strip.tip", "child": "payload.c"}],
            "gravity": {"g": [0.0, 0.0, -G]},
            "output": {"interval": 0.001, "columns": {
                "w": "vz(strip, tip)", "My": "My(strip, root)", "Qz": "Qz(strip, root)",
                "zp": "z(payload.c)", "T": "T", "V": "V", "Rg": "reaction(grip, z)"}}}


def test_a_payload_at_the_tip_of_a_cantilever_at_rest():
    """Clamped along x, started in static equilibrium: the tip sags rho A g L^4 / (8 E I_y) +
    m g L^3 / (3 E I_y) (m3's static mode is the tip's influence function: exact, measured 0),
    the root's shear force from equilibrium is the whole weight (exact), the grip carries the
    payload's weight (exact), the root moment is rho A g L^2 / 2 + m g L less the foreshortened
    arms (5e-4), and nothing moves."""
    r = run_ok(built(strip_with_payload("payload_static", {"name": "root", "kind": "clamp", "parent": "ground",
                                                           "point": [0.0, 0.0, 0.0], "child": "strip.root"})),
               t_end=0.01, dt=1e-4, integrator="genalpha")
    sag = RHO * A * G * L**4 / (8 * E * IY) + M * G * L**3 / (3 * E * IY)
    assert abs(-r["w"][0] - sag) < 1e-12 * sag
    assert abs(r["Qz"][0] + (RHO * A * L + M) * G) < 1e-12 * (RHO * A * L + M) * G
    assert abs(r["Rg"][0] - M * G) < 1e-12 * M * G
    rigid_arm = RHO * A * G * L**2 / 2 + M * G * L
    assert 0 < rigid_arm - r["My"][0] < 1e-3 * rigid_arm
    assert np.abs(r["w"] - r["w"][0]).max() < 1e-12 * sag


@pytest.fixture(scope="module")
def swinging():
    """On a pin tilted out of every coordinate plane, released undeformed; the payload's centre
    of mass off the marker, so its rotation matters; one clamped-free mode per plane and the
    torsion mode (the sympy side of the kernel check grows fast with the modes)."""
    data = strip_with_payload("payload_swing", {"name": "pin", "kind": "revolute", "parent": "ground",
                                                "point": [0.0, 0.0, 0.0], "axis": [0.2, 1.0, 0.4],
                                                "child": "strip.root"},
                              start="undeformed", com=(0.02, 0.01, -0.01),
                              model={"strain": "linear", "axial": [], "bending": ["cf1"]})
    return data, built(data)


def test_a_swinging_payload_conserves_energy(swinging):
    """Nothing dissipates: T + V keeps its start to the integrator's error, falling with the step
    (Newmark, Newton to 1e-14; measured 3.7e-8 and 1.1e-8 of (m_strip + m) g L / 2 at 0.2 and
    0.1 ms; with m3's modes 5.7e-8 and 9.6e-9) while the strip swings down most of its length."""
    errs = []
    for dt in (2e-4, 1e-4):
        r = run_ok(swinging[1], t_end=1.0, dt=dt, integrator="newmark", newton_tol=1e-14)
        E_ = r["T"] + r["V"]
        errs.append(np.abs(E_ - E_[0]).max() / ((RHO * A * L + M) * G * L / 2))
    assert errs[1] < 2e-8 and errs[0] / errs[1] > 3
    assert r["zp"].min() < -0.5


def test_payload_kernels_c_casadi_sympy(swinging, system_kernels_agree):
    data, b = swinging
    system_kernels_agree(derivation(data), b, t=0.3, seed=7)


@pytest.mark.study  # half a minute: two builds; S1 and S3 run as spatial in the default suite
def test_a_planar_payload_run_as_spatial_reproduces_the_planar_rows():
    """A strip on a pin with a payload clamped to its tip (centre of mass off the marker),
    swinging in the plane under gravity: the spatial twin's section rotation in a plane is the
    planar tangent angle, so every column agrees within 1e-9 of its peak. m3's strain with two of
    its modes (static, cp1: both turn the tip section; m3's three made each build 2.5 times as
    long for the same check)."""
    planar = {"system": {"name": "payload_planar"},
              "body": [{"name": "strip", "kind": "beam", "length": L, "density": RHO, "youngs_modulus": E,
                        "area": A, "inertia": IZ,
                        "model": {"strain": "foreshortening", "axial": [], "bending": ["static", "cp1"]}},
                       {"name": "payload", "kind": "rigid", "mass": M, "inertia": 3e-5, "com": [0.02, 0.01],
                        "markers": {"c": [0.0, 0.0]}}],
              "joint": [{"name": "pin", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0],
                         "child": "strip.root"},
                        {"name": "grip", "kind": "clamp", "parent": "strip.tip", "child": "payload.c"}],
              "gravity": {"g": [0.0, -G]},
              "output": {"columns": {"v_tip": "v(strip, tip)", "x_p": "x(payload.c)", "y_p": "y(payload.c)",
                                     "M_mid": "M(strip, 0.5)", "phi": "angle(pin)"}}}
    twin = spatial_twin(planar)
    kw = dict(t_end=0.5, dt=1e-4, integrator="genalpha")
    a, b = run_ok(built(planar), **kw), run_ok(built(twin), **kw)
    for col in planar["output"]["columns"]:
        assert np.abs(b[col] - a[col]).max() <= 1e-9 * np.abs(a[col]).max(), col
