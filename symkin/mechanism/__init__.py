"""The run-time mechanism (issue 62): what every analysis needs to know about a loaded model, below all of them.

A numpy-only layer between the loaded generated code (:mod:`symkin.runtime`) and the analyses, simulation,
design and viewer: they ask it instead of telling mechanisms apart themselves.  This module reads the manifest
(coordinates, joint limits, the kind of mechanism and its task space); :mod:`symkin.mechanism.limits` tests
joint limits, :mod:`symkin.mechanism.passive` closes a parallel mechanism's passive joints (the general closure
solve, :func:`symkin.runtime.parallel.solve_closure`) and checks their limits,
:mod:`symkin.mechanism.working_mode` assembles a mechanism with closed forms in its declared branches,
:mod:`symkin.mechanism.closure` one of any leg topology from its generated closure alone (home assembly,
continuation along the actuators, the dynamics of the actuated joints) and :mod:`symkin.mechanism.casadi_assembly`
its CasADi counterpart (the assembly as a differentiable function of the actuators, for the optimization programs;
the one module here that imports CasADi), :mod:`symkin.mechanism.reach` answers the
Cartesian analyses' questions for every kind (the box around the workspace, reachability through inverse
kinematics, :mod:`symkin.mechanism.feasibility`, a pose platform held at one orientation, the characteristic
length), :mod:`symkin.mechanism.device` views a hybrid device as one mechanism in all its actuated joints, and
:class:`symkin.mechanism.actuated.Mechanism` is the one object of a loaded model in its actuated joints (assembly,
handle, the generated functions bound to them) that the simulation and the identification ask.

The analyses take a :class:`symkin.LoadedModel` (``symkin.load(directory, backend)``):
its generated functions do the arithmetic, its manifest tells the joint types, limits and
task space.  The C backend plugs in by being loaded instead of the numpy one: only
``model.fk`` and ``model.jacobian`` are called, with batches of ``q``.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping, Sequence
from typing import Any
from enum import Enum

import numpy as np

from symkin.runtime.info import GeneratedModel, ModelInfo

#: Task-space components that are TCP coordinates in metres (symkin.kinematics.task_space).
POSITION_COMPONENTS = ("x", "y", "z")

#: Limits assumed for a revolute joint that declares none: one full turn.
DEFAULT_REVOLUTE_LIMITS = (-np.pi, np.pi)

Limits = Sequence[Sequence[float]] | Mapping[str, Sequence[float]] | np.ndarray


def coordinate_names(model: GeneratedModel) -> tuple[str, ...]:
    """Names of the joint coordinates, in the order of ``q``."""
    return model.info.coordinate_names


def revolute_mask(model: GeneratedModel) -> np.ndarray:
    """Boolean array (n,): which coordinates are revolute (angles, periodic)."""
    return np.array([c.revolute for c in model.info.coordinates])


def joint_limits(model: GeneratedModel, limits: Limits | None = None) -> np.ndarray:
    """Joint limits as an array (n, 2) of [lower, upper].

    Args:
        model: a loaded model.
        limits: overrides: an (n, 2) array, or a mapping from coordinate names to
            (lower, upper) for some of them.  Otherwise the limits recorded in the
            manifest (the model file's, evaluated at the parameters' default values) are
            used (``model.joint_limits``); a revolute joint without limits gets one full
            turn [-pi, pi].

    Raises:
        ValueError: a prismatic joint has no limits, or the limits are malformed.
    """
    names = coordinate_names(model)
    coordinates = model.info.coordinates
    if limits is not None and not isinstance(limits, Mapping):
        result = np.array(limits, dtype=np.float64)
        if result.shape != (len(names), 2):
            raise ValueError(f"{model.name}: limits must have shape ({len(names)}, 2), got {result.shape}")
    else:
        overrides = dict(limits or {})
        unknown = set(overrides) - set(names)
        if unknown:
            raise ValueError(f"{model.name}: no coordinates named {sorted(unknown)}; coordinates: {', '.join(names)}")
        rows = []
        for coordinate, declared in zip(coordinates, model.joint_limits):
            bounds = overrides.get(coordinate.name, declared if np.all(np.isfinite(declared)) else None)
            if bounds is None:
                if not coordinate.revolute:
                    raise ValueError(f"{model.name}: prismatic joint '{coordinate.name}' declares no limits; "
                                     "declare them in the model file or pass limits")
                bounds = DEFAULT_REVOLUTE_LIMITS
            rows.append([float(bounds[0]), float(bounds[1])])
        result = np.array(rows)
    bad = [n for n, (lo, hi) in zip(names, result) if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi)]
    if bad:
        raise ValueError(f"{model.name}: limits of {', '.join(bad)} are not finite intervals [lower < upper]")
    return result


def task_space(model: GeneratedModel) -> tuple[str, ...]:
    """Names of the task-space components (rows of ``model.jacobian``)."""
    return model.info.task_space


def position_rows(model: GeneratedModel) -> tuple[int, ...]:
    """Indices of the translational components (x, y, z) among the task-space rows."""
    return tuple(i for i, c in enumerate(task_space(model)) if c in POSITION_COMPONENTS)


def position_axes(model: GeneratedModel) -> tuple[int, ...]:
    """Base-frame axes (0, 1, 2 for x, y, z) of the TCP coordinates that span the workspace.

    A planar arm whose task space is [x, y] has a 2-D workspace; a pose or position task
    space gives a 3-D one.

    Raises:
        ValueError: the task space has no position components.
    """
    axes = tuple(POSITION_COMPONENTS.index(c) for c in task_space(model) if c in POSITION_COMPONENTS)
    if not axes:
        raise ValueError(f"{model.name}: the task space {list(task_space(model))} has no position "
                         "components (x, y, z): there is no positional workspace to analyse")
    return tuple(sorted(axes))


class MechanismKind(str, Enum):
    """How the analyses, the viewer and the commands treat a mechanism: the keys of their tables of generated
    functions (a str, so that a kind prints and serializes as its value)."""

    SERIAL = "serial"
    #: positions only: a translational or planar platform, analysed through its closed-form ik and fk
    PARALLEL = "parallel"
    #: positions and angles: a platform that also rotates, analysed held at a constant orientation
    PARALLEL_POSE = "parallel pose"
    #: angles only: a spherical platform
    PARALLEL_ORIENTATION = "parallel orientation"


def parallel_kind(task: Sequence[str]) -> MechanismKind:
    """The kind of a parallel mechanism with the task coordinates ``task`` (:class:`MechanismKind`)."""
    positions = set(task) & set(POSITION_COMPONENTS)
    if positions == set(task):
        return MechanismKind.PARALLEL
    return MechanismKind.PARALLEL_POSE if positions else MechanismKind.PARALLEL_ORIENTATION


def kind_of(model: GeneratedModel) -> MechanismKind:
    """The kind of a loaded model (:class:`MechanismKind`)."""
    return parallel_kind(task_space(model)) if is_parallel(model) else MechanismKind.SERIAL


#: The task coordinates of a handle that only turns: roll, pitch, yaw (R = Rz(yaw) Ry(pitch) Rx(roll)).
ANGLES = ("roll", "pitch", "yaw")


def turns_only(model: GeneratedModel) -> bool:
    """Whether the handle only turns: a mechanism closing loops whose task coordinates are roll, pitch, yaw (a
    spherical platform such as the Agile Eye), whose workspace is a set of orientations
    (:mod:`symkin.analysis.orientations`) reached through its generated ``ik``."""
    return turns_only_info(model.info)


def turns_only_info(info: ModelInfo) -> bool:
    """:func:`turns_only` of a model's manifest (before its code is loaded)."""
    return info.is_parallel and tuple(info.task_space) == ANGLES


