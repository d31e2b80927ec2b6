"""The ``bodies:`` (mass, centre of mass, inertia tensor in any frame) and ``friction:`` sections."""

from __future__ import annotations

import dataclasses
import difflib
from collections.abc import Iterator, Mapping, Sequence
from typing import Any

import numpy as np
import sympy

from symkin.geometry import rotation_matrix
from symkin.model.reader import X_AXIS, Y_AXIS, Z_AXIS, ZERO, Reader, describe, frame_ops
from symkin.model import joint_kinds
from symkin.model.schema import (Actuator, Body, Friction, Joint, Parallel, ParallelBodies, PlatformMotion, Spring,
                                 Vec3, fixed_pose)
from symkin.model.yaml_source import KeyPath
from symkin.model.units import (ANGLE, ANGULAR_DAMPING, ANGULAR_STIFFNESS, CURRENT, FORCE, INERTIA, LENGTH,
                                LINEAR_DAMPING, MASS, RATIO, STIFFNESS, TORQUE, TORQUE_CONSTANT)

_INERTIA_KEYS = ("xx", "yy", "zz", "xy", "xz", "yz")


def read_bodies(r: Reader, value: Any, links: tuple[str, ...], path: KeyPath = ("bodies",)) -> tuple[Body, ...]:
    """The bodies of a serial model's links (``bodies:``, or a hybrid device's ``wrist.bodies``)."""
    items = r.sequence(path, value, what="bodies")
    if items is None:
        return ()
    bodies = []
    for i, item in enumerate(items):
        bpath = path + (i,)
        item = r.mapping(bpath, item, required=("link", "mass"), optional=("com", "inertia", "inertia_rpy", "origin"))
        if item is None or "link" not in item or "mass" not in item:
            continue
        link = r.name(bpath + ("link",), item["link"])  # a name, not any YAML value (lists are unhashable)
        if link is None or link in r.invalid_links:
            continue  # its joint is already reported
        if link not in links:
            close = difflib.get_close_matches(str(link), links, n=1)
            hint = f"did you mean '{close[0]}'? " if close else ""
            r.fail(bpath + ("link",), f"unknown link {describe(link)}", f"{hint}links: {', '.join(links)}")
            continue
        body = _mass_properties(r, bpath, item, link)
        if body is not None:
            bodies.append(body)
    return tuple(bodies)


def _mass_properties(r: Reader, path: KeyPath, item: dict[str, Any], link: str) -> Body | None:
    """The Body of a mapping with ``mass`` and optional ``com``, ``inertia``, ``inertia_rpy``, ``origin``."""
    mass = r.expr(path + ("mass",), item["mass"], dimension=MASS)
    com = r.vector3(path + ("com",), item["com"], LENGTH) if "com" in item else (ZERO, ZERO, ZERO)
    inertia = _inertia(r, path + ("inertia",), item["inertia"]) if "inertia" in item else sympy.zeros(3, 3)
    if "inertia_rpy" in item and inertia is not None:
        inertia = _rotate_inertia(r, path + ("inertia_rpy",), item["inertia_rpy"], inertia)
    if "origin" in item and com is not None and inertia is not None:
        com, inertia = _body_in_link_frame(r, path + ("origin",), item["origin"], com, inertia)
    if mass is None or com is None or inertia is None or _negative(r, path + ("mass",), mass, "mass"):
        return None
    if "inertia" in item:
        _check_inertia_physical(r, path + ("inertia",), inertia, mass, com)
    return Body(link, mass, com, sympy.ImmutableMatrix(inertia))


def _negative(r: Reader, path: KeyPath, value: sympy.Expr, what: str) -> bool:
    """True (and a recorded problem) if ``value`` is negative at the default parameter values."""
    v = r.default_value(value)
    if v is not None and v < 0:
        r.fail(path, f"negative {what} {value} ({v:g} at the default values)", f"a {what} is zero or positive")
        return True
    return False


