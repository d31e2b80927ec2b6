"""The manifest's records as types (issue 35: one schema): what ``symkin derive`` writes into ``manifest.json``
(:func:`symkin.manifest.build_manifest` builds these and serializes them with ``to_record``) is what every reader
parses (``from_record``, :class:`symkin.runtime.info.ModelInfo`).  A record's keys appear here only; a key is left
out where the model declares nothing (no limits, no friction), as the records have always been written, so
``from_record(r).to_record() == r`` for every manifest (tests/backends/test_manifest_schema.py).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

#: The manifest's file name in a generated model's directory.
MANIFEST_NAME = "manifest.json"
#: The schema's version: a reader refuses any other with a message to derive again.
MANIFEST_VERSION = 1


@dataclass(frozen=True)
class Coordinate:
    """A joint coordinate (an element of ``q``).

    Attributes:
        name: its name in the model file.
        type: its joint's type letter (``R`` revolute, ``P`` prismatic).
        limits: (lower, upper) at the parameters' default values, or None where the model declares none.
        velocity_limit: the largest |qd| the joint allows (rad/s or m/s), or None.
        effort_limit: the largest |tau| its actuator gives (N m or N), or None.
        source_name: its name in the robot file it came from where that is no identifier (a URDF's
            ``joint_0.0``), else None; see :attr:`label`.
        active: driven by an actuator; False for a passive joint (``active: false``, e.g. the measured but
            unmotorized wrist of a haptic device), on which a controller exerts no effort.
        continuous_effort_limit: the effort its drive holds for long (N K_t I_cont), or None.
        viscous, coulomb: its friction, tau_f = viscous qd + coulomb sign(qd) (the larger Coulomb level of
            an asymmetric one), or None where the model declares none.
        gear_ratio: turns of its drive's motor per turn of the coordinate (the model's ``actuators``), or
            None without a declared drive.
    """

    name: str
    type: str
    limits: tuple[float, float] | None
    velocity_limit: float | None = None
    effort_limit: float | None = None
    source_name: str | None = None
    active: bool = True
    continuous_effort_limit: float | None = None
    viscous: float | None = None
    coulomb: float | None = None
    gear_ratio: float | None = None

    @property
    def revolute(self) -> bool:
        """An angle (periodic) rather than a length."""
        return self.type == "R"

    @property
    def bounds(self) -> tuple[float, float]:
        """(lower, upper) position limits, (-inf, inf) where none are declared."""
        return self.limits if self.limits is not None else (-math.inf, math.inf)

    @property
    def label(self) -> str:
        """The name to show people: the robot file's, else the model's."""
        return self.source_name or self.name

    def to_record(self) -> dict[str, Any]:
        """The manifest's record (a key only where the model declares it; an active joint's ``active`` left out)."""
        record: dict[str, Any] = {"name": self.name, "type": self.type}
        if not self.active:
            record["active"] = False
        optional = (("source_name", self.source_name),
                    ("limits", None if self.limits is None else list(self.limits)),
                    ("velocity_limit", self.velocity_limit), ("effort_limit", self.effort_limit),
                    ("gear_ratio", self.gear_ratio), ("continuous_effort_limit", self.continuous_effort_limit))
        record.update({key: value for key, value in optional if value is not None})
        if self.viscous is not None:
            record["friction"] = {"viscous": self.viscous, "coulomb": self.coulomb}
        return record

    @classmethod
    def from_record(cls, record: dict[str, Any]) -> Coordinate:
        limits = record.get("limits")
        friction = record.get("friction", {})
        return cls(record["name"], record["type"], None if not limits else (float(limits[0]), float(limits[1])),
                   record.get("velocity_limit"), record.get("effort_limit"), record.get("source_name"),
                   bool(record.get("active", True)), record.get("continuous_effort_limit"), friction.get("viscous"),
                   friction.get("coulomb"), record.get("gear_ratio"))


@dataclass(frozen=True)
class Parameter:
    """A model parameter: ``fixed`` ones are folded into the code, the others are function arguments."""

    name: str
    default: float
    unit: str
    fixed: bool
    doc: str = ""

    def to_record(self) -> dict[str, Any]:
        return {"name": self.name, "default": self.default, "unit": self.unit, "doc": self.doc, "fixed": self.fixed}

    @classmethod
    def from_record(cls, record: dict[str, Any]) -> Parameter:
        return cls(record["name"], float(record["default"]), record.get("unit", ""), bool(record["fixed"]),
                   record.get("doc") or "")


@dataclass(frozen=True)
class VectorInput:
    """A vector input of a generated function (``q``, ``qd``, ``p``, ``s``...): its elements and their units."""

    elements: tuple[str, ...]
    units: tuple[str, ...]


@dataclass(frozen=True)
class Input:
    """An input of a generated function, in argument order: a vector (``kind`` "vector", ``shape`` (n,), its
    elements and their units; ``default`` NaN) or a parameter (``kind`` "parameter", shape (), its unit and
    ``default``)."""

    name: str
    kind: str
    shape: tuple[int, ...]
    elements: tuple[str, ...]
    units: tuple[str, ...]
    doc: str
    default: float = math.nan

    @property
    def is_parameter(self) -> bool:
        return self.kind == "parameter"

    @property
    def size(self) -> int:
        """The vector's length (1 for a parameter)."""
        return self.shape[0] if self.shape else 1

    def to_record(self) -> dict[str, Any]:
        record: dict[str, Any] = {"name": self.name, "kind": self.kind, "shape": list(self.shape),
                                  "elements": list(self.elements), "units": list(self.units), "doc": self.doc}
        if not math.isnan(self.default):
            record["default"] = self.default
        return record

    @classmethod
    def from_record(cls, record: dict[str, Any]) -> Input:
        return cls(record["name"], record["kind"], tuple(int(d) for d in record["shape"]), tuple(record["elements"]),
                   tuple(record["units"]), record.get("doc") or "",
                   float(record["default"]) if record["kind"] == "parameter" else math.nan)


