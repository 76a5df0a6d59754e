"""One output grammar (issue 17): a one-beam output name (v_tip, N_A, M@0.25, M_<label>_left)
read on a system's one flexible beam is the system quantity it names, and S0's value of it is
the one-beam variant's value, recovery by recovery."""
import random
from dataclasses import replace

import pytest

from flexsym.codegen.derive import derive
from flexsym.core.errors import SpecError
from flexsym.model.library import hub_system, pendulum_system, spin_up_system
from flexsym.model.system import Marker, Output, output_unit, parse_output
from flexsym.model.variant import builtin, customize
from flexsym.physics.assemble import derive_system
from flexsym.physics.energy import BEAM_PARAMS, alpha, w


def _with_step(system):
    beam = system.bodies[0]
    return replace(system, bodies=(replace(beam, markers=(Marker("step", 5.0),)),))


@pytest.mark.parametrize("alias, quantity", [
    ("v_tip", "v(beam, 10.0)"), ("u_tip", "u(beam, 10.0)"), ("N_A", "N(beam, 0.0)"),
    ("M_B", "M(beam, 5.0)"), ("M_C", "M(beam, 10.0)"), ("M@0.25", "M(beam, 2.5)"),
    ("N_s0p3", "N(beam, 3.0)"), ("M_step", "M(beam, step)"), ("M_step_left", "M(beam, step-)"),
    ("N_step_right", "N(beam, step+)"), (" M_root ", "M(beam, root)"),
    ("M_A_clamp", "M(beam, 0.0, equilibrium)"), ("N_A_clamp", "N(beam, 0.0, equilibrium)")])
def test_a_one_beam_name_is_the_system_quantity_it_names(alias, quantity):
    system = _with_step(spin_up_system(builtin("m3")))
    assert parse_output(system, alias) == parse_output(system, quantity)
    assert output_unit(system, alias) == output_unit(system, quantity)


def test_a_one_beam_name_reads_the_one_flexible_beam_of_a_mechanism():
    hub = hub_system(builtin("m3"))  # a rigid hub and one beam
    assert parse_output(hub, "M_A") == parse_output(hub, "M(beam, 0.0)")
    assert parse_output(hub, "T") == ("T", ())  # scalars stay themselves


@pytest.mark.parametrize("alias, message", [
    ("M@1.5", "output 'M@1.5': position 1.5 is outside [0, 1]"),
    ("M_nowhere", "unknown quantity"),
    ("v_tip_left", "unknown quantity"),
])
def test_a_name_that_is_not_an_alias_is_refused_in_one_line(alias, message):
    with pytest.raises(SpecError, match=message.replace("(", r"\(").replace("[", r"\[")):
        parse_output(_with_step(spin_up_system(builtin("m3"))), alias)


def test_an_alias_on_a_system_of_two_beams_is_refused_naming_them():
    two = pendulum_system(builtin("m3"))
    beam = two.bodies[-1]
    two = replace(two, bodies=two.bodies + (replace(beam, name="other"),))
    with pytest.raises(SpecError, match="one flexible beam, and it has 2: .*write M\\(beam, x\\)"):
        parse_output(two, "M_A")


PARAMS = {p.symbol: p.default for p in BEAM_PARAMS}


def _states(old, new):
    """The same random state, rates and drive for the variant's and S0's symbols."""
    theta, rate, acc = new.guided[0].symbols
    rnd = random.Random(11)
    vals = dict(PARAMS)
    for a, b in zip(list(old.q) + list(old.qd) + list(old.qdd), list(new.q) + list(new.qd) + list(new.qdd)):
        vals[a] = vals[b] = rnd.uniform(-0.5, 0.5)
    return vals | {w: 1.3, rate: 1.3, alpha: 0.7, acc: 0.7, theta: 0.2}


