"""FMI 3.0 Co-Simulation export: the FMU validates in FMPy, reproduces `flexsym run` on the same
steps, takes the drive from its inputs step by step, and refuses bad requests and bad calls."""
from __future__ import annotations

import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi1 import FMICallException  # noqa: E402
from fmpy.fmi3 import FMU3Slave, fmi3LogMessageCallback  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

from flexsym.toolchain.build import find_compiler  # noqa: E402
from flexsym.apps.cli import main  # noqa: E402
from flexsym.core.paths import runtime_dir  # noqa: E402

# (id, target, run/export options): every fixed-step integrator, two variants and a scene
CASES = {
    "m3": ("m3", []),
    "m1": ("m1", []),
    "m1-radau5": ("m1", ["--integrator", "radau5", "--dt", "0.01", "--t-end", "5"]),
    "m3-rk4": ("m3", ["--integrator", "rk4", "--dt", "0.005", "--t-end", "5"]),
    "m3-newmark": ("m3", ["--integrator", "newmark", "--t-end", "5", "--ws", "4", "--ts", "10",
                          "--newmark-gamma", "0.6", "--newmark-beta", "0.3025"]),
    "m1-rho": ("m1", ["--rho-inf", "0.5", "--newton", "full", "--newton-tol", "1e-13", "--t-end", "5"]),
    "scene": ("scenes/constant_speed.toml", []),
    "scene-overridden": ("scenes/constant_speed.toml", ["--t-end", "3", "--rho-inf", "0.6"]),
    "ef": ("ef", ["--t-end", "2"]),  # banded matrices
}
ROOT = Path(__file__).resolve().parent.parent


def cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """Each case's FMU and `flexsym run`'s CSV, built once for the module."""
    folder = tmp_path_factory.mktemp("fmu")
    made = {}
    for key, (target, opts) in CASES.items():
        target = str(ROOT / target) if target.endswith(".toml") else target
        fmu, csv = folder / f"{key}.fmu", folder / f"{key}.csv"
        assert main(["export-fmu", target, *opts, "--out", str(fmu)]) == 0
        assert main(["run", target, *opts, "--out", str(csv)]) == 0
        made[key] = (fmu, csv)
    drive = folder / "m3-drive.fmu"
    assert main(["export-fmu", "m3", "--input", "drive", "--t-end", "10", "--out", str(drive)]) == 0
    made["drive"] = (drive, None)
    return made


def read_csv(path):
    with open(path, encoding="utf-8") as fh:
        columns = fh.readline().strip().split(",")
    return columns, np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


@pytest.mark.parametrize("key", [*CASES, "drive"])
def test_fmu_validates(exported, key):
    assert validate_fmu(str(exported[key][0])) == []
    md = read_model_description(str(exported[key][0]))
    assert md.fmiVersion == "3.0" and md.coSimulation is not None and md.modelExchange is None


@pytest.mark.parametrize("key", ["m3", "ef", "drive"])
def test_the_binary_exports_its_fmi3_functions_alone(exported, key, tmp_path):
    """The runtime is linked from objects compiled once for every FMU with hidden visibility
    (build.FMU_FLAGS): an importer sees the fmi3* functions, never the runtime's fsr_* nor the
    model's symbols, which another FMU in the same process also defines."""
    with zipfile.ZipFile(exported[key][0]) as z:
        so = next(n for n in z.namelist() if n.startswith("binaries/") and n.endswith(".so"))
        z.extract(so, tmp_path)
    out = subprocess.run(["nm", "-D", "--defined-only", str(tmp_path / so)], capture_output=True,
                         text=True, check=True).stdout
    names = [line.split()[-1] for line in out.splitlines() if line.strip()]
    assert "fmi3DoStep" in names and [n for n in names if not n.startswith("fmi3")] == []


@pytest.mark.parametrize("key", list(CASES))
def test_fmpy_reproduces_flexsym_run(exported, key):
    """simulate_fmu on the run's row interval gives the CSV's rows (the CSV holds 17 digits)."""
    fmu, csv = exported[key]
    columns, rows = read_csv(csv)
    md = read_model_description(str(fmu))
    interval = float(md.defaultExperiment.stepSize)
    res = fmpy.simulate_fmu(str(fmu), output_interval=interval)
    assert len(res) == len(rows)
    np.testing.assert_array_equal(res["time"], rows[:, 0])  # the same grid, to the last bit
    outputs = {v.name for v in md.modelVariables if v.causality == "output"}
    assert outputs == set(columns[1:])  # every CSV column, named as in the CSV
    for j, name in enumerate(columns[1:], start=1):
        scale = max(np.max(np.abs(rows[:, j])), 1e-300)
        assert np.max(np.abs(res[name] - rows[:, j])) <= 1e-12 * scale, name


