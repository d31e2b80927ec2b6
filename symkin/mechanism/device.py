"""A hybrid device (a parallel platform carrying a wrist) seen by the analyses as one mechanism in all its
actuated coordinates z = (q, qw): the legs' actuators, then the wrist's joints.

:class:`WholeDevice` is a view of the loaded model (as :class:`symkin.mechanism.reach.ConstantOrientation`
is of a pose platform): its joints are z within the legs' and the wrist's limits, its TCP the wrist's
(``device_fk(fk(q), qw)``), its task Jacobian the actuator Jacobian J_a = [J_c,p J, J_c,w]
(``device_actuator_jacobian``: the TCP's velocity and angular velocity, 6 x n).  So the serial analyses
(``symkin workspace``, ``symkin gci``, ``symkin rate``) cover the combined workspace: the grip point's reachable positions,
and 1/kappa of J_a homogenized by a characteristic length (its rows mix m/rad and rad/rad), weighted by
|det J_a| (the pose workspace's measure) where the device is square.  Where the legs do not assemble or
leave the working mode of the platform (:func:`symkin.mechanism.working_mode.working_mode`) the TCP is NaN and
J_a zero: such configurations weigh nothing and are no workspace.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from symkin.manifest_schema import Coordinate, Function, Input
from symkin.mechanism.working_mode import working_mode
from symkin.runtime.info import GeneratedModel

#: The device's task coordinates: the TCP's velocity and angular velocity (rows of device_actuator_jacobian).
DEVICE_TASK_SPACE = ("x", "y", "z", "wx", "wy", "wz")
#: The generated functions the view evaluates.
DEVICE_FUNCTIONS = ("fk", "ik", "device_fk", "device_actuator_jacobian")
#: The device's dynamics in (q, p, qw), offered in z where generated.
DEVICE_DYNAMICS = ("mass_matrix", "gravity_vector")


def _in_device_coordinates(record: Function, coordinates: tuple[Coordinate, ...]) -> Function:
    """The manifest record of a function the view evaluates: one vector input q, the device's joints z = (q, qw)
    (what :func:`symkin.mechanism.call` feeds it), then the model function's parameters."""
    z = Input("q", "vector", (len(coordinates),), tuple(c.name for c in coordinates),
              tuple("rad" if c.revolute else "m" for c in coordinates), "the device's joints z = (q, qw)")
    return dataclasses.replace(record, inputs=(z,) + record.parameter_inputs)


class WholeDevice:
    """A hybrid device as one mechanism in z = (q, qw) (see the module docstring); its ``info.mechanism`` is
    ``hybrid``: not parallel for the analyses (no platform pose to supply), and no serial chain for the
    closed-form inverse kinematics of :mod:`symkin.ik`.

    Every other attribute (``name``, ``parameters``, generated functions) is the model's; ``bind`` binds the model.

    Raises:
        ValueError: the model carries no wrist, or lacks a function of :data:`DEVICE_FUNCTIONS`.
    """

    model: GeneratedModel

    def __init__(self, model: GeneratedModel) -> None:
        if isinstance(model, WholeDevice):
            model = model.model
        if not model.info.wrist:
            raise ValueError(f"{model.name}: --device analyses a parallel platform carrying a wrist (a hybrid "
                             "device); this model has no wrist")
        missing = [f for f in DEVICE_FUNCTIONS if f not in model.functions]
        if missing:
            raise ValueError(f"{model.name}: the whole device's analyses need the generated {', '.join(missing)} "
                             "(add them to the scene outputs and derive again)")
        self.model = model
        self.legs = len(model.info.coordinates)
        #: the dynamics the view evaluates in z where the model has them (symkin rate's apparent mass at the grip)
        self.functions = ("fk", "jacobian") + tuple(f for f in DEVICE_DYNAMICS if f in model.functions)
        coordinates = model.info.coordinates + model.info.wrist
        self.info = dataclasses.replace(model.info, mechanism="hybrid", coordinates=coordinates,
                                        task_space=DEVICE_TASK_SPACE, wrist=(), home=None, passive_limits=(),
                                        functions={**model.info.functions,
                                                   **{name: _in_device_coordinates(model.info.functions[name],
                                                                                   coordinates)
                                                      for name in self.functions if name in model.info.functions}})

    def __getattr__(self, name: str) -> Any:  # the model's name, parameters, generated functions
        if name == "model":  # not yet set (copy, pickle): no recursion
            raise AttributeError(name)
        return getattr(self.model, name)

    def __repr__(self) -> str:
        return f"<the whole device {self.model!r} in (q, qw)>"

    @property
    def joint_limits(self) -> tuple[tuple[float, float], ...]:
        """The legs' then the wrist's (lower, upper) limits ((-inf, inf) where none are declared)."""
        return tuple(c.bounds for c in self.info.coordinates)

    def bind(self, **parameters: float) -> WholeDevice:
        return WholeDevice(self.model.bind(**parameters))

    def _platform(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(q, p, qw, inside): the legs' joints, the platform pose fk(q) (0 where it does not assemble), the
        wrist's joints and the working-mode mask."""
        z = np.asarray(z, dtype=np.float64)
        q, qw = z[..., :self.legs], z[..., self.legs:]
        p, inside = working_mode(self.model, q)
        return q, np.where(np.isfinite(p), p, 0.0), qw, inside

    def fk(self, z: np.ndarray) -> np.ndarray:
        """base_T_tcp (..., 4, 4) of the wrist's TCP; NaN outside the platform's working mode."""
        _, p, qw, inside = self._platform(z)
        return np.where(inside[..., None, None], self.model.device_fk(p, qw), np.nan)

    def mass_matrix(self, z: np.ndarray) -> np.ndarray:
        """M(z) (..., n, n) of the whole device (legs, then wrist: symkin.parallel.dynamics); NaN outside the
        platform's working mode."""
        q, p, qw, inside = self._platform(z)
        return np.where(inside[..., None, None], self.model.mass_matrix(q, p, qw), np.nan)

    def gravity_vector(self, z: np.ndarray) -> np.ndarray:
        """G(z) (..., n): the actuator efforts that hold the device; NaN outside the platform's working mode."""
        q, p, qw, inside = self._platform(z)
        return np.where(inside[..., None], self.model.gravity_vector(q, p, qw), np.nan)

    def jacobian(self, z: np.ndarray) -> np.ndarray:
        """J_a (..., 6, n): [v; w] = J_a zd; zero outside the platform's working mode."""
        q, p, qw, inside = self._platform(z)
        return np.where(inside[..., None, None], self.model.device_actuator_jacobian(q, p, qw), 0.0)
