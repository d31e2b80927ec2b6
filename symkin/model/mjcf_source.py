"""Read an MJCF (MuJoCo) model through MuJoCo's own compiler into the model document of a URDF reading.

MuJoCo's compiler resolves what an MJCF file leaves implicit (defaults classes, ``inertiafromgeom``,
``fromto``, quaternions, euler conventions, degrees, ``armature``, ``damping``, ``frictionloss``), so
symkin reads the compiled ``mujoco.MjModel``, not the XML (issue 29). Its body tree becomes URDF text
(:class:`~symkin.model.generated_urdf.GeneratedUrdf`) read by the URDF reader, so the chain, the
locking and lumping of everything off it, the tip rule and the messages are those of URDF files:

* a body is a link named as the body (``world`` for the world body); a body with k hinge or slide
  joints moves by them in order, each about (along) its axis through its anchor ``pos`` in the frame
  the previous ones left (MuJoCo's ``mj_kinematics``): link k of the body is the frame after joint k
  with its origin at the anchor; the body's inertia (``body_ipos``, ``body_iquat``, principal
  ``body_inertia``) and child bodies are placed from there;
* a joint's coordinate is MuJoCo's ``qpos`` (a joint with ``ref`` is at its model pose at
  q = ref); ``free`` and ``ball`` joints are refused, located;
* ``range`` of a limited joint gives the limits (an unlimited hinge is a URDF ``continuous``
  joint, an unlimited slide has no lower and upper limit); an actuator on a joint (transmission ``joint``)
  gives the effort limit gear * max|forcerange| (or gear * gain * max|ctrlrange| for a motor);
* ``damping`` is viscous and ``frictionloss`` Coulomb friction; ``armature`` is the reflected
  rotor inertia of the joint's drive (``actuators:`` with gear ratio 1, see docs/model-format.md);
  joint ``stiffness`` is a spring about ``springref`` (``springs:``, its force part of G);
* an active joint equality that is affine (``polycoef`` with only c0, c1) couples its joints as a
  URDF ``<mimic>`` (q1 = c1 q2 + c0 + ref1 - c1 ref2); other equalities and tendons are noted as not
  modelled;
* gravity is ``option/gravity``: ``[0, 0, -g]`` with the parameter ``g`` its magnitude when it
  points down z, else the vector as given;
* ``<option><flag .../>`` disabling gravity, damping, frictionloss, springs or equality constraints is
  honoured (the model has none of them), disabling joint limits or actuation is noted
  (:data:`~symkin.model.mjcf_options.NOTED_FLAGS`); so are the fluid forces of a medium (``density``, ``viscosity``, ``wind``) and bodies' ``gravcomp``, which
  symkin does not model.

The line of every message is the line of the body or joint element of that name in the file
(elements of included files are named by the file only).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any
from xml.parsers import expat

import numpy as np

from symkin.errors import ModelError, Problem
from symkin.model.confined_read import ReadableFolders, ReadRefused, read_bounded
from symkin.model.generated_urdf import GeneratedUrdf, read_generated_urdf
from symkin.model.mjcf_compile import compile_confined
from symkin.model.mjcf_options import disabled, option_notes
from symkin.model.urdf_export import urdf_rpy
from symkin.model.yaml_source import MAX_FILE_BYTES, Document

#: mujoco.mjtJoint values.
FREE, BALL, SLIDE, HINGE = 0, 1, 2, 3
_TYPES = {SLIDE: "prismatic", HINGE: "revolute"}


def read_mjcf_document(path: str | Path, allow_read: Sequence[str | Path] = (), **urdf: Any) -> tuple[Document, str]:
    """(model document, URDF text of the compiled model) of the MJCF file ``path``; ``urdf``: the URDF
    reader's tip, base, locks and snap_angles (with body names for links, joint names for joints);
    ``allow_read``: more folders the file may read from (:mod:`symkin.model.mjcf_compile`).

    Raises:
        ModelError: MuJoCo missing, a file MuJoCo's compiler refuses (its message), free or ball
            joints on the way, and every problem the URDF reader finds, located.
    """
    file = str(path)
    model, warnings = _compile(Path(path), allow_read)
    lines = _element_lines(Path(path))
    couplings = _joint_couplings(model)
    generated, unmoving = _urdf(model, file, lines, couplings)
    document = read_generated_urdf(generated, file, **urdf)
    _refuse_unmoving_on_chain(document, model, unmoving, file)
    _drives(document, model, lines, couplings)
    _gravity(document, model)
    option_notes(document, model)
    if warnings:  # MuJoCo's compiler warnings, in the model's notes (not a MUJOCO_LOG.TXT in the working folder)
        document.data["notes"] = [*document.data.get("notes", []),
                                  *(f"MuJoCo's compiler warns: {warning}" for warning in warnings)]
    document.data["description"] = document.data["description"].replace("from the URDF", "from the MJCF", 1)
    return document, generated.text


def _compile(path: Path, allow_read: Sequence[str | Path]) -> tuple[Any, list[str]]:
    """MuJoCo's compiled model of the file, its reads confined and the compiler bounded in a subprocess."""
    try:
        import mujoco  # noqa: F401 - the child process needs it too
    except ImportError:
        raise ModelError([Problem(str(path), None, None, "", "reading an MJCF file needs MuJoCo's compiler",
                                  "pip install mujoco")]) from None
    return compile_confined(path, ReadableFolders.of(path, allow_read))


