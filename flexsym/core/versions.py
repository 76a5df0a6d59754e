"""Tool versions and the generator fingerprint recorded in every manifest."""
from __future__ import annotations

import hashlib
from functools import lru_cache

import casadi
import jinja2
import sympy

from flexsym import __version__
from flexsym.core.paths import module_file, templates_dir

# One module per body kind (physics/body_kinds: the planar kinds, and the spatial ones in its
# subpackage spatial/): in the generator's hash, and in a system's fingerprint (sysgen._OWN)
_KINDS_DIR = module_file("physics.body_kinds.__init__").parent
BODY_KIND_MODULES = tuple("physics.body_kinds." + ".".join(f.relative_to(_KINDS_DIR).with_suffix("").parts)
                          for f in sorted(_KINDS_DIR.rglob("*.py")))
# Modules whose code decides what is generated: a change in any of them changes the
# fingerprint of every variant, so checked-in generated code is detected as stale.
GENERATOR_MODULES = ("model.modes", "physics.integrals", "physics.energy", "model.strain_models",
                     "model.maneuver", "model.output_names", "model.parameters", "model.system",
                     "model.library", "physics.assemble", "physics.efbody", "physics.outputs",
                     "model.variant", "physics.lagrange", "physics.modal", "codegen.derive",
                     "emit.kernels", "emit.cemit", "codegen.generate", "codegen.folder", "physics.fe", "model.fedata",
                     "physics.exact", "physics.exact_kinematics", "physics.exact_body", "model.beam_element", "physics.spatial", "physics.spatial_ef",
                     "physics.rod3d", "scenes.assembly", "model.exact_numbers",  # assembly: a ball joint's start (shortest_turn)
                     *(f"model.joint_kinds.{f.stem}" for f in sorted(  # one module per joint kind
                         module_file("model.joint_kinds.__init__").parent.glob("*.py"))),
                     *BODY_KIND_MODULES)


def tool_versions() -> dict[str, str]:
    return {"flexsym": __version__, "sympy": sympy.__version__, "casadi": casadi.__version__,
            "jinja2": jinja2.__version__}


@lru_cache(maxsize=None)
def generator_hash() -> str:
    h = hashlib.sha256()
    files = [module_file(m) for m in GENERATOR_MODULES]
    files += sorted(templates_dir().glob("*.j2"))
    for f in files:
        h.update(f.name.encode() + b"\0")
        h.update(f.read_bytes().replace(b"\r\n", b"\n"))
    return h.hexdigest()
