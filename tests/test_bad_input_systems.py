"""Bad input on the newer surfaces (issue 18): system and one-beam scenes, finite-element files,
the Python API (kernels, batch, argument types) and the build cache. Each case is refused in
one line naming the file/key/argument, exit 2 on the command line, before any work: nothing
written, no build (the build cache stays empty)."""
from __future__ import annotations

import math
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from flexsym.apps import api
from flexsym.apps.cli import main
from flexsym.core.errors import SpecError
from flexsym.model.limits import MAX_BODIES, MAX_FILE_BYTES, MAX_JOINTS
from flexsym.model.system import Driver, Gravity, Joint, Marker, Output, RigidBody, System

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "scenes"
BASE = (SCENES / "slider_crank.toml").read_text()
PAPER = (SCENES / "paper.toml").read_text()
STEPPED = (SCENES / "stepped_blade.toml").read_text()
GUIDED = ('[[driver]]\nname = "crank_drive"\nkind = "guided"\njoint = "crank_joint"\n'
          'maneuver = "spin-up"   # P(t; 150 rad/s, 0.1 s)\nomega = 150.0\nduration = 0.1\n')
MOTOR = '[[driver]]\nname = "crank_drive"\nkind = "motor"\njoint = "crank_joint"\ntorque = "{}"\n'
SPRING = '\n[[load]]\nkind = "spring"\na = "crank.tip"\nb = "slider.pin"\nk = {k}\nc = {c}\n'
FORCE = '\n[[load]]\nkind = "force"\nmarker = "crank.tip"\nfx = {fx}\nfy = 0.0\n'
TORQUE = '\n[[load]]\nkind = "torque"\nname = "brake"\nbody = "crank"\ntorque = "{}"\n'
COLUMNS = 'columns = { x_s = "x(slider.pin)", w_mid = "w(rod, mid)", N_mid = "N(rod, mid)" }'


def _chain(n: int) -> str:
    """n rigid links in a chain of revolute joints (a valid system but for its size)."""
    out = []
    for k in range(n):
        out.append(f'[[body]]\nname = "l{k}"\nkind = "rigid"\nmass = 1.0\ninertia = 0.1\n'
                   'markers = { a = [0.0, 0.0], b = [1.0, 0.0] }\n')
        parent = 'parent = "ground"\npoint = [0.0, 0.0]' if k == 0 else f'parent = "l{k - 1}.b"'
        out.append(f'[[joint]]\nname = "j{k}"\nkind = "revolute"\n{parent}\nchild = "l{k}.a"\n')
    return "\n".join(out) + '\n[solver]\ndt = 1e-3\nt_end = 1.0\n[output]\ncolumns = { a = "angle(j0)" }\n'


