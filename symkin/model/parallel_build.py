"""Validate the ``parallel:`` section of a model file and build its :class:`Parallel` structure.

A parallel mechanism is a base, a moving platform and legs: joint chains from the base
to the platform (seed sec. 1.3, "Parallel Mechanisms").  The section is either the DELTA
shorthand (see :mod:`symkin.model.delta`) or a list of legs::

    parallel:
      motion: pose                    # or translation, planar, spherical, schoenflies, or a list: [x, y]
      chains:                         # leg types, shared by several legs (optional)
        ups:
          - {name: ub, type: U, axes: [[0, 0, 1], [0, 1, 0]]}
          - {name: l, type: P, axis: [1, 0, 0], active: true}
          - {name: sp, type: S}
      legs:
        - {chain: ups, base: {radius: rb, angle: deg(-10)}, platform: {radius: rp, angle: deg(-50)}}

Joint names get the leg's number appended (``l`` -> ``l1`` in the first leg).  The format
is documented in ``docs/model-format.md`` ("Parallel mechanisms").
"""

from __future__ import annotations

import difflib
from typing import Any

import sympy

from symkin.model import coordinates, joint_kinds
from symkin.model.delta import delta_legs
from symkin.model.leg_joints import leg_joint_limits, read_home_assembly, variable_names
from symkin.model.reader import (
    X_AXIS,
    Y_AXIS,
    Z_AXIS,
    ZERO,
    Reader,
    describe,
    frame_ops,
    ops,
    positive_limit,
    unit_axis,
)
from symkin.model.schema import (
    PLATFORM_COORDINATES,
    Leg,
    LegJoint,
    LegJointType,
    Op,
    Parallel,
    PlatformMotion,
    Rotation,
    Translation,
    Vec3,
)
from symkin.model.yaml_source import KeyPath
from symkin.model.units import ANGLE, LENGTH

PARALLEL_KEYS = ("delta", "motion", "chains", "legs", "fk_branch", "mobility", "home", "home_assembly")
LEG_KEYS = ("name", "chain", "joints", "base", "platform", "ik_branch")
JOINT_KEYS = ("name", "type", "axis", "axes", "origin", "active", "offset", "limits", "velocity_limit", "effort_limit")
BRANCHES = {"positive": 1, "negative": -1}
#: The platform motions a model may name instead of listing its coordinates.
MOTION_SHORTHANDS = {PlatformMotion.TRANSLATION.value: ("x", "y", "z"),
                     PlatformMotion.POSE.value: PLATFORM_COORDINATES,
                     PlatformMotion.PLANAR.value: ("x", "y", "yaw"),
                     PlatformMotion.SPHERICAL.value: ("roll", "pitch", "yaw"),
                     PlatformMotion.SCHOENFLIES.value: ("x", "y", "z", "yaw")}
#: Names of the vector inputs of parallel functions (besides q): platform pose, passive joints and a hybrid
#: device's wrist coordinates.
PARALLEL_INPUT_NAMES = ("p", "s", "qw", "qwd", "qwdd", "tauw")



def build_parallel(r: Reader, section: Any) -> Parallel | None:
    """The parallel structure of ``section`` (problems are recorded in ``r``)."""
    path: KeyPath = ("parallel",)
    section = r.mapping(path, section, optional=PARALLEL_KEYS)
    if section is None:
        return None
    identical, constraints = _mobility(r, path + ("mobility",), section.get("mobility", {}))
    if "delta" in section:
        for key in ("motion", "chains", "legs", "fk_branch", "home_assembly"):
            if key in section:
                r.fail(path + (key,), f"'{key}' cannot be combined with the DELTA shorthand 'delta:'",
                       "remove it: the shorthand defines the legs, the motion and the branches (its knees "
                       "point outwards)")
        built = delta_legs(r, path + ("delta",), section["delta"])
        if built is None:
            return None
        delta_legs_built, delta_branch = built
        translation = MOTION_SHORTHANDS[PlatformMotion.TRANSLATION.value]
        home = _home(r, path + ("home",), section.get("home"), translation)
        return _checked(r, path, Parallel(translation, delta_legs_built, delta_branch, identical,
                                          constraints, "delta", home))
    for key in ("motion", "legs"):
        if key not in section:
            r.fail(path, f"missing required key '{key}'", f"add '{key}:' (or use the DELTA shorthand 'delta:')")
    if "motion" not in section or "legs" not in section:
        return None
    motion = _motion(r, path + ("motion",), section["motion"])
    chains = _chains(r, path + ("chains",), section.get("chains", {}))
    fk_branch = _branch(r, path + ("fk_branch",), section.get("fk_branch", "negative"))
    legs = _legs(r, path + ("legs",), section["legs"], chains)
    if motion is None or fk_branch is None or legs is None:
        return None
    home = _home(r, path + ("home",), section.get("home"), motion)
    assembly = read_home_assembly(r, path, section, legs)
    return _checked(r, path, Parallel(motion, legs, fk_branch, identical, constraints, home=home,
                                      home_assembly=assembly))