def is_parallel(model: GeneratedModel) -> bool:
    """Whether the loaded model is a parallel mechanism."""
    return model.info.is_parallel


def call(model: GeneratedModel, name: str, **state: np.ndarray) -> Any:
    """The generated function ``name`` at a state of the device, fed the vector inputs its manifest record
    declares, in its order, from ``state`` by name (``q``, ``p``, ``qw``, ``qd``, ...): the one binder, so that an
    analysis passes what it knows (q and the poses) whatever the function of this kind of mechanism takes (an
    open chain's dynamics take q, a platform's q and p).

    Raises:
        ValueError: the function was not generated, or takes an input ``state`` does not hold.
    """
    record = model.info.functions.get(name)
    if record is None:
        raise ValueError(f"{model.name}: the analysis needs the generated '{name}'; derive it (--only {name})")
    missing = [i.name for i in record.vector_inputs if i.name not in state]
    if missing:
        raise ValueError(f"{model.name}: '{name}' takes {', '.join(missing)}, which this analysis does not know")
    return getattr(model, name)(*(state[i.name] for i in record.vector_inputs))


#: The wrist's part of each of a device's joint vectors, by the input that takes the legs' part: a hybrid device's
#: generated functions take ``qw`` after ``q``, ``qwd`` after ``qd``... (:mod:`symkin.parallel.dynamics`).
WRIST_INPUTS = {"q": "qw", "qd": "qwd", "qdd": "qwdd", "tau": "tauw"}