# (case, scene text, what the one line must say)
SYSTEM_CASES = [
    # huge finite numbers: one magnitude check before any work
    ("gravity_1e308", BASE + "\n[gravity]\ng = [0.0, -1e308]\n", "g[1] = -1e+308 is beyond the limit"),
    ("gravity_x_1e20", BASE + "\n[gravity]\ng = [1e20, 0.0]\n", "g[0] = 1e+20 is beyond the limit"),
    ("mass_1e308", BASE.replace("mass = 0.1 ", "mass = 1e308 "), "body 'crank' mass = 1e+308 is beyond"),
    ("slider_mass_1e200", BASE.replace("mass = 0.033377851148064755", "mass = 1e200"), "body 'slider' mass = 1e+200"),
    ("inertia_1e50", BASE.replace("inertia = 1.0e-4 ", "inertia = 1e50 "), "body 'crank' inertia = 1e+50"),
    ("com_1e200", BASE.replace("com = [0.075, 0.0]", "com = [1e200, 0.0]"), "body 'crank' com[0] = 1e+200"),
    ("com_y_1e14", BASE.replace("com = [0.075, 0.0]", "com = [0.075, -1e14]"), "body 'crank' com[1]"),
    ("youngs_modulus_1e300", BASE.replace("youngs_modulus = 2.0e11", "youngs_modulus = 1e300"), "body 'rod' section E = 1e+300"),
    ("density_1e100", BASE.replace("density = 7870.0", "density = 1e100"), "body 'rod' section rho = 1e+100"),
    ("beam_length_1e30", BASE.replace("length = 0.3", "length = 1e30"), "body 'rod' length = 1e+30"),
    ("spring_k_1e308", BASE + SPRING.format(k="1e308", c="0.0"), "k = 1e+308 is beyond"),
    ("spring_c_1e250", BASE + SPRING.format(k="1.0", c="1e250"), "c = 1e+250 is beyond"),
    ("force_1e308", BASE + FORCE.format(fx="1e308"), "fx = 1e+308 is beyond"),
    ("force_negative_1e100", BASE + FORCE.format(fx="-1e100"), "fx = -1e+100 is beyond"),
    ("ground_point_1e20", BASE.replace('point = [0.0, 0.0]\nchild = "crank.root"', 'point = [1e20, 0.0]\nchild = "crank.root"'),
     "joint 'crank_joint' point[0] = 1e+20"),
    ("joint_offset_1e15", BASE.replace('child = "rod.root"', 'child = "rod.root"\noffset = 1e15'), "joint 'crank_pin' offset = 1e+15"),
    ("joint_initial_1e200", BASE.replace("initial = 0.45", "initial = 1e200"), "joint 'slide' initial = 1e+200"),
    ("marker_1e50", BASE.replace("tip = [0.15, 0.0]", "tip = [1e50, 0.0]"), "body 'crank' markers[1] x = 1e+50"),
    ("omega_1e300", BASE.replace("omega = 150.0", "omega = 1e300"), "driver 'crank_drive' params ws = 1e+300"),
    # tiny positive quantities: their reciprocal powers would overflow
    ("mass_1e-300", BASE.replace("mass = 0.1 ", "mass = 1e-300 "), "body 'crank': mass = 1e-300 must be >= 1e-20"),
    ("inertia_1e-30", BASE.replace("inertia = 1.0e-6 ", "inertia = 1e-30 "), "body 'slider': inertia = 1e-30 must be"),
    ("area_1e-25", BASE.replace("area = 2.8274333882308137e-5", "area = 1e-25"), "body 'rod': section A = 1e-25"),
    ("beam_length_1e-300", BASE.replace("length = 0.3", "length = 1e-300").replace("mid = 0.15", "mid = 0.0"),
     "body 'rod': length = 1e-300 must be >= 1e-20"),
    # long chains: refused by count before derivation
    ("chain_just_over", _chain(MAX_BODIES + 1), f"[[body]]: {MAX_BODIES + 1} entries, more than the limit"),
    ("joints_over_limit", BASE + "".join(f'\n[[joint]]\nname = "extra{k}"\nkind = "revolute"\nparent = "crank.tip"\n'
                                         f'child = "slider.pin"\n' for k in range(MAX_JOINTS - 3)),
     f"[[joint]]: {MAX_JOINTS + 1} entries, more than the limit of {MAX_JOINTS}"),
    ("chain_of_100", _chain(100), f"[[body]]: 100 entries, more than the limit of {MAX_BODIES}"),
    ("chain_of_5000", _chain(5000), f"[[body]]: 5000 entries, more than the limit of {MAX_BODIES}"),
    # prismatic axis shorter than the tolerance
    ("axis_1e-300", BASE.replace("axis = [1.0, 0.0]", "axis = [1e-300, 0.0]"), "joint 'slide': axis [1e-300, 0.0] is shorter"),
    ("axis_1e-8", BASE.replace("axis = [1.0, 0.0]", "axis = [1e-8, 1e-8]"), "joint 'slide': axis"),
    # initial on a clamp is refused, not ignored
    ("clamp_initial", BASE.replace('kind = "revolute"\nparent = "crank.tip"', 'kind = "clamp"\ninitial = 0.2\nparent = "crank.tip"'),
     "[[joint]] 'crank_pin' initial: applies to revolute and prismatic joints only"),
    ("clamp_initial_zero", BASE.replace('kind = "revolute"\nparent = "crank.tip"', 'kind = "clamp"\ninitial = 0.0\nparent = "crank.tip"'),
     "[[joint]] 'crank_pin' initial"),
    # output column names against every column of the results
    ("column_is_a_joint", BASE.replace(COLUMNS, COLUMNS.replace("x_s =", "slide =")),
     "output column 'slide' is already the name of joint 'slide'"),
    ("column_is_a_guided_joint", BASE.replace(COLUMNS, COLUMNS.replace("x_s =", "crank_joint =")),
     "output column 'crank_joint' is already the name of joint"),
    ("column_is_a_modal_coordinate", BASE.replace(COLUMNS, COLUMNS.replace("x_s =", "rod_v_cp1 =")),
     "output column 'rod_v_cp1' is already the name of an elastic coordinate of 'rod'"),
    ("column_is_violation", BASE.replace(COLUMNS, COLUMNS.replace("x_s =", "violation =")),
     "output column 'violation' is already the name of the constraint violation"),
    ("column_is_energy_h", BASE.replace(COLUMNS, COLUMNS.replace("x_s =", "h =")), "output column 'h'"),
    ("column_T_for_another_quantity", BASE.replace(COLUMNS, COLUMNS.replace("x_s =", "T =")), "output column 'T'"),
    # motor and torque-load laws: poles and overflow found now, naming the driver/load
    ("motor_pole", BASE.replace(GUIDED, MOTOR.format("1/(t - 0.1)")), "driver 'crank_drive' torque = '1/(t - 0.1)': singular"),
    ("motor_overflow", BASE.replace(GUIDED, MOTOR.format("exp(3000*t)")), "driver 'crank_drive' torque = 'exp(3000*t)' is not real and finite"),
    ("motor_pole_at_initial_state", BASE.replace(GUIDED, MOTOR.format("1/crank_joint")), "driver 'crank_drive' torque = '1/crank_joint'"),
    ("motor_log_negative", BASE.replace(GUIDED, MOTOR.format("log(t - 0.2)")), "driver 'crank_drive' torque"),
    ("motor_huge_constant", BASE.replace(GUIDED, MOTOR.format("1e200*1e200")), "driver 'crank_drive' torque = '1e200*1e200': the constant"),
    ("torque_load_pole", BASE + TORQUE.format("1/(t - 0.05)**2"), "load brake torque = '1/(t - 0.05)**2': singular"),
]


