"""Controllers: joint torques from the state (the "control" blocks of seed Figs. 8.17, 8.18).

* :class:`ComputedTorque` - trajectory following (Fig. 8.17): the inverse dynamics of the
  reference acceleration corrected by PD terms,
  tau = ID(q, qd, qdd_r + K_d (qd_r - qd) + K_p (q_r - q)) = M v + V + G + F_f, which makes
  the error obey e'' + K_d e' + K_p e = 0 (K_p = omega^2, K_d = 2 zeta omega).
* :class:`WallRenderer` - the haptic force loop (Fig. 8.18): a virtual wall gives the
  desired force on the hand, F_d = -(k_w d + b_w d') n for a penetration d > 0 (spring and
  damper, pushing only), the force sensed at the TCP is compared with it, and
  tau = G(q) + J_p^T (F_d + K_f (F_d - F_s)) with gravity compensation and force feedback
  of gain K_f (K_f = 0: open-loop impedance rendering).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from symkin.simulation.system import ArmSystem


class ComputedTorque:
    """Computed-torque control towards ``reference(t) -> (q_r, qd_r, qdd_r)``.

    Args:
        system: the simulated system (its plant gives the inverse dynamics).
        reference: the joint reference.
        bandwidth: omega [rad/s] of the error dynamics.
        damping: zeta.
    """

    def __init__(self, system: ArmSystem, reference, bandwidth: float = 50.0, damping: float = 1.0):
        self.system = system
        self.reference = reference
        self.kp = bandwidth * bandwidth
        self.kd = 2.0 * damping * bandwidth

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        s = self.system.split(x)
        q_r, qd_r, qdd_r = self.reference(t)
        v = qdd_r + self.kd * (qd_r - s.qd) + self.kp * (q_r - s.q)
        return self.system.plant.torque(s.q, s.qd, v)


@dataclass(frozen=True)
class Wall:
    """The half-space n . p <= offset is free; beyond it the wall pushes back.

    Attributes:
        normal: unit outward normal n (d,), pointing into the wall.
        offset: n . p on the wall surface [m].
        stiffness: k_w [N/m].
        damping: b_w [N s/m].
    """

    normal: np.ndarray
    offset: float
    stiffness: float = 1000.0
    damping: float = 2.0

    def penetration(self, p: np.ndarray) -> np.ndarray:
        return np.asarray(p) @ self.normal - self.offset

    def force(self, p: np.ndarray, v: np.ndarray) -> np.ndarray:
        """F_d = -max(0, k_w d + b_w d') n inside the wall, zero outside."""
        d = self.penetration(p)
        push = np.where(d > 0.0, np.maximum(0.0, self.stiffness * d + self.damping * (np.asarray(v) @ self.normal)),
                        0.0)
        return -push[..., None] * self.normal


class WallRenderer:
    """Render ``wall`` on the user's hand through the mechanism (seed Fig. 8.18).

    Args:
        system: an :class:`ArmSystem` with a user (the force sensor reads -F_h, the force
            the TCP exerts on the hand).
        wall: the virtual wall.
        force_gain: K_f of the force feedback.
    """

    def __init__(self, system: ArmSystem, wall: Wall, force_gain: float = 0.0):
        if system.user is None:
            raise ValueError("the haptic loop needs a user model on the system")
        self.system = system
        self.user = system.user
        self.wall = wall
        self.force_gain = force_gain

    def desired_and_sensed(self, t: float | np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(F_d, F_s) at state x: wall force and the force felt by the hand (batched: x (..., state) -> (..., d))."""
        s = self.system.split(x)
        desired, sensed, _ = self._forces(s)
        return desired, sensed

    def _forces(self, s) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(F_d, F_s, J_p) at the split state ``s``: the TCP motion evaluated once."""
        p, Jp, v = self.system.tcp_motion(s.q, s.qd)
        sensed = -self.user.force_on_tcp(p, v, s.hand, s.hand_velocity)
        return self.wall.force(p, v), sensed, Jp

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        s = self.system.split(x)
        desired, sensed, Jp = self._forces(s)
        command = desired + self.force_gain * (desired - sensed)
        return self.system.plant.gravity(s.q) + Jp.T @ command