def of_device_joints(model: GeneratedModel, name: str, pose: Callable[[np.ndarray], np.ndarray]
                     ) -> Callable[..., Any]:
    """The generated function ``name`` as a function of the device's joint vectors (q, then qd, qdd or tau as the
    function takes them; each the actuated joints', then a hybrid device's wrist joints'), the one binder of what a
    device records to what a generated function takes: each vector is split into the legs' part and the wrist's
    (:data:`WRIST_INPUTS`), and a function that takes the platform's pose gets ``pose(q)`` of the device's q.  A
    function that takes the joint vectors as they are (an open chain's, a platform's friction) is returned as is.

    Raises:
        ValueError: the function takes the pose but not q.
    """
    function = getattr(model, name)
    inputs = tuple(i.name for i in model.info.functions[name].vector_inputs)
    joint_inputs = [i for i in inputs if i != "p" and i not in WRIST_INPUTS.values()]
    if list(inputs) == joint_inputs and not model.info.wrist:
        return function
    if "p" in inputs and "q" not in joint_inputs:
        raise ValueError(f"{model.name}: '{name}' takes the pose p without q: no joint vector gives it")
    legs = len(model.info.coordinates)

    def of_joints(*vectors: np.ndarray) -> Any:
        values = {}
        for input_name, vector in zip(joint_inputs, vectors, strict=True):
            values[input_name], values[WRIST_INPUTS[input_name]] = vector[..., :legs], vector[..., legs:]
        if "p" in inputs:
            values["p"] = pose(vectors[joint_inputs.index("q")])
        return function(*(values[i] for i in inputs))
    return of_joints


def sampled_in_task_space(model: GeneratedModel) -> bool:
    """Whether the workspace analyses sample the handle's space (a Cartesian grid, reached through inverse
    kinematics) instead of the joint box: so for a mechanism that closes loops, whose joint box also holds
    configurations of other working modes and ones that do not assemble (:mod:`symkin.analysis.study`)."""
    return sampling(model) is not Sampling.JOINTS


class Sampling(str, Enum):
    """How the workspace analyses sample a mechanism (:func:`sampling`): the question they ask instead of its kind."""

    #: the joint box mapped through fk (a mechanism that closes no loops)
    JOINTS = "joints"
    #: a Cartesian grid of the handle's positions reached through the closed-form inverse kinematics
    INVERSE = "inverse"
    #: a Cartesian grid reached by continuing the assembly from the home pose (no closed forms: the general method)
    CONTINUATION = "continuation"
    #: the orientations of a handle that only turns, reached through its inverse kinematics
    ORIENTATIONS = "orientations"


def sampling(model: GeneratedModel) -> Sampling:
    """How the workspace analyses sample ``model`` (:class:`Sampling`): the orientations of a handle that only
    turns; the joint box of a mechanism that closes no loops; a Cartesian grid reached through the inverse
    kinematics where it has a closed form, else by continuing its generated loop closure from the home pose."""
    return sampling_of(model.info, model.functions)