def _assert_refused(rc, err, path, says, tmp_path, before, cache):
    assert rc == 2, err
    assert err.count("\n") == 1 and err.startswith(f"flexsym: error: {path}: "), err
    assert says in err, err
    assert "Traceback" not in err
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir() if p.is_file()} == before
    assert not cache.exists() or not any(cache.iterdir()), "work started: the build cache was written"


@pytest.fixture
def empty_cache(tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    monkeypatch.setenv("FLEXSYM_CACHE", str(cache))
    return cache


def _run_refused(tmp_path, capsys, scene, says, cache, args=()):
    out = tmp_path / "out.csv"
    out.write_bytes(b"t,x_s\n0,1\n")
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir() if p.is_file()}
    rc = main(["run", str(scene), "--out", str(out), *args])
    _assert_refused(rc, capsys.readouterr().err, scene, says, tmp_path, before, cache)


@pytest.mark.parametrize("case, text, says", SYSTEM_CASES, ids=[c[0] for c in SYSTEM_CASES])
def test_bad_system_scene_is_refused_before_any_work(tmp_path, capsys, empty_cache, case, text, says):
    assert text != BASE, case
    scene = tmp_path / f"{case}.toml"
    scene.write_text(text)
    _run_refused(tmp_path, capsys, scene, says, empty_cache)


BEAM_CASES = [
    ("length_1e200", PAPER, "length = 10.0 ", "length = 1e200 ", "[beam] length: 1e+200 is beyond the limit"),
    ("density_1e308", PAPER, "density = 3000.0 ", "density = 1e308 ", "[beam] density: 1e+308"),
    ("E_1e100", PAPER, "youngs_modulus = 7.0e10", "youngs_modulus = 1e100", "[beam] youngs_modulus"),
    ("length_1e-300", PAPER, "length = 10.0 ", "length = 1e-300 ", "[beam] length: 1e-300 is below the limit 1e-20"),
    ("inertia_1e-40", PAPER, "inertia = 2.0e-7 ", "inertia = 1e-40 ", "[beam] inertia: 1e-40 is below"),
    ("segment_inertia_1e-300", STEPPED, "inertia = 5.0e-8", "inertia = 1e-300", "[body] segments[1] inertia"),
    ("segment_density_1e300", STEPPED, "density = 3000.0, youngs_modulus = 7.0e10, area = 2.0e-4",
     "density = 1e300, youngs_modulus = 7.0e10, area = 2.0e-4", "[body] segments[1] density"),
    ("point_mass_1e200", STEPPED, "mass = 0.5", "mass = 1e200", "[body] point_masses[0] mass"),
]


