"""The dimensioning problem as a CasADi nonlinear program (seed sec. 4.1 step 2).

Decision variables: the free parameters, scaled to order one (value / start), and, for a
serial model with a required box, one joint configuration per box point.  The generated
CasADi functions (``fk``, ``ik``, ``jacobian``: their parameters are inputs) are mapped
over fixed sample points, so the objective is a smooth function of the design:

* ``gci`` of a serial model: the Frobenius surrogate of the GCI (seed eq. 8.28) with the
  Cartesian measure dW = |det J| dq over the joint limits, at fixed Sobol nodes q_j,

      v_F = sum_j |det J_j| / kappa_F(J_j)  /  sum_j |det J_j|

  (:func:`symkin.design.smooth.measure_weighted_inverse_frobenius`); with the same nodes
  it is :func:`symkin.analysis.global_index` with ``index=inverse_frobenius_condition_number``,
  except that |det J_j| in the denominator is sqrt(det_j^2 + eps^2): where a node's det J
  changes sign as the design varies, |det J| has a kink that stalls IPOPT.  eps^2 =
  1e-6 mean_j det_j^2 scales with the design like det^2, so a design that only rescales
  det J (the 2R arm's l1 l2 |sin theta2|) keeps its optimum exactly; a node's weight
  grows by at most eps, relatively ~1e-6 at typical nodes;
* ``gci`` of a parallel model: the mean of 1/kappa_F over a midpoint grid of the required
  box (the Cartesian measure over the region the design must serve), the joints from the
  closed-form ``ik``; of a spherical platform (a box of roll, pitch, yaw) the mean of
  1/kappa_F of the angular-velocity Jacobian J_w = E(p) J weighted by the invariant measure
  of SO(3), dW = cos(pitch) d(roll) d(pitch) d(yaw) (:mod:`symkin.analysis.orientations`):

      v_F = sum_j cos(pitch_j) / kappa_F(E_j J_j)  /  sum_j cos(pitch_j);
* ``workspace`` of a serial model: int |det J| dq over the joint limits (area/volume in
  m^d), estimated at the same nodes (with the same smoothed |det J|);
* ``force``: the isotropic force f_iso = min_i tau_max,i / |J_i| (:mod:`symkin.rating.forces`,
  J_i the i-th column of J) at the worst point of the required box, in epigraph form: maximize a
  bound t subject to t |J_i(p_j)| <= tau_max,i at every point p_j and every actuator i, written
  (t |J_i| / tau_max,i)^2 <= 1 (smooth; the minimum over points and actuators has kinks where the
  worst one changes).  A parallel model's points are the box's vertex grid and the objective's
  midpoints, their joints from the closed-form ``ik``; a serial model's the box's vertex grid at
  its box configurations q_b (below), so the optimizer also chooses the configuration (e.g. the
  elbow's side) that holds each point best.  The reported surrogate is the worst force itself,
  min_j f_iso(p_j): of the design alone for a parallel model, of the design and the q_b for a
  serial one.

* ``gci`` of a parallel model without closed forms (legs analysed through their loop closure,
  :mod:`symkin.analysis.continued_workspace`): the same mean of 1/kappa_F over a midpoint grid of the
  required box of positions, the angles held at the home pose's; each point p_j has its assembly
  (q_j, s_j) as decision variables, constrained by the generated closure phi(q_j, s_j, p_j) = 0 on its rows
  R independent at the start design's home assembly (rows that vanish identically, e.g. a Schoenflies
  platform's roll and pitch rows, or repeat others are left out: IPOPT needs independent equality
  constraints), and J_j = dp/dq the p-part of -A^-1 Phi_q, A = [Phi_s Phi_p] on the rows R - the run-time
  mechanism's CasADi counterpart (:class:`symkin.mechanism.casadi_assembly.CasadiAssembly`, the design's
  lengths as symbols); roll-pitch-yaw rows as angular velocity (E(p) J) where the task space has all three,
  position rows divided by the characteristic length.

Constraints (the required box, inflated by the margin, sampled on a vertex grid with its
corners): a serial model's box configurations q_b satisfy fk(q_b) = p_b within the joint
limits (bounds of the variables); a closure model's (q_b, s_b) close the legs within the actuators' limits
and the declared passive-joint limits (bounds), their start continued from the home assembly in the working
mode (:func:`symkin.mechanism.continuation.continue_from`); a parallel model's ``ik`` margin (the radicand of each
leg's solution) is >= 0 at every box point and objective node, and its actuated joints stay
within their limits (declared or overridden), if any.  A bound m_max on the apparent mass at
the handle (every eigenvalue of Lambda = (J M^-1 J^T)^-1, :func:`symkin.rating.formulas.apparent_mass`,
at most m_max) holds at the same points as B = m_max J M^-1 J^T - 1 positive semidefinite:
every principal minor of B >= 0 (smooth in the design, where an eigenvalue is not).

Length: one program builder per way the mechanism is sampled (:class:`symkin.mechanism.Sampling`: Sobol nodes of a
joint box, a Cartesian grid through the closed-form ik, each point's assembly a variable) with its objectives and
constraints; they share the mapping of per-point functions over the points and the box configurations, which would
otherwise be passed between modules as private parts.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any, NamedTuple

import casadi
import numpy as np

from symkin.numerics import sampling
from symkin.rating import forces
from symkin import mechanism
from symkin.mechanism import Sampling, continuation
from symkin.mechanism import passive, stops
from symkin.mechanism.casadi_assembly import CasadiAssembly
from symkin.mechanism.limits import within_limits
from symkin.design import smooth
from symkin.design.problem import DesignProblem, held
from symkin.backends.casadi.loader import casadi_function
from symkin.runtime.info import GeneratedModel

#: Nodes of an objective over a joint box (2**LOG2, Sobol, fixed seed) and per axis of one over a Cartesian grid.
JOINT_NODES_LOG2 = 8
GRID_POINTS_PER_AXIS = 5
#: |det J| of the measure is smoothed as sqrt(det^2 + eps^2), eps = this times the rms of det J over the nodes.
DETERMINANT_SMOOTHING = 1e-3
#: Constraint points per axis of the required box (a vertex grid: corners, edges, faces).
BOX_POINTS_PER_AXIS = 4
#: Configurations sampled to start the box configurations of a serial model near a solution.
START_SAMPLES_LOG2 = 12


def angular_velocity_matrix(orientation: casadi.SX) -> casadi.SX:
    """E with omega = E d(roll, pitch, yaw)/dt: :func:`symkin.mechanism.reach.angular_velocity_matrix` in CasADi."""
    pitch, yaw = orientation[1], orientation[2]
    cp, sp, cy, sy = casadi.cos(pitch), casadi.sin(pitch), casadi.cos(yaw), casadi.sin(yaw)
    return casadi.vertcat(casadi.horzcat(cy * cp, -sy, 0), casadi.horzcat(sy * cp, cy, 0), casadi.horzcat(-sp, 0, 1))


def _node_function(name: str, node: casadi.SX, free: casadi.SX, outputs: casadi.SX) -> casadi.Function:
    """A function of one sample point and the free parameter values, to be mapped over all points."""
    return casadi.Function(name, [node, free], [outputs], ["node", "free"], [name])


def _call(function: casadi.Function, arguments: dict[str, Any]) -> list[casadi.SX]:
    """The outputs of a generated function called by name with the arguments it takes."""
    wanted = set(function.name_in())
    result = function.call({k: v for k, v in arguments.items() if k in wanted})
    return [result[name] for name in function.name_out()]


def _mapped(function: casadi.Function, nodes: Any, free: casadi.MX) -> casadi.MX:
    """``function`` at every column of ``nodes`` (d x N), the free values shared: (outputs x N)."""
    return function.map(nodes.shape[1], "serial")(nodes, free)


class _Terms(NamedTuple):
    """What a kind of mechanism contributes to the program."""

    objective: casadi.MX
    g: casadi.MX
    lbg: np.ndarray
    ubg: np.ndarray
    variables: casadi.MX  # extra decision variables (serial box configurations), with
    start: np.ndarray  # their start values
    lower: np.ndarray  # and bounds
    upper: np.ndarray
    nodes: np.ndarray
    box_points: np.ndarray
    description: str
    surrogate: casadi.MX | None = None  # the reported value (else: objective), of the design and ``symbols``
    symbols: tuple = ()  # the symbols ``variables`` stacks (each by casadi.vec, in this order)
    configuration_count: int = 0  # the entries of ``variables`` that are a serial model's box configurations


NO_VARIABLES = (casadi.MX(0, 1), np.empty(0), np.empty(0), np.empty(0))


@dataclass
class DesignProgram:
    """A nonlinear program min f(x) s.t. lbg <= g(x) <= ubg, lbx <= x <= ubx, and how to read it.

    Attributes:
        x, f, g: CasADi MX expressions (f is -objective / reference).
        x0, lbx, ubx, lbg, ubg: numeric start and bounds.
        objective: Function of the free parameter values (unscaled) and the program's other variables
            (x after them: a serial model's box configurations, an epigraph bound) -> the surrogate; the
            surrogates of the GCI and the workspace measure depend on the free values only.
        reference: |objective(start)|, the scale of f (surrogate = -f * reference).
        free_count: the first ``free_count`` entries of x are the scaled free parameters.
        scales: value = x * scale for those.
        nodes: the objective's sample points (joint configurations or box points).
        box_points: the constraint points of the required box (or an empty array).
        description: the surrogate and its domain, in words.
        configuration_count: the entries of x after the free parameters that are a serial model's joint
            configurations at the box points (a force bound follows them).
    """

    x: casadi.MX
    f: casadi.MX
    g: casadi.MX
    x0: np.ndarray
    lbx: np.ndarray
    ubx: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray
    objective: casadi.Function
    reference: float
    free_count: int
    scales: np.ndarray
    nodes: np.ndarray
    box_points: np.ndarray
    description: str
    configuration_count: int = 0

    def free_values(self, x: np.ndarray) -> np.ndarray:
        """The free parameter values of a solution vector."""
        return np.asarray(x, dtype=np.float64).ravel()[:self.free_count] * self.scales

    def surrogate(self, x: np.ndarray) -> float:
        """The surrogate at a solution vector x (the free values and the other variables)."""
        x = np.asarray(x, dtype=np.float64).ravel()
        return float(self.objective(self.free_values(x), x[self.free_count:]))


def formulate(problem: DesignProblem, casadi_model: GeneratedModel, numpy_model: GeneratedModel, *, nodes: int | None = None,
              box_points: int = BOX_POINTS_PER_AXIS, seed: int = 0) -> DesignProgram:
    """The CasADi program of a dimensioning problem.

    Each term is a CasADi function of one sample point and the free parameter values, built
    from the generated functions (SX) and mapped over the points (MX): the program and
    its exact Hessian stay small however many points there are.

    Args:
        problem: from :func:`symkin.design.problem.design_problem`.
        casadi_model: the model loaded with ``backend="casadi"`` (unbound).
        numpy_model: the same model with the numpy backend (start guesses only).
        nodes: serial: log2 of the Sobol node count; parallel: grid points per axis.
        box_points: constraint points per axis of the required box.
        seed: seed of the fixed Sobol nodes.
    """
    scales = problem.scales
    free = casadi.SX.sym("free", len(problem.free))
    values: dict[str, Any] = dict(problem.values)
    values.update({p.name: free[k] for k, p in enumerate(problem.free)})
    z = casadi.MX.sym("z", len(problem.free))
    build = {Sampling.CONTINUATION: _assembly_terms, Sampling.JOINTS: _joint_box_terms}.get(problem.sampling, _inverse_grid_terms)
    terms = build(problem, casadi_model, numpy_model, free, values, z * scales, nodes, box_points, seed)
    free_values = casadi.MX.sym("free", len(problem.free))
    others = casadi.MX.sym("variables", terms.variables.numel())
    surrogate = terms.objective if terms.surrogate is None else terms.surrogate
    inner = casadi.Function("surrogate_of_symbols", [z, *terms.symbols], [surrogate])
    objective_function = casadi.Function("surrogate", [free_values, others],
                                         [inner(free_values / scales, *_split(others, terms.symbols))],
                                         ["free", "variables"], ["surrogate"])
    start = np.array([p.start for p in problem.free])
    reference = abs(float(objective_function(start, terms.start)))
    if not reference > 0:
        raise ValueError(f"the {problem.objective} surrogate is 0 at the start design {problem.start}: "
                         "start from a design with a nonsingular, reachable workspace")
    return DesignProgram(casadi.vertcat(z, terms.variables), -terms.objective / reference, terms.g,
                   np.concatenate([problem.scaled_start, terms.start]),
                   np.concatenate([[low for low, _ in problem.scaled_bounds], terms.lower]),
                   np.concatenate([[high for _, high in problem.scaled_bounds], terms.upper]),
                   np.asarray(terms.lbg, float), np.asarray(terms.ubg, float), objective_function,
                   reference, len(problem.free), scales, terms.nodes, terms.box_points, terms.description,
                   terms.configuration_count)


def _split(vector: casadi.MX, symbols: tuple[casadi.MX, ...]) -> list[casadi.MX]:
    """``vector`` cut into the shapes of ``symbols`` (each filled column-major, as casadi.vec flattens)."""
    parts, offset = [], 0
    for symbol in symbols:
        rows, columns = symbol.shape
        parts.append(casadi.reshape(vector[offset:offset + rows * columns], rows, columns))
        offset += rows * columns
    return parts


def _joint_box_terms(problem: DesignProblem, casadi_model: GeneratedModel, numpy_model: GeneratedModel, free: casadi.SX, values: dict[str, Any],
            design: casadi.MX, nodes: int | None, box_points: int, seed: int) -> _Terms:
    limits = problem.joint_limits
    n = limits.shape[0]
    node = casadi.SX.sym("q", n)
    J = _call(casadi_function(casadi_model, "jacobian"), {"q": node, **values})[0]
    if problem.objective == "force":
        return _box_force_terms(problem, casadi_model, numpy_model, node, free, J, values, design, box_points, seed)
    sampled = joint_nodes(problem, numpy_model, nodes, seed)
    q = sampled.points
    rows = mechanism.position_rows(numpy_model)
    term = smooth.measure_weighted_inverse_frobenius(J, smooth.homogenized(J, problem.length, rows))
    per_node = _node_function("gci_terms", node, free, casadi.vertcat(term, smooth.determinant(J)))
    terms = _mapped(per_node, casadi.DM(q.T), design)
    det = terms[1, :]
    floor = DETERMINANT_SMOOTHING**2 * casadi.sumsqr(det) / len(q)
    weights = casadi.sum2(casadi.sqrt(det * det + floor))
    objective = (casadi.sum2(terms[0, :]) / weights if problem.objective == "gci"
                 else weights * sampled.volume_per_node)
    description = sampled.description
    if problem.box is None:
        return _Terms(objective, casadi.MX(0, 1), np.empty(0), np.empty(0), *NO_VARIABLES, q, np.empty((0, 0)),
                      description)
    box = _box_configurations(problem, casadi_model, numpy_model, node, free, values, design, box_points, seed)
    description += f"; the box is required at {len(box.points)} points (fk(q_b) = p_b within the joint limits{sampled.within})"
    return _Terms(objective, box.g, box.lbg, box.ubg, casadi.vec(box.qb), box.start.ravel(), box.lower,
                  box.upper, q, box.points, description, symbols=(box.qb,), configuration_count=box.qb.numel())


class JointNodes(NamedTuple):
    """The fixed nodes of a serial model's surrogate over its joint box."""

    points: np.ndarray  # (N, n) configurations within the joint stops
    volume_per_node: float  # the box's volume over every sampled node (those outside the stops are outside)
    description: str  # the surrogate and its domain, in words
    within: str  # " within the joint stops" where the model declares some, else ""


def joint_nodes(problem: DesignProblem, numpy_model: GeneratedModel, nodes: int | None = None,
                seed: int = 0) -> JointNodes:
    """The nodes of a serial model's GCI or workspace surrogate: 2**``nodes`` (default 2**JOINT_NODES_LOG2)
    scrambled Sobol points of the joint limits (seeded by ``seed``), those outside the joint stops dropped.  The
    CasADi program and the JAX one (:mod:`symkin.design.gradient_solving`) share them, so both optimize one
    function."""
    limits = problem.joint_limits
    q = sampling.sobol(limits[:, 0], limits[:, 1], JOINT_NODES_LOG2 if nodes is None else nodes,
                       np.random.default_rng(seed))
    sampled = len(q)
    joint_stops = stops.StopInequalities.of_model(numpy_model)
    q = q[joint_stops.respected(q)]
    count = len(q)
    if not count:
        raise ValueError(f"{numpy_model.name}: no sampled configuration lies within the joint stops; widen the joint "
                         "limits or the stops")
    within = " within the joint stops" if len(joint_stops) else ""
    if problem.objective == "gci":
        description = (f"Frobenius GCI surrogate: sum |det J| / kappa_F / sum |det J| at {count} fixed Sobol "
                       f"nodes over the joint limits{within} (Cartesian measure dW = |det J| dq, |det J| smoothed by "
                       f"{DETERMINANT_SMOOTHING:g} rms det J)")
    else:
        description = (f"workspace measure int |det J| dq over the joint limits{within}, at {count} of {sampled} "
                       "fixed Sobol nodes")
    return JointNodes(q, float(np.prod(limits[:, 1] - limits[:, 0])) / sampled, description, within)


class _BoxConfigurations(NamedTuple):
    """A serial model's joint configurations q_b (n, P) at the box points p_b, with fk(q_b) = p_b and the joint
    stops required: lbg <= g <= ubg."""

    points: np.ndarray  # p_b (P, d)
    qb: casadi.MX  # the configurations, decision variables
    g: casadi.MX  # vec((fk(q_b) - p_b) / box size), to be 0, then the stops at each q_b (:func:`_within_stops`)
    lbg: np.ndarray
    ubg: np.ndarray
    start: np.ndarray  # (P, n) start values
    lower: np.ndarray  # bounds of vec(q_b): the joint limits
    upper: np.ndarray


def _within_stops(model: GeneratedModel, q: casadi.MX) -> tuple[casadi.MX, np.ndarray, np.ndarray]:
    """The model's joint stops (``joint_stops:``, :class:`symkin.mechanism.stops.StopInequalities`) at the
    configurations q (n, P), a column each, as linear constraints lbg <= g <= ubg: (vec(A q), lower - b, upper - b),
    k rows per configuration (none without stops)."""
    inequalities = stops.StopInequalities.of_model(model)
    points = q.shape[1]
    return (casadi.vec(casadi.mtimes(casadi.DM(inequalities.rows), q)),
            np.tile(inequalities.lower - inequalities.offsets, points),
            np.tile(inequalities.upper - inequalities.offsets, points))


def _box_configurations(problem: DesignProblem, casadi_model: GeneratedModel, numpy_model: GeneratedModel,
                        node: casadi.SX, free: casadi.SX, values: dict[str, Any], design: casadi.MX, box_points: int,
                        seed: int) -> _BoxConfigurations:
    """The configurations at the vertex grid of the inflated box (``box_points`` per axis)."""
    limits = problem.joint_limits
    points = sampling.grid(*problem.inflated_box, box_points, midpoints=False)
    axes = list(mechanism.position_axes(numpy_model))
    T = _call(casadi_function(casadi_model, "fk"), {"q": node, **values})[0]
    position = _node_function("tcp", node, free, T[axes, 3])
    qb = casadi.MX.sym("q_box", limits.shape[0], len(points))
    lower, upper = problem.required_box
    size = float(np.max(upper - lower))
    residuals = (_mapped(position, qb, design) - casadi.DM(points.T)) / size
    start = _nearest_configurations(numpy_model.bind(**problem.start), limits, points, axes, seed)
    stop_rows, stop_lower, stop_upper = _within_stops(numpy_model, qb)
    zeros = np.zeros(residuals.numel())
    return _BoxConfigurations(points, qb, casadi.vertcat(casadi.vec(residuals), stop_rows),
                              np.concatenate([zeros, stop_lower]), np.concatenate([zeros, stop_upper]), start,
                              np.tile(limits[:, 0], len(points)), np.tile(limits[:, 1], len(points)))


def _box_force_terms(problem: DesignProblem, casadi_model: GeneratedModel, numpy_model: GeneratedModel, node: casadi.SX,
                  free: casadi.SX, J: casadi.SX, values: dict[str, Any], design: casadi.MX, box_points: int,
                  seed: int) -> _Terms:
    """A serial model's isotropic force at the worst box point, at its box configurations (epigraph form)."""
    box = _box_configurations(problem, casadi_model, numpy_model, node, free, values, design, box_points, seed)
    limits = np.asarray(problem.effort_limits, dtype=np.float64)
    # (|J_i| / tau_max,i)^2 per actuator i (rows) and box point (columns), at the box configurations
    squared = _mapped(_node_function("force_rows", node, free, (casadi.sum1(J * J) / casadi.DM(limits**2).T).T),
                      box.qb, design)
    at_start = numpy_model.bind(**problem.start)
    start = float(np.min(forces.isotropic_force(at_start.jacobian(box.start), limits)))
    if not start > 0:
        raise ValueError(f"{numpy_model.name}: the isotropic force vanishes in the box at the start design")
    bound = casadi.MX.sym("force_bound")  # t / (the start's worst force, at the start configurations)
    g = casadi.vertcat(box.g, casadi.vec((bound * start) ** 2 * squared))
    description = (f"isotropic force min_i tau_max,i / |J_i| at the worst of the box's {box_points}^{box.points.shape[1]} "
                   f"vertex grid (epigraph form), effort limits {', '.join(f'{v:g}' for v in limits)}, at the box "
                   "configurations q_b with fk(q_b) = p_b within the joint limits and stops")
    return _Terms(bound * start, g, np.concatenate([box.lbg, np.full(squared.numel(), -np.inf)]),
                  np.concatenate([box.ubg, np.ones(squared.numel())]), casadi.vertcat(casadi.vec(box.qb), bound),
                  np.concatenate([box.start.ravel(), [1.0]]), np.concatenate([box.lower, [0.0]]),
                  np.concatenate([box.upper, [np.inf]]), box.points, box.points, description,
                  casadi.mmin(1 / casadi.sqrt(squared)), (box.qb, bound), box.qb.numel())


def _nearest_configurations(model: GeneratedModel, limits: np.ndarray, points: np.ndarray, axes: list[int],
                            seed: int) -> np.ndarray:
    """For each point, the sampled configuration (within the limits and stops) whose TCP is nearest: a start for
    IPOPT."""
    q = sampling.sobol(limits[:, 0], limits[:, 1], START_SAMPLES_LOG2, np.random.default_rng(seed + 1))
    q = q[stops.respected(model, q)]
    tcp = model.fk(q)[:, axes, 3]
    nearest = np.argmin(((points[:, None, :] - tcp[None, :, :]) ** 2).sum(axis=-1), axis=1)
    return q[nearest]


class InverseGrid(NamedTuple):
    """Where a parallel model's GCI surrogate is taken and its required box is checked (also by the JAX path,
    :mod:`symkin.design.gradient_solving`)."""

    nodes: np.ndarray  # the objective's midpoint grid of the required box (N, d)
    weights: np.ndarray  # the measure's weight at each node (1, or cos(pitch) for orientations), normalized to sum 1
    points: np.ndarray  # where every leg must reach: the inflated box's vertex grid, then the nodes
    description: str  # the surrogate and its points, in words


def inverse_grid(problem: DesignProblem, nodes: int | None, box_points: int) -> InverseGrid:
    """The nodes, weights and constraint points of a parallel model's GCI surrogate over its required box."""
    per_axis = GRID_POINTS_PER_AXIS if nodes is None else nodes
    p = sampling.grid(*problem.required_box, per_axis)
    if problem.sampling is Sampling.ORIENTATIONS:
        weights = np.cos(p[:, 1])
        measure = "the invariant measure of SO(3), cos(pitch) droll dpitch dyaw, for J_w = E(p) J"
    else:
        weights = np.ones(len(p))
        measure = "Cartesian measure"
    points = np.concatenate([sampling.grid(*problem.inflated_box, box_points, midpoints=False), p])
    held = ""
    if problem.orientation is not None:
        angles = ", ".join(f"{a:g}" for a in np.degrees(problem.orientation))
        held = (f" at the constant orientation roll, pitch, yaw = {angles} deg, of the twist Jacobian with its "
                f"position rows divided by L = {problem.length:g} m (kappa_F of J^-1 diag(L I, E^-1))")
    description = (f"Frobenius GCI surrogate: mean 1/kappa_F over a {per_axis}^{p.shape[1]} midpoint grid of the "
                   f"required box ({measure}){held}, joints from the closed-form ik; the box is required at "
                   f"{len(points)} points (ik margin >= 0)")
    return InverseGrid(p, weights / weights.sum(), points, description)


def margin_reference(problem: DesignProblem, numpy_model: GeneratedModel, points: np.ndarray) -> float:
    """The scale of the ik margins in the reach constraints: their median magnitude at ``points`` at the start
    design (ValueError where the ik fails there)."""
    start_margin = np.asarray(held(problem, numpy_model.bind(**problem.start)).ik(points)[1])
    if not np.all(np.isfinite(start_margin)):
        raise ValueError(f"{numpy_model.name}: the inverse kinematics fails at the start design")
    return float(np.median(np.abs(start_margin))) or 1.0


def _inverse_grid_terms(problem: DesignProblem, casadi_model: GeneratedModel, numpy_model: GeneratedModel, free: casadi.SX, values: dict[str, Any],
              design: casadi.MX, nodes: int | None, box_points: int, seed: int) -> _Terms:
    per_axis = GRID_POINTS_PER_AXIS if nodes is None else nodes
    node = casadi.SX.sym("p", len(problem.required_box[0]))
    pose = node if problem.orientation is None else casadi.vertcat(node, casadi.DM(problem.orientation))
    joints, margin = _call(casadi_function(casadi_model, "ik"), {"p": pose, **values})
    if problem.orientation is None:
        J = _call(casadi_function(casadi_model, "jacobian"), {"q": joints, "p": node, **values})[0]
    else:  # kappa_F of J_h^-1 = J^-1 D is that of J_h (DesignProblem.held_inverse_scaling)
        inverse = _call(casadi_function(casadi_model, "inverse_jacobian"), {"q": joints, "p": pose, **values})[0]
        J = casadi.mtimes(inverse, casadi.DM(problem.held_inverse_scaling))
    masses = _apparent_mass_rows(problem, casadi_model, node, joints, J, values)
    if problem.objective == "force":
        return _force(problem, numpy_model, node, free, J, margin, joints, masses, design, per_axis, box_points)
    grid = inverse_grid(problem, nodes, box_points)
    if problem.sampling is Sampling.ORIENTATIONS:
        J = angular_velocity_matrix(node) @ J
    index = _node_function("inverse_frobenius", node, free, smooth.inverse_frobenius(J))
    objective = casadi.mtimes(_mapped(index, casadi.DM(grid.nodes.T), design), casadi.DM(grid.weights))
    minors, g, lbg, ubg = _reach(problem, numpy_model, node, free, margin, joints, masses, grid.points, design)
    description = grid.description + _bound_apparent_mass(problem, minors, g, lbg, ubg)
    return _Terms(objective, casadi.vertcat(*g), np.concatenate(lbg), np.concatenate(ubg), *NO_VARIABLES, grid.nodes,
                  grid.points, description)


class JointRules(NamedTuple):
    """The linear constraints on a parallel model's joints q at each point of its required box,
    lower <= rows q + offsets <= upper: the actuated joints' limits where the problem gives them (rows of the
    identity), then the joint stops (:class:`symkin.mechanism.stops.StopInequalities`).  One description for both
    programs that require the box: the CasADi one (:func:`_reach`) and the JAX one
    (:mod:`symkin.design.gradient_solving`); a side may be infinite.

    A revolute joint with finite limits is an angle: both programs take it as its representative within pi of the
    limits' centre c (:meth:`centred`), as :func:`symkin.mechanism.limits.within_limits` takes it within the limits, so
    that a joint passing the +-pi of the ik's atan2 inside its range (the pantograph's, limited to [0, pi]) moves the
    constraint by its step, not by 2 pi (a jump that stops SLSQP's line search)."""

    rows: np.ndarray  # (k, n)
    offsets: np.ndarray  # (k,)
    lower: np.ndarray  # (k,)
    upper: np.ndarray  # (k,)
    centres: np.ndarray  # (n,): c of each joint taken within pi of it, NaN for the others

    def centred(self, joints: Any, xp: Any = np) -> Any:
        """Joints (..., n) with each angle of :attr:`centres` moved by a multiple of 2 pi to within pi of its c:
        c + atan2(sin(q - c), cos(q - c)), smooth but at c +- pi, outside the limits (``xp``: numpy or casadi)."""
        if xp is casadi:
            return casadi.vertcat(*[joints[i] if np.isnan(c) else c + casadi.atan2(casadi.sin(joints[i] - c),
                                                                                     casadi.cos(joints[i] - c))
                                    for i, c in enumerate(self.centres)])
        centred = self.centres + np.arctan2(np.sin(joints - self.centres), np.cos(joints - self.centres))
        return np.where(np.isnan(self.centres), joints, centred)


def joint_rules(problem: DesignProblem, numpy_model: GeneratedModel) -> JointRules:
    """The :class:`JointRules` of ``problem`` on ``numpy_model``."""
    n = len(numpy_model.info.coordinates)
    inequalities = stops.StopInequalities.of_model(numpy_model)
    limits = np.empty((0, 2)) if problem.limits is None else np.asarray(problem.limits, dtype=np.float64)
    centres = np.full(n, np.nan)
    angles = mechanism.revolute_mask(numpy_model)[:len(limits)] & np.all(np.isfinite(limits), axis=1)
    centres[:len(limits)][angles] = limits[angles].mean(axis=1)
    return JointRules(np.vstack([np.eye(n)[:len(limits)], inequalities.rows.reshape(-1, n)]),
                      np.concatenate([np.zeros(len(limits)), inequalities.offsets]),
                      np.concatenate([limits[:, 0], inequalities.lower]),
                      np.concatenate([limits[:, 1], inequalities.upper]), centres)


def _reach(problem: DesignProblem, numpy_model: GeneratedModel, node: casadi.SX, free: casadi.SX,
           margin: casadi.SX, joints: casadi.SX, extra: casadi.SX, points: np.ndarray, design: casadi.MX
           ) -> tuple[casadi.MX, list[casadi.MX], list[np.ndarray], list[np.ndarray]]:
    """The ``extra`` rows at every point, and the constraints that every leg reaches every point (ik margin
    >= 0, scaled by its median at the start) with its joints within the problem's :class:`JointRules`:
    (extra, g, lbg, ubg); each rule's rows at every point in turn."""
    reference = margin_reference(problem, numpy_model, points)
    margins = margin.numel()
    rules = joint_rules(problem, numpy_model)
    joints = rules.centred(joints, casadi)
    reached = _mapped(_node_function("reach", node, free, casadi.vertcat(margin / reference, joints, extra)),
                      casadi.DM(points.T), design)
    # the identity's rows sparse: each a joint itself, exactly (no 0 * other joint terms)
    ruled = casadi.mtimes(casadi.sparsify(casadi.DM(rules.rows)), reached[margins:margins + joints.numel(), :])
    g = [casadi.vec(reached[:margins, :]), casadi.vec(ruled.T)]
    lbg = [np.zeros(margins * len(points)), np.repeat(rules.lower - rules.offsets, len(points))]
    ubg = [np.full(margins * len(points), np.inf), np.repeat(rules.upper - rules.offsets, len(points))]
    return reached[margins + joints.numel():, :], g, lbg, ubg


def _apparent_mass_rows(problem: DesignProblem, casadi_model: GeneratedModel, node: casadi.SX, joints: casadi.SX,
                        J: casadi.SX, values: dict[str, Any]) -> casadi.SX:
    """The principal minors of B = m_max J M^-1 J^T - 1 at a point (all >= 0: every apparent mass <= m_max; see the
    module docstring), or no rows without a bound."""
    if problem.max_apparent_mass is None:
        return casadi.SX(0, 1)
    M = _call(casadi_function(casadi_model, "mass_matrix"), {"q": joints, "p": node, **values})[0]
    size = J.shape[0]
    B = problem.max_apparent_mass * casadi.mtimes(J, casadi.solve(M, J.T)) - casadi.SX.eye(size)
    return casadi.vertcat(*[casadi.det(B[rows, rows]) for rows in principal_subsets(size)])


def _bound_apparent_mass(problem: DesignProblem, minors: casadi.MX, g: list[casadi.MX], lbg: list[np.ndarray],
                         ubg: list[np.ndarray]) -> str:
    """Append the apparent-mass constraints (``minors`` at every point >= 0) and describe them."""
    if problem.max_apparent_mass is None:
        return ""
    g.append(casadi.vec(minors))
    lbg.append(np.zeros(minors.numel()))
    ubg.append(np.full(minors.numel(), np.inf))
    return apparent_mass_description(problem)


def apparent_mass_description(problem: DesignProblem) -> str:
    """The words of the apparent-mass constraints (both programs that require a box state them so), or ""."""
    if problem.max_apparent_mass is None:
        return ""
    return (f"; the apparent mass at the handle is at most {problem.max_apparent_mass:g} kg at every point "
            "(principal minors of m_max J M^-1 J^T - 1 >= 0)")


def principal_subsets(size: int) -> list[list[int]]:
    """The index sets of every principal minor of a size x size matrix, by size then lexicographically (both
    programs' order of the apparent-mass constraints)."""
    return [list(rows) for count in range(1, size + 1) for rows in itertools.combinations(range(size), count)]


def _force(problem: DesignProblem, numpy_model: GeneratedModel, node: casadi.SX, free: casadi.SX, J: casadi.SX,
           margin: casadi.SX, joints: casadi.SX, masses: casadi.SX, design: casadi.MX, per_axis: int,
           box_points: int) -> _Terms:
    """The isotropic force at the worst point of the box, in epigraph form (see the module docstring)."""
    corners = sampling.grid(*problem.inflated_box, box_points, midpoints=False)
    p = sampling.grid(*problem.required_box, per_axis)
    points = np.concatenate([corners, p])
    limits = np.asarray(problem.effort_limits, dtype=np.float64)
    # (|J_i| / tau_max,i)^2 per actuator i (rows) and point (columns)
    rows = (casadi.sum1(J * J) / casadi.DM(limits**2).T).T
    extra, g, lbg, ubg = _reach(problem, numpy_model, node, free, margin, joints, casadi.vertcat(rows, masses),
                                points, design)
    squared, minors = extra[:rows.numel(), :], extra[rows.numel():, :]
    worst = casadi.mmin(1 / casadi.sqrt(squared))
    at_start = numpy_model.bind(**problem.start)
    start = float(np.min(forces.isotropic_force(at_start.jacobian(at_start.ik(points).joints, points), limits)))
    if not start > 0:
        raise ValueError(f"{numpy_model.name}: the isotropic force vanishes in the box at the start design")
    bound = casadi.MX.sym("force_bound")  # t / (the start design's worst force)
    g.append(casadi.vec((bound * start) ** 2 * squared))
    lbg.append(np.full(squared.numel(), -np.inf))
    ubg.append(np.ones(squared.numel()))
    description = (f"isotropic force min_i tau_max,i / |J_i| at the worst of {len(points)} points (the box's "
                   f"{box_points}^{p.shape[1]} vertex grid and {per_axis}^{p.shape[1]} midpoints; epigraph form), "
                   f"effort limits {', '.join(f'{v:g}' for v in limits)}; the box is required at every point "
                   "(ik margin >= 0)") + _bound_apparent_mass(problem, minors, g, lbg, ubg)
    return _Terms(bound * start, casadi.vertcat(*g), np.concatenate(lbg), np.concatenate(ubg), bound, np.ones(1),
                  np.zeros(1), np.full(1, np.inf), p, points, description, worst, (bound,))


def _assembly_bounds(problem: DesignProblem, model: GeneratedModel, n: int, ns: int) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper), each (n + ns,): the bounds of one point's (q, s), the actuators' limits (problem.limits) and
    the declared passive-joint limits; an angle whose limits span a full turn (a revolute joint without declared
    limits) is unbounded (a bound at +-pi would stop it turning through pi as the design changes)."""
    lower, upper = np.full(n + ns, -np.inf), np.full(n + ns, np.inf)
    if problem.limits is not None:
        turn = mechanism.revolute_mask(model) & (problem.limits[:, 1] - problem.limits[:, 0] >= 2 * np.pi)
        lower[:n] = np.where(turn, -np.inf, problem.limits[:, 0])
        upper[:n] = np.where(turn, np.inf, problem.limits[:, 1])
    declared = passive.declared_limits(model)
    if declared is not None:
        lower[n + declared.columns], upper[n + declared.columns] = declared.bounds[:, 0], declared.bounds[:, 1]
    return lower, upper


def _assembly_starts(problem: DesignProblem, model: GeneratedModel, poses: np.ndarray, lower: np.ndarray,
                    upper: np.ndarray) -> np.ndarray:
    """(P, n + ns): the start design's assembly at each pose, continued from its home assembly in the working mode
    (straight paths in steps of 1/64 of the box), revolute joints shifted by 2 pi into their bounds.

    Raises:
        ValueError: a pose is not reached that way (the start design does not serve the box).
    """
    bound = model.bind(**problem.start)
    step = float(np.max(problem.inflated_box[1] - problem.inflated_box[0])) / 64
    q, s, taken = continuation.continue_from_home(bound, poses, step=step, limits=problem.limits)
    if not taken.all():
        missed = poses[~taken][0]
        raise ValueError(f"{model.name}: the start design does not reach the required box from its home pose in the "
                         f"working mode ({int(np.count_nonzero(~taken))} of {len(poses)} points missed, e.g. "
                         f"{missed.round(6).tolist()}): start from a design that serves the box, or shrink it")
    revolute = np.concatenate([mechanism.revolute_mask(bound),
                               [unit == "rad" for unit in bound.info.functions["closure"].inputs[1].units]])
    values = np.hstack([q, s])
    finite = np.isfinite(lower)
    shifted = within_limits(values[:, finite], np.stack([lower[finite], upper[finite]], axis=1), revolute[finite])[0]
    values[:, finite] = np.where(revolute[finite], shifted, values[:, finite])
    return values


def _assembly_terms(problem: DesignProblem, casadi_model: GeneratedModel, numpy_model: GeneratedModel, free: casadi.SX,
             values: dict[str, Any], design: casadi.MX, nodes: int | None, box_points: int, seed: int) -> _Terms:
    """The GCI over the required box of legs without closed forms, each point's assembly a decision variable (see
    the module docstring)."""
    per_axis = GRID_POINTS_PER_AXIS if nodes is None else nodes
    task = mechanism.task_space(numpy_model)
    positions = np.array([c in mechanism.POSITION_COMPONENTS for c in task])
    template = mechanism.home_pose(numpy_model)

    def poses(points: np.ndarray) -> np.ndarray:
        result = np.repeat(template[None, :], len(points), axis=0)
        result[:, positions] = points
        return result

    p = sampling.grid(*problem.required_box, per_axis)
    corners = sampling.grid(*problem.inflated_box, box_points, midpoints=False)
    targets = poses(np.concatenate([corners, p]))
    assembly = CasadiAssembly.at_home(casadi_model, numpy_model.bind(**problem.start), values)
    n, ns, m = assembly.n, assembly.ns, assembly.m
    q, s, pose = casadi.SX.sym("q", n), casadi.SX.sym("s", ns), casadi.SX.sym("p", m)
    J = assembly.jacobian(q, s, pose)
    if {"roll", "pitch", "yaw"} <= set(task):
        angles = [task.index(c) for c in ("roll", "pitch", "yaw")]
        rates = casadi.SX.eye(m)
        rates[angles, angles] = angular_velocity_matrix(pose[angles])
        J = rates @ J
    J = smooth.homogenized(J, problem.length, mechanism.position_rows(numpy_model))
    node = casadi.vertcat(q, s, pose)
    assemblies = casadi.MX.sym("assemblies", n + ns, len(targets))
    columns = casadi.vertcat(assemblies, casadi.DM(targets.T))
    residuals = _mapped(_node_function("assembly_rows", node, free, assembly.residual(q, s, pose)), columns, design)
    index = _node_function("inverse_frobenius", node, free, smooth.inverse_frobenius(J))
    objective = casadi.sum2(_mapped(index, columns[:, len(corners):], design)) / len(p)  # the midpoints only
    lower, upper = _assembly_bounds(problem, numpy_model, n, ns)
    start = _assembly_starts(problem, numpy_model, targets, lower, upper)
    stop_rows, stop_lower, stop_upper = _within_stops(numpy_model, assemblies[:n, :])
    zeros = np.zeros(len(assembly.rows) * len(targets))
    held = ", ".join(f"{c} = {template[k]:g}" for k, c in enumerate(task) if not positions[k])
    description = (f"Frobenius GCI surrogate: mean 1/kappa_F over a {per_axis}^{p.shape[1]} midpoint grid of the "
                   f"required box ({held} held; position rows divided by L = {problem.length:g} m)"
                   if problem.length is not None else
                   f"Frobenius GCI surrogate: mean 1/kappa_F over a {per_axis}^{p.shape[1]} midpoint grid of the "
                   "required box")
    description += (f", J from the closure at each point's assembly (q, s), a decision variable; the box is "
                    f"required at {len(targets)} points (the closure's {len(assembly.rows)} independent rows = 0, the "
                    "joints within their limits and stops, started in the home assembly's working mode)")
    return _Terms(objective, casadi.vertcat(casadi.vec(residuals), stop_rows), np.concatenate([zeros, stop_lower]),
                  np.concatenate([zeros, stop_upper]), casadi.vec(assemblies), start.ravel(),
                  np.tile(lower, len(targets)), np.tile(upper, len(targets)), p, targets[:, positions], description,
                  symbols=(assemblies,), configuration_count=assemblies.numel())
