"""Joint kinds as data (flexsym/model/joint_kinds/): each kind's coordinates, cut rows and motor
law as the rest of flexsym reads them, the planar kinematics written once against closed forms,
and every kind's module in the generator's fingerprint."""
import math

import numpy as np
import pytest
import sympy as sp

from flexsym.core.versions import GENERATOR_MODULES
from flexsym.model.joint_kinds import KINDS, planar_cut_rows, planar_frame
from flexsym.model.system import SECOND, Driver, Joint, output_unit
from flexsym.scenes.system_scene import system_from_dict


def test_every_kind_is_one_module_in_the_fingerprint():
    for name, kind in KINDS.items():
        assert kind.name == name
        assert f"model.joint_kinds.{name}" in GENERATOR_MODULES  # editing a kind regenerates


@pytest.mark.parametrize("kind, extra, motions", [
    ("revolute", {}, ("turn",)), ("prismatic", {"axis": (1.0, 0.0)}, ("slide",)),
    ("clamp", {}, ()), ("spherical", {}, ()),
    ("cylindrical", {"axis": (0.0, 0.0, 1.0), "slide": 0.4, "slide_rate": 0.1}, ("turn", "slide")),
    ("universal", {"axis": (0.0, 1.0, 0.0), "parent_axis": (1.0, 0.0, 0.0), "angle2": 0.3}, ("turn", "turn")),
    ("universal", {"axis": (0.0, 1.0, 0.0)}, ()),  # closing a loop: no coordinate
])
def test_coordinates_follow_the_kinds_motions(kind, extra, motions):
    j = Joint("j", kind, "ground", "b.m", initial=0.2, **extra)
    coords = j.coordinates
    assert tuple(c.motion for c in coords) == motions
    if len(coords) == 2:  # the second's name, start values and axis (SECOND)
        value, rate = SECOND[kind][2:]
        assert coords[1].name == f"j_{value}" and coords[1].value == getattr(j, value)
        assert coords[1].rate == getattr(j, rate) and coords[1].axis == j.axis
        assert coords[0].axis == (j.parent_axis if kind == "universal" else j.axis)


def test_planar_frame_of_a_prismatic_joint_against_its_closed_form():
    """The child's point slides along the parent's axis turned by the parent's angle, its angle
    is the parent's plus the offset; a revolute joint's adds its angle and leaves the point."""
    P, phi_p, off, c, axis = np.array([0.3, -0.2]), 0.7, 0.1, 0.25, np.array([3.0, 4.0])

    def direction(angle):
        u = axis / np.linalg.norm(axis)
        return np.array([math.cos(angle) * u[0] - math.sin(angle) * u[1],
                         math.sin(angle) * u[0] + math.cos(angle) * u[1]])

    point, angle = planar_frame(KINDS["prismatic"], P, phi_p, off, [c], direction)
    along = np.array([math.cos(phi_p + math.atan2(4, 3)), math.sin(phi_p + math.atan2(4, 3))])
    assert np.allclose(point, P + c * along, atol=1e-15) and angle == pytest.approx(phi_p + off, abs=1e-15)
    point, angle = planar_frame(KINDS["revolute"], P, phi_p, off, [c], direction)
    assert np.array_equal(point, P) and angle == pytest.approx(phi_p + off + c, abs=1e-15)


def test_planar_cut_rows_measure_the_gap_as_a_length_and_the_angle():
    """A prismatic cut joint: the child point's signed distance from the parent's axis line (the
    cross product, written independently) and the angle mismatch; a clamp: the two point
    differences and the angle; symbolic rows as numeric ones."""
    x, y, a, b = sp.symbols("x y a b", real=True)
    n = sp.Matrix([-sp.sin(a), sp.cos(a)])  # the normal of a unit axis along the parent's x
    rows = planar_cut_rows(KINDS["prismatic"], (sp.Matrix([0, 0]), a), (sp.Matrix([x, y]), b), sp.Rational(1, 10),
                           lambda angle: n.subs(a, angle))
    assert [(s, length) for s, _, length in rows] == [("normal", True), ("angle", False)]
    cross = sp.cos(a) * y - sp.sin(a) * x  # axis x (child - parent), the signed distance
    assert sp.simplify(rows[0][1] - cross) == 0 and sp.simplify(rows[1][1] - (b - a - sp.Rational(1, 10))) == 0
    rows = planar_cut_rows(KINDS["clamp"], ((1.0, 2.0), 0.5), ((1.5, 1.0), 0.9), 0.25, None)
    assert [(s, e) for s, e, _ in rows] == [("x", 0.5), ("y", -1.0), ("angle", pytest.approx(0.15, abs=1e-15))]


def test_a_motor_on_a_slide_gives_a_force_in_newtons():
    """The motor's law comes from the driven coordinate's motion: a cylindrical joint's turn
    takes a torque (N m), its slide a force (N)."""
    assert [KINDS["cylindrical"].law(s) for s in (False, True)] == ["torque", "force"]
    assert KINDS["revolute"].law() == "torque" and KINDS["prismatic"].law() == "force"
    assert KINDS["clamp"].law() is None and KINDS["revolute"].law(True) is None
    system = system_from_dict({
        "system": {"name": "cyl_motor", "dimension": 3},
        "body": [{"name": "slider", "kind": "rigid", "mass": 2.0, "inertia": [0.02, 0.03, 0.04],
                  "markers": {"hole": [0.0, 0.0, 0.0]}}],
        "joint": [{"name": "c", "kind": "cylindrical", "parent": "ground", "point": [0.0, 0.0, 1.0],
                   "child": "slider.hole", "axis": [0.0, 0.0, 1.0]}],
        "driver": [{"name": "push", "kind": "motor", "joint": "c", "coordinate": "slide", "force": "1.0"},
                   {"name": "spin", "kind": "motor", "joint": "c", "torque": "0.1"}],
        "solver": {"t_end": 0.01}, "output": {"columns": {"s": "slide(c)"}},
    })
    assert isinstance(system.drivers[0], Driver)
    assert output_unit(system, "torque(push)") == "N" and output_unit(system, "torque(spin)") == "N m"
