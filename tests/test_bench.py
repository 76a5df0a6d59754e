"""`flexsym bench --quick`: the table, CSV and figure exist and carry consistent numbers."""
import csv

import numpy as np

from flexsym.apps.cli import main


def test_bench_quick(tmp_path, capsys):
    assert main(["bench", "--quick", "--variants", "m3", "--repeat", "2", "--out", str(tmp_path)]) == 0
    rows = list(csv.DictReader(open(tmp_path / "bench.csv")))
    assert {"variant", "integrator", "dt", "cpu_s", "err_integration", "err_reference"} <= set(rows[0])
    assert [r["integrator"] for r in rows] == ["rk4", "genalpha", "radau5"]
    for r in rows:
        assert r["status"] == "ok" and float(r["cpu_s"]) > 0
        # Against ef the error is the model's (#3 truncates at second order: ~2 mm), far above
        # the integration error of these steps.
        assert float(r["err_integration"]) < 1e-4 < float(r["err_reference"]) < 5e-3
        assert np.isnan(float(r["err_N_A"]))  # #3 has no axial force
        assert abs(float(r["err_M_A"])) < 15.0
    rk4, ga, radau = rows
    assert float(rk4["err_integration"]) < float(ga["err_integration"])  # 4th order at 38 ms
    # radau5 steps 0.25 s; its rows, like the others', every 10 ms (rk4: at its 38 ms steps)
    assert [float(r["rows_every"]) for r in rows] == [0.038, 0.01, 0.01] and radau["steps"] == "80"
    md = (tmp_path / "bench.md").read_text()
    assert "| foreshortening | rk4 | 38 ms | 38 ms |" in md and "| radau5 | 250 ms | 10 ms |" in md and "derive + generate [s]" in md
    assert (tmp_path / "work_precision.png").stat().st_size > 10000
