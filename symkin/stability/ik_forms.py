"""Closed-form IK along paths into singularities: symkin's forms against the textbook ones.

Two angles that the textbooks compute with ``acos`` (see :mod:`symkin.ik.subproblems`):

* the UR wrist angle q5 -> 0.  q5 is the angle between the unit vectors k = R1 h2 and
  a6 = R_d h6, a well-conditioned quantity (perturbing the target by eps moves it by about
  eps).  The textbook q5 = acos(k . a6) (e.g. Hawkins 2013, eq. for theta5) turns the rounding
  of the cosine into an error of eps/q5; symkin's atan2(|k x a6|, k . a6) keeps it near eps.
  The reference is the q5 that produced the target.
* the planar arm's elbow theta2 -> 0 (stretched).  Here the problem itself is
  ill-conditioned: theta2's relative condition number with respect to the target is
  d^2 / (l1 l2 sin(theta2) theta2) ~ 4/theta2^2, so no formula can do better than about eps
  times that; both forms stay within it, and FK(IK(x)) = x holds to rounding.  The reference
  is the exact acos evaluated by mpmath at the same float target.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import mpmath
import numpy as np

from symkin.ik import ClosedFormIK, closed_form_solver
from symkin.ik.planar import Planar2R
from symkin.ik.rotations import rotate
from symkin.mechanism.limits import wrap_angle
from symkin.ik.ur import URFamily
from symkin.runtime import LoadedModel

EPS = float(np.finfo(float).eps)


@dataclass(frozen=True)
class FormulaErrors:
    """Errors of one angle along a path into a singularity.

    Attributes:
        title: what is computed.
        angle: the angle's name.
        steps: the angle's exact values along the path (its distance to the singular value).
        textbook: absolute error of the textbook acos form (rad).
        symkin: absolute error of symkin's form (rad).
        bound: eps times the condition number of the angle (rad), where the problem is ill-conditioned.
    """

    title: str
    angle: str
    steps: np.ndarray
    textbook: np.ndarray
    symkin: np.ndarray
    bound: np.ndarray | None = None


def _ur_wrist(model: LoadedModel, ik: ClosedFormIK, steps: Sequence[float]) -> FormulaErrors:
    solver = ik.solver
    assert isinstance(solver, URFamily), "the wrist formula is the UR family's"
    textbook, ours = [], []
    for t in steps:
        q = np.array([0.4, -1.1, 1.3, 0.7, t, -0.5])
        T = model.fk(q)
        found = ik.solve(T)
        branch = int(np.argmin(np.max(np.abs(wrap_angle(found.q[:, :4] - q[:4])), axis=-1)))
        ours.append(abs(found.q[branch, 4] - t))
        R_d = T[:3, :3] @ solver.M_inv[:3, :3]
        a6 = R_d @ solver.h[5]
        k = rotate(solver.h[0], found.q[branch, 0], solver.h2)
        textbook.append(abs(np.arccos(np.clip(np.dot(k, a6), -1.0, 1.0)) - t))
    return FormulaErrors("UR wrist angle q5 -> 0 (target = fk(q), q5 = t)", "q5", np.asarray(steps),
                         np.array(textbook), np.array(ours))


def _planar_elbow(model: LoadedModel, ik: ClosedFormIK, steps: Sequence[float]) -> FormulaErrors:
    solver = ik.solver
    assert isinstance(solver, Planar2R), "the elbow formula is the planar 2R's"
    pair = solver.pair
    l1 = float(np.linalg.norm(pair.c2 - pair.c1))
    l2 = float(np.linalg.norm(pair.point - pair.c2))
    textbook, ours, bound = [], [], []
    for t in steps:
        x = model.fk([0.3, t])[:3, 3]
        found = ik.solve(x[list(solver.components)])
        d2 = float(np.dot(x - pair.c1, x - pair.c1))
        with mpmath.workdps(50):
            d = mpmath.sqrt(sum(mpmath.mpf(float(v)) ** 2 for v in x - pair.c1))
            cosine = (d * d - mpmath.mpf(l1) ** 2 - mpmath.mpf(l2) ** 2) / (2 * mpmath.mpf(l1) * l2)
            exact = mpmath.acos(min(cosine, 1))  # a rounded target may lie a hair beyond reach
            condition = d * d / (mpmath.mpf(l1) * l2 * mpmath.sin(exact) * exact) if exact > 0 else mpmath.inf
            reference = float(exact)
        ours.append(abs(found.q[0, 1] - reference))
        textbook.append(abs(np.arccos(np.clip((d2 - l1 * l1 - l2 * l2) / (2 * l1 * l2), -1, 1)) - reference))
        bound.append(EPS * float(condition) * reference)
    return FormulaErrors("planar elbow theta2 -> 0 (target = fk(0.3, t))", "theta2", np.asarray(steps),
                         np.array(textbook), np.array(ours), np.array(bound))


def formula_errors(model: LoadedModel, steps: Sequence[float]) -> list[FormulaErrors]:
    """The comparisons that apply to ``model``'s closed-form solver (none without one)."""
    ik = closed_form_solver(model)
    if ik is None:
        return []
    if isinstance(ik.solver, URFamily):
        return [_ur_wrist(model, ik, steps)]
    if isinstance(ik.solver, Planar2R):
        return [_planar_elbow(model, ik, steps)]
    return []
