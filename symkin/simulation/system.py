"""The simulated system: the mechanism, optionally held by a user, with its power balance.

State x = [q, qd, p_h, v_h, w] (the hand's position and velocity only with a user):

* q' = qd, qd' = forward_dynamics(q, qd, tau + J_p^T F_h) (seed eqs. 8.34, 8.35), where
  F_h is the force of the user's hand on the TCP;
* w' = qd . (tau + J_p^T F_h - F_f(qd)), the power of the net joint torques.  For any
  mechanism d(k + u)/dt = qd . (M qdd + V + G) (the skew symmetry of dM/dt - 2C), and
  M qdd + V + G = tau_total - F_f, so k + u - w is constant along exact solutions: its
  drift measures the integration error (the energy balance of the tests).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from symkin.simulation.plant import Plant
from symkin.simulation.user import MassSpringDamperUser


@dataclass(frozen=True)
class State:
    """A state vector split into its parts (arrays of shape (..., size))."""

    q: np.ndarray
    qd: np.ndarray
    hand: np.ndarray | None
    hand_velocity: np.ndarray | None
    work: np.ndarray


class ArmSystem:
    """The mechanism under joint torques tau, optionally coupled to a user's hand.

    Args:
        plant: the mechanism's dynamics.
        user: a hand model coupled to the TCP point (None: the arm alone).
    """

    def __init__(self, plant: Plant, user: MassSpringDamperUser | None = None):
        self.plant = plant
        self.user = user
        n = plant.dof
        self.d = len(plant.point_axes) if user is not None else 0
        self.size = 2 * n + 2 * self.d + 1

    def split(self, x: np.ndarray) -> State:
        n, d = self.plant.dof, self.d
        hand = x[..., 2 * n:2 * n + d] if d else None
        hand_velocity = x[..., 2 * n + d:2 * n + 2 * d] if d else None
        return State(x[..., :n], x[..., n:2 * n], hand, hand_velocity, x[..., -1])

    def initial(self, q: np.ndarray, qd: np.ndarray | None = None) -> np.ndarray:
        """The state at rest in ``q`` (or moving with ``qd``); a user's hand starts at the TCP,
        moving with it, work zero."""
        q = np.asarray(q, dtype=float)
        qd = np.zeros(self.plant.dof) if qd is None else np.asarray(qd, dtype=float)
        parts = [q, qd]
        if self.user is not None:
            parts += [self.plant.point(q), self.plant.point_jacobian(q) @ qd]
        return np.concatenate(parts + [np.zeros(1)])

    def tcp_motion(self, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(p, J_p, v = J_p qd): the TCP point, its Jacobian and velocity (one fk, one Jacobian)."""
        Jp = self.plant.point_jacobian(q)
        return self.plant.point(q), Jp, Jp @ qd

    def derivative(self, t: float, x: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """dx/dt at (t, x) under joint torques ``tau`` (held by the caller).

        Written with slices into one output array: this runs four times per RK4 step.
        """
        plant, n, d = self.plant, self.plant.dof, self.d
        q, qd = x[:n], x[n:2 * n]
        out = np.empty(self.size)
        out[:n] = qd
        total = tau
        if self.user is not None:
            p, Jp, v = self.tcp_motion(q, qd)
            hand, hand_velocity = x[2 * n:2 * n + d], x[2 * n + d:2 * n + 2 * d]
            force = self.user.force_on_tcp(p, v, hand, hand_velocity)
            total = tau + Jp.T @ force
            out[2 * n:2 * n + d] = hand_velocity
            out[2 * n + d:2 * n + 2 * d] = self.user.hand_acceleration(t, hand, hand_velocity, force)
        out[n:2 * n] = plant.acceleration(q, qd, total)
        out[-1] = qd @ (total - plant.friction(qd))
        return out

    def balance(self, x: np.ndarray) -> np.ndarray:
        """k + u - w along states (..., size): constant for the exact solution (see the module docstring)."""
        s = self.split(x)
        return self.plant.energy(s.q, s.qd) - s.work
