"""Dimensioning a parallel model over its required box with JAX gradients (issue 66, ``symkin optimize
--gradients jax``; the serial models' L-BFGS-B: :mod:`symkin.design.gradient_solving`).

A parallel model with a closed-form ik (a translational platform's box of positions, or a spherical one's box of
orientations) has the CasADi program's GCI surrogate over its required box (:func:`symkin.design.formulation.
inverse_grid`: the mean of 1/kappa_F of J(ik(p), p) - of E(p) J for orientations, weighted by cos(pitch) - over a
midpoint grid) and its constraints, that every leg reaches every point of the inflated box's vertex grid and of the
grid (ik margin >= 0, scaled by its median at the start), its actuated joints within their limits and the joint stops
kept: SLSQP (Kraft 1988, scipy) on the surrogate's gradient by jax.value_and_grad and the constraints' Jacobian by
jax.jacfwd through the generated ik and Jacobian (few free parameters: forward mode), one compiled XLA program each.
Its force objective - the isotropic force min_i tau_max,i / |J_i| at the worst of the same points - takes the
CasADi program's epigraph form: maximize t subject to (t |J_i(p_j)| / tau_max,i)^2 <= 1 at every point p_j and
actuator i (t scaled by the start design's worst force), the squared column norms and their derivatives by
jax.jacfwd, with the same reach constraints.  A bound m_max on the apparent mass at the handle adds the CasADi
program's constraints at the same points: every principal minor of B = m_max J M^-1 J^T - 1 >= 0
(:func:`symkin.design.formulation._apparent_mass_rows`), M the generated actuator-space mass matrix at (ik(p), p),
M^-1 and the minors by cofactors (:mod:`symkin.numerics.cofactors`: the matrices are n x n with n <= 3 actuators for
a translating handle, and no LAPACK kernel enters the program) and their derivatives by jax.jacfwd.
"""

from __future__ import annotations

import functools
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin import reporting
from symkin.analysis import device_integrand
from symkin.design.formulation import (BOX_POINTS_PER_AXIS, apparent_mass_description, inverse_grid, joint_rules,
                                      margin_reference, principal_subsets)
from symkin.design.problem import DesignProblem
from symkin.design.solving import Solution
from symkin.mechanism import Sampling, reach
from symkin.numerics import cofactors
from symkin.numerics.ordered_linalg import InOrder
from symkin.runtime.info import GeneratedModel

#: SLSQP's options: stop on a change of the (order one) scaled objective below 1e-14.
SLSQP_OPTIONS: dict[str, Any] = {"maxiter": 300, "ftol": 1e-14}


