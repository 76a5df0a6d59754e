"""Planar body kinds, one module each: what a body adds to the derivation (physics/assemble.py).

A kind says which bodies it is for (`applies`, from the body's data: the kinds' predicates are
disjoint, so `kind_of` finds one), the coordinates it adds to q (`coordinates`: (name, group)),
its deformation part, built once from the section parameters of its body (`part`, stored in
der.flex), what it refuses before any work (`check`, check_derivable's), and, given its frame's
pose and motion (`BodyFrame`), its share of T, V, the momentum, the body's mass and first
moment and the strain forces (`contribute`, the body of derive_system's loop). On a beam it
also gives the fields at a station (`fields_at`: u, v and the slope in its frame), from which
a marker's pose follows (`marker_pose`), and N and M at a station (`own_stress`, or from
equilibrium with its `inertial_stress`). After a run, its `gauges` read how far it deformed
against its model's range (physics/validity.py). The interface and what the kinds share are in
base.py. A new kind is one module here (its KIND) plus its tests; `KINDS` lists them. The
spatial kinds (physics/spatial.py's) are the subpackage spatial/, with its own interface and
registry.
"""
from __future__ import annotations

from flexsym.physics.body_kinds import ef, exact, modal, rigid
from flexsym.physics.body_kinds.base import BodyKind, one_kind

KINDS = {m.KIND.name: m.KIND for m in (rigid, modal, exact, ef)}  # by name


def kind_of(body) -> BodyKind:
    """The one kind whose `applies` holds for the body's data."""
    return one_kind(KINDS, body, "planar")
