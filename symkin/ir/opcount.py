"""Operation counts: the arithmetic a generated function performs, before and after optimization.

The count models the emitted code, in which constant subexpressions are literals
(:func:`~symkin.optimize.passes.fold_constants` evaluates them at generation time):

* a subexpression without symbols (``3``, ``sqrt(2)/2``, ``cos(1/10)``) is free;
* an n-term sum is n - 1 additions/subtractions, where all constant terms together count
  as one term;
* a product of k non-constant factors is k - 1 multiplications and divisions (it prints
  as ``c*a*b/(d*e)``: factors with a negative power go after the one ``/`` with their
  positive power), plus one if its constant factors multiply to something other than
  +-1 or if every factor is in the denominator (``1.0/(d*e)``);
* ``x**n`` for an integer |n| <= 16 is |n| - 1 multiplications, plus a division if n < 0;
* ``sqrt``, any other power and every function call count one (``x**(-1/2)`` two).

Shared subexpressions are counted at every occurrence, so the count of a spec is the cost
of evaluating its outputs naively, and the count after CSE (temporaries + outputs) is the
cost of the generated code.

Parameter folding cannot increase the count: replacing a symbol by a number leaves every
term's cost as it was or lowers it (a constant sum term or product factor joins the one
literal, a whole constant subexpression becomes free).  The exception would be a symbolic
exponent becoming a large integer, which the model language rules out (exponents are
constants); the passes never let sympy's re-evaluation of a node raise its cost
(:mod:`symkin.optimize.passes`), and ``tests/derivation/test_optimize.py`` checks the property on
random expressions.
"""

from __future__ import annotations

from collections.abc import Iterable

import sympy

from symkin.ir.spec import FunctionSpec

#: Integer powers up to this exponent are counted (and printed) as repeated multiplication.
MAX_UNROLLED_POWER = 16


def _power_cost(expr: sympy.Pow, base_cost: int, exp_cost: int) -> int:
    """Cost of ``expr`` = base**exp as printed on its own (a denominator factor is priced by :func:`_cost`)."""
    exp = expr.exp
    if exp.is_Integer and abs(int(exp)) <= MAX_UNROLLED_POWER:
        n = abs(int(exp))
        return max(n - 1, 0) + (1 if n and exp < 0 else 0) + base_cost
    if exp == sympy.S.Half:
        return 1 + base_cost
    if exp == -sympy.S.Half:
        return 2 + base_cost
    return 1 + base_cost + exp_cost


def _is_denominator(factor: sympy.Expr) -> bool:
    """Whether a product prints ``factor`` after its ``/`` (a negative rational power)."""
    return bool(factor.is_Pow and factor.exp.is_Rational and factor.exp.is_negative)


def _cost(expr: sympy.Expr, memo: dict[sympy.Expr, tuple[int, bool]]) -> tuple[int, bool]:
    """(operation count, is a constant) of ``expr``."""
    if expr.is_Atom:
        return 0, not expr.free_symbols
    cached = memo.get(expr)
    if cached is not None:
        return cached
    args = [_cost(a, memo) for a in expr.args]
    if all(c for _, c in args):
        result = (0, True)
    elif expr.is_Add:
        variable = [n for n, c in args if not c]
        constant_terms = len(args) - len(variable)
        result = (len(variable) - 1 + (1 if constant_terms else 0) + sum(variable), False)
    elif expr.is_Mul:
        constants, costs, numerator = [], [], 0
        for factor, (n, c) in zip(expr.args, args):
            if c:
                constants.append(factor)
            elif _is_denominator(factor):
                # printed as num/(...): the positive power, joined by the one division
                inverse = sympy.Pow(factor.base, -factor.exp, evaluate=False)
                costs.append(_power_cost(inverse, _cost(factor.base, memo)[0], 0))
            else:
                costs.append(n)
                numerator += 1
        coefficient = sympy.Mul(*constants) if constants else sympy.S.One
        extra = 1 if coefficient not in (1, -1) or numerator == 0 else 0
        result = (len(costs) - 1 + extra + sum(costs), False)
    elif expr.is_Pow:
        (base_cost, _), (exp_cost, _) = args
        result = (_power_cost(expr, base_cost, exp_cost), False)
    else:
        result = (1 + sum(n for n, _ in args), False)
    memo[expr] = result
    return result


def node_cost(expr: sympy.Expr, memo: dict) -> int:
    """Operation count of one expression, with a memo shared across calls."""
    return _cost(expr, memo)[0]


def op_count(exprs: Iterable[sympy.Expr]) -> int:
    """Total operation count of ``exprs`` (see the module docstring for the cost model)."""
    memo: dict[sympy.Expr, tuple[int, bool]] = {}
    return sum(_cost(sympy.sympify(e), memo)[0] for e in exprs)


def spec_op_count(spec: FunctionSpec) -> int:
    """Operation count of all output entries of ``spec`` (and of its definitions, each counted once)."""
    return op_count([e for _, e in spec.definitions] + [e for out in spec.outputs for e in out.entries])
