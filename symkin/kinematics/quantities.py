"""Kinematic quantities of serial chains, registered in the derivation graph.

=====================  =========================================================
``chain``              (internal) link frames, joint axes and TCP by one chain walk
``fk``                 base_T_tcp, 4x4 (seed sec. 3.1, DH step 4)
``frames``             base_T_<link> for every link, 4x4 each
``task_coordinates``   task-space coordinates p = f(q), m (seed eq. 8.5)
``jacobian_geometric`` 6 x n, linear rows over angular rows, base frame
``frame_jacobians``    base_J_<link>, 6 x n, the geometric Jacobian of every link frame
``jacobian``           task Jacobian J = dp/dq, m x n (seed sec. 4 "Jacobian Matrix")
=====================  =========================================================
"""

from __future__ import annotations

import sympy

from symkin.ir.inputs import coordinate_input
from symkin.ir.quantity import Deriving, quantity
from symkin.ir.spec import FunctionSpec, OutputSpec, make_function
from symkin.kinematics import task_space
from symkin.kinematics.chain import ChainFrames, compose_chain
from symkin.model import coordinates, joint_kinds, tree


@quantity("chain", "link frames, joint axes and TCP frame of the serial chain", emitted=False)
def chain_frames(d: Deriving) -> ChainFrames:
    return compose_chain(d.model)


@quantity("fk", "forward kinematics: base_T_tcp (4x4)")
def forward_kinematics(d: Deriving) -> FunctionSpec:
    chain: ChainFrames = d[chain_frames]
    return make_function(
        d.model, "fk", "Forward kinematics: pose of the TCP in the base frame.",
        "base_T_tcp = base_T_1 * 1_T_2 * ... * n_T_tcp (seed sec. 3.1, DH step 4).",
        [coordinate_input(d.model, "q")],
        [OutputSpec("base_T_tcp", chain.tcp.T, "homogeneous transform of the TCP frame in the base frame", "m")],
    )


@quantity("frames", "base_T_<link> (4x4) of every link frame")
def _frames(d: Deriving) -> FunctionSpec:
    chain: ChainFrames = d[chain_frames]
    return make_function(
        d.model, "frames", "Pose of every link frame in the base frame.",
        "base_T_<link> = base_T_1 * ... * (i-1)_T_i for each link i (seed sec. 3.1).",
        [coordinate_input(d.model, "q")],
        [OutputSpec(f"base_T_{name}", frame.T, f"homogeneous transform of frame '{name}' in the base frame", "m")
         for name, frame in chain.links],
    )


@quantity("task_coordinates", "task-space coordinates p = f(q) of the TCP (m)")
def _task_coordinates(d: Deriving) -> FunctionSpec:
    chain: ChainFrames = d[chain_frames]
    p = task_space.coordinates(d.model.task_space, chain.tcp)
    units = ", ".join(f"{c} [{task_space.UNITS[c]}]" for c in d.model.task_space)
    return make_function(
        d.model, "task_coordinates", "Task-space coordinates of the TCP.",
        f"p = f(q) (seed eq. 8.5) with p = [{units}].",
        [coordinate_input(d.model, "q")],
        [OutputSpec("p", p, f"task coordinates [{units}]", shape=(len(p),))],
    )


@quantity("jacobian_geometric_matrix", "geometric Jacobian matrix of the TCP (6 x n)", emitted=False)
def geometric_jacobian_matrix(d: Deriving) -> sympy.ImmutableMatrix:
    """Columns [z_i x (p_tcp - p_i); z_i] for revolute and [z_i; 0] for prismatic joints, times the
    coupling matrix A when joints mimic others (one column per coordinate)."""
    chain: ChainFrames = d[chain_frames]
    return _point_jacobian(d, chain, coordinates.coupling_matrix(d.model), sympy.Matrix(chain.tcp.p),
                           tree.tip_index(d.model))


def _point_jacobian(d: Deriving, chain: ChainFrames, coupling: sympy.Matrix | None, point: sympy.Matrix,
                    link: int) -> sympy.ImmutableMatrix:
    """The geometric Jacobian (6 x coordinates) of a frame at ``point`` carried by joint ``link``'s link: the
    joints from the base to that link move it, those on other branches give zero columns; times the coupling
    matrix A where joints mimic others."""
    moving = set(tree.path_to(tree.parent_indices(d.model), link))
    columns = []
    for k, axis in enumerate(chain.axes):
        if k not in moving:  # a joint on another branch
            columns.append(sympy.zeros(6, 1))
            continue
        linear, angular = joint_kinds.twist_column(axis.type.turns, axis.direction, axis.point, point)
        columns.append(sympy.Matrix(linear + angular))
    J = sympy.Matrix.hstack(*columns)
    return sympy.ImmutableMatrix(J if coupling is None else J * coupling)


@quantity("frame_jacobians", "geometric Jacobian base_J_<link> (6 x n) of every link frame")
def _frame_jacobians(d: Deriving) -> FunctionSpec:
    chain: ChainFrames = d[chain_frames]
    coupling = coordinates.coupling_matrix(d.model)
    return make_function(
        d.model, "frame_jacobians", "Geometric Jacobian of every link frame in the base frame.",
        "[v; w] = base_J_<link> qd with v the velocity of the link frame's origin and w the link's angular velocity, "
        "both in the base frame (jacobian_geometric's columns for each link, Pinocchio's LOCAL_WORLD_ALIGNED frame "
        "Jacobian); joints on other branches of a tree give zero columns.",
        [coordinate_input(d.model, "q")],
        [OutputSpec(f"base_J_{name}", _point_jacobian(d, chain, coupling, sympy.Matrix(frame.p), k),
                    f"rows vx, vy, vz, wx, wy, wz of frame '{name}'; one column per coordinate")
         for k, (name, frame) in enumerate(chain.links)],
    )


@quantity("jacobian_geometric", "geometric Jacobian of the TCP, [v; w] = J qd (6 x n, base frame)")
def _jacobian_geometric(d: Deriving) -> FunctionSpec:
    return make_function(
        d.model, "jacobian_geometric", "Geometric Jacobian of the TCP in the base frame.",
        "[v; w] = J qd with v the TCP velocity and w the angular velocity, both in the base frame; "
        "column i is [z_i x (p_tcp - p_i); z_i] for a revolute and [z_i; 0] for a prismatic joint.",
        [coordinate_input(d.model, "q")],
        [OutputSpec("J", d[geometric_jacobian_matrix], "rows vx, vy, vz, wx, wy, wz; one column per joint")],
    )


@quantity("jacobian", "task Jacobian J = dp/dq (m x n, task space of the model)")
def task_jacobian(d: Deriving) -> FunctionSpec:
    chain: ChainFrames = d[chain_frames]
    components = d.model.task_space
    J = task_space.jacobian_rows(components, sympy.Matrix(d[geometric_jacobian_matrix]), chain.tcp,
                                 coordinates.symbols(d.model, "q"))
    return make_function(
        d.model, "jacobian", "Task Jacobian of the TCP.",
        f"J = d[{', '.join(components)}]/dq, dp = J dq (seed sec. 4 'Jacobian Matrix', eq. 8.29).",
        [coordinate_input(d.model, "q")],
        [OutputSpec("J", J, f"rows {', '.join(components)}; one column per joint")],
    )