def solve_gci_over_the_box(problem: DesignProblem, jax_model: GeneratedModel, numpy_model: GeneratedModel,
                           nodes: int | None, options: dict[str, Any] | None) -> tuple[Solution, str]:
    """SLSQP on a parallel model's GCI surrogate over its required box, the reach constraints at its points (see
    the module docstring)."""
    import jax.numpy as jnp
    from scipy import optimize

    started = time.perf_counter()
    box = _BoxDesign.of(problem, jax_model, numpy_model, nodes)
    grid, names, scales, constraints = box.grid, box.names, box.scales, box.constraints
    rows = grid.nodes.shape[1] if problem.orientation is None else len(problem.held_inverse_scaling)  # J_h^-1's
    rotation = (reach.angular_velocity_matrix(grid.nodes) if problem.sampling is Sampling.ORIENTATIONS
                else np.broadcast_to(np.eye(rows), (len(grid.nodes), rows, rows)))
    surrogate_program, _ = _programs_over_the_box(box.ik, box.jacobian, box.ik_names, box.jacobian_names)
    nodes_arguments = (jnp.asarray(grid.nodes), jnp.asarray(rotation), jnp.asarray(grid.weights))

    # Evaluated at an iterate's z (bytes of the float64 vector: a cache key, as the constraints are) and kept for the
    # callback, which asks at the same z.
    @functools.lru_cache(maxsize=4)
    def surrogate(key: bytes) -> tuple[float, np.ndarray]:
        value, gradient = surrogate_program(*nodes_arguments, box.design_values(np.frombuffer(key)))
        return float(value), np.array([float(gradient[name]) for name in names]) * scales

    z0 = problem.scaled_start
    reference, _ = surrogate(_key(z0))
    if not (np.isfinite(reference) and reference > 0):
        raise ValueError(f"the gci surrogate is {reference} at the start design {problem.start}: start from a design "
                         "whose legs reach the required box, or use the CasADi program (--gradients casadi)")
    history, infeasibility = [reference], [_violation(constraints(_key(z0))[0])]
    chosen = {**SLSQP_OPTIONS, **(options or {})}

    def objective(z: np.ndarray) -> tuple[float, np.ndarray]:
        value, gradient = surrogate(_key(z))
        return -value / reference, -gradient / reference

    def iterate(z: np.ndarray) -> None:
        history.append(surrogate(_key(z))[0])
        infeasibility.append(_violation(constraints(_key(z))[0]))
        reporting.report_progress("optimizing the design (SLSQP iterations)", done=len(history) - 1,
                                   total=int(chosen["maxiter"]))

    build_seconds = time.perf_counter() - started
    started = time.perf_counter()
    result = optimize.minimize(
        objective, z0, jac=True, method="SLSQP", callback=iterate, options=chosen,
        bounds=problem.scaled_bounds, constraints=[{"type": "ineq", "fun": lambda z: constraints(_key(z))[0],
                                         "jac": lambda z: constraints(_key(z))[1]}])
    solve_seconds = time.perf_counter() - started
    optimum = problem.design_at(result.x)
    z_optimum = box.scaled(optimum)
    solution = Solution(
        start=problem.start, optimum=optimum, surrogate_start=reference,
        surrogate_optimum=surrogate(_key(z_optimum))[0], history=np.asarray(history),
        infeasibility=np.asarray(infeasibility), status=str(result.message), success=bool(result.success),
        iterations=int(result.nit), solve_seconds=solve_seconds, build_seconds=build_seconds,
        constraint_violation=_violation(constraints(_key(z_optimum))[0]), solver="SLSQP")
    return solution, f"{grid.description}{apparent_mass_description(problem)}; SLSQP on JAX gradients"


def _key(z: np.ndarray) -> bytes:
    """The scaled free parameters z as a cache key (their float64 bytes): SLSQP asks for the objective, the
    constraints and their Jacobians at the same z."""
    return np.asarray(z, dtype=np.float64).tobytes()


def _reach_constraints(reach_program: Any, points: Any, rows: _ReachRows,
                       design_values: Callable[[np.ndarray], dict[str, Any]], names: list[str],
                       scales: np.ndarray) -> Callable[[bytes], tuple[np.ndarray, np.ndarray]]:
    """key -> (the reach constraints g >= 0 at ``points``, their Jacobian by the scaled free parameters z) of the
    design z (:func:`_key`), by the jitted ``reach_program`` (:func:`_programs_over_the_box`); the last few kept."""

    @functools.lru_cache(maxsize=4)
    def constraints(key: bytes) -> tuple[np.ndarray, np.ndarray]:
        (margins, joints), (margin_slopes, joint_slopes) = reach_program(points, design_values(np.frombuffer(key)))
        columns = [rows(np.asarray(margin_slopes[name]), np.asarray(joint_slopes[name]), shift=0.0) * scale
                   for name, scale in zip(names, scales)]
        return rows(np.asarray(margins), np.asarray(joints), shift=1.0), np.stack(columns, axis=-1)

    return constraints


