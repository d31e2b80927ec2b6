"""Expression optimization: pure passes from a FunctionSpec to an OptimizedFunction.

:func:`optimize` runs, in order:

1. :func:`~symkin.optimize.passes.fold_parameters` - substitute fixed parameters by their
   exact values (and drop them from the inputs);
2. :func:`~symkin.optimize.trig.expand_trig_sums` - sin and cos of angle sums through
   the addition formulas, so each angle costs one sin/cos pair;
3. :func:`~symkin.optimize.passes.fold_constants` - evaluate constant subexpressions
   (``cos(1/10)``, ``sqrt(3)/2``) once, at 30 digits, instead of at every call;
4. :func:`~symkin.optimize.cse.eliminate_common_subexpressions` - one CSE across all
   outputs of the function;
5. :func:`~symkin.optimize.schedule.demand_order` - the temporaries in the order the outputs need them;
6. :func:`~symkin.optimize.maps.unroll_maps` - a spec's column maps (whose values ran through
   the passes and the CSE as one more output, :func:`~symkin.optimize.maps.with_map_values`)
   unrolled into the temporaries, each run of them marked for backends that print loops.

The operation count after each stage is recorded in ``OptimizedFunction.op_counts``.
"""

from __future__ import annotations

from collections.abc import Iterable

from symkin.ir.spec import FunctionSpec, OptimizedFunction
from symkin.optimize.cse import eliminate_common_subexpressions
from symkin.optimize.maps import unroll_maps, with_map_values
from symkin.ir.opcount import spec_op_count
from symkin.optimize.passes import fold_constants, fold_parameters, fold_parameters_after_cse
from symkin.optimize.schedule import demand_order
from symkin.optimize.trig import expand_trig_sums

__all__ = ["optimize", "fold_parameters", "fold_parameters_after_cse", "fold_constants", "expand_trig_sums",
           "eliminate_common_subexpressions", "demand_order", "spec_op_count"]


def optimize(spec: FunctionSpec, fixed: Iterable[str] = ()) -> OptimizedFunction:
    """Optimize one function spec.

    Args:
        spec: the derived function.
        fixed: names of parameters to fold to their default values.

    Folding parameters runs two ways, and the cheaper result is kept: fold, then CSE (sympy
    can simplify with the numbers in place) and CSE, then fold into the temporaries
    (:func:`fold_parameters_after_cse`, never more operations than without folding).  So
    folding never costs operations, at the price of a second CSE when something is fixed.

    Returns:
        The optimized function; ``op_counts`` has ``derived`` (as derived), ``folded``
        (after parameter folding, when any parameter was folded; never above ``derived``)
        and ``cse`` (final: temporaries plus outputs).
    """
    if spec.maps:
        return unroll_maps(demand_order(_reduced(with_map_values(spec), tuple(fixed))), spec.maps)
    return demand_order(_reduced(spec, tuple(fixed)))


def _reduced(spec: FunctionSpec, fixed: tuple[str, ...]) -> OptimizedFunction:
    """The fewer operations of folding, then CSE, and CSE, then folding (see :func:`optimize`)."""
    counts = {"derived": spec_op_count(spec)}
    if not any(i.kind == "parameter" and i.name in fixed for i in spec.inputs):
        return eliminate_common_subexpressions(_prepare(spec), counts)
    folded = fold_parameters(spec, fixed)
    counts["folded"] = spec_op_count(folded)
    fold_first = eliminate_common_subexpressions(_prepare(folded), counts)
    cse_first = fold_parameters_after_cse(eliminate_common_subexpressions(_prepare(spec), counts), fixed)
    return fold_first if fold_first.op_counts["cse"] <= cse_first.op_counts["cse"] else cse_first


def _prepare(spec: FunctionSpec) -> FunctionSpec:
    """The passes between folding and CSE: angle sums expanded, then constants evaluated."""
    return fold_constants(expand_trig_sums(spec))
