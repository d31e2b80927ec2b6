"""A haptic device's datasheet: the measures of :mod:`symkin.analysis.rating` over its workspace and at its
home pose, with the pose where each extreme occurs (``symkin rate``).

The workspace is sampled in the joint space within the limits (:func:`symkin.analysis.workspace.sample_workspace`,
a parallel mechanism through its closed-form fk), cut to its usable part (1/kappa of the translational
Jacobian at least :data:`USABLE_CONDITIONING`: near a singularity the apparent mass and the forces
diverge) and optionally to a required box of TCP positions.  At
every sample the generated functions give M (``mass_matrix``), J (``jacobian``: its translational rows) and
G (``gravity_vector``); the actuators' data come from the manifest (effort limits, continuous effort,
friction) or from the caller (encoders, servo rate).  A measure whose data the model lacks is not rated,
and the datasheet says why.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from symkin.analysis import forces, mechanism, rating, workspace
from symkin.analysis.conditioning import inverse_condition_number
from symkin.runtime.info import GeneratedModel


@dataclass(frozen=True)
class Measure:
    """One row of the datasheet: a name, its unit, its value at every sample and whether its worst value
    is its smallest (a force) or its largest (a mass, a resolution step)."""

    name: str
    unit: str
    values: np.ndarray
    worst_is_min: bool
    doc: str


@dataclass(frozen=True)
class Actuation:
    """What the rating needs beyond the generated functions, per joint (None: not known).

    Attributes:
        effort_limits: peak efforts tau_max (N m or N).
        continuous_limits: efforts the drives hold for long.
        joint_steps: encoder steps at the joints (rad or m per count).
        coulomb, viscous: joint friction (N m or N; N m s/rad or N s/m).
        period: servo period T (s).
    """

    effort_limits: np.ndarray | None = None
    continuous_limits: np.ndarray | None = None
    joint_steps: np.ndarray | None = None
    coulomb: np.ndarray | None = None
    viscous: np.ndarray | None = None
    period: float = 1e-3

    @classmethod
    def of_model(cls, model: GeneratedModel, *, effort_limits: Sequence[float] | None = None,
                 joint_steps: Sequence[float] | None = None, period: float = 1e-3) -> Actuation:
        """The model's declared data (effort limits, continuous effort, friction), overridden by the arguments."""
        coordinates = model.info.coordinates

        def declared(values: Sequence[float | None]) -> np.ndarray | None:
            return None if any(v is None for v in values) else np.array(values, dtype=float)

        efforts = (np.array(effort_limits, dtype=float) if effort_limits is not None
                   else declared([c.effort_limit for c in coordinates]))
        return cls(efforts, declared([c.continuous_effort_limit for c in coordinates]),
                   None if joint_steps is None else np.array(joint_steps, dtype=float),
                   declared([c.coulomb for c in coordinates]), declared([c.viscous for c in coordinates]), period)