@dataclass(frozen=True)
class _BoxDesign:
    """What both box problems start from: the grid (:func:`symkin.design.formulation.inverse_grid`), the model's JAX ik
    and Jacobian with their parameters' names, the free parameters' names and scales (z = value / scale), the
    constraint points, every parameter's value at a design z, the reach constraints (:func:`_reach_constraints`) and,
    under an apparent-mass bound, its constraints (:func:`_mass_constraints`; None without one)."""

    grid: Any
    ik: Any
    jacobian: Any
    ik_names: tuple[str, ...]
    jacobian_names: tuple[str, ...]
    names: list[str]
    scales: np.ndarray
    points: Any
    design_values: Callable[[np.ndarray], dict[str, Any]]
    reach: Callable[[bytes], tuple[np.ndarray, np.ndarray]]
    masses: Callable[[bytes], tuple[np.ndarray, np.ndarray]] | None

    def constraints(self, key: bytes) -> tuple[np.ndarray, np.ndarray]:
        """The constraints g >= 0 at the design z (:func:`_key`) and their Jacobian by z: the reach constraints, then
        the apparent-mass bound's."""
        reach = self.reach(key)
        if self.masses is None:
            return reach
        masses = self.masses(key)
        return np.concatenate([reach[0], masses[0]]), np.concatenate([reach[1], masses[1]])

    def scaled(self, design: dict[str, float]) -> np.ndarray:
        """The scaled free parameters z of a design's values."""
        return np.array([design[name] for name in self.names]) / self.scales

    @classmethod
    def of(cls, problem: DesignProblem, jax_model: GeneratedModel, numpy_model: GeneratedModel,
           nodes: int | None) -> _BoxDesign:
        """ValueError where a free parameter is neither the ik's nor the Jacobian's (nor, under an apparent-mass
        bound, the mass matrix's)."""
        import jax.numpy as jnp

        grid = inverse_grid(problem, nodes, BOX_POINTS_PER_AXIS)
        reference_margin = margin_reference(problem, numpy_model, grid.points)
        (ik, ik_values), (jacobian, jacobian_values) = _task_functions(problem, jax_model)
        mass_matrix, mass_values = (None, {}) if problem.max_apparent_mass is None else jax_model.unbound("mass_matrix")
        parameters = {**ik_values, **jacobian_values, **mass_values}
        parameters.update({k: float(v) for k, v in problem.values.items() if k in parameters})
        missing = [p.name for p in problem.free if p.name not in parameters]
        if missing:
            functions = "the ik, the Jacobian nor the mass matrix" if mass_matrix else "the ik nor the Jacobian"
            raise ValueError(f"{jax_model.name}: neither {functions} depends on {', '.join(missing)}: "
                             f"free only their parameters ({', '.join(sorted(parameters))})")
        ik_names, jacobian_names = tuple(sorted(ik_values)), tuple(sorted(jacobian_values))
        names, scales = [p.name for p in problem.free], problem.scales
        points = jnp.asarray(grid.points)
        _, reach_program = _programs_over_the_box(ik, jacobian, ik_names, jacobian_names)

        def design_values(z: np.ndarray) -> dict[str, Any]:
            """Every parameter, the free ones at the scaled values z."""
            return {**parameters, **{name: float(v) for name, v in zip(names, z * scales)}}

        reach = _reach_constraints(reach_program, points, _ReachRows(problem, numpy_model, reference_margin),
                                   design_values, names, scales)
        masses = None
        if problem.max_apparent_mass is not None:
            program = _mass_program(ik, jacobian, mass_matrix, ik_names, jacobian_names, tuple(sorted(mass_values)))
            masses = _mass_constraints(program, points, problem.max_apparent_mass, design_values, names, scales)
        return cls(grid, ik, jacobian, ik_names, jacobian_names, names, scales, points, design_values, reach, masses)


def _task_functions(problem: DesignProblem, jax_model: GeneratedModel) -> tuple[tuple[Any, dict], tuple[Any, dict]]:
    """((ik, its parameters), (J, its parameters)) of the box's points: the generated ik and Jacobian, or a held
    platform's ik of (points, orientation) and J_h^-1 = J^-1 D (:attr:`DesignProblem.held_inverse_scaling`)."""
    if problem.orientation is None:
        return jax_model.unbound("ik"), jax_model.unbound("jacobian")
    import jax.numpy as jnp
    (ik, ik_values), (inverse, inverse_values) = jax_model.unbound("ik"), jax_model.unbound("inverse_jacobian")
    orientation, scaling = jnp.asarray(problem.orientation), jnp.asarray(problem.held_inverse_scaling)

    def poses(points: Any) -> Any:
        return jnp.concatenate([points, jnp.broadcast_to(orientation, (*points.shape[:-1], 3))], axis=-1)

    return ((lambda points, **parameters: ik(poses(points), **parameters), ik_values),
            (lambda q, points, **parameters: inverse(q, poses(points), **parameters) @ scaling, inverse_values))


