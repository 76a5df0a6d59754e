"""Export a model as an FMI 3.0 Co-Simulation FMU: modelDescription.xml, a binary built with
CMake from the generated kernels, the C runtime and runtime_c/fmi3 (no Python at run time).

Variables (value references fixed here and passed to the C wrapper in flexsym_fmu_config.h):
time; the beam parameters and, unless the drive is an input, the manoeuvre parameters
(tunable); with input="drive" the inputs theta_dot, theta_ddot; the outputs and the
coordinates, named as the columns of `flexsym run`'s CSV. A system (flexsym/codegen/sysgen.py): its
parameters p and drive parameters, its outputs (with the violation column when it has
constraints) and coordinates; ali3p, genalpha3 and rk4p too when it has constraints.
"""
from __future__ import annotations

import hashlib
import os
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

from flexsym.toolchain.build import FMU_FLAGS, _run, find_cmake, find_compiler, runtime_objects
from flexsym.core.errors import SpecError
from flexsym.codegen.folder import read_manifest
from flexsym.core.paths import runtime_dir
from flexsym.model.integrators import BY_NAME as INTEGRATORS, names

PLATFORM = "x86_64-linux"
INPUT_MODES = ("none", "drive")
# every integrator of the runtime's registry; the constrained ones for systems only
METHODS = names(without="constrained")
CONSTRAINED = names("constrained")
DRIVE_INPUTS = (("theta_dot", "rad/s", "guided angular rate; held with its slope theta_ddot over a "
                 "communication step"),
                ("theta_ddot", "rad/s2", "guided angular acceleration, held over a communication step"))


@dataclass(frozen=True)
class FmuOptions:
    integrator: str
    dt: float
    step: float | None
    tol: float | None
    t_end: float          # DefaultExperiment stopTime
    interval: float       # DefaultExperiment stepSize (the rows of flexsym run)
    params: dict          # start values overriding the model's defaults
    input: str = "none"
    tuning: tuple = ()    # (fsr_options field, value) of the integrator's settings given


# run options -> the C runtime's fsr_options field (and the value it stores)
TUNING = {"max_steps": ("max_steps", int), "newton": ("newton_full", lambda v: int(v == "full")),
          "newton_tol": ("newton_tol", float), "rho_inf": ("rho_inf", float),
          "newmark_gamma": ("nm_gamma", float), "newmark_beta": ("nm_beta", float),
          "blowup": ("blowup", float), "penalty": ("penalty", float)}


def tuning_of(options) -> tuple:
    """The integrator settings of validated run options that differ from the runtime's
    defaults because they were given (None: not given)."""
    return tuple((field, conv(getattr(options, name))) for name, (field, conv) in TUNING.items()
                 if getattr(options, name) is not None)


def check_request(opts: FmuOptions, out: Path | None, spec) -> None:
    """Refuse what the FMU cannot do, before anything is generated, built or written
    (spec None: a system)."""
    from flexsym.model.maneuver import maneuver_of

    if opts.input not in INPUT_MODES:
        raise SpecError(f"--input '{opts.input}': expected one of {', '.join(INPUT_MODES)}")
    if out is not None:
        _check_out(out)
    if spec is None and opts.input != "none":
        raise SpecError(f"--input {opts.input}: a system scene's FMU has no inputs yet (its drivers "
                        "run as the scene says)")
    offered = METHODS + (CONSTRAINED if spec is None else ())
    if opts.integrator not in offered:
        raise SpecError(f"--integrator {opts.integrator}: an FMU offers {', '.join(offered)}"
                        + ("" if spec is None else f" ({', '.join(CONSTRAINED)}: system scenes only)"))
    if INTEGRATORS[opts.integrator].has("adaptive") and opts.tol != 0:
        raise SpecError(f"--integrator {opts.integrator} adapts its steps; the FMU takes fixed steps of dt: "
                        f"use --tol 0 ({opts.integrator} at fixed steps) or another integrator")
    if opts.step is not None and opts.step != opts.dt:
        raise SpecError(f"--step {opts.step:g}: the FMU's steps end on its communication points, so "
                        "radau5 steps at dt (drop --step or set --dt to the step)")
    if opts.input == "drive" and not maneuver_of(spec.maneuver).accelerates:
        raise SpecError(f"--input drive: '{spec.name}' is generated without theta'' terms (its manoeuvre "
                        f"'{spec.maneuver}' has theta'' = 0); export a variant whose manoeuvre accelerates")
    if opts.input == "drive" and not INTEGRATORS[opts.integrator].has("drive_input"):
        raise SpecError(f"--input drive needs an implicit integrator ({', '.join(names('drive_input'))}): "
                        f"the stability limit of {opts.integrator} depends on the drive to come")


