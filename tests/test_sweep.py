"""Parameter sweeps (flexsym/sim/sweep.py, `flexsym sweep`): the table, sampling reproducible by
seed, resume after an interruption, Dask and local executors giving the same table, and
malformed sweep specifications refused with one line and exit 2, before anything is written."""
import io
import os

import numpy as np
import pytest

from flexsym.apps import api
from flexsym.apps.cli import main
from flexsym.core.errors import SpecError
from flexsym.toolchain.pipeline import prepare
from flexsym.core.progress import Progress
from flexsym.toolchain.run import run_built
from flexsym.model.variant import builtin
from flexsym.sim.sweep import make_plan, read_table

pd = pytest.importorskip("pandas")

FAST = dict(integrator="radau5", dt=0.01, step=0.25, t_end=20.0)  # #3's 1e-4 m case of the bench


def _same_table(a: dict, b: dict, skip=("cpu_s",)):
    assert list(a) == list(b)
    for k in a:
        if k not in skip:
            assert a[k].dtype == b[k].dtype and np.array_equal(a[k], b[k], equal_nan=a[k].dtype != object), k


def test_grid_table_rows_columns_and_values(isolated_cache, tmp_path):
    out = tmp_path / "t.csv"
    table = api.sweep("m3", ["ws=2:6:3", "L=9,10"], out, at=[15.0], workers=2, **FAST)
    df = pd.read_csv(out)
    assert len(df) == 6 and list(df["run"]) == list(range(6))
    assert list(df["ws"]) == [2, 2, 4, 4, 6, 6] and list(df["L"]) == [9, 10] * 3  # last varies fastest
    for c in ("status", "valid", "message", "v_tip_min", "v_tip_max", "v_tip_final", "v_tip_t_peak",
              "v_tip_at_15", "M_A_min", "t_stop", "steps", "newton_iterations", "cpu_s"):
        assert c in df.columns, c
    assert (df["status"] == "ok").all() and df["valid"].dtype == bool and df["valid"].all()
    # run 5 (ws = 6, L = 10) against `flexsym run`'s rows: summaries are over the output grid
    ref = run_built(prepare(builtin("m3")), params={"ws": 6.0, "L": 10.0}, **FAST)
    v = ref["v_tip"]
    assert table["v_tip_min"][5] == v.min() and table["v_tip_max"][5] == v.max()
    assert table["v_tip_final"][5] == v[-1] and table["v_tip_at_15"][5] == v[ref.t == 15.0][0]
    assert table["v_tip_t_peak"][5] == ref.t[np.argmax(np.abs(v))]
    assert table["steps"][5] == ref.summary["steps"] == 80
    assert not out.with_name("t.csv.partial").exists()


def test_failed_and_invalid_runs_have_their_rows(isolated_cache, tmp_path):
    table = api.sweep("m0", {"ws": [2.0, 6.0]}, tmp_path / "t.csv", integrator="genalpha", dt=0.01)
    assert list(table["status"]) == ["ok", "diverged"] and list(table["valid"]) == ["True", "False"]
    assert "diverged at t = " in table["message"][1] and table["t_stop"][1] < 20.0
    table = api.sweep("m3", {"ws": [6.0, 20.0]}, tmp_path / "u.csv", **FAST)
    assert list(table["status"]) == ["ok", "ok"] and list(table["valid"]) == ["True", "False"]
    assert "range of validity" in table["message"][1]


def test_scene_sweep_uses_the_scene_settings_and_columns(isolated_cache, tmp_path):
    scene = os.path.join(os.path.dirname(__file__), "..", "scenes", "constant_speed.toml")
    table = api.sweep(scene, ["ws=3,6"], tmp_path / "t.csv")
    r = api.run(api.load_scene(scene), out=tmp_path / "ref.csv")  # ws = 6
    assert table["N_A_max"][1] == r["N_A"].max() and table["u_tip_final"][1] == r["u_tip"][-1]
    # the static elongation grows like ws^2: the mean of u_tip over the oscillation, roughly
    assert 3.0 < table["u_tip_max"][1] / table["u_tip_max"][0] < 5.0