def _checked(r: Reader, path: KeyPath, parallel: Parallel) -> Parallel:
    """Structure-wide checks: unique names, as many actuators as the platform has DoF."""
    seen: dict[str, str] = {}
    for leg in parallel.legs:
        for joint in leg.joints:
            for name in (joint.name,) + joint.variables:
                if name in seen and seen[name] != joint.name:
                    r.fail(path, f"the name '{name}' is used twice (joints '{seen[name]}' and '{joint.name}')",
                           "rename a joint (leg numbers are appended to joint names)")
                seen.setdefault(name, joint.name)
    if len({leg.name for leg in parallel.legs}) != len(parallel.legs):
        r.fail(path + ("legs",), "two legs have the same name", "give every leg its own name")
    if legs_reported(r):
        return parallel  # the counts below follow from the legs' reported mistakes: not a mistake of their own
    active = sum(1 for leg in parallel.legs for joint in leg.joints if joint.active is not None)
    if active != parallel.task_dof:
        r.fail(path, f"the platform has {parallel.task_dof} degrees of freedom ({', '.join(parallel.coordinates)}) "
                     f"but the legs have {active} active joints",
               f"mark exactly {parallel.task_dof} joints 'active: true' (fully actuated, seed sec. 2.2)")
    if len(parallel.legs) < 2:
        r.fail(path + ("legs",), "a parallel mechanism has at least two legs (seed sec. 1.3)",
               "add legs, or describe a single chain under 'serial:'")
    return parallel


def legs_reported(r: Reader) -> bool:
    """Whether a mistake in the legs or their chains was reported (their joints and counts are then incomplete)."""
    return r.reported_under("parallel.legs") or r.reported_under("parallel.chains")


def _home(r: Reader, path: KeyPath, value: Any, names: tuple[str, ...]) -> tuple[sympy.Expr, ...] | None:
    """The optional home pose: one expression per task coordinate."""
    if value is None:
        return None
    items = r.sequence(path, value, len(names), f"task coordinates [{', '.join(names)}]")
    if items is None:
        return None
    parts = [r.expr(path + (i,), v) for i, v in enumerate(items)]
    return None if any(p is None for p in parts) else tuple(parts)


def _mobility(r: Reader, path: KeyPath, value: Any) -> tuple[int, int]:
    """Declared identical conditions f_id and constraints s of eq. (8.2), non-negative integers."""
    section = r.mapping(path, value, optional=("identical", "constraints"))
    counts = []
    for key in ("identical", "constraints"):
        item = (section or {}).get(key, 0)
        if isinstance(item, bool) or not isinstance(item, int) or item < 0:
            r.fail(path + (key,), f"'{key}' must be a non-negative integer, got {describe(item)}", "write e.g. 0 or 1")
            item = 0
        counts.append(item)
    return counts[0], counts[1]


def _motion(r: Reader, path: KeyPath, value: Any) -> tuple[str, ...] | None:
    """The platform's coordinates: a shorthand (``translation``, ``planar``, ...) or a list such as [x, y]."""
    if isinstance(value, str) and value in MOTION_SHORTHANDS:
        return MOTION_SHORTHANDS[value]
    fix = (f"write one of {', '.join(MOTION_SHORTHANDS)} or a list of platform coordinates from "
           f"[{', '.join(PLATFORM_COORDINATES)}] in that order, e.g. [x, y] for a planar point")
    if not isinstance(value, list):
        r.fail(path, f"unknown platform motion {describe(value)}", fix)
        return None
    if not value or any(not isinstance(v, str) or v not in PLATFORM_COORDINATES for v in value):
        r.fail(path, f"{describe(value)} is not a list of platform coordinates", fix)
        return None
    canonical = tuple(c for c in PLATFORM_COORDINATES if c in value)
    if tuple(value) != canonical:
        r.fail(path, "the platform coordinates are repeated or out of order",
               f"write [{', '.join(canonical)}] (the order of p: x, y, z, roll, pitch, yaw)")
        return None
    return canonical


def _branch(r: Reader, path: KeyPath, value: Any) -> int | None:
    if isinstance(value, str) and value in BRANCHES:
        return BRANCHES[value]
    r.fail(path, f"unknown branch {describe(value)}", "write 'positive' or 'negative' (see 'Branches' in the docs)")
    return None


