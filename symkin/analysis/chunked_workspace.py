"""The workspace of a serial mechanism from a joint-space budget beyond memory, in chunks on Dask.

:func:`symkin.analysis.study.study_workspace` holds the whole cloud: N configurations, their
TCP points and Jacobians.  Here the budget is cut into tasks of at most ``chunk``
configurations (:func:`symkin.runtime.cluster.run_tasks`: a LocalCluster, a cluster or this
process, one client for every pass); each task draws its own configurations from the
definition alone (``grid``: its range of the row-major grid index; ``random``: the generator
(seed, chunk); ``sobol``: points k0 ... k1 of the scrambled Sobol sequence of 2^m points, with
low digits from the generator (seed, k0), as :mod:`symkin.integration.chunked`) and returns
summaries whose size does not grow with the chunk:

1. extent: the per-chunk minima and maxima of the TCP positions, hence the samples' extent;
2. summary, on the occupancy grid fixed by that extent and the cell size: the occupied cells
   (their flat indices), the minimum, sum and maximum of 1/kappa, the singular configurations
   (1/kappa <= 0) counted per cell, and an evenly spaced subsample of the chunk (``keep``
   configurations in all) for the figures.

The chunks are reduced in chunk order (occupancy is a union), so the result does not depend
on where the chunks ran.  The area/volume over the joint domain (|det J| dq) is the chunked
quasi-Monte Carlo integral of the same budget (:func:`symkin.integration.chunked.integrate_chunked`).
The default cell is that of scattered samples (:func:`symkin.analysis.workspace.default_cell`:
twice the mean spacing), but never finer than the extent over ``MAX_CELLS_PER_AXIS``, which
bounds the grid held by the client.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin.numerics import sampling
from symkin.analysis import global_indices, workspace
from symkin import mechanism
from symkin.integration.chunked import IntegrandSpec, integrate_chunked
from symkin.runtime.cluster import dask_client, run_tasks
from symkin.runtime.payload import ModelPayload

#: configurations per task unless told otherwise
CHUNK = 2**20
#: configurations kept for the figures, in all
KEEP = 2**16
#: the occupancy grid has at most this many cells along an axis
MAX_CELLS_PER_AXIS = {2: 4096, 3: 512}


@dataclass(frozen=True)
class CloudSpec:
    """How every task draws its configurations and scores them.

    Attributes:
        parameters: parameter values the model is bound to ((name, value) pairs).
        limits: joint-limit overrides ((joint, (lower, upper)) pairs).
        length: characteristic length of a task space that mixes translations and rotations.
        method: ``grid``, ``random`` or ``sobol``.
        samples: configurations in all (``grid``: per-axis count^n, ``sobol``: a power of two).
        seed: seed of ``random`` and ``sobol``.
    """

    parameters: tuple[tuple[str, float], ...]
    limits: tuple[tuple[str, tuple[float, float]], ...]
    length: float | None
    method: str
    samples: int
    seed: int

    def model(self, payload: ModelPayload) -> Any:
        loaded = payload.load()
        return loaded.bind(**dict(self.parameters)) if self.parameters else loaded

    def configurations(self, box: np.ndarray, start: int, stop: int) -> np.ndarray:
        """Configurations start ... stop - 1 of the sample (see the module docstring)."""
        n = box.shape[0]
        if self.method == "grid":
            per_axis = round(self.samples ** (1.0 / n))
            axes = [sampling.axis_points(lo, hi, per_axis, midpoints=False) for lo, hi in box]
            index = np.unravel_index(np.arange(start, stop), (per_axis,) * n)
            return np.stack([axis[i] for axis, i in zip(axes, index)], axis=-1)
        if self.method == "random":
            rng = np.random.default_rng([self.seed, start])
            return box[:, 0] + rng.random((stop - start, n)) * (box[:, 1] - box[:, 0])
        unit = sampling.sobol_range(n, (self.seed,), start, stop)
        return box[:, 0] + unit * (box[:, 1] - box[:, 0])


def budget(method: str, samples: int, joints: int) -> int:
    """The configurations a method draws for a requested ``samples`` (as :func:`~symkin.analysis.workspace.sample_workspace`)."""
    if method == "grid":
        return max(2, round(samples ** (1.0 / joints))) ** joints
    if method == "sobol":
        return 2 ** max(1, math.ceil(math.log2(samples)))
    if method == "random":
        return samples
    raise ValueError(f"unknown sampling method '{method}'; choose one of {', '.join(workspace.SAMPLING_METHODS)}")


def _extent_chunk(payload: ModelPayload, spec: CloudSpec, start: int, stop: int) -> tuple[np.ndarray, np.ndarray]:
    model = spec.model(payload)
    box = mechanism.joint_limits(model, dict(spec.limits) or None)
    points = mechanism.tcp_positions(model, spec.configurations(box, start, stop))
    return points.min(axis=0), points.max(axis=0)


@dataclass(frozen=True)
class ChunkSummary:
    """What one task of pass 2 returns (see the module docstring)."""

    occupied: np.ndarray
    inv_kappa_min: float
    inv_kappa_sum: float
    inv_kappa_max: float
    singular_cells: np.ndarray
    singular_counts: np.ndarray
    kept_q: np.ndarray
    kept_points: np.ndarray
    kept_inv_kappa: np.ndarray


def _summary_chunk(payload: ModelPayload, spec: CloudSpec, start: int, stop: int, grid: workspace.Occupancy,
                   keep: int) -> ChunkSummary:
    model = spec.model(payload)
    limits = dict(spec.limits) or None
    box = mechanism.joint_limits(model, limits)
    q = spec.configurations(box, start, stop)
    points = mechanism.tcp_positions(model, q)
    with np.errstate(all="ignore"):
        inv_kappa = global_indices.local_index(model, q, length=spec.length, limits=limits)
    index = np.floor((points - grid.lower) / grid.cell).astype(np.int64)
    index = np.clip(index, 0, np.array(grid.occupied.shape) - 1)
    cells = np.ravel_multi_index(tuple(index.T), grid.occupied.shape)
    singular_cells, singular_counts = np.unique(cells[inv_kappa <= 0.0], return_counts=True)
    kept = np.linspace(0, len(q) - 1, min(keep, len(q))).round().astype(int) if keep else np.zeros(0, int)
    return ChunkSummary(np.unique(cells), float(np.min(inv_kappa)), float(np.sum(inv_kappa)),
                        float(np.max(inv_kappa)), singular_cells, singular_counts, q[kept], points[kept],
                        inv_kappa[kept])


@dataclass(frozen=True)
class ChunkedWorkspace:
    """The reduced result: the samples' extent, occupancy, 1/kappa statistics and the kept subsample."""

    configurations: int
    lower: np.ndarray
    upper: np.ndarray
    occupancy: workspace.Occupancy
    inv_kappa_min: float
    inv_kappa_mean: float
    inv_kappa_max: float
    singular_count: int
    singular_on_boundary: int
    cloud: workspace.WorkspaceCloud
    inv_kappa: np.ndarray
    #: area/volume over the joint domain, None unless the task space is positions only
    measure: Any


