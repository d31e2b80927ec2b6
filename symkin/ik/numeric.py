"""Numerical inverse kinematics of any serial model: damped least squares (Levenberg-Marquardt).

Each iteration solves, for every target of the batch at once,

    (J^T J + mu I) dq = J^T e,        q <- clip(q + dq, lower, upper)

with e the residual of :mod:`symkin.ik.problem` and J its Jacobian from the generated code
(Wampler 1986, "Manipulator inverse kinematic solutions based on vector formulations and
damped least-squares methods"; Nakamura & Hanafusa 1986).  The damping mu follows Nielsen's
gain-ratio rule (Madsen, Nielsen & Tingleff, "Methods for non-linear least squares
problems", 2004, sec. 3.2): a step that reduces 1/2 |e|^2 as the linear model predicts
lowers mu (Gauss-Newton, quadratic convergence near a solution), a step that does not is
refused and mu grows (gradient descent), so singular configurations and unreachable
targets never produce huge steps.

Joint limits are respected: iterates stay in the box (projection), and a joint that sits on
a limit while the step pushes it outwards is frozen for that step (its column of J is
dropped), so the remaining joints still make progress.

A solution is reported as converged only when the residual is within tolerance; otherwise
the result says why it stopped (``max_iterations`` or ``stalled``: no step reduces the
residual any more, as at an unreachable target or a local minimum) and gives the best
configuration found - never silently an approximation.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from symkin.ik.problem import ModelKinematics, Residual, as_target, residual_for
from symkin.mechanism.limits import wrap_angle
from symkin.runtime import LoadedModel

CONVERGED = "converged"
MAX_ITERATIONS = "max_iterations"
STALLED = "stalled"
REASONS = {
    CONVERGED: "the residual is within tolerance",
    MAX_ITERATIONS: "the iteration limit was reached before the residual was within tolerance",
    STALLED: "no step reduces the residual any more: the target is unreachable (within the joint limits) "
             "or the start lies in the basin of a local minimum",
}

#: Convergence threshold: |position residual| <= tolerance * max(1, |target position|) and
#: |angular residual| <= tolerance, so that FK(IK(x)) = x to 1e-12 within 10 m of the base.
DEFAULT_TOLERANCE = 1e-13
#: Initial damping relative to the largest diagonal entry of J^T J (Madsen et al., tau).
INITIAL_DAMPING = 1e-3
#: Smallest damping, relative to max diag(J^T J): keeps J^T J + mu I invertible at singular J.
MIN_DAMPING = 1e-14
#: Damping beyond this multiple of max diag(J^T J) means no step can reduce the residual.
MAX_DAMPING = 1e16
#: A step shorter than this (relative to |q|) is below the floating-point floor.
STEP_FLOOR = 4.0 * np.finfo(float).eps


@dataclass(frozen=True)
class IKResult:
    """The outcome of :func:`solve_numeric` for a batch of targets (batch shape ``...``).

    Attributes:
        q: joint coordinates (..., n): the solution, or the best configuration found.
        converged: (...,) True where the residual is within tolerance.
        iterations: (...,) iterations used.
        position_error: (...,) norm of the length part of the residual (model length unit).
        orientation_error: (...,) norm of the angular part of the residual (rad).
        reason: (...,) why the iteration stopped: ``converged``, ``max_iterations`` or
            ``stalled`` (see :data:`REASONS`).
        at_limit: (..., n) True for the joints that sit on a joint limit.
        kind: the target kind, ``pose`` or ``task``.
    """

    q: np.ndarray
    converged: np.ndarray
    iterations: np.ndarray
    position_error: np.ndarray
    orientation_error: np.ndarray
    reason: np.ndarray
    at_limit: np.ndarray
    kind: str

    def summary(self) -> str:
        """One line per target: reason, iterations and residuals."""
        lines = []
        for index in np.ndindex(self.converged.shape):
            where = f"target {index[0] if len(index) == 1 else index}: " if index else ""
            pinned = np.flatnonzero(self.at_limit[index])
            limits = f"; joints at a limit: {', '.join(str(j + 1) for j in pinned)}" if pinned.size else ""
            lines.append(f"{where}{self.reason[index]} after {self.iterations[index]} iterations, "
                         f"position error {self.position_error[index]:.3g}, "
                         f"orientation error {self.orientation_error[index]:.3g}{limits}")
        return "\n".join(lines)


def _kinematics(model: LoadedModel | ModelKinematics, limits) -> ModelKinematics:
    if isinstance(model, ModelKinematics):
        return model
    return ModelKinematics(model, limits)


def _converged(residual: Residual, e: np.ndarray, length_tolerance: np.ndarray, angle_tolerance: float) -> np.ndarray:
    lengths, angles = residual.split_norms(e)
    return (lengths <= length_tolerance) & (angles <= angle_tolerance)


def _damped_step(J: np.ndarray, e: np.ndarray, mu: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Solve (Jf^T Jf + mu I) dq = Jf^T e with Jf = J restricted to the ``free`` joints."""
    Jf = J * free[:, None, :]
    A = np.swapaxes(Jf, -1, -2) @ Jf + mu[:, None, None] * np.eye(J.shape[-1])
    g = np.einsum("bmn,bm->bn", Jf, e)
    return np.linalg.solve(A, g[..., None])[..., 0]


