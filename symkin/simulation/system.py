"""The simulated system: the mechanism, optionally held by a user, with its power balance.

State x = [q, qd, p_h, v_h, w, D] (the hand's position and velocity only with a user, the
stops' dissipated energy D only with joint stops):

* q' = qd, qd' = forward_dynamics(q, qd, tau + J_p^T F_h) (seed eqs. 8.34, 8.35), where
  F_h is the force of the user's hand on the TCP;
* w' = qd . (tau + J_p^T F_h - F_f(qd)), the power of the net joint torques.  For any
  mechanism d(k + u)/dt = qd . (M qdd + V + G) (the skew symmetry of dM/dt - 2C), and
  M qdd + V + G = tau_total - F_f, so k + u - w is constant along exact solutions: its
  drift measures the integration error (the energy balance of the tests).
* with joint stops (:mod:`symkin.simulation.stops`) the stop torque tau_s joins the
  acceleration but not w; its power is qd . tau_s = -dU/dt - D' (spring energy U, damper
  dissipation D' = sum c d'^2), so k + u + U + D - w is the constant.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from symkin.simulation.plant import Plant
from symkin.simulation.stops import JointStops
from symkin.simulation.user import MassSpringDamperUser


@dataclass(frozen=True)
class State:
    """A state vector split into its parts (arrays of shape (..., size))."""

    q: np.ndarray
    qd: np.ndarray
    hand: np.ndarray | None
    hand_velocity: np.ndarray | None
    work: np.ndarray
    dissipated: np.ndarray | None = None

    def held(self) -> tuple[np.ndarray, np.ndarray]:
        """(position, velocity) of the user's hand: states of a system with a user carry them."""
        if self.hand is None or self.hand_velocity is None:
            raise ValueError("the state carries no user's hand: the system has no user")
        return self.hand, self.hand_velocity


class ArmSystem:
    """The mechanism under joint torques tau, optionally coupled to a user's hand.

    Args:
        plant: the mechanism's dynamics.
        user: a hand model coupled to the TCP point (None: the arm alone).
        stops: spring-dampers at the joint limits (None: the limits are not enforced).
    """

    def __init__(self, plant: Plant, user: MassSpringDamperUser | None = None, stops: JointStops | None = None):
        self.plant = plant
        self.user = user
        self.stops = stops
        n = plant.dof
        self.d = len(plant.point_axes) if user is not None else 0
        self.size = 2 * n + 2 * self.d + 1 + (stops is not None)
        self._work = 2 * n + 2 * self.d

    def split(self, x: np.ndarray) -> State:
        n, d = self.plant.dof, self.d
        hand = x[..., 2 * n:2 * n + d] if d else None
        hand_velocity = x[..., 2 * n + d:2 * n + 2 * d] if d else None
        dissipated = x[..., self._work + 1] if self.stops is not None else None
        return State(x[..., :n], x[..., n:2 * n], hand, hand_velocity, x[..., self._work], dissipated)

    def initial(self, q: np.ndarray, qd: np.ndarray | None = None) -> np.ndarray:
        """The state at rest in ``q`` (or moving with ``qd``); a user's hand starts at the TCP,
        moving with it, work (and stop dissipation) zero."""
        q = np.asarray(q, dtype=float)
        qd = np.zeros(self.plant.dof) if qd is None else np.asarray(qd, dtype=float)
        parts = [q, qd]
        if self.user is not None:
            parts += [self.plant.point(q), self.plant.point_jacobian(q) @ qd]
        return np.concatenate(parts + [np.zeros(1 + (self.stops is not None))])

    def tcp_motion(self, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(p, J_p, v = J_p qd): the TCP point, its Jacobian and velocity (one fk, one Jacobian), batched over ``...``."""
        Jp = self.plant.point_jacobian(q)
        return self.plant.point(q), Jp, (Jp @ qd[..., None])[..., 0]

    def derivative(self, t: float, x: np.ndarray, tau: np.ndarray, contact: np.ndarray | None = None) -> np.ndarray:
        """dx/dt at (t, x) under joint torques ``tau`` (held by the caller).

        ``contact``: the engaged stops of a hybrid mode (see
        :meth:`JointStops.torque_and_dissipation`); None: engaged where a joint is beyond its
        limit.  Written with slices into one output array: this runs four times per RK4 step.
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
        out[self._work] = qd @ (total - plant.friction(qd))
        if self.stops is not None:
            stop, out[self._work + 1] = self.stops.torque_and_dissipation(q, qd, contact)
            total = total + stop
        out[n:2 * n] = plant.acceleration(q, qd, total)
        return out

    def stop_energy(self, s: State) -> np.ndarray:
        """U + D: energy stored in and dissipated by the stops along split states (0 without stops)."""
        if self.stops is None:
            return np.zeros(np.shape(s.work))
        return self.stops.stored_energy(s.q) + s.dissipated

    def balance(self, x: np.ndarray, energy: np.ndarray | None = None) -> np.ndarray:
        """k + u + U + D - w along states (..., size): constant for the exact solution (see the
        module docstring).  ``energy``: k + u at those states, if the caller has it already."""
        s = self.split(x)
        energy = self.plant.energy(s.q, s.qd) if energy is None else energy
        return energy + self.stop_energy(s) - s.work
