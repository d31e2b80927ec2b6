"""A haptic device's datasheet: the measures of :mod:`symkin.rating.formulas` over its workspace and at its
home pose, with the pose where each extreme occurs (``symkin rate``).

The workspace is sampled as the mechanism is (:func:`symkin.mechanism.sampling`: its joint space, centres,
orientations or continued cells), cut to its usable part (1/kappa of the handle's Jacobians at least
:data:`USABLE_CONDITIONING`: near a singularity the apparent mass and the forces diverge) and optionally to a
required box of the handle's coordinates; one rating takes every kind's usable samples (:func:`rate`).  At
every sample the generated functions give M (``mass_matrix``), J (``jacobian``: its translational rows) and
G (``gravity_vector``); the actuators' data come from the manifest (effort limits, continuous effort,
friction) or from the caller (encoders, servo rate).  A measure whose data the model lacks is not rated,
and the datasheet says why.

Length: one rating (its samples by kind of sampling, the measures over them on the host or JAX's device, the
datasheet), each sampling a function of its own.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin.analysis import workspace
from symkin import mechanism
from symkin.numerics.conditioning import inverse_condition_number
from symkin.rating import on_device
from symkin.rating.handle_measures import (NO_GRAVITY, ROTATIONAL_FRICTION,
                                             SPHERICAL_GROUPS, TURNED_GROUPS, Actuation, Measure, SharedFactors, dynamics_at,
                                             friction_measures, gravity_share_measure, pushed_groups, rotation_measures,
                                             translation_measures)
from symkin.mechanism import ANGLES, Sampling, continuation
from symkin.runtime.info import GeneratedModel


@dataclass(frozen=True)
class Datasheet:
    """The rated samples: joint configurations q (N, n), TCP points (N, d) with their axes, the measures,
    the index of the home pose among the samples, {group: why it is not rated} and the groups of measures the
    device's handle has ({group: its measures}, e.g. :func:`~symkin.rating.handle_measures.pushed_groups`), and
    notes on how it was rated (the home assembly of legs solved through their closure).

    Every group is rated whole or listed as not rated (a measure is never dropped silently): raises ValueError
    otherwise.
    """

    model: str
    q: np.ndarray
    points: np.ndarray
    axes: tuple[str, ...]
    measures: tuple[Measure, ...]
    home: int
    skipped: dict[str, str]
    groups: Mapping[str, tuple[str, ...]]
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        rated = [m.name for m in self.measures]
        listed = {name for names in self.groups.values() for name in names}
        stray = [name for name in rated if name not in listed] + [g for g in self.skipped if g not in self.groups]
        # a group is listed as not rated with none of its measures, or rated with all of them
        partial = [group for group, names in self.groups.items()
                   if sum(name in rated for name in names) != (0 if group in self.skipped else len(names))]
        if stray or partial or len(set(rated)) != len(rated):
            raise ValueError(f"{self.model}: the datasheet's measures {rated} and not rated groups "
                             f"{sorted(self.skipped)} do not cover the groups {dict(self.groups)} once each "
                             f"(stray: {stray}, partial: {partial})")

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
                "measures": {m.name: self.extremes(m) for m in self.measures}, "not_rated": dict(self.skipped),
                "notes": list(self.notes)}

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
        return lines + list(self.notes)


def axis_scale(axes: Sequence[str]) -> tuple[float, str, str]:
    """(drawing scale, drawing unit, SI unit) of the handle's coordinates: positions (mm of m) or a spherical
    platform's angles (deg of rad)."""
    return (180.0 / np.pi, "deg", "rad") if set(axes) <= set(ANGLES) else (1000.0, "mm", "m")


def _point(tcp: Sequence[float], axes: Sequence[str]) -> str:
    scale, unit, _ = axis_scale(axes)
    return "(" + ", ".join(f"{round(scale * v, 1) + 0.0:.1f}" for v in tcp) + f") {unit}"   # + 0.0: no -0.0


def home_configuration(model: GeneratedModel, limits: np.ndarray) -> np.ndarray:
    """The pose a datasheet quotes besides the workspace: a parallel mechanism's declared home (q = ik(home)),
    a serial device's declared rest configuration (``serial.home``), else the middle of the joint limits."""
    if mechanism.sampled_in_task_space(model) and model.info.home is not None:
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


@dataclass(frozen=True)
class _Usable:
    """The usable samples of a device's workspace, the home pose last, as every kind of mechanism gives them to the one
    rating (:func:`rate`): the joints q, the poses p the generated functions take (an open chain's: its TCP points),
    the handle's points in ``axes``, the Jacobians of the handle pushed (J_v: its translational rows, None for a
    handle that only turns) and turned (J_w: as angular velocity, None for one that only translates), the mass matrix
    (None: why in ``no_mass``), the efforts that hold the device (None: the generated ``gravity_vector``) and notes."""

    q: np.ndarray
    poses: np.ndarray
    points: np.ndarray
    axes: tuple[str, ...]
    J_v: np.ndarray | None
    J_w: np.ndarray | None
    M: np.ndarray | None
    G: np.ndarray | str | None = None
    no_mass: str = ""
    notes: tuple[str, ...] = ()