def solve_force_over_the_box(problem: DesignProblem, jax_model: GeneratedModel, numpy_model: GeneratedModel,
                              nodes: int | None, options: dict[str, Any] | None) -> tuple[Solution, str]:
    """SLSQP on a translational platform's worst isotropic force over its required box, in the CasADi program's
    epigraph form (:func:`symkin.design.formulation._force`, see the module docstring): the variables are the scaled
    free parameters z and the bound t (the force / the start design's worst), the reach constraints those of
    :func:`solve_gci_over_the_box` at the same points."""
    import jax.numpy as jnp
    from scipy import optimize

    started = time.perf_counter()
    box = _BoxDesign.of(problem, jax_model, numpy_model, nodes)  # its points: the box's vertex grid and midpoints
    grid, names, scales, reached = box.grid, box.names, box.scales, box.constraints
    force_program = _force_program(box.ik, box.jacobian, box.ik_names, box.jacobian_names)
    limits = jnp.asarray(np.asarray(problem.effort_limits, dtype=np.float64))

    @functools.lru_cache(maxsize=4)
    def squared(key: bytes) -> tuple[np.ndarray, np.ndarray]:
        """(|J_i(p_j)|^2 / tau_max,i^2 flattened, its derivatives by z (columns))."""
        values, slopes = force_program(box.points, limits, box.design_values(np.frombuffer(key)))
        return (np.asarray(values).reshape(-1),
                _scaled_columns(slopes, names, scales))

    def worst(z: np.ndarray) -> float:
        """The design's worst isotropic force over the points, min 1 / sqrt(|J_i|^2 / tau_max,i^2)."""
        return float(np.min(1.0 / np.sqrt(squared(_key(z))[0])))

    z0 = problem.scaled_start
    start = worst(z0)
    if not (np.isfinite(start) and start > 0):
        raise ValueError(f"{numpy_model.name}: the isotropic force vanishes in the box at the start design")

    def constraints(y: np.ndarray) -> np.ndarray:
        z, t = y[:-1], y[-1]
        return np.concatenate([1.0 - (t * start) ** 2 * squared(_key(z))[0], reached(_key(z))[0]])

    def constraints_jacobian(y: np.ndarray) -> np.ndarray:
        z, t = y[:-1], y[-1]
        values, slopes = squared(_key(z))
        force = np.concatenate([-(t * start) ** 2 * slopes, (-2.0 * t * start**2 * values)[:, None]], axis=1)
        reach_slopes = reached(_key(z))[1]
        return np.concatenate([force, np.concatenate([reach_slopes, np.zeros((len(reach_slopes), 1))], axis=1)])

    def violation(y: np.ndarray) -> float:
        return _violation(constraints(y))

    y0 = np.append(z0, 1.0)
    history, infeasibility = [start], [violation(y0)]
    chosen = {**SLSQP_OPTIONS, **(options or {})}
    objective_gradient = np.append(np.zeros(len(z0)), -1.0)  # of -t

    def iterate(y: np.ndarray) -> None:
        history.append(float(y[-1]) * start)
        infeasibility.append(violation(y))
        reporting.report_progress("optimizing the design (SLSQP iterations)", done=len(history) - 1,
                                  total=int(chosen["maxiter"]))

    build_seconds = time.perf_counter() - started
    started = time.perf_counter()
    result = optimize.minimize(
        lambda y: (-float(y[-1]), objective_gradient), y0, jac=True, method="SLSQP", callback=iterate, options=chosen,
        bounds=problem.scaled_bounds + [(0.0, None)],
        constraints=[{"type": "ineq", "fun": constraints, "jac": constraints_jacobian}])
    solve_seconds = time.perf_counter() - started
    optimum = problem.design_at(result.x[:-1])
    z_optimum = box.scaled(optimum)
    solution = Solution(
        start=problem.start, optimum=optimum, surrogate_start=start,
        surrogate_optimum=worst(z_optimum), history=np.asarray(history),
        infeasibility=np.asarray(infeasibility), status=str(result.message), success=bool(result.success),
        iterations=int(result.nit), solve_seconds=solve_seconds, build_seconds=build_seconds,
        constraint_violation=_violation(reached(_key(z_optimum))[0]), solver="SLSQP")
    limits_text = ", ".join(f"{v:g}" for v in np.asarray(problem.effort_limits))
    return solution, (f"isotropic force min_i tau_max,i / |J_i| at the worst of {len(grid.points)} points (the box's "
                      f"vertex grid and its {len(grid.nodes)} midpoints; epigraph form), effort limits {limits_text}; "
                      f"the box is required at every point (ik margin >= 0){apparent_mass_description(problem)}; "
                      "SLSQP on JAX gradients")


