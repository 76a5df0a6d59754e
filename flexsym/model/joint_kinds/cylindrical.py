"""A cylindrical joint (spatial): the child turns about the axis, then slides along it."""
from flexsym.model.joint_kinds import JointKind

KIND = JointKind("cylindrical", dimensions=(3,), motions=("turn", "slide"), cut_rows=("across", "axis"),
                 second=("slide", "slide", "slide", "slide_rate"), axis_dims=(3,), axis_needed=(3,))
