"""A prismatic joint: the child slides along the axis (parent's frame), its rotation held."""
from flexsym.model.joint_kinds import JointKind

KIND = JointKind("prismatic", dimensions=(2, 3), motions=("slide",), cut_rows=("across", "lock"),
                 axis_dims=(2, 3), axis_needed=(2, 3))
