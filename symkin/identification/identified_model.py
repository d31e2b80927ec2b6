"""The model file with identified values: a YAML model rewritten from estimated standard parameters.

Identification estimates the standard parameters pi in each link's joint frame F_i, about its origin
(:mod:`symkin.dynamics.regressor`): per link m, h = m c and the rotational inertia J about the origin of F_i;
per joint the reflected rotor inertia I_a and the friction f_v, f_c, f_o.  A model file declares bodies in
link frames about their centres of mass, and drives as actuators and friction levels.  This module maps one
to the other, with the link frame at rotation R and origin p in F_i (the joint's ``after`` operations):

    c = h / m,   I_c = J - m (c.c 1 - c c^T)     (parallel axes, back to the centre of mass),
    com = R^T (c - p),   I = R^T I_c R           (into the link frame),
    rotor_inertia = I_a / N^2,   coulomb = {positive: f_c + f_o, negative: f_c - f_o}

and rewrites the model file's data: what the run identifies is replaced, the rest is kept, and the section
``identified:`` lists the replaced parameters with the method and the data.  The result is read back by the
model reader (:func:`symkin.model.model_from_text`), whose checks (positive masses, the triangle inequality of
the principal moments, non-negative friction) decide whether it is a model at all.

A parallel model's file declares its bodies once for every leg (the platform, the actuated link, a spherical
leg's distal link about their frames' origins, as the regressor's columns are), the rods as a mass, the part of
it at the platform joints and an inertia across them, and one rotor for all actuators:

    mass = m_B + m_C,   platform_fraction = m_B / (m_B + m_C),   inertia = dI + m_B m_C / (m_B + m_C) L^2,

the standard parameters given in what the file holds (:func:`symkin.identification.implied_parameters.nearest_held`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from symkin.dynamics.parameter_names import DRIVE, INERTIAL, ROD
from symkin.errors import ModelError
from symkin.model.schema import Actuator, Joint, Model, PlatformMotion

#: The name of a parallel model's one rotor inertia (reflected, I_a), shared by its actuators.
SHARED_ROTOR = f"rotor.{DRIVE[0]}"


@dataclass(frozen=True)
class Held:
    """The standard parameters a model file holds: pi = fixed + T z, a column of T per value the file declares.

    Attributes:
        T: (P, V), each standard parameter's part of the file's values (0/1: a value shared by several columns).
        fixed: (P,), the columns the file cannot declare, at the model's values (0 elsewhere).
        names: (V,), the file's values named as standard parameters (a shared rotor: :data:`SHARED_ROTOR`).
    """

    T: np.ndarray
    fixed: np.ndarray
    names: tuple[str, ...]

    @property
    def every_column(self) -> bool:
        """Whether the file declares every standard parameter as a value of its own (T = 1, nothing fixed)."""
        return self.T.shape[0] == self.T.shape[1] and np.array_equal(self.T, np.eye(len(self.T))) and \
            not np.any(self.fixed)

    @property
    def columns(self) -> np.ndarray:
        """Which standard parameters the file declares (a boolean per column)."""
        return np.any(self.T != 0, axis=1)

    def values_of(self, pi: np.ndarray) -> np.ndarray:
        """z of the standard parameters ``pi`` the file holds (of others: the least-squares z)."""
        return np.linalg.lstsq(self.T, pi - self.fixed, rcond=None)[0]


def file_held(model: Model, names: Sequence[str], prior: np.ndarray) -> Held:
    """What ``model``'s file holds of the regressor's columns ``names``: an open chain's file every column as a
    value of its own; a parallel model's fewer (:func:`parallel_held`)."""
    if model.parallel is None:
        return Held(np.eye(len(names)), np.zeros(len(names)), tuple(names))
    return parallel_held(model, names, prior)


