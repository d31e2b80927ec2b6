"""The user of a haptic device as a mass-spring-damper (seed sec. 5, Fig. 8.18).

The seed: "the simplest model of the user is a mass-spring-damper system".  Here the hand
is a point mass m_h at p_h, pulled towards the user's intended position r(t) by the arm's
impedance (k_a, b_a) and holding the handle through the grip (k_g, b_g):

    F_h = k_g (p_h - p) + b_g (v_h - v)                          force of the hand on the TCP
    m_h a_h = k_a (r(t) - p_h) + b_a (r'(t) - v_h) - F_h

with p, v the TCP position and velocity.  A compliant grip keeps the hand a state of its
own, so no algebraic loop arises between the hand's and the mechanism's accelerations.
Typical values for a hand holding a stylus (Hogan 1989; Colgate and Brown 1994): a few
hundred grams, arm stiffness of some hundred N/m, a stiff grip.

A handle that only turns (a spherical platform, the Agile Eye) is held by its angles p = (roll,
pitch, yaw): the same equations in those coordinates, with the hand's inertia [kg m^2], the
wrist's torsional stiffness and damping [N m/rad, N m s/rad] and a torsional grip, and F_h the
generalized force conjugate to the angles (N m).  About the home orientation, where
omega = pd, it is a rotor on a torsional spring; farther out it is the same mechanical system
written in the angles (its power balance stays exact).  Values (:data:`TURNING`): a hand of
0.4 kg whose centre of mass lies some 5 cm from the axis (1e-3 kg m^2), the passive stiffness
of the wrist, about 1.5 N m/rad with 0.03 N m s/rad (Formica, Charles, Zhao, Hogan, The passive
stiffness of the wrist and forearm, J. Neurophysiology 108, 2012), a grip ten times stiffer.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: r(t) -> (position (d,), velocity (d,)) the user intends
Intent = Callable[[float], tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class MassSpringDamperUser:
    """Hand mass m_h [kg], arm impedance k_a [N/m], b_a [N s/m] towards ``intent``, grip k_g, b_g."""

    intent: Intent
    mass: float = 0.2
    arm_stiffness: float = 200.0
    arm_damping: float = 5.0
    grip_stiffness: float = 2000.0
    grip_damping: float = 10.0

    def force_on_tcp(self, p: np.ndarray, v: np.ndarray, hand: np.ndarray, hand_velocity: np.ndarray) -> np.ndarray:
        """F_h = k_g (p_h - p) + b_g (v_h - v)."""
        return self.grip_stiffness * (hand - p) + self.grip_damping * (hand_velocity - v)

    def hand_acceleration(self, t: float, hand: np.ndarray, hand_velocity: np.ndarray,
                          force: np.ndarray) -> np.ndarray:
        """a_h = (k_a (r - p_h) + b_a (r' - v_h) - F_h) / m_h."""
        r, rd = self.intent(t)
        return (self.arm_stiffness * (r - hand) + self.arm_damping * (rd - hand_velocity) - force) / self.mass


def sine_intent(center: np.ndarray, direction: np.ndarray, amplitude: float, frequency: float) -> Intent:
    """r(t) = center + amplitude sin(2 pi f t) direction (a user pushing back and forth)."""
    center, direction = np.asarray(center, float), np.asarray(direction, float)
    w = 2.0 * np.pi * frequency

    def intent(t: float) -> tuple[np.ndarray, np.ndarray]:
        return center + amplitude * np.sin(w * t) * direction, amplitude * w * np.cos(w * t) * direction

    return intent


@dataclass(frozen=True)
class HapticDefaults:
    """The default wall and user of the haptic scenarios for a kind of handle (units of its coordinates).

    Attributes:
        wall: distance of the wall from the start, along the first handle coordinate (m or rad).
        push: how far the hand intends to move (m or rad).
        wall_stiffness, wall_damping: k_w, b_w (N/m and N s/m, or N m/rad and N m s/rad).
        hand: :class:`MassSpringDamperUser` parameters instead of its translational defaults.
    """

    wall: float
    push: float
    wall_stiffness: float
    wall_damping: float
    hand: dict[str, float]


#: A handle that translates (a TCP point): the user's defaults above, a 1000 N/m wall 1 cm away.
TRANSLATING = HapticDefaults(0.01, 0.02, 1000.0, 2.0, {})
#: A handle that only turns (see the module docstring): a 2 N m/rad wall 0.1 rad away, passive at 1 kHz
#: (Colgate and Brown: 2 b_w / T = 20 N m/rad).
TURNING = HapticDefaults(0.1, 0.2, 2.0, 0.01, {"mass": 1e-3, "arm_stiffness": 1.5, "arm_damping": 0.03,
                                               "grip_stiffness": 15.0, "grip_damping": 0.1})
