"""Validate a composed YAML document and build the frozen :class:`~symkin.model.schema.Model`.

The format is documented in ``docs/model-format.md``.  Every problem is collected with its
location (file, line, column, key path) and a suggested fix; if any is found a single
:class:`~symkin.errors.ModelError` lists them all, so a user fixes a file in one pass.
"""

from __future__ import annotations

import dataclasses
import hashlib
from collections.abc import Sequence
from typing import Any

from symkin.errors import ModelError
from symkin.model.body_build import (check_leg_bodies, read_actuators, read_bodies, read_friction, read_parallel_bodies,
                                     read_springs, with_motor_effort_limits)
from symkin.model.names import name_problem
from symkin.model.joint_stops_build import read_joint_stops
from symkin.model.parallel_build import build_parallel, check_parallel_names, parallel_task_space
from symkin.model.parameter_build import check_name_clashes, read_parameters
from symkin.model.reader import ZERO, Reader, describe
from symkin.model.scene_build import read_scene
from symkin.model.schema import Joint, Model, Parallel
from symkin.model.units import ACCELERATION
from symkin.model.rotors import with_rotors
from symkin.model.serial_build import read_home, read_serial, read_tip
from symkin.model.task_space_build import read_task_space
from symkin.model.wrist_build import read_wrist
from symkin.model.yaml_source import Document

#: Version of the model format; part of the model hash.
FORMAT_VERSION = 1
#: Sections that say how a model is emitted, not what the mechanism is: left out of the model hash,
#: so that choosing other outputs, backends or folded parameters keeps the mechanism's identity.
EMISSION_KEYS = ("scene",)
TOP_LEVEL_KEYS = ("name", "description", "references", "notes", "allow_nonphysical", "source_names", "parameters",
                  "serial", "parallel", "wrist", "task_space", "bodies", "gravity", "friction", "springs", "actuators",
                  "joint_stops", "scene", "identified")


def build_model(doc: Document, stem: str, allow_nonphysical: bool = False) -> Model:
    """Validate ``doc`` and build its :class:`Model`.

    Args:
        doc: the composed YAML document.
        stem: file name without extension, the default model name.
        allow_nonphysical: accept non-physical inertias with a note (as the model key does).

    Raises:
        ModelError: listing every problem found.
    """
    r = Reader(doc)
    data = r.mapping((), doc.data, optional=TOP_LEVEL_KEYS)
    if data is None:
        raise ModelError(r.problems)
    r.notes = _texts(r, data, "notes", "notes") + _identified(r, data)
    r.allow_nonphysical = allow_nonphysical or _flag(r, data, "allow_nonphysical")

    name = _model_name(r, data, stem)
    description = r.string(("description",), data.get("description", "")) or ""
    references = _references(r, data)
    parameters, derived = read_parameters(r, data.get("parameters", {}))
    if ("serial" in data) == ("parallel" in data):
        r.fail((), "the model declares no mechanism" if "serial" not in data else
               "the model declares both a serial chain and a parallel mechanism",
               "write exactly one of 'serial:' or 'parallel:' (see docs/model-format.md)")
        raise ModelError(r.problems)
    parallel = None
    if "serial" in data:
        joints, base, tcp = read_serial(r, data["serial"])
        tip = read_tip(r, data["serial"], joints)
        home = read_home(r, data["serial"], joints)
        check_name_clashes(r, parameters, derived, joints)
        task_space = read_task_space(r, data.get("task_space", "position"))
        coordinate_names = tuple(j.name for j in joints)
    else:
        joints, base, tcp, tip, home = (), (), (), None, None
        parallel = build_parallel(r, data["parallel"])
        if parallel is None:
            raise ModelError(r.problems)
        task_space = parallel_task_space(r, data, parallel)
        check_parallel_names(r, parameters, derived, parallel)
        coordinate_names = tuple(j.variables[j.active] for leg in parallel.legs for j in leg.joints
                                 if j.active is not None)
    links = tuple(j.link for j in joints)
    r.defer_nonphysical = parallel is None  # a serial model's kinematics do not use the inertias
    bodies = read_bodies(r, data.get("bodies", []), links) if parallel is None else ()
    r.defer_nonphysical = False
    if parallel is not None and "bodies" in data:
        parallel = dataclasses.replace(parallel, bodies=read_parallel_bodies(r, data["bodies"]))
        check_leg_bodies(r, parallel)
    gravity = r.vector3(("gravity",), data["gravity"], ACCELERATION) if "gravity" in data else (ZERO, ZERO, ZERO)
    friction = read_friction(r, data.get("friction", {}), coordinate_names, revolute=_revolute(joints, parallel))
    if "wrist" in data and parallel is None:
        r.fail(("wrist",), "a wrist is carried by a parallel platform; a serial chain goes on in 'serial:'",
               "append the wrist's joints to the serial chain, or declare the mechanism under 'parallel:'")
    elif "wrist" in data and parallel is not None:
        wrist, wrist_friction = read_wrist(r, data["wrist"], parallel)
        if wrist is not None:
            check_name_clashes(r, parameters, derived, wrist.joints)
        parallel = dataclasses.replace(parallel, wrist=wrist)
        friction += wrist_friction
    springs = read_springs(r, data.get("springs", {}), joints)
    if parallel is not None and "springs" in data:
        r.fail(("springs",), "joint springs are modelled on serial chains and trees, not on a parallel model's legs",
               "remove 'springs:' (or model the device as a serial tree to give its joints springs)")
    actuators = read_actuators(r, data.get("actuators", {}), tuple(j.name for j in joints))
    joints = with_motor_effort_limits(joints, actuators)
    joints, bodies = with_rotors(r, joints, actuators, bodies)
    if parallel is not None and "actuators" in data:
        r.fail(("actuators",), "a parallel model's actuator rotors are declared among its bodies",
               "write bodies: {rotor: {inertia: J_m, gear_ratio: N}} (docs/model-format.md)")
    coordinates = tuple(j for j in joints if not j.follower) if parallel is None else parallel.actuated_coordinates
    joint_stops = read_joint_stops(r, data["joint_stops"], coordinates, home) if "joint_stops" in data else ()
    scene = read_scene(r, data.get("scene", {}), parameters,
                   ("fk", "jacobian") if parallel is None else ("closure", "closure_jacobians"))

    if r.problems:
        raise ModelError(r.problems)
    digest = hashlib.sha256(
        f"symkin-model-format-{FORMAT_VERSION}\n{doc.canonical_json(omit=EMISSION_KEYS)}".encode()).hexdigest()
    return Model(
        name=name,
        description=description.strip(),
        references=references,
        notes=tuple(r.notes),
        nonphysical=tuple(r.nonphysical),
        source_names=_source_names(r, data),
        source=doc.file,
        hash=f"sha256:{digest}",
        parameters=parameters,
        derived_parameters=derived,
        joints=joints,
        base=base,
        tcp=tcp,
        task_space=task_space,
        bodies=bodies,
        gravity=gravity or (ZERO, ZERO, ZERO),
        friction=friction,
        springs=springs,
        actuators=actuators,
        joint_stops=joint_stops,
        tip=tip,
        home_configuration=home,
        scene=scene,
        parallel=parallel,
        locations=dict(doc.marks),
        declared_names=dict(r.declared),
    )


