"""The measures of a haptic device's handle at sampled poses, from its Jacobian and mass matrix (:mod:`datasheet`).

A handle pushed (J: the translational rows) is rated by the principal masses of (J M^-1 J^T)^-1, the isotropic and
peak force, the position resolution and, with joint friction, the Coulomb friction felt, the least damping and the
stiffest passive wall (Colgate-Brown; along each axis also with the encoders' quantization, Abbott-Okamura); a
handle turned (J_w) by the same in inertias, torques and angles.  The
actuators' data (:class:`Actuation`) come from the manifest or the caller.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin.rating import forces, formulas
from symkin import mechanism
from symkin.runtime.info import GeneratedModel


@dataclass(frozen=True)
class Measure:
    """One row of the datasheet: a name, its unit, its value at every sample and whether its worst value
    is its smallest (a force) or its largest (a mass, a resolution step); ``axis``: the task axis a figure along one
    axis is taken along (a vendor's per-axis figure), None for one over every direction."""

    name: str
    unit: str
    values: np.ndarray
    worst_is_min: bool
    doc: str
    axis: str | None = None


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

    def fingerprint(self) -> tuple[Any, ...]:
        """The data as a hashable value, equal for equal data (the key of a compiled program that closes over them)."""
        return tuple(None if value is None else (np.shape(value), np.asarray(value, dtype=float).tobytes())
                     for value in (self.effort_limits, self.continuous_limits, self.joint_steps, self.coulomb,
                                   self.viscous)) + (float(self.period),)

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


class SharedFactors:
    """The factorizations that several measures of one handle take, each formed once, when first asked for: J^-T of a
    square J (:func:`symkin.rating.formulas.inverse_transpose`: the peak force, the friction felt, along each axis
    and the damping take it; an SVD for its conditioning and an inverse per sample) and the mobility J M^-1 J^T (the
    principal and the per-axis masses)."""

    def __init__(self, J: Any, M: Any, xp: Any) -> None:
        self.J, self.M, self.xp = J, M, xp

    @functools.cached_property
    def inverse_transpose(self) -> Any:
        """J^-T, or None for a J with more joints than rows (the formulas take their redundant path)."""
        return formulas.inverse_transpose(self.J, self.xp) if self.J.shape[-2] == self.J.shape[-1] else None

    @functools.cached_property
    def mobility(self) -> Any:
        """J M^-1 J^T."""
        return formulas.mobility(self.M, self.J, self.xp)


def dynamics_at(model: GeneratedModel, name: str, q: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """A generated dynamics function at the samples (q, p), fed the inputs it declares (:func:`symkin.mechanism.call`)."""
    return mechanism.call(model, name, q=q, p=poses)


def rotation_measures(J_w: np.ndarray, M: np.ndarray | None, actuation: Actuation, *, no_mass: str = "",
                      xp: Any = np, factors: SharedFactors | None = None) -> tuple[tuple[Measure, ...], dict[str, str]]:
    """A rotating handle's inertia felt with its position free (where M is given, else not rated with the reason
    ``no_mass``), torque capability and angular resolution (:data:`TURNED_GROUPS`), and {group: why not rated}; in
    the array module ``xp`` (:mod:`symkin.rating.formulas`); ``factors``: J_w's, where the caller shares them with
    other measures (:func:`friction_measures`)."""
    out: list[Measure] = []
    skipped = {}
    factors = factors or SharedFactors(J_w, M, xp)
    if M is None:
        skipped["apparent_inertia"] = no_mass
    else:
        inertias = formulas.principal_masses(M, J_w, xp, handle_mobility=factors.mobility)
        out += [Measure("apparent_inertia_min", "kg m^2", inertias[:, 0], False,
                        "smallest principal inertia felt turning the handle (its position free)"),
                Measure("apparent_inertia_max", "kg m^2", inertias[:, -1], False,
                        "largest principal inertia felt turning the handle (its position free)")]
    if actuation.effort_limits is None:
        skipped["torque"] = NO_EFFORT_LIMITS
    else:
        out += [Measure("isotropic_torque", "N m", forces.isotropic_force(J_w, actuation.effort_limits, xp), True,
                        "largest torque rendered about every axis, with no force (peak efforts)"),
                Measure("peak_torque", "N m", formulas.peak_force(J_w, actuation.effort_limits, xp,
                                                                  inverse_transpose=factors.inverse_transpose), True,
                        "largest torque rendered about the best axis, with no force (peak efforts)")]
    if actuation.continuous_limits is None:
        skipped["continuous_torque"] = NO_CONTINUOUS_LIMITS
    else:
        out.append(Measure("continuous_torque", "N m", forces.isotropic_force(J_w, actuation.continuous_limits, xp), True,
                           "largest torque held for long about every axis (continuous efforts)"))
    if actuation.joint_steps is None:
        skipped["angular_resolution"] = NO_ENCODERS
    else:
        out.append(Measure("angular_resolution", "rad", formulas.position_resolution(J_w, actuation.joint_steps, xp), False,
                           "largest handle rotation between neighbouring encoder readings"))
    return tuple(out), skipped


def translation_measures(model: GeneratedModel, J: np.ndarray, M: np.ndarray | None, q: np.ndarray, poses: np.ndarray,
                         actuation: Actuation, axes: Sequence[str], *, no_mass: str = "",
                         G: np.ndarray | str | None = None, xp: Any = np) -> tuple[tuple[Measure, ...], dict[str, str]]:
    """The handle's measures (:func:`pushed_groups` of ``axes``, J's rows) from J (its translational rows), M and the
    generated functions at (q, poses), and {group: why not rated}; where M is None, the apparent mass is not rated
    with the reason ``no_mass``.  ``G``: the efforts that hold the device (N, n), or why there are none (default:
    the generated ``gravity_vector``).  Besides the measures over every direction, each group holds its figure
    along each task axis, as a vendor's datasheet quotes it (issue 64).  ``xp``: the array module of J, M and G."""
    if len(axes) != J.shape[-2]:
        raise ValueError(f"{model.name}: {len(axes)} task axes {list(axes)} for the {J.shape[-2]} rows of J")
    out: list[Measure] = []
    skipped = {}
    factors = SharedFactors(J, M, xp)

    def per_axis(name: str, unit: str, values: np.ndarray, worst_is_min: bool, doc: str) -> list[Measure]:
        return [Measure(f"{name}_{axis}", unit, values[:, k], worst_is_min, doc.replace("<axis>", axis), axis)
                for k, axis in enumerate(axes)]

    if M is None:
        skipped["apparent_mass"] = no_mass
    else:
        masses = formulas.principal_masses(M, J, xp, handle_mobility=factors.mobility)
        out += [Measure("apparent_mass_min", "kg", masses[:, 0], False, "smallest principal mass felt at the handle"),
                Measure("apparent_mass_max", "kg", masses[:, -1], False, "largest principal mass felt at the handle"),
                Measure("inertia_isotropy", "", masses[:, -1] / masses[:, 0], False,
                        "largest over smallest principal mass (1: the same mass in every direction)")]
        out += per_axis("apparent_mass", "kg", formulas.axis_mass(M, J, xp, handle_mobility=factors.mobility), False,
                        "mass felt pushing along <axis> from rest, the handle free in the other directions: "
                        "1 / (e^T J M^-1 J^T e)")
    efforts = actuation.effort_limits
    if efforts is None:
        skipped["force"] = skipped["gravity_share"] = NO_EFFORT_LIMITS
    else:
        out += [Measure("isotropic_force", "N", forces.isotropic_force(J, efforts, xp), True,
                        "largest force rendered in every direction (peak efforts)"),
                Measure("peak_force", "N", formulas.peak_force(J, efforts, xp,
                                                               inverse_transpose=factors.inverse_transpose), True,
                        "largest force rendered in the best direction (peak efforts)")]
        out += per_axis("force", "N", forces.axis_force(J, efforts, xp), True,
                        "largest force rendered along +-<axis> (peak efforts): min_i tau_max,i / |J_i . e|")
        share = (gravity_share_measure(model, q, poses, efforts, xp) if G is None
                 else G if isinstance(G, str) else [held_against_gravity(G, efforts, xp)])
        if isinstance(share, str):
            skipped["gravity_share"] = share
        else:
            out += share
    if actuation.continuous_limits is None:
        skipped["continuous_force"] = NO_CONTINUOUS_LIMITS
    else:
        out.append(Measure("continuous_force", "N", forces.isotropic_force(J, actuation.continuous_limits, xp), True,
                           "largest force held for long in every direction (continuous efforts)"))
        out += per_axis("continuous_force", "N", forces.axis_force(J, actuation.continuous_limits, xp), True,
                        "largest force held for long along +-<axis> (continuous efforts)")
    if actuation.joint_steps is None:
        skipped["resolution"] = NO_ENCODERS
    else:
        out.append(Measure("resolution", "m", formulas.position_resolution(J, actuation.joint_steps, xp), False,
                           "largest handle step between neighbouring encoder readings"))
        out += per_axis("resolution", "m", formulas.axis_step(J, actuation.joint_steps, xp), False,
                        "handle step along <axis> for one encoder count of the joint that moves it most there")
    friction = (friction_measures(J, actuation, TRANSLATIONAL_FRICTION, xp, factors) if J.shape[-2] <= J.shape[-1]
                else "friction and damping at the handle need at least as many joints as task translations")
    viscous, coulomb = actuation.viscous, actuation.coulomb
    if isinstance(friction, str) or viscous is None or coulomb is None:
        skipped["friction"] = skipped["passive_stiffness"] = str(friction)
    else:
        rate = f"{1 / actuation.period:g} Hz"
        sampled = formulas.renderable_stiffness(formulas.axis_damping(J, viscous, xp), actuation.period, xp=xp)
        out += friction + per_axis("renderable_stiffness", "N/m", sampled, True,
                                   f"stiffest passive wall normal to <axis> at {rate} (Colgate-Brown): 2 b_e / T, "
                                   "b_e = 1 / (e^T J B^-1 J^T e) the least damping of a motion along <axis>")
        if actuation.joint_steps is None:
            skipped["passive_stiffness"] = NO_ENCODERS
        else:
            quantized = formulas.quantization_stiffness(formulas.axis_slip_friction(J, coulomb, xp),
                                                        formulas.axis_quantization(J, actuation.joint_steps, xp), xp)
            out += per_axis("quantization_stiffness", "N/m", quantized, True,
                            "stiffest wall normal to <axis> whose one-count limit cycle Coulomb friction dissipates: "
                            "2 f_e / Delta_e, f_e = min_i tau_c,i / |J_ei|, Delta_e = sum_i |J_ei| dq_i")
            out += per_axis("passive_stiffness", "N/m", xp.minimum(sampled, quantized), True,
                            f"stiffest passive wall normal to <axis> at {rate} with its encoders (Abbott and Okamura "
                            "2005): min(2 b_e / T, 2 f_e / Delta_e)")
    if actuation.coulomb is None:
        skipped["backdrive_friction"] = "no joint friction declared (friction: in the model file)"
    elif J.shape[-2] != J.shape[-1]:
        skipped["backdrive_friction"] = (f"the friction along each axis needs as many joints as task translations "
                                         f"({J.shape[-1]} joints, {J.shape[-2]} translations)")
    else:
        out += per_axis("backdrive_friction", "N", formulas.axis_friction(J, actuation.coulomb, xp,
                                                                          inverse_transpose=factors.inverse_transpose),
                        False,
                        "Coulomb friction felt moving the handle along <axis>: sum_i tau_c,i |(J^-1 e)_i|")
    return tuple(out), skipped


#: Why a datasheet has no gravity share: the model declares no gravity (its gravity terms are identically zero).
NO_GRAVITY = "no gravity acts on the device: declare 'gravity: [0, 0, -9.81]' (the direction of g in the base frame)"


def gravity_share_measure(model: GeneratedModel, q: np.ndarray, poses: np.ndarray, efforts: np.ndarray | None,
                          xp: Any = np) -> list[Measure] | str:
    """The share of the effort limits spent holding the device against gravity (``gravity_vector``), or why not."""
    if efforts is None:
        return NO_EFFORT_LIMITS
    if "gravity_vector" not in model.functions:
        return NO_GRAVITY
    return [held_against_gravity(dynamics_at(model, "gravity_vector", q, poses), efforts, xp)]


def held_against_gravity(G: np.ndarray, efforts: np.ndarray, xp: Any = np) -> Measure:
    """The gravity share of the efforts G (N, n) that hold the device still."""
    return Measure("gravity_share", "", formulas.gravity_share(G, efforts, xp), False,
                   "largest share of an effort limit spent holding the device against gravity")


#: (name, unit, doc) of the friction measures of a handle pushed (J: translational rows) and of one turned (J_w).
TRANSLATIONAL_FRICTION = (("coulomb_friction", "N", "largest Coulomb friction felt at the handle, over the directions "
                                                   "of motion"),
                          ("handle_damping", "N s/m", "least viscous damping at the handle"),
                          ("renderable_stiffness", "N/m", "stiffest passive virtual wall"))
ROTATIONAL_FRICTION = (("coulomb_torque", "N m", "largest Coulomb friction torque felt turning the handle, over the "
                                                 "axes of rotation"),
                       ("handle_damping", "N m s/rad", "least viscous damping turning the handle"),
                       ("renderable_stiffness", "N m/rad", "stiffest passive rotational virtual wall"))


def pushed_groups(axes: Sequence[str]) -> dict[str, tuple[str, ...]]:
    """Every measure of a handle pushed along ``axes``, by group (:class:`symkin.rating.datasheet.Datasheet` checks
    that each group is rated whole, or listed as not rated with what to give)."""
    def along(name: str) -> tuple[str, ...]:
        return tuple(f"{name}_{axis}" for axis in axes)

    return {"apparent_mass": ("apparent_mass_min", "apparent_mass_max", "inertia_isotropy") + along("apparent_mass"),
            "force": ("isotropic_force", "peak_force") + along("force"),
            "continuous_force": ("continuous_force",) + along("continuous_force"),
            "gravity_share": ("gravity_share",),
            "resolution": ("resolution",) + along("resolution"),
            "friction": tuple(name for name, _, _ in TRANSLATIONAL_FRICTION) + along("renderable_stiffness"),
            "passive_stiffness": along("quantization_stiffness") + along("passive_stiffness"),
            "backdrive_friction": along("backdrive_friction")}


#: The groups of a handle pushed, an axis written <axis> (``symkin rate --help``).
PUSHED_GROUPS = pushed_groups(("<axis>",))
#: Every measure of a handle turned with its position free (a rotating platform's), by group.
TURNED_GROUPS: dict[str, tuple[str, ...]] = {
    "apparent_inertia": ("apparent_inertia_min", "apparent_inertia_max"),
    "torque": ("isotropic_torque", "peak_torque"),
    "continuous_torque": ("continuous_torque",),
    "angular_resolution": ("angular_resolution",)}
#: Every measure of a spherical platform's handle (turned only): its torques, gravity share and rotational friction.
SPHERICAL_GROUPS: dict[str, tuple[str, ...]] = {**TURNED_GROUPS, "gravity_share": ("gravity_share",),
                                                 "friction": tuple(name for name, _, _ in ROTATIONAL_FRICTION)}

#: Why a measure is not rated, for the data it needs.
NO_EFFORT_LIMITS = "no effort limits: declare effort_limit per joint or give --effort-limit"
NO_CONTINUOUS_LIMITS = ("no continuous efforts: declare each drive's continuous current and torque constant "
                        "(actuators: {JOINT: {continuous_current: ..., torque_constant: ...}})")
NO_ENCODERS = "no encoder data: give --encoder COUNTS[,...] (and --gear)"


def friction_measures(J: np.ndarray, actuation: Actuation, labels: tuple[tuple[str, str, str], ...], xp: Any = np,
                      factors: SharedFactors | None = None) -> list[Measure] | str:
    """The Coulomb friction felt, the least damping and the stiffest passive wall at the servo rate (Colgate-Brown)
    through J (square, or with more joints than rows: :mod:`symkin.rating.formulas`), labelled by ``labels``; or
    why not (no joint friction declared)."""
    if actuation.coulomb is None or actuation.viscous is None:
        return "no joint friction declared (friction: in the model file)"
    (coulomb, coulomb_unit, coulomb_doc), (damped, damping_unit, damping_doc), (wall, wall_unit, wall_doc) = labels
    inverse_transpose = (factors or SharedFactors(J, None, xp)).inverse_transpose
    damping = formulas.handle_damping(J, actuation.viscous, xp, inverse_transpose=inverse_transpose)
    felt = formulas.coulomb_friction_felt(J, actuation.coulomb, xp, inverse_transpose=inverse_transpose)
    return [Measure(coulomb, coulomb_unit, felt, False, coulomb_doc),
            Measure(damped, damping_unit, damping, True, damping_doc),
            Measure(wall, wall_unit, formulas.renderable_stiffness(damping, actuation.period, xp=xp), True,
                    f"{wall_doc} at {1 / actuation.period:g} Hz (Colgate-Brown, K < 2 b / T)")]
