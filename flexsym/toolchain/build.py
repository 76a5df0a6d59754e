"""Compile a generated folder with CMake into a content-addressed build directory.

The build key hashes the generated files, the runtime sources and the compiler, so an
unchanged variant is never rebuilt. Builds happen in a private temporary directory that is
renamed into place when complete: two runs building the same variant at once both end with
a complete build and neither sees a half-built one. The runtime is compiled once per compiler
and flags (build/.runtime/) and its objects are linked into every model, which then compiles
its own sources alone: the binaries are byte for byte those of a plain CMake build. A system's
kernels are compiled once per derivation: the first build of a derivation keeps their objects
(build/.kernels/), and folders that differ in the values of run-time parameters alone (a density
edited in a scene) link them and compile only their system.c.
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
from flexsym.codegen.folder import folder_hash, read_manifest
from flexsym.core.paths import cache_dir, file_lock, runtime_dir

COMPLETE = ".complete"
OBJECTS = "objects.txt"  # the objects of a build made once for many (the runtime, a system's kernels)
KERNELS = "kernels_objects.txt"  # a system's kernels' objects, listed by its build (flexsym_add_kernels)
# A checking build (tests/test_sanitizers.py): every generated variant and the runtime under
# AddressSanitizer and UndefinedBehaviorSanitizer, float-to-integer overflow included; the
# first error aborts the run.
SANITIZE_FLAGS = "-fsanitize=address,undefined,float-cast-overflow -fno-sanitize-recover=all -fno-omit-frame-pointer -g"
# An FMU's runtime (flexsym_add_fmu: C_VISIBILITY_PRESET hidden): it exports its fmi3* functions alone
FMU_FLAGS = "-fvisibility=hidden"


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
        if f.is_file() and (f.suffix in (".c", ".h", ".cmake") or f.name == "CMakeLists.txt"):
            h.update(str(f.relative_to(root)).encode() + b"\0" + f.read_bytes())
    return h.hexdigest()


def build_key(gen_dir: Path | None, compiler: str, flags: str = "") -> str:
    """The key of a build of gen_dir (None: of the runtime alone) with compiler and flags."""
    h = hashlib.sha256()
    if gen_dir is not None:
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
    tag = "asan-" if sanitize else ""
    final = root / f"{name}-{tag}{build_key(gen_dir, compiler, flags)}"
    built = Built(name, final, final / f"flexsym_{name}", final / f"libflexsym_{name}.so")
    if not _complete(built):
        objects = runtime_objects(flags, tag, root, jobs)
        defines = [f"-DFLEXSYM_RUNTIME_OBJECTS={';'.join(map(str, objects))}"]
        listing = None  # a system's kernels: linked when kept, else compiled here and kept
        if manifest.get("kernels_inputs"):
            kept = root / ".kernels" / f"{name}-{tag}{_kernels_key(gen_dir, manifest, compiler, flags)}"
            if _objects_complete(kept):
                defines.append(f"-DFLEXSYM_KERNELS_OBJECTS={';'.join(map(str, _listed(kept)))}")
            else:
                listing = KERNELS

        def make():
            if log:
                log(f"compiling '{name}' (cmake, {Path(compiler).name})")
            _cmake_into(gen_dir, final, f"variant '{name}'", cmake, compiler, jobs, flags, defines,
                        listing=listing)
        _once(final, lambda: _complete(built), make)
        if listing and (final / KERNELS).is_file():
            _keep_kernels(final, kept)
    return built


def _keep_kernels(build_dir: Path, kept: Path) -> None:
    """The kernels' objects that a system's build compiled (its KERNELS listing), copied to
    kept, for the next folder of the same derivation to link (FLEXSYM_KERNELS_OBJECTS): a
    system whose sections' values alone differ (a density edited in its scene) then compiles
    only its system.c."""
    def copy(tmp: Path) -> None:
        names = []
        for line in (build_dir / KERNELS).read_text().split():
            names.append(f"{len(names)}-{Path(line).name}")
            shutil.copyfile(build_dir / line, tmp / names[-1])
        (tmp / OBJECTS).write_text("".join(f"{n}\n" for n in names))
    _once(kept, lambda: _objects_complete(kept), lambda: _atomic_dir(kept, copy, build_dir))


def _kernels_key(gen_dir: Path, manifest: dict, compiler: str, flags: str) -> str:
    """The key of a system's compiled kernels: the files they are compiled from (its manifest's
    kernels_inputs: the kernels, their header, the CMakeLists.txt that sets their flags), the
    runtime, the compiler and the flags."""
    h = hashlib.sha256()
    for name in sorted(manifest["kernels_inputs"]):
        if name not in manifest.get("files", {}):
            raise ToolchainError(f"{gen_dir}: kernels_inputs names '{name}', not a file of the folder")
        h.update(name.encode() + b"\0" + (gen_dir / name).read_bytes())
    h.update(_runtime_hash().encode())
    h.update(compiler.encode())
    h.update(flags.encode())
    return h.hexdigest()[:20]


def _objects_complete(final: Path) -> bool:
    """A build made once for many (the runtime, a system's kernels): its marker, its listing
    and every object listed (one deleted by hand is made again)."""
    return ((final / COMPLETE).is_file() and (final / OBJECTS).is_file()
            and all(p.is_file() for p in _listed(final)))


def runtime_objects(flags: str = "", tag: str = "", root: Path | None = None, jobs: int = 2) -> list[Path]:
    """The runtime's objects, compiled once per compiler and flags into root/.runtime/ (default
    root: the cache's build folder; runtime_c's CMakeLists.txt: the target and flags every
    model's build would compile them with, plus flags)."""
    compiler, cmake = find_compiler(), find_cmake()
    root = Path(root) if root is not None else cache_dir() / "build"
    final = root / ".runtime" / f"{tag}{build_key(None, compiler, flags)}"
    _once(final, lambda: _objects_complete(final),
          lambda: _cmake_into(runtime_dir(), final, "the runtime", cmake, compiler, jobs, flags, [],
                              listing=OBJECTS))
    return _listed(final)


def _listed(final: Path) -> list[Path]:
    return [final / line for line in (final / OBJECTS).read_text().split()]


def _once(final: Path, complete, make) -> None:
    """make() unless complete(), under a lock on final: two processes building the same thing
    at once both end with it complete and neither sees it half-built."""
    if complete():
        return
    with file_lock(final.parent / f".{final.name}.lock"):
        if not complete():  # not built meanwhile by another process
            if final.exists():  # marked complete but an artefact is gone: built again
                shutil.rmtree(final)
            make()


def _complete(built: Built) -> bool:
    """The marker and the artefacts it vouches for (a library deleted by hand is rebuilt)."""
    return all(p.is_file() for p in (built.build_dir / COMPLETE, built.executable, built.library))


def _cmake_into(source: Path, final: Path, what: str, cmake: str, compiler: str, jobs: int,
                flags: str, defines: list[str], listing: str | None = None) -> None:
    """Configure and build the CMake project source in a private directory renamed to final
    when complete (atomic: final is complete or absent). listing: the name of a file of object
    paths the build wrote, rewritten relative to the build directory (which is renamed)."""
    def configure_and_build(tmp: Path) -> None:
        _run([cmake, "-S", str(source), "-B", str(tmp), f"-DFLEXSYM_RUNTIME_DIR={runtime_dir()}",
              f"-DCMAKE_C_COMPILER={compiler}", "-DCMAKE_BUILD_TYPE=Release", *defines]
             + ([f"-DCMAKE_C_FLAGS={flags}", f"-DCMAKE_EXE_LINKER_FLAGS={flags}",
                 f"-DCMAKE_SHARED_LINKER_FLAGS={flags}"] if flags else []),
             f"configuring {what}")
        _run([cmake, "--build", str(tmp), "-j", str(jobs)], f"compiling {what}")
        if listing is not None:
            listed = (tmp / listing).read_text().split()
            (tmp / listing).write_text("".join(f"{Path(p).relative_to(tmp)}\n" for p in listed))
    _atomic_dir(final, configure_and_build, source)


def _atomic_dir(final: Path, fill, origin: Path) -> None:
    """fill(tmp) in a private directory beside final, marked complete (naming origin) and
    renamed to final: final is complete or absent, never half-made."""
    final.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{final.name}-", dir=final.parent))
    try:
        fill(tmp)
        (tmp / COMPLETE).write_text(str(origin) + "\n")
        os.rename(tmp, final)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
