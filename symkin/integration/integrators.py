"""Integrators of a vector integrand over a box, each with an error estimate.

All take an :class:`~symkin.integration.integrand.Integrand` and a budget ``samples`` (the
number of integrand evaluations to spend, approximately for the grid) and return an
:class:`~symkin.integration.estimates.IntegralEstimate`:

* ``grid``: the tensor midpoint rule on n^d cells (n divisible by 4); for the error also
  on (n/2)^d and (n/4)^d cells (a quarter and a sixteenth more work in 2-D).  The error
  estimate is max(|I_n - I_n/2|, |I_n/2 - I_n/4| / 2): for a smooth integrand the rule's
  error falls as h^2, so this is 3 to 6 times the fine rule's error; taking two
  differences keeps it safe where the error oscillates with the grid (a kink of 1/kappa
  at an isotropic configuration); for a discontinuous integrand it is of the right size
  but not a bound;
* ``mc``: plain Monte Carlo with uniform points; standard error from the sample
  covariance, 95 % normal confidence half-width;
* ``qmc``: randomized quasi-Monte Carlo: ``replicates`` independently scrambled Sobol
  point sets of 2^m points each (:func:`symkin.numerics.sampling.sobol`), evaluated in
  one batch; the estimate is their mean and the error the 95 % Student-t half-width
  from their spread (Owen, "Monte Carlo theory, methods and examples", ch. 17);
* ``adaptive``: batched adaptive Genz-Malik cubature (:mod:`symkin.integration.adaptive`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from symkin.numerics import sampling
from symkin.integration.adaptive import adaptive
from symkin.integration.estimates import CONFIDENCE, IntegralEstimate
from symkin.integration.integrand import Integrand

#: Independent scramblings of the quasi-Monte Carlo integrator.
QMC_REPLICATES = 16


def midpoint_grid(integrand: Integrand, samples: int, *, rng: np.random.Generator | None = None) -> IntegralEstimate:
    """Tensor midpoint rule with a three-level difference as error estimate (``rng`` is unused)."""
    d = integrand.dimension
    n = 4
    while (n + 4) ** d * (1 + 0.5**d + 0.25**d) <= samples:
        n += 4

    def rule(count: int) -> np.ndarray:
        return integrand.volume * integrand.mean(sampling.grid(integrand.lower, integrand.upper, count))

    coarse = np.array([rule(n // 2), rule(n // 4)])
    return IntegralEstimate(values=rule(n), evaluations=n**d + (n // 2) ** d + (n // 4) ** d, method="grid",
                            coarse=coarse)


def monte_carlo(integrand: Integrand, samples: int, *, rng: np.random.Generator | None = None) -> IntegralEstimate:
    """Plain Monte Carlo with uniform random points."""
    if samples < 2:
        raise ValueError("Monte Carlo needs at least 2 samples")
    rng = np.random.default_rng() if rng is None else rng
    mean, covariance = integrand.mean_and_covariance(sampling.uniform(integrand.lower, integrand.upper, samples, rng))
    return monte_carlo_estimate(integrand.volume, mean, covariance, samples)


def monte_carlo_estimate(volume: float, mean: np.ndarray, covariance: np.ndarray, samples: int) -> IntegralEstimate:
    """V mean f with the covariance of the mean V^2 cov(f) / N and the 95 % normal quantile.

    ``covariance``: the sample covariance of f (divisor N - 1).
    """
    from scipy.special import ndtri

    return IntegralEstimate(values=volume * mean, evaluations=samples, method="mc",
                            covariance=np.atleast_2d(covariance) * volume**2 / samples,
                            quantile=float(ndtri(0.5 + CONFIDENCE / 2)))


def quasi_monte_carlo(integrand: Integrand, samples: int, *, rng: np.random.Generator | None = None,
                      replicates: int = QMC_REPLICATES) -> IntegralEstimate:
    """Randomized quasi-Monte Carlo: ``replicates`` scrambled Sobol sets of 2^m points, m as large as fits."""
    m = int(np.floor(np.log2(max(samples, 1) / replicates)))
    if replicates < 2 or m < 1:
        raise ValueError(f"quasi-Monte Carlo needs at least {2 * max(replicates, 2)} samples "
                         f"({replicates} replicates of 2 or more points), got {samples}")
    rng = np.random.default_rng() if rng is None else rng
    volume = integrand.volume
    points = sampling.sobol(integrand.lower, integrand.upper, m, rng, replicates=replicates)
    if integrand.moments is None:    # one batch of every replicate's points
        means = volume * integrand(points.reshape(-1, integrand.dimension)).reshape(replicates, 2**m, -1).mean(axis=1)
    else:                            # each replicate reduced where it is evaluated
        means = volume * np.array([integrand.mean(replicate) for replicate in points])
    return quasi_monte_carlo_estimate(means, replicates * 2**m)


def quasi_monte_carlo_estimate(means: np.ndarray, evaluations: int) -> IntegralEstimate:
    """The mean of the replicate estimates (replicates, k) and the Student-t half-width of their spread."""
    from scipy.special import stdtrit

    replicates = len(means)
    return IntegralEstimate(values=means.mean(axis=0), evaluations=evaluations, method="qmc",
                            covariance=np.atleast_2d(np.cov(means, rowvar=False)) / replicates,
                            quantile=float(stdtrit(replicates - 1, 0.5 + CONFIDENCE / 2)))


def adaptive_integrator(integrand: Integrand, samples: int, *, rng: np.random.Generator | None = None,
                        rtol: float = 0.0) -> IntegralEstimate:
    """Batched adaptive Genz-Malik cubature (see :func:`symkin.integration.adaptive.adaptive`; ``rng`` is unused)."""
    return adaptive(integrand, samples, rtol=rtol)


#: The integrators by name (``--method`` of ``symkin gci``).
INTEGRATORS: dict[str, Callable[..., IntegralEstimate]] = {
    "grid": midpoint_grid,
    "mc": monte_carlo,
    "qmc": quasi_monte_carlo,
    "adaptive": adaptive_integrator,
}

#: Which integrators give statistical (confidence-interval) errors.
STATISTICAL = ("mc", "qmc")


def integrate(integrand: Integrand, method: str, samples: int, *, seed: int | np.random.Generator | None = None,
              **options) -> IntegralEstimate:
    """Integrate with the integrator named ``method`` (see :data:`INTEGRATORS`).

    Args:
        integrand: what to integrate.
        method: ``grid``, ``mc``, ``qmc`` or ``adaptive``.
        samples: budget of integrand evaluations.
        seed: seed or generator of the random methods (ignored by the deterministic ones).
        options: method-specific options (``replicates`` for qmc, ``rtol`` for adaptive).
    """
    if method not in INTEGRATORS:
        raise ValueError(f"unknown integration method '{method}'; choose one of {', '.join(INTEGRATORS)}")
    return INTEGRATORS[method](integrand, samples, rng=np.random.default_rng(seed), **options)
