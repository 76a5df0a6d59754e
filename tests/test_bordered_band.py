"""The runtime's bordered band solve (linalg.c: fsr_bordered_*): the nodes of ef beams (spatial
rods or planar ANCF elements) form a band block of the Newton and mass matrices, a joint's or
frame's coordinates a dense border (sysgen._band gives the layout, system.h's bandwidth,
band_first and band_end). The linear algebra against the dense LU on random matrices (a C program, also under the sanitizers), and
whole runs: the same model with its band declaration removed (a copy of its struct with
bandwidth = -1: the dense LU, as before the bordered solve) gives the same rows to round-off,
for every integrator that factors a matrix of the model."""
import ctypes
import subprocess
import tomllib
from pathlib import Path

import numpy as np
import pytest

from flexsym.scenes.system_scene import system_from_dict
from flexsym.sim.inprocess import load_system
from flexsym.toolchain.build import SANITIZE_FLAGS, find_compiler
from flexsym.toolchain.native import SystemStruct
from system_data import with_model
from test_spatial_ef_free import _s6_ef

ROOT = Path(__file__).resolve().parent.parent
FSR_DIVERGED, FSR_SINGULAR = 1, 3  # runtime_c/include/flexsym/runtime.h


@pytest.mark.parametrize("flags", ["-O2", SANITIZE_FLAGS], ids=["optimised", "sanitizers"])
def test_bordered_solve_equals_the_dense_lu(tmp_path, flags):
    """tests/c_models/bordered_check.c: S6's and S7's shapes, a border before and after the
    block, only after it, none (then the band LU's factor and solution bit for bit), an empty
    block; three right-hand sides as the strided columns of the constrained integrators' block
    solve. Measured: 0 to 1.2e-14 of the largest |x|."""
    exe = tmp_path / "bordered_check"
    cc = subprocess.run([find_compiler(), *flags.split(), "-std=c99", f"-I{ROOT / 'runtime_c' / 'src'}",
                         str(ROOT / "tests" / "c_models" / "bordered_check.c"),
                         str(ROOT / "runtime_c" / "src" / "linalg.c"), "-lm", "-o", str(exe)],
                        capture_output=True, text=True)
    if cc.returncode and flags == SANITIZE_FLAGS:
        pytest.skip("the C compiler cannot build with AddressSanitizer/UBSan here")
    assert cc.returncode == 0, cc.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0 and "Sanitizer" not in run.stderr, run.stdout + run.stderr
    assert len(run.stdout.splitlines()) == 8


def test_a_failed_factorization_says_whether_the_newton_iterations_diverged(tmp_path):
    """tests/c_models/factor_failed_check.c calls fsr_factor_failed as genalpha3, ali3p and the
    unconstrained Newton (genalpha, newmark, radau5) do when their matrix will not factor: a
    matrix with a NaN, or one rebuilt after a Newton
    update beyond blowup x L (a user's spatial four-bar on 32 ef elements reached 2.4e99), is
    the iterations diverging (FSR_DIVERGED, reduce --dt); after a small update, or before any,
    the matrix is singular (FSR_SINGULAR)."""
    exe = tmp_path / "factor_failed_check"
    sources = [str(f) for f in sorted((ROOT / "runtime_c" / "src").glob("*.c")) if f.name != "driver.c"]
    cc = subprocess.run([find_compiler(), "-O2", "-std=c99", f"-I{ROOT / 'runtime_c' / 'src'}",
                         f"-I{ROOT / 'runtime_c' / 'include'}",
                         str(ROOT / "tests" / "c_models" / "factor_failed_check.c"), *sources, "-lm",
                         "-o", str(exe)], capture_output=True, text=True)
    assert cc.returncode == 0, cc.stderr
    lines = subprocess.run([str(exe)], capture_output=True, text=True, timeout=60).stdout.splitlines()
    (nan_st, nan_msg), (big_st, big_msg), (small_st, small_msg), (none_st, none_msg) = (
        line.split("|", 1) for line in lines)
    diverged, singular = str(FSR_DIVERGED), str(FSR_SINGULAR)
    assert nan_st == diverged and nan_msg == ("genalpha3: iteration matrix not finite at t = 0.25 s: the "
                                              "Newton iterations diverged; reduce --dt")
    assert big_st == diverged and big_msg == ("genalpha3: iteration matrix singular at t = 0.25 s after a "
                                              "Newton update of 2.4e+99, beyond 10 x L = 5 m: the "
                                              "iterations diverged; reduce --dt")
    assert small_st == none_st == singular
    assert small_msg == none_msg == "genalpha3: iteration matrix singular at t = 0.25 s"


