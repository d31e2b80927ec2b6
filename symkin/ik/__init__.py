"""Inverse kinematics of serial mechanisms, on the generated functions of a loaded model.

Nothing here derives symbolically or imports sympy: every solver evaluates the functions
``symkin derive`` generated (``fk``, ``jacobian_geometric`` or ``jacobian``,
``task_coordinates``) through a :class:`~symkin.runtime.LoadedModel`, so it runs on any
backend the model was loaded with.

* :func:`solve_numeric` - damped least squares for any serial model, batches of targets
  and starts, joint limits respected, a convergence report per target;
* :func:`closed_form_solver` - every solution branch where the structure allows it
  (planar 2R: two elbow branches; the UR family: eight), singular cases flagged;
* :func:`numeric_branches` - the distinct solutions found from many random starts (what
  the closed forms are checked against).

Example::

    import symkin
    from symkin.ik import closed_form_solver, solve_numeric

    ur = symkin.load("generated/ur10e")
    T = ur.fk([0.1, -1.2, 1.3, -0.4, 0.9, 0.2])
    solutions = closed_form_solver(ur).solve(T)    # 8 branches, flags, residuals
    result = solve_numeric(ur, T, q0=[0, -1, 1, 0, 1, 0])
    result.converged, result.iterations, result.reason
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from symkin.ik import planar as _planar  # noqa: F401  (registers the planar 2R solver)
from symkin.ik import ur as _ur  # noqa: F401  (registers the UR-family solver)
from symkin.ik.closed_form import BranchFlag, ClosedFormIK, ClosedFormSolutions, closed_form_solver
from symkin.ik.numeric import DEFAULT_TOLERANCE, IKResult, distinct_solutions, random_configurations, solve_numeric
from symkin.ik.problem import ModelKinematics
from symkin.runtime import LoadedModel

__all__ = ["BranchFlag", "ClosedFormIK", "ClosedFormSolutions", "IKResult", "ModelKinematics",
           "closed_form_solver", "distinct_solutions", "numeric_branches", "random_configurations",
           "solve_numeric"]


def numeric_branches(model: LoadedModel | ModelKinematics, target: np.ndarray | Sequence, *, starts: int = 64,
                     seed: int = 0, kind: str | None = None, tolerance: float = DEFAULT_TOLERANCE,
                     max_iterations: int = 200) -> tuple[np.ndarray, IKResult]:
    """Solve one target from ``starts`` random configurations within the limits.

    Returns:
        (the distinct converged solutions (k, n), revolute angles wrapped to (-pi, pi];
        the :class:`IKResult` of every start).
    """
    kin = model if isinstance(model, ModelKinematics) else ModelKinematics(model)
    q0 = random_configurations(kin, starts, np.random.default_rng(seed))
    result = solve_numeric(kin, np.asarray(target, dtype=float)[None], q0, kind=kind, tolerance=tolerance,
                           max_iterations=max_iterations)
    return distinct_solutions(kin, result.q[result.converged]), result