def test_samples_reproducible_by_seed_and_latin_hypercube_strata(isolated_cache):
    spec = builtin("m3")
    settings = dict(t_end=20.0, dt=0.01, integrator="radau5")
    plan = lambda **kw: make_plan(spec, settings, {"ws": 6.0, "ts": 15.0}, ["ws=2:8", "L=8:12"], **kw)
    a, b, c = plan(samples=50, seed=3), plan(samples=50, seed=3), plan(samples=50, seed=4)
    assert np.array_equal(a.table, b.table) and not np.array_equal(a.table, c.table)
    assert a.sampling == "lhs"
    for j, (lo, hi) in enumerate([(2, 8), (8, 12)]):  # one sample in each of the 50 strata
        strata = np.floor((a.table[:, j] - lo) / (hi - lo) * 50).astype(int)
        assert sorted(strata) == list(range(50))
    r = plan(samples=2000, seed=1, sampling="random")
    assert r.table[:, 0].min() >= 2 and r.table[:, 0].max() <= 8
    assert abs(r.table[:, 0].mean() - 5) < 0.15  # uniform: sd of the mean 1.73 / sqrt(2000)


def test_interrupted_sweep_resumes_to_the_same_table(isolated_cache, tmp_path):
    vary = ["ws=2:6:20", "L=9,10"]
    full = api.sweep("m3", vary, tmp_path / "full.csv", workers=1, **FAST)
    out = tmp_path / "t.csv"

    def stop(done, total):
        if done >= 10:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        api.sweep("m3", vary, out, workers=1, on_chunk=stop, **FAST)
    part = tmp_path / "t.csv.partial"
    assert part.exists() and not out.exists()
    kept = part.read_text().splitlines()[2:]
    assert 10 <= len(kept) < 40
    with open(part, "a") as fh:  # a row cut off in the middle by the interruption
        fh.write("39,6.0,10.0,ok,Tr")
    with pytest.raises(SpecError, match="--resume"):
        api.sweep("m3", vary, out, workers=1, **FAST)
    with pytest.raises(SpecError, match="different sweep"):
        api.sweep("m3", ["ws=2:6:20", "L=9,11"], out, workers=1, resume=True, **FAST)
    table = api.sweep("m3", vary, out, workers=1, resume=True, **FAST)
    _same_table(table, full)
    assert not part.exists()
    # the finished runs were kept, not run again: their CPU times are the recorded ones
    kept_cpu = {int(r.split(",")[0]): float(r.split(",")[-2]) for r in kept}  # then the check value
    assert all(table["cpu_s"][i] == c for i, c in kept_cpu.items())


def test_dask_local_cluster_gives_the_local_table(isolated_cache, tmp_path):
    distributed = pytest.importorskip("distributed")
    vary = ["ws=2:8:7", "E=5e10,7e10", "L=9:11:3"]
    local = api.sweep("m3", vary, tmp_path / "local.csv", at=[10.0], **FAST)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, host="127.0.0.1",
                                  protocol="tcp", dashboard_address=":0") as cluster:
        table = api.sweep("m3", vary, tmp_path / "dask.csv", at=[10.0], dask=cluster.scheduler_address,
                          **FAST)
    _same_table(table, local)
    assert len(table["run"]) == 42


def test_cli_sweep_writes_table_and_plot(isolated_cache, tmp_path, capsys):
    out, png = tmp_path / "t.csv", tmp_path / "t.png"
    assert main(["sweep", "m3", "--integrator", "radau5", "--dt", "0.01", "--step", "0.25",
                 "--vary", "ws=2:6:5", "--vary", "ts=10,15", "--out", str(out), "--plot", str(png),
                 "--plot-x", "ws", "--workers", "2"]) == 0
    assert "10 runs" in capsys.readouterr().out
    assert len(pd.read_csv(out)) == 10 and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


