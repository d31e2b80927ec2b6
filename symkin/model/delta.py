"""The DELTA shorthand: a 3-RUU translational parallel mechanism from its parameters alone.

Geometry of seed sec. 3.2.1 (Fig. 8.14), in the base frame (z up, x towards leg 1):

* leg i sits at the angle phi_i; its frame A_i is ``base_T_A_i = Rz(phi_i) Tx(r_A)``.  (The
  seed calls this "a rotation by -phi_i" but prints the matrix of Rz(+phi_i); with the
  matrix, A_i = r_A (cos phi_i, sin phi_i, 0), which is what is built here.)
* the actuated revolute joint theta_i turns the upper arm (length a) in the x-z plane of
  A_i: ``A_i_T_C_i = Tx(a cos theta_i) Tz(a sin theta_i)`` as in the seed, i.e. a rotation
  about -y of A_i; theta_i = 0 is horizontal, outwards; positive raises the arm.
* the lower arm (length b) joins the elbow C_i to the platform joint B_i through two
  universal joints (RUU, seed sec. 2.2.2); the axes follow the TPM pattern: the elbow U has
  its first axis parallel to the actuator, its second perpendicular; the wrist U has them in
  the opposite order, so the platform keeps its orientation.
* the platform joint B_i lies at ``P + Rz(phi_i) (r_B, 0, 0)``.  (The seed's B_i_T_TCP
  translates by (r_TCP cos phi_i, -r_TCP sin phi_i, 0) in the B_i frame, which would put the
  TCP at B_i + (r_TCP, 0, 0) in *base* axes for every leg; the consistent transform, used
  also for the seed's virtual frame C'_i = C_i - r_TCP x_Ci, is Tx(-r_TCP) in B_i axes.)

The radius convention is explicit: ``radius`` is the circumradius of the (equilateral)
triangle of the base or platform, ``side`` its side length; ``joint_at`` says whether the
joint sits at a vertex (joint radius = circumradius) or at a side midpoint (joint radius =
inradius = circumradius / 2).  The seed's r_base and r_TCP are joint radii (centre to
joint), i.e. ``joint_at: vertex`` with ``radius: r_base``.

Passive-joint limits: ``elbow_limits`` and ``wrist_limits`` bound the two motions of every
elbow and wrist universal joint (``[[lower, upper] | null, [lower, upper] | null]``, on the
variables ``elbow<i>_1``, ``elbow<i>_2``, ``wrist<i>_1``, ``wrist<i>_2``): ``elbow<i>_1`` is the
knee bend about the actuator axis (0 with the rod continuing the upper arm), ``elbow<i>_2`` the
swing of the rod out of the leg plane; the wrist undoes both so that the platform keeps its
orientation, ``wrist<i>_1 = -elbow<i>_2`` and ``wrist<i>_2 = -(theta_i + elbow<i>_1)`` (minus
the rod's elevation in the leg plane).  The U joints and ball joints of haptic DELTAs reach
some +/-30 to 60 deg; the workspace analyses drop the poses beyond the declared ranges
(:mod:`symkin.mechanism.passive`).

Actuators: ``actuator_limits`` bound every actuated angle, ``actuator_effort_limit`` and
``actuator_velocity_limit`` are every actuator's largest torque and speed (the coordinates'
``effort_limit`` and ``velocity_limit``).

Branches: the inverse kinematics takes the knee pointing outwards (``ik_branch: negative``:
the platform joint B_i is reached from the elbow C_i by a negative rotation about the
actuator axis -y_Ai); the forward kinematics the TCP hanging below its elbows.
"""

from __future__ import annotations

import math
from typing import Any

import sympy

from symkin.model.leg_joints import leg_joint_limits, variable_names
from symkin.model.reader import ZERO, Reader, describe, ops, position_limits, positive_limit
from symkin.model.schema import Leg, LegJoint, LegJointType, Rotation, Translation, Vec3
from symkin.model.yaml_source import KeyPath

DELTA_KEYS = ("base", "platform", "upper_arm", "lower_arm", "leg_angles", "actuator", "actuator_limits",
              "actuator_velocity_limit", "actuator_effort_limit", "elbow_limits", "wrist_limits")
JOINT_AT = ("vertex", "side_midpoint")

MINUS_Y: Vec3 = (ZERO, sympy.Integer(-1), ZERO)
PLUS_Z: Vec3 = (ZERO, ZERO, sympy.Integer(1))
#: Knee outwards: B_i lies at a negative rotation about the actuator axis (-y_Ai) from C_i.
KNEE_OUT_BRANCH = -1


def joint_radius(r: Reader, path: KeyPath, value: Any) -> sympy.Expr | None:
    """Distance from the centre to the joints of an equilateral triangle with an explicit convention.

    ``{joint_at: vertex | side_midpoint, radius: R}`` (R: circumradius) or
    ``{joint_at: ..., side: s}`` (R = s / sqrt(3)); the joint radius is R at a vertex and
    R / 2 (the inradius) at a side midpoint.
    """
    section = r.mapping(path, value, required=("joint_at",), optional=("radius", "side"))
    if section is None or "joint_at" not in section:
        return None
    if section["joint_at"] not in JOINT_AT:
        r.fail(path + ("joint_at",), f"unknown joint position {describe(section['joint_at'])}",
               "write 'vertex' (joint at a corner of the triangle) or 'side_midpoint' (at the middle of a side)")
        return None
    if ("radius" in section) == ("side" in section):
        r.fail(path, "give exactly one of 'radius:' (centre to triangle vertex) or 'side:' (triangle side length)",
               "keep one of the two keys")
        return None
    key = "radius" if "radius" in section else "side"
    size = r.expr(path + (key,), section[key])
    if size is None:
        return None
    numeric = r.default_value(size)
    if numeric is not None and numeric < 0:
        r.fail(path + (key,), f"the {key} must not be negative, got {size}", "write a length >= 0")
        return None
    circumradius = size if key == "radius" else size / sympy.sqrt(3)
    return circumradius if section["joint_at"] == "vertex" else circumradius / 2


