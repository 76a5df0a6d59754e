"""What a user's first mechanisms ran into (issue 18, item 1), each checked as the user sees
it: the exit code, the one line, the files written or not, the printed summary."""
from pathlib import Path

import numpy as np
import pytest

from flexsym.apps.cli import main
from flexsym.scenes.scene import load_scene
from flexsym.model.system import output_unit

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "scenes"


def run_cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.parametrize("scene", ["slider_crank", "pendulum", "hub", "four_bar", "stepped_hub"])
def test_select_on_a_mechanism_checks_its_request_before_any_work(capsys, scene, tmp_path, monkeypatch):
    """select takes mechanisms (tests/test_select_systems.py); a one-beam flag on one is refused
    in one line (it was a traceback: 'SystemScene' object has no attribute 'spec'). --exact
    applies to mechanisms too now; --max-bending does not, with or without it."""
    monkeypatch.setenv("FLEXSYM_CACHE", str(tmp_path / "cache"))
    code, out, err = run_cli(capsys, "select", SCENES / f"{scene}.toml", "--tol", "0.01", "--exact",
                             "--max-bending", "2")
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and f"{scene}.toml" in err and "--max-bending" in err
    assert not (tmp_path / "cache").exists()  # refused before any work


@pytest.mark.parametrize("scene, holder", [("slider_crank", "joint 'slider_pin'"),
                                           ("four_bar", "joint 'loop'")])
def test_prestress_on_a_beam_held_beyond_its_root_is_refused(capsys, scene, holder, tmp_path):
    """prestress's N is the beam's own centrifugal load: a coupler or connecting rod is loaded
    axially by its pins, so the model would be silently wrong there (N_mid 0.19 N against ef's
    6.08 N on the slider-crank)."""
    out = tmp_path / "r.csv"
    code, _, err = run_cli(capsys, "run", SCENES / f"{scene}.toml", "--model", "prestress", "--out", out)
    assert code == 2 and "prestress" in err and holder in err and err.count("\n") == 1
    assert not out.exists()


def test_prestress_on_a_free_beam_still_runs(capsys, tmp_path):
    """S3: the pendulum's beam is free beyond its pin: prestress stays available."""
    code, out, _ = run_cli(capsys, "run", SCENES / "pendulum.toml", "--model", "prestress", "--t-end", "0.01")
    assert code == 0 and "ok" in out


def test_a_mechanism_run_prints_every_output_with_its_unit(capsys):
    code, out, _ = run_cli(capsys, "run", SCENES / "slider_crank.toml", "--t-end", "0.02")
    assert code == 0
    rows = {line.split("|")[1].strip(): line.split("|")[2].strip() for line in out.splitlines()
            if line.startswith("| ") and not line.startswith("| quantity")}
    assert rows == {"x_s": "m", "w_mid": "m", "N_mid": "N"}
    assert "status: ok" in out


