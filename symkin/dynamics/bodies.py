"""Velocity Jacobians of the bodies of a serial chain at their centres of mass.

For a body attached to link i with centre of mass c (base frame), the linear and angular
velocities are v_c = Jv qd and w = Jw qd with columns, for every joint j <= i,

* revolute:  Jv_j = z_j x (c - a_j),  Jw_j = z_j;
* prismatic: Jv_j = z_j,              Jw_j = 0,

and zero columns for the joints after link i, where z_j is the unit axis of joint j and
a_j a point on it (both in the base frame, from the one chain walk of
:mod:`symkin.kinematics.chain`).  The angular columns are kept in the body's link axes,
R_i^T z_j, where the inertia tensor is constant.  Everything is a SymEngine expression
(see :mod:`symkin.dynamics.program`).

Massless bodies are dropped here, so they cost nothing downstream: a body with zero mass
has no translational term, one with a zero inertia tensor no rotational term.
"""

from __future__ import annotations

from dataclasses import dataclass

import symengine as se

from symkin.dynamics.program import se_matrix, se_vector
from symkin.kinematics.chain import ChainFrames
from symkin.model import joint_kinds, tree
from symkin.model.schema import Model

ZERO3 = (se.Integer(0), se.Integer(0), se.Integer(0))


@dataclass(frozen=True)
class BodyJacobians:
    """One body's mass properties and velocity Jacobians (SymEngine expressions).

    Attributes:
        link: the link the body is attached to.
        joints: number of joints that move it (i + 1 for link i); later columns are zero.
        mass: the mass m (zero when the body only has rotational inertia).
        com: centre of mass c in the base frame (3-vector).
        linear: the columns Jv_j of the CoM velocity Jacobian (base frame), j < joints.
        angular: the columns of the angular velocity Jacobian in link axes, j < joints.
        inertia: inertia tensor about the CoM in link axes (3x3 rows), or None if zero.
    """

    link: str
    joints: int
    mass: se.Basic
    com: tuple[se.Basic, ...]
    linear: tuple[tuple[se.Basic, ...], ...]
    angular: tuple[tuple[se.Basic, ...], ...]
    inertia: tuple[tuple[se.Basic, ...], ...] | None


def body_jacobians(model: Model, chain: ChainFrames) -> tuple[BodyJacobians, ...]:
    """The velocity Jacobians of every body with mass or inertia, in model order."""
    frames = {name: (k, frame) for k, (name, frame) in enumerate(chain.links)}
    parents = tree.parent_indices(model)
    axes = [(axis.type, se_vector(axis.direction), se_vector(axis.point)) for axis in chain.axes]
    out = []
    for body in model.bodies:
        massless = body.mass == 0
        if massless and body.is_point_mass:
            continue
        k, frame = frames[body.link]
        R = se_matrix(frame.R)
        p = se_vector(frame.p)
        com_local = se_vector(body.com)
        com = tuple(p[r] + sum((R[r][s] * com_local[s] for s in range(3)), se.Integer(0)) for r in range(3))
        linear, angular = [], []
        moving = set(tree.path_to(parents, k))
        for j, (jtype, z, point) in enumerate(axes[:k + 1]):
            if j not in moving:  # a joint on another branch does not move the body
                linear.append(ZERO3)
                angular.append(ZERO3)
                continue
            # the joint's twist per unit rate at the centre of mass
            velocity, w = joint_kinds.twist_column(jtype.turns, z, point, com)
            linear.append(ZERO3 if massless else tuple(velocity))
            # R^T w: the joint's angular velocity in the body's link axes.
            angular.append(tuple(sum((R[s][r] * w[s] for s in range(3)), se.Integer(0)) for r in range(3)))
        inertia = None if body.is_point_mass else tuple(tuple(row) for row in se_matrix(body.inertia))
        out.append(BodyJacobians(body.link, k + 1, se.sympify(body.mass), com, tuple(linear), tuple(angular),
                                 inertia))
    return tuple(out)
