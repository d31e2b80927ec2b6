"""Point sets in a box [lower, upper] (joint space within limits, or a Cartesian box).

Every function returns an array (N, d) of points; the box is given by two arrays of
shape (d,).
"""

from __future__ import annotations

import numpy as np


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
    counts = (counts,) * lower.size if np.isscalar(counts) else tuple(counts)
    axes = [axis_points(lo, hi, c, midpoints=midpoints) for lo, hi, c in zip(lower, upper, counts)]
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.stack([m.ravel() for m in mesh], axis=-1)


def uniform(lower: np.ndarray, upper: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """``count`` independent uniform random points in the box."""
    lower, upper = _box(lower, upper)
    return lower + rng.random((count, lower.size)) * (upper - lower)


#: Bits of the Sobol points: 52 bits are exact in a float64's fraction, so the points can be
#: read back as integers for digital shifts.
SOBOL_BITS = 52


def sobol(lower: np.ndarray, upper: np.ndarray, log2_count: int, rng: np.random.Generator,
          replicates: int | None = None) -> np.ndarray:
    """Randomized Sobol points in the box: 2**log2_count points, or ``replicates`` independent sets of them.

    One scrambled Sobol set (scipy.stats.qmc: random linear matrix scramble and digital
    shift) is drawn; each replicate applies a further independent random digital shift
    (XOR of the 52-bit digits with a random integer per coordinate).  Each replicate is
    then uniformly distributed point by point (unbiased estimates) and the replicates are
    independent given the matrix scramble, which is what a replicate-variance error
    estimate needs (Owen, "Monte Carlo theory, methods and examples", ch. 17).  Drawing
    replicates by digital shifts costs an XOR, where a new scipy scramble costs about a
    millisecond.  Points are the centres of their 2^-52 cells (no quantization bias).

    Returns:
        (2**log2_count, d) points, or (replicates, 2**log2_count, d).
    """
    from scipy.stats import qmc

    lower, upper = _box(lower, upper)
    base = qmc.Sobol(d=lower.size, scramble=True, bits=SOBOL_BITS, rng=rng).random_base2(log2_count)
    digits = (base * 2.0**SOBOL_BITS).astype(np.uint64)
    count = 1 if replicates is None else replicates
    shifts = rng.integers(0, 2**SOBOL_BITS, size=(count, 1, lower.size), dtype=np.uint64)
    unit = ((digits[None, :, :] ^ shifts).astype(np.float64) + 0.5) * 2.0**-SOBOL_BITS
    points = lower + unit * (upper - lower)
    return points[0] if replicates is None else points