@pytest.mark.parametrize("variant, recovery, names", [
    ("m3", "constitutive", "v_tip,u_tip,M_A,M_B,M@0.25,M@0.9"),
    ("m3", "equilibrium", "N_A,N@0.5,M_A,M@0.25,M@0.9"),
    ("prestress", "constitutive", "N_A,N@0.5,M@0.25"),
])
def test_s0_gives_each_alias_the_variants_value(variant, recovery, names):
    """The variant's outputs (outputs.py, written for the guided hub) against S0's system
    outputs of the same names (assemble / body kinds): two derivations, one value each."""
    spec = customize(builtin(variant), outputs=names, moment=recovery, axial_force=recovery)
    old = derive(spec)
    system = spin_up_system(spec)
    new = derive_system(replace(system, outputs=tuple(Output(n, n) for n in spec.outputs)))
    vals = _states(old, new)
    for name in spec.outputs:
        a = float(old.numeric(old.outputs[name]).xreplace(vals))
        b = float(new.outputs[name].xreplace(vals))
        assert abs(a) > 1e-6, name  # a value that can disagree
        assert b == pytest.approx(a, rel=1e-12), name


def test_the_element_stress_method_is_a_system_beams_too():
    """A system scene's modal beam with stress = "element:N" gives the paper's element method
    (outputs._element_method) as the one-beam --stress element:N does, S0 against the variant;
    in 3D it is refused in one line (the method is the plane's)."""
    from flexsym.scenes.system_scene import system_from_dict

    model = {"strain": "geometric_stiffness", "axial": ["static"], "bending": ["static", "cp1"],
             "stress": "element:4", "moment": "constitutive", "axial_force": "constitutive"}
    data = {"system": {"name": "el"},
            "body": [{"name": "beam", "kind": "beam", "length": 10.0, "density": 3000.0,
                      "youngs_modulus": 7e10, "area": 4e-4, "inertia": 2e-7, "model": model}],
            "joint": [{"name": "hub", "kind": "revolute", "parent": "ground", "point": [0.0, 0.0],
                       "child": "beam.root"}],
            "driver": [{"name": "spin", "kind": "guided", "joint": "hub", "maneuver": "spin-up",
                        "omega": 6.0, "duration": 15.0}],
            "output": {"columns": {n: n for n in ("N_A", "M_A", "M_s0p3")}}}
    system = system_from_dict(data, name="el")
    beam_model = system.bodies[0].model
    assert beam_model.stress == "element:4"
    spec = replace(beam_model, outputs=("N_A", "M_A", "M_s0p3"))
    old, new = derive(spec), derive_system(system)
    vals = _states(old, new)
    for name in spec.outputs:
        a = float(old.numeric(old.outputs[name]).xreplace(vals))
        assert abs(a) > 1.0 and float(new.outputs[name].xreplace(vals)) == pytest.approx(a, rel=1e-12), name
    continuum = derive(replace(spec, stress="continuum"))
    assert float(continuum.numeric(continuum.outputs["M_s0p3"]).xreplace(vals)) != pytest.approx(
        float(new.outputs["M_s0p3"].xreplace(vals)), rel=1e-3)  # the method took effect
    flap = dict(data, system={"name": "el3", "dimension": 3})
    flap["body"] = [dict(data["body"][0], inertia_z=2e-7, inertia_y=2e-7, torsion_constant=4e-7,
                         shear_modulus=2.6e10)]
    del flap["body"][0]["inertia"]
    flap["joint"] = [dict(data["joint"][0], point=[0.0, 0.0, 0.0], axis=[0.0, 0.0, 1.0])]
    flap["output"] = {"columns": {"v": "v(beam, tip)"}}
    model3 = dict(model)
    model3.pop("axial_force"), model3.pop("moment")
    flap["body"][0]["model"] = model3 | {"strain": "foreshortening", "axial": []}
    with pytest.raises(SpecError, match="the element stress method .* is the plane's"):
        system_from_dict(flap, name="el3").validate()
