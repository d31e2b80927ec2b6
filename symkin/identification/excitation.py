"""Excitation trajectories for identification: a periodic motion that makes the base regressor well conditioned.

The estimate's accuracy is bounded by the conditioning of the stacked base regressor W = [Y_b(t_1); ...;
Y_b(t_K)] over the run (:mod:`symkin.identification.estimation`): each joint follows a finite Fourier series
(Swevers, Ganseman, Tukel, De Schutter and Van Brussel, "Optimal robot excitation and identification", IEEE
Trans. Robot. Autom. 13(5), 1997)

    q_j(t)   = q0_j + sum_l a_jl / (l w) sin(l w t) - b_jl / (l w) cos(l w t)
    qd_j(t)  =        sum_l a_jl cos(l w t) + b_jl sin(l w t)
    qdd_j(t) =        sum_l -a_jl l w sin(l w t) + b_jl l w cos(l w t),      w = 2 pi / T,

periodic by construction (the run may repeat and be averaged), starting and ending at rest (qd = qdd = 0 at
t = 0).  The coefficients are chosen with CasADi and IPOPT (:mod:`symkin.design`'s solver) to minimize a
smooth bound of cond(W S)^2, S the column scaling of the start (so that the criterion does not depend on
the parameters' units):

    log ||F||_F + log trace(F^-1) >= log cond(F),   F = (W S)^T (W S) / K,

both terms differentiable where cond(W S) is finite (||F||_F >= lambda_max, trace(F^-1) >= 1 / lambda_min,
each within a factor of the number of parameters), subject to the joint position limits, the model's stops on
combinations of joints (``joint_stops:``, as linear constraints on the series) and the given velocity and
acceleration limits at every sample (and checked on a grid ten times as dense).  The columns
of the Coulomb friction (sign(qd)) are piecewise constant: they count in W but give no gradient.  A parallel
model's base regressor takes the platform's pose: p = fk(q) along the motion (its CasADi fk composed), whose
legs must assemble at every constraint point (fk's margin >= 0); a hybrid device's wrist joints follow series of
their own after the legs' actuators (the device's joints, as a run records them).  A platform without a closed-form
fk (the Stewart-Gough platform) moves its pose p instead: the series are the task coordinates', the actuators
follow q = ik(p) with qd = (dq/dp) pd and qdd = (dqd/dp) pd + (dqd/dpd) pdd (CasADi's forward derivatives of the
generated ik), and the actuators' limits and the legs' assembly (ik's margin >= 0) hold at the constraint points.
Legs without the distance form (no fk, no ik) move their actuators about the home assembly, each sample's
assembly found by a rootfinder (:mod:`symkin.identification.closure_excitation`), and the result is shrunk until the legs
close along the whole period.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import casadi
import numpy as np

from symkin.identification import closure_excitation, excitation_bounds
from symkin.backends.casadi.loader import casadi_function
from symkin.design.solving import IPOPT_OPTIONS, IterationReport
from symkin.runtime.info import GeneratedModel
from symkin.mechanism.casadi_assembly import independent_rows
from symkin.mechanism.closure import ClosureAssembly

#: How much of each joint range the start's motion uses (a small motion about the middle of the limits).
START_AMPLITUDE = 0.1
#: The constraints hold at this many times the criterion's samples ...
CONSTRAINT_DENSITY = 4
#: ... and are checked after the solve on a grid this many times as dense again.
CHECK_DENSITY = 10


@dataclass(frozen=True)
class Excitation:
    """A finite Fourier series per joint (or per task coordinate) and how well it excites the base parameters.

    Attributes:
        period: T (s).
        harmonics: L.
        offsets: q0 (n,), of the series' coordinates.
        a, b: the coefficients (n, L).
        condition_start, condition: cond(W S) of the start and of the optimum, at the samples.
        samples: K, the samples of one period the criterion was evaluated at.
        status: IPOPT's return status.
        coordinates: the series' coordinates: the device's joints, or a platform's task coordinates.
        joints: None when the series are the joints', else the map (p, pd, pdd) -> (q, qd, qdd) of the actuators
            (rows: samples).
    """

    period: float
    harmonics: int
    offsets: np.ndarray
    a: np.ndarray
    b: np.ndarray
    condition_start: float
    condition: float
    samples: int
    status: str
    coordinates: tuple[str, ...] = ()
    joints: Callable[..., tuple[np.ndarray, ...]] | None = None

    def series(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The series' values and first two derivatives (len(t), n) at the times ``t``."""
        return excitation_bounds.series(np, self.offsets, self.a, self.b, self.period, np.asarray(t, dtype=np.float64))

    def states(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The device's joints q, qd, qdd (len(t), joints) at the times ``t``."""
        series = self.series(t)
        if self.joints is None:
            return series
        q, qd, qdd, _margin = self.joints(*series)
        return q, qd, qdd


def _limits(model: GeneratedModel, velocity: float | None, acceleration: float | None,
            overrides: dict[str, tuple[float, float]]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per joint: lower and upper position limits (``overrides`` before the model's), and the velocity and
    acceleration bounds.

    Raises:
        ValueError: a joint without position limits, or no velocity or acceleration bound.
    """
    lower, upper, speeds = [], [], []
    for c in model.info.device_coordinates:
        limits = overrides.get(c.name, c.limits)
        if limits is None:
            raise ValueError(f"{model.name}: joint {c.name} has no limits; declare them (or give --limit)")
        lower.append(limits[0])
        upper.append(limits[1])
        speeds.append(velocity if velocity is not None else c.velocity_limit)
    if any(s is None for s in speeds):
        raise ValueError(f"{model.name}: give --max-velocity (the model declares no velocity limit for every joint)")
    if acceleration is None:
        raise ValueError("give --max-acceleration (models declare no acceleration limits)")
    n = len(lower)
    return np.array(lower), np.array(upper), np.array(speeds, dtype=float), np.full(n, float(acceleration))


def optimize_excitation(model: GeneratedModel, *, period: float = 10.0, harmonics: int = 5, samples: int | None = None,
             max_velocity: float | None = None, max_acceleration: float | None = None, seed: int = 0,
             limits: dict[str, tuple[float, float]] | None = None, max_iterations: int = 200) -> Excitation:
    """The excitation trajectory of the module docstring for ``model`` (loaded with ``backend="casadi"``, with
    ``base_regressor``; a parallel model with ``fk``, or without a closed form with ``ik``).

    Raises:
        ValueError: missing limits, or a start IPOPT cannot leave (see the message).
    """
    closure = ClosureAssembly(model) if "closure_base_regressor" in model.info.functions else None
    lower, upper, speeds, accelerations = _limits(model, max_velocity, max_acceleration, limits or {})
    joints = (_task_to_joints(model) if model.info.is_parallel and "fk" not in model.info.functions
              and closure is None else None)
    names = model.info.task_space if joints is not None else tuple(c.name for c in model.info.device_coordinates)
    n, n_q = len(names), len(lower)
    stops = excitation_bounds.stops_of_series(model, n) if joints is None and closure is None else None
    base = "base_regressor" if closure is None else "closure_base_regressor"
    count = len(model.info.functions[base].outputs["pi_b"])
    samples = samples or max(4 * -(-count // n_q), 50)
    t = np.arange(samples) * period / samples
    rng = np.random.default_rng(seed)
    omega = 2 * np.pi / period * np.arange(1, harmonics + 1)
    # a start that moves every joint by ~START_AMPLITUDE of its range, within the velocity bound
    half = (upper - lower) / 2
    scale = np.minimum(START_AMPLITUDE * half[:, None] * omega / harmonics, 0.5 * speeds[:, None] / harmonics)
    if closure is not None:  # legs without the distance form move about their home assembly
        middle = closure.home
    elif joints is None:
        middle = excitation_bounds.start_within_stops(model, (lower + upper) / 2, stops)
    else:  # about home, each task coordinate moving no joint by more than that (dq = J^-1 dp at home)
        middle = np.array(model.info.home, dtype=float)
        rates = np.abs(joints(np.tile(middle, (n, 1)), np.eye(n), np.zeros((n, n)))[1])   # row j: |J^-1 e_j|
        scale = np.min(scale[None, :, :] / np.maximum(rates, 1e-300)[:, :, None], axis=1)
    a0, b0 = rng.uniform(-1, 1, (2, n, harmonics)) * scale
    x = casadi.MX.sym("x", n + 2 * n * harmonics)
    offsets, a, b = x[:n], casadi.reshape(x[n:n + n * harmonics], harmonics, n).T, \
        casadi.reshape(x[n + n * harmonics:], harmonics, n).T
    dense = np.arange(CONSTRAINT_DENSITY * samples) * period / (CONSTRAINT_DENSITY * samples)
    pose = _pose_function(model, samples) if model.info.is_parallel and joints is None and closure is None else None
    sampled = excitation_bounds.series(casadi, offsets, a, b, period, t)
    (q, qd, qdd), _ = _joint_motion(sampled, joints)
    states = _states(model, q.T, qd.T, qdd.T, pose)
    if joints is not None:
        states["p"] = sampled[0].T
    x0 = np.concatenate([middle, a0.ravel(), b0.ravel()])  # each coordinate's L coefficients in a row
    # legs without the distance form: each sample's assembly by a rootfinder from a guess, the start's assembly
    if closure is None:
        function, guess0 = casadi_function(model, base), np.zeros((0, samples))
    else:
        function = closure_excitation.regressor_function(model, independent_rows(closure))
        guess0 = closure_excitation.guesses(closure, excitation_bounds.series(np, middle, a0, b0, period, t)[0])
    guess = states["guess"] = casadi.MX.sym("guess", *guess0.shape)
    (q_c, qd_c, qdd_c), margin = _joint_motion(excitation_bounds.series(casadi, offsets, a, b, period, dense), joints)
    Y = function.map(samples, "serial")(*_arguments(function, model, states, samples))[0]  # (n_q, count * samples)
    regressor_at = casadi.Function("W", [x, guess], [Y])
    W0 = _stacked(regressor_at(x0, guess0).full(), n_q, count, samples)
    column = np.linalg.norm(W0, axis=0)
    column[column == 0] = 1.0
    W = casadi.mtimes(_stacked_mx(Y, n_q, count, samples), casadi.diag(casadi.DM(1.0 / column)))
    F = W.T @ W / samples
    objective = casadi.log(casadi.sumsqr(F)) / 2 + casadi.log(casadi.trace(casadi.solve(F, casadi.DM.eye(count))))
    at_rest = casadi.vertcat(casadi.sum2(a), casadi.mtimes(b, casadi.DM(omega)))  # qd(0) and qdd(0)
    g = casadi.vertcat(casadi.vec(q_c), casadi.vec(qd_c), casadi.vec(qdd_c), at_rest)
    points = len(dense)
    lbg = np.concatenate([np.repeat(lower, points), np.repeat(-speeds, points), np.repeat(-accelerations, points),
                          np.zeros(2 * n)])
    ubg = np.concatenate([np.repeat(upper, points), np.repeat(speeds, points), np.repeat(accelerations, points),
                          np.zeros(2 * n)])
    if stops is not None:  # lower <= a . q + b <= upper at the points, for each stop on a combination of joints
        values = casadi.mtimes(q_c, casadi.DM(stops.rows.T)) + casadi.repmat(casadi.DM(stops.offsets).T, points, 1)
        g = casadi.vertcat(g, casadi.vec(values))
        lbg = np.concatenate([lbg, np.repeat(stops.lower, points)])
        ubg = np.concatenate([ubg, np.repeat(stops.upper, points)])
    if pose is not None:  # a parallel model's legs assemble along the motion: fk's margin >= 0 at the points
        margin = _pose_function(model, points)(q_c.T[:len(model.info.coordinates), :])[1]
    if margin is not None:  # ... or ik's, of a platform moved in its task coordinates
        g = casadi.vertcat(g, casadi.vec(margin))
        assembly = margin.numel()  # one margin per leg and constraint point
        lbg, ubg = np.concatenate([lbg, np.zeros(assembly)]), np.concatenate([ubg, np.full(assembly, np.inf)])
    problem, given = {"x": x, "f": objective, "g": g}, {}
    if closure is not None:  # the guesses are the problem's parameters
        problem["p"], given["p"] = casadi.vec(guess), guess0.ravel(order="F")
    iterations = IterationReport("optimizing the excitation (IPOPT iterations)", problem, max_iterations)
    solver = casadi.nlpsol("excitation", "ipopt", problem,
                           {**IPOPT_OPTIONS, "ipopt.tol": 1e-6, "ipopt.constr_viol_tol": 1e-9,
                            "ipopt.max_iter": max_iterations, "ipopt.hessian_approximation": "limited-memory",
                            **iterations.options()})
    result = solver(x0=x0, lbg=lbg, ubg=ubg, **given)
    # between the constraint points the motion may overshoot by O(dt^2 qdd): shrink it about q0 to fit a grid
    # ten times as dense (a common factor keeps the start at rest and the period)
    check = np.arange(CHECK_DENSITY * len(dense)) * period / (CHECK_DENSITY * len(dense))
    bounds = (lower, upper, speeds, accelerations)

    def fitted(vector: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        """q0, a, b of the coefficient vector shrunk to fit the check grid, and cond(W S) of that motion."""
        offsets_v = vector[:n]
        a_v, b_v = (vector[n + k * n * harmonics:n + (k + 1) * n * harmonics].reshape(n, harmonics) for k in (0, 1))
        if joints is None:
            shrink = excitation_bounds.fitting_factor(excitation_bounds.series(np, offsets_v, a_v, b_v, period, check), offsets_v,
                                     excitation_bounds.between_points(a_v, b_v, omega, period / len(check)), bounds, stops)
        else:
            shrink = excitation_bounds.task_fitting_factor(joints, offsets_v, a_v, b_v, period, check, bounds)
        fitted_guess = guess0
        if closure is not None:  # the legs close along the whole motion (else it shrinks more), assembled anew
            shrink = closure_excitation.assembled_factor(closure, lambda f: excitation_bounds.series(np, offsets_v, f * a_v, f * b_v,
                                                                                    period, check)[0], shrink)
            fitted_guess = closure_excitation.guesses(closure, excitation_bounds.series(np, offsets_v, shrink * a_v, shrink * b_v,
                                                                       period, t)[0])
        W_v = _stacked(regressor_at(np.concatenate([offsets_v, shrink * vector[n:]]), fitted_guess).full(), n_q,
                       count, samples)
        return offsets_v, shrink * a_v, shrink * b_v, _condition(W_v / column)

    status, start = solver.stats()["return_status"], _condition(W0 / column)
    offsets_best, a_best, b_best, condition = fitted(np.asarray(result["x"]).ravel())
    if condition > start:  # IPOPT stopped (at its iteration limit) where the motion excites less than the start
        offsets_best, a_best, b_best, condition = fitted(x0)
        status += "; its last iterate excited less than the start, which is kept"
    return Excitation(period, harmonics, offsets_best, a_best, b_best, start, condition, samples, status,
                      tuple(names), joints)


def _task_to_joints(model: GeneratedModel) -> Callable[..., tuple[Any, ...]]:
    """(p, pd, pdd) -> (q, qd, qdd, margin) of a platform's actuators through its ik (rows: samples; numpy or
    CasADi matrices; the module docstring)."""
    ik = casadi_function(model, "ik")
    p, pd, pdd = (casadi.MX.sym(name, ik.size1_in(0)) for name in ("p", "pd", "pdd"))
    q, margin = ik(*_arguments(ik, model, {"p": p}, 1))[:2]
    qd = casadi.jtimes(q, p, pd)
    qdd = casadi.jtimes(qd, p, pd) + casadi.jtimes(qd, pd, pdd)
    single = casadi.Function("joints", [p, pd, pdd], [q, qd, qdd, margin])

    def joints(p: Any, pd: Any, pdd: Any) -> Any:
        outputs = single.map(p.shape[0], "serial")(p.T, pd.T, pdd.T)
        return tuple(o.T if isinstance(p, casadi.MX) else np.asarray(o.full()).T for o in outputs)

    return joints


def _joint_motion(series: tuple[Any, Any, Any], joints: Callable[..., Any] | None) -> tuple[tuple[Any, Any, Any], Any]:
    """The joints' (q, qd, qdd) along the series' values (rows: samples), and ik's margin there (None for a joint
    series)."""
    if joints is None:
        return series, None
    q, qd, qdd, margin = joints(*series)
    return (q, qd, qdd), margin


def _pose_function(model: GeneratedModel, samples: int) -> casadi.Function:
    """A parallel model's fk (pose, margin) mapped over ``samples`` configurations at the model's parameter values
    (its regressors take the pose p = fk(q))."""
    fk = casadi_function(model, "fk")
    q = casadi.MX.sym("q", fk.size1_in(0), samples)
    outputs = fk.map(samples, "serial")(*_arguments(fk, model, {"q": q}, samples))
    return casadi.Function("pose", [q], list(outputs[:2]))


def _states(model: GeneratedModel, q: Any, qd: Any, qdd: Any, pose: casadi.Function | None) -> dict[str, Any]:
    """The base regressor's state inputs by name from the device's joints (rows: the coordinates, then a hybrid
    device's wrist joints ``qw``), and a parallel model's pose p = fk(q)."""
    legs = len(model.info.coordinates)
    states = {}
    for name, value in (("q", q), ("qd", qd), ("qdd", qdd)):
        states[name] = value[:legs, :]
        if model.info.wrist:
            states[name.replace("q", "qw", 1)] = value[legs:, :]
    if pose is not None:
        states["p"] = pose(states["q"])[0]
    return states


def _arguments(function: casadi.Function, model: GeneratedModel, states: dict[str, Any], samples: int) -> list[Any]:
    """The inputs of ``function`` mapped over ``samples``: the given state matrices by name, then each parameter
    at the model's (bound) value."""
    return [states[name] if name in states else casadi.repmat(casadi.DM(model.parameters[name]), 1, samples)
            for name in function.name_in()]


def _stacked(Y: np.ndarray, n: int, count: int, samples: int) -> np.ndarray:
    """The (n x count*samples) output of the mapped function as W (samples*n x count)."""
    return np.concatenate([Y[:, k * count:(k + 1) * count] for k in range(samples)], axis=0)


def _stacked_mx(Y: casadi.MX, n: int, count: int, samples: int) -> casadi.MX:
    return casadi.vertcat(*[Y[:, k * count:(k + 1) * count] for k in range(samples)])


def _condition(W: np.ndarray) -> float:
    singular = np.linalg.svd(W, compute_uv=False)
    return float(singular[0] / singular[-1]) if singular[-1] > 0 else float("inf")


def figure_png(excitation: Excitation, coordinates: list[str], revolute: list[bool], title: str) -> bytes:
    """q, qd and qdd of one period, one panel each, a line per joint."""
    import io

    from matplotlib.figure import Figure

    t = np.linspace(0.0, excitation.period, 1001)
    states = excitation.states(t)
    figure = Figure(figsize=(8.0, 7.0), layout="constrained")
    axes = figure.subplots(3, 1, sharex=True)
    units = ("rad or m", "rad/s or m/s", "rad/s^2 or m/s^2") if not all(revolute) else ("rad", "rad/s", "rad/s^2")
    for ax, values, label, unit in zip(axes, states, ("q", "qd", "qdd"), units):
        for k, name in enumerate(coordinates):
            ax.plot(t, values[:, k], linewidth=1.0, label=name)
        ax.set_ylabel(f"{label} [{unit}]")
    axes[0].legend(loc="upper right", fontsize="small", ncol=min(len(coordinates), 6))
    axes[-1].set_xlabel("t [s]")
    figure.suptitle(title)
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=110)
    return buffer.getvalue()
