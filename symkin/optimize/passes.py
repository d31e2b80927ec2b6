"""Spec-to-spec rewriting passes (each pure: a new spec, the input untouched)."""

from __future__ import annotations

from collections.abc import Iterable

import sympy
from sympy.core.parameters import distribute

from symkin.ir.spec import FunctionSpec, OutputSpec

#: Digits used to evaluate constant subexpressions before they are rounded to double.
CONSTANT_DIGITS = 30


def _map_outputs(spec: FunctionSpec, fn) -> tuple[OutputSpec, ...]:
    return tuple(OutputSpec(o.name, sympy.ImmutableMatrix(o.expr.applyfunc(fn)), o.doc, o.unit, o.shape)
                 for o in spec.outputs)


def _map_definitions(spec: FunctionSpec, fn) -> tuple[tuple[sympy.Symbol, sympy.Expr], ...]:
    return tuple((symbol, fn(expr)) for symbol, expr in spec.definitions)


def fold_parameters(spec: FunctionSpec, fixed: Iterable[str]) -> FunctionSpec:
    """Substitute the ``fixed`` parameters by their exact default values; drop them from the inputs.

    Folding lets sympy simplify (``0*x``, ``cos(pi/2)``, products of numbers) before CSE,
    so a fixed-geometry servo loop pays only for what varies.  Sympy's automatic
    distribution of a number over a sum (``2*(x + y)`` -> ``2*x + 2*y``) is switched off
    while substituting: it would turn one multiplication into several.
    """
    fixed = set(fixed)
    values = {i.symbols[0]: i.default for i in spec.inputs if i.kind == "parameter" and i.name in fixed}
    if not values:
        return spec
    with distribute(False):
        outputs = _map_outputs(spec, lambda e: e.xreplace(values))
        definitions = _map_definitions(spec, lambda e: e.xreplace(values))
    inputs = tuple(i for i in spec.inputs if not (i.kind == "parameter" and i.name in fixed))
    return FunctionSpec(spec.name, spec.summary, spec.doc, inputs, outputs, definitions)


def _fold(expr: sympy.Expr) -> sympy.Expr:
    if expr.is_Atom:
        return expr
    if expr.is_number and not expr.is_Rational:
        value = expr.evalf(CONSTANT_DIGITS)
        if value.is_Float:
            return value
        return expr
    if expr.is_Pow:
        base = _fold(expr.base)
        return expr if base is expr.base else expr.func(base, expr.exp)  # keep exact exponents (x**2, sqrt)
    args = tuple(_fold(a) for a in expr.args)
    if all(new is old for new, old in zip(args, expr.args)):
        return expr  # nothing folded below: no need to rebuild
    return expr.func(*args)


def fold_constants(spec: FunctionSpec) -> FunctionSpec:
    """Replace constant non-rational subexpressions (``sqrt(3)/2``, ``cos(1/10)``) by 30-digit floats.

    Exponents stay exact so that ``x**2`` and ``sqrt(x)`` keep their cheap forms.
    """
    with distribute(False):
        return FunctionSpec(spec.name, spec.summary, spec.doc, spec.inputs, _map_outputs(spec, _fold),
                            _map_definitions(spec, _fold))
