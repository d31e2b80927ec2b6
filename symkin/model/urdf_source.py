"""Read a URDF robot description into the same plain document a YAML model file gives.

ROS users' robots work without rewriting them: the chain from the URDF's root link (or a
chosen base link) to a tip link becomes a ``serial.chain`` (see docs/model-format.md, "URDF
files"), so the one validator of :mod:`symkin.model.build` checks it and every message points
at the URDF line.  Everything off that chain is handled as Pinocchio's reduced model
(``pinocchio.buildReducedModel``) handles it: every moving joint off the chain or beyond the
tip (grippers, heads, sensors) is locked, at 0 or at a value the caller gives, and the links
it carries become rigid parts of the chain link they hang on (their inertials are lumped into
it), so M and G are those of the arm holding them.

* joints: ``revolute``, ``continuous`` (revolute without limits), ``prismatic`` and
  ``fixed``; fixed joints are merged into the frames around them (the ``origin`` of the
  next moving joint, ``serial.base`` before the first, ``serial.tcp`` after the last);
* ``<origin xyz rpy>`` is parent_T_joint = Trans(xyz) Rz(yaw) Ry(pitch) Rx(roll), ``<axis>``
  (default 1 0 0) the motion axis, ``<limit>`` the position, velocity and effort limits;
* ``<inertial>``: mass, centre of mass and inertia tensor (``<origin>`` rotates its axes);
  links fixed to a moving link add their inertials to it; links fixed to the root do not
  move and are ignored;
* numbers are read as exact decimals, taken as written; with ``snap_angles`` an angle that is a multiple
  of pi/2, pi/4, pi/3 or pi/6 rounded to the digits written (1.5707963267948966, 1.57079632679, 1.5708,
  3.14159; at least :data:`SNAP_DIGITS` significant digits) is read as that exact multiple, so a URDF and the
  YAML model of the same robot derive the same expressions; the model's description says which reading was
  used and a note names each snapped angle;
* ``<mimic joint multiplier offset>``: a follower off the chain is locked at
  multiplier * (its leader's locked value) + offset; a follower on the chain whose leader is
  a moving joint of the chain becomes the coupling q = multiplier * q_leader + offset
  (``mimic:`` of the model: no coordinate of its own);
* ``<dynamics damping friction>`` of a chain joint: its friction (viscous = damping,
  Coulomb = friction, as Pinocchio reads them into ``model.damping`` and ``model.friction``);
* gravity is ``[0, 0, -g]`` with a free parameter ``g = 9.81`` (ROS convention: z up);
  the task space is ``pose``.

With ``branches`` (``--branch LINK``) the joints from the base to each branch link stay moving as
well: the model is the tree of those paths (``parent:`` of the joints that start a branch), the TCP
on the tip.

Without ``chain`` and branches the model is the whole tree below the root: every leaf behind a moving joint is
a branch, and the TCP is on the ``tip`` the caller names (``symkin derive --tip LINK``, ``load_model(path,
tip=...)``: the task frame, it does not cut the tree), else on the leaf link behind the most moving joints (so
sensor frames fixed to the base or to a link do not count, nor do mimic followers; the first in the file's order
among equals).  With ``chain`` (``--chain``) the model is the chain to the tip alone (and with ``branches`` the
tree of the paths to it and to them).  Closed loops (a link with two parent
joints), floating and planar joints, followers on the chain of a joint off it, and
off-chain followers of a chain joint (the links they move cannot be lumped into a chain
link) are refused with a located error.

The file is data: it is parsed with the standard library's expat parser, document type
declarations (and so entities) are refused, and the file size and element count are
bounded.

Length: one reader of one format (links, joints, inertials, mimic and fixed joints, located
errors); its parts only make sense together.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any
from xml.parsers import expat

import numpy as np

from symkin.errors import ModelError, Problem, name_list
from symkin.model.names import code_names, name_problem
from symkin.model.source_kind import XACRO_FIX, XACRO_MESSAGE
from symkin.model.urdf_export import rotation_about, urdf_rpy
from symkin.model.yaml_source import Document, KeyPath, model_file_bytes

MAX_ELEMENTS = 100_000
#: Characters of text kept per element (URDF keeps numbers in attributes; a transmission's reduction is text).
MAX_TEXT = 256
#: A decimal number of at most 64 digits before and after the point and a two-digit exponent (|x| < 1e100):
#: ``1e999999999`` or a megabyte of digits is no measurement, and reading it exactly would hang (issue 59).
_NUMBER = re.compile(r"[+-]?(\d{1,64}\.?\d{0,64}|\.\d{1,64})([eE][+-]?\d{1,2})?")
#: With ``snap_angles``, an angle is read as k pi / d (d in this order: the smallest denominator first) where it is
#: that multiple rounded to the digits written ...
SNAP_DENOMINATORS = (2, 4, 3, 6)
#: ... written with at least this many significant digits (2 is not pi/2 rounded, 1.571 is).
SNAP_DIGITS = 4

SUPPORTED_JOINTS = ("revolute", "continuous", "prismatic", "fixed")


@dataclass
class Element:
    """An XML element with its location."""

    tag: str
    attrib: dict[str, str]
    line: int
    column: int
    children: list[Element] = field(default_factory=list)
    #: the character data directly inside it (``<mechanicalReduction>50</mechanicalReduction>``), at most
    #: :data:`MAX_TEXT` characters.
    text: str = ""

    def find(self, tag: str) -> Element | None:
        return next((c for c in self.children if c.tag == tag), None)

    def findall(self, tag: str) -> list[Element]:
        return [c for c in self.children if c.tag == tag]


class _Fail(Exception):
    """Stops reading after located problems were recorded."""


class _Xacro(Exception):
    """A xacro macro element met while parsing (a .urdf that still holds xacro)."""


class _UrdfReader:
    def __init__(self, file: str, snap_angles: bool = False):
        self.file = file
        #: {URDF name: model name} of the joints and links (symkin.model.names.code_names).
        self.joint_ids: dict[str, str] = {}
        self.link_ids: dict[str, str] = {}
        self.snap_angles = snap_angles
        #: the angles snapped: 'joint[j1].origin.rpy 1.5708 as pi/2 (line 7)' (the model's notes), and where
        self.snapped: list[str] = []
        self.snap_edits: list[tuple[int, str, str, str]] = []
        self.problems: list[Problem] = []
        self.marks: dict[KeyPath, tuple[int, int]] = {}

    def fail(self, element: Element | None, key: str, message: str, fix: str) -> None:
        line, column = (element.line, element.column) if element is not None else (None, None)
        self.problems.append(Problem(self.file, line, column, key, message, fix))

    def stop(self) -> None:
        if self.problems:
            raise ModelError(self.problems)

    # ------------------------------------------------------------------ XML

    def parse(self, text: str) -> Element:
        parser = expat.ParserCreate()
        stack: list[Element] = []
        root: list[Element] = []
        count = [0]

        def refuse_dtd(*_args: Any) -> None:
            raise _Fail("document type declarations are not allowed")

        def start(tag: str, attrib: dict[str, str]) -> None:
            if tag.startswith("xacro:"):
                raise _Xacro()
            count[0] += 1
            if count[0] > MAX_ELEMENTS:
                raise _Fail(f"more than {MAX_ELEMENTS} elements")
            element = Element(tag, dict(attrib), parser.CurrentLineNumber, parser.CurrentColumnNumber + 1)
            (stack[-1].children if stack else root).append(element)
            stack.append(element)

        def characters(data: str) -> None:
            if stack and len(stack[-1].text) < MAX_TEXT:
                stack[-1].text = (stack[-1].text + data)[:MAX_TEXT]

        parser.StartDoctypeDeclHandler = refuse_dtd
        parser.EntityDeclHandler = refuse_dtd
        parser.StartElementHandler = start
        parser.CharacterDataHandler = characters
        parser.EndElementHandler = lambda _tag: stack.pop()
        try:
            parser.Parse(text, True)
        except expat.ExpatError as exc:
            self.problems.append(Problem(self.file, exc.lineno, exc.offset + 1, "",
                                         f"malformed XML: {expat.ErrorString(exc.code)}",
                                         "fix the XML syntax (a URDF is an XML file with a <robot> root)"))
            raise ModelError(self.problems) from None
        except _Xacro:
            self.problems.append(Problem(self.file, parser.CurrentLineNumber, parser.CurrentColumnNumber + 1, "",
                                         XACRO_MESSAGE, XACRO_FIX))
            raise ModelError(self.problems) from None
        except _Fail as exc:
            self.problems.append(Problem(self.file, parser.CurrentLineNumber, parser.CurrentColumnNumber + 1, "",
                                         f"refused: {exc}", "a URDF needs no DOCTYPE or entities; remove them"))
            raise ModelError(self.problems) from None
        if root[0].tag != "robot":
            self.fail(root[0], "", f"the root element is <{root[0].tag}>, not <robot>", "a URDF file has a <robot> root")
            self.stop()
        return root[0]

    # ------------------------------------------------------------------ values

    def numbers(self, element: Element, attribute: str, count: int, default: str, key: str,
                angles: bool = False) -> list[str]:
        """The attribute as ``count`` exact number texts (pi multiples for angles, see the module docstring)."""
        text = element.attrib.get(attribute, default)
        parts = text.split()
        if len(parts) != count or not all(_NUMBER.fullmatch(p) for p in parts):
            shown = text if len(text) <= 80 else text[:80] + "..."
            self.fail(element, key, f"{attribute}=\"{shown}\" is not {count} number(s)",
                      f"write {count} decimal number(s) separated by spaces (at most 64 digits and an exponent below "
                      "100 each)")
            return ["0"] * count
        if not (angles and self.snap_angles):
            return parts
        snapped = [snap_angle(p) for p in parts]
        self.snapped += [f"{key} {p} as {q} (line {element.line})" for p, q in zip(parts, snapped) if q != p]
        self.snap_edits += [(element.line, attribute, p, q) for p, q in zip(parts, snapped) if q != p]
        return snapped

    def number(self, element: Element, attribute: str, key: str, default: str | None = None,
               angle: bool = False) -> str | None:
        if attribute not in element.attrib and default is None:
            self.fail(element, key, f"missing attribute '{attribute}'", f"add {attribute}=\"...\"")
            return None
        return self.numbers(element, attribute, 1, default or "0", key, angles=angle)[0]

    def frame(self, element: Element | None, key: str) -> dict[str, list[str]]:
        """{xyz, rpy} of an <origin> element (identity if absent)."""
        if element is None:
            return {"xyz": ["0", "0", "0"], "rpy": ["0", "0", "0"]}
        return {"xyz": self.numbers(element, "xyz", 3, "0 0 0", key + ".xyz"),
                "rpy": self.numbers(element, "rpy", 3, "0 0 0", key + ".rpy", angles=True)}


def snap_angle(text: str) -> str:
    """``text`` (a decimal angle in rad) as 'pi/2', '-pi', '2*pi/3'... where it is that multiple rounded to the digits
    written (:data:`SNAP_DENOMINATORS`, :data:`SNAP_DIGITS`), else ``text``: |value - k pi / d| <= half a unit of
    its last digit, decided with 40 digits of pi."""
    import mpmath

    match = re.fullmatch(r"[+-]?(\d*)(?:\.(\d*))?(?:[eE]([+-]?\d+))?", text)
    value = Fraction(text)
    if match is None or value == 0:
        return text
    digits = (match.group(1) + (match.group(2) or "")).lstrip("0")
    if len(digits) < SNAP_DIGITS:
        return text
    half_unit = Fraction(1, 2) * Fraction(10) ** (int(match.group(3) or 0) - len(match.group(2) or ""))
    with mpmath.workdps(40):
        exact = mpmath.mpf(value.numerator) / value.denominator
        for d in SNAP_DENOMINATORS:
            k = int(mpmath.nint(exact * d / mpmath.pi))
            if k and abs(exact - k * mpmath.pi / d) <= mpmath.mpf(half_unit.numerator) / half_unit.denominator:
                whole = Fraction(k, d)
                factor = {1: "", -1: "-"}.get(whole.numerator, f"{whole.numerator}*")
                return f"{factor}pi" + (f"/{whole.denominator}" if whole.denominator != 1 else "")
    return text


def _is_identity(frame: dict[str, list[str]]) -> bool:
    return all(Fraction(v) == 0 for v in frame["xyz"]) and all(v == "0" or ("pi" not in v and Fraction(v) == 0)
                                                                 for v in frame["rpy"])


@dataclass(frozen=True)
class UrdfReduction:
    """How a URDF tree became the model's chain: the chain's first and last links and the values
    of the joints locked off it (what a reference such as Pinocchio needs to reduce the same tree)."""

    base: str
    tip: str
    locked: dict[str, float]
    #: the angles --snap-angles read as multiples of pi: (line, attribute, as written, as read)
    snapped: tuple[tuple[int, str, str, str], ...] = ()

    def reference_text(self, text: str) -> str:
        """``text`` (the URDF read) with each snapped angle written as the double nearest its multiple of pi, so a
        reference reads the geometry symkin derives (the attribute on its line, token by token)."""
        lines = text.split("\n")
        for line, attribute, written, read in self.snapped:
            for number in range(line - 1, min(line + 20, len(lines))):  # the element's start tag, maybe on lines
                row = lines[number]
                start = row.find(f'{attribute}="')
                if start < 0 or written not in row[start:].split('"')[1].split():
                    continue
                start += len(attribute) + 2
                end = row.index('"', start)
                tokens = [repr(float(_plain(read))) if t == written else t for t in row[start:end].split()]
                lines[number] = row[:start] + " ".join(tokens) + row[end:]
                break
        return "\n".join(lines)


@dataclass
class _Joint:
    element: Element
    name: str
    type: str
    parent: str
    child: str
    #: (leader joint, multiplier, offset) of a <mimic> joint: q = multiplier * q_leader + offset.
    mimic: tuple[str, Fraction, Fraction] | None = None


def read_urdf_document(path: str | Path, tip: str | None = None, *, base: str | None = None,
                       locks: Mapping[str, float] | None = None, snap_angles: bool = False,
                       branches: Sequence[str] = (), chain: bool = False) -> Document:
    """Read the URDF at ``path`` as a model document (see the module docstring).

    Raises:
        ModelError: unreadable or malformed file, unsupported content, unknown tip.
    """
    name = str(path)
    raw = model_file_bytes(path)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ModelError([Problem(name, None, None, "", f"the file is not UTF-8 text ({exc.reason})",
                                  "save the URDF as UTF-8 text")]) from None
    return urdf_document(text, name, tip, base=base, locks=locks, snap_angles=snap_angles, branches=branches,
                         chain=chain)


def urdf_document(text: str, file: str = "<string>", tip: str | None = None, *, base: str | None = None,
                  locks: Mapping[str, float] | None = None, snap_angles: bool = False,
                  branches: Sequence[str] = (), chain: bool = False) -> Document:
    """The model document of URDF ``text`` (see :func:`read_urdf_document`).

    Args:
        tip: the link that carries the TCP, the task frame (default: see the module docstring).
        chain: the model is the chain to the tip only (everything off it locked and lumped), not the whole tree.
        branches: more links whose joints from the base stay moving: the model is then the tree of the
            paths to the tip and to each of them (a torso's two arms; :mod:`symkin.model.tree`).
        base: the link the chain starts from (default: the root link); links outside its subtree
            are ignored (they do not move relative to it once their joints are locked).
        locks: {joint: value} for joints off the chain (rad or m; default 0, mimic followers from
            their leader).
        snap_angles: read an angle that is a multiple of pi/2, pi/4, pi/3 or pi/6 rounded to the digits written as that
            multiple (:func:`snap_angle`).
    """
    r = _UrdfReader(file, snap_angles)
    robot = r.parse(text)
    links = _links(r, robot)
    joints = _joints(r, robot, links)
    r.stop()
    r.joint_ids, r.link_ids = code_names(joints, "joint"), code_names(links, "link")
    parent_of = {j.child: j for j in joints.values()}
    children: dict[str, list[_Joint]] = {link: [] for link in links}
    for j in joints.values():
        children[j.parent].append(j)
    root = _root(r, robot, links, parent_of)
    if base is not None:
        if base not in links:
            r.fail(robot, "base", f"the base link '{base}' is not a link of the robot",
                   f"choose one of: {name_list(links)}")
            r.stop()
        root = base
    tip = _tip(r, robot, root, children, parent_of, tip)
    whole = not chain and not branches
    if whole and locks:
        r.fail(robot, "lock", f"--lock {next(iter(locks))}: the model is the whole tree, where every joint moves",
               "add --chain (the chain to --tip; joints off it are locked) or --branch LINK to lock joints off them")
        r.stop()
    if whole:  # every leaf behind a moving joint is a branch
        branches = [leaf for leaf in _subtree(root, children) if not children[leaf] and leaf != tip
                    and _moving_count(leaf, root, parent_of) > 0]
    for branch in branches:
        if branch not in links:
            r.fail(robot, "branch", f"the branch link '{branch}' is not a link of the robot",
                   f"choose one of: {name_list(_subtree(root, children))}")
            r.stop()
    kept = {j.name for end in (tip, *branches) for j in _path(r, robot, parent_of, root, end)}
    path = [j for j in _preorder(root, children) if j.name in kept]  # the tree's joints, parents first
    on_path = {root} | {j.child for j in path}
    notes: list[str] = []
    locked = _locked_values(r, robot, joints, children, on_path, path, dict(locks or {}), notes)
    r.stop()

    data: dict[str, Any] = {"notes": notes} if notes else {}
    robot_name = robot.attrib.get("name", "")
    # the robot's name if it can name a model, else the file's (the default of any model file), else one
    # made from either by the rule of the joints and links
    if name_problem(robot_name) is None:
        data["name"] = robot_name
    elif name_problem(Path(file).stem) is not None:
        source = robot_name.strip() or Path(file).stem
        data["name"] = code_names([source], "robot")[source]
    renamed = {kind: {ids[name]: name for name in names if ids[name] != name}
               for kind, names, ids in (("joints", joints, r.joint_ids), ("links", links, r.link_ids))}
    if any(renamed.values()):
        data["source_names"] = {kind: names for kind, names in renamed.items() if names}
    locked_text = ", ".join(f"{name} = {_decimal(value)}" for name, value in locked.items())
    shape = f"tree below {root}, TCP on {tip}" if whole and branches else f"chain {root} -> {tip}"
    data["description"] = (f"{robot_name or 'robot'} from the URDF {Path(file).name}, {shape}"
                           + (f"; locked: {locked_text}" if locked else "")
                           + ("; angles snapped to the multiples of pi/2, pi/4, pi/3 or pi/6 they are rounded to "
                              "the digits written" if snap_angles
                              else "; angles as written") + ".")
    data["parameters"] = {"g": {"value": "9.81", "unit": "m/s^2", "doc": "gravitational acceleration"}}
    serial: dict[str, Any] = {}
    rows: list[dict[str, Any]] = []
    # Each link of the tree: (the model link it moves with, None for the base; fixed frames from there).
    state: dict[str, tuple[str | None, list[dict[str, list[str]]]]] = {root: (None, [])}
    # Links that move: (model link carrying them, frames from that link's frame to theirs).
    carried: dict[str, tuple[str, list[dict[str, list[str]]]]] = {}
    friction: dict[str, dict[str, str]] = {}
    # one branch from the base: its fixed frames before the first moving joint are serial.base, as for a chain
    from_base = sum(1 for j in path if j.type != "fixed" and _moving_ancestor(j, parent_of, root, kept) is None)
    for j in path:
        moving, pending = state[j.parent]
        origin = r.frame(j.element.find("origin"), f"joint[{j.name}].origin")
        if j.type == "fixed":
            state[j.child] = (moving, pending + [origin])
        else:
            if moving is None and from_base == 1:
                joint = _moving_joint(r, j, _nontrivial([origin]))
                if _nontrivial(pending):
                    serial["base"] = _nontrivial(pending)
            else:
                joint = _moving_joint(r, j, _nontrivial(pending + [origin]))
            if rows and moving != rows[-1]["link"]:  # a branch: it hangs on an earlier link or the base
                joint["parent"] = moving if moving is not None else "base"
            r.marks[("serial", "chain", len(rows))] = (j.element.line, j.element.column)
            rows.append(joint)
            state[j.child] = (joint["link"], [])
            dynamics = j.element.find("dynamics")
            if dynamics is not None:
                coefficients = _friction(r, j, dynamics)
                if coefficients:
                    r.marks[("friction", r.joint_ids[j.name])] = (dynamics.line, dynamics.column)
                    friction[r.joint_ids[j.name]] = coefficients
        carrier, frames = state[j.child]
        if carrier is not None:
            carried[j.child] = (carrier, list(frames))
    if not rows:
        r.fail(robot, "", f"the chain {root} -> {tip} has no moving joint", "choose another tip link (--tip)")
        r.stop()
    carrier, pending = state[tip]
    if _nontrivial(pending):
        serial["tcp"] = _nontrivial(pending)
    if carrier != rows[-1]["link"]:
        serial["tip"] = carrier
    serial["chain"] = rows
    data["serial"] = serial
    # Links fixed to a moving link off the chain (sensors, flanges) move with it.
    stack = [j for link in list(carried) for j in children[link] if j.child not in on_path]
    while stack:
        j = stack.pop()
        moving, frames = carried[j.parent]
        step = [r.frame(j.element.find("origin"), f"joint[{j.name}].origin")]
        if j.name in locked:
            step.append(_locked_motion(r, j, locked[j.name]))
        carried[j.child] = (moving, frames + step)
        stack.extend(children[j.child])
    bodies: list[dict[str, Any]] = []
    for link_name, element in links.items():
        if link_name in carried:  # links fixed to the root never move and are ignored
            body = _body(r, link_name, element, *carried[link_name])
            if body is not None:
                r.marks[("bodies", len(bodies))] = (element.line, element.column)
                bodies.append(body)
    if bodies:
        data["bodies"] = bodies
    if friction:
        data["friction"] = friction
    drives = _transmissions(r, robot, {r.joint_ids[j.name] for j in path if j.type != "fixed"})
    if drives:
        data["actuators"] = drives
    data["gravity"] = ["0", "0", "-g"]
    data["task_space"] = "pose"
    if r.snapped:
        data["notes"] = [*data.get("notes", []), f"--snap-angles read {len(r.snapped)} angle(s) as multiples of pi: "
                         + name_list(r.snapped)]
    r.stop()
    return Document(file=file, data=data, marks=r.marks,
                    reduction=UrdfReduction(root, tip, {name: float(value) for name, value in locked.items()},
                                            tuple(r.snap_edits)))


def _transmissions(r: _UrdfReader, robot: Element, chain: set[str]) -> dict[str, dict[str, str]]:
    """{joint: {gear_ratio: |N|}} of the chain's joints with a one-joint ``<transmission>`` whose
    ``mechanicalReduction`` (under ``<actuator>``, or directly under the transmission in the older
    format) is not 1. URDF gives no rotor inertia: the ratio is the drive's, for its resolution and
    effort through the gear (``actuators:``)."""
    drives: dict[str, dict[str, str]] = {}
    seen: dict[str, Element] = {}
    for transmission in robot.findall("transmission"):
        joints, actuators = transmission.findall("joint"), transmission.findall("actuator")
        if len(joints) != 1 or len(actuators) > 1:
            continue  # differentials couple several joints: not a one-joint gear
        joint = r.joint_ids.get(joints[0].attrib.get("name", ""))
        reduction = (actuators[0].find("mechanicalReduction") if actuators else None) or \
            transmission.find("mechanicalReduction")
        if joint not in chain or reduction is None:
            continue
        if joint in seen:  # two gears of one joint: which one is meant is not ours to guess
            first = seen[joint]
            r.fail(transmission, f"transmission[{transmission.attrib.get('name', '')}]",
                   f"a second transmission of joint '{joints[0].attrib.get('name', '')}' (the first, "
                   f"'{first.attrib.get('name', '')}', is at line {first.line})", "keep one transmission per joint")
            continue
        seen[joint] = transmission
        text = reduction.text.strip()
        if not _NUMBER.fullmatch(text) or Fraction(text) == 0:
            r.fail(reduction, f"transmission[{transmission.attrib.get('name', '')}]",
                   f"mechanicalReduction '{text[:40]}' is not a nonzero number", "write the gear ratio, e.g. 50")
            continue
        ratio = abs(Fraction(text))  # a negative reduction only turns the motor the other way
        if ratio != 1:
            r.marks[("actuators", joint)] = (reduction.line, reduction.column)
            drives[joint] = {"gear_ratio": text.lstrip("+-")}
    return drives


def _nontrivial(frames: list[dict[str, list[str]]]) -> list[dict[str, list[str]]]:
    return [f for f in frames if not _is_identity(f)]


def _links(r: _UrdfReader, robot: Element) -> dict[str, Element]:
    links: dict[str, Element] = {}
    for element in robot.findall("link"):
        name = element.attrib.get("name")
        if not name:
            r.fail(element, "link", "a <link> without a name", "add name=\"...\"")
        elif name in links:
            r.fail(element, f"link[{name}]", f"duplicate link name '{name}' (first on line {links[name].line})",
                   "give every link its own name")
        else:
            links[name] = element
    if not links and not r.problems:
        r.fail(robot, "", "the robot has no links", "declare <link> and <joint> elements")
    return links


def _joints(r: _UrdfReader, robot: Element, links: dict[str, Element]) -> dict[str, _Joint]:
    joints: dict[str, _Joint] = {}
    parents: dict[str, _Joint] = {}
    for element in robot.findall("joint"):
        name = element.attrib.get("name", "")
        key = f"joint[{name}]"
        jtype = element.attrib.get("type", "")
        if not name:
            r.fail(element, "joint", "a <joint> without a name", "add name=\"...\"")
            continue
        if name in joints:
            r.fail(element, key, f"duplicate joint name '{name}'", "give every joint its own name")
            continue
        if jtype not in SUPPORTED_JOINTS:
            what = {"floating": "a floating joint (6 DoF, a free-flying base)",
                    "planar": "a planar joint (3 DoF)"}.get(jtype, f"joint type '{jtype}'")
            r.fail(element, key + ".type", f"{what} is not supported; symkin reads serial chains of "
                                           f"{', '.join(SUPPORTED_JOINTS)} joints",
                   "model a mobile base separately, or decompose the joint into revolute/prismatic joints")
            continue
        mimic = None
        m = element.find("mimic")
        if m is not None:
            leader = m.attrib.get("joint")
            if not leader:
                r.fail(m, key + ".mimic", f"the <mimic> of joint '{name}' names no joint", "add joint=\"LEADER\"")
                continue
            multiplier = r.number(m, "multiplier", key + ".mimic", "1")
            offset = r.number(m, "offset", key + ".mimic", "0")
            mimic = (leader, Fraction(multiplier or "1"), Fraction(offset or "0"))
        ends = {}
        for end in ("parent", "child"):
            item = element.find(end)
            link = item.attrib.get("link") if item is not None else None
            if link is None:
                r.fail(element, f"{key}.{end}", f"joint '{name}' has no <{end} link=\"...\"/>", f"add the {end} link")
            elif link not in links:
                r.fail(item, f"{key}.{end}", f"joint '{name}' names the unknown {end} link '{link}'",
                       f"declare <link name=\"{link}\"/> or fix the name")
            else:
                ends[end] = link
        if len(ends) != 2:
            continue
        joint = _Joint(element, name, jtype, ends["parent"], ends["child"], mimic)
        if joint.child in parents:
            first = parents[joint.child]
            r.fail(element, key, f"closed loop: link '{joint.child}' is the child of joint '{first.name}' (line "
                                 f"{first.element.line}) and of joint '{name}'",
                   "symkin reads tree-shaped URDFs (serial chains); model closed loops as parallel mechanisms")
            continue
        parents[joint.child] = joint
        joints[name] = joint
    return joints


def _root(r: _UrdfReader, robot: Element, links: dict[str, Element], parent_of: dict[str, _Joint]) -> str:
    roots = [name for name in links if name not in parent_of]
    if len(roots) != 1:
        if not roots:
            r.fail(robot, "", "every link has a parent joint: the joints form a closed loop",
                   "symkin reads tree-shaped URDFs; remove the joint that closes the loop")
        else:
            r.fail(robot, "", f"the robot has {len(roots)} root links ({name_list(roots)}): they are not connected",
                   "connect every link to one root link by joints")
        r.stop()
    root = roots[0]
    seen, link = set(), None
    for start in links:  # a cycle detached from the root would loop forever below
        link = start
        path = set()
        while link in parent_of and link not in seen:
            if link in path:
                joint = parent_of[link]
                r.fail(joint.element, f"joint[{joint.name}]", f"closed loop through link '{link}'",
                       "symkin reads tree-shaped URDFs; remove the joint that closes the loop")
                r.stop()
            path.add(link)
            link = parent_of[link].parent
        seen |= path
    return root


def _preorder(root: str, children: dict[str, list[_Joint]]) -> list[_Joint]:
    """The joints of ``root``'s subtree, each after its parent's (depth first, in file order)."""
    out, stack = [], list(reversed(children[root]))
    while stack:
        j = stack.pop()
        out.append(j)
        stack.extend(reversed(children[j.child]))
    return out


def _moving_ancestor(j: _Joint, parent_of: dict[str, _Joint], root: str, kept: set[str]) -> str | None:
    """The nearest moving joint of the tree above ``j`` (its name), None if only fixed joints lead to the root."""
    link = j.parent
    while link != root:
        above = parent_of[link]
        if above.type != "fixed" and above.name in kept:
            return above.name
        link = above.parent
    return None


def _subtree(root: str, children: dict[str, list[_Joint]]) -> list[str]:
    """The links of ``root``'s subtree, ``root`` first."""
    links, stack = [], [root]
    while stack:
        link = stack.pop()
        links.append(link)
        stack.extend(j.child for j in reversed(children[link]))
    return links


def _tip(r: _UrdfReader, robot: Element, root: str, children: dict[str, list[_Joint]],
         parent_of: dict[str, _Joint], tip: str | None) -> str:
    """The named tip, or the leaf of the root's subtree behind the most moving joints (the first in the file's
    order among equals): the task frame of a whole tree."""
    subtree = _subtree(root, children)
    if tip is not None:
        if tip not in children:
            r.fail(robot, "tip", f"the tip link '{tip}' is not a link of the robot",
                   f"choose one of: {name_list(subtree)}")
            r.stop()
        return tip
    leaves = [name for name in subtree if not children[name]]
    moving = {leaf: _moving_count(leaf, root, parent_of) for leaf in leaves}
    deepest = [leaf for leaf in leaves if moving[leaf] == max(moving.values())]
    return deepest[0]  # the first in the file's order where several end equally long chains


def _moving_count(link: str, root: str, parent_of: dict[str, _Joint]) -> int:
    """Moving joints between ``root`` and ``link`` (mimic followers do not add a coordinate)."""
    count = 0
    while link != root and link in parent_of:
        count += parent_of[link].type != "fixed" and parent_of[link].mimic is None
        link = parent_of[link].parent
    return count


def _path(r: _UrdfReader, robot: Element, parent_of: dict[str, _Joint], root: str, tip: str) -> list[_Joint]:
    path = []
    link = tip
    while link != root:
        if link not in parent_of:
            r.fail(robot, "tip", f"the tip link '{tip}' is not below the base link '{root}'",
                   "choose a tip in the base link's subtree, or another base (--base)")
            r.stop()
        joint = parent_of[link]
        path.append(joint)
        link = joint.parent
    return path[::-1]


def _locked_values(r: _UrdfReader, robot: Element, joints: dict[str, _Joint], children: dict[str, list[_Joint]],
                   on_path: set[str], path: list[_Joint], locks: dict[str, float],
                   notes: list[str]) -> dict[str, Fraction]:
    """{joint: locked value} of every moving joint hanging off the chain (or beyond the tip) in the
    base's subtree: the caller's value, a mimic follower's from its leader, else 0 clipped into the
    joint's limits (iCub's elbows, the Allegro thumb: limits that exclude 0), with a note in ``notes``."""
    chain_joints = {j.name for j in path}
    for name in locks:
        if name not in joints:
            r.fail(robot, "lock", f"--lock names the unknown joint '{name}'",
                   f"lock one of the joints off the chain: {name_list(j for j in joints if j not in chain_joints)}")
        elif name in chain_joints:
            r.fail(joints[name].element, f"joint[{name}]", f"--lock names '{name}', a joint of the chain to the tip",
                   "lock only joints off the chain; to remove a chain joint, choose a nearer tip (--tip)")
    leaders = {j.name for j in path if j.type != "fixed" and j.mimic is None}
    for j in path:
        if j.mimic is not None and j.type != "fixed" and j.mimic[0] not in leaders:
            r.fail(j.element.find("mimic"), f"joint[{j.name}].mimic",
                   f"joint '{j.name}' on the chain mimics '{j.mimic[0]}', which is not a moving joint of the chain "
                   "with a coordinate of its own (a coupling q = a q_leader + b needs its leader on the chain)",
                   "choose a tip before this joint (--tip), or remove its <mimic> element to make it independent")
    off_chain = []
    stack = [j for link in on_path for j in children[link] if j.name not in chain_joints]
    while stack:
        j = stack.pop()
        off_chain.append(j)
        stack.extend(children[j.child])
    values: dict[str, Fraction] = {}
    followers = []
    for j in sorted(off_chain, key=lambda joint: joint.element.line):
        if j.type == "fixed":
            continue
        if j.mimic is not None and j.name not in locks:
            followers.append((j, j.mimic))
        elif j.name in locks:
            values[j.name] = Fraction(repr(float(locks[j.name])))
        else:
            values[j.name] = _default_lock(j, notes)
    for j, (leader, multiplier, offset) in followers:
        if leader in chain_joints:
            r.fail(j.element.find("mimic"), f"joint[{j.name}].mimic",
                   f"joint '{j.name}' off the chain mimics '{leader}', a joint of the chain: the links it moves "
                   "cannot be lumped into a chain link",
                   f"lock it at a value (--lock {j.name}=VALUE), or choose a tip beyond it (--tip)")
            continue
        if leader not in values:
            r.fail(j.element.find("mimic"), f"joint[{j.name}].mimic",
                   f"joint '{j.name}' mimics '{leader}', which is not a moving joint off the chain",
                   f"lock it at a value (--lock {j.name}=VALUE), or fix the <mimic joint=...> name")
            continue
        values[j.name] = multiplier * values[leader] + offset
    for j in off_chain:
        if j.name in values:
            _check_lock_within_limits(r, j, values[j.name])
    return dict(sorted(values.items(), key=lambda item: joints[item[0]].element.line))


def _limits(j: _Joint) -> tuple[Fraction, Fraction] | None:
    """(lower, upper) of a joint with a proper range in its ``<limit>``, else None (continuous, none given)."""
    limit = j.element.find("limit")
    if j.type == "continuous" or limit is None or not ("lower" in limit.attrib or "upper" in limit.attrib):
        return None
    lower = Fraction(limit.attrib.get("lower", "0")) if _NUMBER.fullmatch(limit.attrib.get("lower", "0")) else None
    upper = Fraction(limit.attrib.get("upper", "0")) if _NUMBER.fullmatch(limit.attrib.get("upper", "0")) else None
    return (lower, upper) if lower is not None and upper is not None and lower < upper else None


def _default_lock(j: _Joint, notes: list[str]) -> Fraction:
    """0 clipped into the joint's limits; a clipped value is noted (where, what, how to choose another)."""
    limits = _limits(j)
    if limits is None or limits[0] <= 0 <= limits[1]:
        return Fraction(0)
    value = limits[0] if limits[0] > 0 else limits[1]
    notes.append(f"line {j.element.line}: joint '{j.name}' off the chain locked at {_decimal(value)}, 0 clipped "
                 f"into its limits [{_decimal(limits[0])}, {_decimal(limits[1])}] (--lock {j.name}=VALUE to choose)")
    return value


def _check_lock_within_limits(r: _UrdfReader, j: _Joint, value: Fraction) -> None:
    limits = _limits(j)
    limit = j.element.find("limit")
    if limits is not None and limit is not None and not limits[0] <= value <= limits[1]:
        r.fail(limit, f"joint[{j.name}].limit", f"joint '{j.name}' is locked at {_decimal(value)}, outside its "
                                                f"limits [{limit.attrib.get('lower')}, {limit.attrib.get('upper')}]",
               f"lock it within its limits (--lock {j.name}=VALUE)")


def _decimal(value: Fraction) -> str:
    return repr(float(value)) if value.denominator != 1 else str(value.numerator)


def _locked_motion(r: _UrdfReader, j: _Joint, value: Fraction) -> dict[str, list[str]]:
    """The frame of joint ``j``'s motion at ``value``: a rotation about its axis (as rpy) or a translation along it."""
    axis_element = j.element.find("axis")
    axis_text = r.numbers(axis_element, "xyz", 3, "1 0 0", f"joint[{j.name}].axis") if axis_element is not None \
        else ["1", "0", "0"]
    axis = [Fraction(a) for a in axis_text]
    norm = math.sqrt(sum(float(a) ** 2 for a in axis))
    if value == 0 or norm == 0:
        return {"xyz": ["0", "0", "0"], "rpy": ["0", "0", "0"]}
    if j.type == "prismatic":
        along = value if norm == 1 else value / Fraction(repr(norm))  # the axis need not be a unit vector
        return {"xyz": [_fraction_text(a * along) for a in axis], "rpy": ["0", "0", "0"]}
    nonzero = [k for k, a in enumerate(axis) if a != 0]
    if len(nonzero) == 1:  # about x, y or z: exact
        rpy = ["0", "0", "0"]
        rpy[nonzero[0]] = _fraction_text(value if axis[nonzero[0]] > 0 else -value)
        return {"xyz": ["0", "0", "0"], "rpy": rpy}
    rotation = rotation_about(np.array([float(a) for a in axis]), float(value))
    return {"xyz": ["0", "0", "0"], "rpy": [repr(angle) for angle in urdf_rpy(rotation)]}


def _fraction_text(value: Fraction) -> str:
    return str(value.numerator) if value.denominator == 1 else f"{value.numerator}/{value.denominator}"


def _moving_joint(r: _UrdfReader, j: _Joint, origin: list[dict[str, list[str]]]) -> dict[str, Any]:
    key = f"joint[{j.name}]"
    joint: dict[str, Any] = {"name": r.joint_ids[j.name], "type": "P" if j.type == "prismatic" else "R",
                             "link": r.link_ids[j.child], "origin": origin}
    axis = j.element.find("axis")
    joint["axis"] = r.numbers(axis, "xyz", 3, "1 0 0", key + ".axis") if axis is not None else ["1", "0", "0"]
    limit = j.element.find("limit")
    if limit is not None:
        angular = j.type != "prismatic"
        if j.type != "continuous" and ("lower" in limit.attrib or "upper" in limit.attrib):
            lower = r.number(limit, "lower", key + ".limit", "0", angle=angular)
            upper = r.number(limit, "upper", key + ".limit", "0", angle=angular)
            if lower is not None and upper is not None and not (Fraction(_plain(lower)) == Fraction(_plain(upper))
                                                                  == 0):
                joint["limits"] = [lower, upper]
        for attribute, field_name in (("velocity", "velocity_limit"), ("effort", "effort_limit")):
            value = r.number(limit, attribute, key + ".limit", "0") if attribute in limit.attrib else None
            if value is not None and Fraction(value) > 0:
                joint[field_name] = value
    if j.mimic is not None:  # a follower on the chain: q = multiplier q_leader + offset, exact
        leader, multiplier, offset = j.mimic
        joint["mimic"] = {"joint": r.joint_ids.get(leader, leader), "multiplier": str(multiplier),
                          "offset": str(offset)}
    return joint


def _friction(r: _UrdfReader, j: _Joint, dynamics: Element) -> dict[str, str]:
    """``<dynamics damping friction>`` as the model's friction: viscous = damping (N*m*s/rad or N*s/m),
    Coulomb = friction (N*m or N); empty when both are zero."""
    key = f"joint[{j.name}].dynamics"
    coefficients = {name: r.number(dynamics, attribute, key, "0")
                    for name, attribute in (("viscous", "damping"), ("coulomb", "friction"))}
    return {name: value for name, value in coefficients.items() if value is not None and Fraction(value) != 0}


def _plain(text: str) -> str:
    """A snapped angle (pi/2, -pi, 2*pi/3) as a number text (for comparisons only)."""
    multiple = re.fullmatch(r"(-?)(\d*)\*?pi(?:/(\d+))?", text)
    if multiple:
        sign, k, d = multiple.groups()
        return repr((-1 if sign else 1) * int(k or 1) * math.pi / int(d or 1))
    return text


def _body(r: _UrdfReader, link: str, element: Element, moving: str, frames: list[dict[str, list[str]]]
          ) -> dict[str, Any] | None:
    """The inertial of URDF ``link`` as a body of the model link ``moving`` (frames: moving -> link)."""
    inertial = element.find("inertial")
    if inertial is None:
        return None
    key = f"link[{link}].inertial"
    mass_element = inertial.find("mass")
    if mass_element is None:
        r.fail(inertial, key, "an <inertial> without <mass value=\"...\"/>", "add the mass")
        return None
    body: dict[str, Any] = {"link": moving, "mass": r.number(mass_element, "value", key + ".mass")}
    origin = _nontrivial(frames + [r.frame(inertial.find("origin"), key + ".origin")])
    if origin:
        body["origin"] = origin
    inertia = inertial.find("inertia")
    if inertia is not None:
        body["inertia"] = {k: r.number(inertia, "i" + k, key + ".inertia", "0")
                           for k in ("xx", "yy", "zz", "xy", "xz", "yz")}
    return body