def sampling_of(info: ModelInfo, functions: Collection[str]) -> Sampling:
    """:func:`sampling` of a model's manifest and the names of its generated ``functions``: known before any code is
    loaded (which backend's code to load may hang on it: ``symkin.analysis.model_files.load_for_analysis``)."""
    if turns_only_info(info):
        return Sampling.ORIENTATIONS
    if not info.is_parallel:
        return Sampling.JOINTS
    return Sampling.CONTINUATION if closure_alone(functions) else Sampling.INVERSE


def closure_alone(functions: Collection[str]) -> bool:
    """Whether generated ``functions`` reach the assembly through the loop closure alone: ``closure`` and
    ``closure_jacobians`` but no closed-form ``ik`` (legs without the distance form)."""
    return "ik" not in functions and {"closure", "closure_jacobians"} <= set(functions)


def handle_on_further_joints(model: GeneratedModel) -> bool:
    """Whether joints on the platform carry the handle beyond it (a hybrid device's wrist): the platform's own task
    space is then not the handle's, and the device is rated as a whole (:class:`symkin.mechanism.device.WholeDevice`)."""
    return bool(model.info.wrist)


def home_pose(model: GeneratedModel) -> np.ndarray:
    """The home pose ``parallel.home`` of a parallel mechanism (task coordinates p).

    Raises:
        ValueError: the model declares none (the workspace analyses scale with it).
    """
    home = model.info.home
    if home is None:
        raise ValueError(f"{model.name}: declare a home pose (parallel.home) to scale the workspace analyses")
    return np.array(home, dtype=np.float64)


def tcp_positions(model: GeneratedModel, q: np.ndarray) -> np.ndarray:
    """TCP positions of a batch of configurations, shape (..., d), from the generated ``fk``.

    d is the number of position components of the task space (2 for a planar arm).  A
    parallel mechanism's ``fk`` gives the position directly (NaN where it cannot be
    assembled).
    """
    if is_parallel(model):
        return parallel_function(model, "fk")(q).position
    return model.fk(q)[..., list(position_axes(model)), 3]


def parallel_function(model: GeneratedModel, name: str):
    """The generated function ``name`` of a parallel mechanism.

    Raises:
        ValueError: it was not generated (e.g. a Stewart-Gough platform has no closed-form fk
            and no ``jacobian``, only ``inverse_jacobian``: it is analysed at a constant
            orientation, over the Cartesian domain, see :mod:`symkin.mechanism.reach`).
    """
    if name not in model.functions:
        raise ValueError(f"{model.name}: the workspace and GCI analyses of a parallel mechanism need its generated "
                         f"'{name}' (derive it, e.g. --only ik,fk,jacobian); platforms without a closed-form fk "
                         "(Stewart-Gough) are analysed at a constant orientation over the Cartesian domain only "
                         "(symkin gci --domain cartesian)")
    return getattr(model, name)


def jacobian(model: GeneratedModel, q: np.ndarray, points: np.ndarray | None = None) -> np.ndarray:
    """The task Jacobian J (..., m, n) at configurations q (..., n).

    A serial arm's is ``model.jacobian(q)``; a parallel mechanism's ``model.jacobian(q, p)``
    at the TCP positions ``points`` (default: fk(q)); it is NaN where p is not, which the
    conditioning indices rate as singular.
    """
    if not is_parallel(model):
        return model.jacobian(q)
    return parallel_function(model, "jacobian")(q, tcp_positions(model, q) if points is None else points)


def is_positional(model: GeneratedModel) -> bool:
    """Whether the task space is only positions and the task Jacobian is square.

    Then |det J| dq is the volume element of the positional workspace (Lebesgue measure
    in metres^d) wherever the map q -> TCP is one-to-one.
    """
    return len(position_rows(model)) == len(task_space(model)) == len(coordinate_names(model))


def mixes_translations_and_rotations(model: GeneratedModel) -> bool:
    """Whether the task Jacobian has both translational rows (m/rad) and rotational rows (rad/rad).

    Its singular values then mix units, and conditioning indices need a characteristic
    length (:func:`symkin.numerics.conditioning.homogenize`).
    """
    return 0 < len(position_rows(model)) < len(task_space(model))