BAD = [
    (["--vary", "omega=1:2:3"], "--vary omega: unknown parameter"),
    (["--vary", "bending=1,2"], "--vary bending: unknown parameter"),
    (["--vary", "step=0.1,0.2"], "--vary step: unknown parameter"),  # genalpha: no step
    (["--vary", "dt=-0.01,0.02"], "--vary dt=-0.01: --dt: must be > 0"),
    (["--vary", "t_end=0,10"], "--vary t_end=0: --t-end: must be > 0"),
    (["--vary", "ws=2:2:5"], "empty range"),
    (["--vary", "ws=3:2", "--samples", "4"], "empty range"),
    (["--vary", "ws=a:b:3"], "'a' is not a number"),
    (["--vary", "ws=1,x,3"], "'x' is not a number"),
    (["--vary", "ws=1:2:0"], "COUNT must be >= 1"),
    (["--vary", "ws=1:2:-3"], "COUNT must be >= 1"),
    (["--vary", "ws=1:2:2.5"], "COUNT '2.5' is not a whole number"),
    (["--vary", "ws=1:2:3", "--vary", "ws=4,5"], "--vary ws: given twice"),
    (["--vary", "ws=1,2,1"], "duplicate values"),
    (["--vary", "ws="], "no values"),
    (["--vary", "ws=1,,2"], "empty value"),
    (["--vary", "ws=1e999,2"], "not finite"),
    (["--vary", "L=-1,10"], "--vary L=-1: --param L: must be > 0"),
    (["--vary", "ts=0,5"], "--vary ts=0: --param ts: must be > 0"),
    (["--vary", "ws=1:2"], "needs --samples"),
    (["--vary", "ws=1:2:3", "--samples", "5"], "with --samples give a range"),
    (["--vary", "ws=1:2:3", "--seed", "1"], "--seed is for --samples"),
    (["--vary", "ws=1:2", "--samples", "0"], "--samples must be"),
    (["--vary", "ws=1:2:3", "--at", "25"], "--at 25: not a time"),
    (["--vary", "ws=1:2:3", "--at", "x"], "--at 'x' is not a number"),
    ([], "at least one --vary"),
    (["--vary", "ws 1:2:3"], "expected NAME="),
    (["--vary", "q0_v_tip=0,0.1"], "--vary q0_v_tip: unknown parameter"),
    (["--vary", "ws=1,2", "--plot", "p.png", "--plot-y", "v_tip_mean"], "--plot-y v_tip_mean: not a column"),
    (["--vary", "ws=1,2", "--plot-x", "L"], "--plot-x L: not a varied input"),
]


@pytest.mark.parametrize("extra,message", BAD, ids=[m for _, m in BAD])
def test_malformed_sweeps_exit_2_with_one_line_and_write_nothing(isolated_cache, tmp_path, capsys,
                                                                 extra, message):
    out = tmp_path / "new" / "t.csv"
    code = main(["sweep", "m3", "--out", str(out), *extra])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and message in err, err
    assert not (tmp_path / "new").exists()


def test_a_partial_file_is_never_overwritten_without_resume(isolated_cache, tmp_path, capsys):
    out = tmp_path / "t.csv"
    part = tmp_path / "t.csv.partial"
    part.write_text("# flexsym sweep 0\n")
    assert main(["sweep", "m3", "--vary", "ws=1,2", "--out", str(out)]) == 2
    # another sweep's file: --resume could not continue it, so the advice is to delete it
    err = capsys.readouterr().err
    assert "different sweep" in err and "delete it" in err and part.read_text() == "# flexsym sweep 0\n"