def _chains(r: Reader, path: KeyPath, value: Any) -> dict[str, tuple[KeyPath, list[Any]]]:
    section = r.mapping(path, value, optional=tuple(value) if isinstance(value, dict) else ())
    if section is None:
        return {}
    out = {}
    for cname, joints in section.items():
        if r.name(path + (cname,), cname) is None:
            continue
        items = r.sequence(path + (cname,), joints, what="joints")
        if items is not None:
            out[cname] = (path + (cname,), items)
    return out


def _legs(r: Reader, path: KeyPath, value: Any, chains: dict[str, tuple[KeyPath, list[Any]]]) -> tuple[Leg, ...] | None:
    items = r.sequence(path, value, what="legs")
    if items is None:
        return None
    legs = []
    for i, item in enumerate(items):
        lpath = path + (i,)
        item = r.mapping(lpath, item, required=("base", "platform"), optional=LEG_KEYS)
        if item is None or "base" not in item or "platform" not in item:
            continue
        number = i + 1
        name = r.name(lpath + ("name",), item["name"]) if "name" in item else f"leg{number}"
        if ("chain" in item) == ("joints" in item):
            r.fail(lpath, "a leg needs exactly one of 'chain:' (a name under 'parallel.chains') or 'joints:'",
                   "keep one of the two keys")
            continue
        if "chain" in item:
            if item["chain"] not in chains:
                known = ", ".join(chains) or "none declared"
                close = difflib.get_close_matches(str(item["chain"]), list(chains), n=1)
                hint = f"did you mean '{close[0]}'? " if close else ""
                r.fail(lpath + ("chain",), f"unknown chain {describe(item['chain'])}", f"{hint}chains: {known}")
                continue
            jpath, entries = chains[item["chain"]]
        else:
            jpath = lpath + ("joints",)
            listed = r.sequence(jpath, item["joints"], what="joints")
            if listed is None:
                continue
            entries = listed
        joints = [_joint(r, jpath + (k,), entry, number) for k, entry in enumerate(entries)]
        base = attachment(r, lpath + ("base",), item["base"])
        platform = attachment(r, lpath + ("platform",), item["platform"])
        branch = _branch(r, lpath + ("ik_branch",), item.get("ik_branch", "positive"))
        if not entries:
            r.fail(jpath, "the leg has no joints", "declare the joints from the base to the platform")
        if name is None or None in joints or base is None or platform is None or branch is None:
            continue
        legs.append(Leg(name, base, tuple(joints), platform, branch))  # type: ignore[arg-type]
    return tuple(legs)


def attachment(r: Reader, path: KeyPath, value: Any) -> tuple[Op, ...] | None:
    """An attachment frame: ``{xyz, rpy}`` or polar ``{radius, angle, z}`` = Rz(angle) Trans(radius, 0, z).

    The polar form is the seed's base_T_A_i (sec. 3.2.1): the leg frame's x axis points
    from the centre towards the joint, z is the base's z.
    """
    if isinstance(value, dict) and ({"radius", "angle"} & set(value)):
        section = r.mapping(path, value, required=("radius", "angle"), optional=("z",))
        if section is None or "radius" not in section or "angle" not in section:
            return None
        radius = r.expr(path + ("radius",), section["radius"], dimension=LENGTH)
        angle = r.expr(path + ("angle",), section["angle"], dimension=ANGLE)
        height = r.expr(path + ("z",), section["z"], dimension=LENGTH) if "z" in section else ZERO
        if radius is None or angle is None or height is None:
            return None
        return ops(Rotation(Z_AXIS, angle), Translation((radius, ZERO, height)))
    return frame_ops(r, path, value)