@dataclass(frozen=True)
class Output:
    """An output of a generated function: its shape, unit and doc, and its elements' names where the manifest
    gives them (the regressors' parameters)."""

    name: str
    shape: tuple[int, ...]
    unit: str
    doc: str
    elements: tuple[str, ...] = ()

    def to_record(self) -> dict[str, Any]:
        record: dict[str, Any] = {"name": self.name, "shape": list(self.shape), "unit": self.unit, "doc": self.doc}
        if self.elements:
            record["elements"] = list(self.elements)
        return record

    @classmethod
    def from_record(cls, record: dict[str, Any]) -> Output:
        return cls(record["name"], tuple(int(d) for d in record["shape"]), record.get("unit") or "",
                   record.get("doc") or "", tuple(record.get("elements", ())))


@dataclass(frozen=True)
class Function:
    """A generated function as the manifest records it: its name and one-line summary, its inputs in argument
    order and its outputs in result order (the backends' loaders bind it from this record)."""

    name: str
    summary: str
    inputs: tuple[Input, ...]
    results: tuple[Output, ...]
    combines: tuple[str, ...] = ()
    op_counts: dict[str, int] = dataclasses.field(default_factory=dict)
    backends: tuple[str, ...] = ()

    @property
    def vectors(self) -> dict[str, VectorInput]:
        """The vector inputs by name."""
        return {i.name: VectorInput(i.elements, i.units) for i in self.inputs if not i.is_parameter}

    @property
    def vector_inputs(self) -> tuple[Input, ...]:
        return tuple(i for i in self.inputs if not i.is_parameter)

    @property
    def parameter_inputs(self) -> tuple[Input, ...]:
        return tuple(i for i in self.inputs if i.is_parameter)

    @property
    def parameters(self) -> tuple[str, ...]:
        """The parameter inputs' names."""
        return tuple(i.name for i in self.parameter_inputs)

    @property
    def outputs(self) -> dict[str, tuple[str, ...]]:
        """The outputs' element names by output (empty where the manifest names none)."""
        return {o.name: o.elements for o in self.results}

    def to_record(self) -> dict[str, Any]:
        record: dict[str, Any] = {"name": self.name, "summary": self.summary,
                                  "inputs": [i.to_record() for i in self.inputs],
                                  "outputs": [o.to_record() for o in self.results]}
        if self.combines:
            record["combines"] = list(self.combines)
        record.update({"op_counts": dict(self.op_counts), "backends": list(self.backends)})
        return record

    @classmethod
    def from_record(cls, record: dict[str, Any]) -> Function:
        """The function of a manifest record (:meth:`to_record` writes them)."""
        return cls(record["name"], record.get("summary") or "", tuple(Input.from_record(i) for i in record["inputs"]),
                   tuple(Output.from_record(o) for o in record["outputs"]), tuple(record.get("combines", ())),
                   dict(record.get("op_counts", {})), tuple(record.get("backends", ())))


