"""The in-memory mechanism model: frozen dataclasses built from a validated model file.

Algorithms never modify a model (as in Pinocchio): derivations and analyses are free
functions of a ``Model``.  All geometry is kept as exact sympy expressions of the
parameter symbols; parameters carry exact default values.

Rigid motions are sequences of elementary operations (:class:`Rotation`,
:class:`Translation`) applied in the moving frame, left to right, so that a DH row or a
URDF origin becomes a short list that the kinematics composer can merge cleverly
(consecutive rotations about the same axis add their angles).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

import sympy

from symkin.errors import Problem

Vec3 = tuple[sympy.Expr, sympy.Expr, sympy.Expr]


class JointType(str, Enum):
    """Joint types of serial chains: one coordinate each."""

    REVOLUTE = "R"
    PRISMATIC = "P"


@dataclass(frozen=True)
class Rotation:
    """Rotation of the moving frame about its own unit ``axis`` by ``angle`` (right hand)."""

    axis: Vec3
    angle: sympy.Expr


@dataclass(frozen=True)
class Translation:
    """Translation of the moving frame by ``vector`` (expressed in the moving frame)."""

    vector: Vec3


Op = Rotation | Translation


@dataclass(frozen=True)
class Parameter:
    """A named model parameter.

    Attributes:
        name: identifier used in expressions and in generated code.
        symbol: the sympy symbol (real).
        value: exact default value (a number expression such as 1807/10000 or pi/2).
        unit: free-text unit, e.g. ``m``, ``kg``, ``rad``, ``kg*m^2``.
        doc: one-line description.
    """

    name: str
    symbol: sympy.Symbol
    value: sympy.Expr
    unit: str = ""
    doc: str = ""


@dataclass(frozen=True)
class DerivedParameter:
    """A parameter defined by an expression of other parameters (inlined, never an input)."""

    name: str
    definition: sympy.Expr
    unit: str = ""
    doc: str = ""


@dataclass(frozen=True)
class Joint:
    """One joint of a serial chain and the link it moves.

    The transform from the parent link frame to this joint's child link frame is::

        parent_T_link = before * Motion(q + offset) * after

    where Motion is a rotation about ``axis`` (revolute) or a translation along ``axis``
    (prismatic), all in the joint frame.

    Attributes:
        name: joint name, also the name of its coordinate.
        type: revolute or prismatic.
        axis: unit motion axis in the joint frame (numbers).
        offset: constant added to the coordinate (DH theta or d column of the moving joint).
        before: fixed operations from the parent link frame to the joint frame.
        after: fixed operations from the moved joint frame to the child link frame.
        link: name of the child link frame (``base_T_<link>`` in outputs).
        limits: (lower, upper) position limits or None.
        velocity_limit: maximal speed or None.
        effort_limit: maximal torque/force or None.
        active: actuated (True) or passive.
    """

    name: str
    type: JointType
    axis: Vec3
    offset: sympy.Expr
    before: tuple[Op, ...]
    after: tuple[Op, ...]
    link: str
    limits: tuple[sympy.Expr, sympy.Expr] | None = None
    velocity_limit: sympy.Expr | None = None
    effort_limit: sympy.Expr | None = None
    active: bool = True


@dataclass(frozen=True)
class Body:
    """Mass properties attached to a link frame.

    Attributes:
        link: the link frame the body is rigidly attached to (or ``base``... not allowed).
        mass: mass.
        com: centre of mass in the link frame.
        inertia: 3x3 inertia tensor about the centre of mass, link-frame axes (zero for a
            point mass).
    """

    link: str
    mass: sympy.Expr
    com: Vec3
    inertia: sympy.ImmutableMatrix

    @property
    def is_point_mass(self) -> bool:
        return self.inertia.is_zero_matrix is True


@dataclass(frozen=True)
class Friction:
    """Joint friction, tau_f = viscous * qd + coulomb * sign(qd) (seed eq. 8.34).

    With ``smoothing_velocity`` v_s the Coulomb term is the smooth
    coulomb * tanh(qd / v_s) instead (differentiable, for optimization and simulation).
    """

    joint: str
    viscous: sympy.Expr
    coulomb: sympy.Expr
    smoothing_velocity: sympy.Expr | None = None


@dataclass(frozen=True)
class Scene:
    """What a user needs from the model: the outputs to emit and how.

    Attributes:
        outputs: names of derivable quantities to emit (see ``symkin quantities``).
        fixed: parameters folded to their default values before code generation.
        backends: code generators to run.
        float32: also emit single-precision variants (C backend).
        combine: outputs also computed together by one function ``scene`` that shares one
            CSE across them (e.g. M, V and G for a servo loop); None means every output.
    """

    outputs: tuple[str, ...]
    fixed: tuple[str, ...] = ()
    backends: tuple[str, ...] = ("numpy",)
    float32: bool = False
    combine: tuple[str, ...] | None = None


@dataclass(frozen=True)
class Model:
    """A validated mechanism model.

    Attributes:
        name: identifier of the model (file and function prefix of generated code).
        description: free text.
        references: citations for the numbers in the model.
        source: path of the model file as given.
        hash: ``sha256:<hex>`` of the canonical model data.
        parameters: free parameters (symbols with defaults), in file order.
        derived_parameters: parameters defined by expressions (already inlined).
        joints: serial chain, base to tip.
        base: fixed operations from the world/base frame to the first joint's parent frame.
        tcp: fixed operations from the last link frame to the TCP frame.
        task_space: names of task-space coordinates (see symkin.kinematics.task_space).
        bodies: mass properties.
        gravity: gravity acceleration vector in the base frame.
        friction: per-joint friction.
        scene: default request.
    """

    name: str
    description: str
    references: tuple[str, ...]
    source: str
    hash: str
    parameters: tuple[Parameter, ...]
    derived_parameters: tuple[DerivedParameter, ...]
    joints: tuple[Joint, ...]
    base: tuple[Op, ...]
    tcp: tuple[Op, ...]
    task_space: tuple[str, ...]
    bodies: tuple[Body, ...] = ()
    gravity: Vec3 = (sympy.Integer(0), sympy.Integer(0), sympy.Integer(0))
    friction: tuple[Friction, ...] = ()
    scene: Scene = field(default_factory=lambda: Scene(outputs=("fk", "jacobian")))
    #: key path -> (line, column) in the model file, for located messages of later stages.
    locations: dict = field(default_factory=dict, compare=False, repr=False)

    def problem(self, path: tuple, message: str, fix: str) -> Problem:
        """A located :class:`~symkin.errors.Problem` about the element at key ``path``."""
        from symkin.model.yaml_source import format_path

        probe = tuple(path)
        while probe and probe not in self.locations:
            probe = probe[:-1]
        line, column = self.locations.get(probe, (None, None))
        return Problem(self.source, line, column, format_path(path), message, fix)

    @property
    def dof(self) -> int:
        """Number of joint coordinates n."""
        return len(self.joints)

    @property
    def parameter_values(self) -> dict[sympy.Symbol, sympy.Expr]:
        """Default value of every free parameter, keyed by symbol."""
        return {p.symbol: p.value for p in self.parameters}

    def parameter(self, name: str) -> Parameter:
        for p in self.parameters:
            if p.name == name:
                return p
        raise KeyError(name)

    @property
    def links(self) -> tuple[str, ...]:
        """Names of the link frames, base to tip."""
        return tuple(j.link for j in self.joints)
