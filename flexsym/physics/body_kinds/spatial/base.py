"""The spatial body kinds' interface (SpatialKind) and what they and physics/spatial.py share:
a body's frame (Frame), its motion's placeholders (Motion), vectors and rotations, time
derivatives along the motion (along_motion)."""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import sympy as sp

from flexsym.core.errors import SpecError
from flexsym.model.exact_numbers import exact


def skew(a: sp.Matrix) -> sp.Matrix:
    return sp.Matrix([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])


def cross(a: sp.Matrix, b: sp.Matrix) -> sp.Matrix:
    return sp.Matrix([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def vec(v) -> sp.Matrix:
    return sp.Matrix([exact(c) for c in v])


def rotation(axis, angle) -> sp.Matrix:
    """Rodrigues: the rotation by angle about the unit axis (a number tuple, normalised here)."""
    a = vec(axis)
    a = a / sp.sqrt(a.dot(a))
    K = skew(a)
    return sp.eye(3) + sp.sin(angle) * K + (1 - sp.cos(angle)) * K * K


def euler_rotation(e: sp.Matrix) -> sp.Matrix:
    """A(e) (ground <- frame) of Euler parameters e = (e0, e1, e2, e3), |e| = 1."""
    v = e[1:, 0]
    return (e[0]**2 - v.dot(v)) * sp.eye(3) + 2 * v * v.T + 2 * e[0] * skew(v)


def euler_G(e: sp.Matrix) -> sp.Matrix:
    """G(e): the frame's angular velocity in its own components is 2 G e' (G e = 0)."""
    e0, e1, e2, e3 = e
    return sp.Matrix([[-e1, e0, e3, -e2], [-e2, -e3, e0, e1], [-e3, e2, -e1, e0]])


@dataclass
class Frame:
    """A body frame: A (ground <- frame), origin R (ground), and in the frame's own components
    its angular velocity omega, origin velocity V and the gravity g."""

    A: sp.Matrix
    R: sp.Matrix
    omega: sp.Matrix
    V: sp.Matrix
    g: sp.Matrix


@dataclass
class Motion:
    """Placeholders of a body frame's angular velocity om and origin velocity vf (its
    components), in which its T is written (casadi substitutes actual: placeholder -> value)."""

    om: sp.Matrix
    vf: sp.Matrix
    actual: dict

    @classmethod
    def of(cls, body: str, fr: Frame) -> "Motion":
        om = sp.Matrix(sp.symbols(f"{body}_Om_x {body}_Om_y {body}_Om_z", real=True))
        vf = sp.Matrix(sp.symbols(f"{body}_V_x {body}_V_y {body}_V_z", real=True))
        return cls(om, vf, {x: e for x, e in zip(om, fr.omega)} | {x: e for x, e in zip(vf, fr.V)})


class SpatialKind:
    """What physics/spatial.derive_spatial asks of a body, with the defaults of a body that has
    none (no coordinates, no part); the frame-level sums (T, V_grav, Q) accumulate in der."""

    name = ""

    def applies(self, body) -> bool:
        raise NotImplementedError

    def coordinates(self, body) -> list:
        """Its Coordinates (assemble.Coordinate), in order."""
        return []

    def part(self, der, body, P: dict) -> None:
        """What it builds once, before the frames (der.spatial[name]); P: its parameters' symbols."""

    def gauges(self, body, length: float) -> list:
        """How far it deforms along a run against its model's range (validity.Gauge); length:
        the run's (a run-time parameter)."""
        return []

    def spin_inertia(self, body, P: dict) -> sp.Expr:
        """A moment of inertia of it (a ball joint's regularisation's size)."""
        raise NotImplementedError

    def hang(self, der, fr: Frame, body: str, marker) -> tuple[Frame, sp.Matrix]:
        """(the frame a child hangs from at its marker, the marker's point in that frame)."""
        raise SpecError(f"body '{body}': a body cannot hang from a {self.name} body's marker")

    def contribute(self, der, body, P: dict, fr: Frame, motion: Motion, gvec: sp.Matrix) -> None:
        """Add its T (der.frame_T), gravity (der.V_grav), strain energy and forces (der.V, der.Q,
        der.terms), damping (der.dissipation)."""
        raise NotImplementedError

    def local_point(self, der, body: str, marker) -> sp.Matrix:
        """A marker's point in its frame's components."""
        raise NotImplementedError

    def marker_point(self, der, body: str, marker) -> sp.Matrix:
        """A marker's ground position."""
        fr = der.spatial["frames"][body]
        return fr.R + fr.A * self.local_point(der, body, marker)

    def section_rotation(self, der, body: str, marker) -> sp.Matrix:
        """Ground <- the marker's (section's) axes."""
        raise NotImplementedError

    def damping_load(self, der, body) -> tuple[sp.Matrix, sp.Matrix] | None:
        """The force and the moment about the ground origin (ground components) of its dampers
        that act on its motion relative to its frame (a tree joint's reaction carries them);
        None: none (the strain-rate damping is internal)."""
        return None

    def momentum(self, der, body, fr: Frame) -> sp.Matrix:
        """Its angular momentum about the ground origin, ground components."""
        raise SpecError(f"body '{body.name}': angular momentum is not derived for a spatial {self.name} body")

    def first_moment(self, der, body, fr: Frame) -> tuple[sp.Expr, sp.Matrix]:
        """(its mass, its first moment about the ground origin, ground components)."""
        raise SpecError(f"body '{body.name}': the first moment is not derived for a spatial {self.name} body")

    def displacement(self, der, beam, x: float, fn: str) -> sp.Expr:
        """u, v or vz at station x of a beam (frame components)."""
        raise SpecError(f"body '{beam.name}' has no fields (not a beam)")

    def section(self, der, beam, x: float, fn: str, loads_beyond, side: int = 0) -> sp.Expr:
        """N, Qy, Qz, Mx, My, Mz at station x in the deformed section's axes, constitutive or
        from equilibrium; loads_beyond(der, beam, x, fn, out, section, side): out plus the
        loads on the beam's markers beyond x (physics/spatial.py). side: the station's
        (system.station_side)."""
        raise SpecError(f"body '{beam.name}' has no sections (not a beam)")


class SpatialBeam(SpatialKind):
    """A flexible body: its frame is its root's; its parameters' mass scale for a ball joint."""

    def spin_inertia(self, body, P: dict) -> sp.Expr:
        return P["rho"] * P["A"] * P["L"]**3 / 3

    def axis_point(self, der, body: str, x: float) -> sp.Matrix:
        """The deformed axis point at station x, frame components."""
        raise NotImplementedError

    def local_point(self, der, body: str, marker) -> sp.Matrix:
        return self.axis_point(der, body, marker.x)


def along_motion(der, X: sp.Matrix, order: int) -> sp.Matrix:
    """d^order X / dt^order along the motion, as placeholders whose values casadi computes:
    forward AD of X's casadi translation along (q, q', d) -> (q', q'', d') (the drive's d' =
    [1, theta', theta'', 0]: X holds no theta''). Its cost grows with X's size; sympy's
    derivative of a beam's momentum by each coordinate in turn took 9-16 s on a 4-element arm
    and 11 minutes on 16 elements (spatial_arm's slew reaction)."""
    out = []
    for e in X:
        sym = sp.Symbol(f"ddt{order}_{len(der.casadi_outputs)}_", real=True)

        def value(tr, xx, e=e):
            z, zd = ca.vertcat(xx["q"], xx["qd"], xx["d"]), ca.vertcat(xx["qd"], xx["qdd"], xx["ddot"])
            v = tr(e)
            for _ in range(order):
                v = ca.jtimes(v, z, zd)
            return v
        der.casadi_outputs[sym] = value
        der.along[sym] = (e, order)  # what it stands for: der.ddt(e, order) (tests compare)
        out.append(sym)
    return sp.Matrix(out)
