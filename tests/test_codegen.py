"""Generated C against casadi against sympy at random states; determinism; staleness."""
import hashlib
import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest
import sympy as sp

from flexsym.physics.energy import BEAM_PARAMS, alpha, w
from flexsym.codegen.folder import MANIFEST, read_manifest
from flexsym.codegen.generate import check_folder, generate_files
from flexsym.model.maneuver import t as t_sym
from flexsym.core.paths import generated_dir
from flexsym.model.variant import BUILTIN, builtin

from conftest import BUILTIN_NAMES

RTOL = 1e-12


def _random_inputs(rng, der):
    n = len(der.coords)
    w_, a_, t_ = rng.uniform(0.0, 8.0), rng.uniform(-1.0, 1.0), rng.uniform(0.0, 25.0)
    return {
        "q": rng.uniform(-0.5, 0.5, n),
        "qd": rng.uniform(-1.0, 1.0, n),
        "qdd": rng.uniform(-2.0, 2.0, n),
        "lambda": np.zeros(0),
        "w": w_, "alpha": a_,
        # the S0 kernels' drive d = [t, theta, theta', theta'']: a guided root without gravity,
        # so t and theta enter no kernel but the drive's
        "d": np.array([t_, rng.uniform(-3.0, 3.0), w_, a_]),
        "p": np.array([p.default for p in BEAM_PARAMS]) * rng.uniform(0.5, 2.0, len(BEAM_PARAMS)),
        "t": np.array([t_]),
        "mp": np.array([rng.uniform(1.0, 10.0), rng.uniform(2.0, 20.0)])[:len(der.maneuver.params)],
    }


def _sympy_reference(der):
    """The kernels of the variant's folder (its S0's) as sympy matrices of the one-beam
    derivation (coordinates without the body prefix, the hub's rate and acceleration w, alpha;
    its outputs from physics/outputs.py, not the system grammar; Jacobians differentiated in
    sympy, not casadi)."""
    T, V, h = der.energies()
    r = der.M * der.qdd - der.f
    man = der.maneuver
    return {
        "mass": [der.M], "force": [der.f], "residual_jac": [r.jacobian(der.q), r.jacobian(der.qd)],
        "outputs": [sp.Matrix(list(der.outputs.values()))], "energy": [sp.Matrix([T, V, h])],
        "drive": [sp.Matrix([t_sym, man.theta, man.rate, man.acceleration])],
    }


def _sympy_eval(der, expr, x):
    subs = {w: x["w"], alpha: x["alpha"], t_sym: x["t"][0]}
    for i, ps in enumerate(der.params):
        subs[ps] = x["p"][i]
    for i, mp in enumerate(der.maneuver.params):
        subs[mp.symbol] = x["mp"][i]
    for i in range(len(der.coords)):
        subs[der.q[i]], subs[der.qd[i]], subs[der.qdd[i]] = x["q"][i], x["qd"][i], x["qdd"][i]
    num = der.numeric(expr)
    fn = sp.lambdify(list(subs), num, "mpmath")
    return np.array(fn(*subs.values()).tolist(), dtype=float)


def check_c_casadi_sympy(der, lib, kernels, rng, trials: int) -> None:
    """A variant's compiled kernels (its S0's, the system path) against their casadi functions
    and against the one-beam sympy derivation, at random states."""
    reference = _sympy_reference(der)
    for trial in range(trials):
        x = _random_inputs(rng, der)
        for kname, sym_outs in reference.items():
            kernel = kernels[kname]
            ins = [x[p.name] for p in kernel.inputs]
            c_out = lib.call(kname, *ins)
            res = kernel.function(*ins)
            ca_out = [o.full() for o in (res if isinstance(res, (list, tuple)) else [res])]
            for port, c_val, ca_val, sym in zip(kernel.outputs, c_out, ca_out, sym_outs):
                c_val = np.asarray(c_val).reshape(port.rows, port.cols)
                ca_val = ca_val.reshape(port.rows, port.cols)
                sp_val = _sympy_eval(der, sym, x).reshape(port.rows, port.cols)
                scale = max(np.max(np.abs(sp_val)), 1e-300)
                assert np.max(np.abs(c_val - ca_val)) <= RTOL * scale, (kname, port.name, "C vs casadi")
                assert np.max(np.abs(c_val - sp_val)) <= RTOL * scale, (kname, port.name, "C vs sympy")


@pytest.mark.parametrize("name", BUILTIN_NAMES)
def test_c_matches_casadi_and_sympy(derivation, model, s0_kernels, name):
    check_c_casadi_sympy(derivation(name), model(name), s0_kernels(name),
                         np.random.default_rng(20261122), 5)


