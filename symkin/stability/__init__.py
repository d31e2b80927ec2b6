"""Numerical-stability checks of generated code against a 50-digit reference.

:func:`~symkin.stability.harness.run_stability` evaluates every generated quantity of a model
at random states, along paths into singular configurations, at length scales 1e-3 to 1e3 and
in float32, against the un-optimized expressions evaluated in 50-digit ball arithmetic;
:mod:`symkin.stability.report` renders the tables and the figure of ``symkin bench stability``.
"""

from symkin.stability.harness import BOUND, KAPPA_LIMIT, Record, StabilityRun, run_stability

__all__ = ["BOUND", "KAPPA_LIMIT", "Record", "StabilityRun", "run_stability"]
