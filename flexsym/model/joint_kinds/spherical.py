"""A spherical (ball) joint, spatial: the child turns freely about the joint's point. Its
coordinates are Euler parameters (physics/spatial.py), not turns in series: it has no
`motions`; at t = 0 the child's frame is the parent's (or its x along `direction`) and its one
start datum is the relative angular velocity `rate` (three numbers, the parent's axes)."""
from flexsym.core.errors import SpecError
from flexsym.model.joint_kinds import JointKind, finite


class Spherical(JointKind):
    euler = True

    def check(self, joint, dimension, where):
        rate = joint.rate
        if rate is not None and (not isinstance(rate, (tuple, list)) or len(rate) != 3 or not all(
                finite(w) for w in rate)):
            raise SpecError(f"{where}: rate {rate!r} must be three finite numbers (the "
                            "child's angular velocity relative to the parent at t = 0, rad/s, "
                            "in the parent's frame)")
        if joint.initial != 0 or joint.fixed:
            raise SpecError(f"{where}: a spherical joint starts with the child's frame parallel "
                            "to the parent's (no initial, no fixed); give its rate only")


KIND = Spherical("spherical", dimensions=(3,), motions=(), cut_rows=("point", ""))
