"""Reference trajectories q_r(t), qd_r(t), qdd_r(t) for trajectory following (seed Fig. 8.17).

* :class:`JointSine` - one joint moves as a sine about a fixed configuration, the others
  stand still: the seed's simplified haptic scenario (sec. 5.3, "theta1 is fixed, and the
  input to theta2 is in the form of a sine wave").
* :func:`task_circle` - a desired TCP path in Cartesian space turned into joint angles by
  inverse kinematics (the "inverse kinematics" block of Fig. 8.17): damped least squares on
  the generated functions (:func:`symkin.ik.solve_numeric`), warm-started from the previous
  sample so the branch stays continuous, then a clamped cubic spline through the joint
  samples gives qd_r and qdd_r.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from symkin.simulation.integrate import SimulationError
from symkin.errors import NotApplicable
from symkin.mechanism import POSITION_COMPONENTS


@dataclass(frozen=True)
class JointSine:
    """q_r(t) = center + e_j A sin(2 pi f t).

    Attributes:
        center: (n,) configuration about which joint ``joint`` oscillates.
        joint: index of the moving joint.
        amplitude: A (rad or m).
        frequency: f [Hz].
    """

    center: np.ndarray
    joint: int
    amplitude: float
    frequency: float

    def __call__(self, t: float | np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q_r, qd_r, qdd_r), each of shape t.shape + (n,)."""
        t = np.asarray(t, dtype=float)
        w = 2.0 * np.pi * self.frequency
        unit = np.zeros(len(self.center))
        unit[self.joint] = 1.0
        s = self.amplitude * np.sin(w * t)[..., None]
        c = self.amplitude * np.cos(w * t)[..., None]
        return self.center + s * unit, w * c * unit, -w * w * s * unit


@dataclass(frozen=True)
class SplineReference:
    """A joint trajectory through samples, as a cubic spline with zero end velocities."""

    times: np.ndarray
    q: np.ndarray

    def __post_init__(self) -> None:
        from scipy.interpolate import CubicSpline

        object.__setattr__(self, "_spline", CubicSpline(self.times, self.q, axis=0, bc_type="clamped"))

    def __call__(self, t: float | np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        t = np.clip(np.asarray(t, dtype=float), self.times[0], self.times[-1])
        spline = self._spline  # type: ignore[attr-defined]
        return spline(t), spline(t, 1), spline(t, 2)


def rest_to_rest(t: np.ndarray, duration: float) -> np.ndarray:
    """s(t) = 10 tau^3 - 15 tau^4 + 6 tau^5, tau = t / duration: 0 -> 1 with zero speed and
    acceleration at both ends."""
    tau = np.clip(np.asarray(t, dtype=float) / duration, 0.0, 1.0)
    return tau ** 3 * (10.0 - 15.0 * tau + 6.0 * tau * tau)


def task_circle(plant, q_start: np.ndarray, radius: float, duration: float, samples: int = 101) -> SplineReference:
    """The joint trajectory that moves the TCP once around a circle, rest to rest.

    The circle lies in the plane of the first two translational task axes and passes through
    the start TCP position; the orientation (pose models) stays that of ``q_start``.

    Args:
        plant: the :class:`~symkin.simulation.plant.Plant` (its model needs ``fk`` and a Jacobian).
        q_start: start configuration (n,).
        radius: circle radius [m].
        duration: time for the circle [s].
        samples: inverse-kinematics samples along the path.

    Raises:
        SimulationError: a point of the circle has no inverse-kinematics solution within the
            joint limits near the previous sample.
        NotApplicable: the handle only turns (a spherical platform).
    """
    plant.require_point()
    if plant.turning:
        raise NotApplicable(f"{plant.name}: tracking follows a TCP circle, and this device's handle only turns "
                            f"({', '.join(plant.point_axes)}): simulate haptic-wall, gravity-compensation, sine or "
                            "free-swing")
    if plant.mechanism.inverse_in_closed_form:
        return _circle_in_closed_form(plant, q_start, radius, duration, samples)
    from symkin.ik import ModelKinematics, solve_numeric

    kin = ModelKinematics(plant.model)
    kind = kin.default_kind
    q_start = np.asarray(q_start, dtype=float)
    times = np.linspace(0.0, duration, samples)
    phi = 2.0 * np.pi * rest_to_rest(times, duration)
    offsets = radius * np.stack([np.cos(phi) - 1.0, np.sin(phi)], axis=-1)
    start = kin.fk(q_start) if kind == "pose" else kin.task_coordinates(q_start)
    q = np.empty((samples, kin.dof))
    previous = q_start
    for k, (a, b) in enumerate(offsets):
        target = start.copy()
        if kind == "pose":
            target[POSITION_COMPONENTS.index(plant.point_axes[0]), 3] += a
            target[POSITION_COMPONENTS.index(plant.point_axes[1]), 3] += b
        else:
            target[plant.point_rows[0]] += a
            target[plant.point_rows[1]] += b
        result = solve_numeric(kin, target, previous, kind=kind)
        if not result.converged:
            raise SimulationError(f"{plant.name}: the circle leaves the reachable workspace at t = {times[k]:.4g} s "
                                  f"({result.reason}); choose a smaller radius or another --q0")
        q[k] = previous = result.q
    return SplineReference(times, q)


def _circle_in_closed_form(plant, q_start: np.ndarray, radius: float, duration: float, samples: int
                           ) -> SplineReference:
    """:func:`task_circle` of a plant whose joints follow from task targets in closed form
    (:meth:`~symkin.mechanism.actuated.Mechanism.joints_at`) at every sample of the circle (a hybrid device's wrist held
    at its start: the platform translates, so the TCP follows the platform's circle)."""
    q_start = np.asarray(q_start, dtype=float)
    times = np.linspace(0.0, duration, samples)
    phi = 2.0 * np.pi * rest_to_rest(times, duration)
    targets = np.tile(plant.mechanism.pose(q_start), (samples, 1))
    first, second = (plant.model.info.task_space.index(axis) for axis in plant.point_axes[:2])
    targets[:, first] += radius * (np.cos(phi) - 1.0)
    targets[:, second] += radius * np.sin(phi)
    q = plant.mechanism.joints_at(targets, q_start)
    lost = np.flatnonzero(~np.all(np.isfinite(q), axis=-1))
    if lost.size:
        raise SimulationError(f"{plant.name}: the circle leaves the reachable workspace at t = {times[lost[0]]:.4g} s; "
                              "choose a smaller radius or another --q0")
    return SplineReference(times, q)