def _element_lines(path: Path) -> dict[tuple[str, str], tuple[int, int]]:
    """{(tag, name): (line, column)} of the named body and joint elements of the file itself."""
    found: dict[tuple[str, str], tuple[int, int]] = {}
    parser = expat.ParserCreate()

    def start(tag: str, attrib: dict[str, str]) -> None:
        if tag in ("body", "joint") and "name" in attrib:
            found.setdefault((tag, attrib["name"]), (parser.CurrentLineNumber, parser.CurrentColumnNumber + 1))

    def refuse(*_args: Any) -> None:
        raise ValueError("document type declarations are not allowed")

    parser.StartElementHandler = start
    parser.StartDoctypeDeclHandler = refuse
    parser.EntityDeclHandler = refuse
    try:
        parser.Parse(read_bounded(path, MAX_FILE_BYTES), True)
    except (expat.ExpatError, ValueError, ReadRefused):
        pass  # MuJoCo compiled it: the lines are a courtesy
    return found


def _name(model: Any, kind: Any, index: int, fallback: str) -> str:
    import mujoco

    return mujoco.mj_id2name(model, kind, index) or f"{fallback}{index}"


def _rotation(quaternion: np.ndarray) -> np.ndarray:
    w, x, y, z = quaternion / np.linalg.norm(quaternion)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _frame(rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = rotation, translation
    return T


def _about(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues' rotation by ``angle`` about the unit ``axis``."""
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def _origin(T: np.ndarray) -> str:
    xyz = " ".join(repr(float(v)) for v in T[:3, 3])
    rpy = " ".join(repr(float(v)) for v in urdf_rpy(T[:3, :3]))
    return f'<origin xyz="{xyz}" rpy="{rpy}"/>'


def _urdf(model: Any, file: str, lines: dict[tuple[str, str], tuple[int, int]], couplings: dict[int, str]
          ) -> tuple[GeneratedUrdf, list[tuple[int, str, int, tuple[int, int] | None]]]:
    """The compiled body tree as URDF text, one element per line, with each line's source place; and the
    free and ball joints (body, name, type, place), which the text leaves at their reference pose."""
    import mujoco
    from xml.sax.saxutils import quoteattr

    out: list[str] = ['<?xml version="1.0"?>', f"<robot name={quoteattr(_model_name(model, file))}>"]
    where: list[tuple[str, Any, Any]] = [(file, 1, 1), (file, 1, 1)]

    def emit(text: str, place: tuple[int, int] | None) -> None:
        out.append(text)
        where.append((file, *place) if place else (file, None, None))

    bodies = [_name(model, mujoco.mjtObj.mjOBJ_BODY, b, "body") for b in range(model.nbody)]
    bodies[0] = "world"
    offset = {0: np.eye(4)}  # body -> the transform from its last link frame to its MuJoCo frame
    link_of = {0: "world"}  # body -> its last link
    unmoving: list[tuple[int, str, int, tuple[int, int] | None]] = []  # free and ball joints, left at qpos0
    emit('<link name="world"/>', None)
    for b in range(1, model.nbody):
        place = lines.get(("body", bodies[b]))
        parent = int(model.body_parentid[b])
        before = offset[parent] @ _frame(_rotation(model.body_quat[b]), model.body_pos[b])
        previous, anchor = link_of[parent], np.zeros(3)
        joints = [j for j in range(model.body_jntadr[b], model.body_jntadr[b] + model.body_jntnum[b])
                  if model.jnt_type[j] in _TYPES]
        offset[b] = _frame(np.eye(3), -np.array(model.jnt_pos[joints[-1]], dtype=float)) if joints else np.eye(4)
        for j in range(model.body_jntadr[b], model.body_jntadr[b] + model.body_jntnum[b]):
            if model.jnt_type[j] not in _TYPES:
                jname = _name(model, mujoco.mjtObj.mjOBJ_JOINT, j, "joint")
                unmoving.append((b, jname, int(model.jnt_type[j]), lines.get(("joint", jname), place)))
        for k, j in enumerate(joints):
            jname = _name(model, mujoco.mjtObj.mjOBJ_JOINT, j, "joint")
            jplace = lines.get(("joint", jname), place)
            kind = int(model.jnt_type[j])
            axis, pos = np.array(model.jnt_axis[j], dtype=float), np.array(model.jnt_pos[j], dtype=float)
            ref = float(model.qpos0[model.jnt_qposadr[j]])
            # MuJoCo: x -> x Trans(p) Motion(q - ref) Trans(-p); the link frame sits at the anchor, at q = 0
            motion = _frame(_about(axis, -ref), np.zeros(3)) if kind == HINGE else _frame(np.eye(3), -ref * axis)
            origin = before @ _frame(np.eye(3), pos - anchor) @ motion
            link = bodies[b] if k == len(joints) - 1 else f"{bodies[b]}/{jname}"
            emit(_link(model, b, link, offset[b]) if link == bodies[b] else f"<link name={quoteattr(link)}/>", place)
            kind_text = "continuous" if kind == HINGE and not model.jnt_limited[j] else _TYPES[kind]
            emit(f"<joint name={quoteattr(jname)} type=\"{kind_text}\">", jplace)
            emit(f"  <parent link={quoteattr(previous)}/><child link={quoteattr(link)}/>{_origin(origin)}"
                 f"<axis xyz=\"{' '.join(repr(float(a)) for a in axis)}\"/>", jplace)
            if j in couplings:
                emit(f"  {couplings[j]}", jplace)
            damping = 0.0 if disabled(model, "DAMPER") else float(model.dof_damping[model.jnt_dofadr[j]])
            dry = 0.0 if disabled(model, "FRICTIONLOSS") else float(model.dof_frictionloss[model.jnt_dofadr[j]])
            emit(f"  {_limit(model, j)}<dynamics damping=\"{damping!r}\" friction=\"{dry!r}\"/>", jplace)
            emit("</joint>", jplace)
            previous, anchor, before = link, pos, np.eye(4)
        if not joints:
            emit(_link(model, b, bodies[b], offset[b]), place)
            emit(f"<joint name={quoteattr(bodies[b] + '/fixed')} type=\"fixed\"><parent link={quoteattr(previous)}/>"
                 f"<child link={quoteattr(bodies[b])}/>{_origin(before)}</joint>", place)
        link_of[b] = bodies[b]
    emit("</robot>", None)
    return GeneratedUrdf("\n".join(out) + "\n", tuple(where)), unmoving


def _refuse_unmoving_on_chain(document: Document, model: Any, unmoving: list[tuple[int, str, int, Any]],
                              file: str) -> None:
    """A free or ball joint between the chain's base and tip: located refusal (off the chain it stays at its
    reference pose, as a locked joint does)."""
    import mujoco

    if not unmoving:
        return
    names = {_name(model, mujoco.mjtObj.mjOBJ_BODY, b, "body"): b for b in range(1, model.nbody)}
    names["world"] = 0
    reduction = document.reduction
    tip = names.get(reduction.tip.split("/")[0], 0)
    base = names.get(reduction.base.split("/")[0], 0)
    on_chain = set()
    while tip not in (base, 0):
        on_chain.add(tip)
        tip = int(model.body_parentid[tip])
    for body, joint, kind, place in unmoving:
        if body in on_chain:
            line, column = place or (None, None)
            raise ModelError([Problem(file, line, column, f"joint[{joint}]",
                                      f"joint '{joint}' on the chain {reduction.base} -> {reduction.tip} is a "
                                      f"{'free' if kind == FREE else 'ball'} joint; symkin reads chains of hinge and "
                                      "slide joints", "start the chain below it (--base BODY), or replace it by "
                                      "hinges")])


def _model_name(model: Any, file: str) -> str:
    """The ``<mujoco model="...">`` name (the first of MuJoCo's names), else the file's stem."""
    names = bytes(model.names)
    return names[:names.index(b"\0")].decode("utf-8", "replace") or Path(file).stem


def _link(model: Any, b: int, name: str, offset: np.ndarray) -> str:
    """The <link> of body ``b`` with its inertial (``offset``: link frame -> MuJoCo body frame)."""
    from xml.sax.saxutils import quoteattr

    mass = float(model.body_mass[b])
    if mass == 0 and not np.any(model.body_inertia[b]):
        return f"<link name={quoteattr(name)}/>"
    frame = offset @ _frame(_rotation(model.body_iquat[b]), model.body_ipos[b])
    ixx, iyy, izz = (repr(float(v)) for v in model.body_inertia[b])
    return (f"<link name={quoteattr(name)}><inertial>{_origin(frame)}<mass value=\"{mass!r}\"/>"
            f"<inertia ixx=\"{ixx}\" iyy=\"{iyy}\" izz=\"{izz}\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>")


def _joint_couplings(model: Any) -> dict[int, str]:
    """{joint: <mimic> element} of the active joint equalities that are affine: MuJoCo's
    q1 - ref1 = c0 + c1 (q2 - ref2) (polycoef c2..c4 zero) is q1 = c1 q2 + (c0 + ref1 - c1 ref2)."""
    import mujoco
    from xml.sax.saxutils import quoteattr

    out: dict[int, str] = {}
    if disabled(model, "CONSTRAINT") or disabled(model, "EQUALITY"):
        return out  # MuJoCo enforces no equality: the joints move freely
    for e in range(model.neq):
        if model.eq_type[e] != mujoco.mjtEq.mjEQ_JOINT or not model.eq_active0[e] or model.eq_obj2id[e] < 0:
            continue
        c0, c1, *higher = (float(v) for v in model.eq_data[e][:5])
        first, second = int(model.eq_obj1id[e]), int(model.eq_obj2id[e])
        if any(higher) or first in out:
            continue  # a polynomial coupling is not a constant map: noted by _drives
        ref1, ref2 = (float(model.qpos0[model.jnt_qposadr[j]]) for j in (first, second))
        leader = _name(model, mujoco.mjtObj.mjOBJ_JOINT, second, "joint")
        out[first] = (f"<mimic joint={quoteattr(leader)} multiplier=\"{c1!r}\" "
                      f"offset=\"{c0 + ref1 - c1 * ref2!r}\"/>")
    return out


def _limit(model: Any, j: int) -> str:
    """<limit> of joint ``j``: its range if limited, the effort of an actuator driving it."""
    attributes = {}
    if model.jnt_limited[j]:
        attributes["lower"], attributes["upper"] = (repr(float(v)) for v in model.jnt_range[j])
    effort = _effort(model, j)
    if not attributes and not effort and model.jnt_type[j] == HINGE:
        return ""  # a continuous joint
    attributes["effort"], attributes["velocity"] = repr(effort), "0"  # URDF requires both; 0: none (MJCF has none)
    return "<limit " + " ".join(f'{k}="{v}"' for k, v in attributes.items()) + "/>"


def _effort(model: Any, j: int) -> float:
    """The largest joint effort of the actuators with a joint transmission on ``j`` (0 if unbounded or none)."""
    import mujoco

    effort = 0.0
    for a in range(model.nu):
        if model.actuator_trntype[a] != mujoco.mjtTrn.mjTRN_JOINT or model.actuator_trnid[a, 0] != j:
            continue
        gear = abs(float(model.actuator_gear[a, 0]))
        if model.actuator_forcelimited[a]:
            effort = max(effort, gear * float(np.max(np.abs(model.actuator_forcerange[a]))))
        elif (model.actuator_ctrllimited[a] and model.actuator_gaintype[a] == mujoco.mjtGain.mjGAIN_FIXED
              and model.actuator_biastype[a] == mujoco.mjtBias.mjBIAS_NONE
              and model.actuator_dyntype[a] == mujoco.mjtDyn.mjDYN_NONE):
            effort = max(effort, gear * abs(float(model.actuator_gainprm[a, 0]))
                         * float(np.max(np.abs(model.actuator_ctrlrange[a]))))
    return effort


def _drives(document: Document, model: Any, lines: dict[tuple[str, str], tuple[int, int]],
            couplings: dict[int, str]) -> None:
    """Armature of the chain's joints as their drives' reflected inertia, stiffness as their springs (about
    ``springref``, MuJoCo's ``qpos_spring``)."""
    import mujoco

    renamed = {source: code for code, source in document.data.get("source_names", {}).get("joints", {}).items()}
    chain = {joint["name"] for joint in document.data["serial"]["chain"]}
    actuators: dict[str, dict[str, str]] = {}
    springs: dict[str, dict[str, str]] = {}
    notes = list(document.data.get("notes", []))
    for j in range(model.njnt):
        source = _name(model, mujoco.mjtObj.mjOBJ_JOINT, j, "joint")
        code = renamed.get(source, source)
        if code not in chain:
            continue
        armature = float(model.dof_armature[model.jnt_dofadr[j]])
        if armature:
            actuators[code] = {"rotor_inertia": repr(armature)}
            place = lines.get(("joint", source))
            if place:
                document.marks[("actuators", code)] = place
        if float(model.jnt_stiffness[j]) and not disabled(model, "SPRING"):
            springs[code] = {"stiffness": repr(float(model.jnt_stiffness[j])),
                             "reference": repr(float(model.qpos_spring[model.jnt_qposadr[j]]))}
            place = lines.get(("joint", source))
            if place:
                document.marks[("springs", code)] = place
    for e in range(0 if disabled(model, "CONSTRAINT") or disabled(model, "EQUALITY") else model.neq):
        if not model.eq_active0[e] or (model.eq_type[e] == mujoco.mjtEq.mjEQ_JOINT
                                       and int(model.eq_obj1id[e]) in couplings):
            continue
        kind = mujoco.mjtEq(model.eq_type[e]).name[len("mjEQ_"):].lower()
        notes.append(f"equality constraint {_name(model, mujoco.mjtObj.mjOBJ_EQUALITY, e, 'equality')} ({kind}) is "
                     "not modelled: symkin's model is the open tree (lock or couple the joints it ties)")
    if model.ntendon:
        notes.append(f"{model.ntendon} tendon(s) not modelled (their forces and couplings are not in the dynamics)")
    if actuators:
        document.data["actuators"] = actuators
    if springs:
        document.data["springs"] = springs
    if notes:
        document.data["notes"] = notes


def _gravity(document: Document, model: Any) -> None:
    """``option/gravity`` (none where the gravity flag is disabled): ``[0, 0, -g]`` with the parameter ``g`` its
    magnitude when it points down z, else the vector as given."""
    gx, gy, gz = (0.0, 0.0, 0.0) if disabled(model, "GRAVITY") else (float(v) for v in model.opt.gravity)
    if gx == gy == gz == 0.0:
        del document.data["parameters"]["g"]
        document.data.pop("gravity", None)
        return
    if gx == 0 and gy == 0 and gz < 0:
        document.data["parameters"]["g"]["value"] = repr(-gz)
    else:
        del document.data["parameters"]["g"]
        document.data["gravity"] = [repr(gx), repr(gy), repr(gz)]
