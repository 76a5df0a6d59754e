"""`flexsym paper` end to end on a short horizon: files, tables, and the reference agreeing with ef."""
import numpy as np

from flexsym.apps.cli import main


def test_paper_command_short(tmp_path, capsys):
    out = tmp_path / "paper"
    code = main(["paper", "--out", str(out), "--t-end", "4", "--repeat", "1", "--ref-elements", "16",
                 "--ref-dt", "1e-3", "--no-end-to-end"])
    assert code == 0
    log = capsys.readouterr().out
    assert "[1/3] reference" in log and "[3/3] figures and report" in log
    for f in ("fig7.png", "fig8.png", "fig9.png", "report.md", "ef.csv", "geometric.csv"):
        assert (out / f).stat().st_size > 500, f
    report = (out / "report.md").read_text()
    assert "| geometric | #1 |" in report and "11.03 s" in report and "357 s" in report
    assert "| foreshortening | #3 |" in report and "not available" in report
    # The reference here is ef itself (same mesh and step): zero difference.
    row = [line for line in report.splitlines() if line.startswith("| ef | EF |")][-1]
    assert row.split("|")[3].strip() == "0.00e+00"
    data = np.loadtxt(out / "geometric.csv", delimiter=",", skiprows=1)
    assert abs(data[-1, 0] - 4.0) < 1e-9
