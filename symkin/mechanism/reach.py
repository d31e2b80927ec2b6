"""What a mechanism's handle reaches, as every Cartesian analysis asks it: the box around the workspace
(:func:`bounding_box`), reachability through closed-form inverse kinematics, the characteristic length
(:func:`characteristic_length_of`) and the integration domain in words (:func:`domain_description`), each answered
here for every kind of mechanism so that the analyses do not tell kinds apart (issue 62).

An open chain's box is the TCP positions of a joint grid padded by a Jacobian bound.  A parallel mechanism's
generated functions differ from a serial arm's (see README): ``fk(q)`` returns ``position`` and ``margin`` (NaN
where the legs cannot be assembled),
``ik(p)`` returns ``joints`` and per-leg ``margin`` (NaN where p is out of reach) and the
velocity functions take both ``q`` and ``p``: ``jacobian(q, p)`` is J = J_x^-1 J_q
(seed eq. 8.29).

**Working mode** (:mod:`symkin.mechanism.working_mode` tells it for configurations).  Both closed forms choose
one of two roots: ``ik`` the branch of each
leg (the DELTA's knee outwards), ``fk`` the assembly (the DELTA's TCP below its elbows).
The workspace analysed here is the set of TCP positions reachable *in the model's
declared working mode* (``ik_branch`` and ``fk_branch`` of the model file): p with
q = ik(p) within the joint limits and fk(q) = p; in joint space, q within the limits with
ik(fk(q)) = q.  On that set q <-> p is one-to-one, so the joint domain (dW = |det J| dq)
and the Cartesian domain (dW = 1_W(p) dp) of :mod:`symkin.analysis.global_indices`
integrate over the same workspace and give the same GCI (tested).  Configurations of
another working mode (e.g. a DELTA leg with its knee inwards, reached from the box of
actuator angles through a leg singularity det J_q = 0) are outside; at that boundary
|det J| = |det J_q| / |det J_x| vanishes, so the joint-domain integrand stays continuous.

**Passive-joint limits** (``limits`` on leg joints, recorded in the manifest) are part of
the working mode: a configuration or point counts only if its passive joint variables,
found from the generated loop closure on the home assembly's branch, are within them
(:mod:`symkin.mechanism.passive`; unresolved poses count as unreachable, with a warning).

**Pose platforms** (task space x, y, z, roll, pitch, yaw: the Stewart-Gough platform) have
no closed-form fk and no ``jacobian``, only ``inverse_jacobian``.  They are analysed at a
constant orientation (:class:`ConstantOrientation`, Gosselin's constant-orientation
workspace): platform centres p (3 coordinates) in, leg lengths out, the pose in the
assembly mode of the home pose (sign of det J^-1), the 6 x 6 twist Jacobian for the
conditioning (homogenized by a characteristic length, :func:`platform_characteristic_length`), and
the Cartesian domain only.

Length: the two adapters of parallel mechanisms to the analyses (working mode, constant
orientation) share their Jacobian and reachability helpers, and the three questions every analysis asks of a
mechanism (its box, its characteristic length, its domain) branch on them; the passive-joint closure is already
its own module (:mod:`symkin.mechanism.passive`).
"""

from __future__ import annotations

from dataclasses import dataclass
from collections.abc import Sequence
from typing import Any

import numpy as np

from symkin.numerics import conditioning, sampling
from symkin import mechanism
from symkin.mechanism import passive
from symkin.mechanism.feasibility import feasible_configurations
from symkin.mechanism.stops import StopInequalities
from symkin.errors import NotApplicable
from symkin.mechanism import Limits
from symkin.mechanism.working_mode import require_functions, working_mode
from symkin.runtime.info import GeneratedModel

#: Largest |fk(ik(p)) - p| relative to the size of the mechanism (metres).
POSITION_ROUND_TRIP_TOLERANCE = 1e-6


