"""Legs reduced to one distance equation: point joint - rod - point joint (seed sec. 3.2.1).

Many legs end in a rod between two *point joints* (U or S: their rotations leave the joint
centre in place): the DELTA's RUU (rod b between two U joints), the Stewart-Gough UPS and
SPS, UPU, PUU, RUS...  The rod only fixes the distance between its two centres, so the
passive variables drop out and the leg gives one equation between the actuated variable
q_i and the platform coordinates p:

    f_i(q, p) = ( |B_i(p) - C_i(q)|^2 - L_i(q)^2 ) / 2 = 0,

where C_i is the proximal joint centre (moved by an actuator before it, as the DELTA's
elbow), B_i = P + R(p) b_i the platform joint, and L_i the rod length (changed by a
prismatic actuator inside the rod, as a Stewart-Gough strut).  For the DELTA this is the
seed's sphere equation with C_i (eq. 8.16, the virtual frame C'_i = C_i - b_i): all points
B_i lie on a sphere of radius b about C_i.

A leg qualifies when its last joint is U or S, the joints between the proximal point joint
and the last one are prismatic (the rod), C_i depends on no passive variable and the leg
has exactly one actuated variable, before the proximal joint or inside the rod.

In a planar mechanism (every point in planes z = const, seed eq. 8.2 with lambda = 3) a
revolute joint about the plane's normal z is a point joint of the plane: a rod between two
of them fixes only the distance between their centres, as the pantograph's distal links do
(C_i its elbow, B_i the handle).  The equation is the same, with circles for spheres.

On a sphere (a spherical mechanism: every joint axis through the centre, the platform turning
about it) the points are the axes' directions: a leg R-R-R whose middle axis w_i(q_i) is turned
by the actuator and whose last axis v_i(p) = R(p) v_i0 is fixed in the platform keeps the angle
alpha_i between them, |v_i - w_i|^2 = 2 - 2 cos alpha_i: the same equation with C_i = w_i,
B_i = v_i, b_i = v_i0 (unit vectors) and L_i^2 = 2 - 2 cos alpha_i (Gosselin's spherical 3-RRR:
w_i . v_i = cos alpha_2).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy

from symkin.kinematics.chain import Frame, MovingFrame
from symkin.model import joint_kinds
from symkin.model.schema import Leg
from symkin.parallel.legs import LegChain, attachment_point, symbol, walk



@dataclass(frozen=True)
class DistanceLeg:
    """A leg reduced to f_i(q_i, p) = (|B_i - C_i|^2 - L_i^2) / 2.

    Attributes:
        leg: the leg.
        q: the actuated variable's symbol.
        rotation: True if the actuated motion is a rotation.
        actuator: ``before`` (moves C_i) or ``rod`` (changes L_i).
        offset: constant added to q in the motion.
        C: proximal joint centre in the base frame (3x1).
        B: platform joint centre in the base frame, B(p) = P + R(p) b_i (3x1).
        b: platform joint centre in the platform frame (3x1).
        L2: squared rod length.
    """

    leg: Leg
    q: sympy.Symbol
    rotation: bool
    actuator: str
    offset: sympy.Expr
    C: sympy.ImmutableMatrix
    B: sympy.ImmutableMatrix
    b: sympy.ImmutableMatrix
    L2: sympy.Expr

    @property
    def constraint(self) -> sympy.Expr:
        """f_i = (|B_i - C_i|^2 - L_i^2) / 2."""
        d = sympy.Matrix(self.B) - sympy.Matrix(self.C)
        return (d.dot(d) - self.L2) / 2


def _point_joints(chain: LegChain, planar: bool) -> list[bool]:
    """Per joint of the leg: does it leave its centre in place whatever the rod's direction (U, S; in a
    planar mechanism also R about the normal z)?"""
    out = []
    first = 0
    for joint in chain.leg.joints:
        motions = chain.motions[first:first + len(joint.motions)]
        first += len(joint.motions)
        normal = (len(motions) == 1 and motions[0].rotation
                  and all(sympy.simplify(c) == 0 for c in motions[0].direction[:2]))
        out.append(joint_kinds.kind(joint.type).point or (planar and normal))
    return out


def reduce_leg(leg: Leg, chain: LegChain, platform: Frame, planar: bool = False) -> DistanceLeg | str:
    """The distance form of ``leg``, or the reason it has none (``planar``: R joints about z are point joints)."""
    joints = leg.joints
    point = _point_joints(chain, planar)
    what = "U, S or R about the plane's normal z" if planar else "U or S"
    if not point[-1]:
        return f"its last joint {joints[-1].name} is a {joints[-1].type.value} joint, not a point joint ({what})"
    proximal = len(joints) - 2
    while proximal >= 0 and joint_kinds.kind(joints[proximal].type).sliding:
        proximal -= 1
    if proximal < 0 or not point[proximal]:
        return f"no rod of prismatic joints between two point joints ({what}) ends the leg"
    actuated = [(i, j, j.active) for i, j in enumerate(joints) if j.active is not None]
    if len(actuated) != 1:
        return f"it has {len(actuated)} actuated joints, the distance form needs exactly one"
    index, active, motion = actuated[0]
    if index == proximal or index == len(joints) - 1:
        return "its actuator is a point joint"
    C = chain.centres[proximal]
    passive = {symbol(v) for j in joints for k, v in enumerate(j.variables) if k != j.active}
    if C.free_symbols & passive:
        return f"the centre of {joints[proximal].name} moves with passive joints before it"
    rod = MovingFrame()  # the rod, in the frame of the proximal joint after its rotations
    walk(leg, start=rod, joints=slice(proximal + 1, len(joints) - 1))
    rod.apply(joints[-1].origin)
    L2 = sympy.expand(sympy.Matrix(rod.p).dot(sympy.Matrix(rod.p)))
    if L2.free_symbols & passive:
        return "a passive prismatic joint changes the rod length"
    variable, _, rotation = active.motions[motion]
    return DistanceLeg(leg, symbol(variable), rotation, "before" if index < proximal else "rod", active.offset,
                       sympy.ImmutableMatrix(C), sympy.ImmutableMatrix(attachment_point(platform, chain)),
                       sympy.ImmutableMatrix(chain.attachment.p), L2)


def reduce_spherical_leg(leg: Leg, chain: LegChain, platform: Frame) -> DistanceLeg | str:
    """The distance form on the unit sphere of a leg of revolute joints about axes through the centre (the
    base origin), or the reason it has none (see the module docstring)."""
    joints = leg.joints
    if len(joints) < 3 or any(len(j.motions) != 1 or not j.motions[0][2] for j in joints):
        return "a spherical leg is a chain of at least three revolute joints"
    for joint, motion in zip(joints, chain.motions):
        moment = sympy.Matrix(motion.point).cross(sympy.Matrix(motion.direction))
        if any(sympy.simplify(c) != 0 for c in moment):
            return f"the axis of {joint.name} does not pass through the centre of rotation (the base origin)"
    actuated = [(i, j) for i, j in enumerate(joints) if j.active is not None]
    proximal = len(joints) - 2
    if len(actuated) != 1 or actuated[0][0] >= proximal:
        return "it needs exactly one actuated joint before its last two"
    index, active = actuated[0]
    C = chain.motions[proximal].direction
    passive = {symbol(v) for j in joints for k, v in enumerate(j.variables) if k != j.active}
    if C.free_symbols & passive:
        return f"the axis of {joints[proximal].name} moves with passive joints before it"
    b_i = sympy.Matrix(chain.attachment.R) * sympy.Matrix(joints[-1].motions[0][1])
    w, v = distal_axes(leg)
    L2 = sympy.simplify((w - v).dot(w - v))
    variable, _, _ = active.motions[active.active]  # type: ignore[index]
    return DistanceLeg(leg, symbol(variable), True, "before", active.offset, sympy.ImmutableMatrix(C),
                       sympy.ImmutableMatrix(sympy.Matrix(platform.R) * b_i), sympy.ImmutableMatrix(b_i), L2)


def distal_axes(leg: Leg) -> tuple[sympy.Matrix, sympy.Matrix]:
    """(w, v): the axes of a spherical leg's last two joints in the frame of the second-to-last joint after its
    rotation, the frame of the distal link that carries both (its own axis is fixed there)."""
    joints = leg.joints
    link = MovingFrame()
    link.apply(joints[-1].origin)
    return sympy.Matrix(joints[-2].motions[0][1]), sympy.Matrix(link.direction(joints[-1].motions[0][1]))


def distance_legs(chains: tuple[LegChain, ...], platform: Frame, surface: str = "space"
                  ) -> tuple[DistanceLeg, ...] | str:
    """Every leg in distance form, or why one of them has none.

    ``surface``: ``space``, ``plane`` (R joints about z are point joints) or ``sphere`` (the points are
    the directions of axes through the centre).
    """
    out = []
    for chain in chains:
        reduced = (reduce_spherical_leg(chain.leg, chain, platform) if surface == "sphere"
                   else reduce_leg(chain.leg, chain, platform, surface == "plane"))
        if isinstance(reduced, str):
            return f"leg '{chain.leg.name}' has no distance form: {reduced}"
        out.append(reduced)
    return tuple(out)
