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

Least squares identifies only the base parameters pi_b = K pi.  :func:`nearest_standard` gives the standard
parameters those data imply and that stay closest to the model's own values (Gautier and Khalil's regrouping
keeps the non-identifiable parameters at their a priori values; here "closest" is in the scaled norm of
:func:`symkin.analysis.consistent.prior_scale`):

    pi = argmin |D^-1 (pi - pi_prior)|  subject to  K pi = pi_b,   D = diag(prior_scale(pi_prior)).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from symkin.analysis.consistent import prior_scale
from symkin.dynamics.parameter_names import DRIVE, INERTIAL
from symkin.errors import ModelError
from symkin.model.schema import Model

#: A column of K smaller than this fraction of K's largest entry holds no identifiable part of its parameter
#: (K from the regressors by least squares carries rounding of about eps cond(Y_b); sqrt(eps) is far above it).
IDENTIFIABLE_TOLERANCE = float(np.sqrt(np.finfo(np.float64).eps))


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


#: States of a run that :func:`combinations` solves Y = Y_b K over (evenly spread; all of a shorter run).
COMBINATION_STATES = 512


def combinations(Y: np.ndarray, Y_b: np.ndarray) -> np.ndarray:
    """K with Y = Y_b K: the base parameters' combinations of the standard ones, from both regressors at the
    same states (N, n, P) and (N, n, b); exact up to rounding where Y_b has full column rank.

    The identity holds at every state, so :data:`COMBINATION_STATES` of them spread over the run suffice
    (benchmarks/bench_identification.py times both on 10^5 states of the UR10e); all are taken if those leave
    Y_b rank-deficient.
    """
    count = len(Y_b)
    chosen = np.unique(np.linspace(0, count - 1, min(count, COMBINATION_STATES)).astype(int))
    K, rank = _least_squares(Y[chosen], Y_b[chosen])
    if rank < Y_b.shape[-1] and len(chosen) < count:  # the spread states do not excite every base parameter
        K, _ = _least_squares(Y, Y_b)
    return K


def _least_squares(Y: np.ndarray, Y_b: np.ndarray) -> tuple[np.ndarray, int]:
    """(K, rank of the stacked Y_b) of the least-squares solution of Y = Y_b K over the given states."""
    K, _, rank, _ = np.linalg.lstsq(Y_b.reshape(-1, Y_b.shape[-1]), Y.reshape(-1, Y.shape[-1]), rcond=None)
    return K, int(rank)


def identifiable(K: np.ndarray) -> np.ndarray:
    """Which standard parameters enter some base parameter (a boolean per column of K)."""
    largest = float(np.max(np.abs(K))) if K.size else 0.0
    return np.max(np.abs(K), axis=0) > IDENTIFIABLE_TOLERANCE * largest


def nearest_standard(K: np.ndarray, base_values: np.ndarray, prior: np.ndarray) -> np.ndarray:
    """The standard parameters nearest ``prior`` whose base parameters are ``base_values`` (module docstring)."""
    D = prior_scale(prior)
    correction = np.linalg.lstsq(K * D, base_values - K @ prior, rcond=None)[0]  # the minimum-norm solution
    return prior + D * correction


def updated_model(path: str | Path, model: Model, names: Sequence[str], values: np.ndarray,
                  identified: np.ndarray, record: Mapping[str, Any],
                  parameter_values: Mapping[str, float] | None = None) -> UpdatedModel:
    """The model file ``path`` (of ``model``) with the identified standard parameters ``values`` (named as the
    regressor's columns, ``identified`` marking those the run identifies).

    A link's bodies are replaced by one body when any of its ten parameters is identified, a joint's actuator
    rotor inertia and friction when its I_a or friction parameters are; ``record`` (method, data, samples) goes
    into the ``identified:`` section with the replaced parameters' names.  ``parameter_values`` are the
    parameter values the run was identified at (written into the file).

    Raises:
        NotUpdated: the file is not a YAML model, the model has gyroscopic rotors (their bodies are not the
            file's), or the estimate is no model (the model reader's problems).
    """
    from symkin.dynamics.newton_euler import link_frame
    from symkin.model import model_from_text
    from symkin.model.source_kind import URDF, XACRO, YAML, source_kind

    if any(a.gyroscopic for a in model.actuators):
        raise NotUpdated("the model's rotors are bodies of their own (gyroscopic: true), which the link bodies "
                         "identified here include; their values are in estimate.json")
    kind = source_kind(path)
    data = _source_data(path, kind)
    given = dict(parameter_values or {})
    numbers = {p.symbol: given.get(p.name, p.value) for p in model.parameters}
    _set_parameters(data, given)
    index = {name: k for k, name in enumerate(names)}
    links, joints = [], []
    for joint in model.joints:
        columns = [index[f"{joint.link}.{p}"] for p in INERTIAL]
        if identified[columns].any():
            R, p = (np.array(m.xreplace(numbers).evalf(), dtype=float) for m in link_frame(joint))
            _replace_bodies(data, joint.link, _body(values[columns], R, p.ravel()))
            links.append(joint.link)
        drive = [index[f"{joint.name}.{p}"] for p in DRIVE]
        if identified[drive].any():
            _replace_drive(data, joint.name, values[drive], identified[drive], model, numbers)
            joints.append(joint.name)
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
    except ModelError as err:
        found = "; ".join(f"{p.key}: {p.message}" for p in err.problems)
        raise NotUpdated(f"the estimate is not a physical model ({found}); --method consistent keeps every link a "
                         "body and the drives' inertia and friction non-negative") from None
    urdf = identified_urdf(written, links, joints) if kind in (URDF, XACRO) else None
    return UpdatedModel(text, replaced, tuple(links), tuple(joints), urdf)


def _source_data(path: str | Path, kind: str) -> dict[str, Any]:
    """The model document's data of ``path``: a YAML model file's, or a robot file's chain as the readers build
    it (read with their defaults, as ``symkin identify`` reads it)."""
    from symkin.model.mjcf_source import read_mjcf_document
    from symkin.model.source_kind import MJCF, URDF, XACRO
    from symkin.model.urdf_source import read_urdf_document
    from symkin.model.xacro_source import read_xacro_document
    from symkin.model.yaml_source import read_document

    if kind == URDF:
        return read_urdf_document(path).data
    if kind == XACRO:
        return read_xacro_document(path)[0].data
    if kind == MJCF:
        return read_mjcf_document(path)[0].data
    return read_document(path).data


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


def _replace_drive(data: dict[str, Any], joint: str, drive: np.ndarray, known: np.ndarray, model: Model,
                   numbers: Mapping[Any, Any]) -> None:
    """The joint's rotor inertia (I_a / N^2) and friction levels from I_a, f_v, f_c, f_o."""
    inertia, viscous, coulomb, offset = map(float, drive)
    if known[0]:
        actuator = next((a for a in model.actuators if a.joint == joint), None)
        ratio = 1.0 if actuator is None else float(actuator.gear_ratio.xreplace(numbers))
        actuators = data.setdefault("actuators", {}) or {}
        data["actuators"] = actuators
        actuators[joint] = {**(actuators.get(joint) or {}), "rotor_inertia": inertia / ratio ** 2}
    if known[1:].any():
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
