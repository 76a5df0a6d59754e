"""The planar body kinds' interface (BodyKind, BeamKind) and what they share: the frame's
rotation and motion (BodyFrame), what a body records for the reactions (record_body)."""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from flexsym.core.errors import SpecError
from flexsym.model.exact_numbers import exact
from flexsym.model.parameters import BEAM_PARAMS
from flexsym.model.system import Gravity


def rot(phi) -> sp.Matrix:
    return sp.Matrix([[sp.cos(phi), -sp.sin(phi)], [sp.sin(phi), sp.cos(phi)]])


def frame_acceleration(der, body: str) -> tuple:
    """(A, {omega, omega', a0x, a0y, gx, gy}) of a body's frame: its rotation, its angular rate
    and acceleration, its origin's acceleration and gravity in frame components (what the
    equilibrium recoveries put in for their placeholders, in this order)."""
    pose = der.poses[body]
    Arot = rot(pose.angle)
    omega = der.ddt(pose.angle)
    a0 = Arot.T * der.ddt(pose.R, 2)
    g = next((ld.g for ld in der.system.loads if isinstance(ld, Gravity)), (0, 0))
    gl = Arot.T * sp.Matrix([exact(c) for c in g])
    return Arot, (omega, der.ddt(omega), a0[0], a0[1], gl[0], gl[1])


def cross(a, b) -> sp.Expr:
    return a[0] * b[1] - a[1] * b[0]


def exact_number(x) -> sp.Rational:
    """A damping value as the exact rational of its decimal representation."""
    return sp.Rational(repr(float(x)))


@dataclass
class BodyFrame:
    """A body's frame in derive_system's loop: its pose (angle, R), A = rot(angle), omega =
    angle', R' and gravity g (ground components)."""

    pose: object
    A: sp.Matrix
    omega: sp.Expr
    Rdot: sp.Matrix
    g: sp.Matrix

    @classmethod
    def of(cls, der, pose, g: sp.Matrix) -> "BodyFrame":
        return cls(pose, rot(pose.angle), der.ddt(pose.angle), der.ddt(pose.R), g)

    def local(self) -> "LocalMotion":
        """Its motion in its own components (what a beam's densities are written in)."""
        ph = sp.symbols("Om_ Vx_ Vy_ Rx_ Ry_ gx_ gy_", real=True)
        A_ = self.A
        Vloc, Rloc, gloc = A_.T * self.Rdot, A_.T * self.pose.R, A_.T * self.g
        actual = {ph[0]: self.omega, ph[1]: Vloc[0], ph[2]: Vloc[1], ph[3]: Rloc[0], ph[4]: Rloc[1],
                  ph[5]: gloc[0], ph[6]: gloc[1]}
        return LocalMotion(ph, Vloc, Rloc, gloc, actual)


@dataclass
class LocalMotion:
    """A frame's motion in its own components: the placeholders ph (Om_ Vx_ Vy_ Rx_ Ry_ gx_
    gy_) of omega, V = A^T R', R = A^T R and g = A^T g, those values, and actual: ph -> value."""

    ph: tuple
    V: sp.Matrix
    R: sp.Matrix
    g: sp.Matrix
    actual: dict


def record_body(der, name, mass, pose, A_, local_moment, H) -> None:
    """The body's mass, first moment m r_G (ground) and angular momentum about the origin
    (the reactions of tree joints are the subtree's momentum balance)."""
    der.mass[name] = mass
    der.first_moment[name] = mass * pose.R + A_ * sp.Matrix(local_moment)
    der.body_momentum[name] = H