@dataclass(frozen=True)
class LegRecord:
    """A parallel mechanism's leg: its topology (joint type letters), its joints, and the declared limits of its
    passive joint variables ({variable: [lower, upper]} at the default parameters; validated where used)."""

    name: str
    topology: str
    joints: tuple[str, ...]
    passive_limits: dict[str, Any] = dataclasses.field(default_factory=dict)

    def to_record(self) -> dict[str, Any]:
        record: dict[str, Any] = {"name": self.name, "topology": self.topology, "joints": list(self.joints)}
        if self.passive_limits:
            record["passive_limits"] = dict(self.passive_limits)
        return record

    @classmethod
    def from_record(cls, record: dict[str, Any]) -> LegRecord:
        return cls(record["name"], record["topology"], tuple(record["joints"]),
                   dict(record.get("passive_limits") or {}))


@dataclass(frozen=True)
class ParallelRecord:
    """A parallel mechanism's platform motion, legs and home pose (task coordinates at the default parameters,
    None where undeclared), a hybrid device's wrist coordinates (the functions' ``qw``) and the declared start of
    its home assembly ({leg joint variable: value at the default parameters}; written only where declared)."""

    motion: str
    legs: tuple[LegRecord, ...]
    home: tuple[float, ...] | None
    wrist: tuple[Coordinate, ...] = ()
    home_assembly: dict[str, float] | None = None

    def to_record(self) -> dict[str, Any]:
        record: dict[str, Any] = {"motion": self.motion, "legs": [leg.to_record() for leg in self.legs],
                                  "home": None if self.home is None else list(self.home)}
        if self.wrist:
            record["wrist"] = [c.to_record() for c in self.wrist]
        if self.home_assembly is not None:
            record["home_assembly"] = dict(self.home_assembly)
        return record

    @classmethod
    def from_record(cls, record: dict[str, Any]) -> ParallelRecord:
        home, assembly = record.get("home"), record.get("home_assembly")
        return cls(record["motion"], tuple(LegRecord.from_record(leg) for leg in record["legs"]),
                   None if home is None else tuple(float(v) for v in home),
                   tuple(Coordinate.from_record(c) for c in record.get("wrist", ())),
                   None if assembly is None else {str(k): float(v) for k, v in assembly.items()})


@dataclass(frozen=True)
class JointStopRecord:
    """A stop lower <= sum_k a_k q_k + b <= upper (:class:`symkin.model.schema.JointStop`) at the parameters'
    defaults: the ``expression`` as the model file writes it, {coordinate: a_k} ``coefficients``, b, (lower, upper)."""

    expression: str
    coefficients: dict[str, float]
    offset: float
    limits: tuple[float, float]

    def to_record(self) -> dict[str, Any]:
        return {"expression": self.expression, "coefficients": dict(self.coefficients), "offset": self.offset,
                "limits": list(self.limits)}

    @classmethod
    def from_record(cls, record: dict[str, Any]) -> JointStopRecord:
        lower, upper = record["limits"]
        return cls(str(record["expression"]), {str(k): float(v) for k, v in record["coefficients"].items()},
                   float(record.get("offset", 0.0)), (float(lower), float(upper)))