def _own(parameters: dict[str, Any], names: tuple[str, ...]) -> dict[str, Any]:
    """The parameters a generated function takes (``names``) out of every parameter of the design."""
    return {name: parameters[name] for name in names}


@functools.lru_cache(maxsize=8)
def _force_program(ik: Any, jacobian: Any, ik_names: tuple[str, ...], jacobian_names: tuple[str, ...]) -> Any:
    """``force(points, limits, parameters) -> (|J_i(p_j)|^2 / tau_max,i^2 (P, n), its derivatives by every
    parameter)``, J_i the i-th column of J(ik(p_j), p_j), by jax.jacfwd; jitted once per generated ik and Jacobian."""
    import jax
    import jax.numpy as jnp

    def squared(points: Any, limits: Any, parameters: dict[str, Any]) -> Any:
        q = ik(points, **_own(parameters, ik_names)).joints
        J = jacobian(q, points, **_own(parameters, jacobian_names))
        return jnp.sum(J * J, axis=-2) / (limits * limits)

    return jax.jit(lambda points, limits, parameters: (squared(points, limits, parameters),
                                                       jax.jacfwd(squared, argnums=2)(points, limits, parameters)))


def _mass_constraints(mass_program: Any, points: Any, bound: float,
                      design_values: Callable[[np.ndarray], dict[str, Any]], names: list[str],
                      scales: np.ndarray) -> Callable[[bytes], tuple[np.ndarray, np.ndarray]]:
    """key -> (the principal minors of m_max J M^-1 J^T - 1 at ``points``, >= 0 where every apparent mass is at most
    the ``bound`` m_max; their Jacobian by z) of the design z (:func:`_key`) by the jitted ``mass_program``
    (:func:`_mass_program`); the last few kept."""

    @functools.lru_cache(maxsize=4)
    def constraints(key: bytes) -> tuple[np.ndarray, np.ndarray]:
        minors, slopes = mass_program(points, bound, design_values(np.frombuffer(key)))
        return (np.asarray(minors).reshape(-1),
                _scaled_columns(slopes, names, scales))

    return constraints


