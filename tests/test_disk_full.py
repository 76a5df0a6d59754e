"""A full disk while `sweep`, `export-fmu` and `fe-export` write: one line "no space left on
device writing FILE", exit 5 (the machine, not the input, as for the toolchain), no half-written
target and what was there before kept. No disk is filled: every output goes through
flexsym/core/files._fdopen, and `full_disk` gives those files a disk with `room` bytes left;
past it a write fails as the kernel fails it, OSError ENOSPC (the bytes that fit are written)."""
from __future__ import annotations

import errno
import io
import os
import stat
from pathlib import Path

import numpy as np
import pytest

from flexsym.apps.cli import main
from flexsym.core import files

ROOT = Path(__file__).resolve().parent.parent
SWEEP = ["sweep", "m3", "--integrator", "radau5", "--dt", "0.01", "--step", "0.25", "--vary", "ws=2:8:40",
         "--workers", "1"]


class _Disk:
    def __init__(self, room: int, only):
        self.room, self.only, self.hits = room, only, 0


@pytest.fixture
def full_disk(monkeypatch):
    """full_disk(room, only=None): from now on, output files share a disk with `room` bytes left
    (only: files whose name passes only(name) are on it); returns the disk (hits: failed writes)."""
    real = files._fdopen

    def install(room: int = 0, only=None):
        disk = _Disk(room, only)

        class Filling(io.FileIO):
            def write(self, b):
                data = bytes(b)
                if disk.room <= 0 and data:
                    disk.hits += 1
                    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
                n = super().write(data[:disk.room])
                disk.room -= n
                return n

        def fdopen(fd, mode):
            name = os.readlink(f"/proc/self/fd/{fd}")
            if disk.only is not None and not disk.only(name):
                return real(fd, mode)
            raw = Filling(fd, "a" if "a" in mode else "w", closefd=True)
            buffered = io.BufferedWriter(raw)
            return buffered if "b" in mode else io.TextIOWrapper(buffered, encoding="utf-8", newline="")

        monkeypatch.setattr(files, "_fdopen", fdopen)
        return disk

    return install


def _one_line(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    return err


# ------------------------------------------------------------------------------- export-fmu

@pytest.mark.parametrize("room", [0, 20_000], ids=["full", "fills-up-mid-zip"])
def test_export_fmu_on_a_full_disk_keeps_the_earlier_fmu(isolated_cache, tmp_path, capsys, full_disk, room):
    out = tmp_path / "m1.fmu"
    out.write_bytes(b"the FMU exported yesterday")
    disk = full_disk(room)
    assert main(["export-fmu", "m1", "--out", str(out)]) == 5
    assert _one_line(capsys) == f"flexsym: error: no space left on device writing {out}"
    assert disk.hits > 0 and out.read_bytes() == b"the FMU exported yesterday"
    assert [p.name for p in tmp_path.iterdir()] == ["m1.fmu"]  # no temporary file left


def test_export_fmu_on_a_full_disk_writes_no_new_file(isolated_cache, tmp_path, capsys, full_disk):
    full_disk(1000)
    assert main(["export-fmu", "m1", "--out", str(tmp_path / "m1.fmu")]) == 5
    assert "no space left on device writing" in _one_line(capsys) and list(tmp_path.iterdir()) == []


def test_an_fmu_gets_the_permissions_of_any_new_file(isolated_cache, tmp_path):
    """The atomic write replaced mkstemp, whose 0600 made the FMU unreadable to others."""
    old = os.umask(0o022)
    try:
        assert main(["export-fmu", "m1", "--out", str(tmp_path / "m1.fmu")]) == 0
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "m1.fmu").stat().st_mode) == 0o644


# ------------------------------------------------------------------------------- fe-export

@pytest.mark.parametrize("room,failing", [(0, "body.toml"), (60_000, "K.mtx")], ids=["full", "fills-up"])
def test_fe_export_on_a_full_disk_leaves_no_folder(tmp_path, capsys, full_disk, room, failing):
    """The folder is written in a temporary sibling: a failure on any file leaves none of it
    (the first matrix written, M.mtx, is about 45 kB)."""
    out = tmp_path / "blade_fe"
    full_disk(room)
    assert main(["fe-export", str(ROOT / "scenes" / "stepped_blade.toml"), "--out", str(out)]) == 5
    assert _one_line(capsys) == f"flexsym: error: no space left on device writing {out / failing}"
    assert list(tmp_path.iterdir()) == []


