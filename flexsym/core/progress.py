"""A one-line progress bar on stderr for long commands (sweeps, bench, paper, select).

Shown when stderr is a terminal, or when asked (FLEXSYM_PROGRESS=1, or enabled=True);
FLEXSYM_PROGRESS=0 turns it off. Redrawn at most ten times a second; never on stdout, so
tables printed by the commands stay clean.
"""
from __future__ import annotations

import os
import sys
import time


def wanted(enabled: bool | None = None, stream=None) -> bool:
    if enabled is not None:
        return enabled
    env = os.environ.get("FLEXSYM_PROGRESS")
    if env is not None:
        return env not in ("", "0")
    stream = stream or sys.stderr
    return bool(getattr(stream, "isatty", lambda: False)())


class Progress:
    def __init__(self, total: int, label: str, enabled: bool | None = None, stream=None, width: int = 30):
        self.stream = stream or sys.stderr
        self.total, self.label, self.width = max(int(total), 0), label, width
        self.enabled = wanted(enabled, self.stream)
        self.done = 0
        self.start = time.perf_counter()
        self._last = 0.0  # time of the last draw
        self._shown = False  # the bar is on the screen (drawn, not closed)

    def update(self, n: int = 1, note: str = "") -> None:
        self.done += n
        now = time.perf_counter()
        if self.enabled and (now - self._last >= 0.1 or self.done >= self.total):
            self._draw(now, note)

    def _draw(self, now: float, note: str) -> None:
        frac = min(1.0, self.done / self.total) if self.total else 1.0
        bar = "#" * int(round(frac * self.width))
        elapsed = now - self.start
        eta = elapsed * (1 - frac) / frac if frac > 0 else 0.0
        line = (f"\r{self.label} [{bar:<{self.width}}] {self.done}/{self.total} "
                f"{elapsed:.0f} s, {eta:.0f} s left {note}")
        self.stream.write(line[:160].ljust(80))
        self.stream.flush()
        self._last, self._shown = now, True

    def wrap(self, log):
        """log(msg) that clears the bar first and draws it again after (both on one terminal)."""
        def logged(*args, **kwargs):
            shown = self._shown
            if shown:
                self.stream.write("\r\033[K")
                self.stream.flush()
            log(*args, **kwargs)
            if shown:
                self._draw(time.perf_counter(), "")
        return logged

    def close(self) -> None:
        if self._shown:
            self._draw(time.perf_counter(), "")
            self.stream.write("\n")
            self.stream.flush()
            self._shown = False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def track(items, label: str, enabled: bool | None = None):
    """Iterate over items with a progress bar (items must have a length)."""
    items = list(items)
    with Progress(len(items), label, enabled) as bar:
        for item in items:
            yield item
            bar.update()