def _cell(lower: np.ndarray, upper: np.ndarray, configurations: int) -> float:
    extent = np.maximum(upper - lower, 1e-12)
    d = extent.size
    scattered = 2.0 * (float(np.prod(extent)) / configurations) ** (1.0 / d)
    return max(scattered, float(extent.max()) / MAX_CELLS_PER_AXIS.get(d, 256))


def chunked_workspace(payload: ModelPayload, spec: CloudSpec, *, chunk: int = CHUNK, keep: int = KEEP,
                      scheduler: str = "local", workers: int | None = None, client: Any = None,
                      progress: Callable[..., None] = lambda _stage, done=None, total=None: None
                      ) -> ChunkedWorkspace:
    """Sample, measure and score the workspace of a serial mechanism in chunks (see the module docstring).

    Raises:
        ValueError: a parallel mechanism (its workspace comes from a Cartesian grid), a bad
            method or chunk size.
    """
    model = spec.model(payload)
    if mechanism.sampled_in_task_space(model):
        raise ValueError(f"{model.name}: a parallel mechanism's workspace is measured on a Cartesian grid, bounded "
                         "by its cells; sample its joint space without --scheduler")
    if chunk < 1:
        raise ValueError("the chunk size must be at least one configuration")
    joints = mechanism.joint_limits(model, dict(spec.limits) or None).shape[0]
    total = budget(spec.method, spec.samples, joints)
    spec = CloudSpec(spec.parameters, spec.limits, spec.length, spec.method, total, spec.seed)
    ranges = [(k, min(total, k + chunk)) for k in range(0, total, chunk)]
    name = f"symkin-workspace-{payload.digest[:12]}-{spec.method}-{spec.seed}-{total}"
    if client is None and scheduler != "serial":
        with dask_client(scheduler, workers) as active:
            return chunked_workspace(payload, spec, chunk=chunk, keep=keep, client=active, progress=progress)
    extents: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    _run(_extent_chunk, [(spec, *r) for r in ranges], payload, f"{name}-extent", extents, scheduler, client,
         lambda done: progress("extent (chunks)", done=done, total=len(ranges)))
    lower = np.min([extents[i][0] for i in range(len(ranges))], axis=0)
    upper = np.max([extents[i][1] for i in range(len(ranges))], axis=0)
    cell = _cell(lower, upper, total)
    start, size, counts = sampling.grid_geometry(lower, upper + 1e-12 * cell, cell)
    grid = workspace.Occupancy(start, size, np.zeros(counts, dtype=bool))
    per_chunk = -(-keep // len(ranges))
    summaries: dict[int, ChunkSummary] = {}
    _run(_summary_chunk, [(spec, *r, grid, per_chunk) for r in ranges], payload, f"{name}-summary", summaries,
         scheduler, client, lambda done: progress("occupancy and 1/kappa (chunks)", done=done,
                                                         total=len(ranges)))
    ordered = [summaries[i] for i in range(len(ranges))]
    occupied = np.zeros(grid.occupied.size, dtype=bool)
    for s in ordered:
        occupied[s.occupied] = True
    occupancy = workspace.Occupancy(start, size, occupied.reshape(counts))
    boundary = occupancy.boundary().ravel()
    singular = sum(int(s.singular_counts.sum()) for s in ordered)
    on_boundary = sum(int(s.singular_counts[boundary[s.singular_cells]].sum()) for s in ordered)
    axes = tuple("xyz"[a] for a in mechanism.position_axes(model))
    cloud = workspace.WorkspaceCloud(np.concatenate([s.kept_q for s in ordered]),
                                     np.concatenate([s.kept_points for s in ordered]), axes)
    measure = None
    if mechanism.is_positional(model):  # |det J| dq is an area/volume only when J maps onto positions
        progress(f"area/volume: qmc over {total} configurations")
        measure = integrate_chunked(payload, IntegrandSpec(spec.parameters, None, "cartesian", spec.limits,
                                                           spec.length), "qmc", total, seed=spec.seed, chunk=chunk,
                                    scheduler=scheduler, client=client).component(0)
    return ChunkedWorkspace(total, lower, upper, occupancy, min(s.inv_kappa_min for s in ordered),
                            math.fsum(s.inv_kappa_sum for s in ordered) / total,
                            max(s.inv_kappa_max for s in ordered), singular, on_boundary,
                            cloud, np.concatenate([s.kept_inv_kappa for s in ordered]), measure)


def _run(function: Callable[..., Any], tasks: list[tuple], payload: ModelPayload, name: str, results: dict,
         scheduler: str, client: Any, progress: Callable[[int], None]) -> None:
    def finished(i: int, result: Any) -> None:
        results[i] = result
        progress(len(results))

    run_tasks(function, tasks, shared=payload, name=name, finished=finished, scheduler=scheduler, client=client)


def report(found: ChunkedWorkspace, chunk: int, where: str) -> list[str]:
    """The lines of ``symkin workspace`` for a chunked run (as :func:`symkin.analysis.study._report`)."""
    axes = found.cloud.axes
    d = len(axes)
    kind = "area" if d == 2 else "volume"
    boundary = found.occupancy.boundary()
    chunks = -(-found.configurations // chunk)
    lines = ["extent of the samples: " + ", ".join(f"{a} [{lo:.6g}, {hi:.6g}] m"
                                                   for a, lo, hi in zip(axes, found.lower, found.upper))]
    if found.measure is not None:
        lines.append(f"{kind}: {found.measure} m^{d} (qmc, |det J| dq over the joint limits, in {chunks} chunks "
                     f"{where})")
    return lines + [
        f"{kind}: {found.occupancy.measure()} m^{d} (occupancy of {found.occupancy.cell[0]:.3g} m cells: between "
        f"interior and all occupied cells); {int(boundary.sum())} boundary cells",
        f"1/kappa: min {found.inv_kappa_min:.4g}, mean {found.inv_kappa_mean:.4g}, max {found.inv_kappa_max:.4g}; "
        f"singular configurations: {found.singular_count}, of which {found.singular_on_boundary} on the workspace "
        "boundary (seed sec. 4.2: boundary singularities)",
        f"figures from {len(found.cloud.q)} of the {found.configurations} configurations, evenly spaced in each chunk",
    ]
