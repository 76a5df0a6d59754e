"""Output quantities: fields evaluated at points of the beam, as expressions of the coordinates."""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from .errors import SpecError
from .integrals import Factor


@dataclass(frozen=True)
class OutputDef:
    name: str
    unit: str
    description: str
    build: object  # (Derivation) -> sp.Expr


def field_at(der, expr: sp.Expr, at) -> sp.Expr:
    """Replace every factor placeholder in a field expression by its value at s = at."""
    subs = {}
    for ph in der.table.placeholders:
        f: Factor = der.table._factor_of[ph]
        if f.kind == "mode":
            subs[ph] = der.modes[f.a].value_at(f.order, at)
        elif at == 1:  # H_ab(1) = int_0^1 a' b' ds: an ordinary modal integral
            subs[ph] = der.table.monomial_symbol(
                [(der.table.mode_value(f.a, 1), 1), (der.table.mode_value(f.b, 1), 1)])
        elif at == 0:
            subs[ph] = sp.Integer(0)
        else:
            raise SpecError(f"the foreshortening field is only available at the root and tip, not s = {at}")
    return sp.expand(expr.xreplace(subs))


OUTPUTS: dict[str, OutputDef] = {o.name: o for o in (
    OutputDef("v_tip", "m", "transverse tip deflection v_o(L) in the moving frame",
              lambda d: field_at(d, d.fields.v, 1)),
    OutputDef("u_tip", "m", "axial tip displacement u_o(L) in the moving frame",
              lambda d: field_at(d, d.fields.u, 1)),
)}


def check_output_names(spec) -> None:
    for name in spec.outputs:
        if name not in OUTPUTS:
            raise SpecError(f"variant '{spec.name}': unknown output '{name}' "
                            f"(known: {', '.join(OUTPUTS)})")
    if len(set(spec.outputs)) != len(spec.outputs):
        raise SpecError(f"variant '{spec.name}': duplicate output in {list(spec.outputs)}")