#: keys of a parallel model's ``bodies:`` (:class:`~symkin.model.schema.ParallelBodies`)
PARALLEL_BODY_KEYS = ("platform", "actuated_link", "distal_link", "rod", "rotor", "links")
_MASS_KEYS = ("mass", "com", "inertia", "inertia_rpy", "origin")


def read_parallel_bodies(r: Reader, value: Any) -> ParallelBodies | None:
    """``bodies:`` of a parallel model: the platform, and on every leg the actuated link, the rod
    (point masses at its ends, or a slender rod with its inertia across it) or a spherical leg's distal
    link, and the actuator's rotor; or, for legs without the distance form, the link each leg joint moves
    (``links: {JOINT: {mass, com, inertia}}``, checked against the legs by :func:`check_leg_bodies`)."""
    path: KeyPath = ("bodies",)
    section = r.mapping(path, value, optional=PARALLEL_BODY_KEYS)
    if section is None:
        return None
    fields: dict[str, Any] = {}
    for key in ("platform", "actuated_link", "distal_link"):
        if key in section:
            item = r.mapping(path + (key,), section[key], required=("mass",), optional=_MASS_KEYS[1:])
            if item is not None and "mass" in item:
                fields[key] = _mass_properties(r, path + (key,), item, key)
    scalars = {"rod": {"mass": "rod_mass", "platform_fraction": "rod_platform_fraction", "inertia": "rod_inertia"},
               "rotor": {"inertia": "rotor_inertia", "gear_ratio": "gear_ratio"}}
    dimensions = {"mass": MASS, "platform_fraction": RATIO, "inertia": INERTIA, "gear_ratio": RATIO}
    for key, names in scalars.items():
        if key not in section:
            continue
        item = r.mapping(path + (key,), section[key], optional=tuple(names))
        for name, field_name in names.items():
            if item is None or name not in item:
                continue
            amount = r.expr(path + (key, name), item[name], dimension=dimensions[name], bare=name == "inertia")
            if amount is not None and not _negative(r, path + (key, name), amount, name.replace("_", " ")):
                fields[field_name] = amount
    if "links" in section:
        fields["links"] = _leg_links(r, path + ("links",), section["links"])
    fraction = r.default_value(fields.get("rod_platform_fraction", ZERO))
    if fraction is not None and fraction > 1:
        r.fail(path + ("rod", "platform_fraction"), f"the fraction of the rod mass at the platform is {fraction:g}",
               "give a number between 0 (all at C_i) and 1 (all at the platform joint B_i)")
    return ParallelBodies(**fields)


def _leg_links(r: Reader, path: KeyPath, value: Any) -> tuple[Body, ...]:
    """``links:`` - {leg joint name: mass properties of the link it moves}."""
    if not isinstance(value, dict):
        r.fail(path, f"expected a mapping, got {describe(value)}",
               "write a mapping from leg joint names to {mass, com, inertia}, e.g. 'theta1: {mass: 0.1}'")
        return ()
    bodies = []
    for key, item in value.items():
        name = r.name(path + (key,), key)
        item = r.mapping(path + (key,), item, required=("mass",), optional=_MASS_KEYS[1:])
        if name is not None and item is not None and "mass" in item:
            body = _mass_properties(r, path + (key,), item, name)
            if body is not None:
                bodies.append(body)
    return tuple(bodies)