def rate(model: GeneratedModel, actuation: Actuation, *, samples: int = 4096, seed: int = 0,
         box: Mapping[str, tuple[float, float]] | None = None, limits: mechanism.Limits | None = None,
         conditioning: float = USABLE_CONDITIONING, orientation: Sequence[float] | None = None) -> Datasheet:
    """The datasheet of a device over the usable samples of its workspace in ``box`` (the handle's coordinates, m or
    rad) where 1/kappa >= ``conditioning``, and at its home pose: the handle pushed (apparent mass, force
    capability, resolution, gravity share, friction: :func:`~symkin.rating.handle_measures.translation_measures`)
    where it translates, turned (apparent inertia, torque, angular resolution:
    :func:`~symkin.rating.handle_measures.rotation_measures`) where it also rotates, and the gravity share and
    the rotational friction where it only turns.

    The samples come from the mechanism, as it is sampled (:func:`symkin.mechanism.sampling`): a serial arm's or a
    closed-form platform's joint space (:func:`_usable_joint_samples`); a platform reached by continuation (legs
    without closed forms), the cells of its continued assembly at a constant ``orientation``
    (:func:`_usable_continued_cells`); a platform that also rotates (Stewart-Gough), its centres at the constant
    ``orientation`` (roll, pitch, yaw in rad; default: its home pose's, :func:`_usable_centres`); a spherical platform
    (the Agile Eye), its orientations (:func:`_usable_orientations`).

    Raises:
        ValueError: the model cannot be rated (no task coordinate it rates, a wrist on the platform, no mass
            matrix), or the box holds no sample.
    """
    sampled = mechanism.sampling(model)
    if sampled is Sampling.CONTINUATION:
        usable = _usable_continued_cells(model, samples, box, limits, conditioning, orientation)
    else:
        if mechanism.handle_on_further_joints(model):
            raise ValueError(f"{model.name}: a platform carrying a wrist: rate the whole device at its grip point "
                             "(symkin rate --device, symkin.mechanism.device.WholeDevice)")
        if sampled is Sampling.INVERSE and mechanism.mixes_translations_and_rotations(model):  # Stewart-Gough
            usable = _usable_centres(model, samples, seed, box, limits, conditioning, orientation)
        elif sampled is Sampling.ORIENTATIONS and orientation is None:
            usable = _usable_orientations(model, samples, seed, box, limits, conditioning)
        elif orientation is not None:
            raise ValueError(f"{model.name}: --orientation applies to platforms that also rotate (Stewart-Gough); "
                             f"its task space is {list(mechanism.task_space(model))}")
        elif sampled is Sampling.INVERSE and not mechanism.is_positional(model):
            raise ValueError(f"{model.name}: symkin rate rates devices whose handle translates with the platform or "
                             f"is a serial arm's TCP; its task space is {list(mechanism.task_space(model))}")
        else:
            usable = _usable_joint_samples(model, samples, seed, box, limits, conditioning)
    return _datasheet(model, usable, actuation)


def _datasheet(model: GeneratedModel, usable: _Usable, actuation: Actuation) -> Datasheet:
    """The measures of the handle over the usable samples (see :func:`rate`): on JAX's device in one compiled
    program for a model loaded with the JAX backend (:mod:`symkin.rating.on_device`), else with numpy."""
    sampled = {name: getattr(usable, name) for name in on_device.SAMPLED}
    measures_of = functools.partial(_measures, model, usable.axes, usable.no_mass, actuation)
    if on_device.rates_on_device(model):
        # one program per model and rating options: a later rating of the model reuses it (XLA compiles it again only
        # for other array shapes)
        measures, skipped = on_device.rated_on_device(
            measures_of, sampled, key=(model, usable.axes, usable.no_mass, actuation.fingerprint()))
    else:
        measures, skipped = measures_of(sampled, np)
    groups = SPHERICAL_GROUPS if usable.J_v is None else \
        pushed_groups(usable.axes) | TURNED_GROUPS if usable.J_w is not None else pushed_groups(usable.axes)
    return Datasheet(model.name, usable.q, usable.points, usable.axes, measures, len(usable.q) - 1, skipped, groups,
                     usable.notes)


