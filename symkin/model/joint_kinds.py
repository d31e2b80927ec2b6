"""Joint kinds as motion subspaces: the one place that knows what R, P, U, S and C joints do.

A joint of kind K moves its child frame by a sequence of elementary motions, one per degree of
freedom, each a rotation about or a translation along a unit axis of the moved frame.  The
motion subspace of a one-coordinate joint about the unit axis z is the pair (angular, linear)
of 3-vectors with twist = (angular, linear) qd (Featherstone's S, Pinocchio's ``S``):
R gives (z, 0), P gives (0, z).  Chains, Jacobians, coordinates and the dynamics ask this module
instead of branching on the kind (issue 30; tests/model/test_joint_kinds.py holds the ratchet on the
branches not yet moved here).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from enum import Enum
from typing import Any

import sympy


@dataclass(frozen=True)
class Kind:
    """A joint kind: its letter and, per elementary motion, whether it is a rotation (angular), which
    declared axis it moves about or along, and how its variable is named.

    Attributes:
        letter: R, P, U, S or C.
        rotations: per motion, True for a rotation, False for a translation.
        motion_axes: per motion, the index of the declared axis it uses (a C joint declares one axis,
            along which it slides and about which it turns).
        actuable: the index of the motion an actuator may drive, None if none may (U, S).
        suffixes: per motion, the suffix of its variable's name ("" for the joint's own name).
    """

    letter: str
    rotations: tuple[bool, ...]
    motion_axes: tuple[int, ...]
    actuable: int | None
    suffixes: tuple[str, ...]

    @property
    def dof(self) -> int:
        return len(self.rotations)

    @property
    def axes(self) -> int:
        """How many axes a model declares for the joint."""
        return max(self.motion_axes) + 1

    @property
    def point(self) -> bool:
        """Rotations only, about axes through one point (U, S): the joint is a point of both links."""
        return self.dof > 1 and all(self.rotations)

    @property
    def sliding(self) -> bool:
        """One translation (P): it changes a distance and adds no point."""
        return self.rotations == (False,)

    @property
    def ball(self) -> bool:
        """Three rotations (S): any orientation about its point."""
        return self.dof == 3 and all(self.rotations)

    def variables(self, name: str) -> tuple[str, ...]:
        """The names of the motions' variables of a joint called ``name``."""
        return tuple(name + suffix for suffix in self.suffixes)

    def default_axes(self, z: Any, y: Any, x: Any) -> tuple[Any, ...]:
        """The axes of a joint that declares none: z, then y, then x of its frame."""
        return (z, y, x)[:self.axes]


#: Every joint kind of serial chains (R, P) and of parallel mechanisms' legs (seed Fig. 8.2).
KINDS = {
    "R": Kind("R", (True,), (0,), 0, ("",)),                       # revolute: rotation about axes[0]
    "P": Kind("P", (False,), (0,), 0, ("",)),                      # prismatic: translation along axes[0]
    "U": Kind("U", (True, True), (0, 1), None, ("_1", "_2")),       # universal: about axes[0], then axes[1]
    "S": Kind("S", (True, True, True), (0, 1, 2), None, ("_1", "_2", "_3")),  # spherical: three moved axes
    "C": Kind("C", (False, True), (0, 0), 0, ("_t", "_r")),        # cylindrical: along axes[0], then about it
}


def kind(joint_type: str | Enum) -> Kind:
    """The :class:`Kind` of a joint type (a :class:`~symkin.model.schema.JointType`, a
    :class:`~symkin.model.schema.LegJointType` or its letter)."""
    letter = joint_type.value if isinstance(joint_type, Enum) else joint_type
    return KINDS[str(letter)]


def is_rotation(joint_type: str | Enum) -> bool:
    """Whether a one-coordinate joint's coordinate is an angle (R) rather than a length (P)."""
    (rotation,) = kind(joint_type).rotations
    return rotation


def per_coordinate(joint_type: str | Enum, angular: Any, linear: Any) -> Any:
    """What a one-coordinate joint's coordinate is measured by: ``angular`` where it is an angle (R), ``linear``
    where it is a length (P) - a unit, a dimension, a typical span, a file format's joint type."""
    return angular if is_rotation(joint_type) else linear


def worked_part(joint_type: str | Enum, pair: tuple[Any, Any]) -> Any:
    """The part of an (angular, linear) pair - a wrench's (moment, force) - that a one-coordinate joint's motion
    works against: tau = S^T f is the moment about a rotation's axis and the force along a translation's axis
    (``dot(axis, worked_part(type, wrench))``, Featherstone 2008 eq. 5.13)."""
    return per_coordinate(joint_type, *pair)


def motion_subspace(joint_type: str | Enum, axis: Any, zero: Any = None) -> tuple[Any, Any]:
    """(angular, linear) 3-vectors of a one-coordinate joint about or along the unit ``axis``: its
    twist per unit coordinate rate, taken at a point on the axis.  ``zero`` is the zero vector of the
    caller's vector type (default a sympy column; SymEngine lists in the dynamics)."""
    zero = sympy.zeros(3, 1) if zero is None else zero
    return (axis, zero) if is_rotation(joint_type) else (zero, axis)


def twist_column(rotation: bool, direction: Iterable[Any], axis_point: Iterable[Any], point: Iterable[Any]
                 ) -> tuple[list[Any], list[Any]]:
    """(linear, angular) velocity of the frame at ``point`` per unit rate of one elementary joint motion - a rotation
    about (``rotation``) or a translation along the unit ``direction`` through ``axis_point``: the motion subspace
    (w, v) = (z, 0) or (0, z) moved from the axis to the point, v + w x (point - axis_point) (Featherstone 2008,
    eq. 2.21) - one column of a geometric Jacobian, as 3-lists of the callers' scalars (sympy, SymEngine, numpy)."""
    z = list(direction)
    zero = [component * 0 for component in z]
    if not rotation:
        return z, zero
    r = [a - b for a, b in zip(point, axis_point)]
    return [z[1] * r[2] - z[2] * r[1], z[2] * r[0] - z[0] * r[2], z[0] * r[1] - z[1] * r[0]], z
