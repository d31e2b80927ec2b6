"""Spec-to-spec rewriting passes (each pure: a new spec, the input untouched)."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable

import sympy
from sympy.core.parameters import distribute

from symkin.ir.spec import FunctionSpec, OutputSpec

#: Digits used to evaluate constant subexpressions before they are rounded to double.
CONSTANT_DIGITS = 30


def _map_outputs(spec: FunctionSpec, fn) -> tuple[OutputSpec, ...]:
    return tuple(OutputSpec(o.name, sympy.ImmutableMatrix(o.expr.applyfunc(fn)), o.doc, o.unit, o.shape)
                 for o in spec.outputs)


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
    inputs = tuple(i for i in spec.inputs if not (i.kind == "parameter" and i.name in fixed))
    return dataclasses.replace(spec, inputs=inputs, outputs=outputs)


def _fold(expr: sympy.Expr) -> sympy.Expr:
    if expr.is_Atom:
        return expr
    if expr.is_number and not expr.is_Rational:
        value = expr.evalf(CONSTANT_DIGITS)
        if value.is_Float:
            return value
        return expr
    if expr.is_Pow:
        return expr.func(_fold(expr.base), expr.exp)  # keep exact exponents (x**2, sqrt)
    return expr.func(*(_fold(a) for a in expr.args))


def fold_constants(spec: FunctionSpec) -> FunctionSpec:
    """Replace constant non-rational subexpressions (``sqrt(3)/2``, ``cos(1/10)``) by 30-digit floats.

    Exponents stay exact so that ``x**2`` and ``sqrt(x)`` keep their cheap forms.
    """
    with distribute(False):
        return dataclasses.replace(spec, outputs=_map_outputs(spec, _fold))
