"""What to optimize: free design parameters with bounds, the objective, the required workspace box.

Seed sec. 4.1, steps 1 and 2 of dimensioning: "definition of parameters and their span of
values (e.g. rod lengths)" and "analytical or numerical description of the optimization
problem".  :func:`design_problem` checks every choice against the loaded model and says
what to change when one does not fit (``ValueError``); nothing is evaluated here.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from symkin import mechanism
from symkin.rating.handle_measures import Actuation
from symkin.analysis.needs import needs_of
from symkin.mechanism import Sampling, reach
from symkin.runtime.info import GeneratedModel

#: What can be maximized: the GCI, the workspace measure, the isotropic force at the worst point of the box.
OBJECTIVES = ("gci", "workspace", "force")

#: Default span of a free parameter without --bounds: from start / SPAN to start * SPAN.
SPAN = 2.0


@dataclass(frozen=True)
class FreeParameter:
    """A design parameter the optimizer varies, within [lower, upper], starting at ``start``."""

    name: str
    start: float
    lower: float
    upper: float

    @property
    def scale(self) -> float:
        """The optimizer works on value / scale (order 1)."""
        return abs(self.start) if self.start != 0 else self.upper - self.lower


@dataclass(frozen=True)
class DesignProblem:
    """A dimensioning problem on one model.

    Attributes:
        objective: ``gci`` (the smooth surrogate of seed eq. 8.28) or ``workspace``.
        free: the free parameters.
        values: values of every other parameter of the model (defaults, or --set).
        sampling: how the model is sampled (:func:`symkin.mechanism.sampling`): its joint box (the GCI's domain),
            or the required box of task coordinates, each point reached through the closed-form ik
            (``INVERSE``), with its assembly (q, s) as variables of the program (``CONTINUATION``: no closed forms;
            its box is one of positions at the home pose's angles), or a spherical platform's orientations
            (``ORIENTATIONS``: the GCI with the invariant measure of SO(3), :mod:`symkin.analysis.orientations`).
        limits: joint limits (n, 2): of a serial model the GCI's integration domain; of a
            parallel model the range of its actuated joints (None: unlimited).
        box: the required workspace box (lower, upper) over the task's position axes [m], or a
            spherical platform's roll, pitch and yaw [rad]; or None.
        margin: the box is required with this clearance on every side (in the box's unit).
        length: characteristic length of a mixed translation/rotation task [m], or None.
        effort_limits: the actuators' effort limits tau_max (N m or N) of the ``force`` objective, else None.
        max_apparent_mass: the largest apparent mass the handle may have (kg): every eigenvalue of
            (J M^-1 J^T)^-1 at every point of the required box at most this (a parallel model whose handle
            translates), else None.
        orientation: a platform that translates and rotates (a Stewart-Gough platform): the constant orientation
            (roll, pitch, yaw in rad, its home pose's) its box of positions is required at, as ``symkin gci`` rates
            it (:class:`symkin.mechanism.reach.ConstantOrientation`); else None.
    """

    objective: str
    free: tuple[FreeParameter, ...]
    values: Mapping[str, float]
    sampling: Sampling
    limits: np.ndarray | None
    box: tuple[np.ndarray, np.ndarray] | None
    margin: float
    length: float | None
    effort_limits: np.ndarray | None = None
    max_apparent_mass: float | None = None
    orientation: np.ndarray | None = None

    @property
    def held_inverse_scaling(self) -> np.ndarray:
        """D with J_h^-1 = J^-1 D for a platform held at :attr:`orientation`: its twist Jacobian J_t = diag(I, E)
        (J^-1)^-1 (E the angular-velocity matrix of the roll-pitch-yaw rates) with the position rows divided by the
        characteristic length L, J_h = diag(I / L, I) J_t, so D = diag(L I, E^-1) and kappa_F(J_h) = kappa_F(J^-1 D)
        from the generated J^-1 without inverting it."""
        assert self.orientation is not None and self.length is not None
        scaling = np.zeros((6, 6))
        scaling[:3, :3] = self.length * np.eye(3)
        scaling[3:, 3:] = np.linalg.inv(reach.angular_velocity_matrix(self.orientation))
        return scaling

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.free)

    def design(self, free_values: Sequence[float]) -> dict[str, float]:
        """All parameter values of a design given the free ones (in the order of ``free``)."""
        return {**self.values, **{p.name: float(v) for p, v in zip(self.free, free_values)}}

    @property
    def scales(self) -> np.ndarray:
        """The free parameters' scales: an optimizer without CasADi's own scaling works on z = value / scale."""
        return np.array([p.scale for p in self.free])

    @property
    def scaled_start(self) -> np.ndarray:
        """The start design's free values in z = value / scale."""
        return np.array([p.start / p.scale for p in self.free])

    @property
    def scaled_bounds(self) -> list[tuple[float, float]]:
        """The free parameters' bounds in z = value / scale."""
        return [(p.lower / p.scale, p.upper / p.scale) for p in self.free]

    def design_at(self, z: np.ndarray) -> dict[str, float]:
        """:meth:`design` of the scaled free values z, each within its bounds (z * scale may round past one)."""
        lower, upper = np.array([p.lower for p in self.free]), np.array([p.upper for p in self.free])
        return self.design(list(np.clip(np.asarray(z) * self.scales, lower, upper)))

    @property
    def joint_limits(self) -> np.ndarray:
        """The joint limits (n, 2); a model sampled in its joint box always has them (ValueError for an unlimited
        one sampled in its task space)."""
        if self.limits is None:
            raise ValueError("this design problem has no joint limits (a parallel model's unlimited actuators)")
        return self.limits

    @property
    def required_box(self) -> tuple[np.ndarray, np.ndarray]:
        """The required workspace box (lower, upper) (ValueError when none is required)."""
        if self.box is None:
            raise ValueError("this design problem requires no workspace box (--require-box)")
        return self.box

    @property
    def start(self) -> dict[str, float]:
        return self.design([p.start for p in self.free])

    @property
    def inflated_box(self) -> tuple[np.ndarray, np.ndarray]:
        """The required box grown by the margin on every side."""
        assert self.box is not None
        return self.box[0] - self.margin, self.box[1] + self.margin


def _parameter_inputs(model: GeneratedModel, functions: Sequence[str]) -> set[str]:
    generated = model.info.functions
    missing = [name for name in functions if name not in generated]
    if missing:
        raise ValueError(f"{model.name}: the generated code has no {', '.join(missing)}; derive the model with "
                         f"--only {','.join(functions)} --backend numpy,casadi")
    return {parameter for name in functions for parameter in generated[name].parameters}


def _irrelevant(model: GeneratedModel, name: str, relevant: list[str]) -> str:
    """Why ``name`` cannot be optimized: the objective's functions do not take it; which free parameters they
    take, or that they take none (a spherical mechanism's kinematics, say, depend on its angles, not its radii)."""
    head = f"{model.name}: the objective does not depend on '{name}' (it is no input of the kinematics); "
    if relevant:
        return head + f"free parameters that matter: {', '.join(relevant)}"
    return head + ("no free parameter of the model is: declare a parameter that shapes the kinematics (a length "
                   "or an angle the joints' placement uses) and derive the model again to optimize it")


def _free_parameters(model: GeneratedModel, free: Sequence[str], bounds: Mapping[str, tuple[float, float]],
                     values: Mapping[str, float], used: set[str]) -> tuple[FreeParameter, ...]:
    known = sorted(model.parameters)
    if not free:
        raise ValueError(f"{model.name}: name the parameters to optimize with --free (parameters: {', '.join(known)})")
    result = []
    for name in free:
        if name not in model.parameters:
            raise ValueError(f"{model.name}: '{name}' is not a free parameter of the model; parameters: "
                             f"{', '.join(known)} (parameters fixed at derivation cannot be optimized)")
        if name not in used:
            raise ValueError(_irrelevant(model, name, sorted(used & set(known))))
        start = float(values.get(name, model.parameters[name]))
        if name in bounds:
            lower, upper = bounds[name]
        elif start != 0:
            lower, upper = sorted((start / SPAN, start * SPAN))
        else:
            raise ValueError(f"{model.name}: '{name}' starts at {start:g}, so no default span applies; "
                             f"give --bounds {name}=LOWER:UPPER")
        if not (np.isfinite(lower) and np.isfinite(upper) and lower < upper):
            raise ValueError(f"--bounds {name}={lower:g}:{upper:g}: need finite LOWER < UPPER")
        result.append(FreeParameter(name, float(np.clip(start, lower, upper)), float(lower), float(upper)))
    if len(set(free)) != len(free):
        raise ValueError(f"--free names a parameter twice: {', '.join(free)}")
    stray = sorted(set(bounds) - set(free))
    if stray:
        raise ValueError(f"--bounds for {', '.join(stray)}, which is not among the free parameters "
                         f"({', '.join(free)})")
    return tuple(result)


def box_axes(model: GeneratedModel) -> tuple[str, ...]:
    """The axes of the required box: the task's position axes, or a spherical platform's roll, pitch, yaw."""
    if mechanism.turns_only(model):
        return mechanism.ANGLES
    return tuple("xyz"[a] for a in mechanism.position_axes(model))


def _box(model: GeneratedModel, box: Mapping[str, tuple[float, float]] | None) -> tuple[np.ndarray, np.ndarray] | None:
    if box is None:
        return None
    axes = box_axes(model)
    unknown = sorted(set(box) - set(axes))
    missing = [a for a in axes if a not in box]
    if unknown or missing:
        raise ValueError(f"{model.name}: the required box needs exactly the axes {', '.join(axes)} of the task "
                         f"space (as {','.join(f'{a}=LOWER:UPPER' for a in axes)}); "
                         + (f"unknown: {', '.join(unknown)}" if unknown else f"missing: {', '.join(missing)}"))
    lower = np.array([box[a][0] for a in axes], dtype=np.float64)
    upper = np.array([box[a][1] for a in axes], dtype=np.float64)
    if not np.all(np.isfinite(lower) & np.isfinite(upper) & (lower < upper)):
        raise ValueError(f"{model.name}: every side of the required box needs finite LOWER < UPPER")
    if axes == mechanism.ANGLES and not (-np.pi / 2 < lower[1] and upper[1] < np.pi / 2):
        raise ValueError(f"{model.name}: the pitch of the required box must lie within (-90 deg, 90 deg), the chart "
                         "of the roll-pitch-yaw angles (at +-90 deg roll and yaw turn about one axis)")
    return lower, upper


#: The generated function an apparent-mass constraint evaluates besides ``NEEDS["design"]``.
APPARENT_MASS_FUNCTIONS = ("mass_matrix",)


def _apparent_mass(model: GeneratedModel, max_apparent_mass: float | None) -> float | None:
    """The apparent-mass bound (kg), after checking that it applies to the model (a parallel model's required box
    is checked with its objective)."""
    if max_apparent_mass is None:
        return None
    what = ("the apparent-mass bound is a constraint at the points of the required box of a parallel mechanism whose "
            "handle translates (the masses felt at the handle, in kg)")
    if mechanism.sampling(model) is Sampling.JOINTS:
        raise ValueError(f"{model.name}: {what}; rate a serial arm's apparent mass with 'symkin rate'")
    if not mechanism.is_positional(model):
        raise ValueError(f"{model.name}: {what}, and this handle turns (task space {list(mechanism.task_space(model))}: "
                         "the masses and inertias it feels mix kg with kg m^2); leave the bound out")
    if not (np.isfinite(max_apparent_mass) and max_apparent_mass > 0):
        raise ValueError(f"the apparent-mass bound must be a positive mass in kg, got {max_apparent_mass:g}")
    return float(max_apparent_mass)


def _effort_limits(model: GeneratedModel, objective: str, effort_limits: Sequence[float] | None,
                   box: tuple[np.ndarray, np.ndarray] | None) -> np.ndarray | None:
    """The effort limits of the ``force`` objective (declared, or given), after checking that it applies."""
    if objective != "force":
        if effort_limits is not None:
            raise ValueError("effort limits belong to the force objective (--maximize force)")
        return None
    if not mechanism.is_positional(model):
        raise ValueError(f"{model.name}: the force objective rates a handle that translates (the isotropic force in "
                         f"N), and the task space {list(mechanism.task_space(model))} is not one of positions only")
    if box is None:
        axes = box_axes(model)
        raise ValueError(f"{model.name}: the force objective is the isotropic force at the worst point of the required "
                         f"box: give --require-box {','.join(f'{a}=LOWER:UPPER' for a in axes)} (in m)")
    names = mechanism.coordinate_names(model)
    limits = Actuation.of_model(model, effort_limits=effort_limits).effort_limits  # declared, or given
    if limits is None:
        raise ValueError(f"{model.name}: the force objective needs the actuators' effort limits, and the model "
                         "declares none for some of them: give --effort-limit T (one value, or one per actuator)")
    if limits.shape != (len(names),) or not np.all(np.isfinite(limits) & (limits > 0)):
        raise ValueError(f"{model.name}: the force objective needs one positive effort limit per actuator "
                         f"({', '.join(names)}), got {list(limits)}")
    return limits


def design_problem(model: GeneratedModel, objective: str, free: Sequence[str], *,
                   bounds: Mapping[str, tuple[float, float]] | None = None,
                   values: Mapping[str, float] | None = None,
                   box: Mapping[str, tuple[float, float]] | None = None, margin: float = 0.0,
                   limits: mechanism.Limits | None = None, length: float | None = None,
                   effort_limits: Sequence[float] | None = None,
                   max_apparent_mass: float | None = None,
                   orientation: Sequence[float] | None = None) -> DesignProblem:
    """Check a dimensioning problem against a loaded model and describe it.

    Args:
        model: the loaded model (any backend; only its manifest is read).
        objective: ``gci``, ``workspace`` or ``force`` (the isotropic force of
            :func:`symkin.rating.forces.isotropic_force` at the worst point of the required box).
        free: names of the parameters to optimize.
        bounds: {name: (lower, upper)}; default from start / 2 to 2 start (a start of 0 needs bounds).
        values: parameter values instead of the defaults (also the start of free ones).
        box: the required workspace box {axis: (lower, upper)} over the task's position
            axes (x, y, z) in m, or a spherical platform's roll, pitch, yaw in rad; required for
            parallel models, whose GCI is taken over it.
        margin: clearance of the box (m, or rad for orientations).
        limits: joint-limit overrides.
        length: characteristic length [m] of a task space mixing translations and rotations.
        effort_limits: the actuators' effort limits of the force objective (default: the model's).
        max_apparent_mass: a bound (kg) on the apparent mass at the handle over the required box (a
            constraint of a parallel model whose handle translates; the model needs its mass_matrix).
        orientation: a platform that translates and rotates: the constant orientation (roll, pitch, yaw in rad) of
            its box of positions (default: its home pose's).

    Raises:
        ValueError: an unknown or irrelevant parameter, bad bounds, a malformed box, or a
            case that is not supported (the message says which and what to do).
    """
    if objective not in OBJECTIVES:
        raise ValueError(f"unknown objective '{objective}'; choose one of {', '.join(OBJECTIVES)}")
    sampled = mechanism.sampling(model)
    values = dict(values or {})
    unknown = sorted(set(values) - set(model.parameters))
    if unknown:
        raise ValueError(f"{model.name}: not parameters of the model: {', '.join(unknown)}; "
                         f"parameters: {', '.join(sorted(model.parameters))}")
    held_orientation = _held_orientation(model, orientation)
    if sampled is Sampling.CONTINUATION and (objective == "force" or max_apparent_mass is not None):
        raise ValueError(f"{model.name}: its legs have no closed-form inverse kinematics; their dimensioning "
                         "maximizes the GCI over the required box (--maximize gci), without force objectives or "
                         "apparent-mass bounds (their dynamics are not part of the dimensioning yet)")
    bound = _apparent_mass(model, max_apparent_mass)  # before asking for mass_matrix: a serial model is told why
    needed = needs_of("design", model)
    used = _parameter_inputs(model, needed + (APPARENT_MASS_FUNCTIONS if bound is not None else ()))
    free_parameters = _free_parameters(model, list(free), dict(bounds or {}), values, used)
    required = _box(model, box)
    if not margin >= 0:
        raise ValueError(f"the box margin must be >= 0, got {margin}")
    task = mechanism.task_space(model)
    n = len(mechanism.coordinate_names(model))
    if mechanism.mixes_translations_and_rotations(model):
        if length is None:
            raise ValueError(f"{model.name}: the task space {list(task)} mixes translations and rotations, so "
                             "1/kappa compares metres with radians: give a characteristic length (--length L in m)")
        if not length > 0:
            raise ValueError(f"the characteristic length must be positive, got {length}")
    else:
        length = None
    if len(task) != n:
        raise ValueError(f"{model.name}: the task Jacobian is {len(task)} x {n}; dimensioning needs a square one "
                         "(the Cartesian measure |det J| dq and kappa_F of J^-1)")
    if sampled is not Sampling.JOINTS:
        if objective == "workspace":
            raise ValueError(f"{model.name}: maximizing the workspace of a parallel mechanism is not supported "
                             "(its workspace has no joint-space parametrization here); maximize the GCI over a "
                             "required box instead (--maximize gci --require-box ...)")
        spherical = sampled is Sampling.ORIENTATIONS
        if required is None:
            axes = box_axes(model)
            unit = "in rad, or with 'deg'" if spherical else "in m"
            what = {"gci": "GCI", "force": "worst-case force"}.get(objective, objective)
            raise ValueError(f"{model.name}: the {what} of a parallel mechanism is taken over the required workspace "
                             f"box: give --require-box {','.join(f'{a}=LOWER:UPPER' for a in axes)} ({unit})")
        if sampled is Sampling.INVERSE and held_orientation is None and len(mechanism.position_rows(model)) != len(task):
            raise ValueError(f"{model.name}: the task space {list(task)} mixes positions and orientations; the GCI "
                             "of a parallel mechanism is taken over a box of TCP positions (such as the DELTA's), of "
                             "a platform's positions at its home orientation (x, y, z, roll, pitch, yaw: a "
                             "Stewart-Gough platform's) or of a spherical platform's orientations (roll, pitch, yaw), "
                             "not over a box of both")
        declared = np.array(model.joint_limits, dtype=np.float64)
        joint_box = mechanism.joint_limits(model, limits) if limits or np.isfinite(declared).any() else None
    else:
        joint_box = mechanism.joint_limits(model, limits)
    fixed = {k: float(v) for k, v in {**model.parameters, **values}.items()
             if k in used and k not in {p.name for p in free_parameters}}
    return DesignProblem(objective, free_parameters, fixed, sampled, joint_box, required, float(margin), length,
                         _effort_limits(model, objective, effort_limits, required), bound, held_orientation)


def _held_orientation(model: GeneratedModel, angles: Sequence[float] | None) -> np.ndarray | None:
    """The constant orientation (``angles``, default its home pose's) a platform that translates and rotates (task
    space x, y, z, roll, pitch, yaw, closed-form ik) is dimensioned at over a box of positions, else None.

    Raises:
        ValueError: angles for another model, or not three finite angles away from pitch = +-90 deg.
    """
    if (mechanism.sampling(model) is Sampling.INVERSE and tuple(mechanism.task_space(model))
            == (*mechanism.POSITION_COMPONENTS, *mechanism.ANGLES)):
        return reach.constant_orientation(model, angles).orientation
    if angles is not None:
        raise ValueError(f"--orientation: {model.name} is not a platform that translates and rotates with a "
                         f"closed-form ik (task space {list(mechanism.task_space(model))}); leave the option out")
    return None


def held(problem: DesignProblem, model: GeneratedModel) -> GeneratedModel:
    """``model`` as the problem rates it: a platform that translates and rotates held at the problem's constant
    orientation (:func:`symkin.mechanism.reach.constant_orientation`: ik and the twist Jacobian of platform
    positions), any other model itself."""
    if problem.orientation is None:
        return model
    return reach.constant_orientation(model, problem.orientation)
