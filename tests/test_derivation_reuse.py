"""A beam's section values (rho, E, A, I; in 3D also Iy, J, G) are run-time parameters of a
system, never numbers of its derivation: they reach the generated folder only as the defaults
of p (system.c's param_defaults). So a system whose sections' values alone changed (a density
edited in its scene) is not derived again (pipeline: its derivation kept per
derivation_fingerprint) and its kernels are not compiled again (build: once per derivation),
and its rows are those of the first build run with the new values as --param."""
from __future__ import annotations

import difflib
import json
import shutil

import numpy as np
import pytest

from flexsym.codegen.sysgen import derivation_fingerprint, derive_folder, fingerprint, folder_files
from flexsym.core.paths import cache_dir
from flexsym.scenes.system_scene import system_from_dict
from flexsym.toolchain.pipeline import prepare_system, system_folder
from flexsym.toolchain.run import run_built

from system_data import run_ok


def _pendulum(model="m3", name: str = "reuse", **section) -> dict:
    """A flexible pendulum hung from a pin (S3's shape) with a stress output, so that A and I
    appear in an output's expression as well as in the energies."""
    sec = {"density": 2700.0, "youngs_modulus": 7e10, "area": 1e-4, "inertia": 2e-10} | section
    return {"system": {"name": name}, "gravity": {"g": [0.0, -9.81]},
            "body": [{"name": "beam", "kind": "beam", "length": 1.0, "model": model} | sec],
            "joint": [{"name": "pin", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0],
                       "child": "beam.root", "initial": 0.6}],
            "output": {"columns": {"w_mid": "w(beam, 0.5)", "s_root": "sigma(beam, 0.1, 0.004)",
                                   "M_mid": "M(beam, 0.5)"}}}


def _blade(**section) -> dict:
    """A spatial beam on a guided hub (S5's shape), tilted so that both bending planes and the
    twist take part: every spatial section value (Iy, J, G) reaches the energies."""
    sec = {"density": 7800.0, "youngs_modulus": 2.1e11, "area": 2e-4, "inertia_z": 1.5e-9,
           "inertia_y": 0.8e-9, "torsion_constant": 2e-9, "shear_modulus": 8e10} | section
    return {"system": {"name": "reuse3", "dimension": 3}, "gravity": {"g": [0.0, 0.0, -9.81]},
            "body": [{"name": "beam", "kind": "beam", "length": 0.8,
                      "model": {"strain": "foreshortening", "axial": [], "bending": ["cf1", "cf2"]}} | sec],
            "joint": [{"name": "hub", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0, 0.0],
                       "child": "beam.root", "axis": [0.0, 0.3, 1.0]}],
            "driver": [{"name": "spin", "kind": "guided", "joint": "hub",
                        "theta": "3*t**2"}],
            "output": {"columns": {"w_tip": "vz(beam, tip)", "T_root": "Mx(beam, root)",
                                   "My_root": "My(beam, root)", "s_root": "sigma(beam, 0.1, 0.004, 0.003)"}}}


OTHER_2D = {"density": 7800.0, "youngs_modulus": 2.1e11, "area": 1.3e-4, "inertia": 3.1e-10}
OTHER_3D = {k.replace("inertia", "inertia_z"): v for k, v in OTHER_2D.items()} | {
    "inertia_y": 1.7e-9, "torsion_constant": 9e-10, "shear_modulus": 7.9e10}


def _forget(system) -> None:
    """Remove system's folder and builds from the cache (a cache kept between runs,
    FLEXSYM_TEST_CACHE, may hold them), not its derivation nor its compiled kernels."""
    for folder in [system_folder(system), *(cache_dir() / "build").glob(f"{system.name}-*")]:
        shutil.rmtree(folder, ignore_errors=True)


def _system(data):
    return system_from_dict(json.loads(json.dumps(data)), name=data["system"]["name"])


@pytest.mark.parametrize("case", ["planar", "planar-exact", "spatial"])
def test_a_sections_values_reach_only_the_parameter_defaults(case):
    """Derived from scratch with other section values, the folder differs from the first in
    the fingerprints and the run-time parameters' defaults alone; the kernels, their header and
    CMakeLists.txt are byte for byte the same; and the folder made from the first system's
    derivation with the other values put in is the second's, byte for byte."""
    if case == "spatial":
        first, second = _system(_blade()), _system(_blade(**OTHER_3D))
    else:
        model = "exact" if case == "planar-exact" else "m3"
        first, second = _system(_pendulum(model)), _system(_pendulum(model, **OTHER_2D))
    assert fingerprint(first) != fingerprint(second)
    assert derivation_fingerprint(first) == derivation_fingerprint(second)
    derived = derive_folder(first)
    a, b = folder_files(first, derived), folder_files(second, derive_folder(second))
    assert folder_files(second, derived) == b  # the kept derivation gives the fresh folder
    shared = json.loads(a["manifest.json"])["kernels_inputs"]
    assert {"CMakeLists.txt", f"fsm_{first.name}.h", "kernels.c"} <= set(shared)  # kernels.cmake: exact's
    for name in shared:
        assert a[name] == b[name], name
    changed = [line for line in difflib.unified_diff(a["system.c"].splitlines(), b["system.c"].splitlines(),
                                                      lineterm="", n=0)
               if line[:1] in "+-" and not line.startswith(("+++", "---"))]
    assert len(changed) == 6, changed  # the banner's fingerprint, the struct's and param_defaults
    assert sum("param_defaults[] =" in line for line in changed) == 2
    assert sum(fingerprint(first) in line for line in changed) == 2
    b_values = [p["default"] for p in json.loads(b["manifest.json"])["params"]]
    assert b_values[:4] == [7800.0, 2.1e11, 1.3e-4, 3.1e-10]