def _check_out(out: Path) -> None:
    if out.suffix != ".fmu":
        raise SpecError(f"--out {out}: an FMU file name ends in .fmu")
    if not out.parent.is_dir():
        raise SpecError(f"--out {out}: folder {out.parent} does not exist")
    if not os.access(out.parent, os.W_OK):
        raise SpecError(f"--out {out}: folder {out.parent} is not writable")
    if out.is_dir():
        raise SpecError(f"--out {out}: is a folder")


def model_identifier(name: str) -> str:
    return "flexsym_" + "".join(ch if ch.isalnum() else "_" for ch in name)


def _num(x: float) -> str:
    return repr(float(x))


def _layout(manifest: dict) -> dict:
    """Value references: time 0, then each group in order (manoeuvre parameters and the drive
    inputs keep their numbers whether or not the FMU declares them)."""
    np_, nmp = len(manifest["params"]), len(manifest["drive_params"])
    ny, nq = len(_outputs(manifest)), len(manifest["coordinates"])
    vr = {"TIME": 0, "P": 1, "MP": 1 + np_, "IN": 1 + np_ + nmp, "Y": 3 + np_ + nmp}
    vr["Q"] = vr["Y"] + ny
    return {"vr": vr, "np": np_, "nmp": nmp, "ny": ny, "nq": nq}


def _starts(manifest: dict, opts: FmuOptions) -> tuple[list[float], list[float]]:
    p = [opts.params.get(x["name"], x["default"]) for x in manifest["params"]]
    mp = [opts.params.get(x["name"], x["default"]) for x in manifest["drive_params"]]
    return p, mp


def _maneuver(manifest: dict) -> str | None:
    """A one-beam variant's manoeuvre (its folder's manifest names the variant), else None."""
    return manifest.get("variant", {}).get("maneuver")


def _outputs(manifest: dict) -> list[str]:
    """The row's columns before the coordinates: outputs, and violation when a system has
    constraints (runtime.h)."""
    return list(manifest["outputs"]) + (["violation"] if manifest.get("constraints") else [])


def token(manifest: dict, opts: FmuOptions) -> str:
    """The model's fingerprint and a digest of the run options compiled into the binary."""
    cfg = f"{opts.integrator} {opts.dt!r} {opts.tol!r} {opts.input} {sorted(opts.params.items())!r}"
    cfg += f" {list(opts.tuning)!r}" if opts.tuning else ""
    return manifest["fingerprint"] + ":" + hashlib.sha256(cfg.encode()).hexdigest()[:12]


def config_header(manifest: dict, opts: FmuOptions) -> str:
    lay, (p, mp) = _layout(manifest), _starts(manifest, opts)
    lines = ["/* written by flexsym export-fmu (flexsym/sim/fmu.py); read by runtime_c/fmi3 */",
             f'#define FSU_TOKEN "{token(manifest, opts)}"',
             f"#define FSU_DRIVE_INPUT {int(opts.input == 'drive')}",
             f"#define FSU_METHOD {INTEGRATORS[opts.integrator].constant}",
             f"#define FSU_MODEL {manifest['model']}",
             f"#define FSU_DT {_num(opts.dt)}",
             f"#define FSU_STEP {_num(opts.step or 0.0)}",
             f"#define FSU_TOL {_num(opts.tol or 0.0)}",
             "#define FSU_TUNE(o) do { " + "".join(
                 f"(o).{f} = {v if isinstance(v, int) else _num(v)}; " for f, v in opts.tuning) + "} while (0)",
             f"#define FSU_NP {lay['np']}", f"#define FSU_NMP {lay['nmp']}",
             f"#define FSU_NY {lay['ny']}", f"#define FSU_NQ {lay['nq']}",
             "#define FSU_P_START {" + ", ".join(map(_num, p)) + "}",
             "#define FSU_MP_START {" + (", ".join(map(_num, mp)) or "0.0") + "}"]
    lines += [f"#define FSU_VR_{k} {v}" for k, v in lay["vr"].items()]
    return "\n".join(lines) + "\n"


