"""A universal joint (spatial): in the tree, two turns in series, about `parent_axis` (the
parent's frame), then about `axis` in the turned frame, the child's; closing a loop, no
coordinate: the child's `axis` stays across a cross axis fixed in the parent (its one rotation
row, physics/spatial._cut_rows)."""
from flexsym.core.errors import SpecError
from flexsym.model.joint_kinds import JointKind


class Universal(JointKind):
    def motions_of(self, joint):
        return self.motions if joint.parent_axis is not None else ()

    def axes(self, joint):
        return (joint.parent_axis, joint.axis) if self.motions_of(joint) else ()

    def check(self, joint, dimension, where):
        if dimension == 3 and joint.axis is None:
            raise SpecError(f"{where}: a universal joint needs its child's axis (three numbers, in the "
                            "child's frame)")
        super().check(joint, dimension, where)
        if not self.motions_of(joint) and (joint.initial or joint.fixed or joint.rate is not None):
            raise SpecError(f"{where}: initial, rate and fixed apply to a universal joint in the tree "
                            "(with parent_axis); one closing a loop has no coordinate")


KIND = Universal("universal", dimensions=(3,), motions=("turn", "turn"), cut_rows=("point", "cross"),
                 second=("turn", "second angle", "angle2", "rate2"), axis_dims=(3,), axis_frame="child's")
