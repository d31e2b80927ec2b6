"""Hybrid devices: a serial wrist carried by a parallel platform (a DELTA with a 3R wrist).

The device's combined coordinates are the platform's task coordinates p followed by the wrist's
coordinates qw (``../shared/design.md``, "Mechanisms as a graph": a tree rooted on a platform).
The platform's pose base_T_platform(p) = Trans(x, y, z) Rz(yaw) Ry(pitch) Rx(roll) is itself a
serial chain of *platform joints*: prismatic along the base axes for x, y and z, then revolute about
z, the moved y and the moved x for yaw, pitch and roll, each one the platform moves in.  With the
wrist on top, the whole device is a serial chain in (p, qw) (:func:`device_chain`), and its forward
kinematics and geometric Jacobian are that chain's serial derivations: exact, and no second code path.

==============================  ================================================================
``device_fk``                   base_T_tcp(p, qw): the pose of the wrist's TCP (4x4)
``device_frames``               base_T_<link>(p, qw) of each wrist link (4x4 each)
``device_jacobian``             [v; w] = J_c [pd; qwd]: geometric Jacobian in the combined coordinates
``device_actuator_jacobian``    [v; w] = J_a [qd; qwd], J_a = J_c diag(J, I), J = J_x^-1 J_q the platform's
==============================  ================================================================

The dynamics of a hybrid device are the parallel dynamics (:mod:`symkin.parallel.dynamics`) with the
platform side in the combined coordinates: the wrist's bodies add M_w(p, qw) (:func:`wrist_inertia`)
to the platform's M_p(p), and the device's coordinates are the legs' q followed by qw.

Every function takes the platform pose p (p = fk(q) or q = ik(p), as the velocity functions of the
parallel part) and the wrist coordinates ``qw``; ``device_actuator_jacobian`` also q.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
import symengine as se
import sympy

from symkin.dynamics.quantities import body_jacobians_of, mass_matrix_graph
from symkin.errors import DerivationError
from symkin.ir.quantity import Deriving, quantity
from symkin.ir.spec import FunctionSpec, InputSpec, OutputSpec, make_function
from symkin.kinematics.chain import ChainFrames
from symkin.kinematics.quantities import chain_frames, geometric_jacobian_matrix
from symkin.model import coordinates, tree
from symkin.model.reader import X_AXIS, Y_AXIS, Z_AXIS
from symkin.model.schema import Joint, JointType, Model, Wrist
from symkin.model.wrist_build import PLATFORM_LINK
from symkin.parallel.inputs import task_input
from symkin.parallel.quantities import PARALLEL, actuated_input, platform_jacobian


#: The platform joints in chain order: (coordinate, joint type, axis in the moved frame).  The
#: translations come first, so their axes are the base axes; then R = Rz(yaw) Ry(pitch) Rx(roll).
PLATFORM_JOINTS = tuple((name, JointType(letter), axis) for name, letter, axis in (
    ("x", "P", X_AXIS), ("y", "P", Y_AXIS), ("z", "P", Z_AXIS),
    ("yaw", "R", Z_AXIS), ("pitch", "R", Y_AXIS), ("roll", "R", X_AXIS)))
ZERO = sympy.Integer(0)


def wrist_of(model: Model) -> Wrist:
    """The wrist of a hybrid device (DerivationError for a model without one)."""
    wrist = None if model.parallel is None else model.parallel.wrist
    if wrist is None:
        raise DerivationError(f"model '{model.name}' carries no wrist: the device quantities are those of a "
                              "parallel platform with a 'wrist:' (docs/model-format.md, \"Hybrid devices\")")
    return wrist


def platform_joints(model: Model) -> tuple[Joint, ...]:
    """The platform's motion as joints, one per task coordinate, in chain order; the last one's link is
    :data:`~symkin.model.wrist_build.PLATFORM_LINK`."""
    moved = [(name, kind, axis) for name, kind, axis in PLATFORM_JOINTS if name in model.task_space]
    return tuple(Joint(name=name, type=kind, axis=axis, offset=ZERO, before=(), after=(),
                       link=PLATFORM_LINK if k == len(moved) - 1 else f"{PLATFORM_LINK}_{name}")
                 for k, (name, kind, axis) in enumerate(moved))


def device_chain(model: Model) -> Model:
    """The hybrid device as one serial model in its combined coordinates (platform joints, then the wrist).

    The wrist's first joint and its joints with ``parent: base`` hang on the platform link, behind the
    wrist's ``base:`` operations; the wrist's bodies, actuators and TCP come along, the legs stay behind
    (their masses are the parallel dynamics').
    """
    wrist = wrist_of(model)
    platform = platform_joints(model)
    joints = list(platform)
    for k, joint in enumerate(wrist.joints):
        on_platform = joint.parent == tree.BASE or (k == 0 and joint.parent is None)
        joints.append(dataclasses.replace(joint, parent=PLATFORM_LINK, before=wrist.base + joint.before)
                      if on_platform else joint)
    names = {j.name for j in wrist.joints}
    return dataclasses.replace(
        model, joints=tuple(joints), base=(), tcp=wrist.tcp, tip=wrist.tip, parallel=None,
        task_space=("x", "y", "z", "roll", "pitch", "yaw"), bodies=wrist.bodies, actuators=wrist.actuators,
        friction=tuple(f for f in model.friction if f.joint in names))


#: The input vector of each coordinate group of the wrist: ``qw`` (joint coordinates), ``qwd``, ``qwdd``, ``tauw``.
WRIST_GROUPS = {"q": "qw", "qd": "qwd", "qdd": "qwdd", "tau": "tauw"}


def wrist_symbols(model: Model, group: str) -> tuple[sympy.Symbol, ...]:
    """The symbols of the wrist's coordinates in ``group`` (``psi1``, ``psi1_d``...), none without a wrist."""
    wrist = None if model.parallel is None else model.parallel.wrist
    return () if wrist is None else coordinates.symbols_of(wrist.coordinates, group)


def wrist_input(model: Model, group: str = "q") -> InputSpec:
    """The wrist's input vector of a coordinate group (:data:`WRIST_GROUPS`): ``qw`` for its joint coordinates."""
    joints = wrist_of(model).coordinates
    return InputSpec(WRIST_GROUPS[group], "vector", coordinates.symbols_of(joints, group),
                     tuple(j.name for j in joints), coordinates.units_of(joints, group),
                     f"wrist {coordinates.GROUPS[group].doc}")


def combined_order(model: Model, size: int) -> list[int]:
    """The device chain's coordinate indices in the order of c = (p, qw) (``size``: the chain's coordinates):
    the chain moves the platform x, y, z, yaw, pitch, roll; p lists them x, y, z, roll, pitch, yaw."""
    order = [name for name, _, _ in PLATFORM_JOINTS if name in model.task_space]
    return [order.index(name) for name in model.task_space] + list(range(len(order), size))


@dataclass(frozen=True)
class WristInertia:
    """The wrist's bodies in the combined coordinates c = (p, qw), SymEngine expressions:
    k_w = 1/2 cd^T matrix cd and u_w = potential = -g . (sum of mass times centre of mass)."""

    matrix: list[list[se.Basic]]
    potential: se.Basic


@quantity("wrist_inertia", "mass matrix and potential of a hybrid device's wrist in its combined coordinates",
          emitted=False, mechanism=PARALLEL)
def wrist_inertia(d: Deriving) -> WristInertia:
    """M_w(c) by the composite-rigid-body algorithm on the device's chain (its platform joints massless, so
    only the wrist's bodies and rotors count), rows and columns in the order of c; u_w from the bodies' centres."""
    chain = d[device_derivation]
    M = chain[mass_matrix_graph]
    index = combined_order(d.model, len(M))
    g = [se.sympify(v) for v in d.model.gravity]
    potential = se.Integer(0)
    for body in chain[body_jacobians_of]:
        potential -= body.mass * sum((g[r] * body.com[r] for r in range(3)), se.Integer(0))
    return WristInertia([[M[i][j] for j in index] for i in index], potential)


@quantity("device_derivation", "the derivation graph of the hybrid device's serial chain", emitted=False,
          mechanism=PARALLEL)
def device_derivation(d: Deriving) -> Deriving:
    """The derivation graph of :func:`device_chain` (its serial quantities: frames, Jacobian, mass matrix, regressor)."""
    return d.of(device_chain(d.model))


def combined_jacobian(d: Deriving) -> sympy.Matrix:
    """J_c, the geometric Jacobian of the TCP in (p, qw): the platform columns in the order of p."""
    J = sympy.Matrix(d[device_derivation][geometric_jacobian_matrix])
    return sympy.Matrix.hstack(*(J[:, k] for k in combined_order(d.model, J.shape[1])))


@quantity("device_fk", "pose of the hybrid device's TCP base_T_tcp(p, qw) (4x4)", mechanism=PARALLEL)
def _device_fk(d: Deriving) -> FunctionSpec:
    chain: ChainFrames = d[device_derivation][chain_frames]
    return make_function(
        d.model, "device_fk", "Forward kinematics of the hybrid device: pose of the wrist's TCP.",
        "base_T_tcp = base_T_platform(p) * platform_T_wrist(qw) * wrist_T_tcp: the platform pose "
        "Trans(x, y, z) Rz(yaw) Ry(pitch) Rx(roll) (p = fk(q)), then the wrist's chain.",
        [task_input(d.model), wrist_input(d.model)],
        [OutputSpec("base_T_tcp", chain.tcp.T, "homogeneous transform of the TCP frame in the base frame", "m")],
    )


@quantity("device_frames", "base_T_<link> (4x4) of every link of a hybrid device's wrist", mechanism=PARALLEL)
def _device_frames(d: Deriving) -> FunctionSpec:
    chain: ChainFrames = d[device_derivation][chain_frames]
    platform = {joint.link for joint in platform_joints(d.model)}
    return make_function(
        d.model, "device_frames", "Pose of every link frame of the wrist in the base frame (the viewer draws them).",
        "base_T_<link> = base_T_platform(p) * platform_T_1 * ... * (i-1)_T_i for each wrist link i.",
        [task_input(d.model), wrist_input(d.model)],
        [OutputSpec(f"base_T_{name}", frame.T, f"homogeneous transform of frame '{name}' in the base frame", "m")
         for name, frame in chain.links if name not in platform],
    )


@quantity("device_jacobian", "geometric Jacobian of the hybrid device in its combined coordinates (p, qw)",
          mechanism=PARALLEL)
def _device_jacobian(d: Deriving) -> FunctionSpec:
    return make_function(
        d.model, "device_jacobian", "Geometric Jacobian of the hybrid device in its combined coordinates.",
        "[v; w] = J_c [pd; qwd] with v the TCP velocity and w its angular velocity in the base frame; a "
        "platform position column is the base axis, an angle column the axis it turns about (Z-Y-X), a "
        "wrist column [z_i x (p_tcp - p_i); z_i] (revolute) or [z_i; 0] (prismatic).",
        [task_input(d.model), wrist_input(d.model)],
        [OutputSpec("J", sympy.ImmutableMatrix(combined_jacobian(d)),
                    "rows vx, vy, vz, wx, wy, wz; columns: platform coordinates, then wrist joints")],
    )


@quantity("device_actuator_jacobian", "geometric Jacobian of the hybrid device in its actuated coordinates",
          mechanism=PARALLEL)
def _device_actuator_jacobian(d: Deriving) -> FunctionSpec:
    J_c = combined_jacobian(d)
    k = len(d.model.task_space)
    J_platform = J_c[:, :k] * platform_jacobian(d, "the device's actuator Jacobian")
    return make_function(
        d.model, "device_actuator_jacobian", "Geometric Jacobian of the hybrid device in its actuated coordinates.",
        "[v; w] = J_a [qd; qwd] with J_a = [J_c,p J, J_c,w]: the platform columns of the combined Jacobian "
        "times the platform's J = J_x^-1 J_q (J_x^-1 = adj(J_x) / det(J_x)), the wrist columns as they are. "
        "tau = J_a^T [f; m] are the actuator efforts with which the TCP exerts the wrench [f; m].",
        [actuated_input(d), task_input(d.model), wrist_input(d.model)],
        [OutputSpec("J", sympy.ImmutableMatrix(J_platform.row_join(J_c[:, k:])),
                    "rows vx, vy, vz, wx, wy, wz; columns: the legs' actuated joints, then wrist joints")],
    )
