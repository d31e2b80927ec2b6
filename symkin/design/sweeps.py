"""Design sweeps: the metrics of thousands of designs, evaluated in chunks on Dask (issue 15).

The one-call entry point is :func:`symkin.design.sweep` (:mod:`symkin.design.sweep_run`).

The seed's dimensioning step (sec. 5) searches the link lengths for the best workspace and
GCI; before a local optimum (:mod:`symkin.design.solving`) a designer wants the map: every
design of a grid or a Sobol set with its GCI (eq. 8.28), workspace measure and extreme
condition numbers.  One derivation serves every design: the parameters are inputs of the
generated functions, so a design is ``model.bind(**values)``.

* :class:`SweepDefinition` - the varied parameters, the design set (a grid, row-major in the
  order the parameters are given, or the first N points of an unscrambled Sobol sequence),
  the metrics, the integration budget and seed, the chunk size.  Design i always has the
  same values, and chunk k holds designs k c ... (k + 1) c - 1.
* :func:`~symkin.design.sweep_metrics.evaluate_design` - the metrics of one design (GCI,
  workspace measure, extreme kappas, peak actuator effort per unit force); a design that
  fails is a row with a status, never an exception.
* :func:`evaluate_chunk` - one chunk, on a worker: the generated code travels as a
  :class:`~symkin.runtime.payload.ModelPayload` (the manifest and the numpy module, a few tens of kB), so a worker on
  another machine needs no shared file system.
* :func:`evaluate_missing` - every chunk not yet in the store (:mod:`symkin.design.sweep_store`), in
  this process (``scheduler="serial"``), on a ``LocalCluster`` (``"local"``, the default
  elsewhere), on a running scheduler (``"tcp://host:8786"``) or on a given
  ``dask.distributed.Client`` (:func:`symkin.runtime.cluster.run_tasks`).  Dask reruns the
  tasks of a worker that dies; each completed chunk is written at once, so an interrupted
  sweep resumes where it stopped.  Each design's
  metrics depend only on its values and the definition, so a sweep gives the same rows, to
  the bit, however it was scheduled, split or resumed.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from symkin.numerics.sobol import Sobol
from symkin.design.sweep_metrics import DEFAULT_METRICS, EMPTY, ESTIMATED, METRICS, OK, evaluate_design
from symkin.runtime.cluster import run_tasks
from symkin.runtime.payload import ModelPayload


@dataclass(frozen=True)
class SweepAxis:
    """A varied parameter: its range and, for a grid, the number of values (ends included)."""

    name: str
    low: float
    high: float
    count: int | None = None

    @property
    def grid_count(self) -> int:
        """The number of grid values (a Sobol axis has none: ValueError)."""
        if self.count is None:
            raise ValueError(f"{self.name}: a grid needs a count, e.g. {self.name}={self.low:g}:{self.high:g}:20")
        return self.count

    def values(self) -> np.ndarray:
        return np.linspace(self.low, self.high, self.grid_count)


@dataclass(frozen=True)
class SweepDefinition:
    """What a sweep evaluates (see the module docstring).

    Attributes:
        axes: the varied parameters.
        metrics: names from :data:`METRICS`.
        sobol: the number of Sobol designs (None: the grid of the axes' counts).
        samples: integrand evaluations per design (quasi-Monte Carlo budget).
        seed: seed of the integrator's scrambling (the same for every design).
        chunk: designs per task.
        fixed: parameter values every design shares (``--set``).
        length: the characteristic length L (m) that homogenizes the Jacobian of a task space mixing translations
            and rotations (:func:`symkin.numerics.conditioning.homogenize`), or ``"auto"``: each design's own
            (:func:`symkin.mechanism.reach.characteristic_length_of`, minimizing the mean kappa_F^2 over its joint
            limits, as ``symkin gci`` takes it); ignored for a task space of one kind.
    """

    axes: tuple[SweepAxis, ...]
    metrics: tuple[str, ...] = DEFAULT_METRICS
    sobol: int | None = None
    samples: int = 4096
    seed: int = 0
    chunk: int = 64
    fixed: tuple[tuple[str, float], ...] = field(default=())
    length: float | str = "auto"

    def __post_init__(self) -> None:
        if self.length != "auto" and not (isinstance(self.length, (int, float)) and math.isfinite(self.length)
                                          and self.length > 0):
            raise ValueError(f"the characteristic length must be a positive length in m or 'auto', got {self.length!r}")
        names = [a.name for a in self.axes]
        if not names:
            raise ValueError("a sweep varies at least one parameter (--vary NAME=LOW:HIGH:COUNT)")
        if len(set(names)) != len(names):
            raise ValueError(f"a parameter is varied twice: {', '.join(names)}")
        unknown = [m for m in self.metrics if m not in METRICS]
        if unknown or not self.metrics:
            raise ValueError(f"unknown metrics {unknown}; choose from {', '.join(METRICS)}")
        for axis in self.axes:
            if not (math.isfinite(axis.low) and math.isfinite(axis.high) and axis.low <= axis.high):
                raise ValueError(f"{axis.name}: the range {axis.low:g}:{axis.high:g} must be finite, low <= high")
            if self.sobol is None and (axis.count is None or axis.count < 1):
                raise ValueError(f"{axis.name}: a grid needs a count, e.g. {axis.name}={axis.low:g}:{axis.high:g}:20")
            if self.sobol is not None and axis.count is not None:
                raise ValueError(f"{axis.name}: with --sobol give the range only, {axis.name}={axis.low:g}:"
                                 f"{axis.high:g}")
        if self.sobol is not None and self.sobol < 1:
            raise ValueError(f"--sobol: the number of designs must be positive, got {self.sobol}")
        if self.samples < 16 or self.chunk < 1:
            raise ValueError("the integration budget must be at least 16 samples and a chunk at least one design")

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.axes)

    @property
    def size(self) -> int:
        return self.sobol if self.sobol is not None else math.prod(a.grid_count for a in self.axes)

    @property
    def chunks(self) -> int:
        return -(-self.size // self.chunk)

    def designs(self, chunk: int | None = None) -> np.ndarray:
        """(N, p) parameter values of every design, or of one chunk's designs."""
        start, stop = (0, self.size) if chunk is None else (chunk * self.chunk, min(self.size, (chunk + 1) * self.chunk))
        if self.sobol is not None:
            low, high = np.array([a.low for a in self.axes]), np.array([a.high for a in self.axes])
            return low + (high - low) * Sobol(len(self.axes)).points(start, stop)
        index = np.unravel_index(np.arange(start, stop), tuple(a.grid_count for a in self.axes))
        return np.stack([a.values()[i] for a, i in zip(self.axes, index)], axis=-1)

    def columns(self) -> list[str]:
        """The columns of a result row, in order."""
        metrics = [c for m in self.metrics for c in ((m, f"{m}_error") if m in ESTIMATED else (m,))]
        return ["design", *self.names, *metrics, "status"]

    def to_json(self) -> str:
        """Canonical JSON (sorted keys): stored with the results, compared on --resume."""
        return json.dumps(asdict(self), sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> SweepDefinition:
        data = json.loads(text)
        data["axes"] = tuple(SweepAxis(**a) for a in data["axes"])
        data["metrics"] = tuple(data["metrics"])
        data["fixed"] = tuple((name, value) for name, value in data["fixed"])
        return cls(**data)


def parse_axis(text: str, with_count: bool) -> SweepAxis:
    """``NAME=LOW:HIGH:COUNT`` (a grid axis) or ``NAME=LOW:HIGH`` (a Sobol range)."""
    name, _, spec = text.partition("=")
    parts = spec.split(":")
    expected = "NAME=LOW:HIGH:COUNT" if with_count else "NAME=LOW:HIGH (with --sobol)"
    if not name.strip() or len(parts) != (3 if with_count else 2):
        raise ValueError(f"--vary '{text}': expected {expected}")
    try:
        low, high = float(parts[0]), float(parts[1])
        count = int(parts[2]) if with_count else None
    except ValueError:
        raise ValueError(f"--vary '{text}': expected {expected} with numbers") from None
    return SweepAxis(name.strip(), low, high, count)


def evaluate_chunk(payload: ModelPayload, definition: SweepDefinition, chunk: int) -> dict[str, list]:
    """Columns (see :meth:`SweepDefinition.columns`) of the designs of one chunk."""
    model = payload.load()
    columns: dict[str, list] = {c: [] for c in definition.columns()}
    first = chunk * definition.chunk
    for offset, point in enumerate(definition.designs(chunk)):
        values = {name: float(v) for name, v in zip(definition.names, point)}
        row = {"design": first + offset, **values, **evaluate_design(model, values, definition)}
        for name in columns:
            columns[name].append(row[name])
    return columns


def evaluate_missing(payload: ModelPayload, definition: SweepDefinition, store: Any, *, scheduler: str = "local",
          workers: int | None = None, client: Any = None,
          progress: Callable[[int, int], None] = lambda done, total: None,
          chunk_done: Callable[[int], None] = lambda chunk: None) -> None:
    """Evaluate every chunk missing from ``store``, writing each to it as it completes (the table:
    ``store.table()``, or ``store.finish()`` for the result file).

    Args:
        payload: the generated code (:meth:`ModelPayload.from_directory`).
        definition: the sweep.
        store: a :class:`~symkin.design.sweep_store.SweepStore` (parts written per chunk).
        scheduler: ``serial`` (this process), ``local`` (a ``LocalCluster`` of ``workers``
            processes, default one per core) or a scheduler address ``tcp://host:port``.
        client: a ``dask.distributed.Client`` to use instead (``scheduler`` is then ignored).
        progress: called with (designs done, designs in all) after each chunk.
        chunk_done: called with the index of each chunk written (tests interrupt a sweep here).
    """
    todo = [k for k in range(definition.chunks) if k not in store.completed()]
    done = definition.size - chunk_designs(definition, todo)

    def finished(chunk: int, columns: dict[str, list]) -> None:
        nonlocal done
        store.write_chunk(chunk, columns)
        done += len(columns["design"])
        progress(done, definition.size)
        chunk_done(chunk)

    run_tasks(evaluate_chunk, [(definition, chunk) for chunk in todo], shared=payload, scheduler=scheduler,
              workers=workers, client=client, name=f"symkin-sweep-{payload.digest[:12]}",
              started=lambda: progress(done, definition.size), finished=lambda i, columns: finished(todo[i], columns))


def summary_rows(table: Any, definition: SweepDefinition) -> list[list[str]]:
    """Rows (status, count) and the best designs by each metric, for the closing summary."""
    data = table.to_pydict()
    statuses: dict[str, int] = {}
    for status in data["status"]:
        key = status if status in (OK, EMPTY) else "failed"
        statuses[key] = statuses.get(key, 0) + 1
    rows = [[f"designs {status}", str(count), ""] for status, count in sorted(statuses.items())]
    ok = [i for i, s in enumerate(data["status"]) if s == OK]
    for metric, best in (("gci", max), ("volume", max), ("kappa_max", min)):
        if metric in definition.metrics and ok:
            i = best(ok, key=lambda k: data[metric][k])
            values = ", ".join(f"{n} = {data[n][i]:.4g}" for n in definition.names)
            rows.append([f"best {metric}", f"{data[metric][i]:.6g}", values])
    return rows


def chunk_designs(definition: SweepDefinition, chunks: Iterable[int]) -> int:
    """How many designs the given chunks hold."""
    return sum(min(definition.size, (k + 1) * definition.chunk) - k * definition.chunk for k in chunks)
