"""Numerical kinematics of parallel mechanisms on top of their generated code (numpy only).

Where no closed form exists (the forward kinematics of a Stewart-Gough platform, the loop closure of an
arbitrary leg topology), Newton's method (:func:`symkin.newton.newton_iterate`, the one solver) on the
*generated* equations and Jacobians solves it, vectorized over a batch, reporting per sample whether it
converged, how many iterations it took and the final residual; where it did not converge the solution is
NaN, never a plausible but wrong pose.

Like :mod:`symkin.runtime.loader`, this module imports neither sympy nor jinja2.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any
from dataclasses import dataclass

import numpy as np

from symkin.errors import GeneratedCodeError
from symkin.newton import NewtonReport, newton_iterate
from symkin.runtime.info import GeneratedModel


def _function(model: GeneratedModel, name: str, purpose: str) -> Callable[..., Any]:
    """The generated function ``name`` (its result is an array or a named tuple of arrays)."""
    if name not in model.functions:
        raise GeneratedCodeError(f"{purpose} needs the generated function '{name}' of model '{model.name}'; "
                                 f"derive it (scene outputs or --only {name})")
    return getattr(model, name)


def _declared_home(model: GeneratedModel) -> np.ndarray:
    """The model's declared home pose (task coordinates at the default parameters).

    Raises:
        GeneratedCodeError: the model declares none (``parallel.home``).
    """
    home = model.info.home
    if home is None:
        raise GeneratedCodeError(f"model '{model.name}' declares no home pose (parallel.home); pass a start p0")
    return np.array(home, dtype=float)


def solve_fk(model: GeneratedModel, q, p0=None, *, tol: float = 1e-12, max_iterations: int = 30) -> NewtonReport:
    """Forward kinematics p(q) by Newton's method on the generated leg equations.

    Solves f(q, p) = 0 for p with the generated ``constraints`` and ``constraint_jacobians``:
    p <- p - J_x(q, p)^-1 f(q, p) (J_x = df/dp).  Quadratic convergence near a regular
    solution; from a start near the wanted assembly mode (e.g. the last pose of a control
    loop, seed sec. 3.2 [24]) it finds that pose.  Works for any model whose legs have the
    distance form (Stewart-Gough, DELTA...).

    Args:
        model: the loaded model (with ``constraints`` and ``constraint_jacobians``).
        q: actuated joint variables, shape (..., n).
        p0: start, shape (..., m) (broadcast against q); default: the model's home pose.
        tol: converged when a Newton step is at most this large (max-norm, task units).
        max_iterations: give up (report failure) after this many steps.

    Returns:
        The report; ``solution`` is p, NaN where the iteration did not converge (no real
        solution, a singular J_x, or too far a start).
    """
    constraints = _function(model, "constraints", "solve_fk")
    jacobians = _function(model, "constraint_jacobians", "solve_fk")
    q = np.asarray(q, dtype=float)
    p0 = _declared_home(model) if p0 is None else np.asarray(p0, dtype=float)
    batch = np.broadcast_shapes(q.shape[:-1], p0.shape[:-1])
    q = np.broadcast_to(q, batch + q.shape[-1:])
    start = np.broadcast_to(p0, batch + p0.shape[-1:])

    q_flat = q.reshape(-1, q.shape[-1])

    def equations(p: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return np.asarray(constraints(q_flat[rows], p)), np.asarray(jacobians(q_flat[rows], p).J_x)

    return newton_iterate(start, equations, tol, max_iterations)


def solve_closure(model: GeneratedModel, q, s, p, *, unknowns: tuple[str, ...] = ("p", "s"), tol: float = 1e-12,
                  max_iterations: int = 50, max_step: float | None = None, stall: int | None = None) -> NewtonReport:
    """Solve the generated loop closure phi(q, s, p) = 0 for some of its vectors (any leg topology).

    Gauss-Newton on the generated ``closure`` and ``closure_jacobians``: the unknown
    vectors are stacked and updated by the least-squares Newton step -A^+ phi, with A the
    matching columns of [Phi_q, Phi_s, Phi_p].  Forward kinematics solves for ("p", "s")
    at given q, inverse kinematics for ("q", "s") at given p, the passive joints alone for
    ("s",).  The closure of a translational platform is overdetermined but consistent (each
    leg has 6 equations and 5 joints), hence least squares.

    Args:
        model: the loaded model (with ``closure`` and ``closure_jacobians``).
        q, s, p: actuated, passive and task coordinates (known values and starts).
        unknowns: which of "q", "s", "p" to solve for.
        tol: converged when a step is at most this large (max-norm).
        max_iterations: give up after this many steps.
        max_step: damping: steps longer than this (max-norm) are shortened to it.
        stall: stop a sample whose residual stagnates over this many steps (:func:`symkin.newton.newton_iterate`).

    Returns:
        The report; ``solution`` maps every vector name to its value (unknowns NaN where not
        converged).
    """
    closure = _function(model, "closure", "solve_closure")
    jacobians = _function(model, "closure_jacobians", "solve_closure")
    names = ("q", "s", "p")
    if not unknowns or set(unknowns) - set(names):
        raise ValueError(f"unknowns must be a non-empty selection of {names}, got {unknowns}")
    values = {name: np.asarray(v, dtype=float) for name, v in zip(names, (q, s, p))}
    batch = np.broadcast_shapes(*(v.shape[:-1] for v in values.values()))
    values = {name: np.broadcast_to(v, batch + v.shape[-1:]) for name, v in values.items()}
    order = [name for name in names if name in unknowns]
    sizes = [values[name].shape[-1] for name in order]
    splits = np.cumsum(sizes)[:-1]

    def unpack(x: np.ndarray) -> dict[str, np.ndarray]:
        return {**values, **dict(zip(order, np.split(x, splits, axis=-1)))}

    flat = {name: v.reshape(-1, v.shape[-1]) for name, v in values.items()}

    def equations(x: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        v = {**{name: value[rows] for name, value in flat.items()}, **dict(zip(order, np.split(x, splits, axis=-1)))}
        phi = np.asarray(closure(v["q"], v["s"], v["p"]))
        J = jacobians(v["q"], v["s"], v["p"])
        blocks = {"q": J.Phi_q, "s": J.Phi_s, "p": J.Phi_p}
        return phi, np.concatenate([np.asarray(blocks[name]) for name in order], axis=-1)

    start = np.concatenate([values[name] for name in order], axis=-1)
    report = newton_iterate(start, equations, tol, max_iterations, max_step, stall)
    return NewtonReport(unpack(np.asarray(report.solution)), report.converged, report.iterations, report.residual, report.step,
                        report.left_region)


@dataclass(frozen=True)
class ClosureVelocities:
    """First-order kinematics of any leg topology at an assembled pose (:func:`closure_velocities`).

    Attributes:
        J: task Jacobian dp/dq, shape (..., m, n): pdot = J qdot; NaN where ``interior`` is zero to
            rounding (the platform is not determined by the actuators there).
        passive: passive joint rates ds/dq, shape (..., ns, n) (the minimum-norm ones where a passive
            motion is idle, e.g. a rod spinning between two S joints).
        interior: per sample, the product of the singular values of N^T Phi_p (see the function):
            zero at the interior (type 2, "parallel") singularities, where the platform moves with the
            actuators locked.
        boundary: per sample, the product of the singular values of N^T Phi_q: zero at the boundary
            (type 1, "serial") singularities, where an actuator moves with the platform held.
    """

    J: np.ndarray
    passive: np.ndarray
    interior: np.ndarray
    boundary: np.ndarray


def _left_null_space(A: np.ndarray) -> np.ndarray:
    """N (k, r, r) whose non-zero columns are an orthonormal basis of the complement of range(A) (k, r, c):
    the left singular vectors of singular values at most r eps sigma_max (the rank test of
    numpy.linalg.matrix_rank), the others zeroed so that every sample keeps the shape."""
    if A.shape[-1] == 0:
        return np.broadcast_to(np.eye(A.shape[1]), (A.shape[0], A.shape[1], A.shape[1])).copy()
    U, S, _ = np.linalg.svd(A, full_matrices=True)
    tolerance = S.max(axis=-1) * max(A.shape[-2:]) * np.finfo(float).eps
    rank = np.count_nonzero(S > tolerance[:, None], axis=-1)
    return U * (np.arange(A.shape[-2])[None, :] >= rank[:, None])[:, None, :]


def _closure_blocks(model: GeneratedModel, q, s, p, purpose: str) -> tuple[tuple[int, ...], np.ndarray, np.ndarray,
                                                                           np.ndarray, np.ndarray]:
    """(batch, Phi_p, Phi_q, Phi_s, finite): the generated closure_jacobians at q, s, p broadcast against each
    other, flattened to (k, rows, .), and which samples have finite blocks."""
    jacobians = _function(model, "closure_jacobians", purpose)
    q, s, p = (np.asarray(v, dtype=float) for v in (q, s, p))
    batch = np.broadcast_shapes(q.shape[:-1], s.shape[:-1], p.shape[:-1])
    flat = [np.broadcast_to(v, batch + v.shape[-1:]).reshape(-1, v.shape[-1]) for v in (q, s, p)]
    blocks = jacobians(*flat)
    Phi_p, Phi_q, Phi_s = (np.asarray(b, dtype=float).reshape(len(flat[0]), -1, b.shape[-1])
                           for b in (blocks.Phi_p, blocks.Phi_q, blocks.Phi_s))
    finite = np.all(np.isfinite(np.concatenate([Phi_p, Phi_q, Phi_s], axis=-1)), axis=(1, 2))
    return batch, Phi_p, Phi_q, Phi_s, finite


def closure_velocities(model: GeneratedModel, q, s, p) -> ClosureVelocities:
    """Task Jacobian, passive rates and both singularity measures of any leg topology, from the closure.

    Differentiating the generated closure phi(q, s, p) = 0 gives Phi_p pdot + Phi_q qdot + Phi_s sdot = 0
    (``closure_jacobians``).  The passive rates are eliminated by the columns N of the orthogonal
    complement of range(Phi_s) (the constraint directions the passive joints cannot take up; per leg,
    its reciprocal wrenches): N^T Phi_p pdot = -N^T Phi_q qdot, the generic counterpart of the distance
    form's J_x pdot = J_q qdot.  Then J = -(N^T Phi_p)^+ N^T Phi_q, exact when the pose is assembled, and
    sdot = -Phi_s^+ (Phi_p J + Phi_q) qdot.  Singularities (Gosselin and Angeles 1990; seed sec. 4.2) are
    where N^T Phi_p (interior) or N^T Phi_q (boundary) loses column rank: the products of their singular
    values, sqrt(det(A^T A)), vanish there.  Their magnitudes mix the units of the closure's rows (m and
    rad): compare a model with itself, e.g. along a path or over its workspace.

    Samples with a non-finite input (an unconverged solve) give NaN throughout.

    Evaluate at an assembled triple: p and s from :func:`solve_closure` at given q (forward kinematics)
    or q and s at given p (inverse kinematics).  No sympy: the generated ``closure_jacobians`` only.

    Args:
        model: the loaded model (with ``closure_jacobians``).
        q, s, p: actuated, passive and task coordinates, broadcast against each other.
    """
    batch, Phi_p, Phi_q, Phi_s, finite = _closure_blocks(model, q, s, p, "closure_velocities")
    m, n, ns = Phi_p.shape[-1], Phi_q.shape[-1], Phi_s.shape[-1]
    J = np.full((len(Phi_p), m, n), np.nan)
    passive = np.full((len(Phi_p), ns, n), np.nan)
    interior = np.full(len(Phi_p), np.nan)
    boundary = np.full(len(Phi_p), np.nan)
    if np.any(finite):
        Phi_p, Phi_q, Phi_s = Phi_p[finite], Phi_q[finite], Phi_s[finite]
        N = _left_null_space(Phi_s)
        task = np.einsum("kri,krj->kij", N, Phi_p)
        actuated = np.einsum("kri,krj->kij", N, Phi_q)
        U, S, Vt = np.linalg.svd(task, full_matrices=False)
        determined = S.min(axis=-1) > S.max(axis=-1) * max(task.shape[-2:]) * np.finfo(float).eps
        with np.errstate(divide="ignore", invalid="ignore"):
            rates = -np.einsum("kji,kj,klj,klm->kim", Vt, 1 / S, U, actuated)
        rates[~determined] = np.nan
        J[finite] = rates
        passive[finite] = -np.einsum("kij,kjm->kim", np.linalg.pinv(Phi_s), Phi_p @ np.nan_to_num(rates) + Phi_q)
        passive[np.flatnonzero(finite)[~determined]] = np.nan
        interior[finite] = np.prod(S, axis=-1)
        boundary[finite] = np.prod(np.linalg.svd(actuated, compute_uv=False), axis=-1)
    return ClosureVelocities(J.reshape(batch + (m, n)), passive.reshape(batch + passive.shape[-2:]),
                             interior.reshape(batch), boundary.reshape(batch))


@dataclass(frozen=True)
class ClosureFrames:
    """The closure's task and actuator blocks seen by the constraints the passive joints cannot take up.

    Attributes:
        task: P Phi_p, shape (..., rows, m);
        actuated: P Phi_q, shape (..., rows, n); P = N N^T projects onto the orthogonal complement of
            range(Phi_s) (:func:`closure_velocities`), a basis-free form of N^T Phi_p and N^T Phi_q: two poses
            compare through task_a^T task_b, whatever bases their N have.
    """

    task: np.ndarray
    actuated: np.ndarray


#: Phi_s counts as of full column rank where its smallest |R_jj| (Phi_s = QR) is above this fraction of its largest.
_FULL_COLUMN_RANK = 1e-10


def _complement_projections(A: np.ndarray, *blocks: np.ndarray) -> tuple[np.ndarray, ...]:
    """P B for each block B (k, r, .), P the orthogonal projector onto the complement of range(A) (k, r, c): where A
    has full column rank, from its QR factorization, P B = B - Q (Q^T B) (a fifth of the SVD's time on a continuation's
    batches); elsewhere (a passive motion the closure leaves idle) from the left singular vectors of
    :func:`_left_null_space`, P = N N^T."""
    projected = [np.empty_like(B) for B in blocks]
    regular = np.ones(len(A), dtype=bool)
    if A.shape[-1] and A.shape[-2] >= A.shape[-1]:
        Q, R = np.linalg.qr(A)
        pivots = np.abs(np.diagonal(R, axis1=-2, axis2=-1))
        regular = pivots.min(axis=-1) > _FULL_COLUMN_RANK * pivots.max(axis=-1)
        Q_T = np.swapaxes(Q, -1, -2)
        for B, out in zip(blocks, projected):
            if regular.all():    # the usual batch: no copies through the mask
                np.subtract(B, Q @ (Q_T @ B), out=out)
            else:
                out[regular] = B[regular] - Q[regular] @ (Q_T[regular] @ B[regular])
    else:
        regular[:] = False
    if not regular.all():
        N = _left_null_space(A[~regular])
        projector = np.einsum("kij,klj->kil", N, N)
        for B, out in zip(blocks, projected):
            out[~regular] = projector @ B[~regular]
    return tuple(projected)


def closure_frames(model: GeneratedModel, q, s, p) -> ClosureFrames:
    """P Phi_p and P Phi_q at assembled poses (see :class:`ClosureFrames`); NaN where an input is not finite.

    A continuation tells whether a step crossed a singularity from these: between two nearby regular
    poses a and b, det(task_a^T task_b) > 0 (the matrix is close to the positive definite task_a^T task_a),
    while across an interior singularity, where one column combination of P Phi_p passes through zero
    and comes back reversed, the determinant turns negative (the Schur complement on that direction is
    -h^2 |(I - projection) d(P Phi_p v)|^2 for a step h); the same for P Phi_q and boundary singularities.
    """
    batch, Phi_p, Phi_q, Phi_s, finite = _closure_blocks(model, q, s, p, "closure_frames")
    task = np.full(Phi_p.shape, np.nan)
    actuated = np.full(Phi_q.shape, np.nan)
    if np.any(finite):
        task[finite], actuated[finite] = _complement_projections(Phi_s[finite], Phi_p[finite], Phi_q[finite])
    return ClosureFrames(task.reshape(batch + task.shape[-2:]), actuated.reshape(batch + actuated.shape[-2:]))
