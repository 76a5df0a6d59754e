"""Two generated models in one program (tests/c_models/two_models.c): the one-beam variant
`geometric` and the system `hub`, from their checked-in folders, link side by side because every
global symbol of a generated folder is named after its model and every runtime entry point takes
the model as a struct. Each model's rows there are those of its own driver, built alone by the
pipeline, character for character."""
from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

from flexsym.core.paths import generated_dir, runtime_dir
from flexsym.toolchain.build import build, find_cmake, find_compiler

C_MODELS = Path(__file__).parent / "c_models"


def test_two_generated_models_in_one_program(tmp_path):
    out = tmp_path / "build"
    for cmd in ([find_cmake(), "-S", str(C_MODELS), "-B", str(out), "-DCMAKE_BUILD_TYPE=Release",
                 f"-DCMAKE_C_COMPILER={find_compiler()}"],
                [find_cmake(), "--build", str(out), "--target", "two_models", "-j", "2"]):
        proc = subprocess.run(cmd, capture_output=True, text=True)
        assert proc.returncode == 0, proc.stdout + proc.stderr
    together = {name: tmp_path / f"{name}_together.csv" for name in ("geometric", "hub")}
    proc = subprocess.run([str(out / "two_models"), "1.0", str(together["geometric"]), str(together["hub"])],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stdout + proc.stderr  # geometric run twice: identical rows
    assert json.loads(proc.stdout)["repeat_identical"] == 1
    for name, folder in (("geometric", generated_dir() / "geometric"), ("hub", generated_dir() / "systems" / "hub")):
        alone = tmp_path / f"{name}_alone.csv"
        run = subprocess.run([str(build(folder).executable), "--t-end", "1.0", "--out", str(alone)],
                             capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        rows = alone.read_text().splitlines()[1:]  # without the header
        assert len(rows) == 1001
        assert together[name].read_text().splitlines() == rows, name


def test_a_model_linked_with_the_cached_runtime_is_the_one_compiling_it(tmp_path):
    """build() compiles the runtime once per compiler and flags and links its objects into each
    model (runtime_c/CMakeLists.txt, FLEXSYM_RUNTIME_OBJECTS), and a system's kernels once per
    derivation (FLEXSYM_KERNELS_OBJECTS): the driver and the library are byte for byte those of
    a plain CMake build of the generated folder, which compiles all the sources itself."""
    folder = generated_dir() / "systems" / "hub"
    built = build(folder, root=tmp_path / "cache")
    plain = tmp_path / "plain"
    for cmd in ([find_cmake(), "-S", str(folder), "-B", str(plain), "-DCMAKE_BUILD_TYPE=Release",
                 f"-DCMAKE_C_COMPILER={find_compiler()}", f"-DFLEXSYM_RUNTIME_DIR={runtime_dir()}"],
                [find_cmake(), "--build", str(plain), "-j", "2"]):
        proc = subprocess.run(cmd, capture_output=True, text=True)
        assert proc.returncode == 0, proc.stdout + proc.stderr
    runtime = next(d for d in (tmp_path / "cache" / ".runtime").iterdir() if d.is_dir())  # not its lock
    listed = (runtime / "objects.txt").read_text().split()
    assert len(listed) >= 10 and all(o.endswith(".c.o") for o in listed)
    for mine, theirs in ((built.executable, plain / "flexsym_hub"), (built.library, plain / "libflexsym_hub.so")):
        assert mine.read_bytes() == theirs.read_bytes(), mine.name
    assert not list(built.build_dir.rglob("linalg.c.o"))  # the model's build compiled no runtime
    # its kernels, compiled in this first build, are kept; a build of a folder with the same
    # kernels (here: the same folder again) links them, and its binaries are the same again
    kept = next(d for d in (tmp_path / "cache" / ".kernels").iterdir() if d.is_dir())
    assert [o.endswith("kernels.c.o") for o in (kept / "objects.txt").read_text().split()] == [True]
    shutil.rmtree(built.build_dir)
    again = build(folder, root=tmp_path / "cache")
    assert not list(again.build_dir.rglob("kernels.c.o"))
    for mine, theirs in ((again.executable, plain / "flexsym_hub"), (again.library, plain / "libflexsym_hub.so")):
        assert mine.read_bytes() == theirs.read_bytes(), mine.name