def model_description(manifest: dict, opts: FmuOptions) -> str:
    spec = manifest["spec"]
    lay, (p, mp) = _layout(manifest), _starts(manifest, opts)
    vr = lay["vr"]
    drive = opts.input == "drive"
    var = []

    def f64(name, ref, causality, variability, description, start=None, initial=None):
        a = f"name={quoteattr(name)} valueReference=\"{ref}\" causality=\"{causality}\" " \
            f"variability=\"{variability}\""
        if initial:
            a += f" initial=\"{initial}\""
        if start is not None:
            a += f" start=\"{_num(start)}\""
        var.append(f"    <Float64 {a} description={quoteattr(description)}/>")

    f64("time", vr["TIME"], "independent", "continuous", "simulation time [s]")
    maneuver = _maneuver(manifest)
    for i, (x, v) in enumerate(zip(manifest["params"], p)):
        what = "beam parameter" + (f" [{x['unit']}]" if "unit" in x else " (SI units)")
        f64(x["name"], vr["P"] + i, "parameter", "tunable", what, v, "exact")
    if not drive:
        of = maneuver or "a guided joint's manoeuvre"
        for i, (x, v) in enumerate(zip(manifest["drive_params"], mp)):
            f64(x["name"], vr["MP"] + i, "parameter", "tunable",
                f"manoeuvre parameter [{x['unit']}] of {of}", v, "exact")
    else:
        for i, (name, unit, what) in enumerate(DRIVE_INPUTS):
            f64(name, vr["IN"] + i, "input", "continuous", f"{what} [{unit}]", 0.0)
    quantities = manifest["outputs"] if maneuver is None else {}  # a variant's names say it
    outputs = [(name, vr["Y"] + i, quantities.get(name, "output quantity") if name != "violation" else
                "max |Phi| / length scale (constraint violation)") for i, name in enumerate(_outputs(manifest))]
    outputs += [(c["name"], vr["Q"] + i, f"{c['group']} coordinate: {c.get('mode', c.get('body', ''))}")
                for i, c in enumerate(manifest["coordinates"])]
    for name, ref, what in outputs:
        f64(name, ref, "output", "continuous", what)
    structure = [f"    <Output valueReference=\"{ref}\"/>" for _, ref, _ in outputs]
    structure += [f"    <InitialUnknown valueReference=\"{ref}\"/>" for _, ref, _ in outputs]
    what = ("theta_dot, theta_ddot from the importer" if drive else f"manoeuvre {maneuver}" if maneuver
            else "drivers as in the scene")
    desc = f"{manifest.get('description', spec['name'])}; {opts.integrator} at dt = {opts.dt:g} s; {what}"
    return "\n".join([
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<fmiModelDescription fmiVersion="3.0" modelName={quoteattr(spec["name"])} '
        f'instantiationToken={quoteattr(token(manifest, opts))} description={quoteattr(desc)} '
        f'generationTool={quoteattr(manifest["generator"])} variableNamingConvention="flat">',
        f'  <CoSimulation modelIdentifier="{model_identifier(spec["name"])}" '
        'canHandleVariableCommunicationStepSize="true" '
        f'fixedInternalStepSize="{_num(opts.dt)}" canGetAndSetFMUState="false" '
        'canSerializeFMUState="false" providesDirectionalDerivatives="false" '
        'providesAdjointDerivatives="false" canBeInstantiatedOnlyOncePerProcess="false" '
        'hasEventMode="false" providesIntermediateUpdate="false" canReturnEarlyAfterIntermediateUpdate="false" '
        'maxOutputDerivativeOrder="0" canInterpolateInputs="false"/>',
        '  <LogCategories>',
        '    <Category name="logStatusError" description="an invalid call or value, or an unsupported function"/>',
        '    <Category name="logStatusDiscard" description="the simulation stopped (divergence, Newton failure)"/>',
        '  </LogCategories>',
        f'  <DefaultExperiment startTime="0" stopTime="{_num(opts.t_end)}" stepSize="{_num(opts.interval)}"/>',
        '  <ModelVariables>', *var, '  </ModelVariables>',
        '  <ModelStructure>', *structure, '  </ModelStructure>',
        '</fmiModelDescription>', ""])