def solve_numeric(model: LoadedModel | ModelKinematics, target: np.ndarray | Sequence,
                  q0: np.ndarray | Sequence | None = None, *, kind: str | None = None,
                  tolerance: float = DEFAULT_TOLERANCE, max_iterations: int = 200,
                  limits: Sequence[tuple[float, float]] | None = None) -> IKResult:
    """Solve f(q) = target by damped least squares, for a batch of targets and starts.

    Args:
        model: a loaded model (any backend) or a :class:`~symkin.ik.problem.ModelKinematics`.
        target: pose targets (..., 4, 4) or task-space targets (..., m), see ``kind``.
        q0: start configurations (..., n), broadcast against the targets' batch shape
            (several starts for one target: q0 of shape (k, n) with one target); default:
            zero clipped into the joint limits.
        kind: ``pose`` or ``task`` (default: ``pose`` for models whose task space is the pose).
        tolerance: convergence threshold: |position residual| <= tolerance * max(1, |target
            position|) and |angular residual| <= tolerance (rad).
        max_iterations: iteration budget per target.
        limits: (lower, upper) per joint instead of the model's limits.

    Returns:
        An :class:`IKResult` with the batch shape of targets and starts broadcast together.
    """
    kin = _kinematics(model, limits)
    residual = residual_for(kin, kind)
    target = as_target(residual, target)
    tshape = residual.target_shape()
    start = np.zeros(kin.dof) if q0 is None else np.asarray(q0, dtype=float)
    if start.ndim == 0 or start.shape[-1] != kin.dof:
        raise ValueError(f"{kin.name}: q0 must have shape (..., {kin.dof}), got {start.shape}")
    batch = np.broadcast_shapes(target.shape[:target.ndim - len(tshape)], start.shape[:-1])
    targets = np.broadcast_to(target, batch + tshape).reshape((-1,) + tshape)
    q = kin.project(np.broadcast_to(start, batch + (kin.dof,)).reshape(-1, kin.dof)).copy()

    e = residual.error(q, targets)
    J = residual.jacobian(q, e)
    cost = 0.5 * np.sum(e * e, axis=-1)
    length_tolerance = tolerance * residual.length_scale(targets)
    done = _converged(residual, e, length_tolerance, tolerance)
    reason = np.where(done, CONVERGED, MAX_ITERATIONS).astype(object)
    diag_max = np.max(np.sum(J * J, axis=-2), axis=-1)
    mu = INITIAL_DAMPING * np.maximum(diag_max, np.finfo(float).tiny)
    nu = np.full(q.shape[0], 2.0)
    iterations = np.zeros(q.shape[0], dtype=int)
    lower, upper = kin.lower, kin.upper

    for _ in range(max_iterations):
        active = np.flatnonzero(~done)
        if active.size == 0:
            break
        qa, ea, Ja, mua = q[active], e[active], J[active], mu[active]
        free = np.ones_like(qa, dtype=bool)
        step = _damped_step(Ja, ea, mua, free)
        blocked = ~kin.wraps & (((qa <= lower) & (step < 0)) | ((qa >= upper) & (step > 0)))
        if blocked.any():
            free = ~blocked
            step = _damped_step(Ja, ea, mua, free)
        q_new = kin.project(qa + step)
        # the displacement the linear model sees: a revolute joint wrapped by 2 pi k into its
        # limits moved by ``step``, not by step - 2 pi k
        moved = q_new - qa
        step = np.where(kin.revolute, step + wrap_angle(moved - step), moved)
        e_new = residual.error(q_new, targets[active])
        cost_new = 0.5 * np.sum(e_new * e_new, axis=-1)
        Jstep = np.einsum("bmn,bn->bm", Ja, step)
        predicted = np.sum(ea * Jstep, axis=-1) - 0.5 * np.sum(Jstep * Jstep, axis=-1)
        accept = (cost_new < cost[active]) & (predicted > 0)
        iterations[active] += 1

        ok, bad = active[accept], active[~accept]
        if ok.size:
            rho = (cost[ok] - cost_new[accept]) / predicted[accept]
            q[ok], e[ok], cost[ok] = q_new[accept], e_new[accept], cost_new[accept]
            J[ok] = residual.jacobian(q[ok], e[ok])
            diag_ok = np.max(np.sum(J[ok] * J[ok], axis=-2), axis=-1)
            mu[ok] = np.maximum(mu[ok] * np.maximum(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3),
                                MIN_DAMPING * np.maximum(diag_ok, np.finfo(float).tiny))
            nu[ok] = 2.0
        if bad.size:
            mu[bad] *= nu[bad]
            nu[bad] *= 2.0

        converged = _converged(residual, e[active], length_tolerance[active], tolerance)
        tiny_step = np.linalg.norm(step, axis=-1) <= STEP_FLOOR * (np.linalg.norm(qa, axis=-1) + STEP_FLOOR)
        diag_max = np.max(np.sum(J[active] * J[active], axis=-2), axis=-1)
        hopeless = mu[active] > MAX_DAMPING * np.maximum(diag_max, np.finfo(float).tiny)
        stalled = ~converged & ((accept & tiny_step) | hopeless)
        reason[active[converged]] = CONVERGED
        reason[active[stalled]] = STALLED
        done[active[converged | stalled]] = True

    lengths, angles = residual.split_norms(e)
    at_limit = (q <= lower) | (q >= upper)
    return IKResult(
        q=q.reshape(batch + (kin.dof,)),
        converged=(reason == CONVERGED).reshape(batch),
        iterations=iterations.reshape(batch),
        position_error=lengths.reshape(batch),
        orientation_error=angles.reshape(batch),
        reason=reason.astype(str).reshape(batch),
        at_limit=at_limit.reshape(batch + (kin.dof,)),
        kind=residual.kind,
    )


