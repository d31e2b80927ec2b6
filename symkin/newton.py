"""Newton's method on a batch of equation systems (numpy only): the one solver of symkin's numerical kinematics.

Every closure solve goes through :func:`newton_iterate` - the forward kinematics of distance-form legs and the
loop closure of any leg topology on the generated code (:mod:`symkin.runtime.parallel`), the assembly checks of
the derivation on the closure rows (:mod:`symkin.parallel.assembly`) and the continuations built on them.  It is
vectorized over a batch and reports, per sample, whether it converged, how many steps it took and the final
residual; where it did not converge the solution is NaN, never a plausible but wrong point.  Square systems
take Newton steps -A^-1 r, tall ones Gauss-Newton steps -A^+ r (QR where A has full column rank, the
minimum-norm pseudo-inverse step elsewhere), and a step longer than ``max_step`` is shortened to it (damping,
so that a start near one solution does not jump to another far away).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class NewtonReport:
    """The outcome of a vectorized Newton solve.

    Attributes:
        solution: the solution, NaN where ``converged`` is False; for :func:`solve_closure`
            a dict of the solved vectors by name.
        converged: per sample, True when the last Newton step was below the tolerance and
            the residual is finite.
        iterations: per sample, Newton steps taken.
        residual: per sample, max-norm of the equations at the returned point (the leg
            equations f for :func:`solve_fk`, the closure residual phi for :func:`solve_closure`).
        step: per sample, max-norm of the last Newton step (an estimate of the error of the
            solution before that step).
        left_region: per sample, True where a correction above the tolerance failed to halve the one before: the
            iterates left the start's Newton-Kantorovich region, inside which the corrections at least halve and
            the solution is the one the start's branch continues to (Ortega and Rheinboldt, Iterative Solution of
            Nonlinear Equations in Several Variables, 12.6.2) - a possible jump of branch (assembly mode); None
            where the solver does not watch it.
    """

    solution: np.ndarray | dict[str, np.ndarray]
    converged: np.ndarray
    iterations: np.ndarray
    residual: np.ndarray
    step: np.ndarray
    left_region: np.ndarray | None = None

    @property
    def all_converged(self) -> bool:
        return bool(np.all(self.converged))


#: A stalled sample (``stall``): its residual fell by less than this factor over the steps looked back on.
STALL_DECREASE = 0.9

#: A tall Jacobian counts as of full column rank when its smallest pivot |R_ii| (A = QR) is
#: above this fraction of its largest.
_FULL_RANK = 1e-10


def _pinv_steps(A: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Minimum-norm least-squares steps -A^+ r of a flat batch (k, rows, cols)."""
    return -np.einsum("kij,kj->ki", np.linalg.pinv(A), r)


