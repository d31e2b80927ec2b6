"""Independent evaluation of a design: the true GCI (1/kappa from singular values, seed eq. 8.28)
with an error estimate, and the reachability of the required box, on the generated numpy code.

Nothing here shares code with the optimizer's CasADi surrogate: a serial model is rated by
:func:`symkin.analysis.gci` (randomized QMC over the joint limits, dW = |det J| dq); a
parallel model by the same integrator over the required box, with the reachability
indicator of its closed-form ``ik`` and actuated-joint limits, if any (dW = 1_W(x) dx,
the Cartesian measure).  The box is
checked on a vertex grid denser than the optimizer's constraint points: by the closed-form
inverse of :mod:`symkin.analysis.inverse` where one exists, else by the ``ik`` margin.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin.analysis import conditioning, global_indices, inverse, mechanism, sampling
from symkin.analysis.estimates import Estimate
from symkin.analysis.integrand import Integrand
from symkin.analysis.integrators import integrate
from symkin.design.problem import DesignProblem

#: Integrand evaluations of the independent GCI (qmc: 16 scrambles of 2^10 points).
EVALUATION_SAMPLES = 2**14
#: Points per axis of the box reachability check.
CHECK_POINTS_PER_AXIS = 11


@dataclass(frozen=True)
class Evaluation:
    """The independent rating of one design.

    Attributes:
        gci: GCI = int 1/kappa dW / int dW with its 95 % confidence half-width.
        measure: int dW (the workspace measure; for a parallel model the reachable volume of the box).
        description: the domain and measure, in words.
        box_reachable: fraction of the box check points that are reachable (None without a box).
        box_check: how the box was checked, in words.
    """

    gci: Estimate
    measure: Estimate
    description: str
    box_reachable: float | None
    box_check: str


def evaluate(problem: DesignProblem, model: Any, design: dict[str, float], *, samples: int = EVALUATION_SAMPLES,
             seed: int = 0, box_configurations: np.ndarray | None = None) -> Evaluation:
    """Rate ``design`` (all parameter values) of ``model`` (numpy backend, unbound).

    ``box_configurations``: a serial model's joint configurations at the optimizer's box
    points, checked by forward kinematics when no closed-form inverse applies.
    """
    bound = model.bind(**design)
    if problem.parallel:
        return _parallel(problem, bound, samples, seed)
    result = global_indices.gci(bound, method="qmc", samples=samples, seed=seed, limits=problem.limits,
                                length=problem.length)
    fraction, check = _serial_box(problem, bound, box_configurations)
    return Evaluation(result.value, result.measure, f"qmc, {result.description}", fraction, check)


def box_check_points(problem: DesignProblem) -> np.ndarray:
    """The points of the required box that are checked: a vertex grid with the corners."""
    assert problem.box is not None
    return sampling.grid(*problem.box, CHECK_POINTS_PER_AXIS, midpoints=False)


#: Largest distance [m] between fk(q_b) and a box point for the optimizer's configuration to count.
POSITION_TOLERANCE = 1e-9


def _serial_box(problem: DesignProblem, model: Any, configurations: np.ndarray | None) -> tuple[float | None, str]:
    if problem.box is None:
        return None, "no required box"
    ik = inverse.inverse_kinematics_for(model)
    if ik is None:
        if configurations is None or not configurations.size:
            return None, "not checked: no closed-form inverse kinematics for this model"
        points = sampling.grid(*problem.inflated_box, round(len(configurations) ** (1 / problem.box[0].size)),
                               midpoints=False)
        error = np.linalg.norm(mechanism.tcp_positions(model, configurations) - points, axis=-1)
        inside = (error < POSITION_TOLERANCE) & np.all((configurations >= problem.limits[:, 0])
                                                       & (configurations <= problem.limits[:, 1]), axis=-1)
        return float(np.mean(inside)), (f"the optimizer's configurations at {len(points)} box points, by the "
                                        "generated fk (no closed-form inverse kinematics for this model)")
    points = box_check_points(problem)
    inside = inverse.reachable(ik, points, problem.limits, mechanism.revolute_mask(model))
    return float(np.mean(inside)), f"closed-form inverse kinematics within the joint limits at {len(points)} points"


def parallel_reachable(model: Any, points: np.ndarray, limits: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """Joints (N, n) of the closed-form ``ik`` and whether each point is reachable (within ``limits``, if any)."""
    with np.errstate(invalid="ignore"):  # the square root of a negative margin: NaN joints, unreachable
        q, margin = model.ik(points)
    inside = np.all(margin >= 0, axis=-1) & np.all(np.isfinite(q), axis=-1)
    if limits is not None:
        inside &= np.all((q >= limits[:, 0]) & (q <= limits[:, 1]), axis=-1)
    return q, inside


def parallel_index(model: Any, points: np.ndarray, limits: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """1/kappa of J at each point (0 where unreachable), and whether it is reachable."""
    q, inside = parallel_reachable(model, points, limits)
    values = np.zeros(len(points))
    if inside.any():
        values[inside] = conditioning.inverse_condition_number(model.jacobian(q[inside], points[inside]))
    return values, inside


def _parallel(problem: DesignProblem, model: Any, samples: int, seed: int) -> Evaluation:
    lower, upper = problem.box

    def function(points: np.ndarray) -> np.ndarray:
        values, inside = parallel_index(model, points, problem.limits)
        return np.stack([values, inside.astype(np.float64)], axis=-1)

    axes = tuple("xyz"[a] for a in mechanism.position_axes(model))
    integrand = Integrand(lower, upper, function, ("1/kappa dW", "dW"), axes, indicator=1)
    result = integrate(integrand, "qmc", samples, seed=seed)
    points = box_check_points(problem)
    fraction = float(np.mean(parallel_reachable(model, points, problem.limits)[1]))
    return Evaluation(result.ratio(0, 1), result.component(1),
                      "qmc over the required box, dW = 1_W(x) dx (reachable by the closed-form ik)", fraction,
                      f"closed-form ik margin at {len(points)} points")