def check_leg_bodies(r: Reader, parallel: Parallel) -> None:
    """A spherical leg's link between its last two joints is a ``distal_link`` (its axes fix its orientation); the
    other legs' is a ``rod`` between its point joints; ``links:`` name joints of the legs, and do not mix with
    the distance form's lumped bodies."""
    bodies = parallel.bodies
    if bodies is None:
        return
    joints = [joint.name for leg in parallel.legs for joint in leg.joints]
    broken = r.reported_under("parallel.legs") or r.reported_under("parallel.chains")
    for body in bodies.links if not broken else ():  # the joints of legs with reported mistakes are missing
        if body.link not in joints:
            close = difflib.get_close_matches(body.link, joints, n=1)
            hint = f"did you mean '{close[0]}'? " if close else ""
            r.fail(("bodies", "links", body.link), f"no leg joint named {describe(body.link)}",
                   f"{hint}name the joint that moves the link, with its leg's number: {', '.join(joints)}")
    lumped = [key for key, present in (("actuated_link", bodies.actuated_link is not None),
                                       ("distal_link", bodies.distal_link is not None),
                                       ("rod", bodies.rod_mass != 0 or bodies.rod_inertia is not None)) if present]
    if bodies.links and lumped:
        r.fail(("bodies", "links"), f"'links:' (a body per leg joint, for legs without the distance form) cannot be "
               f"combined with {', '.join(lumped)} (the distance form's lumped bodies)",
               "declare every leg body under 'links:', or none")
    spherical = parallel.motion is PlatformMotion.SPHERICAL
    if spherical and (bodies.rod_mass != 0 or bodies.rod_inertia is not None):
        r.fail(("bodies", "rod"), "a spherical leg has no rod between point joints: its last two joints turn about "
               "axes through the centre", "declare the link between them as 'distal_link: {mass, com, inertia}'")
    if not spherical and bodies.distal_link is not None:
        r.fail(("bodies", "distal_link"), "a distal link's own inertia is derived for spherical legs only; this "
               f"platform's motion is {parallel.motion.value}", "declare the link between the point joints as "
               "'rod: {mass, platform_fraction, inertia}'")


def _body_in_link_frame(r: Reader, path: KeyPath, value: Any, com: Vec3, inertia: sympy.Matrix
                        ) -> tuple[Vec3 | None, sympy.Matrix | None]:
    """com and inertia given in a frame fixed to the link (``origin:``, one frame or a list),
    expressed in the link frame: c_link = p + R c, I_link = R I R^T with link_T_frame = (R, p)."""
    ops = frame_ops(r, path, value)
    if ops is None:
        return None, None
    R, p = fixed_pose(ops)
    c = p + R * sympy.Matrix(com)
    return (c[0], c[1], c[2]), R * inertia * R.T


def _inertia(r: Reader, path: KeyPath, value: Any) -> sympy.Matrix | None:
    """Inertia about the centre of mass: {xx, yy, zz, xy, xz, yz} or a symmetric 3x3 list."""
    if isinstance(value, dict):
        section = r.mapping(path, value, optional=_INERTIA_KEYS)
        if section is None:
            return None
        parts = {k: r.expr(path + (k,), section[k], dimension=INERTIA, bare=True) if k in section else ZERO
                 for k in _INERTIA_KEYS}
        if any(v is None for v in parts.values()):
            return None
        tensor = sympy.Matrix([[parts["xx"], parts["xy"], parts["xz"]],
                               [parts["xy"], parts["yy"], parts["yz"]],
                               [parts["xz"], parts["yz"], parts["zz"]]])
    else:
        rows = r.sequence(path, value, 3, "rows (or a mapping xx, yy, zz, xy, xz, yz)")
        if rows is None:
            return None
        entries: list[list[sympy.Expr | None]] = []
        for i, row in enumerate(rows):
            cols = r.sequence(path + (i,), row, 3, "entries")
            if cols is None:
                return None
            entries.append([r.expr(path + (i, j), v, dimension=INERTIA, bare=True) for j, v in enumerate(cols)])
        if any(v is None for row in entries for v in row):
            return None
        tensor = sympy.Matrix(entries)
        if (tensor - tensor.T).is_zero_matrix is not True:
            r.fail(path, "the inertia tensor is not symmetric", "make entry [i][j] equal to entry [j][i]")
            return None
    return tensor


