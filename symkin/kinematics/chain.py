"""Compose the frames of a serial chain: link poses, joint axes and the TCP pose.

The chain is walked once, base to tip, applying each joint's fixed operations and motion
in the moving frame (seed sec. 3.1, DH step 4: base_T_tcp = base_T_1 1_T_2 ... n_T_tcp).

The running rotation is kept factored as ``R_prefix * Rot(axis, angle)``: a rotation
about the same axis as the trailing one only adds to ``angle``.  Consecutive parallel
revolute joints (the planar arm, the UR10e's shoulder-elbow-wrist1 group) thus yield
``cos(q2 + q3 + q4)`` instead of expanded products of sines and cosines: the closed forms
of the textbook, exact, and cheaper to evaluate.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import sympy

from symkin.geometry import homogeneous, principal_axis, rotation_matrix
from symkin.model import coordinates, tree
from symkin.model.schema import JointType, Model, Op, Rotation, Translation, Vec3


@dataclass(frozen=True)
class Frame:
    """A pose in the base frame: rotation R (3x3) and origin p (3x1)."""

    R: sympy.ImmutableMatrix
    p: sympy.ImmutableMatrix

    @property
    def T(self) -> sympy.ImmutableMatrix:
        """The homogeneous transform base_T_frame."""
        return homogeneous(sympy.Matrix(self.R), sympy.Matrix(self.p))


@dataclass(frozen=True)
class JointAxis:
    """A joint's motion axis in the base frame: unit direction and a point on the axis."""

    joint: str
    type: JointType
    direction: sympy.ImmutableMatrix
    point: sympy.ImmutableMatrix


@dataclass(frozen=True)
class ChainFrames:
    """Everything the chain walk produces."""

    links: tuple[tuple[str, Frame], ...]
    axes: tuple[JointAxis, ...]
    tcp: Frame


def _canonical(axis: Vec3, angle: sympy.Expr) -> tuple[Vec3, sympy.Expr]:
    """Write a rotation about -e_k as a rotation about +e_k by -angle."""
    principal = principal_axis(axis)
    if principal is not None and principal[1] < 0:
        return tuple(-c for c in axis), -angle
    return axis, angle


class MovingFrame:
    """The frame being moved along the chain, with the factored rotation described above."""

    def __init__(self, rotation: sympy.Matrix | None = None, origin: sympy.Matrix | None = None) -> None:
        """Start at the pose (rotation, origin), the identity by default."""
        self.prefix = sympy.eye(3) if rotation is None else rotation
        self.trail_axis: Vec3 | None = None
        self.trail_angle: sympy.Expr = sympy.Integer(0)
        self.p = sympy.zeros(3, 1) if origin is None else origin
        self._rotation: sympy.Matrix | None = self.prefix

    def rotation(self) -> sympy.Matrix:
        if self._rotation is None:
            assert self.trail_axis is not None
            self._rotation = self.prefix * rotation_matrix(self.trail_axis, self.trail_angle)
        return self._rotation

    def rotate(self, axis: Vec3, angle: sympy.Expr) -> None:
        axis, angle = _canonical(axis, angle)
        if axis == self.trail_axis:
            self.trail_angle = self.trail_angle + angle
        else:
            self.prefix = self.rotation()
            self.trail_axis, self.trail_angle = axis, angle
        self._rotation = None

    def translate(self, vector: Vec3) -> None:
        self.p = self.p + self.rotation() * sympy.Matrix(vector)

    def apply(self, ops: Sequence[Op]) -> None:
        for op in ops:
            if isinstance(op, Rotation):
                self.rotate(op.axis, op.angle)
            else:
                assert isinstance(op, Translation)
                self.translate(op.vector)

    def direction(self, axis: Vec3) -> sympy.Matrix:
        """``axis`` (in the moving frame) in the base frame."""
        canonical, _ = _canonical(axis, sympy.Integer(0))
        if canonical == self.trail_axis:  # a rotation leaves its own axis fixed
            return self.prefix * sympy.Matrix(axis)
        return self.rotation() * sympy.Matrix(axis)

    def frame(self) -> Frame:
        return Frame(sympy.ImmutableMatrix(self.rotation()), sympy.ImmutableMatrix(self.p))

    def copy(self) -> MovingFrame:
        """An independent frame at the same pose with the same factored rotation (a branch starts here)."""
        other = MovingFrame.__new__(MovingFrame)
        other.prefix, other.trail_axis, other.trail_angle = self.prefix, self.trail_axis, self.trail_angle
        other.p, other._rotation = self.p, self._rotation
        return other


def compose_chain(model: Model) -> ChainFrames:
    """Walk the chain (or tree) of ``model`` and return every link frame, joint axis and the TCP.

    There is one axis per joint; a follower's moves with its leader's coordinate
    (:func:`~symkin.model.coordinates.joint_values`). A branch starts from its parent link's frame
    (:mod:`symkin.model.tree`); the TCP hangs on the tip link.
    """
    base = MovingFrame()
    base.apply(model.base)
    links = []
    axes = []
    moved: list[MovingFrame] = []  # each link's frame, where its children start
    parents = tree.parent_indices(model)
    for joint, q, parent in zip(model.joints, coordinates.joint_values(model, "q"), parents):
        moving = (base if parent < 0 else moved[parent]).copy()
        moving.apply(joint.before)
        axes.append(JointAxis(joint.name, joint.type, sympy.ImmutableMatrix(moving.direction(joint.axis)),
                              sympy.ImmutableMatrix(moving.p)))
        moving.apply((joint.motion(q + joint.offset),))
        moving.apply(joint.after)
        links.append((joint.link, moving.frame()))
        moved.append(moving)
    tcp = moved[tree.tip_index(model)].copy() if moved else base
    tcp.apply(model.tcp)
    return ChainFrames(tuple(links), tuple(axes), tcp.frame())