@pytest.mark.parametrize("name", BUILTIN_NAMES + ["prestress"])
def test_outputs_use_drive_flag_matches_the_outputs(derivation, name):
    """The runtime skips the manoeuvre for rows whose outputs do not read it; the flag comes
    from the inputs the emitted C reads, checked here against the sympy outputs (prestress:
    its axial force has the centrifugal prestress, so the flag is set)."""
    der = derivation(name)
    reads_drive = any(e.has(w, alpha) for e in der.outputs.values())
    manifest = read_manifest(generated_dir() / builtin(name).name)
    assert manifest["outputs_use_drive"] == reads_drive
    assert reads_drive == (name == "prestress")


def test_generation_is_deterministic_within_a_process():
    spec = builtin("m3")
    a = generate_files(spec)
    b = generate_files(spec)
    assert a == b


def _hash_in_subprocess(seed: str) -> str:
    code = ("import hashlib, json; from flexsym.codegen.generate import generate_files; "
            "from flexsym.model.variant import builtin; "
            "f = generate_files(builtin('m2')); "
            "print(hashlib.sha256(json.dumps(f, sort_keys=True).encode()).hexdigest())")
    env = dict(os.environ, PYTHONHASHSEED=seed)
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    return out.stdout.strip()


def test_generation_is_deterministic_across_hash_seeds():
    assert _hash_in_subprocess("0") == _hash_in_subprocess("12345")


@pytest.mark.parametrize("spec", BUILTIN, ids=lambda s: s.name)
def test_checked_in_code_is_current(spec):
    """generated/ must be exactly what the generator produces now (regenerate with
    `flexsym generate NAME` after changing flexsym/ or templates/)."""
    folder = generated_dir() / spec.name
    why = check_folder(spec, folder)
    assert why is None, why
    files = generate_files(spec)
    on_disk = {p.name: p.read_text(encoding="utf-8") for p in folder.iterdir() if p.is_file()}
    stale = sorted(n for n in files if on_disk.get(n) != files[n])
    extra = sorted(set(on_disk) - set(files))
    assert not stale and not extra, f"{spec.name}: stale {stale}, unexpected {extra}; " \
                                    f"run `flexsym generate {spec.name}`"


@pytest.mark.parametrize("name", ["hub", "slider_crank", "pendulum"])
def test_checked_in_system_folders_are_current(name):
    """generated/systems/ holds S1-S3's generated folders, so a change of the derivation or
    the system templates shows as a diff (regenerate with `flexsym generate all`)."""
    from flexsym.codegen.sysgen import generate_system_files
    from flexsym.toolchain.pipeline import golden_system_folder, golden_systems

    folder = golden_system_folder(name)
    files = generate_system_files(golden_systems()[name])
    on_disk = {p.name: p.read_text(encoding="utf-8") for p in folder.iterdir() if p.is_file()}
    stale = sorted(n for n in files if on_disk.get(n) != files[n])
    extra = sorted(set(on_disk) - set(files))
    assert not stale and not extra, f"system {name}: stale {stale}, unexpected {extra}; run `flexsym generate all`"
    assert set(golden_systems()) == {"hub", "slider_crank", "pendulum"}


def test_stale_or_edited_folders_are_detected(tmp_path):
    spec = builtin("m1")
    copy = tmp_path / spec.name
    shutil.copytree(generated_dir() / spec.name, copy)
    assert check_folder(spec, copy) is None
    kernels = copy / "kernels.c"
    kernels.write_text(kernels.read_text() + "/* hand edit */\n")
    assert "edited by hand" in check_folder(spec, copy)
    # A manifest from another generator version: fingerprint mismatch.
    shutil.rmtree(copy)
    shutil.copytree(generated_dir() / spec.name, copy)
    m = read_manifest(copy)
    m["fingerprint"] = "0" * 64
    (copy / MANIFEST).write_text(json.dumps(m))
    assert "another spec or generator version" in check_folder(spec, copy)
    assert "no readable" in check_folder(spec, tmp_path / "missing")


def test_generated_files_carry_do_not_edit_header_and_op_counts():
    folder = generated_dir() / "geometric"
    manifest = read_manifest(folder)
    # the kernels, their header and build carry the derivation's fingerprint (shared by every
    # folder of the derivation), system.c the folder's
    for name, fp in (("kernels.c", "derivation"), ("fsm_geometric.h", "derivation"),
                     ("CMakeLists.txt", "derivation"), ("system.c", "fingerprint")):
        text = (folder / name).read_text()
        assert "DO NOT EDIT" in text and manifest[fp] in text, name
    kernels_c = (folder / "kernels.c").read_text()
    for k, info in manifest["kernels"].items():
        assert f" * ops: {info['total_ops']} */" in kernels_c, k
    assert manifest["versions"]["sympy"] == sp.__version__
    for f, digest in manifest["files"].items():
        assert hashlib.sha256((folder / f).read_bytes()).hexdigest() == digest