@pytest.mark.parametrize("case, base, old, new, says", BEAM_CASES, ids=[c[0] for c in BEAM_CASES])
def test_bad_one_beam_scene_is_refused_before_any_work(tmp_path, capsys, empty_cache, case, base, old, new, says):
    assert base.count(old) == 1, case
    scene = tmp_path / f"{case}.toml"
    scene.write_text(base.replace(old, new))
    _run_refused(tmp_path, capsys, scene, says, empty_cache)


def test_scene_file_that_never_ends_is_refused(tmp_path, capsys, empty_cache):
    """A FIFO (nobody writes: reading would wait forever) and /dev/zero (never ends)."""
    fifo = tmp_path / "fifo.toml"
    os.mkfifo(fifo)
    _run_refused(tmp_path, capsys, fifo, "not a regular file", empty_cache)
    zero = tmp_path / "zero.toml"
    zero.symlink_to("/dev/zero")
    _run_refused(tmp_path, capsys, zero, "not a regular file", empty_cache)


def test_huge_scene_file_is_refused_unread(tmp_path, capsys, empty_cache):
    big = tmp_path / "big.toml"
    with open(big, "wb") as fh:  # sparse: the size is checked before reading
        fh.truncate(MAX_FILE_BYTES + 1)
    _run_refused(tmp_path, capsys, big, f"larger than the limit of {MAX_FILE_BYTES} bytes", empty_cache)


# ----- finite-element folders: sizes checked before allocating, files read with limits ---------
@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    from flexsym.scenes.feimport import write_folder
    from flexsym.model.fedata import BeamBody, PointMass, Section

    inner = Section(7.0e10, 3000.0, 4.0e-4, 2.0e-7)
    folder = tmp_path_factory.mktemp("fe") / "blade"
    write_folder(BeamBody.from_segments([(5.0, inner), (5.0, inner)], 4, (PointMass(10.0, 0.5),)), folder)
    return folder


def _corrupt_fe(folder: Path, case: str) -> tuple[str, str]:
    m = folder / "M.mtx"
    if case == "header_1e6":
        m.write_text("%%MatrixMarket matrix coordinate real general\n1000000 1000000 1\n1 1 1.0\n")
        return "M.mtx", "is 1000000 x 1000000; the dof map has 12 dofs"
    if case == "array_header_1e6":
        m.write_text("%%MatrixMarket matrix array real general\n1000000 1000000\n1.0\n")
        return "M.mtx", "is 1000000 x 1000000"
    if case == "too_many_entries":
        m.write_text("%%MatrixMarket matrix coordinate real general\n12 12 100000000\n1 1 1.0\n")
        return "M.mtx", "declares 100000000 entries"
    if case == "mtx_fifo":
        m.unlink()
        os.mkfifo(m)
        return "M.mtx", "not a regular file"
    if case == "mtx_dev_zero":
        m.unlink()
        m.symlink_to("/dev/zero")
        return "M.mtx", "not a regular file"
    if case == "mtx_directory":
        m.unlink()
        m.mkdir()
        return "M.mtx", "not a regular file"
    if case == "body_toml_fifo":
        (folder / "body.toml").unlink()
        os.mkfifo(folder / "body.toml")
        return "body.toml", "not a regular file"
    if case == "too_many_nodes":
        text = (folder / "body.toml").read_text()
        start = text.index("nodes = [")
        end = text.index("]", start)
        nodes = ", ".join(repr(0.001 * k) for k in range(3000))
        (folder / "body.toml").write_text(text[:start] + f"nodes = [{nodes}]" + text[end + 1:])
        return "body.toml", "3000 nodes: more than the limit of 2001"
    raise AssertionError(case)


