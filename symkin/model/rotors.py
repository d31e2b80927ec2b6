"""Gyroscopic rotors (issue 30): the motor of a joint as a body of its own, spinning on the link that carries it.

The reflected-inertia model (``actuators:`` without ``gyroscopic``) adds N^2 J_m to M's diagonal: the
rotor's kinetic energy 1/2 J_m (N qd_i)^2 alone. A rotor mounted on the link before joint i (its
carrier) turns with that link as well, at w_carrier + N qd_i z_i, so its kinetic energy is
1/2 J_m (z_i . w_carrier + N qd_i)^2 (axial inertia only; Spong, "Modeling and control of elastic joint
robots", J. Dyn. Sys. Meas. Control 109(4), 1987, eq. 6; Featherstone, *Rigid Body Dynamics
Algorithms*, 2008, sec. 9.4, the gear as a constraint between the rotor and the joint). The cross
term couples the rotor with every joint before it in M and V.

It is built from what the model format already has: a follower joint ``<joint>_rotor`` on the carrier
link (``parent:``), at joint i's frame and about its axis, whose angle is N q_i (``coupling``), carrying
a body ``<link>_rotor`` of inertia J_m z z^T. A, the tree and Newton-Euler then give the exact
dynamics, and N^2 J_m reappears on M's diagonal through A^T M A.
"""

from __future__ import annotations

import dataclasses

import sympy

from symkin.model import tree
from symkin.model.reader import Reader
from symkin.model.schema import Actuator, Body, Coupling, Joint
from symkin.model.yaml_source import KeyPath

ZERO = sympy.Integer(0)


def with_rotors(r: Reader, joints: tuple[Joint, ...], actuators: tuple[Actuator, ...], bodies: tuple[Body, ...],
                path: KeyPath = ("actuators",)) -> tuple[tuple[Joint, ...], tuple[Body, ...]]:
    """The joints with a rotor joint before each joint whose actuator is ``gyroscopic``, and the bodies
    with the rotors' (problems: a prismatic or coupled joint, a name already taken)."""
    gyroscopic = {a.joint: a for a in actuators if a.gyroscopic}
    if not gyroscopic:
        return joints, bodies
    names = {j.name for j in joints} | {j.link for j in joints}
    out: list[Joint] = []
    rotors: list[Body] = []
    parents = tree.parent_indices_of(joints)
    for k, joint in enumerate(joints):
        drive = gyroscopic.get(joint.name)
        # every joint names its parent from here on: a rotor joint is inserted between them
        carrier = tree.BASE if parents[k] < 0 else joints[parents[k]].link
        if drive is None:
            out.append(dataclasses.replace(joint, parent=carrier))
            continue
        where = path + (joint.name, "gyroscopic")
        if not joint.turns or joint.coupling is not None:
            r.fail(where, f"joint '{joint.name}' is {'coupled' if joint.coupling is not None else 'prismatic'}: "
                         "a gyroscopic rotor turns N times a revolute joint's own coordinate",
                   "drop 'gyroscopic' (the reflected inertia N^2 J_m stays)")
            out.append(dataclasses.replace(joint, parent=carrier))
            continue
        name, link = f"{joint.name}_rotor", f"{joint.link}_rotor"
        taken = sorted({name, link} & names)
        if taken:
            r.fail(where, f"the rotor's joint or link name '{taken[0]}' is taken", "rename that joint or link")
        out.append(Joint(name=name, type=joint.type, axis=joint.axis, offset=ZERO, before=joint.before, after=(),
                         link=link, coupling=Coupling(((joint.name, drive.gear_ratio),), ZERO), parent=carrier))
        axis = sympy.Matrix(joint.axis)
        rotors.append(Body(link, ZERO, (ZERO, ZERO, ZERO),
                           sympy.ImmutableMatrix(drive.rotor_inertia * axis * axis.T / (axis.T * axis)[0, 0])))
        out.append(dataclasses.replace(joint, parent=carrier))
    return tuple(out), bodies + tuple(rotors)
