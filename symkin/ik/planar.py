"""Closed-form IK of two revolute joints about parallel axes (the seed's planar arm, sec. 4.4.1).

Joint 1 turns about the axis (s1 h, through c1), joint 2 about (s2 h, through c2), with
s1, s2 = +-1 and h the common unit direction.  They move a point p (its position at q = 0)
to a target x.  In the plane normal to h, with a = c2 - c1, b0 = p - c2 and x - c1
projected onto the plane:

* the triangle (axis 1, axis 2, point) has sides |a|, |b0| and d = |x - c1|; the turn
  beta of link 2 relative to link 1's direction follows from the half-angle law of cosines
  (:func:`~symkin.ik.subproblems.exterior_angle`); at q = 0 that turn is
  phi0 = angle(a, b0), so  s2 theta2 = +-beta - phi0  (two elbow branches);
* with link 2 turned, the point sits at y = a + rot(h, s2 theta2) b0 (joint 1 at zero) and
  joint 1 turns y onto x:  s1 theta1 = atan2(h . (y x x), y . x)  (subproblem 1).

For the seed's arm (phi0 = 0, |a| = l1, |b0| = l2) this is the textbook
theta2 = +-acos((x^2 + y^2 - l1^2 - l2^2) / (2 l1 l2)), theta1 = atan2(y, x) - atan2(l2 s2, l1 + l2 c2),
but accurate near the stretched (theta2 -> 0) and folded arm, where the acos form loses
half the digits.  Singular cases, flagged: theta2 = 0 or pi (:attr:`BranchFlag.ELBOW`, the
branches coincide); the target on axis 1 (d = 0, theta1 undetermined,
:attr:`BranchFlag.SHOULDER`); d > |a| + |b0| or d < ||a| - |b0|| (unreachable).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from symkin.ik.closed_form import SINGULARITY_EPSILON, STRUCTURE_TOLERANCE, BranchFlag, register
from symkin.ik.problem import POSITION_INDEX, ModelKinematics
from symkin.ik.rotations import cross, rotate
from symkin.ik.screws import HomeScrews
from symkin.ik.subproblems import dot, exterior_angle, perpendicular, signed_angle


@dataclass(frozen=True)
class ParallelPair:
    """Two revolute joints about parallel axes that move a point (see the module docstring)."""

    h: np.ndarray
    c1: np.ndarray
    c2: np.ndarray
    s1: float
    s2: float
    point: np.ndarray

    @classmethod
    def from_screws(cls, screws: HomeScrews, first: int, point: np.ndarray) -> ParallelPair:
        h = screws.directions[first]
        return cls(h, screws.points[first], screws.points[first + 1], 1.0,
                   float(np.sign(np.dot(h, screws.directions[first + 1]))), point)

    # the triangle's fixed sides and its turn at q = 0: computed once per solver, not per call
    @cached_property
    def a_vec(self) -> np.ndarray:
        return perpendicular(self.h, self.c2 - self.c1)

    @cached_property
    def b0(self) -> np.ndarray:
        return perpendicular(self.h, self.point - self.c2)

    @cached_property
    def a(self) -> float:
        return float(np.linalg.norm(self.a_vec))

    @cached_property
    def b(self) -> float:
        return float(np.linalg.norm(self.b0))

    @cached_property
    def phi0(self) -> float:
        return float(signed_angle(self.h, self.a_vec, self.b0))

    def is_regular(self, scale: float) -> bool:
        """The axes are distinct and the point is off the second axis (otherwise no triangle)."""
        return bool(self.a > STRUCTURE_TOLERANCE * scale and self.b > STRUCTURE_TOLERANCE * scale)

    def solve(self, x: np.ndarray, xp: Any = np) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(theta1, theta2, flags), each (..., 2) for the branches +beta, -beta; x is (..., 3); ``xp``: the array
        module (numpy, or jax.numpy on a JAX device with x traced)."""
        h, a, b = self.h, self.a, self.b
        x_vec = perpendicular(h, x - self.c1)
        d = xp.linalg.norm(x_vec, axis=-1)
        beta = exterior_angle(a, b, d, xp)
        flags = xp.where(beta.unreachable, int(BranchFlag.UNREACHABLE_ELBOW), 0)
        flags |= xp.where(beta.clamped, int(BranchFlag.CLAMPED), 0)
        near = (beta.plus <= SINGULARITY_EPSILON) | (np.pi - beta.plus <= SINGULARITY_EPSILON)
        flags |= xp.where(near, int(BranchFlag.ELBOW), 0)
        flags |= xp.where(d <= SINGULARITY_EPSILON * (a + b), int(BranchFlag.SHOULDER), 0)
        # both branches at once: the last axis is (+beta, -beta)
        turn = xp.stack([beta.plus, beta.minus], -1) - self.phi0
        y = self.a_vec + rotate(h, turn, self.b0, xp)
        theta1 = self.s1 * signed_angle(h, y, x_vec[..., None, :], xp)
        return theta1, self.s2 * turn, xp.stack([flags, flags], -1)


class Planar2R:
    """Both elbow branches of a 2R arm with a position target in the plane of motion."""

    name = "planar 2R"
    kind = "task"
    branches: tuple[str, ...] = ("elbow +", "elbow -")

    def __init__(self, pair: ParallelPair, components: tuple[int, ...], home_point: np.ndarray):
        self.pair = pair
        self.components = components
        self.home_point = home_point

    def candidates(self, target: np.ndarray, xp: Any = np) -> tuple[np.ndarray, np.ndarray]:
        """(q (..., 2 branches, 2), flags (..., 2)) for targets (..., m) in the task space's components; ``xp``: the
        array module (numpy, or jax.numpy on a JAX device with the targets traced)."""
        # the point: the target's components, the home point's along the axes the task space leaves out
        x = xp.stack([target[..., self.components.index(k)] if k in self.components
                      else xp.full(target.shape[:-1], self.home_point[k]) for k in range(3)], axis=-1)
        theta1, theta2, flags = self.pair.solve(x, xp)
        # a target off the plane of motion (when the task space has all of x, y, z) is unreachable
        off_plane = xp.abs(dot(x - self.home_point, self.pair.h)) > SINGULARITY_EPSILON * max(
            1.0, float(np.linalg.norm(self.home_point)))
        flags = flags | xp.where(off_plane, int(BranchFlag.UNREACHABLE_ELBOW), 0)[..., None]
        return xp.stack([theta1, theta2], -1), flags


@register
def recognise_planar_2r(kin: ModelKinematics, screws: HomeScrews) -> Planar2R | None:
    """Two revolute joints, parallel distinct axes, a task space of positions that fixes the
    point in the plane of motion (the components left out lie along the axes)."""
    if kin.dof != 2 or not np.all(kin.revolute) or kin.default_kind != "task":
        return None
    if not all(c in POSITION_INDEX for c in kin.task_space):
        return None
    h = screws.directions[0]
    if np.linalg.norm(cross(h, screws.directions[1])) > STRUCTURE_TOLERANCE:
        return None
    missing = [k for k in range(3) if k not in (POSITION_INDEX[c] for c in kin.task_space)]
    if len(missing) > 1 or (missing and abs(h[missing[0]]) < 1.0 - STRUCTURE_TOLERANCE):
        return None
    point = screws.home[:3, 3]
    pair = ParallelPair.from_screws(screws, 0, point)
    if not pair.is_regular(screws.scale):
        return None
    return Planar2R(pair, tuple(POSITION_INDEX[c] for c in kin.task_space), point)
