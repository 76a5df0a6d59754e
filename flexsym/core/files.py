"""Reading a user's file with limits (regular files only, at most a given size), and writing
outputs so that a failure leaves nothing half-written and keeps what was there.

Every output file goes through _fdopen (the one place a descriptor becomes a file object; the
tests make the disk fill up there), and every OSError while writing becomes one OutputError line
naming the file: "no space left on device writing FILE" (exit 5, as the toolchain's: the
machine, not the input).
"""
from __future__ import annotations

import errno
import os
import secrets
import shutil
import stat
from contextlib import contextmanager
from pathlib import Path

from flexsym.core.errors import OutputError, SpecError


def read_limited(path, limit: int, what: str = "file") -> bytes:
    """The bytes of path (FileNotFoundError when missing); SpecError naming it when it is not a regular file (a FIFO,
    a device such as /dev/zero, a directory: reading it may never end) or larger than limit."""
    path = Path(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)  # a FIFO without writer: no wait
    except FileNotFoundError:
        raise  # the caller names what is missing
    except OSError as exc:
        raise SpecError(f"{path}: cannot read: {exc.strerror}") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise SpecError(f"{path}: not a regular file (a {what} must be a file, not a device, "
                            "FIFO or directory)")
        if st.st_size > limit:
            raise SpecError(f"{path}: {st.st_size} bytes is larger than the limit of {limit} bytes "
                            f"for a {what}")
        with os.fdopen(fd, "rb", closefd=True) as fh:
            fd = None
            data = fh.read(limit + 1)
        if len(data) > limit:
            raise SpecError(f"{path}: larger than the limit of {limit} bytes for a {what}")
        return data
    finally:
        if fd is not None:
            os.close(fd)


# ------------------------------------------------------------------------------- writing

def output_error(exc: OSError, path) -> OutputError:
    """One line for an OSError met while writing path."""
    if exc.errno == errno.ENOSPC:
        return OutputError(f"no space left on device writing {path}")
    if exc.errno == errno.EDQUOT:
        return OutputError(f"disk quota exceeded writing {path}")
    return OutputError(f"{exc.strerror or exc} writing {path}")


@contextmanager
def writing(path):
    """Turn an OSError raised in the block into OutputError naming path."""
    try:
        yield
    except OSError as exc:
        raise output_error(exc, path) from None


def _fdopen(fd: int, mode: str):
    """The file object of an output's descriptor (text: UTF-8, newlines as written)."""
    if "b" in mode:
        return os.fdopen(fd, mode)
    return os.fdopen(fd, mode, encoding="utf-8", newline="")


def _new_sibling(path: Path, kind: str) -> Path:
    return path.with_name(f".{path.name}.{kind}-{secrets.token_hex(4)}")


def create(path, mode: str = "w"):
    """A new file (never an existing one), permissions as any new file (0666 less the umask)."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o666)
    try:
        return _fdopen(fd, mode)
    except BaseException:
        os.close(fd)
        raise


@contextmanager
def atomic_write(path, mode: str = "w"):
    """Write path through a temporary sibling renamed over it when the block ends: a reader
    (and a crash) sees the old file or the complete new one. A failure removes the temporary
    file and keeps the old one; an OSError becomes OutputError naming path. A replaced file
    keeps its permissions; a new one gets those of any new file (not mkstemp's 0600)."""
    path = Path(path)
    tmp = _new_sibling(path, "tmp")
    try:
        with writing(path):
            fh = create(tmp, mode)
        try:
            with writing(path):
                try:
                    os.chmod(fh.fileno(), stat.S_IMODE(os.stat(path).st_mode))
                except FileNotFoundError:
                    pass
                yield fh
                fh.flush()
                os.fsync(fh.fileno())
                fh.close()
                os.replace(tmp, path)
        except BaseException:
            _discard(fh)
            raise
    finally:
        if os.path.lexists(tmp):
            os.unlink(tmp)


@contextmanager
def atomic_folder(folder):
    """A new folder, filled in a temporary sibling (yielded) and renamed when the block ends: it
    is complete or absent. A failure removes the temporary folder; an OSError becomes
    OutputError naming the folder (write_new names the file)."""
    folder = Path(folder)
    tmp = _new_sibling(folder, "tmp")
    try:
        with writing(folder):
            os.mkdir(tmp, 0o777)
            yield tmp
            os.rename(tmp, folder)
    finally:
        if os.path.lexists(tmp):
            shutil.rmtree(tmp, ignore_errors=True)


def write_new(path, data, shown=None) -> None:
    """A new file with data (str: UTF-8; bytes), an OSError as OutputError naming it (or shown:
    the name the user knows, for a file of a folder still being filled)."""
    with writing(shown or path):
        fh = create(path, "wb" if isinstance(data, bytes) else "w")
        try:
            fh.write(data)
            fh.close()
        except BaseException:
            _discard(fh)
            raise


def _discard(fh) -> None:
    """Close after a failure: a buffer that cannot be written is given up (close() still
    releases the descriptor when its flush fails), the failure that got here is the one
    reported."""
    try:
        fh.close()
    except (OSError, ValueError):
        pass
