"""What force a mechanism can render from its actuators' effort limits (seed sec. 4.2, Table 8.5).

The actuator efforts that exert the task-space force F are tau = J^T F (virtual work, with
pdot = J qdot), so tau_i = J_i . F with J_i the i-th column of J.  With effort limits
|tau_i| <= tau_max,i:

* the largest force along a unit direction u is f(u) = min_i tau_max,i / |J_i . u|;
* the isotropic force, the largest force the device renders in every direction (a haptic
  device's continuous force specification), is min over u of f(u).  As
  max_u |J_i . u| = |J_i| (Cauchy-Schwarz, equality at u = J_i / |J_i|), it is
  f_iso = min_i tau_max,i / |J_i|;
* the peak force, along the best direction, is max over u of f(u) (not computed here).

f_iso vanishes where a column of J blows up (an interior singularity of a parallel
mechanism, det J_x = 0) and grows where J loses rank (a boundary singularity: the
structure carries the load), so its map shows the seed's isotropy of force beside the
1/kappa maps.  Only translational task spaces are rated (a force in N); J is the task
Jacobian of :func:`symkin.mechanism.jacobian`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np


def isotropic_force(J: np.ndarray, effort_limits: Sequence[float] | np.ndarray, xp: Any = np) -> np.ndarray:
    """f_iso = min_i tau_max,i / |J_i| over a stack of task Jacobians J (..., m, n), in N (NaN where J is); in the
    array module ``xp`` (numpy, or jax.numpy on JAX's device: :mod:`symkin.rating.on_device`)."""
    J = xp.asarray(J, dtype=float)
    limits = np.broadcast_to(np.asarray(effort_limits, dtype=float), J.shape[-1:])
    if np.any(limits <= 0):
        raise ValueError(f"effort limits must be positive, got {list(limits)}")
    with np.errstate(divide="ignore", invalid="ignore"):
        return xp.min(limits / xp.linalg.norm(J, axis=-2), axis=-1)


def axis_force(J: np.ndarray, effort_limits: Sequence[float] | np.ndarray, xp: Any = np) -> np.ndarray:
    """The largest force along each task axis e_a (..., m): :func:`directional_force` along e_1 .. e_m (a maker's
    force "along x" at a pose)."""
    J = xp.asarray(J, dtype=float)
    return xp.stack([directional_force(J, effort_limits, axis, xp) for axis in np.eye(J.shape[-2])], axis=-1)


def directional_force(J: np.ndarray, effort_limits: Sequence[float] | np.ndarray, u: np.ndarray, xp: Any = np
                      ) -> np.ndarray:
    """f(u) = min_i tau_max,i / |J_i . u|: the largest force along the unit directions u (..., m)."""
    J = xp.asarray(J, dtype=float)
    limits = np.broadcast_to(np.asarray(effort_limits, dtype=float), J.shape[-1:])
    with np.errstate(divide="ignore"):
        return xp.min(limits / xp.abs(xp.einsum("...mn,...m->...n", J, u)), axis=-1)
