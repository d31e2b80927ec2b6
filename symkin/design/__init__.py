"""Dimensioning optimization with CasADi and IPOPT (seed sec. 4, steps 1-3; GCI eq. 8.28; Table 8.5).

    problem  = design_problem(model, "gci", ["l1"], bounds={"l1": (0.05, 0.3)})   # step 1
    program  = formulate(problem, casadi_model, numpy_model)                        # step 2
    solution = solve(problem, program)                                              # step 3
    rating   = evaluate(problem, numpy_model, solution.optimum)                     # independent check

:mod:`~symkin.design.problem` (free parameters, bounds, required box; refusals),
:mod:`~symkin.design.smooth` (1/kappa_F of CasADi Jacobians),
:mod:`~symkin.design.formulation` (the nonlinear program over the generated CasADi functions),
:mod:`~symkin.design.solving` (IPOPT, history, run times),
:mod:`~symkin.design.evaluation` (true GCI with error estimates and box reachability on the numpy code),
:mod:`~symkin.design.plots` (figures); design sweeps: :func:`sweep` (:mod:`~symkin.design.sweep_run`) over
:mod:`~symkin.design.sweeps`, :mod:`~symkin.design.sweep_metrics`, :mod:`~symkin.design.sweep_store` and
:mod:`~symkin.design.sweep_plots`.  Not to be confused with :mod:`symkin.optimize`, the
expression optimizer of the code generator.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from symkin.lazy import lazy_exports

if TYPE_CHECKING:  # the names as the type checker sees them
    from symkin.design.evaluation import Evaluation, evaluate, scale_invariance
    from symkin.design.formulation import DesignProgram, formulate
    from symkin.design.problem import (APPARENT_MASS_FUNCTIONS, OBJECTIVES, DesignProblem, FreeParameter,
                                      design_problem)
    from symkin.design.solving import Solution, solve
    from symkin.design.sweep_run import sweep

#: Each public name and the module that defines it: imported when first asked for (PEP 562), so that a command
#: line parser reading :mod:`~symkin.design.sweep_metrics` does not import CasADi and the analyses.
_EXPORTS = {
    "APPARENT_MASS_FUNCTIONS": "problem", "OBJECTIVES": "problem", "DesignProblem": "problem",
    "FreeParameter": "problem", "design_problem": "problem",
    "Evaluation": "evaluation", "evaluate": "evaluation", "scale_invariance": "evaluation",
    "DesignProgram": "formulation", "formulate": "formulation",
    "Solution": "solving", "solve": "solving",
    "sweep": "sweep_run",
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = lazy_exports(__name__, globals(), _EXPORTS)
