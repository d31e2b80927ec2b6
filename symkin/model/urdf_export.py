"""Write a serial model as a URDF: the robot description ROS, Pinocchio, MuJoCo and simulators read.

The URDF's link frames are the model's link frames, so ``base_T_<link>`` of symkin and the
frame placement of ``<link>`` in any URDF reader are the same transform:

* the root link ``base`` is the model's base frame; joint i (the model's coordinate) goes from
  the previous link (``base`` for the first) with ``<origin>`` = [the model's ``base``
  operations, for the first joint] * ``before_i`` * Motion(offset_i), about or along
  ``axis_i``; its child is ``<link_i>`` itself when ``after_i`` is the identity, else the
  link ``<link_i>__joint`` followed by a fixed joint with ``<origin>`` = ``after_i``;
* a fixed joint from the last link to the link ``tcp`` carries the model's TCP operations;
* each body becomes a link fixed to its model link at its centre of mass, whose
  ``<inertial>`` holds its mass and inertia tensor (link axes, about the centre of mass);
  readers merge fixed links into their parent, so a link may carry several bodies;
* revolute joints without limits are ``continuous``; limits, velocity and effort limits are
  written where the model declares them (``effort="0" velocity="0"`` otherwise, as the
  URDF requires the attributes); friction becomes ``<dynamics damping friction>``; joint springs and stops on
  combinations of joints, which URDF cannot express, are listed in a comment.

Every number is the model's expression at the parameters' default values, printed with
``repr`` (the shortest decimal that reads back as the same double); rotations are written as
``rpy`` = (roll, pitch, yaw) with R = Rz(yaw) Ry(pitch) Rx(roll), URDF's convention.  The
model's gravity is not part of a URDF: readers take it from their own setting.
"""

from __future__ import annotations

import math
from xml.sax.saxutils import quoteattr

import numpy as np
import sympy

from symkin.errors import ModelError
from symkin.model import joint_kinds, tree
from symkin.model.schema import Model, Op, Rotation

ROOT_LINK = "base"
TCP_LINK = "tcp"


def _number(expr: sympy.Expr, values: dict) -> float:
    return float(sympy.sympify(expr).xreplace(values))