def build_binary(gen_dir: Path, manifest: dict, opts: FmuOptions, work: Path) -> Path:
    """Compile ID.so in work (CMake, the toolchain of build.py)."""
    ident = model_identifier(manifest["spec"]["name"])
    cfg = work / "config"
    cfg.mkdir()
    (cfg / "flexsym_fmu_config.h").write_text(config_header(manifest, opts), encoding="utf-8")
    cmake, compiler, bdir = find_cmake(), find_compiler(), work / "build"
    runtime = ";".join(map(str, runtime_objects(FMU_FLAGS, "fmu-")))  # compiled once, in the cache
    _run([cmake, "-S", str(runtime_dir() / "fmi3"), "-B", str(bdir), f"-DFLEXSYM_MODEL_DIR={gen_dir}",
          f"-DFLEXSYM_FMU_CONFIG_DIR={cfg}", f"-DFLEXSYM_FMU_ID={ident}", f"-DCMAKE_C_COMPILER={compiler}",
          "-DCMAKE_BUILD_TYPE=Release", f"-DFLEXSYM_FMU_RUNTIME_OBJECTS={runtime}"],
         f"configuring the FMU of '{ident}'")
    _run([cmake, "--build", str(bdir), "-j", "2"], f"compiling the FMU of '{ident}'")
    return bdir / f"{ident}.so"


def export_fmu(gen_dir: Path, opts: FmuOptions, out: Path) -> Path:
    """Write out (atomically: a complete FMU or none; an earlier file is kept until then, and kept
    when writing fails, e.g. with the disk full: OutputError, one line naming out)."""
    from flexsym.core.files import atomic_write

    gen_dir = Path(gen_dir).resolve()
    manifest = read_manifest(gen_dir)
    ident = model_identifier(manifest["spec"]["name"])
    with tempfile.TemporaryDirectory(prefix="flexsym-fmu-") as tmp:
        so = build_binary(gen_dir, manifest, opts, Path(tmp))
        with atomic_write(out, "wb") as fh, zipfile.ZipFile(fh, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr("modelDescription.xml", model_description(manifest, opts))
            z.write(so, f"binaries/{PLATFORM}/{ident}.so")
    return out


def bench(gen_dir: Path, built, opts: FmuOptions, repeat: int = 21) -> dict:
    """CPU time of the FMU's doStep loop (runtime_c/fmi3/fmu_bench.c: instantiate, initialize,
    doStep every opts.interval reading every output, free) against the native driver's
    integration on the same steps and rows (fsr_simulate), medians of `repeat` runs."""
    import json
    import subprocess

    from flexsym.toolchain.run import run_built

    gen_dir = Path(gen_dir).resolve()
    manifest = read_manifest(gen_dir)
    lay = _layout(manifest)
    vrs = [str(lay["vr"]["Y"] + i) for i in range(lay["ny"] + lay["nq"])]
    with tempfile.TemporaryDirectory(prefix="flexsym-fmu-bench-") as tmp:
        so = build_binary(gen_dir, manifest, opts, Path(tmp))
        exe = Path(tmp) / "fmu_bench"
        _run([find_compiler(), "-std=c99", "-O2", "-Wall", f"-I{runtime_dir() / 'fmi3'}",
              str(runtime_dir() / "fmi3" / "fmu_bench.c"), "-o", str(exe), "-ldl"], "compiling fmu_bench")
        proc = subprocess.run([str(exe), str(so), token(manifest, opts), repr(opts.t_end), repr(opts.interval),
                               str(repeat), *vrs], capture_output=True, text=True)
        if proc.returncode != 0:
            raise SpecError(f"fmu_bench failed: {proc.stderr.strip()}")
        fmu = json.loads(proc.stdout)
    every = int(round(opts.interval / opts.dt))
    native = run_built(built, t_end=opts.t_end, dt=opts.dt, integrator=opts.integrator, params=opts.params,
                       out_every=every, repeat=repeat, tol=opts.tol, step=opts.step).summary
    return {"fmu": fmu["cpu_median"], "fmu_min": fmu["cpu_min"], "fmu_max": fmu["cpu_max"],
            "native": native["cpu_median"], "native_min": native["cpu_min"], "native_max": native["cpu_max"],
            "steps": native["steps"], "communication_steps": fmu["steps"],
            "ratio": fmu["cpu_median"] / native["cpu_median"]}


__all__ = ["FmuOptions", "check_request", "export_fmu", "model_description", "bench", "INPUT_MODES"]
