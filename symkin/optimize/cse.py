"""Common-subexpression elimination across all outputs of one function."""

from __future__ import annotations

import sympy
from sympy.core.parameters import distribute

from symkin.ir.spec import FunctionSpec, OptimizedFunction
from symkin.optimize.opcount import op_count

#: Prefix of CSE temporaries; model names must start with a letter, so these never clash.
TEMPORARY_PREFIX = "_x"


def eliminate_common_subexpressions(spec: FunctionSpec, counts: dict[str, int] | None = None) -> OptimizedFunction:
    """Run one CSE over every entry of every output of ``spec``.

    The result is deterministic: sympy's canonical ordering is used and temporaries are
    numbered in evaluation order (``_x0``, ``_x1``...).

    Args:
        spec: the function to optimize.
        counts: op counts of earlier stages, extended with ``cse`` (temporaries + outputs).
    """
    entries = [e for out in spec.outputs for e in out.entries]
    with distribute(False):  # keep 2*(x + y) as one product (see passes.fold_parameters)
        temporaries, reduced = sympy.cse(entries, symbols=sympy.numbered_symbols(TEMPORARY_PREFIX, real=True))
    outputs = []
    start = 0
    for out in spec.outputs:
        size = len(out.entries)
        outputs.append(tuple(reduced[start:start + size]))
        start += size
    counts = dict(counts or {})
    counts["cse"] = op_count([e for _, e in temporaries] + list(reduced))
    return OptimizedFunction(spec, tuple(temporaries), tuple(outputs), counts)
