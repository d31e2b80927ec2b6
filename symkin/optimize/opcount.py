"""Operation counts: the arithmetic a generated function performs, before and after optimization.

The count models the emitted code, not sympy's tree: literals are free; an n-term sum is
n - 1 additions/subtractions; a product of k non-constant factors is k - 1 multiplications
(or divisions), plus one if it has a numeric coefficient other than +-1; ``x**n`` for a
small integer n is n - 1 multiplications (a negative n adds a division); ``sqrt`` and
every other function call count one.  Shared subexpressions are counted at every
occurrence, so the count of a spec is the cost of evaluating its outputs naively, and the
count after CSE (temporaries + outputs) is the cost of the generated code.
"""

from __future__ import annotations

from collections.abc import Iterable

import sympy

from symkin.ir.spec import FunctionSpec


def _cost(expr: sympy.Expr, memo: dict[sympy.Expr, int]) -> int:
    if expr.is_Atom:
        return 0
    cached = memo.get(expr)
    if cached is not None:
        return cached
    if expr.is_Add:
        total = len(expr.args) - 1 + sum(_cost(a, memo) for a in expr.args)
    elif expr.is_Mul:
        coeff, factors = expr.as_coeff_mul()
        total = max(len(factors) - 1, 0) + (0 if coeff in (1, -1) else 1) + sum(_cost(f, memo) for f in factors)
    elif expr.is_Pow:
        base, exp = expr.base, expr.exp
        if exp.is_Integer and abs(int(exp)) <= 16:
            n = abs(int(exp))
            total = max(n - 1, 0) + (1 if exp < 0 else 0) + _cost(base, memo)
        else:
            total = 1 + _cost(base, memo) + _cost(exp, memo)
    else:
        total = 1 + sum(_cost(a, memo) for a in expr.args)
    memo[expr] = total
    return total


def op_count(exprs: Iterable[sympy.Expr]) -> int:
    """Total operation count of ``exprs`` (see the module docstring for the cost model)."""
    memo: dict[sympy.Expr, int] = {}
    return sum(_cost(sympy.sympify(e), memo) for e in exprs)


def spec_op_count(spec: FunctionSpec) -> int:
    """Operation count of all output entries of ``spec`` (and of its definitions, each counted once)."""
    return op_count([e for _, e in spec.definitions] + [e for out in spec.outputs for e in out.entries])
