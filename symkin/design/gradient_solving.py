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

A parallel model with a closed-form ik (a translational platform's box of positions, or a spherical one's box of
orientations) has the CasADi program's GCI surrogate over its required box (:func:`symkin.design.formulation.
inverse_grid`: the mean of 1/kappa_F of J(ik(p), p) - of E(p) J for orientations, weighted by cos(pitch) - over a
midpoint grid) and its constraints, that every leg reaches every point of the inflated box's vertex grid and of the
grid (ik margin >= 0, scaled by its median at the start), its actuated joints within their limits and the joint stops
kept: SLSQP (Kraft 1988, scipy) on the surrogate's gradient by jax.value_and_grad and the constraints' Jacobian by
jax.jacfwd through the generated ik and Jacobian (few free parameters: forward mode), one compiled XLA program each.
A bound on the apparent mass and the force objective stay with the CasADi program.
"""

from __future__ import annotations

import functools
import time
from typing import Any

import numpy as np

from symkin import reporting
from symkin.analysis import device_integrand
from symkin.design.formulation import (BOX_POINTS_PER_AXIS, DETERMINANT_SMOOTHING, inverse_grid, joint_nodes,
                                       joint_rules, margin_reference)
from symkin.design.problem import DesignProblem
from symkin.design.solving import Solution
from symkin.mechanism import Sampling, reach
from symkin.numerics.ordered_linalg import InOrder
from symkin.runtime.info import GeneratedModel

#: The objectives the JAX path optimizes (those of a serial model's joint box without a required box).
OBJECTIVES = ("gci", "workspace")
#: The ways of sampling whose GCI over a required box the JAX path optimizes (a parallel model's closed-form ik).
INVERSE_SAMPLINGS = (Sampling.INVERSE, Sampling.ORIENTATIONS)
#: SLSQP's options: stop on a change of the (order one) scaled objective below 1e-14.
SLSQP_OPTIONS: dict[str, Any] = {"maxiter": 300, "ftol": 1e-14}
#: L-BFGS-B's options: the problems are small and smooth; stop on a relative objective change below ~eps or a
#: projected gradient below 1e-10 of the (order one) scaled objective.
LBFGSB_OPTIONS: dict[str, Any] = {"maxiter": 300, "ftol": 1e-15, "gtol": 1e-10}


def refusal(problem: DesignProblem, jax_model: GeneratedModel) -> str | None:
    """Why the JAX path cannot solve the problem (and what to use instead), or None when it can."""
    fix = "; use the CasADi program (--gradients casadi, the default)"
    if problem.sampling in INVERSE_SAMPLINGS:
        if problem.objective != "gci" or problem.max_apparent_mass is not None:
            return (f"JAX gradients optimize a parallel model's gci over its required box, not the {problem.objective} "
                    f"objective nor a bound on the apparent mass{fix}")
        if not {"ik", "jacobian"} <= set(jax_model.functions) or not device_integrand.loaded_with_jax(jax_model):
            return (f"{jax_model.name}: JAX gradients need the model's JAX ik and jacobian (derive them with --backend "
                    "numpy,jax, or load the model with backend='jax')")
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
        options: overrides of :data:`LBFGSB_OPTIONS` (:data:`SLSQP_OPTIONS` for a parallel model).

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
    if problem.sampling in INVERSE_SAMPLINGS:
        return _solve_over_the_box(problem, jax_model, numpy_model, nodes, options)
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
    scales = np.array([p.scale for p in problem.free])

    def surrogate(z: np.ndarray) -> tuple[float, np.ndarray]:
        values = {**parameters, **{p.name: float(v) for p, v in zip(problem.free, z * scales)}}
        value, gradient = program(points, scale, values)
        return factor * float(value), factor * np.array([float(gradient[p.name]) for p in problem.free]) * scales

    z0 = np.array([p.start for p in problem.free]) / scales
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
                               bounds=[(p.lower / s, p.upper / s) for p, s in zip(problem.free, scales)],
                               options=chosen)
    solve_seconds = time.perf_counter() - started
    # the bounds in the parameters' units (x * scale may round past one)
    lower, upper = np.array([p.lower for p in problem.free]), np.array([p.upper for p in problem.free])
    solution = Solution(
        start=problem.start, optimum=problem.design(list(np.clip(result.x * scales, lower, upper))),
        surrogate_start=reference, surrogate_optimum=-float(result.fun) * reference, history=np.asarray(history),
        infeasibility=np.zeros(len(history)), status=str(result.message), success=bool(result.success),
        iterations=int(result.nit), solve_seconds=solve_seconds, build_seconds=build_seconds, solver="L-BFGS-B")
    return solution, f"{sampled.description}; L-BFGS-B on JAX gradients"


def _solve_over_the_box(problem: DesignProblem, jax_model: GeneratedModel, numpy_model: GeneratedModel,
                        nodes: int | None, options: dict[str, Any] | None) -> tuple[Solution, str]:
    """SLSQP on a parallel model's GCI surrogate over its required box, the reach constraints at its points (see
    the module docstring)."""
    import jax.numpy as jnp
    from scipy import optimize

    started = time.perf_counter()
    grid = inverse_grid(problem, nodes, BOX_POINTS_PER_AXIS)
    reference_margin = margin_reference(problem, numpy_model, grid.points)
    (ik, ik_values), (jacobian, jacobian_values) = jax_model.unbound("ik"), jax_model.unbound("jacobian")
    parameters = {**ik_values, **jacobian_values}
    parameters.update({k: float(v) for k, v in problem.values.items() if k in parameters})
    missing = [p.name for p in problem.free if p.name not in parameters]
    if missing:
        raise ValueError(f"{jax_model.name}: neither the ik nor the Jacobian depends on {', '.join(missing)}: free "
                         f"only their parameters ({', '.join(sorted(parameters))})")
    dimension = grid.nodes.shape[1]
    rotation = (reach.angular_velocity_matrix(grid.nodes) if problem.sampling is Sampling.ORIENTATIONS
                else np.broadcast_to(np.eye(dimension), (len(grid.nodes), dimension, dimension)))
    surrogate_program, reach_program = _programs_over_the_box(ik, jacobian, tuple(sorted(ik_values)),
                                                              tuple(sorted(jacobian_values)))
    nodes_arguments = (jnp.asarray(grid.nodes), jnp.asarray(rotation), jnp.asarray(grid.weights))
    points = jnp.asarray(grid.points)
    rows = _ReachRows(problem, numpy_model, reference_margin)
    names = [p.name for p in problem.free]
    scales = np.array([p.scale for p in problem.free])

    def design_values(z: np.ndarray) -> dict[str, Any]:
        return {**parameters, **{name: float(v) for name, v in zip(names, z * scales)}}

    # Both evaluated at an iterate's z (bytes of the float64 vector: a cache key) and kept for the callback and the
    # constraints' Jacobian, which SLSQP asks for at the same z.
    @functools.lru_cache(maxsize=4)
    def surrogate(key: bytes) -> tuple[float, np.ndarray]:
        value, gradient = surrogate_program(*nodes_arguments, design_values(np.frombuffer(key)))
        return float(value), np.array([float(gradient[name]) for name in names]) * scales

    @functools.lru_cache(maxsize=4)
    def constraints(key: bytes) -> tuple[np.ndarray, np.ndarray]:
        (margins, joints), (margin_slopes, joint_slopes) = reach_program(points, design_values(np.frombuffer(key)))
        columns = [rows(np.asarray(margin_slopes[name]), np.asarray(joint_slopes[name]), shift=0.0) * scale
                   for name, scale in zip(names, scales)]
        return rows(np.asarray(margins), np.asarray(joints), shift=1.0), np.stack(columns, axis=-1)

    def key(z: np.ndarray) -> bytes:
        return np.asarray(z, dtype=np.float64).tobytes()

    z0 = np.array([p.start for p in problem.free]) / scales
    reference, _ = surrogate(key(z0))
    if not (np.isfinite(reference) and reference > 0):
        raise ValueError(f"the gci surrogate is {reference} at the start design {problem.start}: start from a design "
                         "whose legs reach the required box, or use the CasADi program (--gradients casadi)")
    history, infeasibility = [reference], [_violation(constraints(key(z0))[0])]
    chosen = {**SLSQP_OPTIONS, **(options or {})}

    def objective(z: np.ndarray) -> tuple[float, np.ndarray]:
        value, gradient = surrogate(key(z))
        return -value / reference, -gradient / reference

    def iterate(z: np.ndarray) -> None:
        history.append(surrogate(key(z))[0])
        infeasibility.append(_violation(constraints(key(z))[0]))
        reporting.report_progress("optimizing the design (SLSQP iterations)", done=len(history) - 1,
                                   total=int(chosen["maxiter"]))

    build_seconds = time.perf_counter() - started
    started = time.perf_counter()
    result = optimize.minimize(
        objective, z0, jac=True, method="SLSQP", callback=iterate, options=chosen,
        bounds=[(p.lower / s, p.upper / s) for p, s in zip(problem.free, scales)],
        constraints=[{"type": "ineq", "fun": lambda z: constraints(key(z))[0],
                      "jac": lambda z: constraints(key(z))[1]}])
    solve_seconds = time.perf_counter() - started
    lower, upper = np.array([p.lower for p in problem.free]), np.array([p.upper for p in problem.free])
    optimum = np.clip(result.x * scales, lower, upper)
    solution = Solution(
        start=problem.start, optimum=problem.design(list(optimum)), surrogate_start=reference,
        surrogate_optimum=surrogate(key(optimum / scales))[0], history=np.asarray(history),
        infeasibility=np.asarray(infeasibility), status=str(result.message), success=bool(result.success),
        iterations=int(result.nit), solve_seconds=solve_seconds, build_seconds=build_seconds,
        constraint_violation=_violation(constraints(key(optimum / scales))[0]), solver="SLSQP")
    return solution, f"{grid.description}; SLSQP on JAX gradients"


def _violation(g: np.ndarray) -> float:
    """The largest violation of constraints g >= 0 (0 where every one holds)."""
    return float(-np.min(g, initial=0.0)) + 0.0


class _ReachRows:
    """The reach constraints of a parallel model as rows g >= 0, from the ik's margins (P, legs) and joints (P, n) at
    the box's points - the CasADi program's (:func:`symkin.design.formulation._reach`): margin / its start median,
    and each finite side of the problem's joint rules (:func:`symkin.design.formulation.joint_rules`).  Linear in
    (margins, joints) plus constants: ``shift=0`` gives the rows of their derivatives."""

    def __init__(self, problem: DesignProblem, model: GeneratedModel, reference_margin: float) -> None:
        self.reference_margin = reference_margin
        self.rows, self.offsets, self.lower, self.upper = joint_rules(problem, model)

    def __call__(self, margins: np.ndarray, joints: np.ndarray, *, shift: float) -> np.ndarray:
        values = joints @ self.rows.T + shift * self.offsets
        low, high = np.isfinite(self.lower), np.isfinite(self.upper)
        return np.concatenate([margins.reshape(-1) / self.reference_margin,
                               (values[:, low] - shift * self.lower[low]).T.reshape(-1),
                               (shift * self.upper[high] - values[:, high]).T.reshape(-1)])


@functools.lru_cache(maxsize=8)
def _programs_over_the_box(ik: Any, jacobian: Any, ik_names: tuple[str, ...], jacobian_names: tuple[str, ...]
                           ) -> tuple[Any, Any]:
    """(surrogate, reach), jitted once per generated ik and Jacobian: ``surrogate(nodes, rotation, weights,
    parameters) -> (sum_j w_j / kappa_F(R_j J_j), {name: derivative})``, J_j = J(ik(p_j), p_j), by
    jax.value_and_grad; ``reach(points, parameters) -> ((margins, joints), their derivatives by every parameter)``
    by jax.jacfwd."""
    import jax
    import jax.numpy as jnp

    def own(parameters: dict[str, Any], names: tuple[str, ...]) -> dict[str, Any]:
        return {name: parameters[name] for name in names}

    def surrogate(nodes: Any, rotation: Any, weights: Any, parameters: dict[str, Any]) -> Any:
        q = ik(nodes, **own(parameters, ik_names)).joints
        J = rotation @ jacobian(q, nodes, **own(parameters, jacobian_names))
        return jnp.sum(weights * device_integrand.inverse_frobenius(J, InOrder(jnp)))

    def reached(points: Any, parameters: dict[str, Any]) -> tuple[Any, Any]:
        solution = ik(points, **own(parameters, ik_names))
        return solution.margin, solution.joints

    return (jax.jit(jax.value_and_grad(surrogate, argnums=3)),
            jax.jit(lambda points, parameters: (reached(points, parameters),
                                                jax.jacfwd(reached, argnums=1)(points, parameters))))
