"""FMI 3.0 export of system scenes: the FMU of the tree systems S1 (hub.toml) and S3
(pendulum.toml, genalpha) and of a closed loop (S2, slider_crank.toml, ali3p with its violation
column) validates in FMPy and,
stepped every row interval of the scene (10 ms, 1 ms), reproduces `flexsym run SCENE`'s rows
bit for bit."""
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
from fmpy import read_model_description  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

from flexsym.apps.cli import main  # noqa: E402

SCENES = Path(__file__).resolve().parent.parent / "scenes"
CASES = ("hub", "slider_crank", "pendulum")


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """Each scene's FMU and `flexsym run`'s CSV, built once for the module."""
    folder = tmp_path_factory.mktemp("fmu-systems")
    made = {}
    for key in CASES:
        fmu, csv = folder / f"{key}.fmu", folder / f"{key}.csv"
        assert main(["export-fmu", str(SCENES / f"{key}.toml"), "--out", str(fmu)]) == 0
        assert main(["run", str(SCENES / f"{key}.toml"), "--out", str(csv)]) == 0
        made[key] = (fmu, csv)
    return made


@pytest.mark.parametrize("key", CASES)
def test_system_fmu_validates_and_reproduces_flexsym_run(exported, key):
    fmu, csv = exported[key]
    assert validate_fmu(str(fmu)) == []
    md = read_model_description(str(fmu))
    assert md.fmiVersion == "3.0" and md.coSimulation is not None
    with open(csv, encoding="utf-8") as fh:
        columns = fh.readline().strip().split(",")
    rows = np.loadtxt(csv, delimiter=",", skiprows=1, ndmin=2)
    interval = float(md.defaultExperiment.stepSize)
    assert interval == {"hub": 0.01, "slider_crank": 0.001, "pendulum": 0.001}[key]
    outputs = {v.name for v in md.modelVariables if v.causality == "output"}
    assert outputs == set(columns[1:])  # every CSV column (violation too), named as in the CSV
    assert ("violation" in outputs) == (key == "slider_crank")
    params = {v.name for v in md.modelVariables if v.causality == "parameter"}
    assert {"E", "rho", "L"} <= params
    res = fmpy.simulate_fmu(str(fmu), output_interval=interval)
    assert len(res) == len(rows)
    # FMPy's communication points are k * interval, the runtime's row times n * dt: 1 ulp apart
    np.testing.assert_allclose(res["time"], rows[:, 0], rtol=1e-15, atol=0)
    for j, name in enumerate(columns[1:], start=1):  # the same steps: the same bits
        np.testing.assert_array_equal(res[name], rows[:, j], err_msg=name)


def test_system_fmu_parameter_start_value_changes_the_run(exported, tmp_path):
    """A tunable parameter set before initialization: the rows of the run with that value."""
    fmu, _ = exported["slider_crank"]
    md = read_model_description(str(fmu))
    e = float(next(v.start for v in md.modelVariables if v.name == "E"))
    res = fmpy.simulate_fmu(str(fmu), output_interval=0.001, stop_time=0.1, start_values={"E": 3 * e})
    from flexsym.sim.inprocess import load_system
    from flexsym.scenes.scene import load_scene

    scene = load_scene(SCENES / "slider_crank.toml")
    b = load_system(scene.system).batch({"E": [3 * e]}, rows=True, integrator="ali3p", dt=1e-4,
                                        t_end=0.1, interval=0.001)
    ref = b.result(0)
    assert len(res) == len(ref.data)
    for name in ("x_s", "w_mid", "N_mid"):
        scale = np.max(np.abs(ref[name]))
        assert np.max(np.abs(res[name] - ref[name])) <= 1e-12 * scale, name


@pytest.mark.parametrize("argv, message", [
    (["--input", "drive"], "a system scene's FMU has no inputs yet"),
    (["--ws", "5"], "--ws given with a system scene: set the driver's omega"),  # options as `run`'s
    (["--dt", "-1"], "--dt: must be > 0"),
])
def test_malformed_system_export_requests(capsys, tmp_path, argv, message):
    out = tmp_path / "x.fmu"
    assert main(["export-fmu", str(SCENES / "slider_crank.toml"), *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_constrained_fmu_refuses_a_parameter_set_between_steps(exported, tmp_path):
    """ali3p/genalpha3 cannot retune a run (fsr_stepper_retune): E set in step mode makes the next
    doStep fail with one log line naming it, instead of going on with stale matrices."""
    from fmpy import extract
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi3 import FMU3Slave

    fmu_path = exported["slider_crank"][0]
    md = read_model_description(str(fmu_path))
    messages = []
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(fmu_path), str(tmp_path / "u")),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="test")
    fmu.instantiate(logMessage=lambda env, status, category, message: messages.append(message.decode()))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu.enterInitializationMode(startTime=0.0, stopTime=0.1)
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 0.001)
    fmu.setFloat64([vr["E"]], [1.0e11])
    with pytest.raises(FMICallException):
        fmu.doStep(0.001, 0.001)
    assert any("retuning is not available yet" in m for m in messages)
    fmu.freeInstance()


def test_an_fmu_compiles_its_kernels_as_the_model_does(tmp_path, monkeypatch):
    """A folder whose kernels have flags of their own (kernels.cmake: large kernels at -O1,
    the rarely called ones in kernels_rare.c at -O0; forced here by thresholds of 0) exports an
    FMU built from the same files with the same flags: it links, and it steps the driver's rows
    bit for bit."""
    from flexsym.codegen import sysgen
    from flexsym.scenes.system_scene import system_from_dict
    from flexsym.sim.fmu import FmuOptions, export_fmu
    from flexsym.toolchain.pipeline import prepare_system, system_folder
    from flexsym.toolchain.run import run_built

    data = {"system": {"name": "tiers_fmu"}, "gravity": {"g": [0.0, -9.81]},
            "body": [{"name": "beam", "kind": "beam", "length": 1.0, "model": "m3", "density": 2700.0,
                      "youngs_modulus": 7e10, "area": 1e-4, "inertia": 2e-10}],
            "joint": [{"name": "pin", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0],
                       "child": "beam.root", "initial": 0.6}],
            "output": {"columns": {"w_mid": "w(beam, 0.5)", "M_mid": "M(beam, 0.5)"}}}
    system = system_from_dict(data, name="tiers_fmu")
    monkeypatch.setattr(sysgen, "RARE_KERNELS", {"energy": 0, "residual_jac": 0})
    monkeypatch.setattr(sysgen, "LARGE_KERNELS", 0)
    built = prepare_system(system, log=lambda m: None)
    monkeypatch.undo()
    folder = system_folder(system)
    cmake = (folder / "kernels.cmake").read_text()
    assert "kernels_rare.c\" PROPERTIES COMPILE_OPTIONS -O0" in cmake and "\"-O1;" in cmake
    opts = FmuOptions(integrator="genalpha", dt=1e-4, step=None, tol=None, t_end=0.2, interval=1e-3,
                      params={})
    fmu = export_fmu(folder, opts, tmp_path / "tiers.fmu")
    res = fmpy.simulate_fmu(str(fmu), output_interval=1e-3)
    rows = run_built(built, t_end=0.2, dt=1e-4, integrator="genalpha", interval=1e-3)
    assert rows.ok and len(res) == len(rows.t)
    for name in ("w_mid", "M_mid"):
        np.testing.assert_array_equal(res[name], rows[name], err_msg=name)
    assert np.max(np.abs(rows["w_mid"])) > 1e-5
