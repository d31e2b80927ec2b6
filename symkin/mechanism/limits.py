"""Joint coordinates against their limits (actuated joints, and passive joints of parallel legs)."""

from __future__ import annotations

from typing import Any

import numpy as np

#: Tolerance on joint limits and on the reach of a closed form (rounding of points that lie
#: exactly on the workspace boundary, e.g. the fully stretched arm).
LIMIT_TOLERANCE = 1e-9


def within_limits(q: Any, limits: Any, revolute: Any, tolerance: float = LIMIT_TOLERANCE, xp: Any = np
                  ) -> tuple[Any, Any]:
    """Joint coordinates moved into their limits where possible, and whether they are inside.

    A revolute coordinate is an angle: it is shifted by a multiple of 2 pi to the first
    representative at or above ``lower - tolerance``.

    Args:
        q: (..., n) joint coordinates.
        limits: (n, 2) [lower, upper].
        revolute: (n,) which coordinates are angles.
        xp: the array module (numpy, or jax.numpy on a JAX device with the arrays traced).

    Returns:
        (q, inside): the shifted coordinates (..., n) and a boolean (...) array.
    """
    lower, upper = limits[:, 0], limits[:, 1]
    wrapped = lower - tolerance + xp.mod(q - lower + tolerance, 2.0 * np.pi)
    q = xp.where(revolute, wrapped, q)
    inside = xp.all((q >= lower - tolerance) & (q <= upper + tolerance), axis=-1)
    return q, inside


def wrap_angle(angle: Any, xp: Any = np) -> Any:
    """Angles mapped to (-pi, pi], in the array module ``xp`` (numpy, or jax.numpy on a JAX device)."""
    wrapped = xp.remainder(xp.asarray(angle) + np.pi, 2.0 * np.pi) - np.pi
    return xp.where(wrapped == -np.pi, np.pi, wrapped)
