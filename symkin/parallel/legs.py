"""Vector chains of the legs and the platform pose (seed sec. 3.2, "Inverse Kinematics" step 1).

Each leg is walked once from its base frame through every joint, as a serial chain
(:class:`symkin.kinematics.chain.MovingFrame`): the result is the pose of its last joint
frame as a function of the leg's joint variables, and the centre of every joint.  The
platform side of the loop is ``base_T_platform(p) * platform_T_attachment``.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy

from symkin.geometry import rotation_matrix
from symkin.kinematics.chain import Frame, MovingFrame
from symkin.model.schema import Leg, Model, Op
from symkin.parallel.inputs import task_symbols

X_AXIS = (sympy.Integer(1), sympy.Integer(0), sympy.Integer(0))
Y_AXIS = (sympy.Integer(0), sympy.Integer(1), sympy.Integer(0))
Z_AXIS = (sympy.Integer(0), sympy.Integer(0), sympy.Integer(1))


@dataclass(frozen=True)
class Motion:
    """One elementary joint motion as seen from the base: its variable, axis direction and a point on it."""

    variable: sympy.Symbol
    rotation: bool
    direction: sympy.ImmutableMatrix
    point: sympy.ImmutableMatrix


@dataclass(frozen=True)
class LegChain:
    """The walked leg.

    Attributes:
        leg: the leg.
        centres: per joint, its centre (the frame origin after its ``origin`` operations) in
            the base frame.
        motions: every elementary motion, base to platform.
        end: the last joint's frame in the base frame (after all motions).
        attachment: the attachment frame B_i in the platform frame.
        links: per joint, the frame of the link it moves (after all its motions) in the base frame.
    """

    leg: Leg
    centres: tuple[sympy.ImmutableMatrix, ...]
    motions: tuple[Motion, ...]
    end: Frame
    attachment: Frame
    links: tuple[Frame, ...] = ()


def symbol(name: str) -> sympy.Symbol:
    """The (real) symbol of a joint variable; the same for the active ones as in ``q``."""
    return sympy.Symbol(name, real=True)


def fixed_frame(ops: tuple[Op, ...]) -> Frame:
    """The pose reached by fixed operations from the identity."""
    moving = MovingFrame()
    moving.apply(ops)
    return moving.frame()


def walk(leg: Leg, start: MovingFrame | None = None, joints: slice = slice(None)) -> LegChain:
    """Walk ``leg`` (or a slice of its joints) from its base frame (or from ``start``)."""
    moving = start if start is not None else MovingFrame()
    if start is None:
        moving.apply(leg.base)
    centres = []
    motions = []
    links = []
    for joint in leg.joints[joints]:
        moving.apply(joint.origin)
        centres.append(sympy.ImmutableMatrix(moving.p))
        for k, (variable, axis, rotation) in enumerate(joint.motions):
            motions.append(Motion(symbol(variable), rotation, sympy.ImmutableMatrix(moving.direction(axis)),
                                  sympy.ImmutableMatrix(moving.p)))
            amount = symbol(variable) + (joint.offset if k == joint.active else 0)
            if rotation:
                moving.rotate(axis, amount)
            else:
                moving.translate(tuple(c * amount for c in axis))
        links.append(moving.frame())
    return LegChain(leg, tuple(centres), tuple(motions), moving.frame(), fixed_frame(leg.platform), tuple(links))


def platform_frame(model: Model) -> Frame:
    """base_T_platform(p): the TCP frame at the task coordinates p.

    Position (x, y, z) and orientation R = Rz(yaw) Ry(pitch) Rx(roll), the Z-Y-X convention of
    the serial task space, with every coordinate the platform does not move in held at 0: a
    translational platform keeps the base's orientation (a TPM, seed sec. 2.2.1), a planar one
    moves in the plane z = 0, a spherical one turns about the base origin.
    """
    assert model.parallel is not None
    values = dict(zip(model.task_space, task_symbols(model)))
    position = sympy.ImmutableMatrix([values.get(c, sympy.Integer(0)) for c in ("x", "y", "z")])
    rotation = sympy.eye(3)
    for axis, angle in ((Z_AXIS, "yaw"), (Y_AXIS, "pitch"), (X_AXIS, "roll")):
        if angle in values:
            rotation = rotation * rotation_matrix(axis, values[angle])
    return Frame(sympy.ImmutableMatrix(rotation), position)


def attachment_point(platform: Frame, chain: LegChain) -> sympy.Matrix:
    """B_i(p) = P + R(p) b_i: the platform attachment point in the base frame."""
    return sympy.Matrix(platform.p) + sympy.Matrix(platform.R) * sympy.Matrix(chain.attachment.p)
