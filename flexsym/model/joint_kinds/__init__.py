"""Joint kinds, one module each: what a kind *is*, as the rest of flexsym reads it.

A kind says where it applies (planar, spatial), how its coordinates move the child in series
(each a turn about or a slide along the joint's axis: `motions`), the keys of a second
coordinate's start values (`second`), which rows it closes a loop with (`cut_rows`), and the
generalised force a motor on each coordinate gives (`law`). The kinematics is written once, in
terms of that data: the planar child frame and cut rows here (`planar_frame`, `planar_cut_rows`:
symbolic in the derivation, physics/assemble.py, and in the assembly at t = 0,
scenes/assembly.py, which evaluates the same expressions numerically); the spatial composition
in scenes/assembly.joint_motion and the rows in physics/spatial._cut_rows. A new kind is one
module here (its KIND) plus its tests; `KINDS` lists them.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from flexsym.core.errors import SpecError
from flexsym.model.limits import is_real

# Cut rows, by their names in SPATIAL_CUT_ROWS semantics: gap "point" (the two points coincide)
# or "across" (only across the axis); rotation "" (free), "cross" (a universal joint's one),
# "axis" (the axes stay parallel: nothing in the plane, whose axis is z) or "lock" (the relative
# rotation is held).
GAPS = ("point", "across")
ROTATIONS = ("", "cross", "axis", "lock")


def finite(v) -> bool:
    return is_real(v) and math.isfinite(v)


@dataclass(frozen=True)
class JointKind:
    name: str
    dimensions: tuple  # 2: planar, 3: spatial
    motions: tuple  # its coordinates in the tree, in series: "turn" or "slide" along its axis
    cut_rows: tuple  # (gap, rotation) closing a loop (GAPS, ROTATIONS)
    # a second coordinate's (motion, what it is, the Joint field of its value, of its rate)
    second: tuple | None = None
    axis_dims: tuple = ()  # dimensions in which it takes an axis
    axis_needed: tuple = ()  # ... and in which the axis must be given
    axis_frame: str = "parent's"  # the frame its axis is given in
    euler: ClassVar[bool] = False  # its coordinates are Euler parameters (a ball joint)
    takes_parent_axis: ClassVar[bool] = False  # a first axis in the parent's frame (universal)

    def __post_init__(self):
        assert self.cut_rows[0] in GAPS and self.cut_rows[1] in ROTATIONS, self

    def motions_of(self, joint) -> tuple:
        """The motions of this joint's coordinates (a universal joint has them in the tree only)."""
        return self.motions

    def axes(self, joint) -> tuple:
        """Each coordinate's axis (a revolute's default: z)."""
        return (joint.axis or (0.0, 0.0, 1.0),) * len(self.motions_of(joint))

    def law(self, second: bool = False) -> str | None:
        """What a motor on the first (or second) coordinate gives: a torque or a force."""
        motions = self.motions
        if len(motions) <= second:
            return None
        return "torque" if motions[second] == "turn" else "force"

    @property
    def welds(self) -> bool:
        """No relative motion at all (a clamp): the child's frame follows the parent's."""
        return not self.motions and self.cut_rows == ("point", "lock")

    def planar_rows(self) -> tuple:
        """(row suffix, is a length) of its planar cut rows: a point's x and y or the gap across
        the axis, then the angle when the rotation is held (an axis row is void in the plane)."""
        gap = (("x", True), ("y", True)) if self.cut_rows[0] == "point" else (("normal", True),)
        return gap + ((("angle", False),) if self.cut_rows[1] == "lock" else ())

    def check(self, joint, dimension: int, where: str) -> None:
        """Kind-specific validation of the start values (System._check_joint runs the common
        part first): no parent_axis, and a rate is a finite number."""
        if joint.parent_axis is not None and not (self.takes_parent_axis and dimension == 3):
            raise SpecError(f"{where}: parent_axis applies to universal joints of spatial systems only "
                            "(the first turn's axis of one in the tree)")
        rate = joint.rate
        if rate is not None and not finite(rate):
            raise SpecError(f"{where}: rate {rate!r} must be a finite number")

    def check_in_tree(self, joint, closing: bool, where: str) -> None:
        """What it needs in the tree, or closing a loop (System.validate, once the tree is known)."""


def planar_frame(kind: JointKind, point, angle, offset, values, direction):
    """The child's joint point and angle from the parent's (the joint's point on the parent,
    in ground, and the parent's angle): the offset, then each coordinate in series, a turn
    adding to the angle, a slide moving the point along `direction(angle)` (the joint's unit
    axis turned to ground by the parent's angle). Symbolic or numeric alike."""
    phi = angle + offset
    for motion, c in zip(kind.motions, values):
        if motion == "turn":
            phi = phi + c
        else:
            point = point + direction(angle) * c
    return point, phi


def planar_cut_rows(kind: JointKind, parent, child, offset, normal) -> list:
    """(suffix, Phi row, is a length) of a cut joint in the plane: parent, child = (point,
    angle) of each side; normal(parent angle): the unit normal of the axis in ground."""
    (pp, ap), (pc, ac) = parent, child
    rows = []
    for suffix, length in kind.planar_rows():
        if suffix == "normal":
            n = normal(ap)
            e = (pc[0] - pp[0]) * n[0] + (pc[1] - pp[1]) * n[1]
        elif suffix == "angle":
            e = ac - ap - offset
        else:
            k = "xy".index(suffix)
            e = pc[k] - pp[k]
        rows.append((suffix, e, length))
    return rows


def _kinds() -> dict:
    from flexsym.model.joint_kinds import clamp, cylindrical, prismatic, revolute, spherical, universal
    return {m.KIND.name: m.KIND for m in (revolute, prismatic, clamp, spherical, cylindrical, universal)}


KINDS = _kinds()  # by name, in the order error messages list them