@functools.lru_cache(maxsize=8)
def _mass_program(ik: Any, jacobian: Any, mass_matrix: Any, ik_names: tuple[str, ...],
                  jacobian_names: tuple[str, ...], mass_names: tuple[str, ...]) -> Any:
    """``minors(points, bound, parameters) -> (the principal minors of B = bound J M^-1 J^T - 1 at each point (P, S),
    their derivatives by every parameter)``, J and M the generated Jacobian and actuator-space mass matrix at
    (ik(p), p), by jax.jacfwd (the CasADi program's :func:`symkin.design.formulation._apparent_mass_rows`, in the
    order of :func:`symkin.design.formulation.principal_subsets`); jitted once per generated ik, Jacobian and mass
    matrix."""
    import jax
    import jax.numpy as jnp

    def minors(points: Any, bound: Any, parameters: dict[str, Any]) -> Any:
        q = ik(points, **_own(parameters, ik_names)).joints
        J = jacobian(q, points, **_own(parameters, jacobian_names))
        M = mass_matrix(q, points, **_own(parameters, mass_names))
        size = J.shape[-2]
        B = bound * (J @ cofactors.inverse(M, jnp) @ jnp.swapaxes(J, -1, -2)) - jnp.eye(size)
        return jnp.stack([cofactors.determinant(B[..., rows, :][..., :, rows], jnp) for rows in principal_subsets(size)],
                         axis=-1)

    return jax.jit(lambda points, bound, parameters: (minors(points, bound, parameters),
                                                      jax.jacfwd(minors, argnums=2)(points, bound, parameters)))


def _scaled_columns(slopes: dict[str, Any], names: list[str], scales: np.ndarray) -> np.ndarray:
    """The derivatives of flattened values by the scaled free parameters z, as columns: jax.jacfwd's derivatives by
    each parameter (``slopes``), flattened, times its scale."""
    return np.stack([np.asarray(slopes[name]).reshape(-1) * scale for name, scale in zip(names, scales)], -1)


def _violation(g: np.ndarray) -> float:
    """The largest violation of constraints g >= 0 (0 where every one holds)."""
    return float(-np.min(g, initial=0.0)) + 0.0


class _ReachRows:
    """The reach constraints as rows g >= 0 from the ik's margins (P, legs) and joints (P, n) at the box's points, as
    the CasADi program's (:func:`symkin.design.formulation._reach`): margin / its start median, each finite side of
    the joint rules (angles centred, :class:`~symkin.design.formulation.JointRules`); ``shift=0``: their slopes."""

    def __init__(self, problem: DesignProblem, model: GeneratedModel, reference_margin: float) -> None:
        self.reference_margin = reference_margin
        self.rules = joint_rules(problem, model)

    def __call__(self, margins: np.ndarray, joints: np.ndarray, *, shift: float) -> np.ndarray:
        rows, offsets, lower, upper, _ = self.rules
        values = (self.rules.centred(joints) if shift else joints) @ rows.T + shift * offsets
        low, high = np.isfinite(lower), np.isfinite(upper)
        return np.concatenate([margins.reshape(-1) / self.reference_margin,
                               (values[:, low] - shift * lower[low]).T.reshape(-1),
                               (shift * upper[high] - values[:, high]).T.reshape(-1)])


@functools.lru_cache(maxsize=8)
def _programs_over_the_box(ik: Any, jacobian: Any, ik_names: tuple[str, ...], jacobian_names: tuple[str, ...]
                           ) -> tuple[Any, Any]:
    """(surrogate, reach), jitted once per generated ik and Jacobian: ``surrogate(nodes, rotation, weights,
    parameters) -> (sum_j w_j / kappa_F(R_j J_j), {name: derivative})``, J_j = J(ik(p_j), p_j), by
    jax.value_and_grad; ``reach(points, parameters) -> ((margins, joints), their derivatives by every parameter)``
    by jax.jacfwd."""
    import jax
    import jax.numpy as jnp

    def surrogate(nodes: Any, rotation: Any, weights: Any, parameters: dict[str, Any]) -> Any:
        q = ik(nodes, **_own(parameters, ik_names)).joints
        J = rotation @ jacobian(q, nodes, **_own(parameters, jacobian_names))
        return jnp.sum(weights * device_integrand.inverse_frobenius(J, InOrder(jnp)))

    def reached(points: Any, parameters: dict[str, Any]) -> tuple[Any, Any]:
        solution = ik(points, **_own(parameters, ik_names))
        return solution.margin, solution.joints

    return (jax.jit(jax.value_and_grad(surrogate, argnums=3)),
            jax.jit(lambda points, parameters: (reached(points, parameters),
                                                jax.jacfwd(reached, argnums=1)(points, parameters))))
