"""Mobility of mechanisms: Gruebler-Kutzbach-Chebychev, degree of parallelism, joint-DoF budget.

Seed sec. 2.2 ("Synthesis of Parallel Mechanisms"):

* degree of parallelism, eq. (8.1): P_g = k / F (k legs, F DoF); fully parallel when
  P_g = 1, partially parallel when P_g < 1, highly parallel when P_g > 1;
* Gruebler-Kutzbach-Chebychev, eq. (8.2): F = lambda (n - g - 1) + sum f_i - f_id + s, with
  lambda = 6 (spatial) or 3 (planar), n bodies (base and platform included), g joints of
  f_i DoF each, f_id identical (idle) DoF and s constraints that must hold to move;
* bodies of k legs joining base and platform, eq. (8.3): n = g - k + 2;
* hence, without identical conditions and constraints, eq. (8.4): the joint DoF to
  distribute are sum f_i = F + lambda (k - 1) (the seed prints it for lambda = 6).

An identical condition is, e.g., a rod between two *spherical* joints, which can spin about
its own axis without moving anything else.  (The seed says "universal joints at both of its
ends"; a rod between two universal joints cannot spin freely, and the seed's own DELTA count
- 15 joint DoF for F = 3 with RUU legs - needs f_id = 0 for its U-U rods.)
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import sympy

from symkin.model import joint_kinds
from symkin.model.schema import Model, PlatformMotion, fixed_pose

SPATIAL = 6
PLANAR = 3
SCHOENFLIES = 4


def gruebler(lam: int, bodies: int, joint_dofs: list[int] | tuple[int, ...], identical: int = 0,
             constraints: int = 0) -> int:
    """F = lambda (n - g - 1) + sum f_i - f_id + s (seed eq. 8.2)."""
    return lam * (bodies - len(joint_dofs) - 1) + sum(joint_dofs) - identical + constraints


def bodies_of_legs(joints: int, legs: int) -> int:
    """n = g - k + 2: the bodies of k legs with g joints in all between base and platform (seed eq. 8.3)."""
    return joints - legs + 2


def joint_dof_budget(dof: int, legs: int, lam: int = SPATIAL) -> int:
    """sum f_i = F + lambda (k - 1): eq. (8.2) with eq. (8.3), f_id = s = 0 (seed eq. 8.4)."""
    return dof + lam * (legs - 1)


def degree_of_parallelism(legs: int, dof: int) -> Fraction:
    """P_g = k / F (seed eq. 8.1)."""
    return Fraction(legs, dof)


def parallelism_class(pg: Fraction) -> str:
    """fully (P_g = 1), partially (P_g < 1) or highly (P_g > 1) parallel."""
    return "fully parallel" if pg == 1 else "partially parallel" if pg < 1 else "highly parallel"


@dataclass(frozen=True)
class MobilityReport:
    """The terms of eq. (8.2) for one model and what follows from them.

    Attributes:
        model: model name.
        mechanism: ``serial`` or ``parallel``.
        lam: spatial factor lambda.
        bodies: n, base and platform (or last link) included.
        joint_dofs: f_i of every joint.
        identical: f_id.
        constraints: s.
        legs: k (1 for a serial chain).
        intended: the DoF the mechanism is built for (its task coordinates for a parallel
            mechanism, its joints for a serial chain).
    """

    model: str
    mechanism: str
    lam: int
    bodies: int
    joint_dofs: tuple[int, ...]
    identical: int
    constraints: int
    legs: int
    intended: int

    @property
    def joints(self) -> int:
        return len(self.joint_dofs)

    @property
    def mobility(self) -> int:
        return gruebler(self.lam, self.bodies, self.joint_dofs, self.identical, self.constraints)

    @property
    def parallelism(self) -> Fraction:
        return degree_of_parallelism(self.legs, self.mobility) if self.mobility > 0 else Fraction(0)

    @property
    def budget(self) -> int:
        return joint_dof_budget(self.intended, self.legs, self.lam)


def idle_rods(model: Model) -> int:
    """Legs ending in a rod between two spherical joints (only prismatic joints in between): one idle spin each."""
    assert model.parallel is not None
    count = 0
    for leg in model.parallel.legs:
        kinds = [joint_kinds.kind(j.type) for j in leg.joints]
        k = len(kinds) - 2
        while k >= 0 and kinds[k].sliding:
            k -= 1
        if kinds[-1].ball and k >= 0 and kinds[k].ball:
            count += 1
    return count


def idle_platform_spin(model: Model) -> int:
    """1 when a planar platform without 'yaw' is a point that every leg ends on (a pantograph's handle joint).

    The legs then end in revolute joints about one axis through that point, and the platform can spin
    about it without moving anything else: an identical condition of eq. (8.2).
    """
    assert model.parallel is not None
    parallel = model.parallel
    if parallel.motion is not PlatformMotion.PLANAR or "yaw" in parallel.coordinates:
        return 0
    attachments = {tuple(sympy.simplify(c) for c in fixed_pose(leg.platform)[1]) for leg in parallel.legs}
    return 1 if len(attachments) == 1 else 0


def vertical_axes_only(model: Model) -> bool:
    """Whether every revolute motion of every leg turns about a vertical axis (z of the base frame): the legs
    then move within the Schoenflies group X(z) of translations and turns about z (Herve 1978).

    Checked at zero joint values: if every earlier rotation of a leg is about z, a later axis that is vertical
    there stays vertical at any joint values (a turn about z keeps z).
    """
    assert model.parallel is not None
    for leg in model.parallel.legs:
        rotation, _ = fixed_pose(leg.base)
        for joint in leg.joints:
            rotation = rotation * fixed_pose(joint.origin)[0]
            for _variable, axis, turns in joint.motions:
                direction = rotation * sympy.Matrix(axis)
                if turns and any(sympy.simplify(c) != 0 for c in direction[:2]):
                    return False
    return True


def spatial_factor(model: Model) -> int:
    """lambda of eq. (8.2) for a parallel model: the dimension of the displacement group its joints move in -
    3 for a planar or spherical platform, 4 for a Schoenflies platform whose legs turn about vertical axes
    only (the SCARA-like legs of X(z)), 6 otherwise."""
    assert model.parallel is not None
    if model.parallel.motion is PlatformMotion.SCHOENFLIES and vertical_axes_only(model):
        return SCHOENFLIES
    return model.parallel.motion.spatial_factor


def model_mobility(model: Model) -> MobilityReport:
    """The mobility terms of ``model``: bodies and joints from its chain or legs; lambda from
    :func:`spatial_factor` (6 for a serial chain)."""
    if model.parallel is None:
        dofs = tuple(1 for _ in model.joints)
        # a follower's motion is fixed by its leader's (a gear coupling): it takes a DoF like an idle one
        followers = len(model.joints) - model.dof
        return MobilityReport(model.name, "serial", SPATIAL, len(dofs) + 1, dofs, followers, 0, 1, model.dof)
    legs = model.parallel.legs
    dofs = tuple(j.type.dof for leg in legs for j in leg.joints)
    identical = idle_rods(model) + idle_platform_spin(model) + model.parallel.identical
    bodies = bodies_of_legs(len(dofs), len(legs))
    wrist = model.parallel.wrist
    if wrist is not None:
        # an open chain on the platform: each joint adds a body and its DoF, lambda (1 - 1) + 1 = 1 whatever
        # lambda is; a follower's DoF is taken by its coupling, as in a serial chain
        dofs += tuple(1 for _ in wrist.joints)
        bodies += len(wrist.joints)
        identical += len(wrist.joints) - len(wrist.coordinates)
    intended = model.parallel.task_dof + (0 if wrist is None else len(wrist.coordinates))
    return MobilityReport(model.name, "parallel", spatial_factor(model), bodies, dofs, identical,
                          model.parallel.constraints, len(legs), intended)
