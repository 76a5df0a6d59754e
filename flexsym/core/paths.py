"""Where flexsym finds its templates, runtime and checked-in generated code, and its cache."""
from __future__ import annotations

import fcntl
import os
from contextlib import contextmanager
from pathlib import Path

from flexsym.core.errors import FlexsymError

PACKAGE_DIR = Path(__file__).resolve().parent.parent  # the flexsym package


def module_file(dotted: str) -> Path:
    """The source file of a flexsym module given as "layer.module"."""
    return PACKAGE_DIR.joinpath(*dotted.split(".")).with_suffix(".py")


def _resource(name: str) -> Path:
    # A wheel carries the folders inside the package (flexsym/_data/NAME); a source
    # checkout or editable install has them next to the flexsym package.
    for candidate in (PACKAGE_DIR / "_data" / name, PACKAGE_DIR.parent / name):
        if candidate.is_dir():
            return candidate
    raise FlexsymError(f"flexsym installation is incomplete: folder '{name}' not found next to "
                       f"{PACKAGE_DIR}")


def templates_dir() -> Path:
    return _resource("templates")


def runtime_dir() -> Path:
    return _resource("runtime_c")


def generated_dir() -> Path:
    return _resource("generated")


@contextmanager
def file_lock(path: Path):
    """An exclusive advisory lock (flock) held for the block: one generator or builder per
    target at a time, across processes; released when the process dies."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def cache_dir() -> Path:
    """FLEXSYM_CACHE, else $XDG_CACHE_HOME/flexsym, else ~/.cache/flexsym."""
    env = os.environ.get("FLEXSYM_CACHE")
    if env:
        return Path(env).expanduser().resolve()
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "flexsym"
