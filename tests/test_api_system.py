"""A System built in Python is what the API's functions take (issue 17, item 1): generate,
build, run (with run options), inprocess and sweep; the one-beam functions refuse it in one
line. api.run(System) checks and assembles it as a scene file is."""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from flexsym.apps import api
from flexsym.core.errors import SpecError
from flexsym.scenes.scene import load_scene

SCENES = Path(__file__).resolve().parent.parent / "scenes"


@pytest.fixture(scope="module")
def four_bar():
    return load_scene(SCENES / "four_bar.toml")


def test_a_system_with_rounded_angles_runs_as_its_scene(four_bar, tmp_path):
    """The scene's four-bar with its joints' initial angles rounded to 3 decimals (a user's
    numbers), run from Python: assembled first (the header says what moved), its rows over the
    scene's 0.3 s within 1e-8 of each peak of the scene's (whose angles have four decimals:
    both starts closed to round-off; the steps' iterations stop at 1e-12 of the size, up to
    1e-5 N in this stiff coupler's N, EA/L = 2.6e7 N/m; measured 1.6e-9 of N_mid's peak); the in-process batch of the same System gives them bit
    for bit, and a sweep of it runs."""
    o = four_bar.options
    rounded = replace(four_bar.system, joints=tuple(
        replace(j, initial=round(j.initial, 3)) if j.initial else j for j in four_bar.system.joints))
    opts = dict(t_end=o.t_end, dt=o.dt, integrator=o.integrator, interval=o.out_every * o.dt)
    mine = api.run(rounded, **opts)
    scene = api.run(four_bar)
    assert mine.ok and mine.validity == () and any(h.startswith("assembly: joint coupler_pin moved")
                                                   for h in mine.header)
    for c in four_bar.columns:
        peak = np.max(np.abs(scene[c]))
        assert np.max(np.abs(mine[c] - scene[c])) <= 1e-8 * peak, c
    assert api.build(rounded).executable.exists() and (api.generate(rounded) / "system.c").exists()
    assembled = api.system(rounded, t_end=o.t_end)
    b = api.inprocess(assembled).batch({}, rows=True, **opts)
    assert np.array_equal(b.rows[0], mine.data)
    table = api.sweep(assembled, {"E": [2.1e11, 2.0e11]}, tmp_path / "t.csv", **opts | {"t_end": 0.05})
    assert list(table["status"]) == ["ok", "ok"]


@pytest.mark.parametrize("fn", ["kernels", "simulate"])
def test_the_one_beam_functions_refuse_a_system_in_one_line(four_bar, fn):
    with pytest.raises(SpecError) as e:
        getattr(api, fn)(four_bar.system)
    assert str(e.value).startswith(f"{fn}(): takes a one-beam variant") and "\n" not in str(e.value)


def test_inspect_takes_a_system_as_the_command_line_does(four_bar, capsys):
    """api.inspect of a System (or its scene, or the scene's path) is `flexsym inspect
    SCENE`'s text; a one-beam section or LaTeX is refused in one line."""
    from flexsym.apps.cli import main

    text = api.inspect(four_bar.system)
    assert "coupler" in text and "operations" in text
    assert api.inspect(SCENES / "four_bar.toml", sections="system") == api.inspect(four_bar, ["system"])
    assert main(["inspect", str(SCENES / "four_bar.toml")]) == 0
    assert capsys.readouterr().out == text
    for kw, message in (({"sections": "modes"}, "a mechanism shows the sections system, derivation"),
                        ({"latex": True}, "no LaTeX form")):
        with pytest.raises(SpecError, match=message):
            api.inspect(four_bar.system, **kw)


def test_run_options_are_for_a_system_not_a_scene():
    with pytest.raises(SpecError, match=r"run\(\): options \(t_end\) are for a System"):
        api.run(SCENES / "four_bar.toml", t_end=0.1)
    with pytest.raises(SpecError, match="t_end"):
        api.run(load_scene(SCENES / "four_bar.toml").system, t_end=-1.0)