def test_fe_export_with_room_gives_the_folder(tmp_path, capsys, full_disk):
    """The same export with the disk's room enough: the injection itself changes nothing."""
    out = tmp_path / "blade_fe"
    full_disk(10_000_000)
    assert main(["fe-export", str(ROOT / "scenes" / "stepped_blade.toml"), "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["K.mtx", "KG.mtx", "M.mtx", "body.toml"]


@pytest.mark.parametrize("where,message", [
    ("existing", "already exists (choose a new folder)"),
    ("under-a-file", "is not a writable directory"),
    ("link", "already exists"),
], ids=["existing", "under-a-file", "link"])
def test_fe_export_refuses_an_output_it_could_not_create_before_any_work(tmp_path, capsys, where, message):
    """One line and exit 2 before the scene is read (a path under a file was a traceback)."""
    (tmp_path / "existing").mkdir()
    (tmp_path / "existing" / "keep").write_text("mine")
    (tmp_path / "file").write_text("a file")
    (tmp_path / "link").symlink_to(tmp_path / "gone")
    out = {"existing": tmp_path / "existing", "under-a-file": tmp_path / "file" / "blade",
           "link": tmp_path / "link"}[where]
    before = sorted(p.name for p in tmp_path.rglob("*"))
    assert main(["fe-export", str(ROOT / "scenes" / "stepped_blade.toml"), "--out", str(out)]) == 2
    err = _one_line(capsys)
    assert f"--out {out}" in err and message in err, err
    assert sorted(p.name for p in tmp_path.rglob("*")) == before


# ------------------------------------------------------------------------------- sweep

def _sweep(out, *extra):
    return main([*SWEEP, "--out", str(out), *extra])


@pytest.fixture(scope="module")
def full_table(tmp_path_factory):
    out = tmp_path_factory.mktemp("reference") / "t.csv"
    assert _sweep(out) == 0
    return out.read_text().splitlines()


def _same_rows(a: list[str], b: list[str]) -> bool:
    """Equal but for cpu_s, the last column."""
    return len(a) == len(b) and all(x.rsplit(",", 1)[0] == y.rsplit(",", 1)[0] for x, y in zip(a, b))


def test_sweep_disk_full_mid_partial_keeps_the_runs_and_resume_completes(isolated_cache, tmp_path, capsys,
                                                                       full_disk, full_table):
    out, part = tmp_path / "t.csv", tmp_path / "t.csv.partial"
    out.write_text("last week's table\n")
    full_disk(12_000, only=lambda name: name.endswith(".partial"))  # the head and some rows
    assert _sweep(out) == 5
    err = _one_line(capsys)
    assert err.startswith(f"flexsym: error: no space left on device writing {part}; the runs finished so far "
                          f"are kept in {part}") and "--resume" in err
    assert out.read_text() == "last week's table\n" and part.stat().st_size == 12_000
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.csv", "t.csv.partial"]
    cut = not part.read_bytes().endswith(b"\n")  # a row the disk cut (unless it ended on a newline)
    full_disk(10 ** 9)  # room made
    assert _sweep(out, "--resume") == 0
    assert ("was cut off by an interruption" in capsys.readouterr().err) == cut
    assert _same_rows(out.read_text().splitlines(), full_table) and not part.exists()


def test_sweep_disk_full_at_the_table_keeps_every_run_and_the_old_table(isolated_cache, tmp_path, capsys,
                                                                         full_disk, full_table):
    """Every run finished, the table could not be written: the old one stays, the partial file
    holds all runs, and --resume writes the table without running any."""
    out, part = tmp_path / "t.csv", tmp_path / "t.csv.partial"
    out.write_text("last week's table\n")
    full_disk(0, only=lambda name: Path(name).name.startswith(".t.csv.tmp-"))
    assert _sweep(out) == 5
    assert f"no space left on device writing {out}; the runs finished so far are kept in {part}" in \
        _one_line(capsys)
    assert out.read_text() == "last week's table\n"
    kept = part.read_text().splitlines()[2:]
    assert len(kept) == 40
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.csv", "t.csv.partial"]
    full_disk(10 ** 9)
    assert _sweep(out, "--resume") == 0
    assert "40 finished runs kept" in capsys.readouterr().out
    rows = out.read_text().splitlines()
    assert _same_rows(rows, full_table) and not part.exists()
    # nothing was run again: every row is the kept one, its CPU time included
    assert sorted(rows[1:]) == sorted(r.rsplit(",", 1)[0] for r in kept)


def test_sweep_disk_full_before_any_run_leaves_nothing(isolated_cache, tmp_path, capsys, full_disk):
    """Not even the partial file's head fits: no partial file, no table, nothing to resume."""
    full_disk(0)
    assert _sweep(tmp_path / "t.csv") == 5
    assert "no space left on device writing" in _one_line(capsys) and list(tmp_path.iterdir()) == []


def test_sweep_plot_on_a_full_disk_keeps_the_table_and_the_old_plot(isolated_cache, tmp_path, capsys, full_disk):
    out, png = tmp_path / "t.csv", tmp_path / "t.png"
    png.write_bytes(b"old plot")
    full_disk(0, only=lambda name: ".t.png." in name)
    assert _sweep(out, "--plot", str(png)) == 5
    err = capsys.readouterr().err.strip()
    assert err == f"flexsym: error: no space left on device writing {png}"
    assert png.read_bytes() == b"old plot" and len(out.read_text().splitlines()) == 41
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.csv", "t.png"]
    assert np.isfinite(np.loadtxt(out, delimiter=",", skiprows=1, usecols=5)).all()
