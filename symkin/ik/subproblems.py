"""Geometric subproblems of closed-form inverse kinematics, in forms that keep full accuracy.

Paden-Kahan style subproblems (Paden 1985; Murray, Li & Sastry, "A Mathematical
Introduction to Robotic Manipulation", sec. 3.3), vectorized over any batch shape.  The
textbook formulas lose accuracy exactly where a robot needs them most:

* ``theta = acos(c)`` near c = +-1 (the elbow stretched or folded, the UR wrist at
  q5 = 0): the rounding of c, about 1e-16, becomes an angle error of about
  1e-16/sin(theta); for theta = 1e-6 that is 1e-10 rad where the target fixes the angle to
  1e-16 rad.
* ``sqrt(r**2 - c**2)``: cancellation when the two squares are close (the shoulder
  singularity, targets at the edge of the workspace).

Here every angle is an ``atan2`` of a sine and a cosine that are each computed without
cancellation: differences of squares are factored, ``(r - c) (r + c)``, and the law of
cosines is replaced by the half-angle form of the exterior angle,

    tan(beta/2)^2 = (a + b - d)(a + b + d) / ((d - a + b)(d + a - b)),

where every factor is a sum or difference of the given lengths (Kahan, "Miscalculating
area and angles of a needle-like triangle", 2014).  A factor that comes out negative by no
more than rounding (a target exactly on the workspace boundary) is clamped to zero and the
result is flagged ``clamped``; a factor negative beyond that means the target is
unreachable, and the result is NaN with the flag ``unreachable`` - never a silent guess.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin.ik.rotations import cross

#: Rounding allowance, relative to the lengths involved, below which a negative factor is
#: clamped to zero (the target is on the boundary) instead of declared unreachable.
REACH_SLACK = 64.0 * np.finfo(float).eps


@dataclass(frozen=True)
class Roots:
    """Two solutions theta_plus, theta_minus of a subproblem and what happened on the way.

    Attributes:
        plus, minus: the two branches (NaN where unreachable).
        root: the non-negative square root that separates the branches (0: they coincide).
        clamped: a factor was clamped from a rounding-size negative value to zero.
        unreachable: no real solution.
    """

    plus: np.ndarray
    minus: np.ndarray
    root: np.ndarray
    clamped: np.ndarray
    unreachable: np.ndarray


#: Above this many products, :func:`dot` adds the three columns explicitly.
_EXPLICIT_SUM_SIZE = 96


def dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """u . v of 3-vectors over the last axis.

    numpy's reduction over a last axis of length 3 is several times slower on a large
    batch than adding the three columns, and the other way round on a single target (one
    call instead of five); both add in the same order, so the result is the same.
    """
    product = u * v
    if product.size <= _EXPLICIT_SUM_SIZE:
        return product.sum(-1)
    return product[..., 0] + product[..., 1] + product[..., 2]


def perpendicular(h: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The component of v perpendicular to the unit vector h."""
    return v - dot(h, v)[..., None] * h


def signed_angle(h: np.ndarray, u: np.ndarray, v: np.ndarray, xp: Any = np) -> np.ndarray:
    """Subproblem 1: the angle theta with rot(h, theta) u parallel to v in the plane normal to h,

    theta = atan2(h . (u x v), u . v)  (only the components of u, v normal to h matter).
    Returns 0 where u or v has no such component (the subproblem is degenerate there).
    """
    return xp.arctan2(dot(h, cross(u, v, xp)), dot(perpendicular(h, u), perpendicular(h, v)))


def _nonnegative(factor: np.ndarray, scale: np.ndarray, xp: Any = np) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(factor clamped at 0, clamped mask, unreachable mask) for a quantity that must be >= 0."""
    negative = factor < 0.0
    unreachable = factor < -REACH_SLACK * scale
    clamped = negative & ~unreachable
    return xp.where(negative, 0.0, factor), clamped, unreachable


def sinusoid(a: np.ndarray, b: np.ndarray, c: np.ndarray, root: np.ndarray | None = None) -> Roots:
    """Subproblem 4 (a projection): the angles theta with a cos(theta) + b sin(theta) = c.

    theta = atan2(b, a) +- atan2(sqrt(r^2 - c^2), c),  r = hypot(a, b), where the root is
    computed as sqrt((r - c)(r + c)), or taken from the caller when it can measure it
    directly without cancellation (e.g. as the norm of a cross product).
    """
    a, b, c = (np.asarray(x, dtype=float) for x in (a, b, c))  # broadcast by the arithmetic below
    r = np.hypot(a, b)
    if root is None:
        low, clamped, unreachable = _nonnegative(r - np.abs(c), r + np.abs(c))
        root = np.sqrt(low * (r + np.abs(c)))
    else:
        root = np.asarray(root, dtype=float)
        shape = np.broadcast_shapes(r.shape, c.shape, root.shape)
        clamped, unreachable = np.zeros(shape, dtype=bool), np.zeros(shape, dtype=bool)
    phi = np.arctan2(b, a)
    half = np.arctan2(root, c)
    plus = np.where(unreachable, np.nan, phi + half)
    minus = np.where(unreachable, np.nan, phi - half)
    return Roots(plus, minus, root, clamped, unreachable)


def exterior_angle(a: float | np.ndarray, b: float | np.ndarray, d: np.ndarray, xp: Any = np) -> Roots:
    """Subproblem 3 in the plane: the turn beta at the joint between links of lengths a and b
    that puts the far end at distance d from the first joint (beta = 0: stretched).

    beta = 2 atan2(sqrt((a + b - d)(a + b + d)), sqrt((d - a + b)(d + a - b))), the
    half-angle form of the law of cosines cos(beta) = (d^2 - a^2 - b^2) / (2 a b).
    ``plus`` is +beta, ``minus`` is -beta (the two elbow branches); ``xp``: the array module (numpy, or jax.numpy).
    """
    a, b, d = (xp.asarray(x, dtype=float) for x in (a, b, d))  # broadcast by the arithmetic below
    scale = a + b + d
    outer, clamped_out, unreachable_out = _nonnegative((a + b) - d, scale, xp)
    inner, clamped_in, unreachable_in = _nonnegative(d - xp.abs(a - b), scale, xp)
    beta = 2.0 * xp.arctan2(xp.sqrt(outer * (a + b + d)), xp.sqrt(inner * (d + xp.abs(a - b))))
    unreachable = unreachable_out | unreachable_in
    beta = xp.where(unreachable, np.nan, beta)
    return Roots(beta, -beta, xp.sqrt(outer * (a + b + d)), clamped_out | clamped_in, unreachable)