class BodyKind:
    """The interface, with the defaults of a body that has none: no coordinates, no part, no
    checks of its own, no fields, no stress from equilibrium."""

    name = ""

    def applies(self, body) -> bool:
        raise NotImplementedError

    def coordinates(self, body) -> list[tuple[str, str]]:
        """(name, group) of the coordinates it adds to q, in order."""
        return []

    def part(self, body, psyms: dict, qnames: list[str]):
        """Its deformation part (None: none), built once; psyms: its section parameters'
        symbols, qnames: the names of q (a part may record its coordinates' places)."""
        return None

    def check(self, system, tree, body) -> None:
        """Refuse, before any work, what is not derived for it (SpecError, one line)."""

    def gauges(self, body, length: float) -> list:
        """How far it deforms along a run against its model's range (validity.Gauge); length:
        the run's (a run-time parameter)."""
        return []

    def origin(self, point: sp.Matrix, angle: sp.Expr, marker) -> sp.Matrix:
        """Its frame's origin R, its tree joint's child marker at `point`, the frame turned by
        `angle`."""
        raise NotImplementedError

    def contribute(self, der, body, frame: BodyFrame, integral_symbols: bool) -> None:
        """Add its T, V_grav, momentum, strain terms and forces to der (der.V_grav and der.Q
        accumulate during the loop), and record its mass, first moment and momentum."""
        raise NotImplementedError

    def marker_pose(self, der, body, marker) -> tuple[sp.Matrix, sp.Expr]:
        """Ground position and angle of a marker on it."""
        raise NotImplementedError

    def fields_at(self, der, body: str, x: float):
        raise SpecError(f"body '{body}' has no fields (not a beam)")

    # N and M at a station of a beam (assemble._stress): from the equilibrium of the part
    # beyond it (the kind gives the inertial part; assemble adds the loads on its markers), or
    # the kind's own
    def from_equilibrium(self, beam, fn: str) -> bool:
        return False

    def own_stress(self, der, beam, x: float, fn: str, where: str, side: int = 0) -> sp.Expr:
        """side: the station's (system.station_side): which element at a node, or the mean."""
        raise NotImplementedError

    def inertial_stress(self, der, beam, x: float, fn: str, closed: bool = False) -> tuple[sp.Expr, sp.Matrix, sp.Matrix]:
        """(N or M of the inertial loads and gravity beyond x, the section point in ground,
        the section's axis in frame components: the direction N is taken along). closed: a
        point mass at x is on the part beyond (system.loads_at)."""
        raise NotImplementedError

    def damping_load(self, der, body) -> tuple[sp.Matrix, sp.Expr] | None:
        """The force its damping exerts from outside (frame components) and its moment about
        the frame's origin: the mass-proportional and modal dampers act on its motion relative
        to its frame, so the joints carry them (a joint reaction's momentum balance adds them);
        None when it has none (the strain-rate damping is internal)."""
        return None


class BeamKind(BodyKind):
    """A flexible body: a beam whose frame is its root's tangent frame."""

    def check(self, system, tree, b) -> None:
        body = getattr(b.model, "body", None)
        if body is not None:  # the body's data are the beam's: markers and p must agree
            ref = body.reference
            given = (b.length, b.section.rho, b.section.E, b.section.A, b.section.I)
            data = (body.length, ref.rho, ref.E, ref.A, ref.I)
            if any(abs(x - y) > 1e-12 * abs(y) for x, y in zip(given, data)):
                raise SpecError(f"system '{system.name}': body '{b.name}': length and section "
                                f"(rho, E, A, I) {given} differ from its finite-element data's "
                                f"length and root section {data}")

    def origin(self, point: sp.Matrix, angle: sp.Expr, marker) -> sp.Matrix:
        """Its frame is its root's tangent frame (System.validate: a beam hangs by its root)."""
        return point - sp.zeros(2, 1)

    def marker_pose(self, der, body, m) -> tuple[sp.Matrix, sp.Expr]:
        """The deformed axis point and its tangent angle phi + v_x (linear in the slope as the
        modal kinematics)."""
        pose = der.poses[body]
        u, v, slope = self.fields_at(der, body, m.x)
        return pose.R + rot(pose.angle) * sp.Matrix([station(der, body, m.x) + u, v]), pose.angle + slope


def station(der, body: str, x: float) -> sp.Expr:
    """The undeformed axis coordinate of station x on a beam, in its length parameter."""
    part = der.flex[body]
    return exact(x) / exact(part.beam.length) * part.psyms[BEAM_PARAMS[4].symbol]


def one_kind(kinds: dict, body, which: str):
    """The one kind of `kinds` whose `applies` holds for the body's data (`which`: planar or
    spatial, for the message); their predicates are disjoint, so none or two is a bug here."""
    found = [k for k in kinds.values() if k.applies(body)]
    if len(found) != 1:
        raise SpecError(f"body '{body.name}': {len(found)} {which} body kinds apply to it "
                        f"({', '.join(k.name for k in found) or 'none'})")
    return found[0]