def _factored(A: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Q, R, regular) of a flat batch of tall A (k, rows, cols) = Q R: ``regular`` where A has full column rank (its
    smallest pivot |R_ii| above :data:`_FULL_RANK` times its largest)."""
    Q, R = np.linalg.qr(A)
    pivots = np.abs(np.diagonal(R, axis1=1, axis2=2))
    return Q, R, pivots.min(axis=1) > _FULL_RANK * pivots.max(axis=1)


def left_inverses(A: np.ndarray) -> np.ndarray:
    """A^+ (k, cols, rows) of a flat batch of A (k, rows, cols): R^-1 Q^T from A = Q R where A has full column rank
    (the least-squares solution of A x = b is A^+ b; a fifth of the SVD's time), the SVD's pseudo-inverse
    elsewhere."""
    if A.shape[1] < A.shape[2]:
        return np.linalg.pinv(A)
    Q, R, regular = _factored(A)
    inverse = np.empty(A.shape[:1] + A.shape[:0:-1])
    if regular.any():
        inverse[regular] = np.linalg.solve(R[regular], np.swapaxes(Q[regular], -1, -2))
    if not regular.all():
        inverse[~regular] = np.linalg.pinv(A[~regular])
    return inverse


def least_squares_steps(A: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Least-squares steps -A^+ r of a flat batch of tall A (k, rows, cols).

    Where A has full column rank - judged per matrix by the diagonal of R in A = QR - from
    that factorization, R x = -Q^T r (several times faster than the SVD behind pinv, and
    without squaring the condition number as the normal equations would); elsewhere the
    minimum-norm step of pinv.
    """
    if A.shape[1] < A.shape[2]:
        return _pinv_steps(A, r)
    Q, R, regular = _factored(A)
    steps = np.empty(A.shape[:1] + A.shape[2:])
    steps[regular] = -np.linalg.solve(R[regular], np.einsum("kji,kj->ki", Q[regular], r[regular])[..., None])[..., 0]
    steps[~regular] = _pinv_steps(A[~regular], r[~regular])
    return steps


def newton_steps(A: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Newton steps -A^-1 r for a flat batch (k, rows, cols); least squares -A^+ r when A is not
    square; NaN where A or r is not finite or A is singular."""
    steps = np.full(A.shape[:1] + A.shape[2:], np.nan)
    finite = np.all(np.isfinite(A), axis=(1, 2)) & np.all(np.isfinite(r), axis=1)
    if A.shape[1] != A.shape[2]:
        steps[finite] = least_squares_steps(A[finite], r[finite])
        return steps
    try:
        steps[finite] = -np.linalg.solve(A[finite], r[finite][..., None])[..., 0]
    except np.linalg.LinAlgError:  # some matrix is singular: solve one by one, leave those NaN
        for k in np.nonzero(finite)[0]:
            try:
                steps[k] = -np.linalg.solve(A[k], r[k])
            except np.linalg.LinAlgError:
                pass  # the sample stops and is reported as not converged
    return steps


def newton_iterate(start: np.ndarray, equations: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]],
             tol: float, max_iterations: int, max_step: float | None = None, stall: int | None = None) -> NewtonReport:
    """Newton iteration x <- x - A(x)^-1 r(x) (Gauss-Newton -A^+ r where A is not square) on a batch (..., k) of
    unknowns, reported per sample (:class:`NewtonReport`).

    ``equations(x, rows)`` gives r and A of the samples ``rows`` (indices into the flattened
    batch) at their unknowns x (len(rows), k); only the samples still iterating are evaluated.
    With ``max_step`` the iteration is damped: a step longer than that (max-norm) is scaled
    down to it, so a start near one solution does not jump to another far away.

    With ``stall`` a sample also stops, not converged, once its residual (max-norm) has fallen by less than
    :data:`STALL_DECREASE` over its last ``stall`` steps: from a start in a solution's basin the (damped) Newton
    iterates decrease the residual (Deuflhard, Newton Methods for Nonlinear Problems, 2004, sec. 3.3, the
    monotonicity test), so a residual that stagnates for several steps says the start is outside it - the
    iteration circles near a singularity or settles on a least-squares minimum - and the steps left would be
    spent on a sample that does not converge (a continuation's cells beyond the workspace).
    """
    batch = start.shape[:-1]
    x = np.array(start, dtype=float, copy=True).reshape(-1, start.shape[-1])

    def flat_equations(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        r, A = equations(x[rows], rows)
        r = np.asarray(r, dtype=float)
        A = np.asarray(A, dtype=float)
        return r.reshape(len(rows), -1), A.reshape((len(rows),) + A.shape[-2:])

    count = x.shape[0]
    converged = np.zeros(count, dtype=bool)
    iterations = np.zeros(count, dtype=int)
    step_norm = np.full(count, np.inf)
    left = np.zeros(count, dtype=bool)  # a correction above tol that did not halve the one before
    active = np.ones(count, dtype=bool)
    residuals = np.full((count, max_iterations), np.inf) if stall else np.zeros((0, 0))
    for iteration in range(max_iterations):
        rows = np.flatnonzero(active)
        if not len(rows):
            break
        r, A = flat_equations(rows)
        stalled = np.zeros(len(rows), dtype=bool)
        if stall:
            residuals[rows, iteration] = np.max(np.abs(r), axis=-1, initial=0.0)
            if iteration >= stall:
                stalled = residuals[rows, iteration] > STALL_DECREASE * residuals[rows, iteration - stall]
        step = newton_steps(A, r)
        with np.errstate(invalid="ignore"):
            norm = np.max(np.abs(step), axis=-1)
        moved = np.isfinite(norm)
        if max_step is not None:
            with np.errstate(invalid="ignore"):
                step *= (max_step / np.maximum(norm, max_step))[:, None]
        x[rows[moved]] += step[moved]
        iterations[rows] += 1
        with np.errstate(invalid="ignore"):
            left[rows] |= moved & (norm > tol) & (norm > 0.5 * step_norm[rows])
        step_norm[rows] = norm
        done = moved & (norm <= tol)
        converged[rows[done]] = True
        active[rows[~moved | done | stalled]] = False
    r, _ = flat_equations(np.arange(count))
    residual = np.max(np.abs(r), axis=-1) if count else np.zeros(0)
    converged &= np.isfinite(residual)
    x[~converged] = np.nan
    return NewtonReport(x.reshape(start.shape), converged.reshape(batch), iterations.reshape(batch),
                        residual.reshape(batch), step_norm.reshape(batch), left.reshape(batch))
