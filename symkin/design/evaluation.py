"""Independent evaluation of a design: the true GCI (1/kappa from singular values, seed eq. 8.28)
with an error estimate, and the reachability of the required box, on the generated numpy code.

Nothing here shares code with the optimizer's CasADi surrogate: a serial model is rated by
:func:`symkin.analysis.gci` (randomized QMC over the joint limits, dW = |det J| dq); a
parallel model by the same function on the Cartesian domain of the required box, with the
analyses' reachability test of its closed-form ``ik`` (dW = 1_W(x) dx); a spherical platform by
:func:`symkin.analysis.orientations.orientation_gci` over the box of orientations (1/kappa of the
angular-velocity Jacobian, the invariant measure of SO(3)); legs without closed forms by the mean of 1/kappa
over the cells of a midpoint grid of the box that the working mode reaches, flooded from the home assembly
(:func:`symkin.mechanism.continuation.flood_box`; the error is the change from a grid of half as many cells
a side, as :func:`symkin.analysis.continued_workspace.continued_gci`), the home assembly of each design continued
from the start design's (:func:`continued_home`).  The box is
checked on a vertex grid denser than the optimizer's constraint points: by the closed-form
inverse of :mod:`symkin.analysis.inverse` where one exists, else by the ``ik`` margin.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from symkin.mechanism import feasibility
from symkin.numerics import conditioning, sampling
from symkin.analysis import global_indices, inverse, orientations
from symkin.rating import forces, formulas
from symkin.mechanism import continuation, reach, stops
from symkin import mechanism
from symkin.mechanism import Sampling
from symkin.integration.estimates import Estimate
from symkin.mechanism.limits import within_limits
from symkin.design.problem import DesignProblem, held
from symkin.runtime.info import GeneratedModel

#: Integrand evaluations of the independent GCI (qmc: 16 scrambles of 2^10 points).
EVALUATION_SAMPLES = 2**14
#: Points per axis of the box reachability check.
CHECK_POINTS_PER_AXIS = 11
#: Cells per axis of the grid over the box a continued model's GCI is the mean over (its error: half as many).
CONTINUED_CELLS_PER_AXIS = 16
#: Steps of the design from the start design's home assembly to another design's (:func:`continued_home`).
DESIGN_STEPS = 16
#: Configurations and relative rounding of :func:`scale_invariance`'s test J(s p) = s J(p).
SCALE_TEST_CONFIGURATIONS = 8
SCALE_TEST_TOLERANCE = 1e-12


@dataclass(frozen=True)
class Evaluation:
    """The independent rating of one design.

    Attributes:
        gci: GCI = int 1/kappa dW / int dW with its 95 % confidence half-width.
        measure: int dW (the workspace measure; for a parallel model the reachable volume of the box).
        description: the domain and measure, in words.
        box_reachable: fraction of the box check points that are reachable (None without a box).
        box_check: how the box was checked, in words.
        force: the force objective's isotropic force at the worst reachable check point of the box (N;
            :func:`symkin.rating.forces.isotropic_force`; a serial model's in the first feasible branch of its
            closed-form inverse, else at the optimizer's configurations), else None.
        apparent_mass: under an apparent-mass bound, the largest apparent mass at the handle (the largest
            eigenvalue of (J M^-1 J^T)^-1, kg; :func:`symkin.rating.formulas.principal_masses`) over the reachable
            check points of the box, else None.
    """

    gci: Estimate
    measure: Estimate
    description: str
    box_reachable: float | None
    box_check: str
    force: float | None = None
    apparent_mass: float | None = None


def evaluate(problem: DesignProblem, model: GeneratedModel, design: dict[str, float], *, samples: int = EVALUATION_SAMPLES,
             seed: int = 0, box_points: np.ndarray | None = None,
             box_configurations: np.ndarray | None = None) -> Evaluation:
    """Rate ``design`` (all parameter values) of ``model`` (numpy backend, unbound).

    ``box_points``, ``box_configurations``: the optimizer's box points and a serial model's
    joint configurations at them (:class:`~symkin.design.solving.Solution`), checked by forward
    kinematics when no closed-form inverse applies.
    """
    bound = held(problem, model.bind(**design))
    if problem.sampling is Sampling.CONTINUATION:
        return _continued(problem, bound, continued_home(problem, model, design))
    if problem.sampling is not Sampling.JOINTS:
        return _task_box(problem, bound, samples, seed)
    result = global_indices.gci(bound, method="qmc", samples=samples, seed=seed, limits=problem.limits,
                                length=problem.length)
    fraction, check, reached = _joint_box(problem, bound, box_points, box_configurations)
    force = None
    if problem.effort_limits is not None and reached is not None and len(reached):
        force = float(np.min(forces.isotropic_force(bound.jacobian(reached), problem.effort_limits)))
    return Evaluation(result.value, result.measure, f"qmc, {result.description}", fraction, check, force)


def box_check_points(problem: DesignProblem) -> np.ndarray:
    """The points of the required box that are checked: a vertex grid with the corners."""
    return sampling.grid(*problem.required_box, CHECK_POINTS_PER_AXIS, midpoints=False)


#: Largest distance [m] between fk(q_b) and a box point for the optimizer's configuration to count.
POSITION_TOLERANCE = 1e-9


def _joint_box(problem: DesignProblem, model: GeneratedModel, points: np.ndarray | None,
                configurations: np.ndarray | None) -> tuple[float | None, str, np.ndarray | None]:
    """The fraction of the box reached, how it was checked, and the configurations (k, n) that reach its
    checked points (those of the force rating; None where nothing was checked)."""
    if problem.box is None:
        return None, "no required box", None
    ik = inverse.inverse_kinematics_for(model)
    if ik is None:
        if configurations is None or not configurations.size or points is None:
            return None, "not checked: no closed-form inverse kinematics for this model", None
        error = np.linalg.norm(mechanism.tcp_positions(model, configurations) - points, axis=-1)
        # within the limits up to the analyses' tolerance (IPOPT meets bounds to about 1e-8 relative)
        _, in_limits = within_limits(configurations, problem.joint_limits, mechanism.revolute_mask(model))
        inside = (error < POSITION_TOLERANCE) & in_limits & stops.respected(model, configurations)
        return float(np.mean(inside)), (f"the optimizer's configurations at {len(points)} box points, by the "
                                        "generated fk (no closed-form inverse kinematics for this model)"), \
            configurations[inside]
    points = box_check_points(problem)
    q, inside = feasibility.feasible_configurations(ik, points, problem.joint_limits, mechanism.revolute_mask(model),
                                                    stops.StopInequalities.of_model(model))
    return (float(np.mean(inside)), f"closed-form inverse kinematics within the joint limits at {len(points)} points "
            "(the first feasible branch)", q[inside])


def inverse_index(model: GeneratedModel, points: np.ndarray, limits: np.ndarray | None,
                  length: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """1/kappa of J at each point (0 where unreachable), and whether it is reachable: by the
    analyses' own test (:func:`symkin.mechanism.reach.generated_inverse`: IK margin, fk round
    trip, declared passive-joint limits) within the actuated-joint ``limits``; a spherical
    platform's orientations by :func:`symkin.analysis.orientations.orientation_integrand` (1/kappa
    of J_w).  ``length``: a platform held at a constant orientation has its twist Jacobian's position rows
    divided by it (:func:`symkin.numerics.conditioning.homogenize`)."""
    if mechanism.turns_only(model):
        return orientations.reachable_index(model, points, limits)
    ik = reach.generated_inverse(model)
    q, inside = feasibility.feasible_configurations(ik, points, mechanism.joint_limits(model, limits),
                                                    mechanism.revolute_mask(model), stops.StopInequalities.of_model(model))
    values = np.zeros(len(points))
    if inside.any():
        J = model.jacobian(q[inside], points[inside])
        if length is not None:
            J = conditioning.homogenize(J, length, mechanism.position_rows(model))
        values[inside] = conditioning.inverse_condition_number(J)
    return values, inside


def _spherical(problem: DesignProblem, model: GeneratedModel, samples: int, seed: int) -> Evaluation:
    result = orientations.orientation_gci(model, method="qmc", samples=samples, seed=seed, box=problem.required_box,
                                          limits=problem.limits)
    points = box_check_points(problem)
    inside = inverse_index(model, points, problem.limits)[1]
    return Evaluation(result.value, result.measure, f"qmc over the required box, {result.description}",
                      float(np.mean(inside)), f"closed-form ik within the joint limits at {len(points)} orientations")


def _task_box(problem: DesignProblem, model: GeneratedModel, samples: int, seed: int) -> Evaluation:
    if problem.sampling is Sampling.ORIENTATIONS:
        return _spherical(problem, model, samples, seed)
    ik = reach.generated_inverse(model)
    result = global_indices.gci(model, method="qmc", samples=samples, seed=seed, domain="cartesian", inverse=ik,
                                box=problem.box, limits=problem.limits, length=problem.length)
    points = box_check_points(problem)
    q, inside = feasibility.feasible_configurations(ik, points, mechanism.joint_limits(model, problem.limits),
                                                    mechanism.revolute_mask(model), stops.StopInequalities.of_model(model))
    force = mass = None
    J = model.jacobian(q[inside], points[inside]) if inside.any() else None
    if problem.effort_limits is not None and J is not None:
        force = float(np.min(forces.isotropic_force(J, problem.effort_limits)))
    if problem.max_apparent_mass is not None and J is not None:
        mass = float(np.max(formulas.principal_masses(model.mass_matrix(q[inside], points[inside]), J)))
    return Evaluation(result.value, result.measure, f"qmc over the required box, {result.description}",
                      float(np.mean(inside)), f"closed-form ik (margin, fk round trip, joint limits) at {len(points)} "
                      "points", force, mass)


def continued_home(problem: DesignProblem, model: GeneratedModel, design: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """(q, s) of the home assembly of ``design`` (all parameter values; ``model`` unbound), continued from the
    start design's along the straight line of designs (:func:`symkin.mechanism.continuation.home_along_designs`), so
    that every design is rated in the assembly mode the optimizer started in (a fresh multi-start assembly may pick
    another).

    Raises:
        ValueError: the legs stop closing at the home pose on the way (a design that does not reach it).
    """
    return continuation.home_along_designs(model, problem.start, design, DESIGN_STEPS)


def _continued(problem: DesignProblem, model: GeneratedModel, home: tuple[np.ndarray, np.ndarray]) -> Evaluation:
    """A continued model's GCI over the working mode's cells in the box, and the reachable share of the box."""
    lower, upper = problem.required_box
    rated = []
    for per_axis in (CONTINUED_CELLS_PER_AXIS, CONTINUED_CELLS_PER_AXIS // 2):
        flood = continuation.flood_box(model, lower, upper, (per_axis,) * len(lower), start=home,
                                       limits=problem.limits)
        reached = flood.reached
        local = continuation.conditioning_at(model, flood.q[reached], flood.s[reached], flood.poses[reached],
                                             problem.length)
        rated.append((float(np.mean(local.inv_kappa)) if reached.any() else 0.0, float(np.mean(reached)),
                      len(reached)))
    (gci, share, cells), (coarse_gci, coarse_share, coarse_cells) = rated
    volume = float(np.prod(upper - lower))
    check = continuation.flood_box(model, lower, upper, (CHECK_POINTS_PER_AXIS,) * len(lower), start=home,
                                   vertices=True, limits=problem.limits)
    held = "" if problem.length is None else f", position rows divided by L = {problem.length:g} m"
    return Evaluation(Estimate(gci, abs(gci - coarse_gci), cells + coarse_cells, "grid", False),
                      Estimate(share * volume, abs(share - coarse_share) * volume, cells + coarse_cells, "grid", False),
                      f"mean 1/kappa over the working mode's cells of a {CONTINUED_CELLS_PER_AXIS}^{len(lower)} grid of "
                      f"the required box (flooded from the home assembly; error: the change from "
                      f"{CONTINUED_CELLS_PER_AXIS // 2}^{len(lower)} cells{held})",
                      float(np.mean(check.reached)),
                      f"the working mode flooded over a {CHECK_POINTS_PER_AXIS}^{len(lower)} vertex grid of the box "
                      "from the home assembly (closure solved from a neighbour, within the limits, no singularity "
                      "crossed)")


def scale_invariance(problem: DesignProblem, model: GeneratedModel) -> tuple[str, ...]:
    """The free lengths whose common scaling leaves the objective unchanged, or (): the GCI of a model sampled in its
    joint box (revolute joints only), without a required box or characteristic length, whose Jacobian scales with them,
    J(s p) = s J(p) (tested at a few configurations of the box: a length folded into the code would break it).  Then
    kappa does not change and the measure's weights |det J| all scale by s^n (seed eq. 8.28 is a ratio of integrals):
    the optimum is a ray of designs, of which the optimizer returns one; only the lengths' ratios were optimized."""
    if (problem.objective != "gci" or problem.sampling is not Sampling.JOINTS or problem.box is not None
            or problem.length is not None or not mechanism.revolute_mask(model).all()):
        return ()
    lengths = tuple(name for name in problem.names if model.info.units.get(name) == "m")
    if not lengths:
        return ()
    lower, upper = problem.joint_limits[:, 0], problem.joint_limits[:, 1]
    q = lower + (upper - lower) * np.random.default_rng(0).random((SCALE_TEST_CONFIGURATIONS, len(lower)))
    design = problem.start
    J = np.asarray(model.bind(**design).jacobian(q))
    scaled = np.asarray(model.bind(**{**design, **{name: 2.0 * design[name] for name in lengths}}).jacobian(q))
    flat = np.max(np.abs(scaled - 2.0 * J)) <= SCALE_TEST_TOLERANCE * np.max(np.abs(J))
    return lengths if flat else ()
