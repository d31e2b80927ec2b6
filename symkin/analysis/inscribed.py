"""The largest box and the largest upright cylinder inside a workspace, as a maker's datasheet quotes a workspace
("381 W x 267 H x 191 D mm", "160 mm diameter x 110 mm").

Both are found among the interior cells of the workspace's occupancy (:class:`~symkin.analysis.workspace.Occupancy`:
occupied cells whose neighbours are all occupied, the inner end of its volume bracket), so the shapes lie inside the
workspace up to its sampling.  The box is axis-aligned: over every range of layers along the last axis the cells
occupied in all of them form a mask, and over every range of rows of that mask the longest run of columns occupied
in all of them is the widest box there (prefix counts per column; O(c_z^2 c_x^2 c_y) with numpy over the rows).
The cylinder stands along the last axis (z, the vertical of a desk device): over every range of layers its
radius is the largest distance from an occupied cell's centre to the nearest empty cell's centre, less half a cell's
diagonal (so every point within it lies in an occupied cell), by the Euclidean distance transform.  Whether a box of
given sizes fits (a maker's) is a window sum over the mask's summed-volume table at every placement.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Box:
    """An axis-aligned box: its ``lower`` and ``upper`` corners (d,) in m."""

    lower: np.ndarray
    upper: np.ndarray

    @property
    def size(self) -> np.ndarray:
        return self.upper - self.lower

    @property
    def volume(self) -> float:
        return float(np.prod(self.size))


@dataclass(frozen=True)
class Cylinder:
    """An upright cylinder: the ``centre`` of its axis in the horizontal plane (2,), its ``radius`` and its
    ``bottom`` and ``top`` heights, in m."""

    centre: np.ndarray
    radius: float
    bottom: float
    top: float

    @property
    def volume(self) -> float:
        return math.pi * self.radius ** 2 * (self.top - self.bottom)


def largest_box(mask: np.ndarray, lower: np.ndarray, cell: np.ndarray) -> Box | None:
    """The axis-aligned box of most cells of ``mask`` (2-d: c_x x c_y, 3-d: c_x x c_y x c_z), all True, as a
    :class:`Box` in m (``lower``: the grid's corner, ``cell``: its cell sizes); None where no cell is True."""
    mask = np.asarray(mask, dtype=bool)
    layered = mask[..., None] if mask.ndim == 2 else mask
    best, where = 0, None
    layers = layered.shape[2]
    for bottom in range(layers):
        common = np.ones(layered.shape[:2], dtype=bool)
        for top in range(bottom, layers):
            common &= layered[:, :, top]
            if not common.any():
                break
            height = top - bottom + 1
            cells, rows, columns = _largest_rectangle(common)
            if cells * height > best:
                best, where = cells * height, (rows, columns, (bottom, top + 1))
    if where is None:
        return None
    spans = where[:mask.ndim]
    low = np.array([lower[k] + cell[k] * spans[k][0] for k in range(mask.ndim)])
    high = np.array([lower[k] + cell[k] * spans[k][1] for k in range(mask.ndim)])
    return Box(low, high)


def _largest_rectangle(mask: np.ndarray) -> tuple[int, tuple[int, int], tuple[int, int]]:
    """(cells, (first row, end row), (first column, end column)) of the largest all-True rectangle of a 2-d mask:
    for every pair of rows, the columns True in all rows between them (prefix counts), and their longest run."""
    rows, columns = mask.shape
    counts = np.vstack([np.zeros((1, columns), dtype=int), np.cumsum(mask, axis=0)])
    first, last = np.triu_indices(rows)                             # every pair first <= last
    full = (counts[last + 1] - counts[first]) == (last - first + 1)[:, None]
    run = np.zeros(len(first), dtype=int)
    longest = np.zeros(len(first), dtype=int)
    ends = np.zeros(len(first), dtype=int)
    for column in range(columns):
        run = np.where(full[:, column], run + 1, 0)
        longer = run > longest
        longest = np.where(longer, run, longest)
        ends = np.where(longer, column + 1, ends)
    areas = longest * (last - first + 1)
    k = int(np.argmax(areas))
    return int(areas[k]), (int(first[k]), int(last[k]) + 1), (int(ends[k] - longest[k]), int(ends[k]))


def largest_cylinder(mask: np.ndarray, lower: np.ndarray, cell: np.ndarray) -> Cylinder | None:
    """The upright cylinder (axis along the grid's last axis) of largest volume inside the True cells of a 3-d
    ``mask``, in m; None where no cell is True."""
    from scipy import ndimage  # here: importing it costs every command that imports this module 0.17 s

    mask = np.asarray(mask, dtype=bool)
    half_diagonal = float(np.hypot(cell[0], cell[1])) / 2
    best, found = 0.0, None
    for bottom in range(mask.shape[2]):
        common = np.ones(mask.shape[:2], dtype=bool)
        for top in range(bottom, mask.shape[2]):
            common &= mask[:, :, top]
            if not common.any():
                break
            # distance from each cell centre to the nearest empty cell's centre (the grid's outside is empty)
            distance = ndimage.distance_transform_edt(np.pad(common, 1), sampling=cell[:2])[1:-1, 1:-1]
            k = np.unravel_index(int(np.argmax(distance)), distance.shape)
            radius = float(distance[k]) - half_diagonal
            height = (top - bottom + 1) * float(cell[2])
            if radius > 0 and math.pi * radius ** 2 * height > best:
                best = math.pi * radius ** 2 * height
                centre = np.array([lower[0] + cell[0] * (k[0] + 0.5), lower[1] + cell[1] * (k[1] + 0.5)])
                found = Cylinder(centre, radius, float(lower[2] + cell[2] * bottom),
                                 float(lower[2] + cell[2] * (top + 1)))
    return found


def placed_box(mask: np.ndarray, lower: np.ndarray, cell: np.ndarray, size: np.ndarray) -> Box | None:
    """Where an axis-aligned box of ``size`` (d,) m fits among the True cells of ``mask``: the placement of a box of
    whole cells (each size rounded up) nearest the centre of the True cells, or None where it fits nowhere.  Every
    placement is tried at once: the count of True cells in each window from the summed-volume table, the window
    fitting where it is full."""
    mask = np.asarray(mask, dtype=bool)
    cells = np.maximum(np.ceil(np.asarray(size, dtype=float) / cell - 1e-9).astype(int), 1)
    if np.any(cells > mask.shape):
        return None
    table = np.pad(mask.astype(np.int64), [(1, 0)] * mask.ndim)
    for axis in range(mask.ndim):
        table = np.cumsum(table, axis=axis)
    counts = np.zeros(tuple(n - k + 1 for n, k in zip(mask.shape, cells)), dtype=np.int64)
    for corner in np.ndindex(*(2,) * mask.ndim):   # inclusion-exclusion over the window's 2^d corners
        window = tuple(slice(k * c, k * c + m) for k, c, m in zip(cells, corner, counts.shape))
        counts += (-1) ** (mask.ndim - sum(corner)) * table[window]
    fits = np.argwhere(counts == np.prod(cells))
    if len(fits) == 0:
        return None
    middle = np.argwhere(mask).mean(axis=0) - (cells - 1) / 2
    first = fits[int(np.argmin(np.linalg.norm(fits - middle, axis=1)))]
    return Box(lower + cell * first, lower + cell * (first + cells))
