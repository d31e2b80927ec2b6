"""The joint as one unit (issue 30): symkin/model/joint_kinds.py owns what each joint kind does, and a
ratchet keeps branching on joint types from spreading: the modules that still compare with
JointType/LegJointType members are listed with today's counts, which may only go down."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import sympy

from symkin.geometry import rotation_matrix
from symkin.model import joint_kinds
from symkin.model.schema import Joint, JointType, LegJointType, Rotation, Translation

PACKAGE = Path(joint_kinds.__file__).resolve().parents[1]
#: Where the kinds are defined (the enums) and owned (their behaviour).
OWNERS = {"model/schema.py", "model/joint_kinds.py"}
#: module -> branches on joint-type members left to move into joint_kinds (shrink as they move).
REMAINING = {
    "model/delta.py": 4,  # the DELTA shorthand declares its joints' kinds (R, U): declarations, no branch
    "model/serial_build.py": 4,  # reading the letters and words of joint types
}
BRANCH = re.compile(r"\bJointType\.(REVOLUTE|PRISMATIC)\b|\bLegJointType\.[RPUSC]\b")


def test_joint_type_branches_only_shrink():
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        module = path.relative_to(PACKAGE).as_posix()
        count = len(BRANCH.findall(path.read_text(encoding="utf-8")))
        if count and module not in OWNERS:
            found[module] = count
    grown = {m: (n, REMAINING.get(m, 0)) for m, n in found.items() if n > REMAINING.get(m, 0)}
    assert not grown, f"new branches on joint types (found, allowed): {grown}; ask symkin.model.joint_kinds instead"
    shrunk = {m: (found.get(m, 0), n) for m, n in REMAINING.items() if found.get(m, 0) < n}
    assert not shrunk, f"fewer branches than listed (found, listed): {shrunk}; lower REMAINING to lock it in"


#: module -> questions ``is_rotation(`` left outside joint_kinds (issue 62, "finish the joint unit": a joint kind
#: answers with its motion subspace, the part of a wrench its motion works against or what its coordinate is
#: measured by (``per_coordinate``); shrink as they move).
ROTATION_QUESTIONS = {
    "model/schema.py": 1,           # JointType.turns: a joint (Joint.turns, Coordinate.turns) answers for itself
}


def test_questions_on_the_joint_kind_only_shrink():
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        module = path.relative_to(PACKAGE).as_posix()
        count = path.read_text(encoding="utf-8").count("is_rotation(")
        if count and module != "model/joint_kinds.py":
            found[module] = count
    grown = {m: (n, ROTATION_QUESTIONS.get(m, 0)) for m, n in found.items() if n > ROTATION_QUESTIONS.get(m, 0)}
    assert not grown, f"new is_rotation( questions (found, allowed): {grown}; let the joint kind answer instead"
    shrunk = {m: (found.get(m, 0), n) for m, n in ROTATION_QUESTIONS.items() if found.get(m, 0) < n}
    assert not shrunk, f"fewer is_rotation( questions than listed (found, listed): {shrunk}; lower the count"


#: Degrees of freedom of each joint type (seed Fig. 8.2), written out independently of joint_kinds.
DOF = {"R": 1, "P": 1, "U": 2, "S": 3, "C": 2}


@pytest.mark.parametrize("member", list(JointType) + list(LegJointType))
def test_every_joint_type_has_a_kind_with_its_degrees_of_freedom(member):
    assert joint_kinds.kind(member).dof == joint_kinds.kind(member.value).dof == DOF[member.value]


def test_one_coordinate_joints_move_as_their_motion_subspace():
    z = sympy.Matrix([0, 0, 1])
    assert joint_kinds.motion_subspace(JointType.REVOLUTE, z) == (z, sympy.zeros(3, 1))
    assert joint_kinds.motion_subspace(JointType.PRISMATIC, z) == (sympy.zeros(3, 1), z)
    assert joint_kinds.is_rotation(LegJointType.R)
    assert not joint_kinds.is_rotation("P")
    with pytest.raises(ValueError):
        joint_kinds.is_rotation(LegJointType.U)  # two motions: no single coordinate


#: What a leg joint of each kind is, written out independently of joint_kinds: its variables for a joint
#: named "j", the axes a model declares, whether an actuator may drive it, and whether it is a point joint.
LEG_JOINTS = {"R": (("j",), 1, True, False), "P": (("j",), 1, True, False), "U": (("j_1", "j_2"), 2, False, True),
              "S": (("j_1", "j_2", "j_3"), 3, False, True), "C": (("j_t", "j_r"), 1, True, False)}


@pytest.mark.parametrize("letter", sorted(LEG_JOINTS))
def test_every_leg_joint_kind_names_declares_and_actuates_as_documented(letter):
    kind = joint_kinds.kind(letter)
    variables, axes, actuable, point = LEG_JOINTS[letter]
    assert (kind.variables("j"), kind.axes, kind.actuable is not None, kind.point) == (variables, axes, actuable, point)
    assert kind.default_axes("z", "y", "x") == ("z", "y", "x")[:axes]
    assert kind.sliding == (letter == "P")
    assert kind.ball == (letter == "S")


def test_a_joint_moves_a_frame_by_its_own_motion():
    """Joint.motion: a revolute joint turns about its axis by the amount, a prismatic one slides along it."""
    q, axis = sympy.Symbol("q"), (sympy.Integer(0), sympy.Integer(1), sympy.Integer(0))
    joints = {t: Joint("j", t, axis, sympy.Integer(0), (), (), "l") for t in JointType}
    assert joints[JointType.REVOLUTE].motion(q) == Rotation(axis, q)
    assert joints[JointType.PRISMATIC].motion(q) == Translation((0, q, 0))


#: The frame walkers that move a frame by a joint's motion: they ask Joint.motion, not the joint's kind.
WALKERS = ("kinematics/chain.py", "dynamics/newton_euler.py", "model/urdf_export.py")


@pytest.mark.parametrize("module", WALKERS)
def test_frame_walkers_leave_the_motion_to_the_joint(module):
    text = (PACKAGE / module).read_text(encoding="utf-8")
    assert ".motion(" in text
    assert ".turns" not in text, f"{module} branches on the joint's kind: move the frame by joint.motion(amount)"


def test_a_twist_column_is_the_rate_of_a_moved_point():
    """twist_column: the velocity of a point per unit rate of a rotation about an axis through another point (the
    derivative of Rodrigues' rotation at zero) or of a translation along it, in sympy and numpy scalars alike."""
    angle, length = sympy.symbols("angle length")
    axis = sympy.Matrix([2, -1, 2]) / 3
    through, point = sympy.Matrix([1, 2, -1]), sympy.Matrix([sympy.Rational(1, 2), 3, 4])
    turned = rotation_matrix(tuple(axis), angle) * (point - through) + through
    slid = point + length * axis
    for rotation, moved, amount in ((True, turned, angle), (False, slid, length)):
        linear, angular = joint_kinds.twist_column(rotation, axis, through, point)
        assert sympy.simplify(sympy.Matrix(linear) - moved.diff(amount).subs(amount, 0)) == sympy.zeros(3, 1)
        assert sympy.Matrix(angular) == (axis if rotation else sympy.zeros(3, 1))
        numeric = joint_kinds.twist_column(rotation, np.array(axis, dtype=float).ravel(),
                                           np.array(through, dtype=float).ravel(), np.array(point, dtype=float).ravel())
        assert np.allclose(np.concatenate(numeric), np.array(sympy.Matrix(linear + angular), dtype=float).ravel(),
                           rtol=0, atol=8 * np.finfo(float).eps)


#: The Jacobian columns of joints (serial chains, legs, bodies, the platform-motion check): each asks
#: joint_kinds.twist_column instead of transporting a motion subspace itself.
TWIST_COLUMNS = ("kinematics/quantities.py", "dynamics/bodies.py", "parallel/closure.py",
                 "parallel/closure_dynamics.py", "parallel/motion_check.py")


@pytest.mark.parametrize("module", TWIST_COLUMNS)
def test_jacobian_columns_come_from_the_joint_kind(module):
    text = (PACKAGE / module).read_text(encoding="utf-8")
    assert "joint_kinds.twist_column(" in text
    assert ".rotation else" not in text, f"{module} branches on a motion's kind: ask joint_kinds.twist_column"
