"""Is a Cartesian point reachable? Inverse kinematics as the analyses see it.

A Cartesian workspace analysis (reachability grid, GCI over a Cartesian box) needs, for a
batch of TCP points, the joint coordinates of every solution branch and whether each
branch is real.  Any object with this interface plugs in (:class:`InverseKinematics`):
the closed-form planar 2R below now; a parallel mechanism's closed-form inverse
kinematics (DELTA: one quadratic per leg, 2^3 branches or the chosen working mode, with
its passive-joint limits folded into ``valid``) and the serial inverse kinematics of
issue 7 later.  Joint limits are applied here, once, for all of them
(:func:`feasible_configurations`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from symkin.analysis import mechanism
from symkin.analysis.limits import LIMIT_TOLERANCE, within_limits
from symkin.analysis.parallel import parallel_inverse


class InverseKinematics(Protocol):
    """Every inverse-kinematics solution of a batch of TCP points.

    Attributes:
        dimension: d, the number of TCP coordinates of a point (the workspace dimension,
            in the order of :func:`symkin.analysis.mechanism.position_axes`).
        branches: B, the number of solution branches returned per point.
    """

    dimension: int
    branches: int

    def solve(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Solutions of points (N, d): joint coordinates (N, B, n) and validity (N, B).

        ``valid`` is False where a branch has no real solution (the point is out of reach
        for it); joint limits are not checked here.
        """
        ...


def feasible_configurations(inverse: InverseKinematics, points: np.ndarray, limits: np.ndarray,
                            revolute: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each point, the first solution branch within the joint limits.

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
    first = np.argmax(feasible, axis=1)
    return q[np.arange(len(q)), first], feasible.any(axis=1)


def reachable(inverse: InverseKinematics, points: np.ndarray, limits: np.ndarray, revolute: np.ndarray) -> np.ndarray:
    """Boolean (N,): whether each point has an inverse-kinematics solution within the limits."""
    return feasible_configurations(inverse, points, limits, revolute)[1]


# --- planar 2R ------------------------------------------------------------------------------
# Minimal closed form, kept here because symkin has no inverse kinematics yet.  When the
# serial inverse kinematics of issue 7 lands, an adapter from it to InverseKinematics
# replaces this section (and planar_2r_inverse becomes a special case of it).


@dataclass(frozen=True)
class Planar2RInverse:
    """Closed-form inverse kinematics of a planar arm with two revolute joints.

    The arm is p(q) = c + l1 u(q1 + a1) + l2 u(q1 + q2 + a2) with u(phi) = (cos phi,
    sin phi).  With the elbow angle phi2 = q2 + a2 - a1 the law of cosines gives
    cos phi2 = (|p - c|^2 - l1^2 - l2^2) / (2 l1 l2), and then
    q1 + a1 = atan2(p - c) - atan2(l2 sin phi2, l1 + l2 cos phi2).

    Branches: 0 is phi2 >= 0, 1 is phi2 <= 0.
    """

    base: tuple[float, float]
    l1: float
    l2: float
    a1: float
    a2: float
    dimension: int = 2
    branches: int = 2

    def forward(self, q: np.ndarray) -> np.ndarray:
        """TCP points (..., 2) of joint coordinates (..., 2) (the identified closed form)."""
        phi1 = q[..., 0] + self.a1
        phi12 = q[..., 0] + q[..., 1] + self.a2
        return np.stack([self.base[0] + self.l1 * np.cos(phi1) + self.l2 * np.cos(phi12),
                         self.base[1] + self.l1 * np.sin(phi1) + self.l2 * np.sin(phi12)], axis=-1)

    def solve(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        v = np.asarray(points, dtype=np.float64) - np.asarray(self.base)
        r2 = np.einsum("...i,...i->...", v, v)
        cosine = (r2 - self.l1**2 - self.l2**2) / (2.0 * self.l1 * self.l2)
        slack = LIMIT_TOLERANCE * (self.l1 + self.l2) / min(self.l1, self.l2)
        valid = np.abs(cosine) <= 1.0 + slack
        phi2 = np.arccos(np.clip(cosine, -1.0, 1.0))
        heading = np.arctan2(v[..., 1], v[..., 0])
        solutions = []
        for elbow in (phi2, -phi2):
            phi1 = heading - np.arctan2(self.l2 * np.sin(elbow), self.l1 + self.l2 * np.cos(elbow))
            solutions.append(np.stack([phi1 - self.a1, elbow + self.a1 - self.a2], axis=-1))
        return np.stack(solutions, axis=-2), np.stack([valid, valid], axis=-1)


def planar_2r_inverse(model: Any, *, checks: int = 32, tolerance: float = 1e-9) -> Planar2RInverse:
    """Identify a planar 2R arm from its generated ``fk`` and return its inverse kinematics.

    The centre c, lengths l1, l2 and angle offsets a1, a2 are read off four forward
    evaluations (c = (p(0,0) + p(pi,0)) / 2, l2 u(a2) = (p(0,0) - p(0,pi)) / 2, ...) and then
    checked against the generated ``fk`` at ``checks`` pseudo-random configurations, so
    any model (and any bound parameter values) whose generated forward kinematics is a
    planar 2R is accepted, and nothing else.

    Raises:
        ValueError: the model is not a planar arm with two revolute joints.
    """
    if len(mechanism.coordinate_names(model)) != 2 or not mechanism.revolute_mask(model).all():
        raise ValueError(f"{model.name}: the closed-form inverse kinematics needs two revolute joints")
    if len(mechanism.position_axes(model)) != 2:
        raise ValueError(f"{model.name}: the closed-form inverse kinematics needs a planar task space (two of x, y, z)")
    probe = mechanism.tcp_positions(model, np.array([[0.0, 0.0], [np.pi, 0.0], [0.0, np.pi]]))
    base = (probe[0] + probe[1]) / 2.0
    link2 = (probe[0] - probe[2]) / 2.0
    link1 = probe[0] - base - link2
    l1, l2 = float(np.hypot(*link1)), float(np.hypot(*link2))
    if min(l1, l2) <= 0:
        raise ValueError(f"{model.name}: a link of zero length: not a planar 2R arm")
    candidate = Planar2RInverse((float(base[0]), float(base[1])), l1, l2,
                                float(np.arctan2(link1[1], link1[0])), float(np.arctan2(link2[1], link2[0])))
    q = np.random.default_rng(0).uniform(-np.pi, np.pi, (checks, 2))
    mismatch = np.max(np.abs(candidate.forward(q) - mechanism.tcp_positions(model, q)))
    if mismatch > tolerance * (l1 + l2):
        raise ValueError(f"{model.name}: the generated fk is not a planar 2R arm in its task plane "
                         f"(closed form off by {mismatch:.3g}); no closed-form inverse kinematics")
    return candidate


#: Factories tried in order by :func:`inverse_kinematics_for`; each returns an
#: InverseKinematics for the model or raises ValueError.  Closed forms of more mechanisms
#: (parallel mechanisms' generated ``ik``; the serial inverse kinematics of issue 7) are registered here.
INVERSE_FACTORIES: list = [planar_2r_inverse, parallel_inverse]


def inverse_kinematics_for(model: Any) -> InverseKinematics | None:
    """The first inverse kinematics that applies to ``model``, or None."""
    for factory in INVERSE_FACTORIES:
        try:
            return factory(model)
        except ValueError:
            continue
    return None