def parallel_held(model: Model, names: Sequence[str], prior: np.ndarray) -> Held:
    """What a parallel model's file holds of the regressor's columns ``names`` (module docstring): each column its
    own value but the actuators' rotor inertias I_a, one for all, and a spherical model's rods, fixed at
    ``prior`` (the model's pi: its file declares none)."""
    actuators = {f"{c.name}.{DRIVE[0]}" for c in model.coordinates}
    spherical = model.parallel is not None and model.parallel.motion is PlatformMotion.SPHERICAL
    fixed_names = {f"rod.{p}" for p in ROD} if spherical else set()
    values: list[list[int]] = []
    rotor: list[int] = []
    for k, name in enumerate(names):
        if name in actuators:
            rotor.append(k)
        elif name not in fixed_names:
            values.append([k])
    groups = values + ([rotor] if rotor else [])
    T = np.zeros((len(names), len(groups)))
    for column, group in enumerate(groups):
        T[group, column] = 1.0
    fixed = np.where(np.array([name in fixed_names for name in names], dtype=bool), prior, 0.0)
    return Held(T, fixed, tuple(names[k] for k, in values) + ((SHARED_ROTOR,) if rotor else ()))


class NotUpdated(Exception):
    """The model file cannot carry this estimate (the message says why and what would)."""


@dataclass(frozen=True)
class UpdatedModel:
    """The rewritten model file and what it replaced.

    Attributes:
        text: the YAML text of the updated model file (of a robot file: its chain as a symkin model).
        identified: the standard parameters the run identifies (those with a part in some base parameter).
        links: the links whose bodies were replaced; joints: the joints whose drive or friction was.
        urdf: of a URDF or xacro file, the identified model as a URDF (:func:`identified_urdf`), else None.
    """

    text: str
    identified: tuple[str, ...]
    links: tuple[str, ...]
    joints: tuple[str, ...]
    urdf: str | None = None


def updated_model(path: str | Path, model: Model, names: Sequence[str], values: np.ndarray,
                  identified: np.ndarray, record: Mapping[str, Any],
                  parameter_values: Mapping[str, float] | None = None,
                  reading: Mapping[str, Any] | None = None) -> UpdatedModel:
    """The model file ``path`` (of ``model``) with the identified standard parameters ``values`` (named as the
    regressor's columns, ``identified`` marking those the run identifies).

    A link's bodies are replaced by one body when any of its ten parameters is identified, a joint's actuator
    rotor inertia and friction when its I_a or friction parameters are (of a parallel model: its bodies, rods
    and rotor as the module docstring maps them, ``values`` held by its file (:mod:`implied_parameters`); a hybrid
    device's wrist as a serial chain); ``record`` (method, data, samples) goes into the ``identified:`` section
    with the replaced parameters' names.  ``parameter_values`` are the parameter values the run was identified
    at (written into the file); ``reading``: the options a robot file was read with (:func:`symkin.model.load_model`'s
    tip, chain, snap_angles, ...), so the file is rewritten from the model the run identified.

    Raises:
        NotUpdated: the file is not a YAML model, the model has gyroscopic rotors (their bodies are not the
            file's), or the estimate is no model (the model reader's problems).
    """
    from symkin.model import model_from_text
    from symkin.model.source_kind import URDF, XACRO, YAML, source_kind

    wrist = None if model.parallel is None else model.parallel.wrist
    if any(a.gyroscopic for a in model.actuators + (wrist.actuators if wrist is not None else ())):
        raise NotUpdated("the model's rotors are bodies of their own (gyroscopic: true), which the link bodies "
                         "identified here include; their values are in estimate.json")
    kind = source_kind(path)
    data = _source_data(path, reading or {})
    given = dict(parameter_values or {})
    numbers = {p.symbol: given.get(p.name, p.value) for p in model.parameters}
    _set_parameters(data, given)
    estimate = _Estimate({name: k for k, name in enumerate(names)}, values, identified, numbers)
    if model.parallel is None:
        links, joints = _update_chain(data, model.joints, model.actuators, estimate)
    else:
        links, joints = _update_parallel(data, model, estimate)
    replaced = tuple(name for name, known in zip(names, identified) if known)
    data["identified"] = {**record, **({} if kind == YAML else {"robot_file": Path(path).name}),
                          "parameters": list(replaced)}
    # file names stay inside the YAML data (quoted by the dumper): in a comment a newline in one would start a key
    what = "" if kind == YAML else " (its robot file's chain as a symkin model)"
    header = (f"# {model.name} with identified values{what}, written by symkin identify (what was replaced: "
              "'identified:')\n")
    text = header + yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=110, allow_unicode=True)
    try:
        written = model_from_text(text, model.name, file="identified.yaml")
        if written.nonphysical:  # the reader lets the kinematics through; an identified model is its dynamics
            raise ModelError(list(written.nonphysical))
    except ModelError as err:
        found = "; ".join(f"{p.key}: {p.message}" for p in err.problems)
        raise NotUpdated(f"the estimate is not a physical model ({found}); --method consistent keeps every link a "
                         "body and the drives' inertia and friction non-negative") from None
    urdf = identified_urdf(written, links, joints) if kind in (URDF, XACRO) else None
    return UpdatedModel(text, replaced, tuple(links), tuple(joints), urdf)


