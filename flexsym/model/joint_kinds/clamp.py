"""A clamp: the child is welded to the parent (no coordinate; `offset` turns it in the plane)."""
from flexsym.core.errors import SpecError
from flexsym.model.joint_kinds import JointKind


class Clamp(JointKind):
    def check(self, joint, dimension, where):
        super().check(joint, dimension, where)
        if joint.initial != 0:
            raise SpecError(f"{where}: initial applies to revolute and prismatic joints only (a "
                            "clamp has no coordinate; use offset for its angle)")


KIND = Clamp("clamp", dimensions=(2, 3), motions=(), cut_rows=("point", "lock"))