def _joint(r: Reader, path: KeyPath, item: Any, number: int) -> LegJoint | None:
    item = r.mapping(path, item, required=("name", "type"), optional=JOINT_KEYS)
    if item is None or "name" not in item or "type" not in item:
        return None
    base_name = r.name(path + ("name",), item["name"])
    jtype = next((t for t in LegJointType if t.value == item["type"]), None)
    if jtype is None:
        r.fail(path + ("type",), f"unknown joint type {describe(item['type'])}",
               "use R (revolute), P (prismatic), U (universal), S (spherical) or C (cylindrical)")
        return None
    axes = _axes(r, path, item, jtype)
    origin = frame_ops(r, path + ("origin",), item["origin"]) if "origin" in item else ()
    active = item.get("active", False)
    if not isinstance(active, bool):
        r.fail(path + ("active",), f"'active' must be true or false, got {describe(active)}", "write true or false")
        return None
    if active and joint_kinds.kind(jtype).actuable is None:
        r.fail(path + ("active",), f"a {jtype.value} joint cannot be actuated",
               "actuate an R joint (rotary motor), a P joint (linear actuator) or the slide of a C joint (piston)")
        return None
    offset = ZERO
    if "offset" in item:
        if not active:
            r.fail(path + ("offset",), "an offset applies to the actuated variable of an active joint",
                   "remove 'offset' or mark the joint 'active: true'")
            return None
        kind = joint_kinds.kind(jtype)
        offset = r.expr(path + ("offset",), item["offset"],
                        dimension=ANGLE if kind.rotations[kind.actuable or 0] else LENGTH)
    limits = leg_joint_limits(r, path + ("limits",), item["limits"], jtype) if "limits" in item else ()
    actuator = {}
    for key in ("velocity_limit", "effort_limit"):
        if key in item:
            if not active:
                r.fail(path + (key,), f"'{key}' is the actuator's: it applies to an active joint",
                       f"remove '{key}' or mark the joint 'active: true'")
                return None
            kind = joint_kinds.kind(jtype)
            actuator[key] = positive_limit(r, path + (key,), item[key], kind.rotations[kind.actuable or 0])
            if actuator[key] is None:
                return None
    if base_name is None or axes is None or origin is None or offset is None or limits is None:
        return None
    name = f"{base_name}{number}"
    return LegJoint(name, jtype, axes, origin, variable_names(name, jtype),
                    joint_kinds.kind(jtype).actuable if active else None, offset, limits, **actuator)


def _axes(r: Reader, path: KeyPath, item: dict[str, Any], jtype: LegJointType) -> tuple[Vec3, ...] | None:
    single = joint_kinds.kind(jtype).axes == 1
    key, other = ("axis", "axes") if single else ("axes", "axis")
    if other in item:
        r.fail(path + (other,), f"a {jtype.value} joint takes '{key}', not '{other}'", f"write '{key}:'")
        return None
    if key not in item and single:  # no convention fixes it (URDF's default is x, a DH table's z): say it
        r.fail(path, f"the {jtype.value} joint '{item.get('name', '')}' has no axis",
               "add 'axis: [0, 0, 1]' (or the axis it turns about or slides along, in its frame)")
        return None
    if key not in item:
        axes = joint_kinds.kind(jtype).default_axes(Z_AXIS, Y_AXIS, X_AXIS)
    elif single:
        axis = unit_axis(r, path + ("axis",), item["axis"])
        if axis is None:
            return None
        axes = (axis,)
    else:
        rows = r.sequence(path + ("axes",), item["axes"], jtype.dof, "axes")
        if rows is None:
            return None
        parsed = [unit_axis(r, path + ("axes", k), row) for k, row in enumerate(rows)]
        if any(a is None for a in parsed):
            return None
        axes = tuple(parsed)
    for k in range(1, len(axes)):
        cross = sympy.Matrix(axes[k - 1]).cross(sympy.Matrix(axes[k]))
        if cross.is_zero_matrix:
            r.fail(path + ("axes",), f"axes {k} and {k + 1} of the {jtype.value} joint are parallel",
                   "the axes of a U or S joint are not parallel (usually perpendicular)")
            return None
    return axes


def parallel_task_space(r: Reader, data: dict[str, Any], parallel: Parallel) -> tuple[str, ...]:
    """The task coordinates follow from the platform motion; a model may not set them otherwise."""
    if "task_space" in data:
        r.fail(("task_space",), "a parallel mechanism's task space follows from 'parallel.motion'",
               "remove 'task_space:' (list the platform's coordinates under 'parallel.motion')")
    return parallel.coordinates


def check_parallel_names(r: Reader, parameters: tuple, derived: tuple, parallel: Parallel) -> None:
    """Parameters may not take the names of joint variables, task coordinates or input vectors."""
    taken: dict[str, str] = {}
    for name in PARALLEL_INPUT_NAMES:
        taken[name] = f"the input vector '{name}' of generated functions"
    for name in parallel.coordinates:
        taken[name] = f"the task coordinate '{name}'"
    for leg in parallel.legs:
        for joint in leg.joints:
            for k, variable in enumerate(joint.variables):
                symbols = coordinates.all_symbol_names(variable) if k == joint.active else (variable,)
                for symbol in symbols:
                    taken[symbol] = f"the symbol '{symbol}' of joint '{joint.name}' ({leg.name})"
    for p in tuple(parameters) + tuple(derived):
        if p.name in taken:
            r.fail(("parameters", p.name), f"parameter '{p.name}' clashes with {taken[p.name]}",
                   "rename the parameter")