FE_CASES = ("header_1e6", "array_header_1e6", "too_many_entries", "mtx_fifo", "mtx_dev_zero", "mtx_directory",
            "body_toml_fifo", "too_many_nodes")


@pytest.mark.parametrize("case", FE_CASES)
def test_bad_fe_files_are_refused_before_allocating(case, exported, tmp_path, capsys, empty_cache, monkeypatch):
    folder = tmp_path / "blade"
    shutil.copytree(exported, folder)
    name, says = _corrupt_fe(folder, case)
    scene = tmp_path / "scene.toml"
    start, end = STEPPED.index("[body]"), STEPPED.index("[maneuver]")
    scene.write_text(STEPPED[:start] + '[body]\nfolder = "blade"\n\n' + STEPPED[end:])
    monkeypatch.chdir(tmp_path)
    rc = main(["run", str(scene), "--out", "out.csv"])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.count("\n") == 1 and f"blade/{name}" in err and says in err, err
    assert not (tmp_path / "out.csv").exists()
    assert not empty_cache.exists() or not any(empty_cache.iterdir())


# ----- the Python API: Python-built systems, argument types -----------------------------------
def _pendulum(**joint):
    link = RigidBody("link", 1.0, 0.1, markers=(Marker("pin", 0.0), Marker("tip", 1.0)))
    j = Joint("pin", **({"kind": "revolute", "parent": "ground", "child": "link.pin"} | joint))
    return System("pend", (link,), (j,), outputs=(Output("a", "x(link.tip)"),))


def _pendulum_with(**fields):
    from dataclasses import replace

    return replace(_pendulum(), **fields)


def test_api_system_refuses_huge_numbers_bools_and_chains(empty_cache):
    with pytest.raises(SpecError, match=r"body 'link' mass = 1e\+308 is beyond"):
        api.system(System("pend", (RigidBody("link", 1e308, 0.1, markers=(Marker("pin", 0.0),)),),
                          (Joint("pin", "revolute", "ground", "link.pin"),), outputs=(Output("a", "T"),)))
    with pytest.raises(SpecError, match=r"joint 'pin' initial must be a real number \(got bool"):
        api.system(_pendulum(initial=True))
    with pytest.raises(SpecError, match=r"joint 'pin' point\[0\] must be a real number \(got complex"):
        api.system(_pendulum(point=(1j, 0.0)))
    with pytest.raises(SpecError, match=r"joint 'pin' point\[1\] must be a real number \(got str"):
        api.system(_pendulum(point=(0.0, "1")))
    with pytest.raises(SpecError, match=r"joint 'pin' offset must be finite \(got nan"):
        api.system(_pendulum(offset=float("nan")))
    with pytest.raises(SpecError, match=r"load '#1' g must be a real number \(got NoneType"):
        api.system(_pendulum_with(loads=(Gravity(None),)))
    with pytest.raises(SpecError, match="body entries must be RigidBody or FlexibleBeam"):
        api.system(System("p", ("link",), (), outputs=()))
    with pytest.raises(SpecError, match="load entries must be Gravity or PointForce"):
        api.system(_pendulum_with(loads=({"g": [0.0, -9.81]},)))
    with pytest.raises(SpecError, match=r"driver 'm' torque = '1/pin_rate' is infinite or undefined"):
        api.system(_pendulum_with(drivers=(Driver("m", "motor", "pin", expression="1/pin_rate"),)))
    with pytest.raises(SpecError, match="initial applies to revolute and prismatic joints only"):
        api.system(_pendulum(kind="clamp", initial=0.3))
    n = MAX_BODIES + 1
    bodies = tuple(RigidBody(f"l{k}", 1.0, 0.1, markers=(Marker("a", 0.0), Marker("b", 1.0))) for k in range(n))
    joints = tuple(Joint(f"j{k}", "revolute", "ground" if k == 0 else f"l{k - 1}.b", f"l{k}.a") for k in range(n))
    with pytest.raises(SpecError, match=f"{n} bodies, more than the limit of {MAX_BODIES}"):
        api.system(System("chain", bodies, joints, outputs=(Output("a", "angle(j0)"),)))
    with pytest.raises(SpecError, match="output column 'pin' is already the name of joint 'pin'"):
        api.system(System("pend", _pendulum().bodies, _pendulum().joints, outputs=(Output("pin", "angle(pin)"),)))
    assert not empty_cache.exists() or not any(empty_cache.iterdir())


