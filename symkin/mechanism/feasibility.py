"""Is a Cartesian point reachable? Inverse kinematics as the analyses see it.

A Cartesian workspace analysis (reachability grid, GCI over a Cartesian box) needs, for a
batch of TCP points, the joint coordinates of every solution branch and whether each
branch is real.  Any object with this interface plugs in (:class:`InverseKinematics`):
the closed forms of serial arms recognised by :mod:`symkin.ik` whose target is a TCP
position (:class:`symkin.analysis.inverse.ClosedFormInverse`) and a parallel mechanism's
closed-form inverse kinematics (:func:`symkin.mechanism.reach.generated_inverse`: DELTA, one
quadratic per leg, with its passive-joint limits folded into ``valid``).  Joint limits are
applied here, once, for all of them (:func:`feasible_configurations`).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from symkin.mechanism.limits import within_limits
from symkin.mechanism.stops import StopInequalities


class InverseKinematics(Protocol):
    """Every inverse-kinematics solution of a batch of TCP points.

    Attributes:
        dimension: d, the number of TCP coordinates of a point (the workspace dimension,
            in the order of :func:`symkin.mechanism.position_axes`).
        branches: B, the number of solution branches returned per point.
    """

    @property
    def dimension(self) -> int: ...

    @property
    def branches(self) -> int: ...

    def solve(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Solutions of points (N, d): joint coordinates (N, B, n) and validity (N, B).

        ``valid`` is False where a branch has no real solution (the point is out of reach
        for it); joint limits are not checked here.
        """
        ...


def feasible_configurations(inverse: InverseKinematics, points: np.ndarray, limits: np.ndarray,
                            revolute: np.ndarray, stops: StopInequalities | None = None) -> tuple[np.ndarray, np.ndarray]:
    """For each point, the first solution branch within the joint limits (and the model's joint ``stops``).

    Returns:
        (q, reachable): joint coordinates (N, n) (meaningless where unreachable) and a
        boolean (N,) array: the point has a real solution within the limits.  Which
        branch is taken where several are feasible follows the inverse kinematics' branch
        order (for a serial arm the conditioning may differ between branches; for the
        planar 2R it does not).
    """
    q, valid = inverse.solve(np.asarray(points, dtype=np.float64))
    q, inside = within_limits(q, limits, revolute)
    feasible = valid & inside
    if stops is not None and len(stops):
        feasible &= stops.respected(q)
    first = np.argmax(feasible, axis=1)
    return q[np.arange(len(q)), first], feasible.any(axis=1)


def reachable(inverse: InverseKinematics, points: np.ndarray, limits: np.ndarray, revolute: np.ndarray,
              stops: StopInequalities | None = None) -> np.ndarray:
    """Boolean (N,): whether each point has an inverse-kinematics solution within the limits (and ``stops``)."""
    return feasible_configurations(inverse, points, limits, revolute, stops)[1]
