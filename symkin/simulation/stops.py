"""Mechanical joint stops: a unilateral linear spring-damper beyond each declared joint limit.

For a joint q with limits [q_lo, q_hi] the penetration is d = q_lo - q below the lower stop
and d = q - q_hi above the upper one, and while d > 0 the stop applies the torque (force)

    tau_stop = +-(k d + c d')         (pushing back into the range; d' = -qd or +qd)

and nothing while the joint is inside its limits.  This is the linear (Kelvin-Voigt)
contact model with the damper acting only while penetrating (Gilardi and Sharf, "Literature
survey of contact dynamics modelling", Mech. Mach. Theory 37 (2002) 1213-1239, sec. 3.1).
It was chosen over Hunt-Crossley's k d^n + lambda d^n d' (Hunt and Crossley, J. Appl. Mech.
42 (1975) 440-445) because its impact is a linear oscillator with constant parameters:

* for an effective inertia m, omega_n = sqrt(k / m), zeta = c / (2 sqrt(k m)); the contact
  lasts half a damped period pi / omega_d (omega_d = omega_n sqrt(1 - zeta^2)), the
  coefficient of restitution is e = exp(-zeta pi / sqrt(1 - zeta^2)) whatever the impact
  velocity, and the peak penetration is
  (v / omega_n) exp(-zeta / sqrt(1 - zeta^2) atan(sqrt(1 - zeta^2) / zeta));
* the stability of a fixed-step integrator is a condition on the eigenvalues of the
  linearized contact dynamics, exact for this model (:func:`rk4_stability`);
* the parameters follow from a chosen contact time constant and damping ratio.

Its known price (Gilardi and Sharf): the damper force c |d'| appears as a step at impact,
and near separation k d + c d' < 0 (the stop pulls slightly); the step is located exactly
by the event detection of the adaptive integrator (:class:`ContactModes`).

Energy: the spring stores U = sum 1/2 k d^2 over the engaged stops and the damper dissipates
D' = sum c d'^2, so the stop power is qd . tau_stop = -dU/dt - D' and
k + u + U + D - w is constant (:meth:`ArmSystem.balance`).

Defaults from the model: k_i = m_i omega_n^2 and c_i = 2 zeta m_i omega_n, with
m_i = 1 / (M^-1)_ii at a configuration q: the inertia joint i's stop meets when the other joints
are free (unactuated or backdrivable, as in a haptic device; with the others locked it would be
M_ii >= m_i).  omega_n = 1 / T_c for a contact time constant T_c (default 3 ms), zeta = 0.5
(e = 0.16).  M changes with the configuration, so an impact elsewhere has
omega = sqrt(k / m_i(q_contact)) and zeta = c / (2 sqrt(k m_i(q_contact))); the tests check the
closed forms with these.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

#: default contact time constant T_c = 1 / omega_n [s] and damping ratio zeta
TIME_CONSTANT = 3e-3
DAMPING_RATIO = 0.5
#: RK4's stability limit on the imaginary axis: |h omega| <= 2 sqrt(2)
RK4_IMAGINARY_LIMIT = 2.0 * math.sqrt(2.0)
#: omega_max h up to which RK4 resolves a contact (about 12 steps per undamped period; measured
#: on planar_2r falling onto both stops: energy balance error 0.34 % of the energy at 0.45,
#: 28 % at 1.33, see docs/simulation.md)
RK4_RESOLVED = 0.5


def restitution(damping_ratio: float) -> float:
    """e = exp(-zeta pi / sqrt(1 - zeta^2)) of the linear spring-damper (0 from zeta >= 1)."""
    if damping_ratio >= 1.0:
        return 0.0
    return math.exp(-damping_ratio * math.pi / math.sqrt(1.0 - damping_ratio ** 2))


def peak_penetration(velocity: float, omega: float, damping_ratio: float) -> float:
    """Peak of d'' + 2 zeta omega d' + omega^2 d = 0 from d(0) = 0, d'(0) = v (0 <= zeta < 1)."""
    root = math.sqrt(1.0 - damping_ratio ** 2)
    return velocity / omega * math.exp(-damping_ratio / root * math.atan2(root, damping_ratio))


def effective_inertia(mass: np.ndarray) -> np.ndarray:
    """m_i = 1 / (M^-1)_ii (n,): the inertia at joint i with the other joints free."""
    return 1.0 / np.diag(np.linalg.inv(mass))


@dataclass(frozen=True)
class JointStops:
    """Unilateral spring-dampers at the joint limits (see the module docstring).

    Attributes:
        names: the joint names (n,).
        lower, upper: (n,) limits; -inf / inf where a joint has no stop on that side.
        stiffness: (n,) k [N m/rad or N/m].
        damping: (n,) c [N m s/rad or N s/m].
    """

    names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    time_constant: float = field(default=TIME_CONSTANT, compare=False)
    damping_ratio: float = field(default=DAMPING_RATIO, compare=False)

    @classmethod
    def from_plant(cls, plant, q: np.ndarray, *, time_constant: float = TIME_CONSTANT,
                   damping_ratio: float = DAMPING_RATIO, stiffness: dict[str, float] | None = None,
                   damping: dict[str, float] | None = None) -> JointStops | None:
        """Stops at the limits the model declares, parameters from M(q) (None: no limits declared).

        Args:
            plant: the :class:`~symkin.simulation.plant.Plant`.
            q: the configuration whose effective inertias 1 / (M^-1)_ii set the defaults.
            time_constant: T_c = 1 / omega_n [s].
            damping_ratio: zeta.
            stiffness, damping: per-joint values (by name) instead of the defaults.

        Raises:
            ValueError: a parameter is not positive (zeta, c: not negative), or names a joint
                that does not exist or has no limits.
        """
        if not time_constant > 0.0:
            raise ValueError(f"stop time constant must be positive, got {time_constant:g} s")
        if not damping_ratio >= 0.0:
            raise ValueError(f"stop damping ratio must not be negative, got {damping_ratio:g}")
        limits = plant.joint_limits
        limited = np.isfinite(limits).any(axis=1)
        if not limited.any():
            return None
        names = tuple(plant.coordinates)
        inertia = effective_inertia(plant.mass_matrix(np.asarray(q, dtype=float)))
        omega = 1.0 / time_constant
        k = np.where(limited, inertia * omega ** 2, 0.0)
        c = np.where(limited, 2.0 * damping_ratio * inertia * omega, 0.0)
        for label, values, target, strict in (("stiffness", stiffness, k, True), ("damping", damping, c, False)):
            for name, value in (values or {}).items():
                if name not in names:
                    raise ValueError(f"stop {label}: no joint '{name}'; joints: {', '.join(names)}")
                i = names.index(name)
                if not limited[i]:
                    raise ValueError(f"stop {label}: joint '{name}' declares no limits, so it has no stop")
                if not (value > 0.0 if strict else value >= 0.0):
                    raise ValueError(f"stop {label} of '{name}' must be {'positive' if strict else 'non-negative'}, "
                                     f"got {value:g}")
                target[i] = value
        return cls(names, limits[:, 0], limits[:, 1], k, c, time_constant, damping_ratio)

    def penetration(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(d_lower, d_upper) = (q_lo - q, q - q_hi), (..., n): positive beyond the stop."""
        return self.lower - q, q - self.upper

    def contact(self, q: np.ndarray) -> np.ndarray:
        """Engaged stop per joint (..., n): -1 lower, +1 upper, 0 free."""
        d_lo, d_hi = self.penetration(q)
        return np.where(d_lo > 0.0, -1, np.where(d_hi > 0.0, 1, 0))

    def depth(self, q: np.ndarray) -> np.ndarray:
        """max(0, d) per joint (..., n): how far beyond its limit each joint is."""
        d_lo, d_hi = self.penetration(q)
        return np.maximum(0.0, np.maximum(d_lo, d_hi))

    def torque_and_dissipation(self, q: np.ndarray, qd: np.ndarray,
                               contact: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(tau_stop (..., n), D' = sum c d'^2 (...,)) at states (..., n).

        ``contact``: the engaged stops (-1, 0, +1 per joint) of a hybrid mode; the spring-damper
        then acts on the engaged joints whatever the sign of d (the smooth continuation the
        event-located integrator needs).  None: engaged where d > 0.
        """
        side = self.contact(q) if contact is None else contact
        if not np.any(side):
            return np.zeros_like(q), np.zeros(np.shape(q)[:-1])
        # d = side (q - limit), d' = side qd; tau = -side (k d + c d')
        limit = np.where(side < 0, self.lower, np.where(side > 0, self.upper, 0.0))
        d = side * (q - limit)
        rate = side * qd
        tau = -side * (self.stiffness * d + self.damping * rate)
        return tau, np.sum(self.damping * rate * rate, axis=-1)

    def stored_energy(self, q: np.ndarray) -> np.ndarray:
        """U = sum 1/2 k max(0, d)^2 (...,)."""
        return 0.5 * np.sum(self.stiffness * self.depth(q) ** 2, axis=-1)

    def describe(self, units: tuple[Sequence[str], Sequence[str]]) -> list[str]:
        """Summary lines: the parameters per stopped joint (``units``: position and effort unit per joint)."""
        lines = [f"joint stops: linear spring-damper beyond the limits, T_c = {self.time_constant * 1e3:g} ms, "
                 f"zeta = {self.damping_ratio:g} (e = {restitution(self.damping_ratio):.3g} at the start configuration, "
                 "other joints free)"]
        for i, name in enumerate(self.names):
            if self.stiffness[i] > 0.0:
                position, effort = units[0][i], units[1][i]
                lines.append(f"  {name}: [{self.lower[i]:.4g}, {self.upper[i]:.4g}] {position}, k = "
                             f"{self.stiffness[i]:.4g} {effort}/{position}, c = {self.damping[i]:.4g} "
                             f"{effort} s/{position}")
        return lines


def rk4_amplification(z: np.ndarray) -> np.ndarray:
    """|R(z)| of classic RK4, R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24: stable where <= 1."""
    return np.abs(1.0 + z * (1.0 + z * (0.5 + z * (1.0 / 6.0 + z / 24.0))))


@dataclass(frozen=True)
class Stability:
    """The stops' linearized contact dynamics against a fixed step h.

    Attributes:
        eigenvalues: of [[0, I], [-M^-1 K, -M^-1 C]] with every stop engaged [1/s].
        omega_max: the largest |lambda| [rad/s].
        step: h [s].
        stable: h lambda inside RK4's stability region for every eigenvalue.
        substeps_needed: the fewest RK4 steps per period that are stable.
        substeps_resolved: the fewest with omega_max h <= :data:`RK4_RESOLVED`.
    """

    eigenvalues: np.ndarray
    omega_max: float
    step: float
    stable: bool
    substeps_needed: int
    substeps_resolved: int

    def describe(self) -> str:
        """One summary line."""
        return (f"RK4 step h = {self.step * 1e3:.4g} ms in contact: omega_max h = {self.omega_max * self.step:.3g} "
                f"({'stable' if self.stable else 'UNSTABLE'}: |R(h lambda)| <= 1 needs --substeps >= "
                f"{self.substeps_needed}; contacts resolved (omega_max h <= {RK4_RESOLVED:g}) from --substeps "
                f"{self.substeps_resolved})")


def stop_configurations(stops: JointStops, q: np.ndarray) -> np.ndarray:
    """(m, n): ``q`` and every corner of the limits (joints without stops keep their value in q),
    where the stops engage: the configurations :func:`rk4_stability` is checked at."""
    q = np.asarray(q, dtype=float)
    choices = [(lo, hi) if np.isfinite(lo) and np.isfinite(hi) else (qi,)
               for qi, lo, hi in zip(q, stops.lower, stops.upper)]
    corners = np.array(np.meshgrid(*choices, indexing="ij")).reshape(len(q), -1).T
    return np.vstack([q, corners])


def rk4_stability(stops: JointStops, masses: np.ndarray, period: float, substeps: int = 1) -> Stability:
    """Is RK4 with h = period / substeps stable in contact with every stop at once?

    The contact dynamics linearized at a configuration with mass matrix M, all stops engaged
    (K, C diagonal), are x' = A x with A = [[0, I], [-M^-1 K, -M^-1 C]]; RK4 is stable iff
    |R(h lambda)| <= 1 for every eigenvalue lambda of A, here for every M of ``masses``
    ((n, n) or (m, n, n), e.g. at :func:`stop_configurations`).  For light damping this is
    omega_max h <= 2 sqrt(2), i.e. k <= 8 m_eff / h^2.
    """
    n = len(stops.names)
    inverse = np.linalg.inv(np.reshape(masses, (-1, n, n)))
    A = np.zeros((len(inverse), 2 * n, 2 * n))
    A[:, :n, n:] = np.eye(n)
    A[:, n:, :n] = -inverse * stops.stiffness                     # M^-1 diag(k): columns scaled
    A[:, n:, n:] = -inverse * stops.damping
    lam = np.linalg.eigvals(A).ravel()
    h = period / substeps

    def ok(step: float) -> bool:
        return bool(np.all(rk4_amplification(step * lam) <= 1.0 + 1e-12))

    needed = substeps
    if not ok(h):
        needed = max(substeps, int(math.ceil(period * float(np.max(np.abs(lam))) / RK4_IMAGINARY_LIMIT)))
        while not ok(period / needed):
            needed += 1
    else:
        while needed > 1 and ok(period / (needed - 1)):
            needed -= 1
    omega = float(np.max(np.abs(lam)))
    return Stability(lam, omega, h, ok(h), needed, max(1, int(math.ceil(period * omega / RK4_RESOLVED))))


@dataclass(frozen=True)
class Guard:
    """An event function of :class:`ContactModes`: the penetration d of one stop of one joint.

    Attributes:
        stops: the stops.
        joint: the joint index.
        side: -1 lower stop, +1 upper stop.
        entering: True: d rises through 0 (contact); False: d falls through 0 (release).
    """

    stops: JointStops
    joint: int
    side: int
    entering: bool
    terminal = True

    @property
    def direction(self) -> float:
        return 1.0 if self.entering else -1.0

    def __call__(self, t: float, x: np.ndarray) -> float:
        q = x[self.joint]
        return float(self.stops.lower[self.joint] - q if self.side < 0 else q - self.stops.upper[self.joint])


class ContactModes:
    """The hybrid modes of the stops for :func:`~symkin.simulation.integrate.run_adaptive`.

    A mode is the engaged stop per joint (tuple of -1, 0, +1).  In a mode the spring-dampers
    of the engaged stops act whatever the sign of d (smooth right-hand side); a free joint's
    guards are its penetrations rising through zero, an engaged joint's guard is its
    penetration falling through zero.
    """

    def __init__(self, stops: JointStops):
        self.stops = stops

    def initial(self, x: np.ndarray) -> tuple[int, ...]:
        return tuple(int(c) for c in self.stops.contact(x[:len(self.stops.names)]))

    def argument(self, mode: tuple[int, ...]) -> np.ndarray:
        return np.array(mode, dtype=float)

    def guards(self, mode: tuple[int, ...]) -> list[Guard]:
        guards = []
        for i, side in enumerate(mode):
            if side:
                guards.append(Guard(self.stops, i, side, False))
                continue
            if np.isfinite(self.stops.lower[i]):
                guards.append(Guard(self.stops, i, -1, True))
            if np.isfinite(self.stops.upper[i]):
                guards.append(Guard(self.stops, i, 1, True))
        return guards

    def switch(self, mode: tuple[int, ...], guard: Guard) -> tuple[int, ...]:
        new = list(mode)
        new[guard.joint] = guard.side if guard.entering else 0
        return tuple(new)
