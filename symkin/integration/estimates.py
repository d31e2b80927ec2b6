"""Results of the integrators: values with error estimates, and ratios of integrals.

An integrator estimates the integrals I_1..I_k of the k components of one integrand over
a box (for a global index: numerator and workspace measure).  How its error is estimated
depends on the method, and so does the error of a ratio I_i / I_j such as the GCI:

* statistical (Monte Carlo, randomized quasi-Monte Carlo): the covariance matrix C of
  the estimator; the ratio's variance follows by the delta method,
  var(I_i / I_j) ~= (C_ii - 2 R C_ij + R^2 C_jj) / I_j^2 with R = I_i / I_j, and the
  reported error is the half-width of the 95 % confidence interval (normal or Student-t
  quantile times the standard error);
* levels (regular grid): the same rule on grids 2 and 4 times coarser; for any result
  g (an integral or a ratio) the error is max(|g_1 - g_2|, |g_2 - g_4| / 2) with g_1 the
  fine, g_2 and g_4 the coarser results (see :mod:`symkin.integration.integrators`);
* bounds (adaptive cubature): per-component error estimates e; the ratio's error is
  propagated to first order, (e_i + |R| e_j) / |I_j|.

No error estimate is smaller than the rounding of the computation (:func:`rounding_floor`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Confidence level of the error of statistical estimates.
CONFIDENCE = 0.95

#: Unit roundoff of the floating-point arithmetic.
EPS = float(np.finfo(np.float64).eps)


def rounding_floor(value: float, evaluations: int) -> float:
    """The smallest error an estimate can claim: eps (16 + sqrt(N)) |value|.

    Each of the N integrand values carries rounding errors of a few eps (the generated
    code, the singular values), and their weighted sum accumulates them like a random
    walk; 16 eps covers the final ratio and the fixed costs.
    """
    return EPS * (16.0 + np.sqrt(evaluations)) * abs(value)


@dataclass(frozen=True)
class Estimate:
    """A scalar result and its error estimate.

    Attributes:
        value: the estimate.
        error: estimated absolute error; for statistical methods the half-width of the
            95 % confidence interval, otherwise a deterministic error estimate.
        evaluations: integrand evaluations (points) spent.
        method: integrator name.
        statistical: whether ``error`` is a confidence half-width.
    """

    value: float
    error: float
    evaluations: int
    method: str
    statistical: bool

    @property
    def relative_error(self) -> float:
        """error / |value| (inf for a zero value)."""
        return self.error / abs(self.value) if self.value else float("inf")

    def __str__(self) -> str:
        """The value with the digits its error supports (two beyond the error's leading digit)."""
        if self.value and self.error > 0:
            digits = int(np.clip(np.ceil(np.log10(abs(self.value) / self.error)) + 2, 2, 17))
        else:
            digits = 17
        return f"{self.value:.{digits}g} +- {self.error:.2g}"


@dataclass(frozen=True)
class IntegralEstimate:
    """Integrals of the k components of an integrand, with the method's error model.

    Exactly one of ``covariance``, ``coarse`` and ``bounds`` is set (see module docstring).

    Attributes:
        values: the k integral estimates.
        evaluations: integrand evaluations (points) spent.
        method: integrator name.
        covariance: (k, k) covariance of the estimator (statistical methods).
        quantile: factor from standard error to the 95 % confidence half-width.
        coarse: (2, k) estimates of the rule on grids 2 and 4 times coarser (regular grid).
        bounds: the k error estimates (adaptive cubature).
    """

    values: np.ndarray
    evaluations: int
    method: str
    covariance: np.ndarray | None = None
    quantile: float = 0.0
    coarse: np.ndarray | None = None
    bounds: np.ndarray | None = None

    def __post_init__(self) -> None:
        if sum(x is not None for x in (self.covariance, self.coarse, self.bounds)) != 1:
            raise ValueError("an IntegralEstimate needs exactly one error model")

    @property
    def statistical(self) -> bool:
        return self.covariance is not None

    def _bounds(self) -> np.ndarray:
        """The per-component error bounds (set when neither a covariance nor coarse levels are)."""
        if self.bounds is None:
            raise ValueError("the estimate carries no error bounds")
        return self.bounds

    def _estimate(self, value: float, error: float) -> Estimate:
        error = max(float(error), rounding_floor(float(value), self.evaluations))
        return Estimate(float(value), error, self.evaluations, self.method, self.statistical)

    def _level_error(self, coarse: np.ndarray, result) -> float:
        fine, (half, quarter) = result(self.values), (result(v) for v in coarse)
        error = max(abs(fine - half), abs(half - quarter) / 2)
        return error if np.isfinite(error) else np.inf

    def component(self, i: int) -> Estimate:
        """The integral of component i and its error."""
        if self.covariance is not None:
            error = self.quantile * np.sqrt(max(self.covariance[i, i], 0.0))
        elif self.coarse is not None:
            error = self._level_error(self.coarse, lambda v: v[i])
        else:
            error = self._bounds()[i]
        return self._estimate(self.values[i], error)

    def ratio(self, i: int = 0, j: int = 1) -> Estimate:
        """The ratio I_i / I_j (e.g. a global index: weighted integral over measure) and its error.

        Raises:
            ValueError: I_j is zero (e.g. an empty workspace).
        """
        numerator, denominator = self.values[i], self.values[j]
        if denominator == 0:
            raise ValueError("the denominator integral is zero: the domain has no measure "
                             "(empty workspace, or all samples unreachable)")
        R = numerator / denominator
        if self.covariance is not None:
            C = self.covariance
            variance = (C[i, i] - 2.0 * R * C[i, j] + R * R * C[j, j]) / denominator**2
            error = self.quantile * np.sqrt(max(variance, 0.0))
        elif self.coarse is not None:
            error = self._level_error(self.coarse, lambda v: v[i] / v[j] if v[j] else np.inf)
        else:
            bounds = self._bounds()
            error = (bounds[i] + abs(R) * bounds[j]) / abs(denominator)
        return self._estimate(R, error)