@pytest.mark.parametrize("call, says", [
    (lambda: api.load_scene(42), "load_scene(): path must be the path of a .toml scene (got int"),
    (lambda: api.run(3.5), "scene must be"),
    (lambda: api.run(None), "scene must be"),
    (lambda: api.system("pendulum"), "system(): data must be a dict"),
    (lambda: api.system([1, 2]), "system(): data must be a dict"),
    (lambda: api.system({}, t_end=True), "system(): t_end must be a finite number > 0"),
    (lambda: api.variant(7), "variant(): name_or_spec must be a variant name"),
    (lambda: api.kernels(None), "target must be a variant name"),
    (lambda: api.inprocess(3.5), "target must be a variant name"),
    (lambda: api.simulate([1]), "target must be a variant name"),
    (lambda: api.inspect("m1", sections=5), "inspect(): sections must be a string"),
    (lambda: api.inspect("m1", sections=[None]), "unknown section"),
], ids=["load_scene_int", "run_float", "run_none", "system_str", "system_list", "system_t_end_bool",
        "variant_int", "kernels_none", "inprocess_float", "simulate_list", "inspect_int", "inspect_none"])
def test_api_misuse_is_one_spec_error_naming_the_argument(call, says, empty_cache):
    with pytest.raises(SpecError) as info:
        call()
    assert says in str(info.value) and "\n" not in str(info.value)
    assert not empty_cache.exists() or not any(empty_cache.iterdir())


# ----- compiled kernels and the in-process batch: arrays checked at the boundary ---------------
@pytest.fixture(scope="module")
def m1_kernels():
    return api.kernels("m1")


@pytest.mark.parametrize("method, args, says", [
    ("mass", lambda n, p: (np.zeros(n - 1),), "fsm_geometric_mass: q has {m} values, expected {n}"),
    ("mass", lambda n, p: (np.zeros(n + 3),), "fsm_geometric_mass: q has"),
    ("mass", lambda n, p: ([0.0] * (n - 1) + [math.nan],), "fsm_geometric_mass: q has a value that is not finite"),
    ("mass", lambda n, p: (np.zeros(n, dtype=complex),), "fsm_geometric_mass: q must hold real numbers"),
    ("mass", lambda n, p: (np.zeros(n, dtype=bool),), "fsm_geometric_mass: q must hold real numbers (got dtype bool"),
    ("mass", lambda n, p: (["a"] * n,), "fsm_geometric_mass: q must hold real numbers"),
    ("mass", lambda n, p: (np.zeros(n), np.ones(p - 1)), "fsm_geometric_mass: p has"),
    ("force", lambda n, p: (np.zeros(n), np.zeros(1), 1.0), "fsm_geometric_force: qd has 1 values"),
    ("force", lambda n, p: (np.zeros(n), np.zeros(n), math.inf), "drive: w has a value that is not finite"),
    ("force", lambda n, p: (np.zeros(n), np.zeros(n), 1.0, 0.0, [1.0]), "fsm_geometric_force: p has 1 values"),
    ("energy", lambda n, p: (np.zeros(n), None, 1.0), "fsm_geometric_energy: qd must hold real numbers"),
    ("maneuver", lambda n, p: (0.0, [1.0]), "fsm_geometric_drive: mp has 1 values"),
    ("outputs", lambda n, p: (np.zeros(n), None, None, True), "drive: w must hold real numbers (got dtype bool"),
    ("force", lambda n, p: (np.zeros(n), np.zeros(n), [1.0, 2.0]), "drive: w has 2 values, expected 1"),
], ids=["q_short", "q_long", "q_nan", "q_complex", "q_bool", "q_str", "p_short", "qd_short", "w_inf",
        "force_p_short", "qd_none", "mp_short", "w_bool", "w_array"])
def test_kernel_arrays_are_checked_before_c_reads_them(m1_kernels, method, args, says):
    n, p = m1_kernels.nq, len(m1_kernels.param_defaults)
    with pytest.raises(SpecError) as info:
        getattr(m1_kernels, method)(*args(n, p))
    assert says.format(n=n, m=n - 1) in str(info.value), str(info.value)