@dataclass(frozen=True)
class ModelRecord:
    """The model a manifest was derived from.

    Attributes:
        name, hash, source, description: the model's name, the hash of its source, its file's name and
            description.
        dof: its coordinates' count.
        coordinates: its joint coordinates, in the order of ``q``.
        task_space: the task-space components.
        source_names: joints and links renamed to identifiers, {model name: name in the robot file}.
        notes: what the reading decided (locks clipped into limits, non-physical inertias accepted).
        parallel: a parallel mechanism's record, else None.
        tree: a branched serial model's ``parents`` (-1: the base) and ``tip`` link, else None.
        home_configuration: a serial device's declared rest configuration, else None.
        joint_stops: stops on combinations of the coordinates (written only where declared).
    """

    name: str
    hash: str
    source: str
    description: str
    dof: int
    coordinates: tuple[Coordinate, ...]
    task_space: tuple[str, ...]
    source_names: dict[str, Any] = dataclasses.field(default_factory=dict)
    notes: tuple[str, ...] = ()
    parallel: ParallelRecord | None = None
    tree: dict[str, Any] | None = None
    home_configuration: tuple[float, ...] | None = None
    joint_stops: tuple[JointStopRecord, ...] = ()

    def to_record(self) -> dict[str, Any]:
        record: dict[str, Any] = {"name": self.name, "hash": self.hash, "source": self.source,
                                  "description": self.description, "dof": self.dof,
                                  "coordinates": [c.to_record() for c in self.coordinates],
                                  "task_space": list(self.task_space)}
        if self.source_names:
            record["source_names"] = dict(self.source_names)
        if self.notes:
            record["notes"] = list(self.notes)
        if self.parallel is not None:
            record["parallel"] = self.parallel.to_record()
        if self.tree is not None:
            record["tree"] = dict(self.tree)
        if self.home_configuration is not None:
            record["home_configuration"] = list(self.home_configuration)
        if self.joint_stops:
            record["joint_stops"] = [stop.to_record() for stop in self.joint_stops]
        return record

    @classmethod
    def from_record(cls, record: dict[str, Any]) -> ModelRecord:
        parallel, rest = record.get("parallel"), record.get("home_configuration")
        return cls(record["name"], record.get("hash", ""), record.get("source", ""), record.get("description") or "",
                   int(record.get("dof", len(record["coordinates"]))),
                   tuple(Coordinate.from_record(c) for c in record["coordinates"]), tuple(record["task_space"]),
                   dict(record.get("source_names") or {}), tuple(record.get("notes", ())),
                   None if parallel is None else ParallelRecord.from_record(parallel), record.get("tree"),
                   None if rest is None else tuple(float(v) for v in rest),
                   tuple(JointStopRecord.from_record(stop) for stop in record.get("joint_stops", ())))


@dataclass(frozen=True)
class Manifest:
    """A generated model's ``manifest.json``: the generator's versions, the model, its parameters, the graph
    quantities derived (in order), the options, every generated function and each backend's files."""

    generator: dict[str, str]
    model: ModelRecord
    parameters: tuple[Parameter, ...]
    derived_quantities: tuple[str, ...]
    options: dict[str, Any]
    functions: tuple[Function, ...]
    backends: dict[str, tuple[str, ...]]

    def to_record(self) -> dict[str, Any]:
        return {"manifest_version": MANIFEST_VERSION, "generator": dict(self.generator),
                "model": self.model.to_record(), "parameters": [p.to_record() for p in self.parameters],
                "derived_quantities": list(self.derived_quantities), "options": dict(self.options),
                "functions": [f.to_record() for f in self.functions],
                "backends": {name: {"files": list(files)} for name, files in self.backends.items()}}

    @classmethod
    def from_record(cls, record: dict[str, Any]) -> Manifest:
        """The manifest of its JSON object (its version checked by :func:`symkin.manifest.read_manifest`)."""
        return cls(dict(record.get("generator", {})), ModelRecord.from_record(record["model"]),
                   tuple(Parameter.from_record(p) for p in record["parameters"]),
                   tuple(record.get("derived_quantities", ())), dict(record.get("options", {})),
                   tuple(Function.from_record(f) for f in record["functions"]),
                   {name: tuple(entry["files"]) for name, entry in record.get("backends", {}).items()})
