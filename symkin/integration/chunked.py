"""The GCI integrators in chunks of points, on Dask: budgets beyond memory (10^9 points and more).

:func:`~symkin.integration.integrators.quasi_monte_carlo` and
:func:`~symkin.integration.integrators.monte_carlo` draw every point at once.  Here the budget is
cut into chunks of at most ``chunk`` points; each chunk is a task
(:func:`symkin.runtime.cluster.run_tasks`: a LocalCluster, a cluster, or this process) that
draws its own points from the definition alone, evaluates the integrand on the worker (rebuilt
there from the model's :class:`~symkin.runtime.payload.ModelPayload` and an
:class:`IntegrandSpec`) and returns the moments of its values, so memory is bounded by the chunk size on
every machine:

* ``qmc``: replicate r is the scrambled Sobol sequence of 2^m points whose scrambling comes
  from the seed sequence (seed, r) (:class:`~symkin.numerics.sobol.Sobol`, its points k0 ... k1
  drawn alone); as in :func:`~symkin.numerics.sampling.sobol`, the digits below its 30 bits
  are uniform random, here from the generator (seed, r, k0) of the chunk.  A task
  returns the moments of f over its points (below); the replicate means and the Student-t half-width of their
  spread are those of the in-memory integrator (Owen, "Monte Carlo theory, methods and
  examples", ch. 17);
* ``mc``: chunk c draws its uniform points from the generator (seed, c) and returns the moments of f
  (count, mean, scatter): the mean and the covariance of the mean (95 % normal half-width).

A chunk reduces its values to their moments where they are evaluated
(:meth:`~symkin.integration.integrand.Integrand.reduce`): on a worker's JAX device for a payload of
JAX code whose integrand the device decides (:meth:`IntegrandSpec.build`), so that only k + k^2 numbers
come back from it, or from the values on the worker.  The chunks' moments are combined in chunk order
(Chan, Golub and LeVeque's pairwise update, :func:`~symkin.integration.integrand.combined`), so for a
given chunk size the estimate does not depend on where or in which order the chunks ran (tested: serial and on a 2-worker
LocalCluster agree to the bit); another chunk size draws other low digits.
The chunked estimates are not bit-identical to the in-memory ones (their random streams
differ) but estimate the same integrals with the same error model (tested within the error bars).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin.integration.estimates import IntegralEstimate
from symkin.integration.integrand import Integrand, Moments, combined
from symkin.integration.integrators import QMC_REPLICATES, monte_carlo_estimate, quasi_monte_carlo_estimate
from symkin.numerics.sampling import sobol_range
from symkin.runtime.cluster import run_tasks
from symkin.runtime.payload import ModelPayload

#: points per task unless told otherwise (2^20 points of a 6-joint arm: about 0.1 GB of Jacobians)
CHUNK = 2**20
METHODS = ("qmc", "mc")


@dataclass(frozen=True)
class IntegrandSpec:
    """What a worker needs besides the model to rebuild the integrand: that of
    :func:`~symkin.analysis.global_indices.joint_space_integrand` (the joint domain) or of
    :func:`~symkin.analysis.global_indices.cartesian_integrand` (a Cartesian box, reachability by
    the model's inverse kinematics).

    Attributes:
        parameters: parameter values the model is bound to ((name, value) pairs).
        index: name of a :mod:`symkin.numerics.conditioning` function (None: the measure alone).
        measure: ``cartesian`` (dW = |det J| dq) or ``joint`` (joint domain only).
        limits: joint-limit overrides ((joint, (lower, upper)) pairs).
        length: characteristic length for a task space that mixes translations and rotations.
        domain: ``joint`` or ``cartesian``.
        box: the Cartesian box ((lower...), (upper...)), computed once by the caller (Cartesian domain).
        orientation: roll, pitch, yaw of a rotating platform held at a constant orientation, or None.
    """

    parameters: tuple[tuple[str, float], ...] = ()
    index: str | None = "inverse_condition_number"
    measure: str = "cartesian"
    limits: tuple[tuple[str, tuple[float, float]], ...] = ()
    length: float | None = None
    domain: str = "joint"
    box: tuple[tuple[float, ...], tuple[float, ...]] | None = None
    orientation: tuple[float, float, float] | None = None

    def build(self, model: Any) -> Integrand:
        """The integrand of ``model`` (loaded on the worker) where it is evaluated: fused on JAX's device for a
        model loaded with the JAX backend that the device decides (:func:`~symkin.analysis.global_indices.
        joint_space_integrand_for`, :func:`~symkin.analysis.global_indices.cartesian_integrand_for`), else here."""
        from symkin.numerics import conditioning
        from symkin.analysis import inverse
        from symkin.analysis.global_indices import cartesian_integrand_for, joint_space_integrand_for
        from symkin.mechanism import reach

        bound = model.bind(**dict(self.parameters)) if self.parameters else model
        index = getattr(conditioning, self.index) if self.index is not None else None
        limits = dict(self.limits) or None
        if self.domain == "joint":
            return joint_space_integrand_for(bound, index=index, measure=self.measure, limits=limits,
                                             length=self.length)
        held = reach.held_at(bound, self.orientation)
        ik = inverse.inverse_kinematics_for(held)
        if ik is None or self.box is None:
            raise ValueError(f"{model.name}: the Cartesian domain needs an inverse kinematics and a box")
        box = (np.array(self.box[0], dtype=float), np.array(self.box[1], dtype=float))
        return cartesian_integrand_for(held, ik, box, index=index, limits=limits, length=self.length)


def _qmc_chunk(payload: ModelPayload, spec: IntegrandSpec, seed: int, replicate: int, start: int,
               stop: int) -> Moments:
    """The moments of f over points start ... stop - 1 of replicate ``replicate`` (see the module docstring)."""
    integrand = spec.build(payload.load())
    unit = sobol_range(integrand.dimension, (seed, replicate), start, stop)
    with np.errstate(all="ignore"):
        return integrand.reduce(integrand.lower + unit * (integrand.upper - integrand.lower))


def _mc_chunk(payload: ModelPayload, spec: IntegrandSpec, seed: int, chunk: int, count: int) -> Moments:
    """The moments of f over ``count`` uniform points from the generator (seed, chunk)."""
    integrand = spec.build(payload.load())
    unit = np.random.default_rng([seed, chunk]).random((count, integrand.dimension))
    with np.errstate(all="ignore"):
        return integrand.reduce(integrand.lower + unit * (integrand.upper - integrand.lower))


def integrate_chunked(payload: ModelPayload, spec: IntegrandSpec, method: str, samples: int, *, seed: int = 0,
                      chunk: int = CHUNK, replicates: int = QMC_REPLICATES, scheduler: str = "local",
                      workers: int | None = None, client: Any = None,
                      progress: Callable[[int, int], None] = lambda done, total: None) -> IntegralEstimate:
    """Integrate the integrand of ``spec`` (its joint limits or Cartesian box) with ``samples`` points in chunks.

    Args:
        method: ``qmc`` (replicates x 2^m points, m as large as fits the budget) or ``mc``.
        chunk: points per task at most.
        scheduler, workers, client: where the tasks run (:func:`symkin.runtime.cluster.run_tasks`).
        progress: called with (points done, points in all) as chunks complete.
    """
    if method not in METHODS:
        raise ValueError(f"chunked integration: method '{method}' is not one of {', '.join(METHODS)}")
    if chunk < 1:
        raise ValueError("the chunk size must be at least one point")
    volume = spec.build(payload.load()).volume
    if method == "qmc":
        m = int(math.floor(math.log2(max(samples, 1) / replicates)))
        if replicates < 2 or m < 1:
            raise ValueError(f"quasi-Monte Carlo needs at least {2 * max(replicates, 2)} samples, got {samples}")
        size = 2**m
        tasks: list[tuple[Any, ...]] = [(spec, seed, r, k, min(size, k + chunk)) for r in range(replicates)
                                        for k in range(0, size, chunk)]
        total = replicates * size
        counts = [task[4] - task[3] for task in tasks]
        function: Callable[..., Any] = _qmc_chunk
    else:
        if samples < 2:
            raise ValueError("Monte Carlo needs at least 2 samples")
        counts = [min(chunk, samples - k) for k in range(0, samples, chunk)]
        tasks = [(spec, seed, c, count) for c, count in enumerate(counts)]
        total = samples
        function = _mc_chunk
    results: dict[int, Any] = {}
    done = 0

    def finished(i: int, result: Any) -> None:
        nonlocal done
        results[i] = result
        done += counts[i]
        progress(done, total)

    run_tasks(function, tasks, shared=payload, name=f"symkin-integrate-{payload.digest[:12]}-{method}-{seed}",
              finished=finished, scheduler=scheduler, workers=workers, client=client)
    ordered: list[Moments] = [results[i] for i in range(len(tasks))]
    components = len(ordered[0].mean)
    if method == "qmc":
        means = [combined([part for task, part in zip(tasks, ordered) if task[2] == r], components).mean
                 for r in range(replicates)]
        return quasi_monte_carlo_estimate(volume * np.array(means), total)
    union = combined(ordered, components)
    return monte_carlo_estimate(volume, union.mean, union.scatter / (samples - 1), samples)
