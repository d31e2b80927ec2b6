"""Operation counts: the arithmetic a generated function performs, before and after optimization.

The count models the emitted code, in which constant subexpressions are literals
(:func:`~symkin.optimize.passes.fold_constants` evaluates them at generation time):

* a subexpression without symbols (``3``, ``sqrt(2)/2``, ``cos(1/10)``) is free;
* an n-term sum is n - 1 additions/subtractions, where all constant terms together count
  as one term;
* a product of k non-constant factors is k - 1 multiplications (or divisions), plus one
  if its constant factors multiply to something other than +-1;
* ``x**n`` for an integer |n| <= 16 is |n| - 1 multiplications, plus a division if n < 0;
* ``sqrt``, any other power and every function call count one.

Shared subexpressions are counted at every occurrence, so the count of a spec is the cost
of evaluating its outputs naively, and the count after CSE (temporaries + outputs) is the
cost of the generated code.

Parameter folding cannot increase the count: replacing a symbol by a number leaves every
term's cost as it was or lowers it (a constant sum term or product factor joins the one
literal, a whole constant subexpression becomes free).  The exception would be a symbolic
exponent becoming a large integer, which the model language rules out (exponents are
constants); ``tests/test_optimize.py`` checks the property on random expressions.
"""

from __future__ import annotations

from collections.abc import Iterable

import sympy

from symkin.ir.spec import FunctionSpec

#: Integer powers up to this exponent are counted (and printed) as repeated multiplication.
MAX_UNROLLED_POWER = 16


def _cost(expr: sympy.Expr, memo: dict[sympy.Expr, tuple[int, bool]]) -> tuple[int, bool]:
    """(operation count, is a constant) of ``expr``."""
    if expr.is_Atom:
        return 0, not expr.free_symbols
    cached = memo.get(expr)
    if cached is not None:
        return cached
    args = [_cost(a, memo) for a in expr.args]
    constant = all(c for _, c in args)
    if constant:
        result = (0, True)
    elif expr.is_Add or expr.is_Mul:
        variable = [n for n, c in args if not c]
        constants = [a for a, (_, c) in zip(expr.args, args) if c]
        if expr.is_Add:
            extra = 1 if constants else 0
        else:
            extra = 1 if constants and sympy.Mul(*constants) not in (1, -1) else 0
        result = (len(variable) - 1 + extra + sum(variable), False)
    elif expr.is_Pow:
        (base_cost, _), (exp_cost, exp_constant) = args
        exp = expr.exp
        if exp.is_Integer and abs(int(exp)) <= MAX_UNROLLED_POWER:
            n = abs(int(exp))
            result = (max(n - 1, 0) + (1 if exp < 0 else 0) + base_cost, False)
        else:
            result = (1 + base_cost + exp_cost, False)
    else:
        result = (1 + sum(n for n, _ in args), False)
    memo[expr] = result
    return result


def op_count(exprs: Iterable[sympy.Expr]) -> int:
    """Total operation count of ``exprs`` (see the module docstring for the cost model)."""
    memo: dict[sympy.Expr, tuple[int, bool]] = {}
    return sum(_cost(sympy.sympify(e), memo)[0] for e in exprs)


def spec_op_count(spec: FunctionSpec) -> int:
    """Operation count of all output entries of ``spec``."""
    return op_count(e for out in spec.outputs for e in out.entries)
