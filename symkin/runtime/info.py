"""One typed view of a loaded model, built once from its manifest (:class:`ModelInfo`).

Every consumer of a loaded model (analyses, IK, design, simulation, the CLI) reads what it
needs about the mechanism from ``model.info`` rather than indexing ``manifest.json``: the
joint coordinates with their types and limits, the task space, the parameters, the generated
functions with their parameter inputs and vector elements, and, for a parallel mechanism, its
home pose and the passive-joint limits of its legs.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Protocol


@dataclass(frozen=True)
class Coordinate:
    """A joint coordinate (an element of ``q``).

    Attributes:
        name: its name in the model file.
        revolute: an angle (periodic) rather than a length.
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
    revolute: bool
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
    def bounds(self) -> tuple[float, float]:
        """(lower, upper) position limits, (-inf, inf) where none are declared."""
        return self.limits if self.limits is not None else (-math.inf, math.inf)

    @property
    def label(self) -> str:
        """The name to show people: the robot file's, else the model's."""
        return self.source_name or self.name


@dataclass(frozen=True)
class Parameter:
    """A model parameter: ``fixed`` ones are folded into the code, the others are function arguments."""

    name: str
    default: float
    unit: str
    fixed: bool


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


@dataclass(frozen=True)
class Output:
    """An output of a generated function: its shape, unit and doc, and its elements' names where the manifest
    gives them (the regressors' parameters)."""

    name: str
    shape: tuple[int, ...]
    unit: str
    doc: str
    elements: tuple[str, ...] = ()


@dataclass(frozen=True)
class Function:
    """A generated function as the manifest records it: its name and one-line summary, its inputs in argument
    order and its outputs in result order (the backends' loaders bind it from this record)."""

    name: str
    summary: str
    inputs: tuple[Input, ...]
    results: tuple[Output, ...]

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

    @classmethod
    def from_record(cls, record: dict[str, Any]) -> Function:
        """The function of a manifest record (:func:`symkin.manifest.build_manifest` writes them)."""
        inputs = tuple(Input(i["name"], i["kind"], tuple(int(d) for d in i["shape"]), tuple(i["elements"]),
                             tuple(i["units"]), i.get("doc") or "",
                             float(i["default"]) if i["kind"] == "parameter" else math.nan)
                       for i in record["inputs"])
        results = tuple(Output(o["name"], tuple(int(d) for d in o["shape"]), o.get("unit") or "", o.get("doc") or "",
                               tuple(o.get("elements", ()))) for o in record["outputs"])
        return cls(record["name"], record.get("summary") or "", inputs, results)


@dataclass(frozen=True)
class ModelInfo:
    """What a loaded model is (see the module docstring).

    Attributes:
        name: model name.
        mechanism: ``serial`` or ``parallel`` (``hybrid`` for the view of a hybrid device as a whole,
            :class:`symkin.analysis.device.WholeDevice`).
        coordinates: the joint coordinates, in the order of ``q``.
        task_space: the task-space components (rows of ``jacobian``), e.g. ``("x", "y")``.
        parameters: every parameter, fixed or free.
        functions: the generated functions, by name.
        home: a parallel mechanism's declared home pose (task coordinates), else None.
        passive_limits: per leg of a parallel mechanism, {passive variable: [lower, upper]} as recorded
            (validated where they are used, :func:`symkin.analysis.passive.declared_limits`, with the
            manifest's place in the message).
        wrist: a hybrid device's wrist coordinates, in the order of the functions' ``qw``; () otherwise.
        home_configuration: a serial device's declared rest configuration (``serial.home``), else None.
        model_hash: the hash of the model's source (what a derivation was made from).
        description: the model file's description ("" without one).
        backend_files: the files each backend emitted, by backend (its keys: the emitted backends).
        tree: a branched serial model's links, each with its parent (the viewer draws them), else None.
    """

    name: str
    mechanism: str
    coordinates: tuple[Coordinate, ...]
    task_space: tuple[str, ...]
    parameters: tuple[Parameter, ...]
    functions: dict[str, Function]
    home: tuple[float, ...] | None = None
    passive_limits: tuple[dict[str, Any], ...] = ()
    wrist: tuple[Coordinate, ...] = ()
    home_configuration: tuple[float, ...] | None = None
    model_hash: str = ""
    description: str = ""
    backend_files: dict[str, tuple[str, ...]] = dataclasses.field(default_factory=dict)
    tree: Any = None

    @property
    def is_parallel(self) -> bool:
        return self.mechanism == "parallel"

    @property
    def coordinate_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.coordinates)


    @property
    def units(self) -> dict[str, str]:
        """{parameter name: unit}."""
        return {p.name: p.unit for p in self.parameters}

    def with_task_space(self, task_space: tuple[str, ...]) -> ModelInfo:
        """The same model seen through other task coordinates (e.g. a platform held at a constant orientation)."""
        return dataclasses.replace(self, task_space=tuple(task_space))

    @classmethod
    def from_manifest(cls, manifest: dict[str, Any]) -> ModelInfo:
        model = manifest["model"]
        parallel = model.get("parallel")
        coordinates = tuple(_coordinate(c) for c in model["coordinates"])
        parameters = tuple(Parameter(p["name"], float(p["default"]), p.get("unit", ""), bool(p["fixed"]))
                           for p in manifest["parameters"])
        functions = {f["name"]: Function.from_record(f) for f in manifest["functions"]}
        home = tuple(float(v) for v in parallel["home"]) if parallel and parallel.get("home") is not None else None
        passive = tuple(dict(leg.get("passive_limits") or {}) for leg in parallel["legs"]) if parallel else ()
        wrist = tuple(_coordinate(c) for c in parallel.get("wrist", ())) if parallel else ()
        rest = tuple(float(v) for v in model["home_configuration"]) if "home_configuration" in model else None
        backends = {name: tuple(record["files"]) for name, record in manifest.get("backends", {}).items()}
        return cls(model["name"], "parallel" if parallel else "serial", coordinates, tuple(model["task_space"]),
                   parameters, functions, home, passive, wrist, rest, model.get("hash", ""),
                   model.get("description") or "", backends, model.get("tree"))


def _coordinate(record: dict[str, Any]) -> Coordinate:
    """A coordinate of the manifest (the model's ``coordinates``, a hybrid device's ``wrist``)."""
    return Coordinate(record["name"], record["type"] == "R",
                      (float(record["limits"][0]), float(record["limits"][1])) if record.get("limits") else None,
                      record.get("velocity_limit"), record.get("effort_limit"), record.get("source_name"),
                      bool(record.get("active", True)), record.get("continuous_effort_limit"),
                      record.get("friction", {}).get("viscous"), record.get("friction", {}).get("coulomb"),
                      record.get("gear_ratio"))


class GeneratedModel(Protocol):
    """What the analyses, IK, design and simulation take: a :class:`symkin.runtime.loader.LoadedModel`
    or a view of one (a platform held at a constant orientation, a bound design).

    The generated functions (``fk``, ``jacobian``, ``ik``...) are attributes named as in ``functions``.
    """

    name: str
    info: ModelInfo
    functions: tuple[str, ...]
    parameters: dict[str, float]

    @property
    def joint_limits(self) -> tuple[tuple[float, float], ...]: ...

    def bind(self, **parameters: float) -> GeneratedModel: ...

    def __getattr__(self, name: str) -> Any: ...
