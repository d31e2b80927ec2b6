"""The measures of a haptic device's handle at sampled poses, from its Jacobian and mass matrix (:mod:`datasheet`).

A handle pushed (J: the translational rows) is rated by the principal masses of (J M^-1 J^T)^-1, the isotropic and
peak force, the position resolution and, with joint friction, the Coulomb friction felt, the least damping and the
stiffest passive wall (Colgate-Brown); a handle turned (J_w) by the same in inertias, torques and angles.  The
actuators' data (:class:`Actuation`) come from the manifest or the caller.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from symkin.analysis import forces, mechanism, rating
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


def dynamics_at(model: GeneratedModel, name: str, q: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """A generated dynamics function at the samples: of q (a serial arm), of (q, p) (a parallel platform)."""
    function = getattr(model, name)
    return function(q, poses) if mechanism.is_parallel(model) else function(q)


def rotation_measures(J_w: np.ndarray, M: np.ndarray | None, actuation: Actuation) -> tuple[Measure, ...]:
    """A rotating handle's inertia felt with its position free (where M is given), torque capability and angular
    resolution."""
    out = []
    if M is not None:
        inertias = rating.principal_masses(M, J_w)
        out += [Measure("apparent_inertia_min", "kg m^2", inertias[:, 0], False,
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


def translation_measures(model: GeneratedModel, J: np.ndarray, M: np.ndarray | None, q: np.ndarray, poses: np.ndarray,
                         actuation: Actuation, *, no_mass: str = "") -> tuple[tuple[Measure, ...], dict[str, str]]:
    """The handle's measures from J (its translational rows), M and the generated functions at (q, poses); where M
    is None, the apparent mass is listed as skipped with the reason ``no_mass``."""
    out: list[Measure] = []
    skipped = {}
    if M is None:
        skipped["apparent_mass"] = no_mass
    else:
        masses = rating.principal_masses(M, J)
        out += [Measure("apparent_mass_min", "kg", masses[:, 0], False, "smallest principal mass felt at the handle"),
                Measure("apparent_mass_max", "kg", masses[:, -1], False, "largest principal mass felt at the handle"),
                Measure("inertia_isotropy", "", masses[:, -1] / masses[:, 0], False,
                        "largest over smallest principal mass (1: the same mass in every direction)")]
    efforts = actuation.effort_limits
    if efforts is None:
        skipped["force"] = "no effort limits: declare effort_limit per joint or give --effort-limit"
    else:
        out += [Measure("isotropic_force", "N", forces.isotropic_force(J, efforts), True,
                        "largest force rendered in every direction (peak efforts)"),
                Measure("peak_force", "N", rating.peak_force(J, efforts), True,
                        "largest force rendered in the best direction (peak efforts)")]
        out += gravity_share_measure(model, q, poses, efforts)
    if actuation.continuous_limits is not None:
        out.append(Measure("continuous_force", "N", forces.isotropic_force(J, actuation.continuous_limits), True,
                           "largest force held for long in every direction (continuous efforts)"))
    if actuation.joint_steps is None:
        skipped["resolution"] = "no encoder data: give --encoder COUNTS[,...] (and --gear)"
    else:
        out.append(Measure("resolution", "m", rating.position_resolution(J, actuation.joint_steps), False,
                           "largest handle step between neighbouring encoder readings"))
    friction = (friction_measures(J, actuation, TRANSLATIONAL_FRICTION) if J.shape[-2] <= J.shape[-1]
                else "friction and damping at the handle need at least as many joints as task translations")
    if isinstance(friction, str):
        skipped["friction"] = friction
    else:
        out += friction
    return tuple(out), skipped


def gravity_share_measure(model: GeneratedModel, q: np.ndarray, poses: np.ndarray, efforts: np.ndarray
                          ) -> list[Measure]:
    """The share of the effort limits spent holding the device against gravity, where ``gravity_vector`` exists."""
    if "gravity_vector" not in model.functions:
        return []
    return [Measure("gravity_share", "", rating.gravity_share(dynamics_at(model, "gravity_vector", q, poses), efforts),
                    False, "largest share of an effort limit spent holding the device against gravity")]


#: (name, unit, doc) of the friction measures of a handle pushed (J: translational rows) and of one turned (J_w).
TRANSLATIONAL_FRICTION = (("coulomb_friction", "N", "largest Coulomb friction felt at the handle, over the directions "
                                                   "of motion"),
                          ("handle_damping", "N s/m", "least viscous damping at the handle"),
                          ("renderable_stiffness", "N/m", "stiffest passive virtual wall"))
ROTATIONAL_FRICTION = (("coulomb_torque", "N m", "largest Coulomb friction torque felt turning the handle, over the "
                                                 "axes of rotation"),
                       ("handle_damping", "N m s/rad", "least viscous damping turning the handle"),
                       ("renderable_stiffness", "N m/rad", "stiffest passive rotational virtual wall"))


def friction_measures(J: np.ndarray, actuation: Actuation, labels: tuple[tuple[str, str, str], ...]
                       ) -> list[Measure] | str:
    """The Coulomb friction felt, the least damping and the stiffest passive wall at the servo rate (Colgate-Brown)
    through J (square, or with more joints than rows: :mod:`symkin.analysis.rating`), labelled by ``labels``; or
    why not (no joint friction declared)."""
    if actuation.coulomb is None or actuation.viscous is None:
        return "no joint friction declared (friction: in the model file)"
    (coulomb, coulomb_unit, coulomb_doc), (damped, damping_unit, damping_doc), (wall, wall_unit, wall_doc) = labels
    damping = rating.handle_damping(J, actuation.viscous)
    return [Measure(coulomb, coulomb_unit, rating.coulomb_friction_felt(J, actuation.coulomb), False, coulomb_doc),
            Measure(damped, damping_unit, damping, True, damping_doc),
            Measure(wall, wall_unit, rating.renderable_stiffness(damping, actuation.period), True,
                    f"{wall_doc} at {1 / actuation.period:g} Hz (Colgate-Brown, K < 2 b / T)")]
