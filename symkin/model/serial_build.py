"""The ``serial:`` section: a DH table (classic or modified) or a URDF-like joint chain, base and TCP frames."""

from __future__ import annotations

import dataclasses
from typing import Any

import sympy

from symkin.model.reader import (
    X_AXIS,
    Z_AXIS,
    ZERO,
    Reader,
    describe,
    frame_ops,
    ops,
    position_limits,
    positive_limit,
    unit_axis,
)
from symkin.errors import name_list
from symkin.model.units import ANGLE, LENGTH
from symkin.model import tree
from symkin.model.schema import Coupling, Joint, JointType, Op, Rotation, Translation
from symkin.model.yaml_source import Document, KeyPath

#: Most joints of one chain (exact expressions grow with the chain; beyond this, derivation
#: would run for hours).
MAX_JOINTS = 64
JOINT_TYPES = {"R": JointType.REVOLUTE, "revolute": JointType.REVOLUTE,
               "P": JointType.PRISMATIC, "prismatic": JointType.PRISMATIC}
#: Joint types that exist in legs of parallel mechanisms but not in a serial chain.
MULTI_DOF_JOINT_TYPES = ("U", "S", "C", "E", "H")
DH_CONVENTIONS = {"classic": "classic", "distal": "classic", "modified": "modified", "proximal": "modified"}
DH_COLUMNS = ("name", "type", "theta", "d", "a", "alpha")


def read_serial(r: Reader, section: Any, path: KeyPath = ("serial",)
                ) -> tuple[tuple[Joint, ...], tuple[Op, ...], tuple[Op, ...]]:
    """(joints, base, tcp) of the serial section at ``path`` (``serial:``, or a hybrid device's ``wrist:``)."""
    section = r.mapping(path, section, optional=("dh", "chain", "base", "tcp", "tip", "home"))
    if section is None:
        return (), (), ()
    joints: list[Joint] = []
    if ("dh" in section) == ("chain" in section):
        r.fail(path, "a serial mechanism needs exactly one of 'dh:' (a DH table) or 'chain:' (a joint chain)",
               "keep one of the two sections")
    elif "dh" in section:
        joints = _dh_table(r, path + ("dh",), section["dh"])
    else:
        joints = _chain(r, path + ("chain",), section["chain"])
    base = frame_ops(r, path + ("base",), section["base"]) if "base" in section else ()
    tcp = frame_ops(r, path + ("tcp",), section["tcp"]) if "tcp" in section else ()
    if not joints and not r.problems:
        r.fail(path, "the chain has no joints", "declare at least one joint")
    if len(joints) > MAX_JOINTS:
        r.fail(path, f"the chain has {len(joints)} joints, more than the limit of {MAX_JOINTS}",
               "split the mechanism; symbolic expressions grow with every joint of a chain")
    check_unique(r, [(path, j.name) for j in joints], "joint")
    check_unique(r, [(path, j.link) for j in joints], "link")
    rows_path = path + (("dh", "rows") if "dh" in section else ("chain",))
    rows = section["dh"].get("rows") if "dh" in section and isinstance(section["dh"], dict) else section.get("chain")
    joints = _couplings(r, rows_path, rows if isinstance(rows, list) else [], joints)
    _check_leaders(r, rows_path, joints)
    _check_parents(r, rows_path, joints)
    return tuple(joints), base or (), tcp or ()


def read_tip(r: Reader, section: Any, joints: tuple[Joint, ...], path: KeyPath = ("serial",)) -> str | None:
    """``serial.tip``: the link that carries the TCP (default: the last joint's link)."""
    if not isinstance(section, dict) or "tip" not in section:
        return None
    tip = r.name(path + ("tip",), section["tip"])
    links = [j.link for j in joints]
    if tip is not None and joints and tip not in links:
        r.fail(path + ("tip",), f"the tip '{tip}' is not a link of the chain",
               f"name one of: {', '.join(links)}")
        return None
    return tip


