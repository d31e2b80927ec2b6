"""Run time against error of the GCI integrators (``symkin bench gci``, benchmarks/bench_gci.py).

Each integrator runs at a ladder of budgets; for each run the wall time, the estimate,
its error estimate and the achieved error against a high-accuracy reference are
recorded.  The reference is the batched adaptive Genz-Malik cubature of the joint-space
formulation at a tight tolerance (the integrand is smooth there, so its error estimate
is reliable), reported with its own error estimate.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from symkin.integration.estimates import Estimate
from symkin.analysis.global_indices import gci
from symkin.runtime.info import GeneratedModel

#: Default budgets: 2^8 ... 2^20 integrand evaluations, a factor 4 apart.
DEFAULT_BUDGETS = tuple(4**k for k in range(4, 11))

#: Budget and tolerance of the reference computation.
REFERENCE_SAMPLES = 2**21
REFERENCE_RTOL = 1e-13


@dataclass(frozen=True)
class Trial:
    """One integrator run.

    Attributes:
        backend: the generated code that was timed (``numpy``, ``c``...).
        domain: ``joint`` or ``cartesian``.
        method: integrator name.
        samples: requested budget.
        evaluations: integrand evaluations actually spent.
        seconds: wall time (best of the repeats).
        estimate: the GCI and its error estimate.
        achieved: |estimate - reference|.
    """

    backend: str
    domain: str
    method: str
    samples: int
    evaluations: int
    seconds: float
    estimate: Estimate
    achieved: float

    @property
    def bracketed(self) -> bool:
        """Whether the error estimate covers the achieved error."""
        return self.achieved <= self.estimate.error


def reference_gci(model: GeneratedModel, *, samples: int = REFERENCE_SAMPLES, rtol: float = REFERENCE_RTOL, **kwargs) -> Estimate:
    """High-accuracy GCI: adaptive cubature over joint space with the Cartesian measure.

    Keyword arguments go to :func:`symkin.analysis.global_indices.gci` (limits, length, index).
    """
    return gci(model, method="adaptive", samples=samples, rtol=rtol, domain="joint", measure="cartesian",
               **kwargs).value


def _warm_up(model: GeneratedModel, methods: Sequence[str], domains: Sequence[str], seed: int, kwargs: dict) -> None:
    """One small run of each integrator, so that one-time imports (scipy.special) are not timed."""
    for domain in domains:
        for method in methods:
            gci(model, method=method, samples=512, seed=seed, domain=domain, **kwargs)


def time_against_error(model: GeneratedModel, reference: Estimate, *, methods: Sequence[str], budgets: Sequence[int] = DEFAULT_BUDGETS,
                       domains: Sequence[str] = ("joint",), repeats: int = 3, seed: int = 0,
                       progress: Callable[[str], None] | None = None, **kwargs) -> list[Trial]:
    """Run every integrator at every budget, timed against ``reference``.

    Args:
        model: a loaded model (its backend is what is timed).
        reference: the reference value (see :func:`reference_gci`).
        methods: integrators to run.
        budgets: integrand evaluations per run.
        domains: ``joint`` and/or ``cartesian`` (the latter needs ``inverse=``; its box
            is computed once, before the timed runs, unless ``box=`` is given).
        repeats: runs per point; the fastest wall time is kept (the estimate is the same
            for a given seed).
        seed: seed of the random integrators.
        progress: called with a description of each run.
        kwargs: more arguments of :func:`symkin.analysis.global_indices.gci` (limits, inverse, box...).
    """
    if "cartesian" in domains and kwargs.get("box") is None:
        # The Cartesian box is found once (joint grid through fk), not timed in every run.
        from symkin.mechanism.reach import bounding_box

        kwargs["box"] = bounding_box(model, limits=kwargs.get("limits"))
    _warm_up(model, methods, domains, seed, kwargs)
    trials = []
    for domain in domains:
        for method in methods:
            for samples in budgets:
                if progress is not None:
                    progress(f"{domain} {method} {samples} samples")
                best = float("inf")
                for _ in range(repeats):
                    start = time.perf_counter()
                    result = gci(model, method=method, samples=samples, seed=seed, domain=domain, **kwargs)
                    best = min(best, time.perf_counter() - start)
                estimate = result.value
                trials.append(Trial(model.backend, domain, method, samples, estimate.evaluations, best, estimate,
                                    abs(estimate.value - reference.value)))
    return trials


def fastest_within(trials: Sequence[Trial], relative_error: float) -> dict[tuple[str, str, str], Trial | None]:
    """For each (backend, domain, method), the fastest trial whose achieved error is within ``relative_error``.

    The achieved error is relative to the reference value (|estimate - reference| /
    |reference|, computed from the trial's ``achieved`` and its estimate).
    """
    best: dict[tuple[str, str, str], Trial | None] = {}
    for t in trials:
        key = (t.backend, t.domain, t.method)
        best.setdefault(key, None)
        reference = abs(t.estimate.value) or 1.0
        current = best[key]
        if t.achieved <= relative_error * reference and (current is None or t.seconds < current.seconds):
            best[key] = t
    return best
