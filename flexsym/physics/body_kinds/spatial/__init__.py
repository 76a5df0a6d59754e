"""Spatial body kinds, one module each: what a body adds to physics/spatial.derive_spatial.

The 3D counterpart of the planar kinds one level up, kept apart because a body's share of a
spatial derivation is written in other terms (a frame's rotation matrix and placeholder motion,
T left to casadi) and asked other things (a hung body's section frame, the section's axes, six
section loads). A kind says which bodies it is for (`applies`: the planar kind's predicate,
the data being the same), its coordinates, the part it builds once before the frames (`part`),
the frame a child hangs from at its marker (`hang`), its share of T, V and Q given its frame
(`contribute`), and its markers' points and axes, angular momentum and first moment, fields and
section loads, and its `gauges` after a run (physics/validity.py). The interface and the
vectors and frames it is written in are in base.py.
"""
from __future__ import annotations

from flexsym.physics.body_kinds.base import one_kind
from flexsym.physics.body_kinds.spatial import ef, modal, rigid
from flexsym.physics.body_kinds.spatial.base import SpatialKind

KINDS = {m.KIND.name: m.KIND for m in (rigid, modal, ef)}  # by name


def kind_of(body) -> SpatialKind:
    """The one spatial kind whose `applies` holds for the body's data."""
    return one_kind(KINDS, body, "spatial")