def read_home(r: Reader, section: Any, joints: tuple[Joint, ...], path: KeyPath = ("serial",)
              ) -> tuple[sympy.Expr, ...] | None:
    """``serial.home``: the device's rest configuration, one expression per coordinate (the joints but the
    followers), within the limits at the parameters' defaults; None where the model declares none."""
    if not isinstance(section, dict) or "home" not in section:
        return None
    coordinates = [j for j in joints if not j.follower]
    names = ", ".join(j.name for j in coordinates)
    items = r.sequence(path + ("home",), section["home"], len(coordinates), f"joint coordinates [{names}]")
    if items is None:
        return None
    values = [r.expr(path + ("home", i), item) for i, item in enumerate(items)]
    if any(v is None for v in values):
        return None
    expressions = tuple(v for v in values if v is not None)
    for i, (joint, value) in enumerate(zip(coordinates, expressions)):
        number = r.default_value(value)
        if number is None or joint.limits is None:
            continue
        lower, upper = (r.default_value(b) for b in joint.limits)
        if lower is not None and upper is not None and not lower <= number <= upper:
            r.fail(path + ("home", i), f"the home value {number:g} of '{joint.name}' lies outside its limits "
                                       f"[{lower:g}, {upper:g}]",
                   "choose a home configuration within the joint limits")
    return expressions


def _check_parents(r: Reader, path: KeyPath, joints: list[Joint]) -> None:
    """Every ``parent:`` names the base or the link of an earlier joint (parents first: no cycle)."""
    earlier: list[str] = []
    for i, joint in enumerate(joints):
        if joint.parent is not None and joint.parent != tree.BASE and joint.parent not in earlier:
            later = joint.parent in {j.link for j in joints}
            r.fail(path + (i, "parent"), f"joint '{joint.name}' hangs on '{joint.parent}', "
                                         f"{'a link declared after it' if later else 'no link of the chain'}",
                   f"name '{tree.BASE}' or the link of an earlier joint: {', '.join(earlier) or '(none yet)'}; "
                   "list the joints of a tree parents first")
        earlier.append(joint.link)


def _couplings(r: Reader, path: KeyPath, rows: list[Any], joints: list[Joint]) -> list[Joint]:
    """The joints with their ``coupling:`` expressions read (they may name any joint of the chain)."""
    by_name = {j.name: k for k, j in enumerate(joints)}
    symbols = {j.name: sympy.Dummy(j.name) for j in joints}
    for i, item in enumerate(rows):
        if not isinstance(item, dict) or "coupling" not in item or item.get("name") not in by_name:
            continue
        cpath = path + (i, "coupling")
        if "mimic" in item:
            r.fail(cpath, "a joint has either 'mimic:' or 'coupling:'", "keep 'coupling:' (mimic is its one-term form)")
            continue
        coupling = _coupling(r, cpath, item["coupling"], symbols)
        if coupling is not None:
            k = by_name[item["name"]]
            joints[k] = dataclasses.replace(joints[k], coupling=coupling)
    return joints


def _coupling(r: Reader, path: KeyPath, value: Any, symbols: dict[str, sympy.Dummy]) -> Coupling | None:
    """``coupling: q3 - q2 + pi/2``: an affine expression in the chain's joints (coordinates) and parameters."""
    combination = read_affine(r, path, value, symbols,
                              "write a constant combination such as 'q3 - q2 + pi/2': a coupling is a gear, belt or "
                              "linkage ratio", "the joint would be fixed",
                              "name the coordinates the joint moves with, or replace the joint by a fixed transform")
    return None if combination is None else Coupling(*combination)


