"""The bending modes the built-in `exact` takes on a beam of a planar mechanism, from the joints
at its ends (a scene's `model = "exact"` or `--model exact`; a mode set given by name is kept).

Measured against converged `ef` (docs/theory/exact-kinematics.md, "Which modes by default"):
on a beam pinned at both ends, pinned-pinned modes converge much faster than clamped-free ones
(S2's w_mid 3.7e-4 of its peak with five, where ten clamped-free gave 1.2e-3; the four-bar's M_mid
20 times closer); on a beam pinned at its root with a free tip, pinned-free modes (S3's w_mid
3.3e-4 with five, 3.2e-3 clamped-free). Those modes leave the root's slope free: the frame is the
chord's (pp) or the pin's (pf), so they are chosen only where nothing reads or holds that frame.
Anything else keeps the clamped-free set."""
from __future__ import annotations

from dataclasses import replace

from flexsym.model.system import FlexibleBeam, System, Tree, parse_output
from flexsym.model.variant import _refs, body_model, builtin

# outputs that read the beam's frame (which these modes move to the chord or the pin)
_FRAME_OUTPUTS = ("u", "v")
_JOINT_OUTPUTS = ("angle", "rate")


def end_family(system: System, tree: Tree, b: FlexibleBeam) -> str | None:
    """'pp' (pinned at both ends), 'pf' (pinned root, free tip) or None (keep clamped-free)."""
    if getattr(b.model, "body", None) is not None or system.unpinned_root(tree, b):
        return None
    root = system.joint(tree.joint_of(b.name))
    for load in system.loads:  # a force or spring on the beam: clamped-free (a torque: unpinned_root)
        if any((getattr(load, k, None) or "").partition(".")[0] == b.name for k in ("marker", "a", "b")):
            return None
    for o in system.outputs:
        fn, args = parse_output(system, o.quantity)
        if (fn in _FRAME_OUTPUTS and args[0] == b.name) or (fn in _JOINT_OUTPUTS and args[0] == root.name):
            return None
    ends = [j for j in system.joints if j is not root
            and b.name in (j.parent.partition(".")[0], j.child.partition(".")[0])]
    if not ends:
        return "pf"
    j = ends[0]
    if len(ends) > 1 or j.kind != "revolute" or j.name not in tree.cut:
        return None
    ref = j.parent if j.parent.partition(".")[0] == b.name else j.child
    return "pp" if system.marker(ref)[1].x == b.length else None


def with_end_modes(system: System) -> System:
    """The system with each built-in `exact` beam's clamped-free modes cf1..cfN replaced by
    pp1..ppN or pf1..pfN where end_family says so."""
    exact, tree, bodies = builtin("exact"), system.tree(), []
    for b in system.bodies:
        family = end_family(system, tree, b) if b.flexible and b.model == exact else None
        if family:  # the model a scene naming these modes gets
            modes = _refs("bending", [f"{family}{k + 1}" for k in range(len(exact.bending))])
            b = replace(b, model=body_model(exact.strain, exact.axial, modes))
        bodies.append(b)
    return replace(system, bodies=tuple(bodies))