def test_a_density_edited_in_a_scene_is_neither_derived_nor_compiled_again():
    """The second system (other rho, E, A, I) takes the first one's derivation and compiled
    kernels: no derivation line, one kernels build, a model build that compiled system.c alone;
    its rows are those of the first build run with --param for the new values, bit for bit."""
    first, second = _system(_pendulum()), _system(_pendulum(**OTHER_2D))
    _forget(first)
    _forget(second)
    one = prepare_system(first, log=lambda m: None)
    said = []
    two = prepare_system(second, log=said.append)
    assert not any("deriving" in s for s in said) and any("derivation reused" in s for s in said), said
    assert not list(two.build_dir.rglob("kernels.c.o"))  # linked from the kernels' own build
    kernels = [d for d in (one.build_dir.parent / ".kernels").glob("reuse-*") if d.is_dir()]
    assert len(kernels) == 1
    options = dict(t_end=0.3, dt=1e-4, integrator="genalpha")
    params = {"rho": 7800.0, "E": 2.1e11, "A": 1.3e-4, "I": 3.1e-10}
    edited, passed = run_ok(two, **options), run_ok(one, params=params, **options)
    assert edited.columns == passed.columns
    for c in edited.columns:
        assert np.array_equal(edited[c], passed[c]), c
    assert np.max(np.abs(edited["w_mid"])) > 1e-4  # the run moved: the check is not vacuous
    unedited = run_ok(one, **options)
    assert not np.array_equal(unedited["w_mid"], edited["w_mid"])  # the values took effect


def test_a_derivation_kept_in_a_damaged_file_is_derived_again():
    """A kept derivation that cannot be read or filled in is derived again, not trusted."""
    model = {"strain": "linear", "axial": [], "bending": ["cf1"]}  # small: derived twice here
    first, third = (_system(_pendulum(model, name="reuse_damaged", **extra)) for extra in ({}, {"area": 1.9e-4}))
    _forget(first)
    _forget(third)
    prepare_system(first, log=lambda m: None)
    kept = cache_dir() / "systems" / ".derived" / f"reuse_damaged-{derivation_fingerprint(first)[:20]}.json"
    kept.write_text(kept.read_text()[:-100])
    said = []
    built = prepare_system(third, log=said.append)
    assert any("deriving the equations" in s for s in said), said
    assert run_built(built, t_end=0.01, dt=1e-3, integrator="genalpha").ok


def test_rare_kernels_built_apart_at_O0_give_the_same_rows(monkeypatch):
    """A system whose rarely called kernels (sysgen.RARE_KERNELS: the energies, the Newton
    matrix's residual_jac) exceed their size go to kernels_rare.c, compiled at -O0: here forced
    by thresholds of 0 on the pendulum. The rows, with the energy columns that read them and
    the Newton matrix that genalpha builds, are those of the folder without the split, bit for
    bit; and a second section's folder links both kept kernel objects."""
    from flexsym.codegen import sysgen

    plain, split = _system(_pendulum(name="tiers_plain")), _system(_pendulum(name="tiers_split"))
    split2 = _system(_pendulum(name="tiers_split", **OTHER_2D))
    for s in (plain, split, split2):
        _forget(s)
    one = prepare_system(plain, log=lambda m: None)
    monkeypatch.setattr(sysgen, "RARE_KERNELS", {"energy": 0, "residual_jac": 0})
    two = prepare_system(split, log=lambda m: None)
    three = prepare_system(split2, log=lambda m: None)
    monkeypatch.undo()
    folder = system_folder(split)
    rare, hot = (folder / "kernels_rare.c").read_text(), (folder / "kernels.c").read_text()
    assert "fsm_tiers_split_energy(" in rare and "fsm_tiers_split_residual_jac(" in rare
    assert "fsm_tiers_split_energy(" not in hot and "fsm_tiers_split_force(" in hot
    assert "kernels_rare.c\" PROPERTIES COMPILE_OPTIONS -O0" in (folder / "kernels.cmake").read_text()
    assert "kernels.cmake" in (folder / "CMakeLists.txt").read_text()
    assert {"kernels_rare.c", "kernels.cmake"} <= set(json.loads((folder / "manifest.json").read_text())["kernels_inputs"])
    assert not (system_folder(plain) / "kernels_rare.c").exists()
    assert not (system_folder(plain) / "kernels.cmake").exists()
    options = dict(t_end=0.3, dt=1e-4, integrator="genalpha", energy=True, newton="full")
    a, b = run_ok(one, **options), run_ok(two, **options)
    assert a.columns == b.columns and "h" in a.columns
    for c in a.columns:
        assert np.array_equal(a[c], b[c]), c
    assert a.summary["jacobian_evaluations"] >= 3000  # residual_jac ran every step (full Newton)
    assert not list(three.build_dir.rglob("kernels*.c.o"))  # both objects linked from the kept build
    params = {"rho": 7800.0, "E": 2.1e11, "A": 1.3e-4, "I": 3.1e-10}
    c, d = run_ok(three, **options), run_ok(one, params=params, **options)
    for col in c.columns:
        assert np.array_equal(c[col], d[col]), col