def _measures(model: GeneratedModel, axes: tuple[str, ...], no_mass: str, actuation: Actuation,
              sampled: Mapping[str, Any], xp: Any) -> tuple[tuple[Measure, ...], dict[str, str]]:
    """The handle's measures over the usable samples and {group: why not rated}, in the array module ``xp``:
    ``sampled`` maps the names of :data:`symkin.rating.on_device.SAMPLED` to the usable samples' arrays (a
    :class:`_Usable`'s), ``axes`` and ``no_mass`` are the usable samples' too."""
    q, poses, J_v, J_w, M, G = (sampled[name] for name in on_device.SAMPLED)
    measures: tuple[Measure, ...] = ()
    skipped: dict[str, str] = {}
    if J_v is not None:
        measures, skipped = translation_measures(model, J_v, M, q, poses, actuation, axes, no_mass=no_mass, G=G, xp=xp)
    turning = None if J_w is None else SharedFactors(J_w, M, xp)
    if J_w is not None:
        turned, not_turned = rotation_measures(J_w, M, actuation, no_mass=no_mass, xp=xp, factors=turning)
        measures, skipped = measures + turned, skipped | not_turned
    if J_v is None:  # a handle that only turns: what the pushed measures would have said of it
        assert J_w is not None, "a handle that neither translates nor turns is refused before"
        share = gravity_share_measure(model, q, poses, actuation.effort_limits, xp)
        if isinstance(share, str):
            skipped["gravity_share"] = share
        else:
            measures += tuple(share)
        friction = friction_measures(J_w, actuation, ROTATIONAL_FRICTION, xp, turning)
        if isinstance(friction, str):
            skipped["friction"] = friction
        else:
            measures += tuple(friction)
    return measures, skipped


def _usable_joint_samples(model: GeneratedModel, samples: int, seed: int, box: Mapping[str, tuple[float, float]] | None,
                          limits: mechanism.Limits | None, conditioning: float) -> _Usable:
    """A serial arm's or a closed-form platform's joint space sampled within the limits (TCP points by fk)."""
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
    J = mechanism.jacobian(model, q, points if mechanism.sampled_in_task_space(model) else None)[..., rows, :]
    keep = _usable(keep, conditioning, J)
    q, points, J = q[keep], points[keep], J[keep]
    if len(q) < 2:
        raise ValueError(f"{model.name}: no sampled pose lies in the box {dict(box or {})} with 1/kappa >= "
                         f"{conditioning:g}")
    return _Usable(q, points, points, cloud.axes, J, None, dynamics_at(model, "mass_matrix", q, points))


#: Why a platform reached by continuation (legs without closed forms) has no apparent mass, inertia or gravity share
#: in its datasheet.
NO_CONTINUED_DYNAMICS = ("no mass properties: legs without closed forms (any topology) rate their apparent mass, "
                         "inertia and gravity share from the generated closure_dynamics (declare bodies: links: and "
                         "platform:)")


def _usable_continued_cells(model: GeneratedModel, samples: int, box: Mapping[str, tuple[float, float]] | None,
                            limits: mechanism.Limits | None, conditioning: float,
                            orientation: Sequence[float] | None) -> _Usable:
    """A platform whose legs have no closed forms, over the working mode of its home assembly at a constant
    ``orientation`` (roll, pitch, yaw in rad; default the home pose's), on the grid of
    :func:`symkin.mechanism.continuation.continued_grid` (about ``samples`` cells).

    J = dp/dq at each reached cell (:func:`symkin.mechanism.continuation.handle_jacobian`): its position rows J_v
    rate the handle pushed with its angles free (forces with no moment, tau = J_v^T f, the translation's
    resolution and friction), its angle rows J_w (as angular velocity) the handle turned with its position free.
    With the generated ``closure_dynamics`` (bodies declared), M = W^T M_z W
    (:func:`symkin.mechanism.continuation.dynamics_at_rest`); without it the apparent mass and inertia are not
    rated (:data:`NO_CONTINUED_DYNAMICS`).
    """
    from symkin.mechanism import reach

    held = reach.held_orientation(model, orientation)
    found = continuation.continued_grid(model, orientation=held, limits=limits,
                                        cells=max(8, int(round(samples ** (1 / 3)))))
    assembly = found.home
    assert assembly is not None, "a grid continued without a start solves its home assembly"
    home_q, home_s = assembly.q, assembly.s
    reached = found.reached
    task = mechanism.task_space(model)
    positions = [k for k, c in enumerate(task) if c in mechanism.POSITION_COMPONENTS]
    angles = [k for k in range(len(task)) if k not in positions]
    points = found.centres()[reached]
    poses = np.repeat(found.pose[None], len(points), axis=0)
    poses[:, positions] = points
    home_pose = mechanism.home_pose(model)
    if np.allclose(home_pose[angles], found.pose[angles]):
        home_J = continuation.handle_jacobian(model, home_q[None], home_s[None], home_pose[None])[0]
    else:
        nearest = int(np.argmin(np.linalg.norm(points - home_pose[positions], axis=-1)))
        home_q, home_s = found.q[reached][nearest], found.s[reached][nearest]
        home_pose, home_J = poses[nearest], found.J[reached][nearest]
    q = np.concatenate([found.q[reached], home_q[None]])
    s = np.concatenate([found.s[reached], home_s[None]])
    poses = np.concatenate([poses, home_pose[None]])
    points = poses[:, positions]
    J = np.concatenate([found.J[reached], home_J[None]])
    J_v, J_w = J[:, positions, :], J[:, angles, :]
    keep = np.all(np.isfinite(J), axis=(-2, -1))
    if box:
        keep &= _within(points, found.axes, box)
    keep = _usable(keep, conditioning, J_v, *([J_w] if angles else []))
    q, s, points, poses, J_v, J_w = q[keep], s[keep], points[keep], poses[keep], J_v[keep], J_w[keep]
    if len(q) < 2:
        raise ValueError(f"{model.name}: no reached cell lies in the box {dict(box or {})} with 1/kappa >= "
                         f"{conditioning:g}")
    M: np.ndarray | None = None
    G: np.ndarray | str = NO_CONTINUED_DYNAMICS
    if "closure_dynamics" in model.functions:
        at_rest = continuation.dynamics_at_rest(model, q, s, poses)  # bias at rest: the gravity efforts
        M, G = at_rest.M, at_rest.bias if np.any(at_rest.potential != 0) else NO_GRAVITY
    return _Usable(q, poses, points, found.axes, J_v, J_w if angles else None, M, G, NO_CONTINUED_DYNAMICS,
                   (assembly.describe(model),))