def test_progress_bar_only_on_a_terminal_or_when_asked(monkeypatch):
    monkeypatch.delenv("FLEXSYM_PROGRESS", raising=False)
    quiet, shown = io.StringIO(), io.StringIO()
    for stream, enabled in ((quiet, None), (shown, True)):
        with Progress(3, "sweep", enabled=enabled, stream=stream) as bar:
            for _ in range(3):
                bar.update()
    assert quiet.getvalue() == "" and "3/3" in shown.getvalue() and "[###" in shown.getvalue()
    monkeypatch.setenv("FLEXSYM_PROGRESS", "1")
    forced = io.StringIO()
    with Progress(2, "x", stream=forced) as bar:
        bar.update(2)
    assert "2/2" in forced.getvalue()


def test_ctrl_c_keeps_finished_runs_and_resume_completes(isolated_cache, tmp_path):
    """Real SIGINTs to `flexsym sweep`: exit 130, the finished runs stay in the partial file, and
    the same command with --resume completes the table without running them again."""
    import signal
    import subprocess
    import sys
    import time

    out, part = tmp_path / "t.csv", tmp_path / "t.csv.partial"
    # runs slow enough (the default integrator) that the workers are inside their chunks when
    # the signals come
    cmd = [sys.executable, "-m", "flexsym.apps.cli", "sweep", "m3", "--vary", "ws=2:8:1000", "--out", str(out),
           "--workers", "2"]
    # The sweep holds once 200 runs are in the partial file (a test hook), so the signal lands
    # mid-sweep however fast or loaded the machine is.
    env = dict(os.environ, FLEXSYM_TEST_HOLD_SWEEP_AFTER="200")
    # SIGINT as a user has it, even when the suite itself runs as a background job (which
    # inherits SIGINT ignored)
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.time() + 900  # a bound on a hang, not on the machine's speed
    while not (part.exists() and len(part.read_text().splitlines()) > 200):
        assert proc.poll() is None and time.time() < deadline, proc.communicate()
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    first = proc.stderr.readline()
    # A second Ctrl-C while the sweep stops (GNU timeout sends two): it used to leave the exit
    # waiting for the workers forever, when they were still running their chunks.
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    # 130, or killed by the second SIGINT once the interpreter has restored its default action
    assert proc.returncode in (130, -signal.SIGINT) and "--resume" in first and "Traceback" not in err
    assert not out.exists()
    kept = {int(r.split(",")[0]): r.rsplit(",", 1)[0] for r in part.read_text().splitlines()[2:]}  # no check value
    assert 200 < len(kept) < 1000
    done = subprocess.run(cmd + ["--resume"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    rows = out.read_text().splitlines()
    assert len(rows) == 1001 and not part.exists()
    assert all(rows[i + 1] == r for i, r in kept.items())  # kept runs were not run again


def test_solver_options_per_run(isolated_cache, tmp_path, capsys):
    """step, dt and t_end vary per run like parameters: each row is `flexsym run` with that
    option; radau5's error falls steeply with its step; a scene keeps its row interval."""
    out = tmp_path / "t.csv"
    steps = [0.05, 0.1, 0.2, 0.4]
    table = api.sweep("m3", {"step": steps}, out, integrator="radau5", dt=0.01)
    built = prepare(builtin("m3"))
    for i, h in enumerate(steps):
        r = run_built(built, integrator="radau5", dt=0.01, step=h, params={"ws": 6.0, "ts": 15.0})
        assert table["v_tip_min"][i] == r["v_tip"].min() and table["steps"][i] == r.summary["steps"]
    err = np.abs(table["v_tip_min"][1:] - table["v_tip_min"][0])
    assert err[0] < err[1] < err[2] and err[1] / err[0] > 8  # high order: at least 2^3 per halving
    table = api.sweep("m3", {"dt": [0.01, 0.02], "t_end": [5.0, 10.0]}, tmp_path / "u.csv",
                      integrator="rk4")
    assert list(table["steps"]) == [500, 1000, 250, 500] and list(table["t_stop"]) == [5, 10, 5, 10]
    scene = os.path.join(os.path.dirname(__file__), "..", "scenes", "constant_speed.toml")
    table = api.sweep(scene, {"dt": [5e-5, 1e-4]}, tmp_path / "s.csv")
    r = api.run(api.load_scene(scene), out=tmp_path / "ref.csv")  # dt = 1e-4, rows every 1e-4 s
    assert table["N_A_max"][1] == r["N_A"].max() and table["steps"][0] == 2 * table["steps"][1]
    assert main(["sweep", scene, "--vary", "dt=3e-5,1e-4", "--out", str(tmp_path / "v.csv")]) == 2
    err = capsys.readouterr().err
    assert "--vary dt=3e-05: " in err and "[output] interval: must be a whole number of steps" in err


# ------------------------------------------------------------------ a partial file edited or duplicated

CLI_SWEEP = ["sweep", "m3", "--integrator", "radau5", "--dt", "0.01", "--step", "0.25", "--vary", "ws=2:8:40",
             "--workers", "1"]


@pytest.fixture(scope="module")
def interrupted(tmp_path_factory):
    """The partial file of `CLI_SWEEP` interrupted after 10 runs (its text), and the table of the
    whole sweep run without interruption."""
    folder = tmp_path_factory.mktemp("interrupted")

    def stop(done, total):
        if done >= 10:
            raise KeyboardInterrupt

    opts = dict(integrator="radau5", dt=0.01, step=0.25, workers=1)
    with pytest.raises(KeyboardInterrupt):
        api.sweep("m3", ["ws=2:8:40"], folder / "t.csv", on_chunk=stop, **opts)
    text = (folder / "t.csv.partial").read_text(encoding="utf-8")
    assert text.endswith("\n") and 12 <= len(text.splitlines()) < 42
    return text, api.sweep("m3", ["ws=2:8:40"], folder / "full.csv", **opts)


def _resume(capsys, out, *extra):
    code = main([*CLI_SWEEP, "--out", str(out), "--resume", *extra])
    return code, capsys.readouterr().err


def _cells(line: str) -> list[str]:
    return next(__import__("csv").reader([line]))


def _edit(lines: list[str], k: int, column: int, value: str) -> str:
    """Line k (0-based) with one cell replaced, written back as CSV."""
    buf = io.StringIO()
    cells = _cells(lines[k])
    cells[column] = value
    __import__("csv").writer(buf, lineterminator="").writerow(cells)
    return buf.getvalue()


# (id, how the text is changed, what the one line names): each is a row no sweep wrote for this plan
PARTIAL_EDITS = [
    ("extra-cell", lambda L: L.__setitem__(3, "7," + L[3]), "line 4: 31 cells, where a row of this sweep has 30"),
    ("missing-cell", lambda L: L.__setitem__(4, L[4].split(",", 1)[1]), "line 5: 29 cells"),
    ("empty-line", lambda L: L.insert(3, ""), "line 4: 0 cells"),
    ("run-not-a-number", lambda L: L.__setitem__(3, "x" + L[3][1:]), "line 4: run 'x' is not a run number"),
    ("run-negative", lambda L: L.__setitem__(3, "-" + L[3]), "line 4: run '-1' is not a run number"),
    ("run-out-of-range", lambda L: L.__setitem__(3, "40" + L[3][1:]),
     "line 4: run 40 is not a run of this sweep (runs 0 to 39)"),
    ("input-not-the-plans", lambda L: L.__setitem__(4, _edit(L, 4, 1, "5.0")),
     "line 5: run 2 with ws = 5.0, but run 2 of this sweep has ws = 2.3076923076923075"),
    ("input-not-a-number", lambda L: L.__setitem__(4, _edit(L, 4, 1, "fast")), "line 5: ws = 'fast' is not a number"),
    ("result-edited", lambda L: L.__setitem__(4, _edit(L, 4, 5, "-9.99")),
     "line 5: the row of run 2 is not the one the sweep wrote"),
    ("result-not-a-number", lambda L: L.__setitem__(4, _edit(L, 4, 5, "abc")), "line 5: the row of run 2 is not"),
    ("status-edited", lambda L: L.__setitem__(4, _edit(L, 4, 2, "bogus")), "line 5: the row of run 2 is not"),
    ("check-removed", lambda L: L.__setitem__(4, _edit(L, 4, -1, "")), "line 5: the row of run 2 is not"),
    ("duplicate-other-values", lambda L: L.insert(5, _edit(L, 4, -2, "0.5")), "line 6: the row of run 2 is not"),
    ("unterminated-quote", lambda L: L.__setitem__(4, '"' + L[4]), "line 5: not a row of the table"),
    ("columns-edited", lambda L: L.__setitem__(1, L[1].replace("v_tip_min", "v_min")),
     "line 2: not this sweep's columns"),
    ("another-sweep", lambda L: L.__setitem__(0, L[0][:-4] + "0000"), "line 1: belongs to a different sweep"),
    ("not-a-partial-file", lambda L: L.__setitem__(0, "run,ws"), "line 1: is not a sweep's partial file"),
]


@pytest.mark.parametrize("edit,message", [e[1:] for e in PARTIAL_EDITS], ids=[e[0] for e in PARTIAL_EDITS])
def test_a_partial_row_the_sweep_did_not_write_is_refused_with_one_line(interrupted, tmp_path, capsys, edit,
                                                                         message):
    """--resume trusts no row it cannot check: one line naming the file and the line, exit 2,
    nothing run, the partial file as it was and no table."""
    lines = interrupted[0].split("\n")
    edit(lines)
    text = "\n".join(lines)
    out, part = tmp_path / "t.csv", tmp_path / "t.csv.partial"
    part.write_text(text, encoding="utf-8")
    code, err = _resume(capsys, out)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert f"{part}: {message}" in err, err
    assert part.read_text(encoding="utf-8") == text and not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.csv.partial"]


def test_two_valid_rows_of_one_run_that_differ_are_refused(interrupted, tmp_path, capsys):
    """A run finished twice (e.g. by two sweeps before the lock): both rows check, they differ
    (cpu_s), neither is chosen silently."""
    from flexsym.sim.sweep import _check_value

    lines = interrupted[0].split("\n")
    key = lines[0].split()[-1]
    row = _edit(lines, 4, -2, "0.5").rsplit(",", 1)[0]
    lines.insert(7, f"{row},{_check_value(key, row)}")
    (tmp_path / "t.csv.partial").write_text("\n".join(lines), encoding="utf-8")
    code, err = _resume(capsys, tmp_path / "t.csv")
    assert code == 2 and "line 8: run 2 again, with other values than on line 5" in err, err


def test_non_utf8_bytes_in_a_partial_file_are_refused(interrupted, tmp_path, capsys):
    part = tmp_path / "t.csv.partial"
    part.write_bytes(interrupted[0].encode() + b"3,\xff\xfe\n")
    code, err = _resume(capsys, tmp_path / "t.csv")
    n = len(interrupted[0].splitlines()) + 1
    assert code == 2 and f"line {n}: not UTF-8 text" in err and len(err.strip().splitlines()) == 1, err


def test_a_row_cut_off_by_a_crash_is_dropped_said_and_run_again(interrupted, tmp_path, capsys):
    text, full = interrupted
    lines = text.splitlines()
    cut = lines[-1][:57]  # the last row, without its end and newline: a crash mid-write
    part = tmp_path / "t.csv.partial"
    part.write_text("\n".join(lines[:-1]) + "\n" + cut, encoding="utf-8")
    code, err = _resume(capsys, tmp_path / "t.csv")
    assert code == 0, err
    assert f"{part}: line {len(lines)} was cut off by an interruption" in err and "run again" in err
    _same_table(read_table(tmp_path / "t.csv"), full)
    assert not part.exists()


def test_a_row_copied_twice_unchanged_is_harmless(interrupted, tmp_path, capsys):
    lines = interrupted[0].splitlines()
    (tmp_path / "t.csv.partial").write_text("\n".join(lines + lines[2:5]) + "\n", encoding="utf-8")
    code, err = _resume(capsys, tmp_path / "t.csv")
    assert code == 0, err
    _same_table(read_table(tmp_path / "t.csv"), interrupted[1])


@pytest.mark.parametrize("kind", ["directory", "fifo"])
def test_a_partial_path_that_is_not_a_file_is_refused_without_waiting(tmp_path, kind):
    """A directory was a traceback, a FIFO a hang (reading it waits for a writer); in a
    subprocess with a timeout, so that a hang fails the test instead of stopping the suite."""
    import subprocess
    import sys

    part = tmp_path / "t.csv.partial"
    part.mkdir() if kind == "directory" else os.mkfifo(part)
    proc = subprocess.run([sys.executable, "-m", "flexsym.apps.cli", *CLI_SWEEP, "--out", str(tmp_path / "t.csv"),
                           "--resume"], capture_output=True, text=True, timeout=300)
    err = proc.stderr.strip()
    assert proc.returncode == 2 and len(err.splitlines()) == 1 and f"{part}: not a regular file" in err, err
    assert not (tmp_path / "t.csv").exists()


# ------------------------------------------------------------------ a second sweep, a killed sweep

@pytest.fixture
def held_sweep():
    """start(out, hold): `flexsym sweep` in a subprocess that holds once `hold` runs are in its
    partial file (a test hook), returned once they are (the wait is bounded by a hang, not by the
    machine's speed); whatever a failed test leaves running (the sweep, its workers) is killed."""
    import signal
    import subprocess
    import sys
    import time

    started = []

    def start(out, hold: int, workers: int = 2):
        cmd = [sys.executable, "-m", "flexsym.apps.cli", "sweep", "m3", "--integrator", "radau5", "--dt", "0.01",
               "--step", "0.25", "--vary", "ws=2:8:400", "--out", str(out), "--workers", str(workers)]
        env = dict(os.environ, FLEXSYM_TEST_HOLD_SWEEP_AFTER=str(hold))
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                                preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        started.append((proc, []))
        part = out.with_name(out.name + ".partial")
        deadline = time.time() + 900
        while not (part.exists() and len(part.read_text().splitlines()) >= 2 + hold):
            assert proc.poll() is None and time.time() < deadline, proc.communicate()
            time.sleep(0.05)
        started[-1][1].extend(_children(proc.pid))
        return proc, cmd

    yield start
    for proc, workers in started:
        for pid in [proc.pid, *workers]:
            if _alive(pid):
                os.kill(pid, signal.SIGKILL)
        proc.communicate()


def _children(pid: int) -> list[int]:
    kids = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as fh:
                    fields = fh.read().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                kids.append(int(entry))
    return kids


def _alive(pid: int) -> bool:
    """Running (a zombie waiting for its reaper counts as gone)."""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _gone(pids, timeout: float = 120.0) -> list[int]:
    """The pids still alive after waiting for them to end (polled; the bound is for a hang)."""
    import time

    deadline = time.time() + timeout
    while any(_alive(p) for p in pids) and time.time() < deadline:
        time.sleep(0.05)
    return [p for p in pids if _alive(p)]


def test_a_second_sweep_on_a_running_sweeps_table_is_told_to_wait_and_resume_then_works(held_sweep, tmp_path,
                                                                                         capsys):
    """While a sweep runs, the same command (with or without --resume) is refused in one line:
    both appending to one partial file interleaved rows, and the one to finish second crashed
    removing it. Stopped, the first one's advice (--resume) completes the table."""
    import signal

    out = tmp_path / "t.csv"
    part = tmp_path / "t.csv.partial"
    first, cmd = held_sweep(out, 20)
    before = part.read_bytes()
    for extra in ([], ["--resume"]):
        assert main(cmd[3:] + extra) == 2
        err = capsys.readouterr().err
        assert f"{part}: in use by a sweep still running on {out}" in err and len(err.strip().splitlines()) == 1
    assert part.read_bytes() == before and not out.exists()
    first.send_signal(signal.SIGINT)
    _, err = first.communicate(timeout=300)
    assert first.returncode == 130 and "--resume" in err
    assert main(cmd[3:]) == 2 and "pass --resume" in capsys.readouterr().err
    assert main(cmd[3:] + ["--resume"]) == 0
    rows = out.read_text().splitlines()
    kept = [r.rsplit(",", 1)[0] for r in before.decode().splitlines()[2:]]
    assert len(rows) == 401 and all(rows[1 + int(r.split(",")[0])] == r for r in kept) and not part.exists()


@pytest.mark.parametrize("how", ["sigkill-parent", "sigterm-worker"])
def test_no_worker_outlives_a_killed_sweep(held_sweep, tmp_path, capsys, how):
    """SIGKILL of the sweep left its workers running its chunks as orphans (their pipes kept
    them alive), and a busy worker caught SIGTERM as a task's error and went on. Now each
    worker dies with the sweep, and on SIGTERM; the table's lock goes with them."""
    import signal

    out = tmp_path / "t.csv"
    proc, cmd = held_sweep(out, 20)
    workers = _children(proc.pid)
    assert len(workers) == 2, workers
    if how == "sigterm-worker":
        os.kill(workers[0], signal.SIGTERM)
        assert _gone(workers[:1]) == []
    os.kill(proc.pid, signal.SIGKILL)
    proc.communicate(timeout=120)
    assert _gone(workers) == []
    assert main(cmd[3:] + ["--resume"]) == 0, capsys.readouterr().err  # no survivor holds the lock
    assert len(out.read_text().splitlines()) == 401


def test_no_dask_local_cluster_worker_outlives_a_killed_sweep(isolated_cache, tmp_path):
    """A sweep on a Dask LocalCluster of its own process (worker processes, as sweep_bench has
    them), that process killed with SIGKILL: the cluster's nannies end their workers."""
    pytest.importorskip("distributed")
    import signal
    import subprocess
    import sys
    import time

    out = tmp_path / "t.csv"
    script = ("import sys\nfrom distributed import LocalCluster\nfrom flexsym.apps import api\n"
              "if __name__ == '__main__':\n"
              "    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host='127.0.0.1',\n"
              "                      dashboard_address=':0') as c:\n"
              f"        api.sweep('m3', ['ws=2:8:400'], {str(out)!r}, dask=c.scheduler_address, **{FAST!r})\n")
    (tmp_path / "run.py").write_text(script)
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # this checkout's flexsym
    env = dict(os.environ, FLEXSYM_TEST_HOLD_SWEEP_AFTER="20",
               PYTHONPATH=os.pathsep.join([root, *filter(None, [os.environ.get("PYTHONPATH")])]))
    proc = subprocess.Popen([sys.executable, str(tmp_path / "run.py")], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    part = tmp_path / "t.csv.partial"
    workers = []
    try:
        deadline = time.time() + 900
        while not (part.exists() and len(part.read_text().splitlines()) >= 22):
            assert proc.poll() is None and time.time() < deadline, proc.communicate()
            time.sleep(0.05)
        workers = _children(proc.pid)
        assert len(workers) >= 2, workers
        os.kill(proc.pid, signal.SIGKILL)
        proc.communicate(timeout=120)
        assert _gone(workers) == []
    finally:
        for pid in [proc.pid, *workers]:
            if _alive(pid):
                os.kill(pid, signal.SIGKILL)