def _bordered_and_dense(data: dict, layout: tuple, runs: list) -> None:
    """The system of scene data `data` declares the band (bandwidth, band_first, band_end) =
    layout; each run (options of batch, params: its parameters) gives the same rows with it as
    with its dense copy, to round-off: the coordinates within 1e-13 m (L = 1 m), the outputs
    within 1e-6 of each one's peak (and 1e-14: an output at round-off, S6's violation)."""
    model = load_system(system_from_dict(data, name=data["system"]["name"]))
    s = SystemStruct.from_address(model.model.value)
    assert (s.bandwidth, s.band_first, s.band_end) == layout and s.nq == len(model.coordinates)
    dense = SystemStruct.from_buffer_copy(s)
    dense.bandwidth = -1
    for options in runs:
        params = {k: [v] for k, v in options.pop("params", {}).items()}
        got = model.batch(params, rows=True, **options)
        model.model = ctypes.c_void_p(ctypes.addressof(dense))
        try:
            want = model.batch(params, rows=True, **options)
        finally:
            model.model = ctypes.c_void_p(ctypes.addressof(s))
        assert got.status == want.status == ["ok"], (options, got.messages, want.messages)
        a, b = got.rows[0], want.rows[0]
        assert a.shape == b.shape and len(a) > 10 and got.row_columns == want.row_columns
        assert np.abs(a - b).max() > 0  # the solve did change (round-off)
        if "violation" in got.row_columns:  # |Phi| / L: round-off on both
            v = got.row_columns.index("violation")
            assert max(a[:, v].max(), b[:, v].max()) <= 1e-12
            a, b = np.delete(a, v, axis=1), np.delete(b, v, axis=1)
        ny = len(model.outputs)  # rows: t, the outputs, the coordinates
        assert np.abs(a[:, 1 + ny:] - b[:, 1 + ny:]).max() <= 1e-13  # m and rad (L = 1 m)
        y, z = a[:, 1:1 + ny], b[:, 1:1 + ny]
        assert (np.abs(y - z).max(axis=0) <= 1e-6 * np.abs(z).max(axis=0) + 1e-14).all(), options


def _ef(data: dict, n: int) -> dict:
    return with_model(data, {"variant": "ef", "elements": n})


def test_s6_ef_bordered_runs_equal_the_dense_ones():
    """S6's strip, 4 elements on the ball joint: the 4 Euler parameters first, a border; the 24
    node coordinates the band. genalpha3 (the study's), ali3p and rk4p (its mass matrix, at its
    stability limit's step): the coordinates within 1e-13 m (measured 3.4e-15, 3.4e-15, 7e-19),
    every output within 1e-6 of its peak (the moments amplify the nodes' round-off by their
    stiffness: 8e-9, 8e-8, 1e-12). ali3p's modified Newton stops anywhere within its tolerance
    (1e-12 m), differently when the round-off differs: it runs full Newton to 1e-14 here."""
    _bordered_and_dense(_s6_ef(4, T="T", V="V", viol="violation"), (11, 4, 28), [
        {"integrator": "genalpha3", "t_end": 0.05, "dt": 1e-4, "out_every": 10, "params": {"bending_inertia": 1e-4}},
        {"integrator": "ali3p", "t_end": 0.02, "dt": 1e-4, "out_every": 10, "params": {"bending_inertia": 1e-4},
         "newton": "full", "newton_tol": 1e-14},
        {"integrator": "rk4p", "t_end": 2e-4, "dt": 1.25e-7, "out_every": 40},
    ])


