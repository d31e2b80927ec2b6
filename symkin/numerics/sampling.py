"""Point sets in a box [lower, upper] (joint space within limits, or a Cartesian box).

Every function returns an array (N, d) of points; the box is given by two arrays of
shape (d,).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from symkin.numerics.sobol import BITS, Sobol


def _box(lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    lower = np.atleast_1d(np.asarray(lower, dtype=np.float64))
    upper = np.atleast_1d(np.asarray(upper, dtype=np.float64))
    if lower.shape != upper.shape or lower.ndim != 1 or not np.all(lower < upper):
        raise ValueError(f"a box needs lower < upper of equal shape (d,), got {lower} and {upper}")
    return lower, upper


def axis_points(lower: float, upper: float, count: int, *, midpoints: bool) -> np.ndarray:
    """``count`` points on [lower, upper]: cell midpoints, or equally spaced with both ends."""
    if count < (1 if midpoints else 2):
        raise ValueError(f"too few points per axis: {count}")
    if midpoints:
        return lower + (np.arange(count) + 0.5) * ((upper - lower) / count)
    return np.linspace(lower, upper, count)


def grid(lower: np.ndarray, upper: np.ndarray, counts: int | tuple[int, ...], *,
         midpoints: bool = True) -> np.ndarray:
    """A regular tensor grid, ``counts`` points per axis (an int for all axes).

    Args:
        midpoints: True for the midpoints of counts^d equal cells (the midpoint rule's
            nodes, never on the box boundary); False for the vertices including both ends
            (for boundaries and figures).

    Returns:
        (prod(counts), d) points, the last axis varying fastest (``reshape(*counts, d)``
        restores the grid).
    """
    lower, upper = _box(lower, upper)
    per_axis = (int(counts),) * lower.size if isinstance(counts, (int, np.integer)) else tuple(counts)
    axes = [axis_points(lo, hi, c, midpoints=midpoints) for lo, hi, c in zip(lower, upper, per_axis)]
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.stack([m.ravel() for m in mesh], axis=-1)


def uniform(lower: np.ndarray, upper: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """``count`` independent uniform random points in the box."""
    lower, upper = _box(lower, upper)
    return lower + rng.random((count, lower.size)) * (upper - lower)


def sobol(lower: np.ndarray, upper: np.ndarray, log2_count: int, rng: np.random.Generator,
          replicates: int | None = None) -> np.ndarray:
    """Scrambled Sobol points in the box: 2**log2_count points, or ``replicates`` independent sets of them.

    Each set is an independent scramble of the Sobol sequence (random linear matrix scramble
    and digital shift, :class:`symkin.numerics.sobol.Sobol`, drawn from a child of ``rng`` as
    scipy.stats.qmc.Sobol does: the same points).  It has 30 digits, so every point
    would sit on the lower corner of its 2^-30 cell, a bias of about 1e-10 that randomized
    QMC reaches at 2^18 points; the remaining digits are therefore drawn uniformly at
    random, which makes every point exactly uniform (unbiased estimates) and keeps the
    net's stratification (Owen, "Monte Carlo theory, methods and examples", ch. 17).
    Independent scrambles make the replicate spread an honest error estimate.

    Returns:
        (2**log2_count, d) points, or (replicates, 2**log2_count, d).
    """
    lower, upper = _box(lower, upper)
    count = 1 if replicates is None else replicates
    sets = np.stack([Sobol(lower.size, rng.spawn(1)[0]).points(0, 2**log2_count) for _ in range(count)])
    unit = sets + rng.random(sets.shape) * 2.0**-BITS
    points = lower + unit * (upper - lower)
    return points[0] if replicates is None else points


def sobol_range(dimension: int, key: Sequence[int], start: int, stop: int) -> np.ndarray:
    """Points start ... stop - 1 (in the unit cube) of one scrambled Sobol sequence, drawn without the others.

    The scramble comes from the seed sequence ``key``, the digits beyond :data:`~symkin.numerics.sobol.BITS`
    from the generator (``*key``, start), as in :func:`sobol`: a chunk of a sequence can be
    drawn by any process from its definition alone (the chunked integrators and workspace).
    """
    sequence = Sobol(dimension, np.random.default_rng(np.random.SeedSequence(list(key))).spawn(1)[0])
    unit = sequence.points(start, stop)
    return unit + np.random.default_rng([*key, start]).random(unit.shape) * 2.0**-BITS


def grid_geometry(lower: np.ndarray, upper: np.ndarray, cell: float) -> tuple[np.ndarray, np.ndarray, tuple[int, ...]]:
    """(corner, cell sizes, cells per axis) of a grid of cubic cells of side ``cell`` centred on the box
    [lower, upper] and covering it."""
    counts = np.maximum(np.ceil((upper - lower) / cell).astype(int), 1)
    centre = (lower + upper) / 2
    start = centre - counts * cell / 2
    return start, np.full(lower.shape, float(cell)), tuple(int(c) for c in counts)


def cell_centres(lower: np.ndarray, cell: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """The centres of a grid's cells, shape (*shape, d), from its corner ``lower`` and cell sizes ``cell``."""
    axes = [lower[i] + (np.arange(c) + 0.5) * cell[i] for i, c in enumerate(shape)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