def _model_name(r: Reader, data: dict[str, Any], stem: str) -> str:
    if "name" in data:
        return r.name(("name",), data["name"]) or "invalid"
    problem = name_problem(stem)
    if problem:
        r.fail((), f"the model has no 'name:' and the file name is not usable as one: {problem}",
               "add a line 'name: my_robot' at the top of the file")
        return "invalid"
    return stem


def _references(r: Reader, data: dict[str, Any]) -> tuple[str, ...]:
    return tuple(_texts(r, data, "references", "citations"))


def _identified(r: Reader, data: dict[str, Any]) -> list[str]:
    """``identified: {method, data, samples, parameters: [names], robot_file}`` (written by ``symkin identify``; the
    robot file where the model was read from one): a note."""
    if "identified" not in data:
        return []
    section = r.mapping(("identified",), data["identified"], required=("method", "data", "samples", "parameters"),
                        optional=("robot_file",))
    if section is None or not {"method", "data", "samples", "parameters"} <= set(section):
        return []
    method, source = r.string(("identified", "method"), section["method"]), r.string(("identified", "data"),
                                                                                    section["data"])
    samples = section["samples"]
    if not isinstance(samples, int) or isinstance(samples, bool) or samples < 1:
        r.fail(("identified", "samples"), f"expected a number of samples, got {describe(samples)}",
               "write the run's sample count, e.g. 'samples: 4500'")
    items = r.sequence(("identified", "parameters"), section["parameters"], what="standard parameter names") or []
    names = [n for i, v in enumerate(items) if (n := r.string(("identified", "parameters", i), v)) is not None]
    robot = r.string(("identified", "robot_file"), section["robot_file"]) if "robot_file" in section else None
    if method is None or source is None:
        return []
    return [f"identified by symkin identify ({method}) from {source}, {samples} samples: "
            f"{len(names)} standard parameters" + (f" (the chain of the robot file {robot})" if robot else "")]


def _texts(r: Reader, data: dict[str, Any], key: str, what: str) -> list[str]:
    items = r.sequence((key,), data.get(key, []), what=what)
    if items is None:
        return []
    return [s for i, v in enumerate(items) if (s := r.string((key, i), v)) is not None]


def _source_names(r: Reader, data: dict[str, Any]) -> dict[str, dict[str, str]]:
    """``source_names: {joints: {name: source name}, links: {...}}`` (written by the URDF reader)."""
    section = r.mapping(("source_names",), data.get("source_names", {}), optional=("joints", "links"))
    out: dict[str, dict[str, str]] = {}
    for kind, names in (section or {}).items():
        if not isinstance(names, dict):
            r.fail(("source_names", kind), f"expected a mapping of names, got {names!r:.40}",
                   "write {model name: name in the source file, ...}")
            continue
        out[kind] = {str(k): v for k, v in names.items() if r.string(("source_names", kind, k), v) is not None}
    return out


def _flag(r: Reader, data: dict[str, Any], key: str) -> bool:
    value = data.get(key, False)
    if not isinstance(value, bool):
        r.fail((key,), f"expected true or false, got {value!r:.40}", f"write '{key}: true' or leave it out")
        return False
    return value


def _revolute(joints: Sequence[Joint], parallel: Parallel | None) -> dict[str, bool]:
    """{coordinate: whether it turns} (a serial joint's type, a leg's actuated motion), for the units of friction."""
    if parallel is None:
        return {j.name: j.turns for j in joints}
    return {j.variables[j.active]: j.motions[j.active][2] for leg in parallel.legs for j in leg.joints
            if j.active is not None}