@dataclass(frozen=True)
class Datasheet:
    """The rated samples: joint configurations q (N, n), TCP points (N, d) with their axes, the measures,
    the index of the home pose among the samples, and {measure: why it is not rated}."""

    model: str
    q: np.ndarray
    points: np.ndarray
    axes: tuple[str, ...]
    measures: tuple[Measure, ...]
    home: int
    skipped: dict[str, str] = field(default_factory=dict)

    def extremes(self, measure: Measure) -> dict[str, Any]:
        """min, max, mean and the worst value of a measure, each extreme with its pose (q, TCP)."""
        values = measure.values
        finite = np.flatnonzero(np.isfinite(values))
        low, high = finite[np.argmin(values[finite])], finite[np.argmax(values[finite])]

        def at(k: int) -> dict[str, Any]:
            return {"value": float(values[k]), "q": self.q[k].tolist(), "tcp": self.points[k].tolist()}

        return {"unit": measure.unit, "doc": measure.doc, "min": at(low), "max": at(high),
                "mean": float(np.mean(values[finite])), "worst": "min" if measure.worst_is_min else "max",
                "home": float(values[self.home]) if np.isfinite(values[self.home]) else None}

    def to_json(self) -> dict[str, Any]:
        return {"model": self.model, "samples": len(self.q), "axes": list(self.axes),
                "home": {"q": self.q[self.home].tolist(), "tcp": self.points[self.home].tolist()},
                "measures": {m.name: self.extremes(m) for m in self.measures}, "not_rated": dict(self.skipped)}

    def summary(self) -> list[str]:
        """One line per measure: its worst value over the workspace, its range and its value at home."""
        lines = []
        for m in self.measures:
            e = self.extremes(m)
            worst = e[e["worst"]]
            lines.append(f"{m.name}: {worst['value']:.4g} {m.unit} at worst ({e['worst']} over the workspace, "
                         f"at {'TCP' if self.axes[0] not in ANGLES else 'orientation'} "
                         f"{_point(worst['tcp'], self.axes)}); range {e['min']['value']:.4g} .. {e['max']['value']:.4g}, "
                         f"at home {'-' if e['home'] is None else format(e['home'], '.4g')}")
        lines += [f"{name}: not rated ({why})" for name, why in self.skipped.items()]
        return lines


#: The handle's coordinates a datasheet maps: positions (m, drawn in mm) or a spherical platform's angles (rad, deg).
ANGLES = ("roll", "pitch", "yaw")


def axis_scale(axes: Sequence[str]) -> tuple[float, str, str]:
    """(drawing scale, drawing unit, SI unit) of the handle's coordinates: mm of m, or deg of rad."""
    return (180.0 / np.pi, "deg", "rad") if set(axes) <= set(ANGLES) else (1000.0, "mm", "m")


def _point(tcp: Sequence[float], axes: Sequence[str]) -> str:
    scale, unit, _ = axis_scale(axes)
    return "(" + ", ".join(f"{scale * v:.1f}" for v in tcp) + f") {unit}"


def home_configuration(model: GeneratedModel, limits: np.ndarray) -> np.ndarray:
    """The pose a datasheet quotes besides the workspace: a parallel mechanism's declared home (q = ik(home)),
    a serial device's declared rest configuration (``serial.home``), else the middle of the joint limits."""
    if mechanism.is_parallel(model) and model.info.home is not None:
        return np.asarray(model.ik(np.array(model.info.home)).joints, dtype=float)
    if model.info.home_configuration is not None:
        return np.array(model.info.home_configuration, dtype=float)
    return limits.mean(axis=1)


def _within(points: np.ndarray, axes: Sequence[str], box: Mapping[str, tuple[float, float]]) -> np.ndarray:
    unknown = set(box) - set(axes)
    if unknown:
        raise ValueError(f"--box: no task axes {sorted(unknown)}; the TCP moves along {', '.join(axes)}")
    inside = np.ones(len(points), dtype=bool)
    for name, (low, high) in box.items():
        column = points[:, list(axes).index(name)]
        inside &= (column >= low) & (column <= high)
    return inside


