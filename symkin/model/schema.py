"""The in-memory mechanism model: frozen dataclasses built from a validated model file.

Algorithms never modify a model (as in Pinocchio): derivations and analyses are free
functions of a ``Model``.  All geometry is kept as exact sympy expressions of the
parameter symbols; parameters carry exact default values.

Rigid motions are sequences of elementary operations (:class:`Rotation`,
:class:`Translation`) applied in the moving frame, left to right, so that a DH row or a
URDF origin becomes a short list that the kinematics composer can merge cleverly
(consecutive rotations about the same axis add their angles).

Length: one vocabulary (every dataclass of a model, serial and parallel), read together by
everything below the derivation; split it and every reader imports from several places.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

import sympy

from symkin.errors import ModelError, Problem
from symkin.geometry import Vec3, rotation_matrix
from symkin.model import joint_kinds
from symkin.model.joint_kinds import kind as joint_kind



class JointType(str, Enum):
    """Joint types of serial chains: one coordinate each."""

    REVOLUTE = "R"
    PRISMATIC = "P"

    @property
    def turns(self) -> bool:
        """Whether a joint of this type rotates about its axis (its coordinate an angle), not translates."""
        return joint_kinds.is_rotation(self)


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


def fixed_pose(ops: tuple[Op, ...]) -> tuple[sympy.Matrix, sympy.Matrix]:
    """(R, p) of the frame reached from the identity by fixed operations (moving-frame order, left to right)."""
    rotation, origin = sympy.eye(3), sympy.zeros(3, 1)
    for op in ops:
        if isinstance(op, Rotation):
            rotation = rotation * rotation_matrix(op.axis, op.angle)
        else:
            origin = origin + rotation * sympy.Matrix(op.vector)
    return rotation, origin


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
class Coupling:
    """A joint whose motion is an affine combination of the coordinates: theta = sum_k a_k q_k + b.

    The map is constant, so the coordinates' Jacobian columns are J A, their mass matrix A^T M A and
    their generalized forces A^T tau (virtual work; Featherstone 2008, sec. 8.1). ``mimic:`` (URDF
    ``<mimic>``) is the one-term case q = a q_leader + b; a parallelogram's distal joint moves by
    q3 - q2 (the PHANToM's elbow, q3 the distal link's absolute angle), a differential by q4 + q5.
    A joint whose own name is among the terms keeps its coordinate (the PHANToM's q3); one without
    is a follower and adds none.

    Attributes:
        terms: (coordinate, multiplier a_k) pairs, in chain order, every multiplier nonzero.
        offset: b, added to the position (not to rates and accelerations).
    """

    terms: tuple[tuple[str, sympy.Expr], ...]
    offset: sympy.Expr
    #: declared as ``mimic:`` (or a URDF ``<mimic>``): a follower of another joint by definition.
    mimic: bool = False

    @property
    def leader(self) -> str | None:
        """The one coordinate of a one-term coupling (URDF's mimic leader), else None."""
        return self.terms[0][0] if len(self.terms) == 1 else None

    @property
    def multiplier(self) -> sympy.Expr:
        """a of a one-term coupling q = a q_leader + b."""
        return self.terms[0][1]

    def follows_others(self, name: str) -> bool:
        """True if the joint ``name`` with this coupling is a follower (has no coordinate of its own)."""
        return self.mimic or all(coordinate != name for coordinate, _ in self.terms)


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
        coupling: the motion as an affine combination of coordinates, None for a joint that moves
            by its own coordinate.
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
    coupling: Coupling | None = None
    #: the link this joint hangs on (a branch of a tree: :mod:`symkin.model.tree`), None for the previous
    #: joint's link (the base for the first joint).
    parent: str | None = None

    @property
    def turns(self) -> bool:
        """Whether the joint's motion is a rotation about its axis (its coordinate an angle), not a translation."""
        return self.type.turns

    def motion(self, amount: sympy.Expr) -> Op:
        """The joint's motion by ``amount`` (its coordinate plus its offset) as a moving-frame operation: a rotation
        about its axis by that angle (R) or a translation along it by that length (P).  Every frame walker (the
        chain, Newton-Euler's link frames, the URDF export) moves a frame by it as by any fixed operation, so the
        joint's kind decides the motion here only."""
        if self.turns:
            return Rotation(self.axis, amount)
        return Translation(tuple(c * amount for c in self.axis))

    @property
    def follower(self) -> bool:
        """True if the joint has no coordinate of its own (it moves by others')."""
        return self.coupling is not None and self.coupling.follows_others(self.name)


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
    With ``coulomb_negative`` the Coulomb level differs with the direction of motion (as the
    Puma 560's in Corke's Robotics Toolbox, Tc+ != Tc-): ``coulomb`` opposes positive motion,
    ``coulomb_negative`` (a magnitude) negative motion.
    """

    joint: str
    viscous: sympy.Expr
    coulomb: sympy.Expr
    smoothing_velocity: sympy.Expr | None = None
    coulomb_negative: sympy.Expr | None = None

    @property
    def asymmetric(self) -> bool:
        return self.coulomb_negative is not None and self.coulomb_negative != self.coulomb


@dataclass(frozen=True)
class JointStop:
    """A stop on a combination of joint coordinates: lower <= sum_k a_k q_k + b <= upper (``joint_stops:``), e.g.
    the PHANToM's parallelogram, whose links collide at -65 deg <= q3 - q2 <= 55 deg whatever q2 and q3 are
    separately.  The box of the coordinates' own limits cannot hold such a stop; the analyses keep the
    configurations that respect every stop (:mod:`symkin.mechanism.stops`).

    Attributes:
        terms: (coordinate, multiplier a_k) pairs, every multiplier nonzero.
        offset: b.
        lower, upper: the bounds (rad for angles, m for lengths).
        expression: the combination as the model file writes it (for messages).
    """

    terms: tuple[tuple[str, sympy.Expr], ...]
    offset: sympy.Expr
    lower: sympy.Expr
    upper: sympy.Expr
    expression: str


@dataclass(frozen=True)
class Spring:
    """A spring on a joint (a torsion spring on a revolute joint, a linear one on a prismatic joint): the
    potential 1/2 k (theta - theta_0)^2 of the joint's value theta, whose generalized force k (theta - theta_0)
    is part of G (MuJoCo's joint ``stiffness`` about ``springref``; a gravity-balancing spring).

    Attributes:
        joint: the joint it acts on.
        stiffness: k >= 0 (N m/rad on a revolute joint, N/m on a prismatic one).
        reference: theta_0, the joint value where the spring is relaxed (rad or m).
    """

    joint: str
    stiffness: sympy.Expr
    reference: sympy.Expr


@dataclass(frozen=True)
class Actuator:
    """The drive of one serial joint: a motor whose rotor turns ``gear_ratio`` times per joint turn.

    The rotor's kinetic energy 1/2 J_m (N qd)^2 adds the reflected inertia N^2 J_m to M's diagonal
    entry of the joint (and N^2 J_m qdd to its torque); the rotor's gyroscopic coupling with the
    links that carry it is neglected, as in Pinocchio's and MuJoCo's ``armature`` (Featherstone
    2008, sec. 9.4; Spong et al. 2006, sec. 7.4: valid for large gear ratios).

    Attributes:
        joint: the joint it drives.
        rotor_inertia: J_m, the rotor's inertia about its axis (kg m^2; kg for a linear motor).
        gear_ratio: N, motor turns per joint turn (1: direct drive).
        torque_constant: K_t, motor torque per ampere (N m/A; N/A for a linear motor), or None.
        peak_current, continuous_current: the drive's current limits (A), or None.
        gyroscopic: model the rotor as a body of its own on the link that carries the motor, spinning
            N times as fast as the joint (:mod:`symkin.model.rotors`), instead of the reflected inertia
            alone: its kinetic energy 1/2 J_m (z . w_carrier + N qd)^2 then couples it with the motion of
            the links before it (Spong 1987; Featherstone 2008, sec. 9.4 treats the gear as this constraint).
    """

    joint: str
    rotor_inertia: sympy.Expr = sympy.Integer(0)
    gear_ratio: sympy.Expr = sympy.Integer(1)
    torque_constant: sympy.Expr | None = None
    peak_current: sympy.Expr | None = None
    continuous_current: sympy.Expr | None = None
    gyroscopic: bool = False

    @property
    def peak_effort(self) -> sympy.Expr | None:
        """N K_t I_peak: the largest joint torque the motor gives (None without K_t and I_peak)."""
        if self.torque_constant is None or self.peak_current is None:
            return None
        return self.gear_ratio * self.torque_constant * self.peak_current

    @property
    def continuous_effort(self) -> sympy.Expr | None:
        """N K_t I_cont: the joint torque the motor holds without overheating (None without them)."""
        if self.torque_constant is None or self.continuous_current is None:
            return None
        return self.gear_ratio * self.torque_constant * self.continuous_current

    @property
    def reflected_inertia(self) -> sympy.Expr:
        """N^2 J_m: the inertia the joint sees (MuJoCo's and Pinocchio's ``armature``)."""
        return self.gear_ratio ** 2 * self.rotor_inertia


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
class Coordinate:
    """One generalized coordinate q_i: an actuated joint variable (revolute: rad, prismatic: m).

    ``limits`` are (lower, upper) position bounds, ``velocity_limit`` and ``effort_limit`` the
    actuator's largest speed and effort, each None where the model declares none.
    """

    name: str
    type: JointType
    limits: tuple[sympy.Expr, sympy.Expr] | None = None
    velocity_limit: sympy.Expr | None = None
    effort_limit: sympy.Expr | None = None

    @property
    def turns(self) -> bool:
        """Whether the coordinate is an angle (an actuated rotation), not a length."""
        return self.type.turns


class LegJointType(str, Enum):
    """Joint types of the legs of parallel mechanisms (seed Fig. 8.2) and their degrees of freedom."""

    R = "R"  # revolute: rotation about ``axes[0]``
    P = "P"  # prismatic: translation along ``axes[0]``
    U = "U"  # universal: rotation about ``axes[0]``, then about ``axes[1]`` (moved frame)
    S = "S"  # spherical: rotations about ``axes[0]``, ``axes[1]``, ``axes[2]`` (moved frames)
    C = "C"  # cylindrical: translation along ``axes[0]``, then rotation about it

    @property
    def dof(self) -> int:
        return joint_kind(self).dof


@dataclass(frozen=True)
class LegJoint:
    """One joint of a leg of a parallel mechanism.

    The leg frame moves through ``origin`` (fixed operations, as a serial chain's
    ``origin``) and then through the joint's motion: one elementary motion per degree of
    freedom, in the order of :attr:`variables`.

    Attributes:
        name: joint name (with the leg's number appended, e.g. ``theta1``).
        type: R, P, U, S or C.
        axes: unit axis of each elementary motion, in the moved joint frame (one shared axis for C).
        origin: fixed operations from the previous joint's frame (or the leg's base frame).
        variables: coordinate name of each elementary motion: ``name`` for R and P,
            ``name_1``, ``name_2`` (, ``name_3``) for U and S, ``name_t``, ``name_r`` for C.
        active: index into ``variables`` of the actuated motion, or None (passive joint).
            R and P joints and the slide of a C joint can be actuated.
        offset: constant added to the actuated variable (e.g. the strut length at zero stroke).
        velocity_limit, effort_limit: the actuator's largest speed and effort (active joints), or None.
        limits: position limits (lower, upper) of each motion (one per variable), None for
            a motion without limits; () when the joint declares none.  The actuated
            motion's limits are its coordinate's; the passive ones restrict the workspace
            (:mod:`symkin.mechanism.reach`).
    """

    name: str
    type: LegJointType
    axes: tuple[Vec3, ...]
    origin: tuple[Op, ...]
    variables: tuple[str, ...]
    active: int | None = None
    offset: sympy.Expr = sympy.Integer(0)
    limits: tuple[tuple[sympy.Expr, sympy.Expr] | None, ...] = ()
    velocity_limit: sympy.Expr | None = None
    effort_limit: sympy.Expr | None = None

    def limits_of(self, k: int) -> tuple[sympy.Expr, sympy.Expr] | None:
        """The limits of motion k (index into :attr:`variables`), or None."""
        return self.limits[k] if self.limits else None

    @property
    def motions(self) -> tuple[tuple[str, Vec3, bool], ...]:
        """(variable, axis, is_rotation) of every elementary motion, in order."""
        kind = joint_kinds.kind(self.type)
        return tuple(zip(self.variables, (self.axes[k] for k in kind.motion_axes), kind.rotations))


@dataclass(frozen=True)
class Leg:
    """One kinematic chain from the base to the moving platform.

    Closure (seed sec. 3.2, "Inverse Kinematics" step 1): walking the joints from the leg's
    base frame must end in the platform's attachment frame,
    ``base_T_leg * prod_j(origin_j * motion_j) = base_T_platform(p) * platform_T_attachment``.

    Attributes:
        name: leg name (``leg1``...).
        base: fixed operations from the base frame to the leg's first joint frame (A_i).
        joints: the joints, base to platform.
        platform: fixed operations from the platform frame to the attachment frame (B_i).
        ik_branch: +1 or -1, the root chosen by the closed-form inverse kinematics (see
            ``docs/model-format.md``, "Branches").
    """

    name: str
    base: tuple[Op, ...]
    joints: tuple[LegJoint, ...]
    platform: tuple[Op, ...]
    ik_branch: int = 1


@dataclass(frozen=True)
class ParallelBodies:
    """Mass properties of a parallel mechanism, the same on every leg (``bodies:`` of a parallel model).

    Attributes:
        platform: the moving platform, com and inertia in the platform (TCP) frame; None if massless.
        actuated_link: the link the actuator moves (the DELTA's upper arm), com and inertia in the
            frame right after the actuated motion; None if massless.
        distal_link: the link between a spherical leg's last two joints (the Agile Eye's distal arc), com and
            inertia in the frame right after the leg's second-to-last joint; its orientation is fixed by
            the two axes it carries, so its full inertia enters the dynamics (spherical models only).
        rod_mass: mass of each leg's rod between its point joints C_i and B_i (the DELTA's
            parallelogram, a Stewart strut), lumped at its two ends.
        rod_platform_fraction: the part of ``rod_mass`` lumped at the platform joint B_i; the rest
            is at C_i (the elbow of a DELTA, the fixed base joint of a Stewart strut).
        rod_inertia: the rod's moment of inertia about its centre of mass (at ``rod_platform_fraction``
            of the way from C_i to B_i) about any axis across it (a uniform bar: m L^2 / 12), for a rod
            of fixed length; its inertia about its own axis is neglected (a slender rod).  None: the
            rod is its two lumped ends (a dumbbell, m f (1 - f) L^2).
        rotor_inertia: each actuator's rotor inertia about its axis (motor side).
        gear_ratio: motor turns per actuated-joint turn (1: direct drive); the joint sees
            gear_ratio^2 rotor_inertia.
        links: the links of legs without the distance form (``links:``), each a Body whose ``link`` is the leg
            joint that moves it (e.g. ``theta1``), com and inertia in that joint's frame after its motion
            (:mod:`symkin.parallel.closure_dynamics`).
    """

    platform: Body | None = None
    actuated_link: Body | None = None
    distal_link: Body | None = None
    rod_mass: sympy.Expr = sympy.Integer(0)
    rod_platform_fraction: sympy.Expr = sympy.Rational(1, 2)
    rod_inertia: sympy.Expr | None = None
    rotor_inertia: sympy.Expr = sympy.Integer(0)
    gear_ratio: sympy.Expr = sympy.Integer(1)
    links: tuple[Body, ...] = ()


#: The coordinates a platform may move in, in the order of the task coordinates p: position in the base
#: frame, then the angles of R = Rz(yaw) Ry(pitch) Rx(roll).  Coordinates a model does not declare stay 0.
PLATFORM_COORDINATES = ("x", "y", "z", "roll", "pitch", "yaw")
_POSITION = frozenset(("x", "y", "z"))
_ANGLES = frozenset(("roll", "pitch", "yaw"))


class PlatformMotion(str, Enum):
    """The kind of motion of a platform, classified from its declared coordinates."""

    TRANSLATION = "translation"  # p = (x, y, z), orientation constant (TPM, seed sec. 2.2.1)
    POSE = "pose"  # p = (x, y, z, roll, pitch, yaw), R = Rz(yaw) Ry(pitch) Rx(roll)
    PLANAR = "planar"  # p within (x, y, yaw): the platform moves in the plane z = 0 (lambda = 3)
    SPHERICAL = "spherical"  # p within (roll, pitch, yaw): rotations about the base origin (lambda = 3)
    SCHOENFLIES = "schoenflies"  # p = (x, y, z, yaw): translations and rotations about the vertical
    LOWER = "lower mobility"  # any other independent subset (a 5-DoF platform, ...)

    @classmethod
    def of(cls, coordinates: tuple[str, ...]) -> PlatformMotion:
        """The kind of a platform moving in ``coordinates`` (names from :data:`PLATFORM_COORDINATES`)."""
        declared = frozenset(coordinates)
        if declared == _POSITION:
            return cls.TRANSLATION
        if declared == _POSITION | _ANGLES:
            return cls.POSE
        if declared <= {"x", "y", "yaw"}:
            return cls.PLANAR
        if declared <= _ANGLES:
            return cls.SPHERICAL
        if declared == _POSITION | {"yaw"}:
            return cls.SCHOENFLIES
        return cls.LOWER

    @property
    def spatial_factor(self) -> int:
        """lambda of eq. (8.2): 3 for planar and spherical mechanisms, 6 otherwise (seed sec. 2.2)."""
        return 3 if self in (PlatformMotion.PLANAR, PlatformMotion.SPHERICAL) else 6


@dataclass(frozen=True)
class Wrist:
    """A serial chain carried by the platform of a parallel mechanism (a hybrid device: a DELTA with a
    3R wrist, as Force Dimension's omega.7 and sigma.7; ``wrist:`` of a parallel model).

    Its joints, bodies and actuators are a serial model's (:class:`Joint`, :class:`Body`,
    :class:`Actuator`); the chain starts in the platform (TCP) frame, where a serial chain starts in
    the base frame, and a joint's ``parent: base`` names the platform.  The device's combined
    coordinates are the platform's task coordinates p followed by the wrist's coordinates qw
    (:mod:`symkin.parallel.hybrid`).

    Attributes:
        joints: the wrist's joints, platform to tip.
        base: fixed operations from the platform frame to the first joint's parent frame.
        tcp: fixed operations from the tip link frame to the device's TCP (the handle, the tool).
        tip: the link that carries the TCP, None for the last joint's link.
        bodies: mass properties of the wrist's links.
        actuators: the drives of the wrist's joints.
    """

    joints: tuple[Joint, ...]
    base: tuple[Op, ...] = ()
    tcp: tuple[Op, ...] = ()
    tip: str | None = None
    bodies: tuple[Body, ...] = ()
    actuators: tuple[Actuator, ...] = ()

    @property
    def coordinates(self) -> tuple[Joint, ...]:
        """The wrist's own coordinates qw: its joints but the followers (:class:`Coupling`)."""
        return tuple(j for j in self.joints if not j.follower)


@dataclass(frozen=True)
class Parallel:
    """The structure of a parallel mechanism.

    Attributes:
        coordinates: the platform's task coordinates p, a subset of :data:`PLATFORM_COORDINATES` in
            its order (``x, y, z`` for a translational platform).
        legs: the kinematic chains, in order.
        fk_branch: +1 or -1, the root of the closed-form forward kinematics (trilateration, circle intersection).
        identical: identical (idle) conditions declared in addition to the detected ones
            (f_id of eq. 8.2).
        constraints: constraints that must hold for the mechanism to move (s of eq. 8.2).
        kind: ``delta`` when built from the DELTA shorthand, else ``legs``.
        home: a reachable platform pose (task coordinates): the default start of numerical
            solvers and the centre of sampled workspaces; None if not declared.
        bodies: mass properties of the legs and the platform; None for a kinematic model.
        wrist: the serial chain the platform carries (a hybrid device), None for a plain parallel mechanism.
        home_assembly: (variable, value) pairs where the solve of the legs' closure at ``home`` starts (the
            analyses that continue the closure start from the assembly it reaches); None if not declared.
    """

    coordinates: tuple[str, ...]
    legs: tuple[Leg, ...]
    fk_branch: int = -1
    identical: int = 0
    constraints: int = 0
    kind: str = "legs"
    home: tuple[sympy.Expr, ...] | None = None
    bodies: ParallelBodies | None = None
    wrist: Wrist | None = None
    home_assembly: tuple[tuple[str, sympy.Expr], ...] | None = None

    @property
    def motion(self) -> PlatformMotion:
        """The kind of the platform's motion (translation, pose, planar, spherical, ...)."""
        return PlatformMotion.of(self.coordinates)

    @property
    def actuated_coordinates(self) -> tuple[Coordinate, ...]:
        """The actuated joint variables, leg by leg: the model's generalized coordinates q."""
        out = []
        for leg in self.legs:
            for joint in leg.joints:
                if joint.active is not None:
                    _, _, rotation = joint.motions[joint.active]
                    out.append(Coordinate(joint.variables[joint.active],
                                          JointType.REVOLUTE if rotation else JointType.PRISMATIC,
                                          joint.limits_of(joint.active), joint.velocity_limit, joint.effort_limit))
        return tuple(out)

    @property
    def task_dof(self) -> int:
        return len(self.coordinates)


@dataclass(frozen=True)
class Model:
    """A validated mechanism model.

    Attributes:
        name: identifier of the model (file and function prefix of generated code).
        description: free text.
        references: citations for the numbers in the model.
        source: path of the model file as given.
        hash: ``sha256:<hex>`` of the canonical model data without its ``scene:`` section: the
            mechanism's identity, the same whatever is emitted from it.
        parameters: free parameters (symbols with defaults), in file order.
        derived_parameters: parameters defined by expressions (already inlined).
        joints: serial chain, base to tip.
        base: fixed operations from the world/base frame to the first joint's parent frame.
        tcp: fixed operations from the last link frame to the TCP frame.
        task_space: names of task-space coordinates (see symkin.kinematics.task_space); for a
            parallel mechanism x, y, z (translation) or x, y, z, roll, pitch, yaw (pose).
        bodies: mass properties.
        gravity: gravity acceleration vector in the base frame.
        friction: per-joint friction.
        springs: joint springs (their forces are part of G) of a serial chain or tree.
        actuators: per-joint drives (rotor inertia and gear ratio) of a serial chain.
        joint_stops: stops on affine combinations of the coordinates (a parallelogram's links meeting).
        scene: default request.
        parallel: legs and platform of a parallel mechanism, None for a serial chain.
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
    springs: tuple[Spring, ...] = ()
    #: the drives of serial joints (rotor inertia, gear ratio); a parallel model's rotors are in its bodies.
    actuators: tuple[Actuator, ...] = ()
    #: stops on combinations of the coordinates (``joint_stops:``), beside each coordinate's own limits.
    joint_stops: tuple[JointStop, ...] = ()
    #: the link that carries the TCP (``serial.tip``), None for the last joint's link.
    tip: str | None = None
    #: a serial device's rest configuration (``serial.home``), one expression per coordinate, or None.
    home_configuration: tuple[sympy.Expr, ...] | None = None
    scene: Scene = field(default_factory=lambda: Scene(outputs=("fk", "jacobian")))
    #: the legs and platform of a parallel mechanism (``joints`` is empty then), None for serial chains.
    parallel: Parallel | None = None
    #: what the reading decided that the file leaves open (a joint locked at a value clipped into its
    #: limits, a non-physical inertia accepted): printed by symkin check and derive, kept in the manifest.
    notes: tuple[str, ...] = ()
    #: located problems that block only the outputs that use the inertias (a serial model's non-physical inertia
    #: tensor, without allow_nonphysical): symkin.dynamics.physical.require_physical refuses those outputs.
    nonphysical: tuple[Problem, ...] = field(default=(), compare=False)
    #: the names in the source file of joints and links renamed to identifiers (a URDF's ``joint_0.0``):
    #: {"joints": {model name: source name}, "links": {...}}; see :meth:`source_name`.
    source_names: dict = field(default_factory=dict, compare=False)  # a dict: out of eq and hash
    #: key path -> (line, column) in the model file, for located messages of later stages.
    locations: dict = field(default_factory=dict, compare=False, repr=False)
    #: every name the file gives (parameters, joints, links, legs...) -> its key path, for a backend's reserved
    #: words (:func:`symkin.pipeline.resolve_request`): they become identifiers of the generated code.
    declared_names: dict = field(default_factory=dict, compare=False, repr=False)

    def problem(self, path: tuple, message: str, fix: str) -> Problem:
        """A located :class:`~symkin.errors.Problem` about the element at key ``path``."""
        from symkin.model.yaml_source import format_path, located_problem

        probe = tuple(path)
        while probe and probe not in self.locations:
            probe = probe[:-1]
        return located_problem(self.source, self.locations.get(probe), format_path(path), message, fix)

    def refuse_closed_loops(self, work: str, fix: str) -> None:
        """Refuse, located at ``parallel``, a model whose legs close loops for ``work`` that follows open chains
        (a reference library's serial trees); ``fix`` says what to do instead.

        Raises:
            ModelError: the model has legs.
        """
        if self.parallel is not None:
            raise ModelError([self.problem(("parallel",), f"{work}; a parallel mechanism has closed loops", fix)])

    def source_name(self, kind: str, name: str) -> str:
        """The name in the source file of the joint (``kind`` "joints") or link ("links") ``name``."""
        return str(self.source_names.get(kind, {}).get(name, name))

    @property
    def mechanism(self) -> str:
        """``serial`` or ``parallel``."""
        return "serial" if self.parallel is None else "parallel"

    @property
    def coordinates(self) -> tuple[Joint | Coordinate, ...]:
        """The generalized coordinates q, each with a ``name`` and a ``type`` (R or P).

        A serial chain's coordinates are its joints but the followers (:class:`Coupling`); a parallel
        mechanism's are its actuated joint variables, leg by leg (the passive ones follow from
        the loop closure).
        """
        if self.parallel is None:
            return tuple(j for j in self.joints if not j.follower)
        return self.parallel.actuated_coordinates

    @property
    def dof(self) -> int:
        """Number of generalized coordinates n (joints of a chain, actuators of a parallel mechanism)."""
        return len(self.coordinates)

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
