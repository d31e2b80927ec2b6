"""What inverse kinematics asks of a model: generated functions, joint limits and the residual.

Inverse kinematics never derives anything: it evaluates the functions that ``symkin derive``
generated, through a :class:`~symkin.runtime.LoadedModel` of any backend (numpy today, C
later), so the same solver runs on whichever backend is fastest.

Two kinds of targets:

* ``pose``: a 4x4 base_T_tcp.  The residual is e = [p_t - p; log(R_t R^T)] (base frame) and
  its Jacobian is the geometric Jacobian [v; w] = J qd (``jacobian_geometric``, or
  ``jacobian`` when the model's task space is ``pose``).
* ``task``: a vector in the model's task space (``[x, y]`` for the planar arm, ``[x, y, z,
  yaw]`` for a SCARA, ``[x, y, wz]`` for a planar arm that orients its tool).  The residual
  is p_t - f(q), angle components wrapped to (-pi, pi], and its Jacobian the task Jacobian
  ``jacobian``.  f(q) comes from ``task_coordinates``, or from ``fk`` when the task space has
  only position components and angular-velocity components: x, y, z are the translation,
  wx, wy, wz the rotation vector log(R) (for a planar arm, wz is the angle about z, whose
  rate is the Jacobian's wz row).

The target kind follows the model's task space: ``pose`` for the pose task space, ``task``
otherwise; what a kind needs and the generated code lacks is named in the error.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from symkin.errors import GeneratedCodeError
from symkin.ik.rotations import log_so3, pose_error, right_jacobian_inverse
from symkin.mechanism.limits import wrap_angle
from symkin.runtime.info import GeneratedModel

POSE_TASK_SPACE = ("x", "y", "z", "wx", "wy", "wz")
POSITION_INDEX = {"x": 0, "y": 1, "z": 2}
#: angular-velocity task components: their coordinate is the rotation vector's component
ROTATION_INDEX = {"wx": 0, "wy": 1, "wz": 2}
ANGLES = ("roll", "pitch", "yaw")
TARGET_KINDS = ("pose", "task")


def _derive_hint(names: str) -> str:
    return f"derive the model with these outputs, e.g. 'symkin derive MODEL --only {names}'"


class ModelKinematics:
    """The generated functions and joint data that inverse kinematics uses.

    Args:
        model: a loaded model (``symkin.load(...)``), any backend, possibly ``bind()``-ed.
        limits: (lower, upper) per joint; default: the model's limits (``model.joint_limits``).

    Raises:
        GeneratedCodeError: ``fk`` was not generated.
    """

    def __init__(self, model: GeneratedModel, limits: Sequence[tuple[float, float]] | None = None):
        self.model = model
        functions = set(model.functions)
        if "fk" not in functions:
            raise GeneratedCodeError(f"{model.name}: inverse kinematics needs the generated 'fk'; "
                                     + _derive_hint("fk,jacobian_geometric"))
        self.name = model.name
        self.coordinates = model.info.coordinate_names
        self.revolute = np.array([c.revolute for c in model.info.coordinates])
        self.dof = len(self.coordinates)
        self.task_space = model.info.task_space
        bounds = np.array(model.joint_limits if limits is None else limits, dtype=float).reshape(self.dof, 2)
        if np.any(bounds[:, 0] > bounds[:, 1]):
            raise ValueError(f"{model.name}: a lower joint limit is above its upper limit: {bounds.tolist()}")
        self.lower, self.upper = bounds[:, 0], bounds[:, 1]
        #: revolute joints whose limits span a full turn: they pass a limit by wrapping around
        self.wraps = self.revolute & (self.upper - self.lower >= 2.0 * np.pi)
        self._pose_jacobian = ("jacobian_geometric" if "jacobian_geometric" in functions
                               else "jacobian" if self.task_space == POSE_TASK_SPACE and "jacobian" in functions
                               else None)
        self._has_task = ("task_coordinates" in functions
                          or all(c in POSITION_INDEX or c in ROTATION_INDEX for c in self.task_space)
                          ) and "jacobian" in functions

    @property
    def default_kind(self) -> str:
        """``pose`` for models whose task space is the pose, else ``task`` (the kind follows the task space)."""
        return "pose" if self.task_space == POSE_TASK_SPACE else "task"

    @property
    def has_pose_jacobian(self) -> bool:
        """Whether the geometric Jacobian (pose targets, :meth:`pose_jacobian`) was generated."""
        return self._pose_jacobian is not None

    def fk(self, q: np.ndarray) -> np.ndarray:
        return self.model.fk(q)

    def pose_jacobian(self, q: np.ndarray) -> np.ndarray:
        """Geometric Jacobian (..., 6, n), rows vx, vy, vz, wx, wy, wz (base frame)."""
        return getattr(self.model, self._require_pose())(q)

    def _require_pose(self) -> str:
        """The name of the generated geometric Jacobian, or a clear error."""
        if self._pose_jacobian is None:
            raise GeneratedCodeError(f"{self.name}: pose targets need the generated 'jacobian_geometric'; "
                                     + _derive_hint("fk,jacobian_geometric"))
        return self._pose_jacobian

    def task_coordinates(self, q: np.ndarray) -> np.ndarray:
        """Task coordinates (..., m) of the model's task space."""
        self._require_task()
        if "task_coordinates" in self.model.functions:
            return self.model.task_coordinates(q)
        T = self.model.fk(q)
        rotation = (log_so3(T[..., :3, :3]) if any(c in ROTATION_INDEX for c in self.task_space)
                    else np.empty(T.shape[:-2] + (0,)))  # no rotation component is read
        return np.stack([T[..., POSITION_INDEX[c], 3] if c in POSITION_INDEX else rotation[..., ROTATION_INDEX[c]]
                         for c in self.task_space], axis=-1)

    def task_jacobian(self, q: np.ndarray) -> np.ndarray:
        self._require_task()
        return self.model.jacobian(q)

    def _require_task(self) -> None:
        if not self._has_task:
            raise GeneratedCodeError(
                f"{self.name}: task-space targets need the generated 'jacobian' and task coordinates "
                f"(task space [{', '.join(self.task_space)}]); use pose targets, or "
                + _derive_hint("fk,jacobian,task_coordinates"))

    def project(self, q: np.ndarray) -> np.ndarray:
        """``q`` moved into the joint limits: a revolute angle outside them is first shifted by
        the multiple of 2 pi that brings it inside (the same configuration), if there is one,
        and clipped otherwise."""
        two_pi = 2.0 * np.pi
        with np.errstate(invalid="ignore"):
            turns = np.where(q < self.lower, np.ceil((self.lower - q) / two_pi),
                             np.where(q > self.upper, np.floor((self.upper - q) / two_pi), 0.0))
        shifted = q + two_pi * np.where(np.isfinite(turns), turns, 0.0)
        inside = (shifted >= self.lower) & (shifted <= self.upper)
        q = np.where(self.revolute & inside, shifted, q)
        return np.clip(q, self.lower, self.upper)

    def within_limits(self, q: np.ndarray) -> np.ndarray:
        return np.all((q >= self.lower) & (q <= self.upper), axis=-1)


