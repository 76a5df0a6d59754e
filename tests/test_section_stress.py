"""Section forces, moments and stresses of a beam in a mechanism (issue 19, item 3): N and M
from equilibrium by default, sigma = N/A - M y/I at a section point, each against a closed
form or a balance it must meet."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from flexsym.apps.cli import main

ROOT = Path(__file__).resolve().parent.parent
FOUR_BAR = (ROOT / "scenes" / "four_bar.toml").read_text()
RHO, E, A, I, L, G = 7850.0, 2.1e11, 5.026548245743669e-05, 2.0106192982974676e-10, 0.4, 9.81
C = 0.004  # the outer fibre of the 8 mm rod

BEAM = f"""
[system]
name = "{{name}}"

[[body]]
name = "rod"
kind = "beam"
length = {L}
density = {RHO}
youngs_modulus = {E}
area = {A}
inertia = {I}
model = "m3"
markers = {{{{ mid = 0.2 }}}}

[[joint]]
name = "root"
kind = "{{kind}}"
parent = "ground"
point = [0.0, 0.0]
child = "rod.root"
{{initial}}

[gravity]
g = [0.0, -{G}]

[solver]
integrator = "genalpha"
dt = 1e-4
t_end = {{t_end}}

[output]
interval = 1e-3
columns = {{{{ {{columns}} }}}}
"""


def run(tmp_path, text, *extra):
    scene = tmp_path / "s.toml"
    scene.write_text(text)
    out = tmp_path / "s.csv"
    assert main(["run", str(scene), "--out", str(out), *extra]) == 0
    lines = out.read_text().splitlines()
    return np.genfromtxt(out, delimiter=",", names=True, comments="#"), lines


def test_hanging_rod_carries_its_weight_below_each_section(tmp_path, capsys):
    """A rod hanging from a pin at rest (m3: no axial coordinate, so N can only come from
    equilibrium, the default): N(x) = rho A g (L - x), no bending, and sigma = rho g (L - x) at
    every section point, for all t (the released rod has nothing to ring with)."""
    cols = ('N_root = "N(rod, root)", N_mid = "N(rod, mid)", M_root = "M(rod, root)", '
            f's_top = "sigma(rod, mid, {C})", s_bot = "sigma(rod, mid, -{C})", s_axis = "sigma(rod, 0.1, 0)"')
    d, lines = run(tmp_path, BEAM.format(name="hanging", kind="revolute", t_end=0.05, columns=cols,
                                         initial=f"initial = {-np.pi / 2!r}"))
    weight = RHO * A * G
    assert np.allclose(d["N_root"], weight * L, rtol=1e-9) and np.allclose(d["N_mid"], weight * L / 2, rtol=1e-9)
    assert np.abs(d["M_root"]).max() <= 1e-9 * weight * L * L
    for c in ("s_top", "s_bot"):
        assert np.allclose(d[c], RHO * G * L / 2, rtol=1e-9)
    assert np.allclose(d["s_axis"], RHO * G * (L - 0.1), rtol=1e-9)
    units = next(ln for ln in lines if ln.startswith("# units:"))
    assert "N_root [N]" in units and "M_root [N m]" in units and "s_top [Pa]" in units


def test_cantilever_released_under_gravity_tension_on_top_at_the_root(tmp_path, capsys):
    """A horizontal cantilever clamped to ground, released undeformed under gravity: it swings
    between undeformed and twice its static sag, so the root's top fibre goes from 0 to about
    twice the static sigma = rho A g L^2/2 * c / I in tension and the bottom one as much in
    compression (a suddenly applied load; three modes: within 10 %)."""
    cols = (f's_top = "sigma(rod, root, {C})", s_bot = "sigma(rod, root, -{C})", '
            'M_root = "M(rod, root)", N_root = "N(rod, root)"')
    d, _ = run(tmp_path, BEAM.format(name="cantilever", kind="clamp", t_end=0.1, columns=cols, initial=""))
    static = RHO * A * G * L**2 / 2 * C / I
    # at t = 0 the beam is undeformed and falls freely but at its clamp; three clamped modes
    # cannot fall uniformly, and the residual of their inertial load is 1.6 % of the static root
    # stress (the continuum's is 0)
    assert abs(d["s_top"][0]) <= 3e-2 * static
    assert 1.8 <= d["s_top"].max() / static <= 2.2 and d["s_top"].min() >= -0.05 * static
    assert np.allclose(d["s_top"] + d["s_bot"], 2 * d["N_root"] / A, rtol=0, atol=1e-9 * static)
    assert np.abs(d["N_root"]).max() / A <= 1e-3 * static  # a horizontal rod: N only from its sag


def test_four_bar_coupler_has_no_moment_at_its_pins_by_default(tmp_path, capsys):
    """M at a pinned end is zero. From equilibrium (the default) it is, to the constraint
    forces' accuracy (measured 3.1e-6 of M_mid's peak at the pins, genalpha3's multipliers at
    0.1 ms); the modes' curvature (moment = "constitutive") reads a moment there that the
    pin cannot carry (20 % of the mid-span peak on the slider-crank's rod)."""
    cols = ('columns = { M_mid = "M(coupler, mid)", M_root = "M(coupler, root)", '
            'M_tip = "M(coupler, tip)" }')
    text = FOUR_BAR.replace(FOUR_BAR[FOUR_BAR.index("columns = {"):].splitlines()[0], cols)
    text = text.replace("t_end = 0.3", "t_end = 0.25")
    d, _ = run(tmp_path, text)
    peak = np.abs(d["M_mid"]).max()
    assert peak > 0.5
    assert np.abs(d["M_root"]).max() <= 1e-5 * peak and np.abs(d["M_tip"]).max() <= 1e-5 * peak
    constitutive = text.replace('model = "m2"', 'model = { variant = "m2", moment = "constitutive" }')
    c, _ = run(tmp_path, constitutive.replace(', M_tip = "M(coupler, tip)"', ""))
    (tmp_path / "t.toml").write_text(constitutive)  # no mode has curvature at the free end: refused
    assert main(["run", str(tmp_path / "t.toml"), "--out", str(tmp_path / "t.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "output M_tip = 'M(coupler, tip)': no bending mode" in err[-1] and not (tmp_path / "t.csv").exists()
    assert np.abs(c["M_root"]).max() >= 1e-2 * np.abs(c["M_mid"]).max()


@pytest.mark.parametrize("quantity, says", [
    ("sigma(rod, mid)", "needs (beam, x, y)"),
    ("sigma(rod, mid, top)", "is not a number"),
    ("sigma(rod, mid, 0.5)", "farther from the axis than any section"),
    ("sigma(rod, mid, nan)", "farther from the axis"),
    ("sigma(rod, 2.0, 0)", "outside 0..0.4"),
])
def test_sigma_bad_input_is_refused_in_one_line(tmp_path, capsys, quantity, says):
    scene = tmp_path / "s.toml"
    scene.write_text(BEAM.format(name="bad", kind="clamp", t_end=0.01, columns=f's = "{quantity}"', initial=""))
    out = tmp_path / "s.csv"
    assert main(["run", str(scene), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err and "s.toml" in err
    assert not out.exists()
