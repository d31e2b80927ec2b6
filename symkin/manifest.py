"""The manifest of a generated model directory (``OUT/<model>/manifest.json``).

The manifest is the contract between ``symkin derive`` and everything that uses its
output (``symkin.load``, analyses, users' build systems).  It records the model identity,
the generator versions, every function with its inputs, outputs, op counts and the
backends that emitted it, and the files of each backend.  It holds no timestamps or
timings, so the same model always gives the same bytes.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import TYPE_CHECKING

from symkin._version import __version__
from symkin.errors import GeneratedCodeError
from symkin.manifest_schema import (MANIFEST_NAME, MANIFEST_VERSION, Coordinate, Function, Input, JointStopRecord,
                                    LegRecord, Manifest, ModelRecord, Output, ParallelRecord, Parameter)

if TYPE_CHECKING:  # reading a manifest must not import sympy
    from symkin.ir.bundle import ModelCode
    from symkin.model.schema import Model



def _input(i) -> Input:
    """The record of an input spec."""
    return Input(i.name, i.kind, tuple(i.shape), tuple(i.element_names), tuple(i.units), i.doc,
                 math.nan if i.default is None else float(i.default))


def _coordinate(model: Model, coordinate, joints: tuple | None = None, actuators: tuple | None = None
                ) -> Coordinate:
    """Name and type of a joint coordinate, whether it is passive, and its position, velocity and effort
    limits where the model declares them.

    Limits are numbers: their expressions evaluated at the parameters' default values (the
    analyses in :mod:`symkin.analysis` and the simulation read them without sympy).
    """
    values = model.parameter_values
    from symkin.model.body_build import drive_of  # sympy: only when a manifest is built

    drive = drive_of(coordinate.name, model.joints if joints is None else joints,
                     model.actuators if actuators is None else actuators)
    # an actuated leg joint of a parallel mechanism: the legs' rotor (parallel.rotor), the same for every leg
    rotor = model.parallel.bodies if joints is None and model.parallel is not None else None
    friction = next((f for f in model.friction if f.joint == coordinate.name), None)
    coulomb = None if friction is None else [friction.coulomb] + (
        [friction.coulomb_negative] if friction.coulomb_negative is not None else [])

    def number(bound) -> float | None:
        return None if bound is None else float(bound.xreplace(values))

    source_name = model.source_name("joints", coordinate.name)
    return Coordinate(
        coordinate.name, coordinate.type.value,
        None if coordinate.limits is None else (float(coordinate.limits[0].xreplace(values)),
                                                float(coordinate.limits[1].xreplace(values))),
        number(getattr(coordinate, "velocity_limit", None)), number(getattr(coordinate, "effort_limit", None)),
        source_name if source_name != coordinate.name else None,  # a URDF's joint_0.0, as named there
        getattr(coordinate, "active", True),  # False: a passive joint (active: false), no actuator drives it
        # s N K_t I_cont: what the motor holds for long
        None if drive is None or drive[0].continuous_effort is None else number(drive[1] * drive[0].continuous_effort),
        # what the hand feels at the handle (symkin rate): b and the larger Coulomb level
        None if friction is None else number(friction.viscous),
        None if coulomb is None else max(abs(float(c.xreplace(values))) for c in coulomb),
        # motor turns per turn of the coordinate, s N (an encoder on the motor: symkin rate)
        number(drive[1] * drive[0].gear_ratio) if drive is not None else
        number(rotor.gear_ratio) if rotor is not None else None,
    )


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

    values = model.parameter_values
    record = ModelRecord(
        model.name, model.hash, Path(model.source).name, model.description, model.dof,
        tuple(_coordinate(model, c) for c in model.coordinates), tuple(model.task_space),
        dict(model.source_names or {}), tuple(model.notes),
        parallel_record(model) if model.parallel is not None else None,
        # a branched serial model: each joint's parent (-1: the base), the TCP's link
        {"parents": list(tree.parent_indices(model)), "tip": tree.tip_index(model)}
        if model.parallel is None and not tree.is_chain(model) else None,
        None if model.home_configuration is None else tuple(float(v.xreplace(values))
                                                             for v in model.home_configuration),
        tuple(JointStopRecord(stop.expression, {name: float(a.xreplace(values)) for name, a in stop.terms},
                              float(stop.offset.xreplace(values)),
                              (float(stop.lower.xreplace(values)), float(stop.upper.xreplace(values))))
              for stop in model.joint_stops))
    functions = tuple(
        Function(f.name, f.spec.summary, tuple(_input(i) for i in f.spec.inputs),
                 tuple(Output(o.name, tuple(o.shape), o.unit, o.doc, tuple(o.elements or ())) for o in f.spec.outputs),
                 tuple(f.spec.parts or ()), f.op_counts, tuple(sorted(backend_files)))
        for f in code.functions)
    return Manifest(
        {"symkin": __version__, "sympy": sympy.__version__}, record,
        tuple(Parameter(p.name, p.default, p.unit, p.fixed, p.doc) for p in code.parameters), tuple(derived),
        {"float32": code.float32}, functions,
        {name: tuple(sorted(files)) for name, files in sorted(backend_files.items())}).to_record()


def parallel_record(model: Model) -> ParallelRecord:
    """Legs, platform motion and home pose of a parallel model (home at the default parameters).

    Limits of passive joint variables, where declared, are listed per leg under
    ``passive_limits`` (numbers at the default parameters; the actuated ones are the
    coordinates' ``limits``).
    """
    parallel = model.parallel
    assert parallel is not None
    home = None
    if parallel.home is not None:
        home = tuple(float(e.xreplace(model.parameter_values)) for e in parallel.home)
    legs = []
    for leg in parallel.legs:
        passive = {variable: [float(b.xreplace(model.parameter_values)) for b in limits]
                   for joint in leg.joints for k, variable in enumerate(joint.variables)
                   if k != joint.active and (limits := joint.limits_of(k)) is not None}
        legs.append(LegRecord(leg.name, "".join(j.type.value for j in leg.joints), tuple(j.name for j in leg.joints),
                        passive))
    # a hybrid device: the wrist's coordinates qw, as the model's q are recorded
    wrist = () if parallel.wrist is None else tuple(_coordinate(model, joint, parallel.wrist.joints,
                                                                parallel.wrist.actuators)
                                                    for joint in parallel.wrist.coordinates)
    assembly = (None if parallel.home_assembly is None else
                {name: float(value.xreplace(model.parameter_values)) for name, value in parallel.home_assembly})
    return ParallelRecord(parallel.motion.value, tuple(legs), home, wrist, assembly)


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
