"""A revolute joint: the child turns about the axis (z in the plane; given, or z, in space)."""
from flexsym.model.joint_kinds import JointKind

KIND = JointKind("revolute", dimensions=(2, 3), motions=("turn",), cut_rows=("point", "axis"),
                 axis_dims=(3,))