def rotation_about(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues' formula: the rotation by ``angle`` about the unit ``axis``."""
    x, y, z = axis / np.linalg.norm(axis)
    c, s, t = math.cos(angle), math.sin(angle), 1 - math.cos(angle)
    return np.array([[c + x * x * t, x * y * t - z * s, x * z * t + y * s],
                     [y * x * t + z * s, c + y * y * t, y * z * t - x * s],
                     [z * x * t - y * s, z * y * t + x * s, c + z * z * t]])


def _transform(ops: tuple[Op, ...], values: dict) -> np.ndarray:
    """The 4x4 transform of moving-frame operations, applied left to right."""
    T = np.eye(4)
    for op in ops:
        step = np.eye(4)
        if isinstance(op, Rotation):
            step[:3, :3] = rotation_about(np.array([_number(a, values) for a in op.axis]), _number(op.angle, values))
        else:
            step[:3, 3] = [_number(v, values) for v in op.vector]
        T = T @ step
    return T


def urdf_rpy(R: np.ndarray) -> tuple[float, float, float]:
    """(roll, pitch, yaw) with R = Rz(yaw) Ry(pitch) Rx(roll); at pitch = +-pi/2 roll is 0."""
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    if math.hypot(R[0, 0], R[1, 0]) < 1e-12:
        return 0.0, pitch, math.atan2(-R[0, 1], R[1, 1])
    return math.atan2(R[2, 1], R[2, 2]), pitch, math.atan2(R[1, 0], R[0, 0])


def _origin(T: np.ndarray) -> str:
    xyz = " ".join(repr(float(v)) for v in T[:3, 3])
    rpy = " ".join(repr(float(v)) for v in urdf_rpy(T[:3, :3]))
    return f'<origin xyz="{xyz}" rpy="{rpy}"/>'


def _is_identity(T: np.ndarray) -> bool:
    return bool(np.array_equal(T, np.eye(4)))


def xml_comment(text: str) -> str:
    """``<!-- text -->`` that stays one comment whatever ``text`` holds (a file name is hostile text): XML allows
    no "--" inside a comment, so a model file named my--arm.yaml would leave the document malformed, and "-->"
    would end the comment early; every "--" becomes "- -" (the space before the end keeps a final "-" apart)."""
    while "--" in text:
        text = text.replace("--", "- -")
    return f"<!-- {text} -->"


def export_urdf(model: Model) -> str:
    """The URDF text of the serial ``model`` (see the module docstring).

    Raises:
        ModelError: a parallel model (a URDF describes trees, not closed loops).
    """
    if model.parallel is not None:
        raise ModelError([model.problem(("parallel",), "a URDF describes kinematic trees; a parallel mechanism "
                                                       "has closed loops and cannot be written as one",
                                        "export a serial model, or model one leg as a serial chain")])
    values = model.parameter_values
    taken = {ROOT_LINK, TCP_LINK} & {j.link for j in model.joints}
    if taken:
        raise ModelError([model.problem(("serial",), f"the link name '{sorted(taken)[0]}' is the exported URDF's "
                                                     "own (its root link is 'base', the TCP link 'tcp')",
                                        "rename that link of the model")])
    friction = {f.joint: f for f in model.friction}
    lines = ['<?xml version="1.0"?>',
             xml_comment(f"{model.name}: exported by symkin from {model.source} (model {model.hash}); numbers at "
                         "the parameters' default values"),
             f"<robot name={quoteattr(model.name)}>", f'  <link name="{ROOT_LINK}"/>']
    if model.springs:  # URDF has no element for them: said in the file, not dropped unseen
        springs = ", ".join(f"{s.joint} (k = {_number(s.stiffness, values)!r}, theta_0 = {_number(s.reference, values)!r})"
                            for s in model.springs)
        lines.insert(2, xml_comment(f"joint springs of the model, which URDF cannot hold: {springs}"))
    if model.joint_stops:  # nor stops on combinations of joints
        stops = ", ".join(f"{_number(s.lower, values)!r} <= {s.expression} <= {_number(s.upper, values)!r}"
                          for s in model.joint_stops)
        lines.insert(2, xml_comment(f"joint stops of the model, which URDF cannot hold: {stops}"))
    base = _transform(model.base, values)
    for joint, p in zip(model.joints, tree.parent_indices(model)):
        parent, pending = (ROOT_LINK, base) if p < 0 else (model.joints[p].link, np.eye(4))
        axis = np.array([_number(a, values) for a in joint.axis])
        # the joint frame at the coordinate 0: moved by the joint's offset
        origin = pending @ _transform(joint.before + (joint.motion(joint.offset),), values)
        after = _transform(joint.after, values)
        child = joint.link if _is_identity(after) else f"{joint.link}__joint"
        kind = joint_kinds.per_coordinate(joint.type, "revolute" if joint.limits is not None else "continuous",
                                          "prismatic")
        lines.append(f"  <link name={quoteattr(child)}/>")
        lines.append(f"  <joint name={quoteattr(joint.name)} type=\"{kind}\">")
        lines.append(f"    <parent link={quoteattr(parent)}/><child link={quoteattr(child)}/>")
        lines.append(f"    {_origin(origin)}")
        lines.append(f'    <axis xyz="{" ".join(repr(float(a)) for a in axis / np.linalg.norm(axis))}"/>')
        # URDF's continuous joint needs no bounds; a prismatic one without limits gets wide ones
        limit = joint_kinds.per_coordinate(joint.type, "", 'lower="-1e9" upper="1e9" ')
        if joint.limits is not None:
            lower, upper = (_number(b, values) for b in joint.limits)
            limit = f'lower="{lower!r}" upper="{upper!r}" '
        effort = _number(joint.effort_limit, values) if joint.effort_limit is not None else 0.0
        velocity = _number(joint.velocity_limit, values) if joint.velocity_limit is not None else 0.0
        lines.append(f'    <limit {limit}effort="{effort!r}" velocity="{velocity!r}"/>')
        coupling = joint.coupling
        if coupling is not None and coupling.leader is not None and joint.follower:  # URDF's <mimic> has one leader
            lines.append(f"    <mimic joint={quoteattr(coupling.leader)} "
                         f'multiplier="{_number(coupling.multiplier, values)!r}" '
                         f'offset="{_number(coupling.offset, values)!r}"/>')
        if joint.name in friction:
            f = friction[joint.name]
            lines.append(f'    <dynamics damping="{_number(f.viscous, values)!r}" '
                         f'friction="{_number(f.coulomb, values)!r}"/>')
        lines.append("  </joint>")
        if child != joint.link:
            lines.append(f"  <link name={quoteattr(joint.link)}/>")
            lines.append(f"  <joint name={quoteattr(joint.name + '__after')} type=\"fixed\">")
            lines.append(f"    <parent link={quoteattr(child)}/><child link={quoteattr(joint.link)}/>")
            lines.append(f"    {_origin(after)}")
            lines.append("  </joint>")
    tip = model.joints[tree.tip_index(model)].link if model.joints else ROOT_LINK
    lines.append(f'  <link name="{TCP_LINK}"/>')
    lines.append(f'  <joint name="{TCP_LINK}_joint" type="fixed">')
    lines.append(f'    <parent link={quoteattr(tip)}/><child link="{TCP_LINK}"/>')
    lines.append(f"    {_origin(_transform(model.tcp, values))}")
    lines.append("  </joint>")
    for k, body in enumerate(model.bodies):
        name = f"{body.link}__body{k}"
        I = [[_number(body.inertia[i, j], values) for j in range(3)] for i in range(3)]
        lines.append(f"  <link name={quoteattr(name)}>")
        lines.append(f'    <inertial><mass value="{_number(body.mass, values)!r}"/>')
        lines.append(f'      <inertia ixx="{I[0][0]!r}" iyy="{I[1][1]!r}" izz="{I[2][2]!r}" ixy="{I[0][1]!r}" '
                     f'ixz="{I[0][2]!r}" iyz="{I[1][2]!r}"/></inertial>')
        lines.append("  </link>")
        com = " ".join(repr(_number(c, values)) for c in body.com)
        lines.append(f"  <joint name={quoteattr(name + '_joint')} type=\"fixed\">")
        lines.append(f"    <parent link={quoteattr(body.link)}/><child link={quoteattr(name)}/>")
        lines.append(f'    <origin xyz="{com}" rpy="0 0 0"/>')
        lines.append("  </joint>")
    lines.append("</robot>")
    return "\n".join(lines) + "\n"
