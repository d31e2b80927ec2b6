"""The dimensioning problem as a CasADi nonlinear program (seed sec. 4.1 step 2).

Decision variables: the free parameters, scaled to order one (value / start), and, for a
serial model with a required box, one joint configuration per box point.  The generated
CasADi functions (``fk``, ``ik``, ``jacobian``: their parameters are inputs) are mapped
over fixed sample points, so the objective is a smooth function of the design:

* ``gci`` of a serial model: the Frobenius surrogate of the GCI (seed eq. 8.28) with the
  Cartesian measure dW = |det J| dq over the joint limits, at fixed Sobol nodes q_j,

      v_F = sum_j |det J_j| / kappa_F(J_j)  /  sum_j |det J_j|

  (:func:`symkin.design.smooth.measure_weighted_inverse_frobenius`); with the same nodes
  it is :func:`symkin.analysis.global_index` with ``index=inverse_frobenius_condition_number``;
* ``gci`` of a parallel model: the mean of 1/kappa_F over a midpoint grid of the required
  box (the Cartesian measure over the region the design must serve), the joints from the
  closed-form ``ik``;
* ``workspace`` of a serial model: int |det J| dq over the joint limits (area/volume in
  m^d), estimated at the same nodes.

Constraints (the required box, inflated by the margin, sampled on a vertex grid with its
corners): a serial model's box configurations q_b satisfy fk(q_b) = p_b within the joint
limits (bounds of the variables); a parallel model's ``ik`` margin (the radicand of each
leg's solution) is >= 0 at every box point and objective node, and its actuated joints stay
within declared limits.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi
import numpy as np

from symkin.analysis import mechanism, sampling
from symkin.design import smooth
from symkin.design.problem import DesignProblem

#: Nodes of the serial objective (2**LOG2, Sobol, fixed seed) and per axis of the parallel one.
SERIAL_NODES_LOG2 = 8
PARALLEL_NODES_PER_AXIS = 5
#: Constraint points per axis of the required box (a vertex grid: corners, edges, faces).
BOX_POINTS_PER_AXIS = 4
#: Configurations sampled to start the box configurations of a serial model near a solution.
START_SAMPLES_LOG2 = 12


def casadi_function(model: Any, name: str) -> casadi.Function:
    """The ``casadi.Function`` behind a function of a model loaded with ``backend="casadi"``."""
    function = getattr(model, name, None)
    function = getattr(function, "func", function)  # a bound model wraps it in functools.partial
    if function is None or not hasattr(function, "casadi"):
        raise ValueError(f"{model.name}: no CasADi function '{name}'; derive the model with --backend numpy,casadi")
    return function.casadi


def _mapped(function: casadi.Function, count: int, arguments: dict[str, Any]) -> dict[str, Any]:
    """``function`` over ``count`` columns; scalars (the parameters) are shared by all."""
    wanted = set(function.name_in())
    return function.map(count)(**{k: v for k, v in arguments.items() if k in wanted})


def _blocks(matrix: Any, count: int) -> list[Any]:
    """The ``count`` square blocks of a mapped matrix output (rows x rows*count)."""
    width = matrix.shape[1] // count
    return [matrix[:, j * width:(j + 1) * width] for j in range(count)]


@dataclass
class Program:
    """A nonlinear program min f(x) s.t. lbg <= g(x) <= ubg, lbx <= x <= ubx, and how to read it.

    Attributes:
        x, f, g: CasADi SX expressions (f is -objective / |objective(start)|).
        x0, lbx, ubx, lbg, ubg: numeric start and bounds.
        objective: Function of the free parameter values (unscaled) -> the surrogate.
        free_count: the first ``free_count`` entries of x are the scaled free parameters.
        scales: value = x * scale for those.
        nodes: the objective's sample points (joint configurations or box points).
        box_points: the constraint points of the required box (or an empty array).
        description: the surrogate and its domain, in words.
    """

    x: casadi.SX
    f: casadi.SX
    g: casadi.SX
    x0: np.ndarray
    lbx: np.ndarray
    ubx: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray
    objective: casadi.Function
    free_count: int
    scales: np.ndarray
    nodes: np.ndarray
    box_points: np.ndarray
    description: str

    def free_values(self, x: np.ndarray) -> np.ndarray:
        """The free parameter values of a solution vector."""
        return np.asarray(x, dtype=np.float64).ravel()[:self.free_count] * self.scales


def formulate(problem: DesignProblem, casadi_model: Any, numpy_model: Any, *, nodes: int | None = None,
              box_points: int = BOX_POINTS_PER_AXIS, seed: int = 0) -> Program:
    """The CasADi program of a dimensioning problem.

    Args:
        problem: from :func:`symkin.design.problem.design_problem`.
        casadi_model: the model loaded with ``backend="casadi"`` (unbound).
        numpy_model: the same model with the numpy backend (start guesses only).
        nodes: serial: log2 of the Sobol node count; parallel: grid points per axis.
        box_points: constraint points per axis of the required box.
        seed: seed of the fixed Sobol nodes.
    """
    scales = np.array([p.scale for p in problem.free])
    z = casadi.SX.sym("z", len(problem.free))
    values: dict[str, Any] = dict(problem.values)
    values.update({p.name: z[k] * scales[k] for k, p in enumerate(problem.free)})
    build = _parallel if problem.parallel else _serial
    objective, g, lbg, ubg, extra, nodes_used, points, description = build(
        problem, casadi_model, numpy_model, values, nodes, box_points, seed)
    free_values = casadi.SX.sym("p", len(problem.free))
    objective_of = casadi.Function("objective", [z], [objective]).call([free_values / scales])[0]
    objective_function = casadi.Function("objective", [free_values], [objective_of], ["free"], ["surrogate"])
    start = np.array([p.start for p in problem.free])
    reference = abs(float(objective_function(start)))
    if not reference > 0:
        raise ValueError(f"the {problem.objective} surrogate is 0 at the start design {problem.start}: "
                         "start from a design with a nonsingular, reachable workspace")
    x = casadi.vertcat(z, extra[0])
    x0 = np.concatenate([start / scales, extra[1]])
    lbx = np.concatenate([[p.lower for p in problem.free] / scales, extra[2]])
    ubx = np.concatenate([[p.upper for p in problem.free] / scales, extra[3]])
    return Program(x, -objective / reference, g, x0, lbx, ubx, np.asarray(lbg, float), np.asarray(ubg, float),
                   objective_function, len(problem.free), scales, nodes_used, points, description)


def _serial(problem: DesignProblem, casadi_model: Any, numpy_model: Any, values: dict[str, Any],
            nodes: int | None, box_points: int, seed: int):
    limits = problem.limits
    q = sampling.sobol(limits[:, 0], limits[:, 1], SERIAL_NODES_LOG2 if nodes is None else nodes,
                       np.random.default_rng(seed))
    count = len(q)
    jacobian = _mapped(casadi_function(casadi_model, "jacobian"), count, {"q": casadi.DM(q.T), **values})
    rows = mechanism.position_rows(numpy_model)
    blocks = _blocks(next(iter(jacobian.values())), count)
    weights = casadi.sum1(casadi.vertcat(*[casadi.fabs(smooth.determinant(J)) for J in blocks]))
    if problem.objective == "gci":
        terms = [smooth.measure_weighted_inverse_frobenius(J, smooth.homogenized(J, problem.length, rows))
                 for J in blocks]
        objective = casadi.sum1(casadi.vertcat(*terms)) / weights
        description = (f"Frobenius GCI surrogate: sum |det J| / kappa_F / sum |det J| at {count} fixed Sobol "
                       "nodes over the joint limits (Cartesian measure dW = |det J| dq)")
    else:
        objective = weights * float(np.prod(limits[:, 1] - limits[:, 0])) / count
        description = f"workspace measure int |det J| dq over the joint limits, at {count} fixed Sobol nodes"
    if problem.box is None:
        return objective, casadi.SX(0, 1), [], [], (casadi.SX(0, 1), [], [], []), q, np.empty((0, 0)), description
    points = sampling.grid(*problem.inflated_box, box_points, midpoints=False)
    qb = casadi.SX.sym("q_box", q.shape[1], len(points))
    fk = _mapped(casadi_function(casadi_model, "fk"), len(points), {"q": qb, **values})
    transforms = _blocks(next(iter(fk.values())), len(points))
    axes = list(mechanism.position_axes(numpy_model))
    size = float(np.max(problem.box[1] - problem.box[0]))
    residuals = [(T[axes, 3] - casadi.DM(p)) / size for T, p in zip(transforms, points)]
    start = _nearest_configurations(numpy_model.bind(**problem.start), limits, points, axes, seed)
    count_b = len(points)
    lower = np.tile(limits[:, 0], count_b)
    upper = np.tile(limits[:, 1], count_b)
    g = casadi.vertcat(*residuals)
    zeros = np.zeros(g.shape[0])
    description += f"; the box is required at {count_b} points (fk(q_b) = p_b within the joint limits)"
    return (objective, g, zeros, zeros, (casadi.vec(qb), start.ravel(), lower, upper), q, points, description)


def _nearest_configurations(model: Any, limits: np.ndarray, points: np.ndarray, axes: list[int],
                            seed: int) -> np.ndarray:
    """For each point, the sampled configuration (within the limits) whose TCP is nearest: a start for IPOPT."""
    q = sampling.sobol(limits[:, 0], limits[:, 1], START_SAMPLES_LOG2, np.random.default_rng(seed + 1))
    tcp = model.fk(q)[:, axes, 3]
    nearest = np.argmin(((points[:, None, :] - tcp[None, :, :]) ** 2).sum(axis=-1), axis=1)
    return q[nearest]


def _parallel(problem: DesignProblem, casadi_model: Any, numpy_model: Any, values: dict[str, Any],
              nodes: int | None, box_points: int, seed: int):
    per_axis = PARALLEL_NODES_PER_AXIS if nodes is None else nodes
    p = sampling.grid(*problem.box, per_axis)
    ik = casadi_function(casadi_model, "ik")
    solved = _mapped(ik, len(p), {"p": casadi.DM(p.T), **values})
    joints, _ = (solved[name] for name in ik.name_out())
    jacobian = _mapped(casadi_function(casadi_model, "jacobian"), len(p), {"q": joints, "p": casadi.DM(p.T), **values})
    blocks = _blocks(next(iter(jacobian.values())), len(p))
    objective = casadi.sum1(casadi.vertcat(*[smooth.inverse_frobenius(J) for J in blocks])) / len(p)
    description = (f"Frobenius GCI surrogate: mean 1/kappa_F over a {per_axis}^{p.shape[1]} midpoint grid of the "
                   "required box (Cartesian measure), joints from the closed-form ik")
    corners = sampling.grid(*problem.inflated_box, box_points, midpoints=False)
    points = np.concatenate([corners, p])
    reach = _mapped(ik, len(points), {"p": casadi.DM(points.T), **values})
    reach_joints, margin = (reach[name] for name in ik.name_out())
    start_margin = np.asarray(numpy_model.ik(points, **problem.start)[1])
    if not np.all(np.isfinite(start_margin)):
        raise ValueError(f"{numpy_model.name}: the inverse kinematics fails at the start design")
    reference = float(np.median(np.abs(start_margin))) or 1.0
    g = [casadi.vec(margin) / reference]
    lbg, ubg = [np.zeros(margin.numel())], [np.full(margin.numel(), np.inf)]
    declared = np.array(numpy_model.joint_limits, dtype=np.float64)
    for k, (lo, hi) in enumerate(declared):
        if np.isfinite(lo) or np.isfinite(hi):
            g.append(reach_joints[k, :].T)
            lbg.append(np.full(len(points), lo))
            ubg.append(np.full(len(points), hi))
    description += f"; the box is required at {len(points)} points (ik margin >= 0)"
    return (objective, casadi.vertcat(*g), np.concatenate(lbg), np.concatenate(ubg), (casadi.SX(0, 1), [], [], []),
            p, points, description)
