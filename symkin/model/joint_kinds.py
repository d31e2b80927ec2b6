"""Joint kinds as motion subspaces: the one place that knows what R, P, U, S and C joints do.

A joint of kind K moves its child frame by a sequence of elementary motions, one per degree of
freedom, each a rotation about or a translation along a unit axis of the moved frame.  The
motion subspace of a one-coordinate joint about the unit axis z is the pair (angular, linear)
of 3-vectors with twist = (angular, linear) qd (Featherstone's S, Pinocchio's ``S``):
R gives (z, 0), P gives (0, z).  Chains, Jacobians, coordinates and the dynamics ask this module
instead of branching on the kind (issue 30; tests/test_joint_kinds.py holds the ratchet on the
branches not yet moved here).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import Any

import sympy


@dataclass(frozen=True)
class Kind:
    """A joint kind: its letter and, per elementary motion, whether it is a rotation (angular)."""

    letter: str
    rotations: tuple[bool, ...]

    @property
    def dof(self) -> int:
        return len(self.rotations)


#: Every joint kind of serial chains (R, P) and of parallel mechanisms' legs (seed Fig. 8.2).
KINDS = {
    "R": Kind("R", (True,)),            # revolute: rotation about axes[0]
    "P": Kind("P", (False,)),           # prismatic: translation along axes[0]
    "U": Kind("U", (True, True)),       # universal: rotation about axes[0], then axes[1] (moved frame)
    "S": Kind("S", (True, True, True)),  # spherical: three rotations about moved axes
    "C": Kind("C", (False, True)),      # cylindrical: translation along axes[0], then rotation about it
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


def motion_subspace(joint_type: str | Enum, axis: Any, zero: Any = None) -> tuple[Any, Any]:
    """(angular, linear) 3-vectors of a one-coordinate joint about or along the unit ``axis``: its
    twist per unit coordinate rate, taken at a point on the axis.  ``zero`` is the zero vector of the
    caller's vector type (default a sympy column; SymEngine lists in the dynamics)."""
    zero = sympy.zeros(3, 1) if zero is None else zero
    return (axis, zero) if is_rotation(joint_type) else (zero, axis)
