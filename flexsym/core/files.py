"""Reading a user's file with limits: regular files only, at most a given size."""
from __future__ import annotations

import os
import stat
from pathlib import Path

from flexsym.core.errors import SpecError


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
