"""Assembling a parallel mechanism numerically: the actuated and passive joints that close every leg at a pose.

Damped Gauss-Newton (:func:`symkin.newton.newton_iterate`, the one solver) on the generated closure rows
(:mod:`symkin.parallel.closure`), for the checks that need the mechanism assembled at a few poses (the
platform-motion check at home, the base parameters' rank on the closure).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from symkin.ir.evaluate import SYMENGINE_BACKEND, symengine_entries
from symkin.ir.quantity import Deriving
from symkin.model import coordinates
from symkin.newton import newton_iterate
from symkin.parallel.inputs import passive_symbols, task_symbols

#: Gauss-Newton on the closure at the home pose: steps and the largest step (rad or m) from the start.
ITERATIONS, MAX_STEP, TOLERANCE = 100, 0.2, 1e-12
#: The step of the central differences of the closure (rad or m): their error h^2 ~ 1e-12 slows Newton's last
#: steps a little, the residual still reaches rounding.
DIFFERENCE = 1e-6
#: Further starts when Gauss-Newton stops at a point that does not close the legs (a least-squares minimum).
STARTS = 8
#: The legs close when every closure row is below this (times the pose's scale, m): a converged Newton solve
#: leaves rounding, ~1e-15; a least-squares minimum misses by a link length.
CLOSED = 1e-9


def assembler(d: Deriving, backend: str = SYMENGINE_BACKEND
              ) -> Callable[[np.ndarray], tuple[np.ndarray, np.ndarray] | None]:
    """assemble(p): (q, s) closing every leg at p (the closure's rows below :data:`CLOSED` of the pose's scale), by
    damped Gauss-Newton on the generated closure (its Jacobian by central differences: the assembly needs no more
    than the rows' zero, and the closure alone derives in a fraction of the time of its Jacobians) from q = s = 0
    and then from :data:`STARTS` fixed random starts; None if none closes.  The closure is compiled once, by
    SymEngine's ``backend`` (:func:`symkin.ir.evaluate.symengine_entries`)."""
    model = d.model
    q_symbols, s_symbols = coordinates.symbols(model, "q"), passive_symbols(model)
    function = symengine_entries(d["closure"], q_symbols + s_symbols + task_symbols(model), model.parameter_values,
                                 backend)
    n, k = len(q_symbols), len(s_symbols)
    return lambda p: _gauss_newton(function, n, k, p)


def _gauss_newton(function: Callable[[np.ndarray], np.ndarray], n: int, k: int, p: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray] | None:
    """(q, s) of the first start, in order, whose damped Gauss-Newton solve (:func:`symkin.newton.newton_iterate`)
    closes the legs at p; None if none does.  The zero start alone first (it usually closes them), then the random
    ones as one batch."""
    def residuals(X: np.ndarray) -> np.ndarray:  # rows of X: states; one call for the batch
        return function(np.concatenate([X, np.broadcast_to(p, (len(X), len(p)))], axis=1))

    def equations(X: np.ndarray, _rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        steps = DIFFERENCE * np.eye(n + k)
        shifted = residuals(np.concatenate([X[:, None, :] + steps, X[:, None, :] - steps], axis=1).reshape(-1, n + k))
        shifted = shifted.reshape(len(X), 2, n + k, -1)
        return residuals(X), np.swapaxes((shifted[:, 0] - shifted[:, 1]) / (2 * DIFFERENCE), 1, 2)

    scale = max(float(np.max(np.abs(p), initial=0.0)), 1.0)
    rng = np.random.default_rng(0)
    starts = np.stack([np.zeros(n + k)] + [rng.uniform(-np.pi / 2, np.pi / 2, n + k) for _ in range(STARTS)])
    for batch in (starts[:1], starts[1:]):
        report = newton_iterate(batch, equations, TOLERANCE, ITERATIONS, MAX_STEP)
        for x, residual in zip(report.solution, report.residual):
            if np.all(np.isfinite(x)) and residual <= CLOSED * scale:
                return x[:n], x[n:]
    return None
