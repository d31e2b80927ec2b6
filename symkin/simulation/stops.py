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

from symkin.mechanism.stops import StopInequalities

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


def effective_inertia(mass: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
    """m_i = 1 / (M^-1)_ii (n,): the inertia at joint i with the other joints free; with ``rows`` (s, n), the inertia
    1 / (a^T M^-1 a) each combination a . q meets (Khatib's effective mass along a)."""
    inverse = np.linalg.inv(mass)
    if rows is None:
        return 1.0 / np.diag(inverse)
    return 1.0 / np.einsum("ri,ij,rj->r", rows, inverse, rows)


@dataclass(frozen=True)
class JointStops:
    """Unilateral spring-dampers at the joint limits and at the model's stops on combinations of joints
    (``joint_stops:``, e.g. the PHANToM's -65 deg <= q3 - q2 <= 55 deg), see the module docstring.

    Each stop r acts on its value v_r = a_r . q + b_r: the first n are the joints themselves (a_r = e_r,
    b_r = 0; -inf / inf limits and k = c = 0 where a joint declares none), the others the model's combinations.
    A stop's force along its value, f_r = -side (k d + c d'), reaches the joints as a_r f_r (virtual work).

    Attributes:
        names: each stop's name (n + s,): the joint's, or the combination as the model file writes it.
        lower, upper: (n + s,) limits of each stop's value; -inf / inf where a joint has no stop on that side.
        stiffness: (n + s,) k [N m/rad or N/m].
        damping: (n + s,) c [N m s/rad or N s/m].
        rows: (n + s, n) a_r; None: the identity (the joints' own stops only).
        offsets: (n + s,) b_r; None: zero.
    """

    names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    time_constant: float = field(default=TIME_CONSTANT, compare=False)
    damping_ratio: float = field(default=DAMPING_RATIO, compare=False)
    rows: np.ndarray | None = None
    offsets: np.ndarray | None = None

    @classmethod
    def from_plant(cls, plant, q: np.ndarray, *, time_constant: float = TIME_CONSTANT,
                   damping_ratio: float = DAMPING_RATIO, stiffness: dict[str, float] | None = None,
                   damping: dict[str, float] | None = None) -> JointStops | None:
        """Stops at the limits and the stops the model declares, parameters from M(q) (None: none declared).

        Args:
            plant: the :class:`~symkin.simulation.plant.Plant`.
            q: the configuration whose effective inertias 1 / (a^T M^-1 a) set the defaults.
            time_constant: T_c = 1 / omega_n [s].
            damping_ratio: zeta.
            stiffness, damping: per-stop values (by joint name, or a combination's text) instead of the defaults.

        Raises:
            ValueError: a parameter is not positive (zeta, c: not negative), or names a stop
                that does not exist.
        """
        if not time_constant > 0.0:
            raise ValueError(f"stop time constant must be positive, got {time_constant:g} s")
        if not damping_ratio >= 0.0:
            raise ValueError(f"stop damping ratio must not be negative, got {damping_ratio:g}")
        names = tuple(plant.coordinates)
        coupled = StopInequalities.of_model(plant.model).over(len(names))
        limits = np.vstack([plant.joint_limits, np.column_stack([coupled.lower, coupled.upper])])
        rows = np.vstack([np.eye(len(names)), coupled.rows])
        offsets = np.concatenate([np.zeros(len(names)), coupled.offsets])
        labels = names + coupled.expressions
        limited = np.isfinite(limits).any(axis=1)
        if not limited.any():
            return None
        inertia = effective_inertia(plant.mass_matrix(np.asarray(q, dtype=float)), rows)
        omega = 1.0 / time_constant
        k = np.where(limited, inertia * omega ** 2, 0.0)
        c = np.where(limited, 2.0 * damping_ratio * inertia * omega, 0.0)
        for label, values, target, strict in (("stiffness", stiffness, k, True), ("damping", damping, c, False)):
            for name, value in (values or {}).items():
                if name not in labels:
                    raise ValueError(f"stop {label}: no joint or stop '{name}'; stops: {', '.join(labels)}")
                i = labels.index(name)
                if not limited[i]:
                    raise ValueError(f"stop {label}: joint '{name}' declares no limits, so it has no stop")
                if not (value > 0.0 if strict else value >= 0.0):
                    raise ValueError(f"stop {label} of '{name}' must be {'positive' if strict else 'non-negative'}, "
                                     f"got {value:g}")
                target[i] = value
        if not len(coupled):
            return cls(names, limits[:, 0], limits[:, 1], k, c, time_constant, damping_ratio)
        return cls(labels, limits[:, 0], limits[:, 1], k, c, time_constant, damping_ratio, rows, offsets)

    @property
    def dof(self) -> int:
        """n, the joints the stops act on."""
        return len(self.names) if self.rows is None else self.rows.shape[1]

    def values(self, q: np.ndarray) -> np.ndarray:
        """Each stop's value a_r . q + b_r (..., n + s): q itself without stops on combinations."""
        return q if self.rows is None else q @ self.rows.T + self.offsets

    def penetration(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(d_lower, d_upper) = (lo - v, v - hi) of every stop's value v, (..., n + s): positive beyond the stop."""
        v = self.values(q)
        return self.lower - v, v - self.upper

    def contact(self, q: np.ndarray) -> np.ndarray:
        """Engaged side per stop (..., n + s): -1 lower, +1 upper, 0 free."""
        d_lo, d_hi = self.penetration(q)
        return np.where(d_lo > 0.0, -1, np.where(d_hi > 0.0, 1, 0))

    def depth(self, q: np.ndarray) -> np.ndarray:
        """max(0, d) per stop (..., n + s): how far beyond its limit each stop's value is."""
        d_lo, d_hi = self.penetration(q)
        return np.maximum(0.0, np.maximum(d_lo, d_hi))

    def torque_and_dissipation(self, q: np.ndarray, qd: np.ndarray,
                               contact: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(tau_stop (..., n), D' = sum c d'^2 (...,)) at states (..., n).

        ``contact``: the engaged stops (-1, 0, +1 per stop) of a hybrid mode; the spring-damper
        then acts on the engaged stops whatever the sign of d (the smooth continuation the
        event-located integrator needs).  None: engaged where d > 0.
        """
        side = self.contact(q) if contact is None else contact
        if not np.any(side):
            return np.zeros_like(q), np.zeros(np.shape(q)[:-1])
        # d = side (v - limit), d' = side a . qd; f = -side (k d + c d') along v, a f at the joints
        limit = np.where(side < 0, self.lower, np.where(side > 0, self.upper, 0.0))
        d = side * (self.values(q) - limit)
        rate = side * (qd if self.rows is None else qd @ self.rows.T)
        force = -side * (self.stiffness * d + self.damping * rate)
        return force if self.rows is None else force @ self.rows, np.sum(self.damping * rate * rate, axis=-1)

    def stored_energy(self, q: np.ndarray) -> np.ndarray:
        """U = sum 1/2 k max(0, d)^2 (...,)."""
        return 0.5 * np.sum(self.stiffness * self.depth(q) ** 2, axis=-1)

    def stop_units(self, units: tuple[Sequence[str], Sequence[str]]) -> tuple[list[str], list[str]]:
        """(position unit, effort unit) per stop from the joints' ``units``: a combination's are its first joint's
        (a stop's joints are all angles or all lengths)."""
        first = range(self.dof) if self.rows is None else np.argmax(self.rows != 0.0, axis=1)
        return [units[0][j] for j in first], [units[1][j] for j in first]

    def describe(self, units: tuple[Sequence[str], Sequence[str]]) -> list[str]:
        """Summary lines: the parameters per stop (``units``: position and effort unit per joint)."""
        lines = [f"joint stops: linear spring-damper beyond the limits, T_c = {self.time_constant * 1e3:g} ms, "
                 f"zeta = {self.damping_ratio:g} (e = {restitution(self.damping_ratio):.3g} at the start configuration, "
                 "other joints free)"]
        positions, efforts = self.stop_units(units)
        for i, name in enumerate(self.names):
            if self.stiffness[i] > 0.0:
                position, effort = positions[i], efforts[i]
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
    choices = [(lo, hi) if np.isfinite(lo) and np.isfinite(hi) else (qi,)                 # the joints' own stops
               for qi, lo, hi in zip(q, stops.lower[:stops.dof], stops.upper[:stops.dof])]
    corners = np.array(np.meshgrid(*choices, indexing="ij")).reshape(len(q), -1).T
    return np.vstack([q, corners])


def rk4_stability(stops: JointStops, masses: np.ndarray, period: float, substeps: int = 1) -> Stability:
    """Is RK4 with h = period / substeps stable in contact with every stop at once?

    The contact dynamics linearized at a configuration with mass matrix M, all stops engaged
    (K, C diagonal over the stops' values, R^T K R and R^T C R at the joints for the stops' rows R), are
    x' = A x with A = [[0, I], [-M^-1 R^T K R, -M^-1 R^T C R]]; RK4 is stable iff
    |R(h lambda)| <= 1 for every eigenvalue lambda of A, here for every M of ``masses``
    ((n, n) or (m, n, n), e.g. at :func:`stop_configurations`).  For light damping this is
    omega_max h <= 2 sqrt(2), i.e. k <= 8 m_eff / h^2.
    """
    n = stops.dof
    inverse = np.linalg.inv(np.reshape(masses, (-1, n, n)))
    A = np.zeros((len(inverse), 2 * n, 2 * n))
    A[:, :n, n:] = np.eye(n)
    if stops.rows is None:
        A[:, n:, :n] = -inverse * stops.stiffness                     # M^-1 diag(k): columns scaled
        A[:, n:, n:] = -inverse * stops.damping
    else:
        A[:, n:, :n] = -inverse @ (stops.rows.T * stops.stiffness @ stops.rows)
        A[:, n:, n:] = -inverse @ (stops.rows.T * stops.damping @ stops.rows)
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
    """An event function of :class:`ContactModes`: the penetration d of one side of one stop.

    Attributes:
        stops: the stops.
        joint: the stop's index (a joint's own stop, or after the n joints a stop on a combination).
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
        stops = self.stops
        v = stops.values(x[:stops.dof])[self.joint]
        return float(stops.lower[self.joint] - v if self.side < 0 else v - stops.upper[self.joint])


class ContactModes:
    """The hybrid modes of the stops for :func:`~symkin.simulation.integrate.run_adaptive`.

    A mode is the engaged side per stop (tuple of -1, 0, +1).  In a mode the spring-dampers
    of the engaged stops act whatever the sign of d (smooth right-hand side); a free stop's
    guards are its penetrations rising through zero, an engaged stop's guard is its
    penetration falling through zero.
    """

    def __init__(self, stops: JointStops):
        self.stops = stops

    def initial(self, x: np.ndarray) -> tuple[int, ...]:
        return tuple(int(c) for c in self.stops.contact(x[:self.stops.dof]))

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