def test_revolute_ef_bordered_runs_equal_the_dense_ones():
    """A strip of 4 elements on a revolute joint (no constraint: the ODE integrators' Newton
    matrix, newton.c): the joint angle a border of one coordinate. genalpha (one stage; full
    Newton, see above: modified it is 2.4e-9 m from the dense run, its own tolerance's drift
    over 500 steps) and radau5 (three coupled stages, interleaved: a border of three unknowns):
    measured 6e-16 and 7e-15 m, outputs 1e-14 and 8e-13 of their peaks."""
    data = _ef({
        "system": {"name": "ef_revolute", "dimension": 3},
        "body": [{"name": "strip", "kind": "beam", "length": 1.0, "density": 2700.0,
                  "youngs_modulus": 7.0e10, "shear_modulus": 2.6e10, "area": 1.0e-4,
                  "inertia_z": 3.3333e-9, "inertia_y": 2.0833e-10, "torsion_constant": 7.021e-10}],
        "joint": [{"name": "pin", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0, 0.0],
                   "axis": [0.2, 1.0, 0.4], "child": "strip.root"}],
        "gravity": {"g": [0.0, 0.0, -9.81]},
        "output": {"interval": 1e-3, "columns": {"z_tip": "z(strip.tip)", "w_mid": "w(strip, 0.5)",
                                                "th": "angle(pin)"}},
    }, 4)
    _bordered_and_dense(data, (11, 1, 25), [
        {"integrator": "genalpha", "t_end": 0.05, "dt": 1e-4, "out_every": 10, "newton": "full"},
        {"integrator": "radau5", "t_end": 0.05, "dt": 1e-3, "out_every": 1},
    ])


def _scene(name: str, n: int) -> dict:
    with open(ROOT / "scenes" / f"{name}.toml", "rb") as f:
        return _ef(tomllib.load(f), n)


def test_planar_ef_pendulum_bordered_runs_equal_the_dense_ones():
    """S3 with a 4-element planar ef beam (ANCF: 4 coordinates per node, an element spans 8, so
    the half-bandwidth is 7): the pin's angle a border of one coordinate, the 17 node
    coordinates the band. genalpha (full Newton to 1e-14: modified Newton stops anywhere within
    its tolerance, differently when the round-off differs) and radau5: measured 6e-15 and 4e-14 m,
    outputs 4e-13 and 1.1e-11 of their peaks."""
    _bordered_and_dense(_scene("pendulum", 4), (7, 1, 18), [
        {"integrator": "genalpha", "t_end": 0.2, "dt": 1e-4, "out_every": 10, "newton": "full",
         "newton_tol": 1e-14},
        {"integrator": "radau5", "t_end": 0.2, "dt": 1e-3, "out_every": 1},
    ])


def test_planar_ef_slider_crank_bordered_runs_equal_the_dense_ones():
    """S2 with a 4-element planar ef rod: the loop's cut joint at the rod's tip node, its rows
    on the slider's coordinate (a border) and the tip node. The constrained integrators'
    matrices (genalpha3, ali3p at full Newton to 1e-14, rk4p's mass matrix): measured 3e-15,
    7e-15 and 2e-22 m; N_mid, the axial stiffness times the nodes' round-off, 7e-9 and 1.1e-8 of
    its peak, the other outputs 2e-12 at most."""
    _bordered_and_dense(_scene("slider_crank", 4), (7, 2, 19), [
        {"integrator": "genalpha3", "t_end": 0.02, "dt": 1e-4, "out_every": 10},
        {"integrator": "ali3p", "t_end": 0.02, "dt": 1e-4, "out_every": 10, "newton": "full",
         "newton_tol": 1e-14},
        {"integrator": "rk4p", "t_end": 2e-4, "dt": 1e-7, "out_every": 100},
    ])