def read_affine(r: Reader, path: KeyPath, value: Any, symbols: dict[str, sympy.Dummy], nonlinear_fix: str,
                constant: str, constant_fix: str) -> tuple[tuple[tuple[str, sympy.Expr], ...], sympy.Expr] | None:
    """(terms, offset) of an affine expression sum_k a_k q_k + b in the coordinates ``symbols`` and the parameters
    (a coupling, a joint stop), or None with a located problem: not affine (``nonlinear_fix``), or naming no
    coordinate (what it would be, ``constant``, and ``constant_fix``)."""
    expr = r.expr(path, value, {**r.names, **symbols})
    if expr is None:
        return None
    terms = []
    for name, symbol in symbols.items():
        a = sympy.diff(expr, symbol)
        if a.free_symbols & set(symbols.values()):
            r.fail(path, f"'{value}' is not affine in the coordinates ({name} enters nonlinearly)", nonlinear_fix)
            return None
        if a != 0:
            terms.append((name, a))
    if not terms:
        r.fail(path, f"'{value}' names no coordinate: {constant}", constant_fix)
        return None
    offset = expr.xreplace({symbol: sympy.S.Zero for symbol in symbols.values()})  # an Expr, also for 'q3'
    return tuple(terms), offset


def _check_leaders(r: Reader, path: KeyPath, joints: list[Joint]) -> None:
    """Every coupling (``mimic:``, ``coupling:``) names joints of the chain that have a coordinate of their own."""
    own = {j.name for j in joints if not j.follower}
    names = {j.name for j in joints}
    for i, joint in enumerate(joints):
        if joint.coupling is None:
            continue
        mimic = joint.coupling.mimic
        for leader, _ in joint.coupling.terms:
            if leader in own and not (mimic and leader == joint.name):
                continue
            what = ("the joint itself" if leader == joint.name else
                    "a joint that mimics another" if leader in names else "no joint of the chain")
            r.fail(path + (i, "mimic", "joint") if mimic else path + (i, "coupling"),
                   f"joint '{joint.name}' {'mimics' if mimic else 'moves with'} '{leader}', {what}",
                   f"name joints with a coordinate of their own: {name_list(sorted(own - {joint.name})) or '(none)'}")


def check_unique(r: Reader, items: list[tuple[KeyPath, str]], what: str) -> None:
    seen: set[str] = set()
    for path, item in items:
        if item in seen:
            r.fail(path, f"duplicate {what} name '{item}'", f"give every {what} its own name")
        seen.add(item)


def _joint_type(r: Reader, path: KeyPath, value: Any) -> JointType | None:
    if not isinstance(value, str):
        r.fail(path, f"a joint type must be a name, got {describe(value)}", "use 'R' (revolute) or 'P' (prismatic)")
        return None
    if value in JOINT_TYPES:
        return JOINT_TYPES[value]
    if value in MULTI_DOF_JOINT_TYPES:
        r.fail(path, f"joint type '{value}' has several degrees of freedom; a serial chain uses R or P joints",
               "decompose it into R joints (U = 2 R, S = 3 R with intersecting axes, C = R + P)")
    else:
        r.fail(path, f"unknown joint type {describe(value)}", "use 'R' (revolute) or 'P' (prismatic)")
    return None


_JOINT_EXTRAS = ("link", "limits", "velocity_limit", "effort_limit", "active", "mimic", "coupling")


