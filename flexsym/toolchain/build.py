"""Compile a generated folder with CMake into a content-addressed build directory.

The build key hashes the generated files, the runtime sources and the compiler, so an
unchanged variant is never rebuilt. Builds happen in a private temporary directory that is
renamed into place when complete: two runs building the same variant at once both end with
a complete build and neither sees a half-built one.
"""
from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

from flexsym.core.errors import ToolchainError
from flexsym.codegen.generate import folder_hash, read_manifest
from flexsym.core.paths import cache_dir, file_lock, runtime_dir

COMPLETE = ".complete"
# A checking build (tests/test_sanitizers.py): every generated variant and the runtime under
# AddressSanitizer and UndefinedBehaviorSanitizer, float-to-integer overflow included; the
# first error aborts the run.
SANITIZE_FLAGS = "-fsanitize=address,undefined,float-cast-overflow -fno-sanitize-recover=all -fno-omit-frame-pointer -g"


@dataclass(frozen=True)
class Built:
    name: str
    build_dir: Path
    executable: Path
    library: Path


def find_compiler() -> str:
    cc = os.environ.get("CC")
    candidates = [cc] if cc else ["cc", "gcc", "clang"]
    for c in candidates:
        path = shutil.which(c)
        if path:
            return path
    looked = f"CC={cc}" if cc else "cc, gcc, clang"
    raise ToolchainError(f"no C compiler found (looked for {looked}); install one "
                         "(Debian/Ubuntu: apt install gcc) or set CC")


def find_cmake() -> str:
    try:  # the PyPI cmake package (a dependency) ships its own binary
        import cmake

        exe = Path(cmake.CMAKE_BIN_DIR) / "cmake"
        if exe.exists():
            return str(exe)
    except ImportError:
        pass
    path = shutil.which("cmake")
    if not path:
        raise ToolchainError("cmake not found: `pip install cmake` (a flexsym dependency)")
    return path


def _runtime_hash() -> str:
    h = hashlib.sha256()
    root = runtime_dir()
    for f in sorted(root.rglob("*")):
        if f.is_file() and f.suffix in (".c", ".h", ".cmake"):
            h.update(str(f.relative_to(root)).encode() + b"\0" + f.read_bytes())
    return h.hexdigest()


def build_key(gen_dir: Path, compiler: str, flags: str = "") -> str:
    h = hashlib.sha256()
    h.update(folder_hash(gen_dir).encode())
    h.update(_runtime_hash().encode())
    h.update(compiler.encode())
    h.update(flags.encode())
    return h.hexdigest()[:20]


def _run(cmd: list[str], what: str, cwd: Path | None = None) -> None:
    proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    if proc.returncode != 0:
        tail = "\n".join((proc.stdout + proc.stderr).strip().splitlines()[-25:])
        raise ToolchainError(f"{what} failed (exit {proc.returncode}):\n{tail}")


def build(gen_dir: Path, jobs: int = 2, root: Path | None = None, sanitize: bool = False,
          log=None) -> Built:
    """Build (or reuse) gen_dir under root (default: the cache's build folder); sanitize: a
    separate build with SANITIZE_FLAGS; log(msg): a line when it compiles."""
    gen_dir = Path(gen_dir).resolve()
    manifest = read_manifest(gen_dir)
    if manifest is None:
        raise ToolchainError(f"{gen_dir} is not a generated variant (no manifest.json)")
    name = manifest["spec"]["name"]
    compiler = find_compiler()
    cmake = find_cmake()
    root = Path(root) if root is not None else cache_dir() / "build"
    flags = SANITIZE_FLAGS if sanitize else ""
    final = root / f"{name}-{'asan-' if sanitize else ''}{build_key(gen_dir, compiler, flags)}"
    built = Built(name, final, final / f"flexsym_{name}", final / f"libflexsym_{name}.so")
    if _complete(built):
        return built
    with file_lock(root / f".{final.name}.lock"):
        if not _complete(built):  # not built meanwhile by another process
            if final.exists():  # marked complete but an artefact is gone: built again
                shutil.rmtree(final)
            if log:
                log(f"compiling '{name}' (cmake, {Path(compiler).name})")
            _build_into(gen_dir, final, name, cmake, compiler, jobs, flags)
    return built


def _complete(built: Built) -> bool:
    """The marker and the artefacts it vouches for (a library deleted by hand is rebuilt)."""
    return all(p.is_file() for p in (built.build_dir / COMPLETE, built.executable, built.library))


def _build_into(gen_dir: Path, final: Path, name: str, cmake: str, compiler: str, jobs: int,
                flags: str = "") -> None:
    root = final.parent
    tmp = Path(tempfile.mkdtemp(prefix=f".{name}-", dir=root))
    try:
        _run([cmake, "-S", str(gen_dir), "-B", str(tmp), f"-DFLEXSYM_RUNTIME_DIR={runtime_dir()}",
              f"-DCMAKE_C_COMPILER={compiler}", "-DCMAKE_BUILD_TYPE=Release"]
             + ([f"-DCMAKE_C_FLAGS={flags}", f"-DCMAKE_EXE_LINKER_FLAGS={flags}",
                 f"-DCMAKE_SHARED_LINKER_FLAGS={flags}"] if flags else []),
             f"configuring variant '{name}'")
        _run([cmake, "--build", str(tmp), "-j", str(jobs)], f"compiling variant '{name}'")
        (tmp / COMPLETE).write_text(str(gen_dir) + "\n")
        os.rename(tmp, final)  # atomic: a build directory is complete or absent
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
