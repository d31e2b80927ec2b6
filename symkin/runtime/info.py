"""One typed view of a loaded model, built once from its manifest (:class:`ModelInfo`).

Every consumer of a loaded model (analyses, IK, design, simulation, the CLI) reads what it
needs about the mechanism from ``model.info`` rather than indexing ``manifest.json``: the
joint coordinates with their types and limits, the task space, the parameters, the generated
functions with their parameter inputs and vector elements, and, for a parallel mechanism, its
home pose and the passive-joint limits of its legs.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Protocol

from symkin.manifest_schema import Coordinate, Function, JointStopRecord, Manifest, Parameter


@dataclass(frozen=True)
class ModelInfo:
    """What a loaded model is (see the module docstring).

    Attributes:
        name: model name.
        mechanism: ``serial`` or ``parallel`` (``hybrid`` for the view of a hybrid device as a whole,
            :class:`symkin.mechanism.device.WholeDevice`).
        coordinates: the joint coordinates, in the order of ``q``.
        task_space: the task-space components (rows of ``jacobian``), e.g. ``("x", "y")``.
        parameters: every parameter, fixed or free.
        functions: the generated functions, by name.
        home: a parallel mechanism's declared home pose (task coordinates), else None.
        passive_limits: per leg of a parallel mechanism, {passive variable: [lower, upper]} as recorded
            (validated where they are used, :func:`symkin.mechanism.passive.declared_limits`, with the
            manifest's place in the message).
        wrist: a hybrid device's wrist coordinates, in the order of the functions' ``qw``; () otherwise.
        home_configuration: a serial device's declared rest configuration (``serial.home``), else None.
        model_hash: the hash of the model's source (what a derivation was made from).
        description: the model file's description ("" without one).
        backend_files: the files each backend emitted, by backend (its keys: the emitted backends).
        tree: a branched serial model's links, each with its parent (the viewer draws them), else None.
        home_assembly: a parallel model's declared start of its home assembly, {leg joint variable: value}
            (``parallel.home_assembly``), else None.
        joint_stops: stops on combinations of the coordinates (``joint_stops:``), beside their own limits.
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
    home_assembly: dict[str, float] | None = None
    joint_stops: tuple[JointStopRecord, ...] = ()

    @property
    def is_parallel(self) -> bool:
        return self.mechanism == "parallel"

    @property
    def coordinate_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.coordinates)

    @property
    def device_coordinates(self) -> tuple[Coordinate, ...]:
        """The joints a run of the device records: the coordinates, then a hybrid device's wrist joints."""
        return self.coordinates + self.wrist


    @property
    def units(self) -> dict[str, str]:
        """{parameter name: unit}."""
        return {p.name: p.unit for p in self.parameters}

    def with_task_space(self, task_space: tuple[str, ...]) -> ModelInfo:
        """The same model seen through other task coordinates (e.g. a platform held at a constant orientation)."""
        return dataclasses.replace(self, task_space=tuple(task_space))

    @classmethod
    def from_manifest(cls, manifest: dict[str, Any]) -> ModelInfo:
        """The view of a manifest's JSON object (:class:`symkin.manifest_schema.Manifest`)."""
        record = Manifest.from_record(manifest)
        model, parallel = record.model, record.model.parallel
        return cls(model.name, "parallel" if parallel else "serial", model.coordinates, model.task_space,
                   record.parameters, {f.name: f for f in record.functions},
                   None if parallel is None else parallel.home,
                   () if parallel is None else tuple(leg.passive_limits for leg in parallel.legs),
                   () if parallel is None else parallel.wrist, model.home_configuration, model.hash,
                   model.description, dict(record.backends), model.tree,
                   None if parallel is None else parallel.home_assembly, model.joint_stops)


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