def _unzipped(path: Path) -> str:
    """The FMU unpacked next to it (in the test's temporary folder), once: unpacking again would
    overwrite a binary that an earlier instance may still have loaded."""
    folder = path.with_suffix(".unzipped")
    return str(folder) if folder.is_dir() else extract(str(path), str(folder))


def _slave(path: Path, messages: list):
    md = read_model_description(str(path))
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=_unzipped(path),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="test")
    fmu.instantiate(logMessage=lambda env, status, category, message: messages.append(message.decode()))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    return fmu, vr


def _drive_run(path: Path, t_end: float, h: float, drive) -> np.ndarray:
    """v_tip at every communication point, theta_dot and theta_ddot set before each step."""
    fmu, vr = _slave(path, [])
    fmu.enterInitializationMode(startTime=0.0, stopTime=t_end)
    fmu.setFloat64([vr["theta_dot"], vr["theta_ddot"]], list(drive(0.0)))
    fmu.exitInitializationMode()
    n = int(round(t_end / h))
    v = np.empty(n + 1)
    v[0] = fmu.getFloat64([vr["v_tip"]])[0]
    for k in range(n):
        t = k * h
        fmu.setFloat64([vr["theta_dot"], vr["theta_ddot"]], list(drive(t)))
        fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        v[k + 1] = fmu.getFloat64([vr["v_tip"]])[0]
    fmu.terminate()
    fmu.freeInstance()
    return v


def test_drive_input_with_constant_acceleration_equals_the_same_manoeuvre(exported, tmp_path, capsys):
    """theta'' = alpha constant: holding theta'' and integrating theta' over a step is exact, so
    the FMU fed (alpha t, alpha) step by step is the run of the scene with theta = alpha t^2 / 2."""
    alpha, t_end = 0.4, 10.0
    scene = tmp_path / "accel.toml"
    text = (ROOT / "scenes" / "paper.toml").read_text(encoding="utf-8")
    assert 'kind = "spin-up"' in text
    scene.write_text(_with_maneuver(text, f'kind = "expression"\ntheta = "{alpha / 2!r}*t**2"', t_end),
                     encoding="utf-8")
    csv = tmp_path / "accel.csv"
    code, _, err = cli(capsys, "run", scene, "--out", csv)
    assert code == 0, err
    columns, rows = read_csv(csv)
    v = _drive_run(exported["drive"][0], t_end, 0.01, lambda t: (alpha * t, alpha))
    ref = rows[:, columns.index("v_tip")]
    assert len(v) == len(ref)
    assert np.max(np.abs(v - ref)) <= 1e-12 * np.max(np.abs(ref))


def _with_maneuver(text: str, maneuver: str, t_end: float) -> str:
    lines, out, skip = text.splitlines(), [], False
    for line in lines:
        if line.startswith("["):
            skip = line.strip() == "[maneuver]"
            out.append(line)
            if skip:
                out.append(maneuver)
            continue
        if skip:
            continue
        if line.startswith("t_end"):
            line = f"t_end = {t_end}"
        out.append(line)
    return "\n".join(out) + "\n"


def test_drive_input_fed_the_spin_up_converges_to_the_built_in_manoeuvre(exported, tmp_path):
    """Fed theta', theta'' of the spin-up (eq. 39) at the communication points, the FMU holds
    theta'' over each step (a causal importer knows no later value): theta'' lags by about
    (h + dt) / 2 on average (dt: generalized-alpha takes the drive at the end of its step), so
    the error in v_tip is first order in h + dt: 11 / 3 times smaller from h = 10 ms to 2 ms."""
    ws, ts, t_end = 6.0, 15.0, 10.0

    def spin_up(t):
        return ws / ts * (t - ts / (2 * np.pi) * np.sin(2 * np.pi * t / ts)), \
            ws / ts * (1 - np.cos(2 * np.pi * t / ts))

    csv = tmp_path / "m3.csv"
    assert main(["run", "m3", "--t-end", str(t_end), "--out", str(csv)]) == 0
    columns, rows = read_csv(csv)
    ref = rows[:, columns.index("v_tip")]  # every 10 ms
    errors = []
    for h in (0.01, 0.002):
        v = _drive_run(exported["drive"][0], t_end, h, spin_up)
        errors.append(np.max(np.abs(v[:: int(round(0.01 / h))] - ref)))
    assert errors[0] < 1e-3  # 7.7e-4 m against a peak of 0.58 m
    assert 3.2 < errors[0] / errors[1] < 4.2  # (10 + 1) / (2 + 1) = 3.67