def _rotate_inertia(r: Reader, path: KeyPath, value: Any, inertia: sympy.Matrix) -> sympy.Matrix | None:
    """Inertia given in axes rotated by rpy from the link frame (URDF <inertial><origin rpy>):
    I_link = R I R^T with R = Rz(yaw) Ry(pitch) Rx(roll)."""
    rpy = r.vector3(path, value, ANGLE)
    if rpy is None:
        return None
    roll, pitch, yaw = rpy
    R = rotation_matrix(Z_AXIS, yaw) * rotation_matrix(Y_AXIS, pitch) * rotation_matrix(X_AXIS, roll)
    return R * inertia * R.T


def _check_inertia_physical(r: Reader, path: KeyPath, tensor: sympy.Matrix, mass: sympy.Expr, com: Vec3) -> None:
    """At default parameter values the principal moments are >= 0 and obey the triangle inequality.

    A violation is judged against the body's size as the dynamics see it, max(largest moment,
    m |c|^2) with c the centre of mass in the link frame: one below 1e-12 of it (1e-9 for the
    triangle inequality) is rounding in the file (iCub's head: a lone product of inertia of 2.4e-35
    on a 1.3 kg body), invisible to any double computed from it.  A real violation is refused, or
    with ``allow_nonphysical`` (``--allow-nonphysical``) noted: every simulator loads such files, and
    M may then be indefinite, which forward dynamics and the analyses report as for a singular M.  Where the reader
    defers it (a serial model's bodies: ``defer_nonphysical``) it blocks only the outputs that use the inertias
    (:func:`symkin.dynamics.physical.require_physical`), and the kinematics derive.
    """
    given = [r.default_value(v) for v in (*tensor, mass, *com)]
    values = [v for v in given if v is not None]
    if len(values) < len(given):
        return
    moments = np.linalg.eigvalsh(np.array(values[:9], dtype=float).reshape(3, 3))
    m, c = values[9], np.array(values[10:], dtype=float)
    scale = max(1e-300, float(np.max(np.abs(moments))), m * float(c @ c))
    a, b, largest = moments
    if a >= -1e-12 * scale and a + b >= largest - 1e-9 * scale:
        return
    message = f"the inertia tensor is not physical (principal moments {a:.6g}, {b:.6g}, {largest:.6g})"
    fix = ("principal moments must be >= 0 and each at most the sum of the other two; to proceed as simulators do, "
           "pass --allow-nonphysical (or 'allow_nonphysical: true')")
    if r.allow_nonphysical:
        r.note(path, message + "; accepted (allow_nonphysical): M may be indefinite")
    elif r.defer_nonphysical:  # the kinematics do not use it: only the outputs that do are refused
        r.nonphysical.append(r.doc.problem(path, message, fix))
        r.note(path, message + ": the outputs that use the inertias (M, V, G, tau, regressors) are refused")
    else:
        r.fail(path, message, fix)


def _per_joint(r: Reader, path: KeyPath, value: Any, joint_names: tuple[str, ...]
               ) -> Iterator[tuple[str, KeyPath, Any]]:
    """(joint, key path, entry) of a section keyed by joint names (``friction:``, ``actuators:``); unknown
    joints are reported by the mapping check and skipped, and so are joints whose own mistake is reported."""
    section = r.mapping(path, value, optional=joint_names + tuple(sorted(r.invalid_joints)))
    for jname, spec in (section or {}).items():
        if jname in joint_names:
            yield jname, path + (jname,), spec