class _GeneratedInverse:
    """The generated closed-form ``ik`` as an :class:`~symkin.mechanism.feasibility.InverseKinematics`, one branch.

    A point is valid where every leg reaches it (finite ``ik``), the solution is in the
    working mode (:meth:`in_mode`, on the finite solutions) and the declared passive-joint
    limits hold.  Subclasses have the fields ``model`` and ``passive_limits``.
    """

    dimension: int = 3
    branches: int = 1
    model: Any  # the subclasses' fields
    passive_limits: passive.PassiveLimits | None

    def in_mode(self, q: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Boolean (N,): the solutions q (N, n) of points (N, 3) are in the working mode."""
        raise NotImplementedError

    def poses(self, points: np.ndarray) -> tuple[Any, np.ndarray]:
        """The loaded model whose ``closure`` gives the passive variables, and the task coordinates of points."""
        return self.model, points

    def solve(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        points = np.asarray(points, dtype=np.float64)
        with np.errstate(invalid="ignore"):  # NaN where out of reach, as documented
            q = self.model.ik(points).joints
        finite = np.isfinite(q).all(axis=-1)
        valid = np.zeros(len(points), dtype=bool)
        if finite.any():
            valid[finite] = self.in_mode(q[finite], points[finite])
        if self.passive_limits is not None:
            model, task = self.poses(points)
            valid = passive.admissible(model, self.passive_limits, q, task, valid)
        return q[:, None, :], valid[:, None]


@dataclass(frozen=True)
class WorkingModeInverse(_GeneratedInverse):
    """The generated closed-form ``ik`` as an :class:`~symkin.mechanism.feasibility.InverseKinematics`.

    One branch (the model's working mode): a point is valid where every leg reaches it
    (margin >= 0), the forward kinematics of the solution returns to it and the passive
    joint variables are within their declared limits.

    Attributes:
        model: the loaded parallel model (with ``ik`` and ``fk``).
        size: a length of the mechanism (m) that scales the round-trip tolerance.
        passive_limits: the declared passive-joint limits, None if there are none.
        dimension: the number of task coordinates, all positions.
    """

    model: GeneratedModel
    size: float
    passive_limits: passive.PassiveLimits | None = None
    #: the platform's coordinates (3 for a translational platform, 2 for a planar point such as a pantograph's)
    dimension: int = 3

    def in_mode(self, q: np.ndarray, points: np.ndarray) -> np.ndarray:
        """fk(q) returns to the point (the fk branch of the working mode)."""
        with np.errstate(invalid="ignore"):
            p = self.model.fk(q).position
        return np.all(np.abs(p - points) <= POSITION_ROUND_TRIP_TOLERANCE * self.size, axis=-1)


def generated_inverse(model: GeneratedModel) -> WorkingModeInverse | ConstantOrientationInverse:
    """The closed-form inverse kinematics of a parallel mechanism, as the Cartesian analyses see it.

    A translational platform (DELTA) gives a :class:`WorkingModeInverse`; a pose platform held at
    one orientation (:class:`ConstantOrientation`) a :class:`ConstantOrientationInverse`.

    Raises:
        NotApplicable: the model is not parallel, its platform also rotates and it was not held at
            a constant orientation, it lacks the generated ``ik`` or ``fk``, or its passive-joint
            limits are malformed or cannot be evaluated (no generated ``closure``).
    """
    if isinstance(model, ConstantOrientation):
        return constant_orientation_inverse(model)
    if not mechanism.is_parallel(model):
        raise NotApplicable(f"{model.name}: not a parallel mechanism")
    kind = mechanism.parallel_kind(mechanism.task_space(model))
    if kind is mechanism.MechanismKind.PARALLEL_ORIENTATION:
        task = list(mechanism.task_space(model))
        raise NotApplicable(f"{model.name}: the platform only turns (task space {task}): its workspace is a set of "
                            "orientations, which the positional workspace and GCI analyses do not cover; rate it "
                            "with the generated inverse_jacobian and singularities at chosen orientations")
    if kind is mechanism.MechanismKind.PARALLEL_POSE:
        task = list(mechanism.task_space(model))
        raise NotApplicable(f"{model.name}: the platform also rotates (task space {task}): "
                            "its Cartesian workspace is analysed at a constant orientation "
                            "(symkin.mechanism.reach.constant_orientation(model, (roll, pitch, yaw)))")
    require_functions(model, ("ik", "fk", "jacobian"))
    size = max(float(np.linalg.norm(mechanism.home_pose(model))), 1e-3)
    return WorkingModeInverse(model, size, passive.declared_limits(model), len(mechanism.task_space(model)))


# --- pose platforms (Stewart-Gough) at a constant orientation --------------------------------

#: Rows of the Jacobian of a platform held at a constant orientation: linear and angular
#: velocity of the platform frame, in the base frame.
TWIST_COMPONENTS = ("x", "y", "z", "wx", "wy", "wz")
#: Smallest |cos(pitch)| of a constant orientation: at pitch = +-90 deg the roll-pitch-yaw
#: rates do not determine the angular velocity (a representation singularity, not the platform's).
GIMBAL_TOLERANCE = 1e-6
#: Largest |l_i^2 - |p - c_i|^2| / size^2 of the sphere-centre identification (see
#: :func:`leg_sphere_centres`).
SPHERE_TOLERANCE = 1e-9


def angular_velocity_matrix(orientation: Any, xp: Any = np) -> Any:
    """E (..., 3, 3) with omega = E d(roll, pitch, yaw)/dt, omega in the base frame, R = Rz(yaw) Ry(pitch)
    Rx(roll), at orientations (..., 3), in the array module ``xp`` (numpy, or jax.numpy on a device).

    omega = e_z dyaw + Rz(yaw) e_y dpitch + Rz(yaw) Ry(pitch) e_x droll, so the columns of E
    are Rz Ry e_x = (cy cp, sy cp, -sp), Rz e_y = (-sy, cy, 0) and e_z; E = I at roll = pitch =
    yaw = 0 and det E = cos(pitch).
    """
    orientation = xp.asarray(orientation, dtype=xp.float64)
    pitch, yaw = orientation[..., 1], orientation[..., 2]
    cp, sp, cy, sy = xp.cos(pitch), xp.sin(pitch), xp.cos(yaw), xp.sin(yaw)
    zero, one = xp.zeros_like(cp), xp.ones_like(cp)
    return xp.stack([xp.stack([cy * cp, -sy, zero], -1), xp.stack([sy * cp, cy, zero], -1),
                     xp.stack([-sp, zero, one], -1)], -2)


class ConstantOrientation:
    """A pose platform (task space x, y, z, roll, pitch, yaw) held at one orientation.

    The analyses see a positional parallel mechanism: TCP points are the 3 coordinates of
    the platform centre (Gosselin's constant-orientation workspace; Merlet, Parallel Robots,
    ch. 6), the joints are the model's, and

    * ``ik(points)`` is the generated ``ik`` at the poses (points, orientation);
    * ``jacobian(q, points)`` (6 x 6) is the twist Jacobian, dt = J dq with
      t = (v, omega): linear velocity of the platform centre and angular velocity, in the
      base frame.  From the generated J^-1 (dq = J^-1 dp, p with roll-pitch-yaw rates):
      J = diag(I, E) (J^-1)^-1 (:func:`angular_velocity_matrix`), so kappa does not depend
      on the angle parametrization; singular J^-1 give J = 0 (1/kappa = 0,
      :func:`~symkin.numerics.conditioning.from_inverse`).  Its rows mix m/s and rad/s: the
      conditioning indices homogenize them with a characteristic length (task space
      ``TWIST_COMPONENTS``).

    Every other attribute (``name``, ``joint_limits``, ``parameters``, generated functions)
    is the model's; ``bind`` binds the model and keeps the orientation.

    Raises:
        ValueError: the model is not a pose platform with a generated ``ik`` and
            ``inverse_jacobian``, or the orientation is not 3 finite angles away from pitch = +-90 deg.
    """

    model: GeneratedModel

    def __init__(self, model: GeneratedModel, orientation) -> None:
        if isinstance(model, ConstantOrientation):
            model = model.model
        if not mechanism.is_parallel(model) or tuple(mechanism.task_space(model)) != (
                *mechanism.POSITION_COMPONENTS, *mechanism.ANGLES):
            raise ValueError(f"{model.name}: a constant orientation applies to a parallel platform with the task "
                             f"space x, y, z, roll, pitch, yaw, not {list(mechanism.task_space(model))}")
        for name in ("ik", "inverse_jacobian"):
            if name not in model.functions:
                raise ValueError(f"{model.name}: the constant-orientation analyses need the generated '{name}' "
                                 "(add it to the scene outputs and derive again)")
        angles = np.array(orientation, dtype=np.float64).reshape(-1)
        if angles.shape != (3,) or not np.all(np.isfinite(angles)):
            raise ValueError(f"{model.name}: the orientation must be 3 finite angles (roll, pitch, yaw in rad), "
                             f"got {orientation!r}")
        if abs(np.cos(angles[1])) < GIMBAL_TOLERANCE:
            raise ValueError(f"{model.name}: pitch = {np.degrees(angles[1]):g} deg is the singularity of the "
                             "roll-pitch-yaw angles (the angular velocity is not defined by their rates); "
                             "choose another orientation")
        self.model = model
        self.orientation = angles
        self.rates = np.eye(6)
        self.rates[3:, 3:] = angular_velocity_matrix(angles)
        self.info = model.info.with_task_space(TWIST_COMPONENTS)
        self.functions = (*model.functions, "jacobian")

    def __getattr__(self, name: str) -> Any:  # the model's name, parameters, joint_limits, generated functions
        if name == "model":  # not yet set (copy, pickle): no recursion
            raise AttributeError(name)
        return getattr(self.model, name)

    def __repr__(self) -> str:
        return f"<{self.model!r} at the constant orientation roll, pitch, yaw = {orientation_text(self)}>"

    def bind(self, **parameters: float) -> ConstantOrientation:
        return ConstantOrientation(self.model.bind(**parameters), self.orientation)

    def poses(self, points: np.ndarray) -> np.ndarray:
        """The poses (..., 6) of platform centres ``points`` (..., 3) at this orientation."""
        points = np.asarray(points, dtype=np.float64)
        return np.concatenate([points, np.broadcast_to(self.orientation, (*points.shape[:-1], 3))], axis=-1)

    def ik(self, points: np.ndarray):
        return self.model.ik(self.poses(points))

    def inverse_jacobian(self, q: np.ndarray, points: np.ndarray) -> np.ndarray:
        """The generated J^-1 (..., 6, 6) at (q, pose of ``points``): dq = J^-1 d(x, y, z, roll, pitch, yaw)."""
        return self.model.inverse_jacobian(q, self.poses(points))

    def jacobian(self, q: np.ndarray, points: np.ndarray) -> np.ndarray:
        """The twist Jacobian J (..., 6, 6) at (q, pose of ``points``); J = 0 where J^-1 is singular or NaN."""
        return self.rates @ conditioning.from_inverse(self.inverse_jacobian(q, points))


def home_position(model: GeneratedModel) -> np.ndarray:
    """The platform centre (x, y, z) of the home pose ``parallel.home``."""
    return mechanism.home_pose(model)[:3]


def orientation_text(model: ConstantOrientation) -> str:
    """'0, 10, 0 deg': the constant orientation (roll, pitch, yaw) in degrees."""
    return ", ".join(f"{a:g}" for a in np.degrees(model.orientation)) + " deg"


def constant_orientation(model: GeneratedModel, orientation=None) -> ConstantOrientation:
    """``model`` held at ``orientation`` (roll, pitch, yaw in rad; default: that of ``parallel.home``)."""
    if orientation is None:
        orientation = mechanism.home_pose(model)[3:]
    return ConstantOrientation(model, orientation)


def held_at(model: GeneratedModel, angles: Sequence[float] | None) -> Any:
    """``model`` held at the constant orientation ``angles`` (roll, pitch, yaw in rad) if its platform
    rotates (:func:`symkin.mechanism.constant_orientation`; None: the home orientation), else ``model``.

    Raises:
        ValueError: angles are given for a mechanism whose platform does not rotate.
    """
    rotates = mechanism.is_parallel(model) and mechanism.mixes_translations_and_rotations(model)
    if angles is None:
        return constant_orientation(model) if rotates else model
    if not rotates:
        raise ValueError(f"--orientation: {model.name} is not a parallel platform that rotates "
                         f"(task space {list(mechanism.task_space(model))}); leave the option out")
    return constant_orientation(model, list(angles))


def held_orientation(model: GeneratedModel, angles: Sequence[float] | None) -> dict[str, float]:
    """The angles (roll, pitch, yaw in rad, or None: the home pose's) as the held angles, by name, of a grid over
    the handle's positions reached by continuation (:attr:`symkin.mechanism.Sampling.CONTINUATION`); an angle
    outside its task space must be 0 (the legs hold it there).

    Raises:
        ValueError: a nonzero angle the task space does not have.
    """
    if angles is None:
        return {}
    task = mechanism.task_space(model)
    extra = [f"{name} = {value:g}" for name, value in zip(mechanism.ANGLES, angles)
             if name not in task and value != 0.0]
    if extra:
        raise ValueError(f"--orientation: {model.name}'s task space {list(task)} holds {', '.join(extra)} at 0 "
                         "(parallel.motion); give 0 there")
    return {name: float(value) for name, value in zip(mechanism.ANGLES, angles) if name in task}


def home_sign(model: GeneratedModel) -> float:
    """The sign of det J^-1 at the home pose ``parallel.home``: the assembly mode analysed.

    Raises:
        ValueError: the home pose is out of reach or singular.
    """
    home = mechanism.home_pose(model)
    with np.errstate(invalid="ignore"):
        q = model.ik(home).joints
        determinant = float(np.linalg.det(model.inverse_jacobian(q, home))) if np.all(np.isfinite(q)) else np.nan
    if not np.isfinite(determinant) or determinant == 0.0:
        raise ValueError(f"{model.name}: the home pose {home.tolist()} is out of reach or singular "
                         f"(det J^-1 = {determinant:.3g}); check parallel.home")
    return float(np.sign(determinant))


@dataclass(frozen=True)
class ConstantOrientationInverse(_GeneratedInverse):
    """The generated ``ik`` of a pose platform at a constant orientation, as an InverseKinematics.

    Points are platform centres (x, y, z); joints are the actuator coordinates.  A point is
    valid where every leg reaches it (finite ``ik``), the pose is in the assembly mode of
    the home pose, det J^-1 having its sign there (the platform cannot change sign
    without crossing a singularity det J^-1 = 0, e.g. the plane of the base joints, below
    which lies the mirror image of the workspace), and the declared passive-joint limits
    hold.  The actuators' limits are applied by the analyses
    (:func:`symkin.mechanism.feasibility.feasible_configurations`).

    Attributes:
        model: the :class:`ConstantOrientation`.
        sign: det J^-1 at the home pose (:func:`home_sign`).
        passive_limits: the declared passive-joint limits, None if there are none.
    """

    model: ConstantOrientation
    sign: float
    passive_limits: passive.PassiveLimits | None = None

    def in_mode(self, q: np.ndarray, points: np.ndarray) -> np.ndarray:
        """det J^-1 has the sign of the home pose's (the assembly mode)."""
        return self.sign * np.linalg.det(self.model.inverse_jacobian(q, points)) > 0

    def poses(self, points: np.ndarray) -> tuple[Any, np.ndarray]:
        return self.model.model, self.model.poses(points)


def constant_orientation_inverse(model: ConstantOrientation) -> ConstantOrientationInverse:
    """The inverse kinematics of a platform held at a constant orientation (see :class:`ConstantOrientationInverse`)."""
    return ConstantOrientationInverse(model, home_sign(model.model), passive.declared_limits(model.model))


def leg_sphere_centres(model: ConstantOrientation) -> np.ndarray:
    """Centres c_i (n, 3) with l_i(p) = |p - c_i| at the constant orientation (distance-form legs).

    A UPS leg's length is |p + R b_i - a_i| (base joint a_i, platform joint b_i), so at a
    fixed R, l_i^2 is a quadratic in p with c_i = a_i - R b_i.  The centres are read off the
    generated ``ik`` (c_ik = (l_i^2(-e_k) - l_i^2(e_k)) / 4) and checked at pseudo-random
    points, so any model whose legs have the distance form is accepted, and nothing else.

    Raises:
        ValueError: a leg length is not the distance to a fixed point.
    """
    size = max(float(np.linalg.norm(mechanism.home_pose(model.model)[:3])), 1e-3)
    steps = size * np.vstack([np.eye(3), -np.eye(3)])
    with np.errstate(invalid="ignore"):
        squares = model.ik(steps).joints ** 2
    centres = ((squares[3:] - squares[:3]) / (4.0 * size)).T
    checks = np.random.default_rng(0).uniform(-2.0 * size, 2.0 * size, (32, 3))
    with np.errstate(invalid="ignore"):
        lengths = model.ik(checks).joints
    mismatch = np.abs(lengths**2 - np.sum((checks[:, None, :] - centres) ** 2, axis=-1))
    if not np.all(np.isfinite(mismatch)) or mismatch.max() > SPHERE_TOLERANCE * size**2:
        raise ValueError(f"{model.name}: the legs' lengths are not distances |p - c_i| at a constant orientation "
                         "(not UPS-like legs): no Cartesian box of the constant-orientation workspace")
    return centres


#: Cells along the longest side of the legs' reach box in the coarse grid of :func:`constant_orientation_box` ...
BOX_CELLS = 32
#: ... and the padding, in cells, around its reachable cells.
BOX_PADDING = 2


def reachable_points(model: ConstantOrientation, points: np.ndarray, limits: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint coordinates (N, n) and reachability (N,) of platform centres at the constant orientation.

    Reachable: in the assembly mode of the home pose (:class:`ConstantOrientationInverse`) with
    the actuators within ``limits`` (n, 2).
    """
    return feasible_configurations(constant_orientation_inverse(model), points, limits, mechanism.revolute_mask(model),
                                   StopInequalities.of_model(model))


def constant_orientation_box(model: ConstantOrientation, limits: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A box (lower, upper) around the constant-orientation workspace.

    Leg i reaches only the ball |p - c_i| <= upper limit of l_i (:func:`leg_sphere_centres`),
    so the workspace lies in the intersection of the balls' bounding boxes.  That box also
    holds the mirror image of the workspace in the other assembly mode (below the base), so
    it is shrunk to the reachable cell centres of a coarse grid (:data:`BOX_CELLS` along its
    longest side) padded by :data:`BOX_PADDING` cells: a part of the workspace thinner than
    that padding, outside every reachable cell, would be cut off (the volume is checked
    against an independent Monte Carlo estimate over the full box in the tests).

    Raises:
        ValueError: the balls' boxes do not intersect or no cell centre is reachable.
    """
    limits = np.asarray(limits, dtype=np.float64)
    centres = leg_sphere_centres(model)
    reach = limits[:, 1][:, None]
    lower, upper = (centres - reach).max(axis=0), (centres + reach).min(axis=0)
    where = f"{model.name}: no platform position is reachable at the orientation " \
            f"{np.degrees(model.orientation).round(6).tolist()} deg within the leg limits"
    if not np.all(lower < upper):
        raise ValueError(where)
    cell = float(np.max(upper - lower)) / BOX_CELLS
    counts = np.maximum(np.ceil((upper - lower) / cell).astype(int), 1)
    points = sampling.grid(lower, lower + counts * cell, tuple(counts), midpoints=True)
    _, reachable = reachable_points(model, points, limits)
    if not reachable.any():
        raise ValueError(where)
    pad = (BOX_PADDING + 0.5) * cell
    return (np.maximum(points[reachable].min(axis=0) - pad, lower),
            np.minimum(points[reachable].max(axis=0) + pad, upper))


#: Sobol points of the Cartesian box sampled for the characteristic length (log2).
LENGTH_SAMPLES_LOG2 = 12


def platform_characteristic_length(model: ConstantOrientation, limits: np.ndarray, seed: int = 0) -> float:
    """The characteristic length of a platform at a constant orientation: the L minimizing the
    mean kappa_F^2 of the homogenized twist Jacobian over the reachable points of a Sobol
    sample of its workspace box (:func:`symkin.numerics.conditioning.characteristic_length`).

    Raises:
        ValueError: no sampled point is reachable.
    """
    lower, upper = constant_orientation_box(model, limits)
    points = sampling.sobol(lower, upper, LENGTH_SAMPLES_LOG2, np.random.default_rng(seed))
    q, reachable = reachable_points(model, points, limits)
    if not reachable.any():
        raise ValueError(f"{model.name}: no sampled position is reachable at this orientation: "
                         "no characteristic length; give one (--length)")
    return conditioning.characteristic_length(model.jacobian(q[reachable], points[reachable]),
                                              mechanism.position_rows(model))


# --- what every mechanism reaches: the box around its workspace, its characteristic length, the domain in words ---

#: Joint-space points evaluated for :func:`bounding_box` (split evenly over the axes).
BOX_SAMPLES = 2**16
#: Configurations sampled to choose the characteristic length of a mechanism with fk (``length="auto"``).
JOINT_LENGTH_SAMPLES_LOG2 = 10


def bounding_box(model: GeneratedModel, *, limits: Limits | None = None, samples: int = BOX_SAMPLES) -> tuple[np.ndarray, np.ndarray]:
    """A Cartesian box that contains the workspace.

    The TCP positions of a joint grid (limits included) are padded by a first-order bound
    of how far the TCP can move inside one grid cell: twice the largest Frobenius norm of
    the positional Jacobian rows at the grid nodes times the half diagonal of a cell.  A
    platform at a constant orientation has no fk: its box is bounded by the legs' reach
    (:func:`symkin.mechanism.constant_orientation_box`).

    Returns:
        (lower, upper), arrays of shape (d,).
    """
    box = mechanism.joint_limits(model, limits)
    if isinstance(model, ConstantOrientation):  # no fk: the legs' reach bounds the workspace
        return constant_orientation_box(model, box)
    n = box.shape[0]
    per_axis = max(3, int(samples ** (1.0 / n)))
    q = sampling.grid(box[:, 0], box[:, 1], per_axis, midpoints=False)
    if mechanism.is_parallel(model):
        return _parallel_bounding_box(model, q, per_axis)
    points = mechanism.tcp_positions(model, q)
    J = model.jacobian(q)[:, list(mechanism.position_rows(model)), :]
    half_diagonal = 0.5 * np.linalg.norm((box[:, 1] - box[:, 0]) / (per_axis - 1))
    margin = 2.0 * np.max(np.linalg.norm(J, axis=(-2, -1))) * half_diagonal
    return points.min(axis=0) - margin, points.max(axis=0) + margin


def _parallel_bounding_box(model: GeneratedModel, q: np.ndarray, per_axis: int) -> tuple[np.ndarray, np.ndarray]:
    """Box of a parallel mechanism: the working-mode TCP positions of a joint grid, padded.

    The Jacobian grows without bound next to the assembly limit (det J_x -> 0), so the
    padding is not a Jacobian bound but twice the largest distance between the TCP
    positions of neighbouring grid nodes that both lie in the working mode.
    """
    points, inside = working_mode(model, q)
    if not inside.any():
        raise ValueError(f"{model.name}: no configuration within the joint limits assembles in the working mode")
    shape = (per_axis,) * q.shape[1]
    grid_points = np.where(inside[:, None], points, np.nan).reshape(*shape, -1)
    gaps = [np.nanmax(np.linalg.norm(np.diff(grid_points, axis=axis), axis=-1), initial=0.0)
            for axis in range(len(shape))]
    margin = 2.0 * max(gaps)
    return points[inside].min(axis=0) - margin, points[inside].max(axis=0) + margin


def homogenizing_length(model: GeneratedModel, length: float | str | None, limits: np.ndarray) -> float | None:
    """The characteristic length L that homogenizes the model's task Jacobian
    (:func:`symkin.numerics.conditioning.homogenize`): None for a task space of one kind; ``length`` (m) or, for
    ``"auto"``, :func:`characteristic_length_of` over the joint limits where it mixes translations and rotations.

    Raises:
        ValueError: a mixed task space and no length.
    """
    if not mechanism.mixes_translations_and_rotations(model):
        return None
    if length is None:
        raise ValueError(f"{model.name}: the task space {list(mechanism.task_space(model))} mixes translations "
                         "and rotations: give a characteristic length (length=L in m, or 'auto')")
    return characteristic_length_of(model, limits) if length == "auto" else float(length)


def characteristic_length_of(model: GeneratedModel, limits: np.ndarray | None = None, seed: int = 0) -> float:
    """Characteristic length of a model with a mixed task space, from a Sobol sample of its joint space.

    See :func:`symkin.numerics.conditioning.characteristic_length`; a platform at a constant
    orientation is sampled over its Cartesian workspace (:func:`symkin.mechanism.platform_characteristic_length`).
    """
    limits = mechanism.joint_limits(model) if limits is None else limits
    if isinstance(model, ConstantOrientation):  # no fk: sampled over its Cartesian workspace
        return platform_characteristic_length(model, limits, seed)
    q = sampling.sobol(limits[:, 0], limits[:, 1], JOINT_LENGTH_SAMPLES_LOG2, np.random.default_rng(seed))
    return conditioning.characteristic_length(mechanism.jacobian(model, q), mechanism.position_rows(model))


def domain_description(model: GeneratedModel, domain: str, measure: str) -> str:
    """The integration domain and measure of a global index, in words (for reports)."""
    if domain == "joint":
        if mechanism.is_parallel(model):
            return ("joint space, dW = |det J| dq over the configurations in the working mode "
                    "(ik(fk(q)) = q, one-to-one): the Cartesian measure" if measure == "cartesian" else
                    "joint space, dW = dq over the configurations in the working mode (joint measure)")
        return ("joint space, dW = |det J| dq (Cartesian measure, with multiplicity where the map is "
                "not one-to-one)" if measure == "cartesian" else "joint space, dW = dq (joint measure)")
    description = "Cartesian box with reachability from inverse kinematics, dW = 1_W(x) dx"
    if isinstance(model, ConstantOrientation):
        description += (f" (platform centres at roll, pitch, yaw = {orientation_text(model)}; "
                        "in the assembly mode of the home pose: sign of det J^-1)")
    elif mechanism.is_parallel(model):
        description += " (in the working mode: fk(ik(x)) = x)"
    return description