def random_configurations(kinematics: ModelKinematics, count: int, rng: np.random.Generator) -> np.ndarray:
    """``count`` configurations drawn uniformly within the joint limits (count, n).

    Unlimited revolute joints are drawn in [-pi, pi], unlimited prismatic joints in [-1, 1].
    """
    span = np.where(kinematics.revolute, np.pi, 1.0)
    lower = np.where(np.isfinite(kinematics.lower), kinematics.lower, -span)
    upper = np.where(np.isfinite(kinematics.upper), kinematics.upper, span)
    return rng.uniform(lower, upper, size=(count, kinematics.dof))


def distinct_solutions(kinematics: ModelKinematics, q: np.ndarray, tolerance: float = 1e-6) -> np.ndarray:
    """The distinct configurations among the rows of ``q`` (k, n), revolute angles compared modulo 2 pi.

    Returned with revolute angles wrapped to (-pi, pi], sorted lexicographically.
    """
    wrapped = np.where(kinematics.revolute, wrap_angle(q), q)
    kept: list[np.ndarray] = []
    for row in wrapped:
        close = False
        for other in kept:
            diff = np.where(kinematics.revolute, wrap_angle(row - other), row - other)
            if np.max(np.abs(diff)) <= tolerance:
                close = True
                break
        if not close:
            kept.append(row)
    if not kept:
        return np.zeros((0, kinematics.dof))
    return np.array(sorted(kept, key=tuple))
