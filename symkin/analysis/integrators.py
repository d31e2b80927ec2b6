"""Integrators of a vector integrand over a box, each with an error estimate.

All take an :class:`~symkin.analysis.integrand.Integrand` and a budget ``samples`` (the
number of integrand evaluations to spend, approximately for the grid) and return an
:class:`~symkin.analysis.estimates.IntegralEstimate`:

* ``grid``: the tensor midpoint rule on n^d cells (n even) and, for the error, on (n/2)^d
  cells; the error estimate is the difference of the two (for a smooth integrand the
  midpoint rule's error falls as h^2, so the difference is about 3 times the fine
  rule's error: a safe estimate; for a discontinuous one it falls as h and the estimate
  is of the right size but not a bound);
* ``mc``: plain Monte Carlo with uniform points; standard error from the sample
  covariance, 95 % normal confidence half-width;
* ``qmc``: randomized quasi-Monte Carlo: ``replicates`` independently scrambled Sobol
  point sets of 2^m points each (scipy.stats.qmc); the estimate is their mean and the
  error the 95 % Student-t half-width from their spread (Owen, "Monte Carlo theory,
  methods and examples", ch. 17);
* ``adaptive``: batched adaptive Genz-Malik cubature (:mod:`symkin.analysis.adaptive`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from symkin.analysis import sampling
from symkin.analysis.adaptive import adaptive
from symkin.analysis.estimates import CONFIDENCE, IntegralEstimate
from symkin.analysis.integrand import Integrand

#: Independent scramblings of the quasi-Monte Carlo integrator.
QMC_REPLICATES = 16


def grid(integrand: Integrand, samples: int, *, rng: np.random.Generator | None = None) -> IntegralEstimate:
    """Tensor midpoint rule with the coarse-grid difference as error estimate (``rng`` is unused)."""
    d = integrand.dimension
    n = 2
    while (n + 2) ** d * (1 + 0.5**d) <= samples:
        n += 2
    fine = integrand.volume * integrand(sampling.grid(integrand.lower, integrand.upper, n)).mean(axis=0)
    coarse = integrand.volume * integrand(sampling.grid(integrand.lower, integrand.upper, n // 2)).mean(axis=0)
    return IntegralEstimate(values=fine, evaluations=n**d + (n // 2) ** d, method="grid", coarse=coarse)


def monte_carlo(integrand: Integrand, samples: int, *, rng: np.random.Generator | None = None) -> IntegralEstimate:
    """Plain Monte Carlo with uniform random points."""
    from scipy.stats import norm

    if samples < 2:
        raise ValueError("Monte Carlo needs at least 2 samples")
    rng = np.random.default_rng() if rng is None else rng
    f = integrand(sampling.uniform(integrand.lower, integrand.upper, samples, rng))
    volume = integrand.volume
    covariance = np.atleast_2d(np.cov(f, rowvar=False)) * volume**2 / samples
    return IntegralEstimate(values=volume * f.mean(axis=0), evaluations=samples, method="mc",
                            covariance=covariance, quantile=float(norm.ppf(0.5 + CONFIDENCE / 2)))


def quasi_monte_carlo(integrand: Integrand, samples: int, *, rng: np.random.Generator | None = None,
                      replicates: int = QMC_REPLICATES) -> IntegralEstimate:
    """Randomized quasi-Monte Carlo: ``replicates`` scrambled Sobol sets of 2^m points, m as large as fits."""
    from scipy.stats import t

    m = int(np.floor(np.log2(max(samples, 1) / replicates)))
    if replicates < 2 or m < 1:
        raise ValueError(f"quasi-Monte Carlo needs at least {2 * max(replicates, 2)} samples "
                         f"({replicates} replicates of 2 or more points), got {samples}")
    rng = np.random.default_rng() if rng is None else rng
    volume = integrand.volume
    means = np.array([volume * integrand(sampling.sobol(integrand.lower, integrand.upper, m, rng)).mean(axis=0)
                      for _ in range(replicates)])
    covariance = np.atleast_2d(np.cov(means, rowvar=False)) / replicates
    return IntegralEstimate(values=means.mean(axis=0), evaluations=replicates * 2**m, method="qmc",
                            covariance=covariance, quantile=float(t.ppf(0.5 + CONFIDENCE / 2, replicates - 1)))


def adaptive_integrator(integrand: Integrand, samples: int, *, rng: np.random.Generator | None = None,
                        rtol: float = 0.0) -> IntegralEstimate:
    """Batched adaptive Genz-Malik cubature (see :func:`symkin.analysis.adaptive.adaptive`; ``rng`` is unused)."""
    return adaptive(integrand, samples, rtol=rtol)


#: The integrators by name (``--method`` of ``symkin gci``).
INTEGRATORS: dict[str, Callable[..., IntegralEstimate]] = {
    "grid": grid,
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