def test_a_one_beam_scene_summary_and_csv_carry_units(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the scene writes its [output] file, paper.csv, here
    code, out, _ = run_cli(capsys, "run", SCENES / "paper.toml", "--t-end", "0.5")
    assert code == 0
    assert "| v_tip | m |" in out and "| M_A | N m |" in out
    lines = (tmp_path / "paper.csv").read_text().splitlines()
    assert lines[0].startswith("t,v_tip,M_A")
    assert lines[1] == "# units: t [s], v_tip [m], M_A [N m], M_B [N m], M_C [N m]"


def test_output_units():
    system = load_scene(SCENES / "slider_crank.toml").system
    cases = {"x(slider.pin)": "m", "angle(crank_joint)": "rad", "rate(crank_joint)": "rad/s",
             "angle(slide)": "m", "rate(slide)": "m/s", "N(rod, mid)": "N", "M(rod, 0.1)": "N m",
             "w(rod, mid)": "m", "reaction(slider_pin, x)": "N", "reaction(crank_pin, moment)": "N m",
             "T": "J", "V": "J", "violation": "1 (of the size)"}
    assert {q: output_unit(system, q) for q in cases} == cases


def test_the_csv_does_not_depend_on_the_picture(capsys, tmp_path):
    """--plot needs marker positions as extra columns; they stay out of the user's CSV: the
    file is byte for byte the one written without --plot."""
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    assert run_cli(capsys, "run", SCENES / "pendulum.toml", "--t-end", "0.05", "--out", a)[0] == 0
    assert run_cli(capsys, "run", SCENES / "pendulum.toml", "--t-end", "0.05", "--out", b,
                   "--plot", tmp_path / "b.png")[0] == 0
    assert a.read_bytes() == b.read_bytes()
    assert (tmp_path / "b.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("variant", ["m3", "exact", "ef"])
def test_inspect_is_readable_and_names_integrals_as_they_are(capsys, variant):
    """No line wider than 120 columns (was up to 10,000), and an integral's name is printed as
    written (the 2-D printer read '^' and '_' in names as exponents and subscripts)."""
    code, out, _ = run_cli(capsys, "inspect", variant)
    assert code == 0
    assert max(len(line) for line in out.splitlines()) <= 120
    if variant == "m3":
        assert "J[H[v_cp1,v_cp1]*phi_v_cp1]" in out


def test_a_variant_made_with_generate_name_runs_by_that_name(capsys, tmp_path, monkeypatch):
    """`flexsym generate m3 --name pre5 ...` then `flexsym run pre5` (and build, inspect, a chain
    pre5 -> pre6): the saved definition rebuilds the same spec, so the generated code is reused."""
    monkeypatch.setenv("FLEXSYM_CACHE", str(tmp_path / "cache"))
    code, out, _ = run_cli(capsys, "generate", "m3", "--name", "pre5", "--bending", "static,cp1",
                           "--outputs", "v_tip,M_A")
    assert code == 0
    folders = sorted(p.name for p in (tmp_path / "cache" / "variants").iterdir() if p.is_dir())
    code, out, err = run_cli(capsys, "run", "pre5", "--t-end", "0.5", "--out", tmp_path / "a.csv")
    assert code == 0 and "| pre5 |" in out and "generating" not in err  # the code generate made
    assert (tmp_path / "a.csv").read_text().startswith("t,v_tip,M_A,v_static,v_cp1\n")
    assert run_cli(capsys, "generate", "pre5", "--name", "pre6", "--bending", "static,cp1,cp2")[0] == 0
    code, out, err = run_cli(capsys, "run", "pre6", "--t-end", "0.5", "--out", tmp_path / "b.csv")
    assert code == 0 and "generating" not in err
    # outputs not given are the new variant's defaults (as for any customisation)
    assert (tmp_path / "b.csv").read_text().startswith("t,v_tip,u_tip,M_A,M_B,M_C,v_static,v_cp1,v_cp2\n")
    after = sorted(p.name for p in (tmp_path / "cache" / "variants").iterdir() if p.is_dir())
    assert [f for f in after if not f.startswith("pre6-")] == folders and len(after) == len(folders) + 1
    assert run_cli(capsys, "inspect", "pre6")[0] == 0
    code, _, err = run_cli(capsys, "run", "pre7")
    assert code == 2 and err.count("\n") == 1 and "generate BASE --name NAME" in err
    (tmp_path / "cache" / "variants" / "pre5.json").write_text("{not json")
    code, _, err = run_cli(capsys, "run", "pre5")
    assert code == 2 and err.count("\n") == 1 and "pre5.json: not a saved variant" in err


def test_a_system_build_says_what_it_does(capsys, tmp_path, monkeypatch):
    """Deriving and compiling a system takes 5-45 s: each stage is a line on stderr the first
    time; a cached model runs without them."""
    monkeypatch.setenv("FLEXSYM_CACHE", str(tmp_path / "cache"))
    argv = ("run", SCENES / "pendulum.toml", "--t-end", "0.01", "--out", tmp_path / "p.csv")
    code, _, err = run_cli(capsys, *argv)
    assert code == 0
    stages = [ln for ln in err.splitlines() if ln.startswith("flexsym: system 'pendulum': ")]
    assert [s.split(": ", 2)[2].split(" ")[0] for s in stages] == ["deriving", "derived", "kernels", "compiling"]
    code, _, err = run_cli(capsys, *argv)
    assert code == 0 and "flexsym: system" not in err


def test_output_piped_into_head_ends_quietly(tmp_path):
    """`flexsym variants | head -1`: the reader leaves early; no traceback."""
    import subprocess
    import sys

    proc = subprocess.run(f"{sys.executable} -m flexsym.apps.cli variants | head -1", shell=True,
                          capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert proc.stdout.count("\n") == 1 and "Traceback" not in proc.stderr and proc.stderr == ""


def test_fe_export_of_a_mechanism_and_elements_beside_a_folder_are_refused(capsys, tmp_path):
    """fe-export on a system scene was a traceback; `elements` next to an imported `folder`
    was silently ignored (the folder's mesh was used whatever it said). A system scene's one
    beam from finite-element data is exported (planar or spatial); a scene without one, or
    with several, is refused in one line."""
    code, _, err = run_cli(capsys, "fe-export", SCENES / "hub.toml", "--out", tmp_path / "fe")
    assert code == 2 and err.count("\n") == 1 and "0 beams from finite-element data" in err
    assert not (tmp_path / "fe").exists()
    assert run_cli(capsys, "fe-export", SCENES / "stepped_hub.toml", "--out", tmp_path / "hub_fe")[0] == 0
    assert run_cli(capsys, "fe-export", SCENES / "flap_mesh.toml", "--out", tmp_path / "flap_fe")[0] == 0
    assert (tmp_path / "flap_fe" / "KG_ww_yy.mtx").exists()
    assert run_cli(capsys, "fe-export", SCENES / "stepped_blade.toml", "--out", tmp_path / "fe")[0] == 0
    text = (SCENES / "stepped_blade.toml").read_text()
    start = text.index("[body]")
    end = text.index("\n[", start + 1)
    scene = tmp_path / "imported.toml"
    scene.write_text(text[:start] + '[body]\nfolder = "fe"\nelements = 20\n' + text[end:])
    code, _, err = run_cli(capsys, "run", scene, "--out", tmp_path / "r.csv")
    assert code == 2 and err.count("\n") == 1 and "drop segments, point_masses and elements" in err
    assert not (tmp_path / "r.csv").exists()