def read_friction(r: Reader, value: Any, joint_names: tuple[str, ...], path: KeyPath = ("friction",),
                  revolute: Mapping[str, bool] | None = None) -> tuple[Friction, ...]:
    """Per-joint friction (``friction:``, or a hybrid device's ``wrist.friction``); with ``revolute`` (by joint
    name) the coefficients' dimensions are checked: N m s/rad and N m for a revolute joint, N s/m and N for a
    prismatic one."""
    out = []
    for jname, fpath, spec in _per_joint(r, path, value, joint_names):
        spec = r.mapping(fpath, spec, optional=("viscous", "coulomb", "smoothing_velocity"))
        if spec is None:
            continue
        turns = None if revolute is None else revolute.get(jname)
        damping, level = ((None, None) if turns is None else (ANGULAR_DAMPING, TORQUE) if turns
                          else (LINEAR_DAMPING, FORCE))  # a smoothing velocity may be shared by both kinds
        viscous = r.expr(fpath + ("viscous",), spec["viscous"], dimension=damping) if "viscous" in spec else ZERO
        coulomb_negative = None
        if isinstance(spec.get("coulomb"), dict):  # {positive: c+, negative: c-}: a level per direction
            levels = r.mapping(fpath + ("coulomb",), spec["coulomb"], required=("positive", "negative"))
            if levels is None or "positive" not in levels or "negative" not in levels:
                continue
            coulomb = r.expr(fpath + ("coulomb", "positive"), levels["positive"], dimension=level)
            coulomb_negative = r.expr(fpath + ("coulomb", "negative"), levels["negative"], dimension=level)
            if coulomb_negative is None:
                continue
            _negative(r, fpath + ("coulomb", "negative"), coulomb_negative, "Coulomb friction level (a magnitude)")
        else:
            coulomb = r.expr(fpath + ("coulomb",), spec["coulomb"], dimension=level) if "coulomb" in spec else ZERO
        smoothing = r.expr(fpath + ("smoothing_velocity",), spec["smoothing_velocity"]) \
            if "smoothing_velocity" in spec else None
        if viscous is None or coulomb is None or ("smoothing_velocity" in spec and smoothing is None):
            continue
        for key, coeff in (("viscous", viscous), ("coulomb", coulomb)):
            v = r.default_value(coeff)
            if v is not None and v < 0:
                r.fail(fpath + (key,), f"negative {key} friction coefficient {coeff}",
                       "friction coefficients are zero or positive")
        if smoothing is not None:
            v = r.default_value(smoothing)
            if smoothing == 0 or (v is not None and v <= 0):
                r.fail(fpath + ("smoothing_velocity",), f"the smoothing velocity must be positive, got {smoothing}",
                       "give the speed below which Coulomb friction fades out, e.g. a parameter v_s: 0.01")
        out.append(Friction(jname, viscous, coulomb, smoothing, coulomb_negative))
    return tuple(out)


def read_springs(r: Reader, value: Any, joints: Sequence[Joint], path: KeyPath = ("springs",)) -> tuple[Spring, ...]:
    """``springs:`` of a serial model: {joint: {stiffness: k, reference: theta_0}}, k >= 0 in N m/rad (revolute)
    or N/m (prismatic), theta_0 (default 0) in rad or m; any joint of the chain or tree, followers included."""
    out = []
    kinds = {j.name: j for j in joints}
    for jname, spath, spec in _per_joint(r, path, value, tuple(kinds)):
        spec = r.mapping(spath, spec, required=("stiffness",), optional=("reference",))
        if spec is None or "stiffness" not in spec:
            continue
        jtype = kinds[jname].type
        stiffness = r.expr(spath + ("stiffness",), spec["stiffness"],
                           dimension=joint_kinds.per_coordinate(jtype, ANGULAR_STIFFNESS, STIFFNESS))
        reference = (r.expr(spath + ("reference",), spec["reference"],
                            dimension=joint_kinds.per_coordinate(jtype, ANGLE, LENGTH))
                     if "reference" in spec else ZERO)
        if stiffness is None or reference is None:
            continue
        _negative(r, spath + ("stiffness",), stiffness, "spring stiffness")
        out.append(Spring(jname, stiffness, reference))
    return tuple(out)