def delta_legs(r: Reader, path: KeyPath, value: Any) -> tuple[tuple[Leg, ...], int] | None:
    """The three RUU legs and the forward-kinematics branch of a DELTA."""
    section = r.mapping(path, value, required=DELTA_KEYS[:5], optional=DELTA_KEYS[5:])
    if section is None or any(k not in section for k in DELTA_KEYS[:5]):
        return None
    r_base = joint_radius(r, path + ("base",), section["base"])
    r_platform = joint_radius(r, path + ("platform",), section["platform"])
    lengths = [_length(r, path + (key,), section[key]) for key in ("upper_arm", "lower_arm")]
    angles = _angles(r, path + ("leg_angles",), section["leg_angles"])
    prefix = r.name(path + ("actuator",), section["actuator"]) if "actuator" in section else "theta"
    limits: tuple[tuple[sympy.Expr, sympy.Expr], ...] = ()
    if "actuator_limits" in section:
        bounds = position_limits(r, path + ("actuator_limits",), section["actuator_limits"], revolute=True)
        if bounds is None:
            return None
        limits = (bounds,)
    elbow, wrist = (leg_joint_limits(r, path + (key,), section[key], LegJointType.U) if key in section else ()
                    for key in ("elbow_limits", "wrist_limits"))
    actuator = {}
    for key in ("velocity_limit", "effort_limit"):
        if f"actuator_{key}" in section:
            actuator[key] = positive_limit(r, path + (f"actuator_{key}",), section[f"actuator_{key}"], revolute=True)
            if actuator[key] is None:
                return None
    if r_base is None or r_platform is None or None in lengths or angles is None or prefix is None \
            or elbow is None or wrist is None:
        return None
    upper, lower = lengths
    legs = []
    for i, phi in enumerate(angles):
        n = i + 1
        joints = (
            _joint(f"{prefix}{n}", LegJointType.R, (MINUS_Y,), (), active=0, limits=limits, **actuator),
            _joint(f"elbow{n}", LegJointType.U, (MINUS_Y, PLUS_Z), ops(Translation((upper, ZERO, ZERO))),
                   limits=elbow),
            _joint(f"wrist{n}", LegJointType.U, (PLUS_Z, MINUS_Y), ops(Translation((lower, ZERO, ZERO))),
                   limits=wrist),
        )
        base = ops(Rotation(PLUS_Z, phi), Translation((r_base, ZERO, ZERO)))
        platform = ops(Rotation(PLUS_Z, phi), Translation((r_platform, ZERO, ZERO)))
        legs.append(Leg(f"leg{n}", base, joints, platform, KNEE_OUT_BRANCH))
    orientation = _orientation(r, path + ("leg_angles",), angles)
    if orientation is None:
        return None
    # Below the elbows: the side opposite to n = (S2 - S1) x (S3 - S1), which points up when the
    # legs go round counter-clockwise (seen from +z).
    return tuple(legs), -orientation


def _joint(name: str, jtype: LegJointType, axes: tuple[Vec3, ...], origin: tuple, active: int | None = None,
           limits: tuple = (), **actuator: Any) -> LegJoint:
    return LegJoint(name, jtype, axes, origin, variable_names(name, jtype), active, limits=limits, **actuator)


def _length(r: Reader, path: KeyPath, value: Any) -> sympy.Expr | None:
    length = r.expr(path, value)
    if length is None:
        return None
    numeric = r.default_value(length)
    if numeric is not None and numeric <= 0:
        r.fail(path, f"an arm length must be positive, got {length}", "write a positive length")
        return None
    return length


def _angles(r: Reader, path: KeyPath, value: Any) -> list[sympy.Expr] | None:
    items = r.sequence(path, value, 3, "leg angles phi_1, phi_2, phi_3")
    if items is None:
        return None
    angles = [r.expr(path + (i,), v) for i, v in enumerate(items)]
    return None if any(a is None for a in angles) else angles


def _orientation(r: Reader, path: KeyPath, angles: list[sympy.Expr]) -> int | None:
    """+1 if the legs go round counter-clockwise (seen from +z), -1 if clockwise."""
    values = [v for v in (r.default_value(a) for a in angles) if v is not None]
    if len(values) != len(angles):
        return 1  # symbolic angles: counter-clockwise as in the seed (phi_i = (i - 1) 120 deg)
    (x1, y1), (x2, y2), (x3, y3) = [(math.cos(v), math.sin(v)) for v in values]
    cross = (x2 - x1) * (y3 - y1) - (y2 - y1) * (x3 - x1)
    if abs(cross) < 1e-9:
        r.fail(path, "two leg angles coincide or the legs are on one line",
               "spread the legs around the base, e.g. [0, deg(120), deg(240)]")
        return None
    return 1 if cross > 0 else -1
