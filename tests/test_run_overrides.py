"""Run options on the command line for scene files (issue 19, item 5): `flexsym run SCENE --dt ...`
replaces the scene's [solver] / [output] values, validated once with them through the option table
(flexsym/model/options.py with_overrides), and records the effective options in the CSV header."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from flexsym.apps.cli import main

ROOT = Path(__file__).resolve().parents[1]
SLIDER = (ROOT / "scenes" / "slider_crank.toml").read_text()
PAPER = (ROOT / "scenes" / "paper.toml").read_text()


def rows(path: Path) -> tuple[list[str], np.ndarray, list[str]]:
    lines = path.read_text().splitlines()
    return lines[0].split(","), np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2), \
        [x for x in lines if x.startswith("#")]


@pytest.mark.parametrize("text, edits, flags", [
    (SLIDER, (('integrator = "ali3p"', 'integrator = "genalpha3"'), ("dt = 1e-4", "dt = 2e-4"),
              ("t_end = 0.3", "t_end = 0.05"), ("interval = 0.001", "interval = 0.002")),
     ["--integrator", "genalpha3", "--dt", "2e-4", "--t-end", "0.05", "--interval", "0.002"]),
    (PAPER, (("t_end = 20.0", "t_end = 0.5"), ("dt = 1.0e-3", "dt = 2.0e-3")),
     ["--t-end", "0.5", "--dt", "2e-3"]),
], ids=["system scene", "one-beam scene"])
def test_overrides_equal_an_edited_scene_and_are_recorded(tmp_path, monkeypatch, capsys, text, edits, flags):
    monkeypatch.chdir(tmp_path)
    edited = text
    for old, new in edits:
        assert old in edited
        edited = edited.replace(old, new, 1)
    (tmp_path / "given.toml").write_text(text)
    (tmp_path / "edited.toml").write_text(edited)
    assert main(["run", "edited.toml", "--out", "edited.csv"]) in (0, 4)
    assert main(["run", "given.toml", "--out", "given.csv", *flags]) in (0, 4)
    cols_e, data_e, header_e = rows(tmp_path / "edited.csv")
    cols_g, data_g, header_g = rows(tmp_path / "given.csv")
    assert cols_g == cols_e and data_g.shape == data_e.shape
    assert np.array_equal(data_g, data_e), "the same options give the same rows, bit for bit"
    units = header_e[0]
    assert units.startswith("# units: t [s]") and header_g[0] == units
    assert header_e == [units]  # nothing replaced: nothing recorded (the scene is the record)
    assert len(header_g) == 2 and header_g[1].startswith("# run options: ")
    listed = header_g[1].rsplit("(from the command line: ", 1)[1].rstrip(")").split(", ")
    assert sorted(listed) == sorted(f for f in flags if f.startswith("--"))
    for flag, value in zip(flags[::2], flags[1::2]):
        key = flag[2:].replace("-", "_")
        assert f"{key} = {value}" in header_g[1] or f"{key} = {float(value)!r}" in header_g[1]


@pytest.mark.parametrize("flags, says", [
    (["--integrator", "rk5"], "--integrator: unknown integrator 'rk5'"),
    (["--dt", "1"], "--dt: 1 s is larger than [solver] t_end = 0.3 s"),
    (["--t-end", "1e-4", "--dt", "1e-3"], "--dt: 0.001 s is larger than --t-end = 0.0001 s"),
    (["--dt", "3e-4"], "[output] interval: must be a whole number of steps --dt = 0.0003 s"),
    (["--rho-inf", "0.5"], "--rho-inf: applies to genalpha and genalpha3, not to integrator ali3p"),
    (["--ws", "3"], "--ws given with a system scene: set the driver's omega in the scene"),
    (["--param", "L=0.4"], "--param given with a scene file: it does not combine with a scene file"),
    (["--elements", "4"], "--elements does not combine with a scene file: set it in the scene's [model] "
                          "table (--elements goes with --model ef)"),
    (["--model", "m3", "--elements", "4"], "--elements: applies to --model ef, not to 'm3'"),
    (["--model", "ef", "--elements", "0"], "--elements: must be in 1..512 (got 0)"),
    (["--model", "ef", "--elements", "4.5"], "--elements: '4.5' is not a whole number"),
    (["--model", "M3"], "--model: 'M3' is not a variant name"),
])
def test_a_bad_override_is_refused_before_any_work(tmp_path, monkeypatch, capsys, flags, says):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.toml").write_text(SLIDER)
    (tmp_path / "earlier.csv").write_text("t,x_s\n0,0\n")
    assert main(["run", "s.toml", "--out", "earlier.csv", *flags]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("flexsym: error: s.toml: ") and says in err[0], err
    assert (tmp_path / "earlier.csv").read_text() == "t,x_s\n0,0\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["earlier.csv", "s.toml"]


@pytest.mark.parametrize("text, edits", [
    (SLIDER, (('model = "m2"', 'model = { variant = "ef", elements = 3 }'),)),
    (PAPER, (('variant = "m3"', 'variant = "ef"\nelements = 3'),)),
], ids=["system scene", "one-beam scene"])
def test_model_ef_with_elements_equals_an_edited_scene(tmp_path, monkeypatch, text, edits):
    """`--model ef --elements 3` runs the scene's beams as ef on 3 elements: the rows of the
    scene edited to say so, bit for bit (a finer reference without editing the file), and the
    CSV header says what replaced the scene's model."""
    monkeypatch.chdir(tmp_path)
    edited = text
    for old, new in edits:
        assert old in edited, old
        edited = edited.replace(old, new, 1)
    (tmp_path / "given.toml").write_text(text)
    (tmp_path / "edited.toml").write_text(edited)
    short = ["--t-end", "0.02"]
    assert main(["run", "edited.toml", "--out", "edited.csv", *short]) in (0, 4)
    assert main(["run", "given.toml", "--out", "given.csv", "--model", "ef", "--elements", "3", *short]) in (0, 4)
    cols_e, data_e, _ = rows(tmp_path / "edited.csv")
    cols_g, data_g, header = rows(tmp_path / "given.csv")
    assert cols_g == cols_e and any(c.endswith("dx3") for c in cols_g) and not any(c.endswith("dx4") for c in cols_g)
    assert np.array_equal(data_g, data_e)
    assert header[-1] == ("# model: ef on 3 elements, in place of the scene's (from the command line: "
                          "--model, --elements)")
