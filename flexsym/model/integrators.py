"""The integrator registry, as the C runtime declares it: one line per integrator in
runtime_c/include/flexsym/integrators.h,

    FSR_INTEGRATOR(name, NAME, code, FSR_CAP_... | FSR_CAP_...)

read here at import (no compiled library needed: the command line checks --integrator before
anything is built), by the C preprocessor (the fsr_method codes, the run loop's table) and by
CMake (the source files). So the list exists once; adding an integrator is its C file plus one
line there. The option table (options.py), in-process runs (sim/inprocess.py) and FMU export
(sim/fmu.py) derive what they need from REGISTRY.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

from flexsym.core.errors import FlexsymError
from flexsym.core.paths import runtime_dir

REGISTRY_FILE = ("include", "flexsym", "integrators.h")  # under runtime_c/
# FSR_CAP_* (runtime.h) -> the word used here
CAPABILITIES = {"FSR_CAP_CONSTRAINED": "constrained", "FSR_CAP_IMPLICIT": "implicit",
                "FSR_CAP_ADAPTIVE": "adaptive", "FSR_CAP_FIXED_GRID": "fixed_grid",
                "FSR_CAP_DRIVE_INPUT": "drive_input"}
_LINE = re.compile(r"FSR_INTEGRATOR\((\w+),\s*(\w+),\s*(\d+),\s*([\w\s|]+)\)\s*\Z")


@dataclass(frozen=True)
class Integrator:
    name: str          # --integrator, src/<name>.c
    constant: str      # its fsr_method constant, FSR_<NAME>
    code: int          # that constant's value
    capabilities: frozenset

    def has(self, capability: str) -> bool:
        return capability in self.capabilities


def parse(text: str) -> tuple[Integrator, ...]:
    """The registry lines of the header's text, in order; FlexsymError on a line it cannot read
    or a repeated name or code (the C enum would accept a repeated code)."""
    out = []
    for n, line in enumerate(text.splitlines(), 1):
        if not line.startswith("FSR_INTEGRATOR("):
            continue
        m = _LINE.match(line.strip())
        flags = m and [f.strip() for f in m.group(4).split("|") if f.strip() != "0"]  # 0: none
        if not m or any(f not in CAPABILITIES for f in flags):
            raise FlexsymError(f"integrator registry, line {n}: cannot read '{line.strip()}'")
        out.append(Integrator(m.group(1), "FSR_" + m.group(2), int(m.group(3)),
                              frozenset(CAPABILITIES[f] for f in flags)))
    for key in ("name", "code"):
        values = [getattr(i, key) for i in out]
        if len(set(values)) != len(values):
            raise FlexsymError(f"integrator registry: a {key} appears twice ({values})")
    return tuple(out)


REGISTRY: tuple[Integrator, ...] = parse(runtime_dir().joinpath(*REGISTRY_FILE).read_text(encoding="utf-8"))
BY_NAME = {i.name: i for i in REGISTRY}


def names(with_: str | None = None, without: str | None = None) -> tuple[str, ...]:
    """The integrators' names in the registry's order, those with (and without) a capability."""
    return tuple(i.name for i in REGISTRY
                 if (with_ is None or i.has(with_)) and (without is None or not i.has(without)))