def _dynamics(model: GeneratedModel, name: str, q: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """A generated dynamics function at the samples: of q (a serial arm), of (q, p) (a parallel platform)."""
    function = getattr(model, name)
    return function(q, poses) if mechanism.is_parallel(model) else function(q)


def _usable(keep: np.ndarray, conditioning: float, *jacobians: np.ndarray) -> np.ndarray:
    """``keep`` where 1/kappa of every Jacobian is at least ``conditioning``; the last sample, the home pose, is kept
    whatever (a datasheet quotes it)."""
    with np.errstate(invalid="ignore"):
        for J in jacobians:
            keep = keep & (np.nan_to_num(inverse_condition_number(J), nan=0.0) >= conditioning)
    keep[-1] = True
    return keep


#: The usable workspace a datasheet rates: where 1/kappa of J's translational rows is at least this (near a
#: singularity the apparent mass and the force capability diverge, and no device is used there).
USABLE_CONDITIONING = 0.05


def rate(model: GeneratedModel, actuation: Actuation, *, samples: int = 4096, seed: int = 0,
         box: Mapping[str, tuple[float, float]] | None = None, limits: mechanism.Limits | None = None,
         conditioning: float = USABLE_CONDITIONING, orientation: Sequence[float] | None = None) -> Datasheet:
    """The datasheet of a device whose handle translates (its task space has x, y or z), over the sampled
    poses in ``box`` (TCP coordinates, m) where 1/kappa >= ``conditioning``, and at its home pose.

    A platform that also rotates (Stewart-Gough) is rated over its workspace at the constant ``orientation``
    (roll, pitch, yaw in rad; default: its home pose's) by :func:`rate_pose_platform`, a spherical platform (the
    Agile Eye) over its orientations by :func:`rate_orientation_platform`.

    Raises:
        ValueError: the model cannot be rated (no task coordinate it rates, a wrist on the platform, no mass
            matrix), or the box holds no sample.
    """
    kind = mechanism.kind_of(model)
    if model.info.wrist:
        raise ValueError(f"{model.name}: a platform carrying a wrist: rate the whole device at its grip point "
                         "(symkin rate --device, symkin.analysis.device.WholeDevice)")
    if kind is mechanism.MechanismKind.PARALLEL_POSE:
        return rate_pose_platform(model, actuation, samples=samples, seed=seed, box=box, limits=limits,
                                  conditioning=conditioning, orientation=orientation)
    if kind is mechanism.MechanismKind.PARALLEL_ORIENTATION and orientation is None:
        return rate_orientation_platform(model, actuation, samples=samples, seed=seed, box=box, limits=limits,
                                         conditioning=conditioning)
    if orientation is not None:
        raise ValueError(f"{model.name}: --orientation applies to platforms that also rotate (Stewart-Gough); "
                         f"this is a {kind.value} mechanism")
    if kind not in (mechanism.MechanismKind.SERIAL, mechanism.MechanismKind.PARALLEL):
        raise ValueError(f"{model.name}: symkin rate rates devices whose handle translates with the platform or is "
                         f"a serial arm's TCP; this is a {kind.value} mechanism")
    rows = list(mechanism.position_rows(model))
    if not rows:
        raise ValueError(f"{model.name}: the task space ({', '.join(mechanism.task_space(model))}) has no translation")
    if "mass_matrix" not in model.functions:
        raise ValueError(f"{model.name}: the rating needs the generated mass_matrix (derive it with bodies declared)")
    box_limits = mechanism.joint_limits(model, limits)
    cloud = workspace.sample_workspace(model, samples, limits=limits, seed=seed)
    home = home_configuration(model, box_limits)
    q = np.concatenate([cloud.q, home[None]])
    points = np.concatenate([cloud.points, mechanism.tcp_positions(model, home[None])])
    keep = np.all(np.isfinite(points), axis=-1)
    if box:
        keep &= _within(points, cloud.axes, box)  # the home pose (last) is quoted anyway: _usable keeps it
    J = mechanism.jacobian(model, q, points if mechanism.is_parallel(model) else None)[..., rows, :]
    keep = _usable(keep, conditioning, J)
    q, points, J = q[keep], points[keep], J[keep]
    if len(q) < 2:
        raise ValueError(f"{model.name}: no sampled pose lies in the box {dict(box or {})} with 1/kappa >= "
                         f"{conditioning:g}")
    M = _dynamics(model, "mass_matrix", q, points)
    measures, skipped = _measures(model, J, M, q, points, actuation)
    return Datasheet(model.name, q, points, cloud.axes, measures, len(q) - 1, skipped)


def rate_pose_platform(model: GeneratedModel, actuation: Actuation, *, samples: int = 4096, seed: int = 0,
                       box: Mapping[str, tuple[float, float]] | None = None, limits: mechanism.Limits | None = None,
                       conditioning: float = USABLE_CONDITIONING,
                       orientation: Sequence[float] | None = None) -> Datasheet:
    """The datasheet of a platform that translates and rotates, over its workspace at a constant orientation.

    Platform centres are sampled (Sobol) in the box around the constant-orientation workspace
    (:func:`symkin.analysis.parallel.constant_orientation_box`) and kept where reachable; the twist Jacobian
    t = (v, omega) = J_t qd (:class:`symkin.analysis.parallel.ConstantOrientation`) splits into J_v and J_w.
    The handle's measures are those of a device whose hand pushes and twists it: the apparent mass
    (J_v M^-1 J_v^T)^-1 with the orientation free, forces with no moment (tau = J_v^T f), the translation's
    resolution; then the apparent rotational inertia (J_w M^-1 J_w^T)^-1 with the position free, torques with
    no force (tau = J_w^T m) and the angular resolution.  A sample is usable where 1/kappa of J_v and of J_w
    are both at least ``conditioning``.
    """
    from symkin.analysis import parallel, sampling

    view = parallel.constant_orientation(model, orientation)
    box_limits = mechanism.joint_limits(model, limits)
    lower, upper = parallel.constant_orientation_box(view, box_limits)
    points = sampling.sobol(lower, upper, max(1, int(np.ceil(np.log2(samples)))), np.random.default_rng(seed))
    q, reachable = parallel.reachable_points(view, points, box_limits)
    q, points = q[reachable], points[reachable]
    home = parallel.home_position(model)[None]
    home_q, home_reachable = parallel.reachable_points(view, home, box_limits)
    if not home_reachable[0]:
        raise ValueError(f"{model.name}: the home position is not reachable at the orientation "
                         f"{parallel.orientation_text(view)}; rate it at the home pose's orientation")
    q, points = np.concatenate([q, home_q]), np.concatenate([points, home])
    keep = np.ones(len(q), dtype=bool)
    if box:
        keep &= _within(points, mechanism.POSITION_COMPONENTS, box)
    twist = view.jacobian(q, points)
    J_v, J_w = twist[..., :3, :], twist[..., 3:, :]
    keep = _usable(keep, conditioning, J_v, J_w)
    q, points, J_v, J_w = q[keep], points[keep], J_v[keep], J_w[keep]
    if len(q) < 2:
        raise ValueError(f"{model.name}: no reachable platform centre at the orientation "
                         f"{parallel.orientation_text(view)} lies in the box {dict(box or {})} with 1/kappa >= "
                         f"{conditioning:g}")
    poses = view.poses(points)
    M = _dynamics(model, "mass_matrix", q, poses)
    measures, skipped = _measures(model, J_v, M, q, poses, actuation)
    return Datasheet(model.name, q, points, mechanism.POSITION_COMPONENTS,
                     measures + _rotation_measures(J_w, M, actuation), len(q) - 1, skipped)


def rate_orientation_platform(model: GeneratedModel, actuation: Actuation, *, samples: int = 4096, seed: int = 0,
                              box: Mapping[str, tuple[float, float]] | None = None,
                              limits: mechanism.Limits | None = None,
                              conditioning: float = USABLE_CONDITIONING) -> Datasheet:
    """The datasheet of a spherical platform (the Agile Eye): its handle twisted about the centre of rotation.

    Orientations are sampled (scrambled Sobol) over the roll-pitch-yaw chart, or the ``box`` of angles (rad), and
    kept where every leg reaches them within the joint limits (:func:`symkin.analysis.orientations.orientation_cloud`).
    The angular-velocity Jacobian J_w = E(p) J (omega = J_w qd; E maps the roll-pitch-yaw rates to omega, J is the
    generated ``jacobian``) rates the handle: the apparent rotational inertia (J_w M^-1 J_w^T)^-1, the isotropic and
    peak torque, the angular resolution, the gravity share, and with joint friction the Coulomb torque felt, the
    least rotational damping and the stiffest passive rotational wall at the servo rate.  A sample is usable where
    1/kappa(J_w) >= ``conditioning``.
    """
    from symkin.analysis import orientations
    from symkin.analysis.parallel import angular_velocity_matrix

    for name in ("ik", "jacobian", "mass_matrix"):
        mechanism.parallel_function(model, name)
    unknown = set(box or {}) - set(ANGLES)
    if unknown:
        raise ValueError(f"--box: no task axes {sorted(unknown)}; the platform turns in {', '.join(ANGLES)} (rad)")
    lower, upper = (np.array(bound, dtype=float) for bound in orientations.FULL_CHART)
    for name, (low, high) in (box or {}).items():
        k = ANGLES.index(name)
        lower[k], upper[k] = max(lower[k], low), min(upper[k], high)
    points, _ = orientations.orientation_cloud(model, samples, seed=seed, box=(lower, upper), limits=limits)
    points = np.concatenate([points, mechanism.home_pose(model)[None]])  # the home pose is quoted anyway
    q = np.asarray(model.ik(points).joints, dtype=float)
    J_w = angular_velocity_matrix(points) @ model.jacobian(q, points)
    keep = _usable(np.ones(len(q), dtype=bool), conditioning, J_w)
    q, points, J_w = q[keep], points[keep], J_w[keep]
    if len(q) < 2:
        raise ValueError(f"{model.name}: no reachable orientation in the box {dict(box or {})} has 1/kappa >= "
                         f"{conditioning:g}")
    M = _dynamics(model, "mass_matrix", q, points)
    measures, skipped = _rotation_measures(J_w, M, actuation), {}
    if actuation.effort_limits is None:
        skipped["torque"] = "no effort limits: declare effort_limit per joint or give --effort-limit"
    elif "gravity_vector" in model.functions:
        measures += (Measure("gravity_share", "", rating.gravity_share(_dynamics(model, "gravity_vector", q, points),
                                                                      actuation.effort_limits), False,
                             "largest share of an effort limit spent holding the device against gravity"),)
    if actuation.joint_steps is None:
        skipped["angular_resolution"] = "no encoder data: give --encoder COUNTS[,...] (and --gear)"
    if actuation.coulomb is None or actuation.viscous is None:
        skipped["friction"] = "no joint friction declared (friction: in the model file)"
    else:
        damping = rating.handle_damping(J_w, actuation.viscous)
        measures += (Measure("coulomb_torque", "N m", rating.coulomb_friction_felt(J_w, actuation.coulomb), False,
                             "largest Coulomb friction torque felt turning the handle, over the axes of rotation"),
                     Measure("handle_damping", "N m s/rad", damping, True,
                             "least viscous damping turning the handle"),
                     Measure("renderable_stiffness", "N m/rad", rating.renderable_stiffness(damping, actuation.period),
                             True, f"stiffest passive rotational virtual wall at {1 / actuation.period:g} Hz "
                                   "(Colgate-Brown, K < 2 b / T)"))
    return Datasheet(model.name, q, points, ANGLES, measures, len(q) - 1, skipped)


def _rotation_measures(J_w: np.ndarray, M: np.ndarray, actuation: Actuation) -> tuple[Measure, ...]:
    """A rotating handle's inertia felt with its position free, torque capability and angular resolution."""
    inertias = rating.principal_masses(M, J_w)
    out = [Measure("apparent_inertia_min", "kg m^2", inertias[:, 0], False,
                   "smallest principal inertia felt turning the handle (its position free)"),
           Measure("apparent_inertia_max", "kg m^2", inertias[:, -1], False,
                   "largest principal inertia felt turning the handle (its position free)")]
    if actuation.effort_limits is not None:
        out += [Measure("isotropic_torque", "N m", forces.isotropic_force(J_w, actuation.effort_limits), True,
                        "largest torque rendered about every axis, with no force (peak efforts)"),
                Measure("peak_torque", "N m", rating.peak_force(J_w, actuation.effort_limits), True,
                        "largest torque rendered about the best axis, with no force (peak efforts)")]
    if actuation.continuous_limits is not None:
        out.append(Measure("continuous_torque", "N m", forces.isotropic_force(J_w, actuation.continuous_limits), True,
                           "largest torque held for long about every axis (continuous efforts)"))
    if actuation.joint_steps is not None:
        out.append(Measure("angular_resolution", "rad", rating.position_resolution(J_w, actuation.joint_steps), False,
                           "largest handle rotation between neighbouring encoder readings"))
    return tuple(out)


def _measures(model: GeneratedModel, J: np.ndarray, M: np.ndarray, q: np.ndarray, poses: np.ndarray,
              actuation: Actuation) -> tuple[tuple[Measure, ...], dict[str, str]]:
    """The handle's measures from J (its translational rows), M and the generated functions at (q, poses)."""
    masses = rating.principal_masses(M, J)
    out = [Measure("apparent_mass_min", "kg", masses[:, 0], False, "smallest principal mass felt at the handle"),
           Measure("apparent_mass_max", "kg", masses[:, -1], False, "largest principal mass felt at the handle"),
           Measure("inertia_isotropy", "", masses[:, -1] / masses[:, 0], False,
                   "largest over smallest principal mass (1: the same mass in every direction)")]
    skipped = {}
    square = J.shape[-1] == J.shape[-2]  # J: the translational rows (of the twist Jacobian of a rotating platform)
    efforts = actuation.effort_limits
    if efforts is None:
        skipped["force"] = "no effort limits: declare effort_limit per joint or give --effort-limit"
    else:
        out += [Measure("isotropic_force", "N", forces.isotropic_force(J, efforts), True,
                        "largest force rendered in every direction (peak efforts)"),
                Measure("peak_force", "N", rating.peak_force(J, efforts), True,
                        "largest force rendered in the best direction (peak efforts)")]
        if "gravity_vector" in model.functions:
            out.append(Measure("gravity_share", "", rating.gravity_share(_dynamics(model, "gravity_vector", q, poses),
                                                                         efforts), False,
                               "largest share of an effort limit spent holding the device against gravity"))
    if actuation.continuous_limits is not None:
        out.append(Measure("continuous_force", "N", forces.isotropic_force(J, actuation.continuous_limits), True,
                           "largest force held for long in every direction (continuous efforts)"))
    if actuation.joint_steps is None:
        skipped["resolution"] = "no encoder data: give --encoder COUNTS[,...] (and --gear)"
    else:
        out.append(Measure("resolution", "m", rating.position_resolution(J, actuation.joint_steps), False,
                           "largest handle step between neighbouring encoder readings"))
    if not square:
        skipped["friction"] = "friction and damping at the handle need as many joints as task translations"
    elif actuation.coulomb is None or actuation.viscous is None:
        skipped["friction"] = "no joint friction declared (friction: in the model file)"
    else:
        out.append(Measure("coulomb_friction", "N", rating.coulomb_friction_felt(J, actuation.coulomb), False,
                           "largest Coulomb friction felt at the handle, over the directions of motion"))
        damping = rating.handle_damping(J, actuation.viscous)
        out += [Measure("handle_damping", "N s/m", damping, True, "least viscous damping at the handle"),
                Measure("renderable_stiffness", "N/m", rating.renderable_stiffness(damping, actuation.period), True,
                        f"stiffest passive virtual wall at {1 / actuation.period:g} Hz (Colgate-Brown, "
                        "K < 2 b / T)")]
    return tuple(out), skipped