@dataclass(frozen=True)
class Residual:
    """The equations f(q) = target of one target kind, for the solvers.

    Attributes:
        kind: ``pose`` or ``task``.
        names: component names of the residual.
        angular: which residual components are angles (rad), the others lengths.
    """

    kind: str
    kinematics: ModelKinematics
    names: tuple[str, ...]
    angular: np.ndarray

    def error(self, q: np.ndarray, target: np.ndarray) -> np.ndarray:
        """e(q) = target - f(q) (pose: the twist of :func:`~symkin.ik.rotations.pose_error`)."""
        if self.kind == "pose":
            return pose_error(target, self.kinematics.fk(q))
        e = target - self.kinematics.task_coordinates(q)
        return np.where(self.angular, wrap_angle(e), e)

    def jacobian(self, q: np.ndarray, e: np.ndarray) -> np.ndarray:
        """J with de/dq = -J at q, where ``e`` is the residual there (..., m, n).

        Task targets: the task Jacobian.  Pose targets: with R_e = R_t R^T = exp([e_w]) and
        dR = [w] R, dR_e = -R_e [w], so de_w = -J_r^-1(e_w) w, and J = [J_v; J_r^-1(e_w) J_w]
        (it equals the geometric Jacobian at a solution, e_w = 0).
        """
        if self.kind == "pose":
            J = np.array(self.kinematics.pose_jacobian(q), dtype=float)
            J[..., 3:, :] = right_jacobian_inverse(e[..., 3:]) @ J[..., 3:, :]
            return J
        return self.kinematics.task_jacobian(q)

    def target_shape(self) -> tuple[int, ...]:
        return (4, 4) if self.kind == "pose" else (len(self.names),)

    def length_scale(self, target: np.ndarray) -> np.ndarray:
        """max(1, |target position|): positions are compared relative to this."""
        if self.kind == "pose":
            p = target[..., :3, 3]
        else:
            p = np.where(self.angular, 0.0, target)
        return np.maximum(1.0, np.linalg.norm(p, axis=-1))

    def split_norms(self, e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(|length part|, |angle part|) of residuals e (..., m)."""
        lengths = np.linalg.norm(np.where(self.angular, 0.0, e), axis=-1)
        angles = np.linalg.norm(np.where(self.angular, e, 0.0), axis=-1)
        return lengths, angles


def residual_for(kinematics: ModelKinematics, kind: str | None = None) -> Residual:
    """The residual of ``kind`` targets (default: the model's :attr:`~ModelKinematics.default_kind`)."""
    kind = kind or kinematics.default_kind
    if kind not in TARGET_KINDS:
        raise ValueError(f"unknown target kind {kind!r}; use one of {', '.join(TARGET_KINDS)}")
    if kind == "pose":
        kinematics._require_pose()
        return Residual("pose", kinematics, POSE_TASK_SPACE[:3] + ("rx", "ry", "rz"),
                        np.array([False, False, False, True, True, True]))
    kinematics._require_task()
    angular = np.array([c in ANGLES or c in ROTATION_INDEX for c in kinematics.task_space])
    return Residual("task", kinematics, kinematics.task_space, angular)


def as_target(residual: Residual, target: np.ndarray | Sequence) -> np.ndarray:
    """``target`` as a float array of shape (..., *target_shape), or a clear error."""
    array = np.asarray(target, dtype=float)
    shape = residual.target_shape()
    if array.shape[array.ndim - len(shape):] != shape or array.ndim < len(shape):
        raise ValueError(f"{residual.kinematics.name}: a {residual.kind} target has shape (..., "
                         f"{', '.join(map(str, shape))}), got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{residual.kinematics.name}: the target has non-finite values")
    return array
