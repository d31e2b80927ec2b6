"""A vectorized integrand over a box: what every integrator of :mod:`symkin.integration.integrators` integrates."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

#: Points per call of the integrand: bounds the memory of one batch (a (N, 4, 4) fk array
#: of 2**17 points is 16 MiB) while keeping the per-call overhead negligible.
CHUNK = 2**17


@dataclass(frozen=True)
class Moments:
    """The first two moments of a batch of values (N, k): its count N, mean (k,) and scatter (k, k) =
    sum (f - mean)(f - mean)^T."""

    count: int
    mean: np.ndarray
    scatter: np.ndarray


def combined(parts: Sequence[Moments], components: int) -> Moments:
    """The moments of the union of batches, from theirs in the order given, by Chan, Golub and LeVeque's pairwise
    update (Am. Stat. 37(3), 1983): n = n_a + n_b, mean = mean_a + (n_b / n) delta, scatter = scatter_a + scatter_b
    + (n_a n_b / n) delta delta^T with delta = mean_b - mean_a, which keeps the digits a one-pass sum of squares
    loses.  ``components``: k, the shape of the moments of no batch."""
    count, mean, scatter = 0, np.zeros(components), np.zeros((components, components))
    for part in parts:
        total = count + part.count
        if total == 0:
            continue
        delta = part.mean - mean
        mean = mean + delta * (part.count / total)
        scatter = scatter + part.scatter + np.outer(delta, delta) * (count * part.count / total)
        count = total
    return Moments(count, mean, scatter)


@dataclass(frozen=True)
class Integrand:
    """f: [lower, upper] in R^d -> R^k, evaluated on batches of points.

    Attributes:
        lower, upper: the box, arrays of shape (d,).
        function: maps points (N, d) to values (N, k); it must be vectorized (one call
            evaluates the whole batch through the generated code).
        components: names of the k components, e.g. ("1/kappa dW", "dW").
        variables: names of the d coordinates, e.g. joint names or ("x", "y").
        indicator: index of a component that is the 0/1 indicator of the integration
            domain inside the box (a reachability test), or None for an integrand that is
            continuous on the box; where it jumps, every component may jump, which the
            adaptive integrator must know (see :mod:`symkin.integration.adaptive`).
        moments: where the values are computed elsewhere (an accelerator), the reduction done there: points
            (N, d) -> (mean (k,), scatter (k, k) = sum (f - mean)(f - mean)^T) of their values, so that only
            those come back; the statistics of several batches are combined here (:meth:`mean_and_covariance`).
            None: the values come back and are reduced here.
    """

    lower: np.ndarray
    upper: np.ndarray
    function: Callable[[np.ndarray], np.ndarray]
    components: tuple[str, ...]
    variables: tuple[str, ...]
    indicator: int | None = None
    moments: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]] | None = None

    @property
    def dimension(self) -> int:
        return int(np.size(self.lower))

    @property
    def volume(self) -> float:
        """Volume of the box."""
        return float(np.prod(np.asarray(self.upper) - np.asarray(self.lower)))

    def __call__(self, points: np.ndarray) -> np.ndarray:
        """Values (N, k) at points (N, d), evaluated in batches of at most :data:`CHUNK` points."""
        points = np.asarray(points, dtype=np.float64)
        if points.shape[0] <= CHUNK:
            return self._checked(self.function(points), points.shape[0])
        return np.concatenate([self._checked(self.function(points[s:s + CHUNK]), len(points[s:s + CHUNK]))
                               for s in range(0, points.shape[0], CHUNK)])

    def mean(self, points: np.ndarray) -> np.ndarray:
        """The mean (k,) of the values at points (N, d)."""
        return self.mean_and_covariance(points)[0] if self.moments is not None else self(points).mean(axis=0)

    def mean_and_covariance(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The mean (k,) and sample covariance (k, k; divisor N - 1) of the values at points (N, d)."""
        points = np.asarray(points, dtype=np.float64)
        if self.moments is None:
            values = self(points)
            return values.mean(axis=0), np.atleast_2d(np.cov(values, rowvar=False))
        reduced = self.reduce(points)
        return reduced.mean, reduced.scatter / max(reduced.count - 1, 1)

    def reduce(self, points: np.ndarray) -> Moments:
        """The count, mean and scatter of the values at points (N, d), reduced where they are evaluated: with
        :attr:`moments` batches of at most :data:`CHUNK` points on the device, combined here (:func:`combined`);
        without, from the values evaluated here."""
        points = np.asarray(points, dtype=np.float64)
        if self.moments is None:
            values = self(points)
            mean = values.mean(axis=0)
            return Moments(len(points), mean, (values - mean).T @ (values - mean))
        return combined([Moments(len(batch), *(np.asarray(v, dtype=np.float64) for v in self.moments(batch)))
                         for batch in (points[start:start + CHUNK] for start in range(0, len(points), CHUNK))],
                        len(self.components))

    def _checked(self, values: np.ndarray, count: int) -> np.ndarray:
        values = np.asarray(values, dtype=np.float64)
        if values.shape != (count, len(self.components)):
            raise ValueError(f"the integrand returned shape {values.shape}, expected ({count}, {len(self.components)})")
        return values