def test_parameters_are_tunable_and_bad_calls_are_refused(exported):
    messages: list = []
    fmu, vr = _slave(exported["m3"][0], messages)
    fmu.setFloat64([vr["ws"]], [4.0])  # before initialization
    fmu.enterInitializationMode(startTime=0.0, stopTime=2.0)
    fmu.exitInitializationMode()
    fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.5)
    v1 = fmu.getFloat64([vr["v_tip"]])[0]
    with pytest.raises(FMICallException):
        fmu.setFloat64([vr["E"]], [-1.0])  # a beam parameter must be positive
    assert messages[-1].count("\n") == 0 and "E must be a positive number" in messages[-1]
    with pytest.raises(FMICallException):
        fmu.doStep(currentCommunicationPoint=0.5, communicationStepSize=0.0015)  # off the 1 ms grid
    assert "not on the step grid" in messages[-1]
    with pytest.raises(FMICallException):
        fmu.doStep(currentCommunicationPoint=0.4, communicationStepSize=0.1)  # not where the FMU is
    with pytest.raises(FMICallException):
        fmu.getFloat64([999], )
    with pytest.raises(FMICallException):
        fmu.setFloat64([vr["v_tip"]], [1.0])  # an output
    fmu.setFloat64([vr["ws"]], [8.0])  # tunable in step mode: takes effect from here
    fmu.doStep(currentCommunicationPoint=0.5, communicationStepSize=0.5)
    assert np.isfinite(fmu.getFloat64([vr["v_tip"]])[0]) and v1 < 0
    fmu.terminate()
    fmu.freeInstance()
    # a wrong instantiation token: no instance, one line
    md = read_model_description(str(exported["m3"][0]))
    bad = FMU3Slave(guid="not-the-token", unzipDirectory=_unzipped(exported["m3"][0]),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bad")
    messages.clear()
    with pytest.raises(Exception):
        bad.instantiate(logMessage=lambda env, status, category, message: messages.append(message.decode()))
    assert len(messages) == 1 and "instantiationToken" in messages[0]


def test_tunable_start_values_match_the_run(exported, tmp_path):
    csv = tmp_path / "ws4.csv"
    assert main(["run", "m3", "--ws", "4", "--ts", "10", "--t-end", "3", "--out", str(csv)]) == 0
    columns, rows = read_csv(csv)
    res = fmpy.simulate_fmu(str(exported["m3"][0]), stop_time=3.0, output_interval=0.01,
                            start_values={"ws": 4.0, "ts": 10.0})
    np.testing.assert_array_equal(res["v_tip"], rows[:, columns.index("v_tip")])


@pytest.mark.parametrize("argv, message", [
    (["export-fmu", "m9", "--out", "{tmp}/x.fmu"], "unknown variant"),
    (["export-fmu", "m3", "--out", "{tmp}/missing/x.fmu"], "does not exist"),
    (["export-fmu", "m3", "--out", "{tmp}/x.zip"], "ends in .fmu"),
    (["export-fmu", "m3", "--integrator", "dopri5", "--out", "{tmp}/x.fmu"], "adapts its steps"),
    (["export-fmu", "m3", "--integrator", "ali3p", "--out", "{tmp}/x.fmu"], "system scenes only"),
    (["export-fmu", "m3", "--integrator", "radau5", "--step", "0.2", "--out", "{tmp}/x.fmu"], "--step"),
    (["export-fmu", "m3", "--integrator", "rk4", "--input", "drive", "--out", "{tmp}/x.fmu"],
     "implicit integrator"),
    (["export-fmu", "m3", "--input", "torque", "--out", "{tmp}/x.fmu"], "--input"),
    (["export-fmu", "m3", "--dt", "-1", "--out", "{tmp}/x.fmu"], "--dt: must be > 0"),
    (["export-fmu", "m3", "--rho-inf", "2", "--out", "{tmp}/x.fmu"], "--rho-inf: must be"),
    (["export-fmu", "m3", "--penalty", "10", "--out", "{tmp}/x.fmu"], "--penalty"),
    (["export-fmu", str(ROOT / "scenes/constant_speed.toml"), "--input", "drive", "--out", "{tmp}/x.fmu"],
     "without theta'' terms"),
])
def test_malformed_export_requests(capsys, tmp_path, argv, message):
    keep = tmp_path / "x.fmu"
    keep.write_bytes(b"an earlier file")
    code, out, err = cli(capsys, *[a.replace("{tmp}", str(tmp_path)) for a in argv])
    assert code == 2
    assert message in err and len(err.strip().splitlines()) == 1
    assert keep.read_bytes() == b"an earlier file"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.fmu"]


def test_header_agrees_with_the_standard_headers(tmp_path):
    """runtime_c/fmi3/fmi3.h is written from the standard; FMPy ships the standard's headers.
    Every function must be declared alike (else a compile error), every type alike in size
    and enumeration values."""
    std = Path(fmpy.__file__).parent / "c-code"
    ours = runtime_dir() / "fmi3"
    src = tmp_path / "check.c"
    src.write_text('#include "fmi3Functions.h"\n#define FLEXSYM_FMI3_STANDARD_TYPES\n#include "fmi3.h"\n'
                   "int main(void) { return 0; }\n")
    cc = find_compiler()
    proc = subprocess.run([cc, "-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror", "-fsyntax-only",
                           f"-I{std}", f"-I{ours}", str(src)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    probe = ('#include <stdio.h>\n#include HEADER\nint main(void) { printf("%zu %zu %zu %zu %zu %zu '
             '%d %d %d %d %d %d %d %d\\n", sizeof(fmi3Instance), sizeof(fmi3ValueReference), '
             "sizeof(fmi3Float64), sizeof(fmi3Boolean), sizeof(fmi3Byte), sizeof(fmi3Status), "
             "(int)fmi3OK, (int)fmi3Warning, (int)fmi3Discard, (int)fmi3Error, (int)fmi3Fatal, "
             "(int)fmi3Dependent, (int)fmi3IntervalChanged, (int)sizeof(fmi3Clock)); return 0; }\n")
    outputs = []
    for header in ('"fmi3Functions.h"', '"fmi3.h"'):
        (tmp_path / "probe.c").write_text(probe.replace("HEADER", header))
        exe = tmp_path / "probe"
        subprocess.run([cc, "-std=c99", f"-I{std}", f"-I{ours}", str(tmp_path / "probe.c"), "-o", str(exe)],
                       check=True)
        outputs.append(subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout)
    assert outputs[0] == outputs[1]


def _steps(fmu, vr, t0, t1, h):
    for k in range(int(round((t1 - t0) / h))):
        fmu.doStep(currentCommunicationPoint=t0 + k * h, communicationStepSize=h)
    return fmu.getFloat64([vr["v_tip"]])[0]


def test_retuning_between_steps(exported):
    """A parameter set between steps drops the run's caches: set to its own value the run goes on
    as before (up to the Newton tolerance: the iteration matrix is rebuilt); E x 100 makes rk4's
    5 ms step unstable for #3 (omega_max 72.8 -> 728 rad/s), and the next step is refused."""
    runs = []
    for retune in (False, True):
        fmu, vr = _slave(exported["m3"][0], [])
        fmu.enterInitializationMode(startTime=0.0, stopTime=3.0)
        fmu.exitInitializationMode()
        _steps(fmu, vr, 0.0, 1.0, 0.01)
        if retune:
            fmu.setFloat64([vr["E"], vr["ws"]], [7.0e10, 6.0])
        runs.append(_steps(fmu, vr, 1.0, 3.0, 0.01))
        fmu.freeInstance()
    assert runs[0] != 0 and abs(runs[1] - runs[0]) <= 1e-9 * abs(runs[0])
    messages: list = []
    fmu, vr = _slave(exported["m3-rk4"][0], messages)
    fmu.enterInitializationMode(startTime=0.0, stopTime=5.0)
    fmu.exitInitializationMode()
    _steps(fmu, vr, 0.0, 0.5, 0.01)
    fmu.setFloat64([vr["E"]], [7.0e12])
    with pytest.raises(FMICallException):
        fmu.doStep(currentCommunicationPoint=0.5, communicationStepSize=0.01)
    assert "exceeds the stability limit" in messages[-1]
    fmu.freeInstance()


# ------------------------------------------------------------------ stop time (FMI 3.0 stopTimeDefined)

def _v_tips(fmu, vr, t0: float, n: int, h: float = 0.01) -> np.ndarray:
    """v_tip after each of n steps of h from t0."""
    out = np.empty(n)
    for k in range(n):
        fmu.doStep(currentCommunicationPoint=t0 + k * h, communicationStepSize=h)
        out[k] = fmu.getFloat64([vr["v_tip"]])[0]
    return out


def test_without_a_stop_time_the_fmu_runs_until_the_importer_stops(exported):
    """stopTimeDefined = false means no stop time: ExitInitializationMode refused it (a 1e6 s
    horizon of 1e9 steps). Now the run goes on past the exported t_end (20 s), its rows those of
    `flexsym run` up to there and those of a run given stopTime = 25 after."""
    fmu_path, csv = exported["m3"]
    columns, rows = read_csv(csv)
    runs = []
    for stop in (None, 25.0):
        messages: list = []
        fmu, vr = _slave(fmu_path, messages)
        fmu.enterInitializationMode(startTime=0.0, stopTime=stop)
        fmu.exitInitializationMode()
        runs.append(_v_tips(fmu, vr, 0.0, 2500))
        fmu.terminate()
        fmu.freeInstance()
        assert messages == []
    free, stopped = runs
    np.testing.assert_array_equal(free, stopped)  # bit for bit, 20 s to 25 s included
    ref = rows[1:, columns.index("v_tip")]
    assert np.max(np.abs(free[:2000] - ref)) <= 1e-12 * np.max(np.abs(ref))
    assert np.isfinite(free).all() and free[-1] != free[1999]


def test_a_step_past_a_defined_stop_time_is_refused_at_do_step(exported):
    messages: list = []
    fmu, vr = _slave(exported["m3"][0], messages)
    fmu.enterInitializationMode(startTime=0.0, stopTime=1.0)
    fmu.exitInitializationMode()
    last = _v_tips(fmu, vr, 0.0, 100)[-1]
    with pytest.raises(FMICallException):
        fmu.doStep(currentCommunicationPoint=1.0, communicationStepSize=0.01)
    assert len(messages) == 1 and "\n" not in messages[0], messages
    assert "fmi3DoStep: t = 1.01 s is past stopTime = 1 s, set in fmi3EnterInitializationMode" in messages[0]
    assert fmu.getFloat64([vr["v_tip"]])[0] == last  # refused, not half done: the run is at 1 s
    fmu.terminate()
    fmu.freeInstance()


@pytest.mark.parametrize("stop,message", [
    (2.0e5, "stopTime = 200000 s is 2e+08 steps of dt = 0.001 s, more than this FMU's limit of 100000000 steps"),
    (float("inf"), "stopTime = inf s must be > 0"),
    (float("nan"), "stopTime = nan s must be > 0"),
    (-1.0, "stopTime = -1 s must be > 0"),
], ids=["beyond-the-step-limit", "inf", "nan", "negative"])
def test_a_stop_time_the_fmu_cannot_reach_is_refused_at_initialization(exported, stop, message):
    """Refused where it is given (it was refused at ExitInitializationMode, by the runtime's
    limit, as a number of steps); the instance stays usable."""
    messages: list = []
    fmu, vr = _slave(exported["m3"][0], messages)
    with pytest.raises(FMICallException):
        fmu.enterInitializationMode(startTime=0.0, stopTime=stop)
    assert len(messages) == 1 and message in messages[0], messages
    fmu.enterInitializationMode(startTime=0.0, stopTime=1.0)
    fmu.exitInitializationMode()
    assert np.isfinite(_v_tips(fmu, vr, 0.0, 10)).all()
    fmu.freeInstance()


def test_a_long_stop_time_is_bounded_by_steps_not_by_rows(exported):
    """stopTime = 2e4 s is 2e7 steps of 1 ms: within the runtime's step limit, and the FMU keeps
    one row, but the all-rows limit (1e7) refused it at ExitInitializationMode."""
    messages: list = []
    fmu, vr = _slave(exported["m3"][0], messages)
    fmu.enterInitializationMode(startTime=0.0, stopTime=2.0e4)
    fmu.exitInitializationMode()
    assert np.isfinite(_v_tips(fmu, vr, 0.0, 50)).all() and messages == []
    fmu.freeInstance()


def test_an_importers_stop_time_beyond_the_exported_one_is_the_run_to_that_time(exported, tmp_path):
    """The exported t_end is DefaultExperiment's suggestion; an importer asking for more gets
    `flexsym run` with that t_end (m3-rk4 was exported with --t-end 5)."""
    fmu_path = exported["m3-rk4"][0]
    assert float(read_model_description(str(fmu_path)).defaultExperiment.stopTime) == 5.0
    csv = tmp_path / "six.csv"
    assert main(["run", "m3", "--integrator", "rk4", "--dt", "0.005", "--t-end", "6", "--out", str(csv)]) == 0
    columns, rows = read_csv(csv)
    res = fmpy.simulate_fmu(str(fmu_path), stop_time=6.0, output_interval=0.01)
    assert len(res) == len(rows) and res["time"][-1] == 6.0
    ref = rows[:, columns.index("v_tip")]
    assert np.max(np.abs(res["v_tip"] - ref)) <= 1e-12 * np.max(np.abs(ref))