def read_actuators(r: Reader, value: Any, joint_names: tuple[str, ...], path: KeyPath = ("actuators",)
                   ) -> tuple[Actuator, ...]:
    """``actuators:`` of a serial model (or a hybrid device's wrist): {joint: {rotor_inertia, gear_ratio,
    torque_constant, peak_current, continuous_current}}, all >= 0 (the gear ratio > 0)."""
    out = []
    for jname, apath, spec in _per_joint(r, path, value, joint_names):
        spec = r.mapping(apath, spec, optional=ACTUATOR_KEYS + ("gyroscopic",))
        if spec is None:
            continue
        gyroscopic = spec.get("gyroscopic", False)
        if not isinstance(gyroscopic, bool):
            r.fail(apath + ("gyroscopic",), f"'gyroscopic' must be true or false, got {describe(gyroscopic)}",
                   "write true (the rotor as a body spinning on the link before) or false (reflected inertia)")
            continue
        values = {key: r.expr(apath + (key,), spec[key], dimension=ACTUATOR_DIMENSIONS[key],
                              bare=key == "rotor_inertia")
                  for key in ACTUATOR_KEYS if key in spec}
        if any(v is None for v in values.values()):
            continue
        inertia = values.get("rotor_inertia", sympy.Integer(0))
        gear = values.get("gear_ratio", sympy.Integer(1))
        for key in ("rotor_inertia", "torque_constant", "peak_current", "continuous_current"):
            if key in values:
                _negative(r, apath + (key,), values[key], key.replace("_", " "))
        if ("peak_current" in values or "continuous_current" in values) and "torque_constant" not in values:
            r.fail(apath, "a current limit needs the motor's torque constant to become a torque",
                   "add torque_constant: K_t (N m/A)")
        ratio = r.default_value(gear)
        if gear == 0 or (ratio is not None and ratio <= 0):
            r.fail(apath + ("gear_ratio",), f"the gear ratio must be positive, got {gear}",
                   "give the motor turns per joint turn, e.g. 13.3 for a capstan drive, 1 for direct drive")
        out.append(Actuator(jname, inertia, gear, values.get("torque_constant"), values.get("peak_current"),
                            values.get("continuous_current"), gyroscopic))
    return tuple(out)


#: Keys of one joint's entry of ``actuators:``.
ACTUATOR_KEYS = ("rotor_inertia", "gear_ratio", "torque_constant", "peak_current", "continuous_current")
#: ... and the dimension of each.
ACTUATOR_DIMENSIONS = {"rotor_inertia": INERTIA, "gear_ratio": RATIO, "torque_constant": TORQUE_CONSTANT,
                       "peak_current": CURRENT, "continuous_current": CURRENT}


def drive_of(name: str, joints: Sequence[Joint], actuators: Sequence[Actuator]) -> tuple[Actuator, sympy.Expr] | None:
    """The motor that drives joint ``name`` and the factor s from its joint torque to ``name``'s effort.

    A joint's own actuator (s = 1); else, for a coordinate, the one motor on a follower of it alone,
    q_f = a q + b (the PHANToM's q3 motor turns the parallelogram's lever, whose angle is q3): by virtual
    work its torque tau_f gives q the generalized force a tau_f, so s = |a|.  None if there is no such
    motor or several followers' motors share the coordinate (their limits are not a box in q).
    """
    own = next((a for a in actuators if a.joint == name), None)
    if own is not None:
        return own, sympy.Integer(1)
    by_joint = {a.joint: a for a in actuators}
    driving = [(by_joint[j.name], sympy.Abs(j.coupling.multiplier)) for j in joints
               if j.follower and j.coupling is not None and j.coupling.leader == name and j.name in by_joint]
    return driving[0] if len(driving) == 1 else None


def with_motor_effort_limits(joints: tuple[Joint, ...], actuators: tuple[Actuator, ...]) -> tuple[Joint, ...]:
    """The joints, each without an ``effort_limit`` of its own given its drive's peak torque s N K_t I_peak
    (:func:`drive_of`)."""
    out = []
    for joint in joints:
        drive = drive_of(joint.name, joints, actuators)
        if joint.effort_limit is None and drive is not None and drive[0].peak_effort is not None:
            joint = dataclasses.replace(joint, effort_limit=drive[1] * drive[0].peak_effort)
        out.append(joint)
    return tuple(out)