def _dh_table(r: Reader, path: KeyPath, section: Any) -> list[Joint]:
    """Joints from a DH table (seed sec. 3.1, eq. 8.12 and Table 8.3).

    classic (distal):   ^{i-1}T_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)
    modified (proximal, Craig): ^{i-1}T_i = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i) Tz(d_i),
    where row i holds alpha_{i-1} and a_{i-1} as in Craig's tables.
    The joint coordinate adds to theta (revolute) or d (prismatic).
    """
    section = r.mapping(path, section, required=("convention", "rows"))
    if section is None or "convention" not in section or "rows" not in section:
        return []
    convention = DH_CONVENTIONS.get(section["convention"]) if isinstance(section["convention"], str) else None
    if convention is None:
        r.fail(path + ("convention",), f"unknown DH convention {describe(section['convention'])}",
               "use 'classic' (distal, Denavit-Hartenberg) or 'modified' (proximal, Craig)")
        return []
    rows = r.sequence(path + ("rows",), section["rows"], what="DH rows")
    if rows is None:
        return []
    joints = []
    for i, row in enumerate(rows):
        rpath = path + ("rows", i)
        fields = _dh_row_fields(r, rpath, row)
        if fields is None or any(k not in fields for k in ("name", "theta", "d", "a", "alpha")):
            r.invalid_links.add(_declared_link(fields, i))
            r.invalid_joints.add(str(fields.get("name")) if isinstance(fields, dict) else "")
            continue  # the missing keys are reported
        jname = r.name(rpath + ("name",), fields["name"])
        jtype = _joint_type(r, rpath + ("type",), fields.get("type", "R"))
        values = {k: r.expr(rpath + (k,), fields[k], dimension=ANGLE if k in ("theta", "alpha") else LENGTH)
                  for k in ("theta", "d", "a", "alpha")}
        extras = _joint_extras(r, rpath, fields, default_link=f"link{i + 1}",
                               revolute=None if jtype is None else jtype.turns)
        if jname is None or jtype is None or any(v is None for v in values.values()) or extras is None:
            r.invalid_links.add(_declared_link(fields, i))
            r.invalid_joints.add(str(fields["name"]))
            continue
        theta, d, a, alpha = values["theta"], values["d"], values["a"], values["alpha"]
        revolute = jtype.turns
        if convention == "classic":
            before = () if revolute else ops(Rotation(Z_AXIS, theta))
            after = ops(*((Translation((ZERO, ZERO, d)),) if revolute else ()),
                         Translation((a, ZERO, ZERO)), Rotation(X_AXIS, alpha))
        else:
            before = ops(Rotation(X_AXIS, alpha), Translation((a, ZERO, ZERO)),
                          *(() if revolute else (Rotation(Z_AXIS, theta),)))
            after = ops(Translation((ZERO, ZERO, d))) if revolute else ()
        joints.append(Joint(name=jname, type=jtype, axis=Z_AXIS, offset=theta if revolute else d,
                            before=before, after=after, **extras))
    return joints


def _dh_row_fields(r: Reader, path: KeyPath, row: Any) -> dict[str, Any] | None:
    """A DH row as a mapping; list rows are [name, type, theta, d, a, alpha(, [lower, upper])]."""
    if isinstance(row, list):
        if len(row) not in (6, 7):
            r.fail(path, f"a DH row has 6 entries [{', '.join(DH_COLUMNS)}] (and optionally [lower, upper] limits), "
                         f"this one has {len(row)}",
                   "write the row as [name, type, theta, d, a, alpha] or as a mapping with those keys")
            return None
        fields = dict(zip(DH_COLUMNS, row))
        if len(row) == 7:
            fields["limits"] = row[6]
        # List entries are located by index; map the field names onto those paths.
        for k, key in enumerate(list(DH_COLUMNS) + ["limits"]):
            if k < len(row):
                _alias_path(r.doc, path + (k,), path + (key,))
        return fields
    return r.mapping(path, row, required=("name", "theta", "d", "a", "alpha"), optional=("type",) + _JOINT_EXTRAS)


def _declared_link(fields: Any, index: int) -> str:
    """The link a joint entry declares (or its default name), even if the entry is invalid."""
    link = fields.get("link") if isinstance(fields, dict) else None
    return link if isinstance(link, str) else f"link{index + 1}"


def _alias_path(doc: Document, source: KeyPath, alias: KeyPath) -> None:
    """Make every location under ``source`` also known under ``alias``."""
    for key in [k for k in doc.marks if k[:len(source)] == source]:
        doc.marks.setdefault(alias + key[len(source):], doc.marks[key])
        if key in doc.raw:
            doc.raw.setdefault(alias + key[len(source):], doc.raw[key])


