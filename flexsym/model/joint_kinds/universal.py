"""A universal joint (spatial): in the tree, two turns in series, about `parent_axis` (the
parent's frame), then about `axis` in the turned frame, the child's; closing a loop, no
coordinate: the child's `axis` stays across a cross axis fixed in the parent (its one rotation
row, physics/spatial._cut_rows)."""
import math

from flexsym.core.errors import SpecError
from flexsym.model.joint_kinds import JointKind, finite
from flexsym.model.limits import MIN_AXIS

PERPENDICULAR = 1e-9  # |cos| of its two axes above this: not across each other


class Universal(JointKind):
    takes_parent_axis = True

    def motions_of(self, joint):
        return self.motions if joint.parent_axis is not None else ()

    def axes(self, joint):
        return (joint.parent_axis, joint.axis) if self.motions_of(joint) else ()

    def check(self, joint, dimension, where):
        if dimension == 3 and joint.axis is None:
            raise SpecError(f"{where}: a universal joint needs its child's axis (three numbers, in the "
                            "child's frame)")
        super().check(joint, dimension, where)
        if joint.parent_axis is not None:
            self._check_parent_axis(joint, where)
        if not self.motions_of(joint) and (joint.initial or joint.fixed or joint.rate is not None):
            raise SpecError(f"{where}: initial, rate and fixed apply to a universal joint in the tree "
                            "(with parent_axis); one closing a loop has no coordinate")


    @staticmethod
    def _check_parent_axis(joint, where):
        """In the tree: a direction, across its axis (the cross: the child starts parallel to its
        parent, so the two axes are given in one frame)."""
        a1, a2 = joint.parent_axis, joint.axis
        if (not isinstance(a1, (tuple, list)) or len(a1) != 3 or not all(finite(a) for a in a1)
                or math.hypot(*a1) < MIN_AXIS):
            raise SpecError(f"{where}: parent_axis {a1!r} must be three finite numbers, not shorter "
                            f"than {MIN_AXIS:g} (a direction in the parent's frame)")
        cos = sum(x * y for x, y in zip(a1, a2)) / (math.hypot(*a1) * math.hypot(*a2))
        if abs(cos) > PERPENDICULAR:
            raise SpecError(f"{where}: parent_axis {list(a1)} and axis {list(a2)} are "
                            f"{math.degrees(math.acos(max(-1.0, min(1.0, cos)))):.6g} degrees apart: a "
                            "universal joint's two axes cross at right angles (the child starts "
                            "parallel to its parent, so both are given in one frame)")

    def check_in_tree(self, joint, closing, where):
        """In the tree it turns about parent_axis and axis (two coordinates); closing a loop it
        takes its cross axis from the assembled start (physics/spatial._cut_rows), so a
        parent_axis there is refused rather than silently replaced."""
        if not closing and joint.parent_axis is None:
            raise SpecError(f"{where}: a universal joint in the tree needs parent_axis (three numbers, "
                            "the first turn's axis in the parent's frame, across axis; to close a "
                            "loop, list it after the joints of the tree)")
        if closing and joint.parent_axis is not None:
            raise SpecError(f"{where}: closes a loop: parent_axis applies to a universal joint in the "
                            "tree (closing a loop, its cross axis is taken across axis and the "
                            "parent's x at t = 0)")


KIND = Universal("universal", dimensions=(3,), motions=("turn", "turn"), cut_rows=("point", "cross"),
                 second=("turn", "second angle", "angle2", "rate2"), axis_dims=(3,), axis_frame="child's")
