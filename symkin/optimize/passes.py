"""Spec-to-spec rewriting passes (each pure: a new spec, the input untouched).

Both passes substitute leaves (a fixed parameter by its value, a constant subexpression by a
30-digit float) and rebuild the expression bottom-up with :func:`_rebuild`, which lets sympy
re-evaluate every node whose arguments changed, except where sympy's evaluation would cost
more operations than the node as it stands (``atan2(y, 2)`` evaluates to ``atan(y/2)``: one
call becomes a call and a product; ``2*(x + y)`` distributes to ``2*x + 2*y``).  Since replacing a symbol by a number never raises the
cost of an unevaluated node under the op-count model (:mod:`symkin.ir.opcount`), no
pass can increase a function's operation count.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable

import sympy

from symkin.errors import DerivationError
from symkin.ir.spec import FunctionSpec, OptimizedFunction
from symkin.ir.opcount import node_cost, op_count

#: Digits used to evaluate constant subexpressions before they are rounded to double.
CONSTANT_DIGITS = 30

Replacement = Callable[[sympy.Expr], "sympy.Expr | None"]


def rebuild(expr: sympy.Expr, replace: Replacement, memo: dict,
            build: Callable[[sympy.Expr, tuple], sympy.Expr] = lambda expr, args: expr.func(*args)) -> sympy.Expr:
    """``expr`` with ``replace(node)`` substituted wherever it is not None, bottom-up.

    A node whose arguments changed is rebuilt with ``build(node, new_args)`` (sympy
    evaluation by default); ``memo`` maps nodes already seen to their result.
    """
    done = memo.get(expr)
    if done is not None:
        return done
    new = replace(expr)
    if new is None:
        if expr.is_Atom:
            new = expr
        else:
            args = tuple(rebuild(a, replace, memo, build) for a in expr.args)
            new = expr if args == expr.args else build(expr, args)
    memo[expr] = new
    return new


def _cheaper_node(costs: dict) -> Callable[[sympy.Expr, tuple], sympy.Expr]:
    """A ``build`` for :func:`rebuild`: the node re-evaluated by sympy, or left unevaluated where that is cheaper."""
    def build(expr: sympy.Expr, args: tuple) -> sympy.Expr:
        evaluated = expr.func(*args)
        try:
            plain = expr.func(*args, evaluate=False)
        except TypeError:  # a node type without unevaluated construction
            return evaluated
        return evaluated if node_cost(evaluated, costs) <= node_cost(plain, costs) else plain
    return build


def _rebuild(expr: sympy.Expr, replace: Replacement, memo: dict, costs: dict) -> sympy.Expr:
    """``expr`` with ``replace(node)`` substituted wherever it is not None, re-evaluated where that is cheaper."""
    return rebuild(expr, replace, memo, _cheaper_node(costs))


def map_spec(spec: FunctionSpec, rewrite: Callable[[sympy.Expr], sympy.Expr]) -> FunctionSpec:
    """``spec`` with ``rewrite`` applied to every output entry and every definition."""
    outputs = tuple(dataclasses.replace(o, expr=sympy.ImmutableMatrix(o.expr.applyfunc(rewrite)))
                    for o in spec.outputs)
    definitions = tuple((symbol, rewrite(expr)) for symbol, expr in spec.definitions)
    return dataclasses.replace(spec, outputs=outputs, definitions=definitions)


def _replace_in_spec(spec: FunctionSpec, replace: Replacement) -> FunctionSpec:
    memo: dict = {}
    costs: dict = {}
    return map_spec(spec, lambda e: _rebuild(e, replace, memo, costs))


def fold_parameters(spec: FunctionSpec, fixed: Iterable[str]) -> FunctionSpec:
    """Substitute the ``fixed`` parameters by their exact default values; drop them from the inputs.

    Folding lets sympy simplify (``0*x``, ``cos(pi/2)``, products of numbers) before CSE,
    so a fixed-geometry servo loop pays only for what varies; it never adds operations
    (see the module docstring).
    """
    fixed = set(fixed)
    values = {i.symbols[0]: i.default for i in spec.inputs if i.kind == "parameter" and i.name in fixed}
    if not values:
        return spec
    inputs = tuple(i for i in spec.inputs if not (i.kind == "parameter" and i.name in fixed))
    problem = (f"{spec.name}: the fixed parameters {', '.join(f'{k} = {v}' for k, v in values.items())} make an "
               "output undefined (a division by zero or the like)")
    try:
        folded = _replace_in_spec(spec, lambda e: values.get(e) if e.is_Symbol else None)
    except TypeError:  # sympy compares an undefined value (atan2 of zoo, ...)
        raise DerivationError(f"{problem}; keep them free or change their values") from None
    if any(e.has(sympy.zoo, sympy.nan) for o in folded.outputs for e in o.entries):
        raise DerivationError(f"{problem}; keep them free or change their values")
    return dataclasses.replace(folded, inputs=inputs)


def _constant_value(expr: sympy.Expr) -> sympy.Expr | None:
    if expr.is_Atom or expr.is_Rational or not expr.is_number:
        return None
    value = expr.evalf(CONSTANT_DIGITS)
    return value if value.is_Float else None


def fold_constants(spec: FunctionSpec) -> FunctionSpec:
    """Replace constant non-rational subexpressions (``sqrt(3)/2``, ``cos(1/10)``) by 30-digit floats.

    Rational numbers stay exact, so exponents keep their cheap forms (``x**2``, ``sqrt(x)``).
    """
    return _replace_in_spec(spec, _constant_value)


def fold_parameters_after_cse(function: OptimizedFunction, fixed: Iterable[str]) -> OptimizedFunction:
    """Fold the ``fixed`` parameters into an already optimized function (temporaries and outputs).

    The other order than :func:`fold_parameters` followed by CSE: it keeps the CSE found
    with the parameters as symbols (numbers in products can hide common factors from
    sympy's CSE), and it cannot add operations to it: every temporary and output is rebuilt
    with :func:`_rebuild`, and a temporary that folds to a number, a single symbol or the value
    of an earlier temporary is substituted into its uses instead of being kept.  ``op_counts["cse"]`` is recomputed.
    """
    spec = function.spec
    fixed = set(fixed)
    values: dict[sympy.Symbol, sympy.Expr] = {i.symbols[0]: i.default for i in spec.parameter_inputs
                                              if i.name in fixed}
    if not values:
        return function
    memo: dict = {}
    constants_memo: dict = {}
    costs: dict = {}

    def fold(expr: sympy.Expr) -> sympy.Expr:
        substituted = _rebuild(expr, lambda e: values.get(e) if e.is_Symbol else None, memo, costs)
        return _rebuild(substituted, _constant_value, constants_memo, costs)

    temporaries = []
    first_with_value: dict[sympy.Expr, sympy.Symbol] = {}
    for symbol, expr in function.temporaries:
        folded = fold(expr)
        if folded.is_Atom:
            values[symbol] = folded  # a number or an alias: substitute it into later uses
        elif folded in first_with_value:
            values[symbol] = first_with_value[folded]  # two temporaries that folding made equal
        else:
            first_with_value[folded] = symbol
            temporaries.append((symbol, folded))
    outputs = tuple(tuple(fold(e) for e in entries) for entries in function.outputs)
    inputs = tuple(i for i in spec.inputs if not (i.kind == "parameter" and i.name in fixed))
    counts = dict(function.op_counts)
    counts["cse"] = op_count([e for _, e in temporaries] + [e for entries in outputs for e in entries])
    return OptimizedFunction(dataclasses.replace(spec, inputs=inputs), tuple(temporaries), outputs, counts)
