"""Dimensioning with JAX gradients: L-BFGS-B on the smooth surrogate, its gradient by jax.value_and_grad through the
generated JAX code (issue 66, "gradients for design"; ``symkin optimize --gradients jax``).

The alternative to the CasADi program (:mod:`symkin.design.formulation`, IPOPT with exact Hessians) for the problems
that have bounds only: a serial model's GCI or workspace over its joint box, no required box.  It optimizes the
same function - the same fixed Sobol nodes (:func:`symkin.design.formulation.joint_nodes`), the same Frobenius
surrogate with the same smoothed |det J| in the denominator:

    v_F(p) = sum_j |det J_j| / kappa_F(J_h,j)  /  sum_j sqrt(det_j^2 + eps^2),   eps^2 = 1e-6 mean_j det_j^2

(1/kappa_F = n / (||J_h||_F ||J_h^-1||_F), J_h the homogenized Jacobian), or the workspace estimate
sum_j sqrt(det_j^2 + eps^2) vol / N - on the free parameters scaled to order one (value / start), with the value
and its gradient from one compiled XLA program per generated Jacobian
(:func:`symkin.analysis.device_integrand.compiled_surrogate_gradient`: the nodes and the parameters are its
arguments).  scipy's L-BFGS-B (Byrd, Lu, Nocedal and Zhu 1995) keeps the parameters within their bounds.  A node
where J^T J is exactly singular makes the value NaN (1/kappa_F is written with ||J^-1||_F): the solve refuses it
and names the CasADi path, whose surrogate is written with adj J.

A parallel model with a closed-form ik and a required box takes SLSQP with the reach constraints
(:mod:`symkin.design.box_gradient_solving`: its GCI, and its worst isotropic force in epigraph form; an apparent-mass
bound at the handle too).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from symkin import reporting
from symkin.analysis import device_integrand
from symkin.design import box_gradient_solving
from symkin.design.formulation import DETERMINANT_SMOOTHING, joint_nodes
from symkin.design.problem import DesignProblem
from symkin.design.solving import Solution
from symkin.mechanism import Sampling
from symkin.runtime.info import GeneratedModel

#: The objectives the JAX path optimizes (those of a serial model's joint box without a required box).
OBJECTIVES = ("gci", "workspace")
#: The objectives the JAX path optimizes over a parallel model's required box.
BOX_OBJECTIVES = ("gci", "force")
#: The ways of sampling whose GCI over a required box the JAX path optimizes (a parallel model's closed-form ik).
INVERSE_SAMPLINGS = (Sampling.INVERSE, Sampling.ORIENTATIONS)
#: L-BFGS-B's options: the problems are small and smooth; stop on a relative objective change below ~eps or a
#: projected gradient below 1e-10 of the (order one) scaled objective.
LBFGSB_OPTIONS: dict[str, Any] = {"maxiter": 300, "ftol": 1e-15, "gtol": 1e-10}


def refusal(problem: DesignProblem, jax_model: GeneratedModel) -> str | None:
    """Why the JAX path cannot solve the problem (and what to use instead), or None when it can."""
    fix = "; use the CasADi program (--gradients casadi, the default)"
    if problem.sampling in INVERSE_SAMPLINGS:
        if problem.objective not in BOX_OBJECTIVES:
            return (f"JAX gradients optimize a parallel model's {' or '.join(BOX_OBJECTIVES)} over its required box, "
                    f"not the {problem.objective} objective{fix}")
        jacobian = "jacobian" if problem.orientation is None else "inverse_jacobian"  # a held pose platform's
        needed = ("ik", jacobian) + (() if problem.max_apparent_mass is None else ("mass_matrix",))
        if not set(needed) <= set(jax_model.functions) or not device_integrand.loaded_with_jax(jax_model):
            return (f"{jax_model.name}: JAX gradients need the model's JAX {', '.join(needed)} (derive them with "
                    "--backend numpy,jax, or load the model with backend='jax')")
        return None
    if problem.sampling != Sampling.JOINTS or problem.objective not in OBJECTIVES:
        return (f"JAX gradients optimize a serial model's {' or '.join(OBJECTIVES)} over its joint limits or a "
                f"parallel model's gci over its required box with a closed-form ik, not the {problem.objective} of "
                f"this model{fix}")
    if problem.box is not None:
        return f"JAX gradients optimize within the parameters' bounds only, not with a required workspace box{fix}"
    if not device_integrand.jacobian_of_joints_on_device(jax_model):
        return (f"{jax_model.name}: JAX gradients need the model's JAX code (derive it with --backend numpy,jax, or "
                "load it with backend='jax')")
    return None


def solve_with_jax(problem: DesignProblem, jax_model: GeneratedModel, numpy_model: GeneratedModel, *,
                   nodes: int | None = None, seed: int = 0, options: dict[str, Any] | None = None) -> tuple[Solution, str]:
    """Maximize the problem's surrogate with L-BFGS-B and JAX gradients (see the module docstring).

    Args:
        problem: from :func:`symkin.design.problem.design_problem` (a serial model's gci or workspace, no box; a
            parallel model's gci over its required box).
        jax_model: the model loaded with ``backend="jax"``; numpy_model: the same with numpy (its joint stops).
        nodes: serial: log2 of the Sobol node count (default :data:`symkin.design.formulation.JOINT_NODES_LOG2`);
            parallel: grid points per axis of the box (default :data:`symkin.design.formulation.GRID_POINTS_PER_AXIS`).
        seed: seed of the nodes (the CasADi program's with the same seed are the same).
        options: overrides of :data:`LBFGSB_OPTIONS` (:data:`symkin.design.box_gradient_solving.SLSQP_OPTIONS` for a parallel model).

    Returns:
        (the solution, the surrogate and its domain in words).

    Raises:
        ValueError: a problem the JAX path does not solve (:func:`refusal`), or a surrogate that is not finite and
            positive at the start.
    """
    import jax.numpy as jnp
    from scipy import optimize

    why = refusal(problem, jax_model)
    if why is not None:
        raise ValueError(why)
    if problem.sampling in INVERSE_SAMPLINGS and problem.objective == "force":
        return box_gradient_solving.solve_force_over_the_box(problem, jax_model, numpy_model, nodes, options)
    if problem.sampling in INVERSE_SAMPLINGS:
        return box_gradient_solving.solve_gci_over_the_box(problem, jax_model, numpy_model, nodes, options)
    started = time.perf_counter()
    sampled = joint_nodes(problem, numpy_model, nodes, seed)
    jacobian, parameters = jax_model.unbound("jacobian")
    parameters = {**parameters, **{k: float(v) for k, v in problem.values.items() if k in parameters}}
    missing = [p.name for p in problem.free if p.name not in parameters]
    if missing:
        raise ValueError(f"{jax_model.name}: the Jacobian does not depend on {', '.join(missing)}: free only "
                         f"parameters of the generated jacobian ({', '.join(sorted(parameters))})")
    scale = jnp.asarray(device_integrand.row_scale(jax_model, problem.joint_limits, problem.length))
    points = jnp.asarray(sampled.points, dtype=jnp.float64)
    program = device_integrand.compiled_surrogate_gradient(jacobian, "cartesian", problem.objective,
                                                           DETERMINANT_SMOOTHING)
    factor = 1.0 if problem.objective == "gci" else sampled.volume_per_node
    scales = problem.scales

    def surrogate(z: np.ndarray) -> tuple[float, np.ndarray]:
        values = {**parameters, **{p.name: float(v) for p, v in zip(problem.free, z * scales)}}
        value, gradient = program(points, scale, values)
        return factor * float(value), factor * np.array([float(gradient[p.name]) for p in problem.free]) * scales

    z0 = problem.scaled_start
    reference, _ = surrogate(z0)
    if not (np.isfinite(reference) and reference > 0):
        raise ValueError(f"the {problem.objective} surrogate is {reference} at the start design {problem.start}: start "
                         "from a design with a nonsingular workspace, or use the CasADi program (--gradients casadi), "
                         "whose surrogate stays finite at singular nodes")
    history = [reference]
    chosen = {**LBFGSB_OPTIONS, **(options or {})}

    def objective(z: np.ndarray) -> tuple[float, np.ndarray]:
        value, gradient = surrogate(z)
        if not np.isfinite(value):
            raise ValueError(f"the {problem.objective} surrogate is not finite at {problem.design(list(z * scales))}: a "
                             "node's J^T J is singular there; use the CasADi program (--gradients casadi)")
        return -value / reference, -gradient / reference

    def iterate(intermediate_result: optimize.OptimizeResult) -> None:
        history.append(-float(intermediate_result.fun) * reference)
        reporting.report_progress("optimizing the design (L-BFGS-B iterations)", done=len(history) - 1,
                                   total=int(chosen["maxiter"]))

    build_seconds = time.perf_counter() - started
    started = time.perf_counter()
    result = optimize.minimize(objective, z0, jac=True, method="L-BFGS-B", callback=iterate,
                               bounds=problem.scaled_bounds, options=chosen)
    solve_seconds = time.perf_counter() - started
    solution = Solution(
        start=problem.start, optimum=problem.design_at(result.x),
        surrogate_start=reference, surrogate_optimum=-float(result.fun) * reference, history=np.asarray(history),
        infeasibility=np.zeros(len(history)), status=str(result.message), success=bool(result.success),
        iterations=int(result.nit), solve_seconds=solve_seconds, build_seconds=build_seconds, solver="L-BFGS-B")
    return solution, f"{sampled.description}; L-BFGS-B on JAX gradients"