def _chain(r: Reader, path: KeyPath, section: Any) -> list[Joint]:
    """Joints of a URDF-like chain: parent_T_link = Trans(xyz) Rz(yaw) Ry(pitch) Rx(roll) Motion(axis, q)."""
    items = r.sequence(path, section, what="joints")
    if items is None:
        return []
    joints = []
    for i, item in enumerate(items):
        jpath = path + (i,)
        item = r.mapping(jpath, item, required=("name",),
                         optional=("type", "axis", "origin", "offset", "parent") + _JOINT_EXTRAS)
        if item is None or "name" not in item:
            continue
        jname = r.name(jpath + ("name",), item["name"])
        jtype = _joint_type(r, jpath + ("type",), item.get("type", "R"))
        if "axis" not in item:  # no convention fixes it (URDF's default is x, a DH table's z): say it
            r.fail(jpath, f"the joint '{item['name']}' has no axis",
                   "add 'axis: [0, 0, 1]' (or the axis it turns about or slides along, in its frame)")
        axis = unit_axis(r, jpath + ("axis",), item["axis"]) if "axis" in item else None
        before = frame_ops(r, jpath + ("origin",), item["origin"]) if "origin" in item else ()
        revolute = None if jtype is None else jtype.turns
        offset = (r.expr(jpath + ("offset",), item["offset"], dimension=None if revolute is None else ANGLE if revolute
                         else LENGTH) if "offset" in item else ZERO)
        extras = _joint_extras(r, jpath, item, default_link=f"link{i + 1}", revolute=revolute)
        parent = None if "parent" not in item else tree.BASE if item["parent"] == tree.BASE else \
            r.name(jpath + ("parent",), item["parent"])
        if jname is None or jtype is None or axis is None or before is None or offset is None or extras is None \
                or ("parent" in item and parent is None):
            r.invalid_links.add(_declared_link(item, i))
            r.invalid_joints.add(str(item.get("name")))
            continue
        joints.append(Joint(name=jname, type=jtype, axis=axis, offset=offset, before=before, after=(),
                            parent=parent, **extras))
    return joints


def _joint_extras(r: Reader, path: KeyPath, item: dict[str, Any], default_link: str,
                  revolute: bool | None = None) -> dict[str, Any] | None:
    """Link name, limits and activity of a joint (keys shared by DH rows and chain joints); the limits are angles
    of a ``revolute`` joint, lengths of a prismatic one (and the velocity and effort limits in kind)."""
    link = r.name(path + ("link",), item["link"]) if "link" in item else default_link
    limits = None
    ok = link is not None
    if "limits" in item:
        limits = position_limits(r, path + ("limits",), item["limits"], revolute)
        ok = ok and limits is not None
    extras: dict[str, Any] = {"link": link, "limits": limits}
    for key in ("velocity_limit", "effort_limit"):
        extras[key] = positive_limit(r, path + (key,), item[key], revolute) if key in item else None
        ok = ok and (key not in item or extras[key] is not None)
    active = item.get("active", True)
    if not isinstance(active, bool):
        r.fail(path + ("active",), f"'active' must be true or false, got {describe(active)}", "write true or false")
        ok = False
    extras["active"] = active
    extras["coupling"] = None  # a coupling: expression is read once every joint is known (_couplings)
    if "mimic" in item:
        extras["coupling"] = _mimic(r, path + ("mimic",), item["mimic"])
        ok = ok and extras["coupling"] is not None
    return extras if ok else None


def _mimic(r: Reader, path: KeyPath, value: Any) -> Coupling | None:
    """``mimic: {joint: LEADER, multiplier: a, offset: b}``: q = a q_leader + b (a defaults to 1, b to 0)."""
    value = r.mapping(path, value, required=("joint",), optional=("multiplier", "offset"))
    if value is None or "joint" not in value:
        return None
    leader = r.name(path + ("joint",), value["joint"])
    multiplier = r.expr(path + ("multiplier",), value["multiplier"]) if "multiplier" in value else sympy.Integer(1)
    offset = r.expr(path + ("offset",), value["offset"]) if "offset" in value else ZERO
    if multiplier is not None and multiplier.is_zero:
        r.fail(path + ("multiplier",), "a multiplier of 0 makes the joint fixed, not a follower",
               "write a nonzero multiplier, or replace the joint by a fixed transform")
        return None
    if leader is None or multiplier is None or offset is None:
        return None
    return Coupling(((leader, multiplier),), offset, mimic=True)
