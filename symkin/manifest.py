"""The manifest of a generated model directory (``OUT/<model>/manifest.json``).

The manifest is the contract between ``symkin derive`` and everything that uses its
output (``symkin.load``, analyses, users' build systems).  It records the model identity,
the generator versions, every function with its inputs, outputs, op counts and the
backends that emitted it, and the files of each backend.  It holds no timestamps or
timings, so the same model always gives the same bytes.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from symkin._version import __version__
from symkin.errors import GeneratedCodeError

if TYPE_CHECKING:  # reading a manifest must not import sympy
    from symkin.ir.bundle import ModelCode
    from symkin.model.schema import Model

MANIFEST_NAME = "manifest.json"
MANIFEST_VERSION = 1


def _input_record(i) -> dict[str, Any]:
    record: dict[str, Any] = {"name": i.name, "kind": i.kind, "shape": list(i.shape),
                              "elements": list(i.element_names), "units": list(i.units), "doc": i.doc}
    if i.default is not None:
        record["default"] = float(i.default)
    return record


def _coordinate_record(model: Model, coordinate, joints: tuple | None = None, actuators: tuple | None = None
                       ) -> dict[str, Any]:
    """Name and type of a joint coordinate, whether it is passive, and its position, velocity and effort
    limits where the model declares them.

    Limits are numbers: their expressions evaluated at the parameters' default values (the
    analyses in :mod:`symkin.analysis` and the simulation read them without sympy).
    """
    record: dict[str, Any] = {"name": coordinate.name, "type": coordinate.type.value}
    if not getattr(coordinate, "active", True):  # a passive joint (active: false): no actuator drives it
        record["active"] = False
    if model.source_name("joints", coordinate.name) != coordinate.name:  # a URDF's joint_0.0, as named there
        record["source_name"] = model.source_name("joints", coordinate.name)
    values = model.parameter_values
    if coordinate.limits is not None:
        record["limits"] = [float(bound.xreplace(values)) for bound in coordinate.limits]
    for key in ("velocity_limit", "effort_limit"):
        bound = getattr(coordinate, key, None)
        if bound is not None:
            record[key] = float(bound.xreplace(values))
    from symkin.model.body_build import drive_of  # sympy: only when a manifest is built

    drive = drive_of(coordinate.name, model.joints if joints is None else joints,
                     model.actuators if actuators is None else actuators)
    if drive is not None:  # motor turns per turn of the coordinate, s N (an encoder on the motor: symkin rate)
        record["gear_ratio"] = float((drive[1] * drive[0].gear_ratio).xreplace(values))
    if drive is not None and drive[0].continuous_effort is not None:  # s N K_t I_cont: what the motor holds for long
        record["continuous_effort_limit"] = float((drive[1] * drive[0].continuous_effort).xreplace(values))
    friction = next((f for f in model.friction if f.joint == coordinate.name), None)
    if friction is not None:  # what the hand feels at the handle (symkin rate): b and the larger Coulomb level
        coulomb = [friction.coulomb] + ([friction.coulomb_negative] if friction.coulomb_negative is not None else [])
        record["friction"] = {"viscous": float(friction.viscous.xreplace(values)),
                              "coulomb": max(abs(float(c.xreplace(values))) for c in coulomb)}
    return record


def build_manifest(model: Model, code: ModelCode, derived: list[str], backend_files: dict[str, list[str]]) -> dict:
    """The manifest of ``code`` derived from ``model``.

    Args:
        model: the source model.
        code: the optimized functions.
        derived: names of the graph quantities that were derived, in order.
        backend_files: files written by each backend.
    """
    import sympy

    from symkin.model import tree

    manifest: dict[str, Any] = {
        "manifest_version": MANIFEST_VERSION,
        "generator": {"symkin": __version__, "sympy": sympy.__version__},
        "model": {
            "name": model.name,
            "hash": model.hash,
            "source": Path(model.source).name,
            "description": model.description,
            "dof": model.dof,
            "coordinates": [_coordinate_record(model, c) for c in model.coordinates],
            "task_space": list(model.task_space),
        },
        "parameters": [{"name": p.name, "default": p.default, "unit": p.unit, "doc": p.doc, "fixed": p.fixed}
                       for p in code.parameters],
        "derived_quantities": list(derived),
        "options": {"float32": code.float32},
        "functions": [
            {
                "name": f.name,
                "summary": f.spec.summary,
                "inputs": [_input_record(i) for i in f.spec.inputs],
                "outputs": [{"name": o.name, "shape": list(o.shape), "unit": o.unit, "doc": o.doc,
                             **({"elements": list(o.elements)} if o.elements else {})}
                            for o in f.spec.outputs],
                **({"combines": list(f.spec.parts)} if f.spec.parts else {}),
                "op_counts": f.op_counts,
                "backends": sorted(backend_files),
            }
            for f in code.functions
        ],
        "backends": {name: {"files": sorted(files)} for name, files in sorted(backend_files.items())},
    }
    if model.source_names:  # joints and links renamed to identifiers: {model name: name in the file}
        manifest["model"]["source_names"] = model.source_names
    if model.notes:  # what the reading decided (locks clipped into limits, non-physical inertias accepted)
        manifest["model"]["notes"] = list(model.notes)
    if model.parallel is not None:
        manifest["model"]["parallel"] = _parallel_record(model)
    elif not tree.is_chain(model):  # a branched serial model: each joint's parent (-1: the base), the TCP's link
        manifest["model"]["tree"] = {"parents": list(tree.parent_indices(model)), "tip": tree.tip_index(model)}
    if model.home_configuration is not None:  # a serial device's declared rest configuration (serial.home)
        manifest["model"]["home_configuration"] = [float(v.xreplace(model.parameter_values))
                                                   for v in model.home_configuration]
    return manifest


def _parallel_record(model: Model) -> dict[str, Any]:
    """Legs, platform motion and home pose of a parallel model (home at the default parameters).

    Limits of passive joint variables, where declared, are listed per leg under
    ``passive_limits`` (numbers at the default parameters; the actuated ones are the
    coordinates' ``limits``).
    """
    parallel = model.parallel
    assert parallel is not None
    home = None
    if parallel.home is not None:
        home = [float(e.xreplace(model.parameter_values)) for e in parallel.home]
    legs = []
    for leg in parallel.legs:
        record: dict[str, Any] = {"name": leg.name, "topology": "".join(j.type.value for j in leg.joints),
                                  "joints": [j.name for j in leg.joints]}
        passive = {variable: [float(b.xreplace(model.parameter_values)) for b in limits]
                   for joint in leg.joints for k, variable in enumerate(joint.variables)
                   if k != joint.active and (limits := joint.limits_of(k)) is not None}
        if passive:
            record["passive_limits"] = passive
        legs.append(record)
    record = {"motion": parallel.motion.value, "legs": legs, "home": home}
    if parallel.wrist is not None:  # a hybrid device: the wrist's coordinates qw, as the model's q are recorded
        record["wrist"] = [_coordinate_record(model, joint, parallel.wrist.joints, parallel.wrist.actuators)
                           for joint in parallel.wrist.coordinates]
    return record


def dumps(manifest: dict) -> str:
    """Deterministic JSON text of a manifest."""
    return json.dumps(manifest, indent=2, ensure_ascii=False) + "\n"


def read_manifest(directory: str | Path) -> dict:
    """Read and sanity-check ``directory/manifest.json``.

    Raises:
        GeneratedCodeError: missing, unreadable or of an unknown version.
    """
    path = Path(directory) / MANIFEST_NAME
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise GeneratedCodeError(f"{directory} holds no {MANIFEST_NAME}: is it the output of 'symkin derive'? "
                                 "Pass the model's directory, e.g. generated/ur10e") from None
    except (OSError, json.JSONDecodeError) as exc:
        raise GeneratedCodeError(f"cannot read {path}: {exc}") from None
    if manifest.get("manifest_version") != MANIFEST_VERSION:
        raise GeneratedCodeError(f"{path}: manifest version {manifest.get('manifest_version')} is not "
                                 f"{MANIFEST_VERSION}; derive the model again with this symkin")
    return manifest
