"""The integrator registry (runtime_c/include/flexsym/integrators.h): the one list that the C
runtime, CMake and Python read (flexsym/model/integrators.py)."""
from __future__ import annotations

import re

import pytest

from flexsym.core.errors import FlexsymError
from flexsym.core.paths import runtime_dir
from flexsym.model import integrators, options
from flexsym.sim import fmu, inprocess


def test_every_descriptor_file_has_one_registry_line_and_back():
    """A line without its file fails the build; this catches the file without its line (an
    integrator nobody can select)."""
    defined = {m.group(1) for f in (runtime_dir() / "src").glob("*.c")
               for m in re.finditer(r"^const fsr_integrator\* fsr_integrator_(\w+)\(void\)", f.read_text(), re.M)}
    assert defined == set(integrators.names())
    for name in defined:
        assert (runtime_dir() / "src" / f"{name}.c").is_file()


def test_python_derives_its_lists_from_the_registry():
    assert options.INTEGRATORS == integrators.names()
    assert options.BY_NAME["integrator"].choices == integrators.names()
    assert set(options.IMPLICIT) == {"genalpha", "newmark", "radau5", "ali3p", "genalpha3"}
    assert options.BY_NAME["tol"].integrators == ("dopri5",)
    assert inprocess.METHOD_CODES["radau5"] == 4 and len(set(inprocess.METHOD_CODES.values())) == len(integrators.REGISTRY)
    assert fmu.CONSTRAINED == ("ali3p", "genalpha3", "rk4p")
    assert set(fmu.METHODS) | set(fmu.CONSTRAINED) == set(integrators.names())


@pytest.mark.parametrize("text, says", [
    ("FSR_INTEGRATOR(rk4, RK4, 0, FSR_CAP_FAST)", "cannot read"),
    ("FSR_INTEGRATOR(rk4, RK4, 0)", "cannot read"),
    ("FSR_INTEGRATOR(rk4, RK4, 0, 0)\nFSR_INTEGRATOR(rk5, RK5, 0, 0)", "a code appears twice"),
    ("FSR_INTEGRATOR(rk4, RK4, 0, 0)\nFSR_INTEGRATOR(rk4, RK4B, 1, 0)", "a name appears twice"),
], ids=["unknown_capability", "no_capabilities", "code_twice", "name_twice"])
def test_a_registry_line_python_cannot_read_is_refused(text, says):
    with pytest.raises(FlexsymError, match=says):
        integrators.parse(text)


def test_a_line_reads_as_name_constant_code_and_capabilities():
    (i,) = integrators.parse("/* comment */\nFSR_INTEGRATOR(radau5, RADAU5, 4, FSR_CAP_IMPLICIT | FSR_CAP_DRIVE_INPUT)\n")
    assert (i.name, i.constant, i.code, i.capabilities) == ("radau5", "FSR_RADAU5", 4,
                                                            frozenset({"implicit", "drive_input"}))