@dataclass(frozen=True)
class _Estimate:
    """The standard parameters' values by name (``index``), which the run identifies, and the model's numbers."""

    index: Mapping[str, int]
    values: np.ndarray
    identified: np.ndarray
    numbers: Mapping[Any, Any]

    def of(self, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
        """(values, identified) of the named columns."""
        columns = [self.index[name] for name in names]
        return self.values[columns], self.identified[columns]


def _update_chain(section: dict[str, Any], joints: Sequence[Joint], actuators: Sequence[Actuator],
                  estimate: _Estimate) -> tuple[list[str], list[str]]:
    """A serial chain's links' bodies and joints' drives in ``section`` (a serial model's data, a wrist's section):
    the links and joints replaced."""
    from symkin.dynamics.newton_euler import link_frame

    links, replaced = [], []
    for joint in joints:
        body, known = estimate.of([f"{joint.link}.{p}" for p in INERTIAL])
        if known.any():
            R, p = (np.array(m.xreplace(estimate.numbers).evalf(), dtype=float) for m in link_frame(joint))
            _replace_bodies(section, joint.link, _body(body, R, p.ravel()))
            links.append(joint.link)
        drive, known = estimate.of([f"{joint.name}.{p}" for p in DRIVE])
        if known.any():
            _replace_drive(section, joint.name, drive, known, actuators, estimate.numbers)
            replaced.append(joint.name)
    return links, replaced


def _update_parallel(data: dict[str, Any], model: Model, estimate: _Estimate) -> tuple[list[str], list[str]]:
    """A parallel model's ``bodies:`` (platform, actuated and distal links, rods, legs' links, the rotor), its actuators'
    friction and a hybrid device's wrist: the bodies and joints replaced."""
    from symkin.model.schema import ParallelBodies
    from symkin.parallel import hybrid

    assert model.parallel is not None
    declared = model.parallel.bodies or ParallelBodies()
    bodies = data.setdefault("bodies", {}) or {}
    data["bodies"] = bodies
    links, joints = [], []
    # the bodies of legs without the distance form are in their joints' frames (bodies.links), as the others in theirs
    leg_links = bodies.setdefault("links", {}) if declared.links else {}
    for key, place in [(k, bodies) for k in ("platform", "actuated_link", "distal_link")] + [
            (body.link, leg_links) for body in declared.links]:
        if f"{key}.{INERTIAL[0]}" not in estimate.index:
            continue
        values, known = estimate.of([f"{key}.{p}" for p in INERTIAL])
        if known.any():
            body = _body(values, np.eye(3), np.zeros(3))
            if isinstance(body, str):
                raise NotUpdated(f"the estimate gives the {key} a {body}; --method consistent keeps every body rigid")
            place[key] = body
            links.append(key)
    rod = [f"rod.{p}" for p in ROD if f"rod.{p}" in estimate.index]
    if model.parallel.motion is not PlatformMotion.SPHERICAL and estimate.of(rod)[1].any():
        bodies["rod"] = {**(bodies.get("rod") or {}), **_rod(estimate.of(rod)[0], _rod_length_squared(model,
                                                                                                     estimate))}
        links.append("rod")
    rotor = [f"{c.name}.{DRIVE[0]}" for c in model.coordinates]
    inertia, known = estimate.of(rotor)
    if known.any():
        gear = float(declared.gear_ratio.xreplace(estimate.numbers))
        bodies["rotor"] = {**(bodies.get("rotor") or {}), "inertia": float(np.mean(inertia)) / gear ** 2}
    for c in model.coordinates:
        drive, known = estimate.of([f"{c.name}.{p}" for p in DRIVE])
        if known[1:].any():
            _replace_friction(data, c.name, drive)
        if known.any():
            joints.append(c.name)
    wrist = model.parallel.wrist
    if wrist is not None:
        chain = hybrid.device_chain(model).joints[len(hybrid.platform_joints(model)):]
        wrist_links, wrist_joints = _update_chain(data["wrist"], chain, wrist.actuators, estimate)
        links, joints = links + wrist_links, joints + wrist_joints
    return links, joints


def _rod(ends: np.ndarray, length_squared: float | None) -> dict[str, Any]:
    """``rod: {mass, platform_fraction[, inertia]}`` from the end masses m_B, m_C [and dI] (module docstring)."""
    mB, mC = map(float, ends[:2])
    if mB < 0 or mC < 0:
        raise NotUpdated(f"the estimate gives the rods end masses {mB:.6g} kg (platform) and {mC:.6g} kg (proximal), "
                         "one negative; --method consistent keeps them non-negative")
    mass = mB + mC
    rod: dict[str, Any] = {"mass": mass, "platform_fraction": mB / mass if mass > 0 else 0.0}
    if len(ends) == len(ROD) and length_squared is not None:
        rod["inertia"] = float(ends[2]) + (mB * mC / mass if mass > 0 else 0.0) * length_squared
    return rod


def _rod_length_squared(model: Model, estimate: _Estimate) -> float | None:
    """L^2 of the rods (every leg's the same where the regressor has rod.dI), at the model's numbers."""
    if f"rod.{ROD[2]}" not in estimate.index:
        return None
    from symkin.derivation import Derivation
    from symkin.parallel.quantities import reduced_legs

    return float(Derivation(model)[reduced_legs][0].L2.xreplace(estimate.numbers))


def _source_data(path: str | Path, reading: Mapping[str, Any]) -> dict[str, Any]:
    """The model document's data of ``path`` as :func:`symkin.model.read_model_document` reads it with the options
    ``reading`` (those ``symkin identify`` read it with; allow_nonphysical is the builder's, not the reader's)."""
    from symkin.model import read_model_document

    return read_model_document(path, **{key: value for key, value in reading.items()
                                        if key != "allow_nonphysical"}).data


def identified_urdf(model: Model, links: Sequence[str], joints: Sequence[str]) -> str:
    """The identified ``model`` written as a URDF (:func:`symkin.model.urdf_export.export_urdf`: its TCP is the link
    ``tcp``), with a comment on what was identified and what a URDF cannot carry: rotor inertias and
    direction-dependent Coulomb levels stay in identified.yaml."""
    from symkin.model.urdf_export import export_urdf, xml_comment

    values = model.parameter_values
    rotors = [a.joint for a in model.actuators if a.joint in joints and (a.rotor_inertia * a.gear_ratio ** 2).xreplace(values) != 0]
    asymmetric = [f.joint for f in model.friction if f.joint in joints and f.asymmetric]
    lost = ([f"the rotor inertias of {', '.join(rotors)}"] if rotors else []) + (
        [f"the direction-dependent Coulomb levels of {', '.join(asymmetric)} (their positive one is written)"]
        if asymmetric else [])
    note = (f"identified by symkin identify: the inertials of {', '.join(links) or 'no link'} and the friction of "
            f"{', '.join(joints) or 'no joint'} (the parameters: identified.yaml, its section identified)"
            + (f"; not part of a URDF, in identified.yaml only: {'; '.join(lost)}" if lost else ""))
    head, rest = export_urdf(model).split("\n", 1)
    return f"{head}\n{xml_comment(note)}\n{rest}"


def _body(link: np.ndarray, R: np.ndarray, p: np.ndarray) -> dict[str, Any] | str:
    """A body mapping in the link frame from ten standard parameters in F_i (module docstring), or a reason."""
    m, hx, hy, hz, xx, xy, yy, xz, yz, zz = map(float, link)
    if not m > 0:
        return f"mass {m:.6g} kg"
    c = np.array([hx, hy, hz]) / m
    J = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    I_c = R.T @ (J - m * (c @ c * np.eye(3) - np.outer(c, c))) @ R
    com = R.T @ (c - p)
    return {"mass": m, "com": [float(x) for x in com],
            "inertia": {"xx": float(I_c[0, 0]), "yy": float(I_c[1, 1]), "zz": float(I_c[2, 2]),
                        "xy": float(I_c[0, 1]), "xz": float(I_c[0, 2]), "yz": float(I_c[1, 2])}}


def _replace_bodies(data: dict[str, Any], link: str, body: dict[str, Any] | str) -> None:
    if isinstance(body, str):
        raise NotUpdated(f"the estimate gives link {link} a {body}; --method consistent keeps every link a body")
    bodies = data.setdefault("bodies", [])
    at = next((k for k, b in enumerate(bodies) if isinstance(b, dict) and b.get("link") == link), len(bodies))
    kept = [b for b in bodies if not (isinstance(b, dict) and b.get("link") == link)]
    kept.insert(min(at, len(kept)), {"link": link, **body})
    data["bodies"] = kept


def _replace_drive(data: dict[str, Any], joint: str, drive: np.ndarray, known: np.ndarray,
                   actuators: Sequence[Actuator], numbers: Mapping[Any, Any]) -> None:
    """The joint's rotor inertia (I_a / N^2) and friction levels from I_a, f_v, f_c, f_o."""
    if known[0]:
        actuator = next((a for a in actuators if a.joint == joint), None)
        ratio = 1.0 if actuator is None else float(actuator.gear_ratio.xreplace(numbers))
        section = data.setdefault("actuators", {}) or {}
        data["actuators"] = section
        section[joint] = {**(section.get(joint) or {}), "rotor_inertia": float(drive[0]) / ratio ** 2}
    if known[1:].any():
        _replace_friction(data, joint, drive)


def _replace_friction(data: dict[str, Any], joint: str, drive: np.ndarray) -> None:
    """The joint's friction levels from f_v, f_c, f_o (``drive``'s last three)."""
    _, viscous, coulomb, offset = map(float, drive)
    sections = data.setdefault("friction", {}) or {}
    data["friction"] = sections
    old = sections.get(joint) or {}
    entry: dict[str, Any] = {"viscous": viscous}
    entry["coulomb"] = coulomb if offset == 0 else {"positive": coulomb + offset, "negative": coulomb - offset}
    if "smoothing_velocity" in old:
        entry["smoothing_velocity"] = old["smoothing_velocity"]
    sections[joint] = entry


def _set_parameters(data: dict[str, Any], given: Mapping[str, float]) -> None:
    """The values the run was identified at, in the file's ``parameters:``."""
    parameters = data.get("parameters") or {}
    for name, value in given.items():
        entry = parameters.get(name)
        if isinstance(entry, dict):
            entry["value"] = float(value)
        else:
            parameters[name] = float(value)
