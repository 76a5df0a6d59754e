"""The command line: inspect, custom mode sets, and clear errors for bad input."""

from pathlib import Path

import numpy as np
import pytest

from flexsym.apps.cli import main
from flexsym.core.paths import generated_dir

SCENES = Path(__file__).resolve().parent.parent / "scenes"


def run_cli(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_inspect_shows_which_terms_are_differentiated_wrt_what(capsys):
    code, out, _ = run_cli(capsys, "inspect", "m1", "--section", "energy")
    assert code == 0
    assert "cubic" in out and "d/d(v_static, v_cp1, v_cp2)" in out
    assert "NOT a potential force" in out
    code, out, _ = run_cli(capsys, "inspect", "m3", "--section", "energy,mass,stiffness")
    assert "(depends on q)" in out and "every term is differentiated" in out
    # The trap of benchmark.md section 3 is a separate, visibly different strain model.
    code, out, _ = run_cli(capsys, "inspect", "m1", "--strain", "cubic_energy", "--section", "energy")
    assert "d/d(u_static, v_static, v_cp1, v_cp2)" in out


def test_inspect_latex_and_ops(capsys):
    code, out, _ = run_cli(capsys, "inspect", "m2", "--latex", "--section", "mass,integrals,ops")
    assert code == 0
    assert r"\int_{0}^{1}" in out and r"\rho" in out
    assert "fsm_geometric_sine_force" in out and "fsm_geometric_sine_residual_jac" in out  # m2


def test_custom_mode_set_runs_in_its_own_folder(capsys, isolated_cache, tmp_path):
    out_csv = tmp_path / "custom.csv"
    code, out, err = run_cli(capsys, "run", "m1", "--bending", "static,cp1,cp2,cp3,cp4",
                             "--axial", "static,sin1,sin2", "--name", "rich", "--t-end", "3",
                             "--out", str(out_csv), "--plot", str(tmp_path / "rich.png"))
    assert code == 0, err
    header = out_csv.read_text().splitlines()[0].split(",")
    assert header == ["t", "v_tip", "u_tip", "N_A", "N_B", "N_C", "M_A", "M_B", "M_C", "u_static",
                      "u_sin1", "u_sin2", "v_static", "v_cp1", "v_cp2", "v_cp3", "v_cp4"]
    assert (tmp_path / "rich.png").stat().st_size > 1000
    folders = list((isolated_cache / "variants").glob("rich-*"))
    assert len(folders) == 1 and (folders[0] / "manifest.json").exists()
    assert not (generated_dir() / "rich").exists()
    data = np.loadtxt(out_csv, delimiter=",", skiprows=1)
    assert data[-1, 0] == pytest.approx(3.0) and np.all(np.isfinite(data))


@pytest.mark.parametrize("argv,msg", [
    (["run", "m9"], "unknown variant 'm9'"),
    (["run", "m1", "--bending", "static,cp1,cp1"], "duplicate bending mode 'cp1'"),
    (["run", "m1", "--bending", "static,xx1"], "unknown bending mode 'xx1'"),
    (["run", "m1", "--strain", "nonlinear"], "unknown strain model 'nonlinear'"),
    (["run", "m1", "--axial", ""], "needs at least one axial mode"),
    (["run", "m1", "--bending", "cp1,cp2"], "no bending mode moves the tip"),
    (["run", "m1", "--name", "Bad-Name"], "variant name 'Bad-Name'"),
    (["run", "m1", "--dt", "-0.001"], "--dt: must be > 0 (got -0.001)"),
    (["run", "m1", "--t-end", "0"], "--t-end: must be > 0 (got 0)"),
    (["run", "m1", "--param", "rho=-1", "--t-end", "0.1"], "--param rho: must be > 0 (got -1)"),
    (["run", "m1", "--param", "nope=3"], "unknown parameter 'nope'"),
    (["inspect", "m1", "--section", "everything"], "unknown section"),
])
def test_bad_input_is_refused_with_one_clear_line(capsys, argv, msg):
    code, out, err = run_cli(capsys, *argv)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and msg in lines[0], err


def test_failed_run_does_not_touch_existing_output(capsys, tmp_path):
    out_csv = tmp_path / "keep.csv"
    out_csv.write_text("sentinel\n")
    code, _, err = run_cli(capsys, "run", "m1", "--dt", "0", "--out", str(out_csv))
    assert code == 2 and out_csv.read_text() == "sentinel\n"
    code, _, err = run_cli(capsys, "run", "m1", "--param", "E=0", "--out", str(out_csv))
    assert code == 2 and out_csv.read_text() == "sentinel\n"


def test_missing_compiler_is_one_clear_line(capsys, monkeypatch):
    monkeypatch.setenv("CC", "/nonexistent/cc")
    code, _, err = run_cli(capsys, "build", "m1")
    assert code == 5  # a toolchain problem, not bad input (2)
    assert "no C compiler found (looked for CC=/nonexistent/cc)" in err


def test_divergence_exit_code_and_message(capsys, tmp_path):
    code, out, err = run_cli(capsys, "run", "m0", "--out", str(tmp_path / "m0.csv"))
    assert code == 3
    assert "diverged at t = 10.1" in err
    assert (tmp_path / "m0.csv").exists()


def test_variants_listing(capsys):
    code, out, _ = run_cli(capsys, "variants")
    assert code == 0
    for word in ("geometric", "m3", "foreshortening", "clamped-pinned", "cp"):
        assert word in out


def test_generate_and_build_take_a_system_scene(capsys, tmp_path):
    """`flexsym generate` / `build` take a system scene as `run` does (issue 17: every command
    takes the model): the folder is a system's, written to --out when given, and built; a
    one-beam override flag is refused in one line, nothing written."""
    import json

    scene = str(SCENES / "pendulum.toml")
    code, out, err = run_cli(capsys, "generate", scene, "--out", str(tmp_path / "gen"))
    assert code == 0, err
    manifest = json.loads((tmp_path / "gen" / "manifest.json").read_text())
    assert manifest["kind"] == "system" and manifest["spec"]["name"] == "pendulum"
    assert "generated system 'pendulum'" in out and "ops: mass" in out
    code, out, err = run_cli(capsys, "build", scene, "--model", "m1")
    assert code == 0, err
    assert out.startswith("built 'pendulum': ") and Path(out.split(": ", 1)[1].strip()).is_file()
    code, out, err = run_cli(capsys, "generate", scene, "--strain", "linear", "--out", str(tmp_path / "no"))
    assert code == 2 and "--strain does not combine with a scene file" in err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "no").exists()