def test_kernel_call_by_name_checks_count_and_sizes(m1_kernels):
    name = next(iter(m1_kernels.kernels))
    info = m1_kernels.kernels[name]
    with pytest.raises(SpecError, match="inputs given, expected"):
        m1_kernels.call(name)
    short = [np.zeros(max(0, size - 1)) for size in info["inputs"].values()]
    with pytest.raises(SpecError, match="has .* values, expected"):
        m1_kernels.call(name, *short)


@pytest.fixture(scope="module")
def m1_inprocess(m1_kernels):
    return api.inprocess("m1")


@pytest.mark.parametrize("runs, says", [
    ({"ws": [True]}, "ws: True is not a real number"),
    ({"ws": [2.0, False]}, "ws: False"),
    ({"ws": [1 + 2j]}, "ws: (1+2j)"),
    ({"ws": ["4.0"]}, "ws: '4.0'"),
    ({"ws": [None]}, "ws: None"),
    ({"E": [np.bool_(True)]}, "E: np.True_ is not a real number"),
    ({"q0_v_cp1": [b"1"]}, "q0_v_cp1: b'1'"),
], ids=["bool", "bool_second", "complex", "str", "none", "numpy_bool", "bytes"])
def test_batch_refuses_non_real_values(m1_inprocess, runs, says):
    with pytest.raises(SpecError) as info:
        m1_inprocess.batch(runs, t_end=0.1)
    assert says in str(info.value), str(info.value)


def test_batch_refuses_non_real_at(m1_inprocess):
    with pytest.raises(SpecError, match="at: True"):
        m1_inprocess.batch({"ws": [1.0]}, t_end=0.1, at=[True])
    with pytest.raises(SpecError, match="at: nan is not a finite real number"):
        m1_inprocess.batch({"ws": [1.0]}, t_end=0.1, at=[math.nan])


def test_batch_non_finite_value_fails_its_run_only(m1_inprocess):
    """nan and inf are real numbers: the runtime refuses them per run, naming the parameter."""
    b = m1_inprocess.batch({"ws": [1.0, math.nan]}, integrator="radau5", dt=0.01, t_end=0.1)
    assert b.status == ["ok", "failed"] and "ws must be finite" in b.messages[1]


def test_build_with_its_library_gone_is_rebuilt(m1_kernels):
    """A build directory marked complete whose library was deleted is built again, not used."""
    from flexsym.toolchain.build import build

    from flexsym.model.variant import builtin
    from flexsym.toolchain.pipeline import generated_folder

    built = m1_kernels.built
    built.library.unlink()
    again = build(generated_folder(builtin("m1")))
    assert again.build_dir == built.build_dir and again.library.is_file() and again.executable.is_file()


@pytest.mark.parametrize("gone", ["driver", "marker", "library-and-marker", "runtime-object-and-marker"])
def test_build_with_another_artefact_gone_is_rebuilt(tmp_path, gone):
    """The sibling cases, on a build root of the test's own: a deleted driver, a lost .complete
    marker (a directory half removed), both library and marker, an object of the cached
    runtime with the marker (the runtime is compiled again, then linked); the rebuilt model
    runs."""
    from flexsym.model.variant import builtin
    from flexsym.toolchain.build import COMPLETE, build
    from flexsym.toolchain.pipeline import generated_folder
    from flexsym.toolchain.run import run_built

    folder = generated_folder(builtin("m1"))
    built = build(folder, root=tmp_path)
    marker = built.build_dir / COMPLETE
    runtime_object = next((tmp_path / ".runtime").rglob("linalg.c.o"))
    for part in {"driver": [built.executable], "marker": [marker],
                 "library-and-marker": [built.library, marker],
                 "runtime-object-and-marker": [runtime_object, marker]}[gone]:
        part.unlink()
    again = build(folder, root=tmp_path)
    assert again == built and all(p.is_file() for p in (again.executable, again.library, marker))
    assert runtime_object.is_file()
    assert run_built(again, t_end=0.1, dt=0.01).ok
    # the runtime's objects, the kernels' objects kept for the derivation, the model's build
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.endswith(".lock")) == [
        ".kernels", ".runtime", built.build_dir.name]