def _usable_centres(model: GeneratedModel, samples: int, seed: int, box: Mapping[str, tuple[float, float]] | None,
                    limits: mechanism.Limits | None, conditioning: float,
                    orientation: Sequence[float] | None) -> _Usable:
    """A platform that translates and rotates, over its workspace at a constant orientation: platform centres
    sampled (Sobol) in the box around it (:func:`symkin.mechanism.reach.constant_orientation_box`), kept where
    reachable; the twist Jacobian t = (v, omega) = J_t qd (:class:`symkin.mechanism.reach.ConstantOrientation`)
    splits into J_v and J_w: the handle pushed with the orientation free and turned with the position free.  A
    sample is usable where 1/kappa of J_v and of J_w are both at least ``conditioning``."""
    from symkin.numerics import sampling
    from symkin.mechanism import reach

    view = reach.constant_orientation(model, orientation)
    box_limits = mechanism.joint_limits(model, limits)
    lower, upper = reach.constant_orientation_box(view, box_limits)
    points = sampling.sobol(lower, upper, max(1, int(np.ceil(np.log2(samples)))), np.random.default_rng(seed))
    q, reachable = reach.reachable_points(view, points, box_limits)
    q, points = q[reachable], points[reachable]
    home = reach.home_position(model)[None]
    home_q, home_reachable = reach.reachable_points(view, home, box_limits)
    if not home_reachable[0]:
        raise ValueError(f"{model.name}: the home position is not reachable at the orientation "
                         f"{reach.orientation_text(view)}; rate it at the home pose's orientation")
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
                         f"{reach.orientation_text(view)} lies in the box {dict(box or {})} with 1/kappa >= "
                         f"{conditioning:g}")
    poses = view.poses(points)
    M = dynamics_at(model, "mass_matrix", q, poses)
    return _Usable(q, poses, points, mechanism.POSITION_COMPONENTS, J_v, J_w, M)


def _usable_orientations(model: GeneratedModel, samples: int, seed: int, box: Mapping[str, tuple[float, float]] | None,
                         limits: mechanism.Limits | None, conditioning: float) -> _Usable:
    """A spherical platform (the Agile Eye): its handle twisted about the centre of rotation.

    Orientations are sampled (scrambled Sobol) over the roll-pitch-yaw chart, or the ``box`` of angles (rad), and
    kept where every leg reaches them within the joint limits (:func:`symkin.analysis.orientations.orientation_cloud`).
    The angular-velocity Jacobian J_w = E(p) J (omega = J_w qd; E maps the roll-pitch-yaw rates to omega, J is the
    generated ``jacobian``) rates the handle.  A sample is usable where 1/kappa(J_w) >= ``conditioning``.
    """
    from symkin.analysis import orientations
    from symkin.mechanism.reach import angular_velocity_matrix

    missing = [name for name in ("ik", "jacobian", "mass_matrix") if name not in model.functions]
    if missing:
        raise ValueError(f"{model.name}: rating a spherical platform needs its generated {', '.join(missing)} "
                         "(derive it, e.g. --only ik,jacobian,mass_matrix)")
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
    return _Usable(q, points, points, ANGLES, None, J_w, dynamics_at(model, "mass_matrix", q, points))
