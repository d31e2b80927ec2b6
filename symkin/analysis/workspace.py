"""Workspace of a mechanism: TCP point clouds, occupancy grids, boundary and area/volume.

Two ways to see the workspace W (seed sec. 4.1 and 5.2):

* forward: sample the joint space within the limits and map through the generated
  ``fk`` (:func:`sample_workspace`): a TCP point cloud, for any serial mechanism;
* inverse: test points of a Cartesian grid for reachability with an inverse kinematics
  (:func:`symkin.analysis.grids.reachability_grid`): the way of parallel mechanisms.

Both give an :class:`Occupancy` grid, from which the boundary (occupied cells with an
empty neighbour) and a bracketed area/volume follow.  The integrators of
:mod:`symkin.analysis.global_indices` give the area/volume with controlled error
(:func:`symkin.analysis.global_indices.workspace_measure`).
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import product

import numpy as np

from symkin.numerics import sampling
from symkin.mechanism.working_mode import assemble
from symkin import mechanism
from symkin.integration.estimates import Estimate
from symkin.mechanism import Limits
from symkin.runtime.info import GeneratedModel

SAMPLING_METHODS = ("grid", "random", "sobol")

@dataclass(frozen=True)
class WorkspaceCloud:
    """TCP points of sampled joint configurations.

    Attributes:
        q: (N, n) joint configurations within the limits.
        points: (N, d) TCP positions (d = position components of the task space).
        axes: names of the d coordinates, e.g. ("x", "y").
        grid_shape: the per-axis counts when ``q`` is a grid including the limits (then
            ``points.reshape(*grid_shape, d)`` is a curvilinear grid of the workspace);
            None for scattered samples.
    """

    q: np.ndarray
    points: np.ndarray
    axes: tuple[str, ...]
    grid_shape: tuple[int, ...] | None = None


def default_method(model: GeneratedModel) -> str:
    """Joint-space sampling that suits the model: a grid up to 3 joints (curvilinear maps), else Sobol."""
    return "grid" if len(mechanism.coordinate_names(model)) <= 3 else "sobol"


def sample_workspace(model: GeneratedModel, samples: int = 2**14, *, method: str | None = None, limits: Limits | None = None,
                     seed: int | None = None) -> WorkspaceCloud:
    """Sample the joint space within the limits and map it through ``fk``.

    Args:
        model: a loaded model.
        samples: about how many configurations (``grid``: per-axis count
            round(samples^(1/n)), limits included; ``sobol``: the next power of two).
        method: ``grid``, ``random`` (uniform) or ``sobol`` (scrambled); default
            :func:`default_method`.
        limits: joint-limit overrides.
        seed: seed of ``random`` and ``sobol``.
    """
    box = mechanism.joint_limits(model, limits)
    n = box.shape[0]
    grid_shape = None
    method = default_method(model) if method is None else method
    if method == "grid":
        per_axis = max(2, int(round(samples ** (1.0 / n))))
        grid_shape = (per_axis,) * n
        q = sampling.grid(box[:, 0], box[:, 1], per_axis, midpoints=False)
    elif method == "random":
        q = sampling.uniform(box[:, 0], box[:, 1], samples, np.random.default_rng(seed))
    elif method == "sobol":
        q = sampling.sobol(box[:, 0], box[:, 1], max(1, int(np.ceil(np.log2(samples)))), np.random.default_rng(seed))
    else:
        raise ValueError(f"unknown sampling method '{method}'; choose one of {', '.join(SAMPLING_METHODS)}")
    axes = tuple("xyz"[a] for a in mechanism.position_axes(model))
    points, inside = assemble(model, q)  # only configurations that assemble in the working mode belong to it
    if not inside.all():
        return WorkspaceCloud(q[inside], points[inside], axes, None)
    return WorkspaceCloud(q, points, axes, grid_shape)


@dataclass(frozen=True)
class Occupancy:
    """A Cartesian grid of cells, each occupied (in the workspace) or not.

    Attributes:
        lower: (d,) corner of the grid.
        cell: (d,) cell sizes.
        occupied: boolean array of shape (c_1, ..., c_d).
    """

    lower: np.ndarray
    cell: np.ndarray
    occupied: np.ndarray

    @property
    def cell_volume(self) -> float:
        return float(np.prod(self.cell))

    def centers(self) -> np.ndarray:
        """Cell centres, shape (c_1, ..., c_d, d)."""
        return sampling.cell_centres(self.lower, self.cell, self.occupied.shape)

    def boundary(self) -> np.ndarray:
        """Occupied cells with at least one empty neighbour (of the 3^d - 1 around it) or at the grid's edge.

        Diagonal neighbours count, so that the corners of a staircase along an oblique
        boundary are boundary cells too.
        """
        padded = np.pad(self.occupied, 1, constant_values=False)
        shape = self.occupied.shape
        all_neighbours = np.ones_like(self.occupied)
        for offset in product((0, 1, 2), repeat=self.occupied.ndim):
            window = tuple(slice(o, o + n) for o, n in zip(offset, shape))
            all_neighbours &= padded[window]
        return self.occupied & ~all_neighbours

    def interior(self) -> np.ndarray:
        """Occupied cells whose neighbours are all occupied."""
        return self.occupied & ~self.boundary()

    def lookup(self, points: np.ndarray, mask: np.ndarray | None = None) -> np.ndarray:
        """Boolean (N,): whether each point falls in a cell of ``mask`` (default: occupied)."""
        mask = self.occupied if mask is None else mask
        index = np.floor((np.asarray(points) - self.lower) / self.cell).astype(int)
        inside = np.all((index >= 0) & (index < np.array(mask.shape)), axis=-1)
        result = np.zeros(len(index), dtype=bool)
        result[inside] = mask[tuple(index[inside].T)]
        return result

    def measure(self) -> Estimate:
        """Area/volume bracketed between the interior cells and all occupied cells.

        Value: the midpoint of the bracket; error: its half-width.  The bracket holds when
        the cells are large enough for every cell inside the workspace to hold a sample
        (see :func:`occupancy_from_cloud`).
        """
        inner = self.interior().sum() * self.cell_volume
        outer = self.occupied.sum() * self.cell_volume
        return Estimate((inner + outer) / 2, (outer - inner) / 2, int(self.occupied.size), "occupancy", False)


def cloud_spacing(cloud: WorkspaceCloud, inside: np.ndarray | None = None) -> float:
    """Largest distance between the TCP points of neighbouring grid configurations (both ``inside``, a mask over
    the grid's configurations, where given: those that belong, e.g. within stops).

    Every point of the workspace lies within about this distance of a cloud point.

    Raises:
        ValueError: the cloud was not sampled on a grid.
    """
    if cloud.grid_shape is None:
        raise ValueError("the spacing of a cloud is known only for grid sampling")
    shape = cloud.grid_shape
    points = cloud.points.reshape(*shape, -1)
    kept = np.ones(shape, dtype=bool) if inside is None else np.asarray(inside, dtype=bool).reshape(shape)
    gaps = []
    for axis in range(len(shape)):
        step = np.linalg.norm(np.diff(points, axis=axis), axis=-1)
        both = np.take(kept, range(shape[axis] - 1), axis=axis) & np.take(kept, range(1, shape[axis]), axis=axis)
        gaps.append(float(np.max(step[both], initial=0.0)))
    return max(gaps)


def default_cell(cloud: WorkspaceCloud) -> float:
    """Cell size of :func:`occupancy_from_cloud`.

    For a grid cloud twice :func:`cloud_spacing`, so that every cell whose inscribed ball
    lies in the workspace holds a point (no holes); for scattered samples twice the mean
    spacing (bounding-box volume / N)^(1/d), a heuristic (holes are possible).
    """
    if cloud.grid_shape is not None:
        return 2.0 * cloud_spacing(cloud)
    extent = np.ptp(cloud.points, axis=0)
    d = extent.size
    return float(2.0 * (np.prod(np.maximum(extent, 1e-12)) / len(cloud.points)) ** (1.0 / d))


def occupancy_from_cloud(cloud: WorkspaceCloud, cell: float | None = None) -> Occupancy:
    """Cells that hold at least one TCP point.

    Args:
        cloud: the point cloud.
        cell: cell size; default :func:`default_cell`.
    """
    cell = default_cell(cloud) if cell is None else float(cell)
    lower, upper = cloud.points.min(axis=0), cloud.points.max(axis=0)
    start, size, counts = sampling.grid_geometry(lower, upper + 1e-12 * cell, cell)
    index = np.minimum(np.floor((cloud.points - start) / size).astype(int), np.array(counts) - 1)
    occupied = np.zeros(counts, dtype=bool)
    occupied[tuple(index.T)] = True
    return Occupancy(start, size, occupied)


def grid_cells(box: tuple[np.ndarray, np.ndarray], cell: float) -> tuple[np.ndarray, np.ndarray, tuple, np.ndarray]:
    """(start, cell sizes, counts, cell centres (N, d)) of the Cartesian grid of ``box``."""
    start, size, counts = sampling.grid_geometry(np.asarray(box[0], float), np.asarray(box[1], float), cell)
    return start, size, counts, Occupancy(start, size, np.zeros(counts, dtype=bool)).centers().reshape(-1, len(counts))


def limit_curves(model: GeneratedModel, *, limits: Limits | None = None, count: int = 200) -> list[np.ndarray]:
    """TCP paths along the four edges of the joint-limit box of a 2-DoF mechanism.

    The workspace boundary of a serial arm lies on the images of the joint-limit faces
    and of the singular set (det J = 0); for 2 joints the faces are these four curves.

    Returns:
        Four arrays (count, d): q1 = lower, q1 = upper, q2 = lower, q2 = upper.
    """
    box = mechanism.joint_limits(model, limits)
    if box.shape[0] != 2:
        raise ValueError(f"{model.name}: limit curves are drawn for 2-DoF mechanisms only")
    curves = []
    for fixed in range(2):
        moving = 1 - fixed
        for bound in box[fixed]:
            q = np.empty((count, 2))
            q[:, fixed] = bound
            q[:, moving] = np.linspace(box[moving, 0], box[moving, 1], count)
            curves.append(mechanism.tcp_positions(model, q))
    return curves

