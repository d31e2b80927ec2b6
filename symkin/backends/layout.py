"""Language-neutral layout helpers shared by the backends."""

from __future__ import annotations

import itertools

import sympy

from symkin.backends.naming import shape_text, type_name
from symkin.ir.spec import InputSpec, OptimizedFunction, OutputSpec

__all__ = ["element_indices", "element_text", "expressions", "nonzero_elements", "shape_text", "type_name",
           "used_symbols"]


def element_indices(shape: tuple[int, ...]) -> list[tuple[int, ...]]:
    """Row-major indices of an array of ``shape`` (``[()]`` for a scalar)."""
    return list(itertools.product(*(range(s) for s in shape)))


def nonzero_elements(output: OutputSpec, entries: tuple[sympy.Expr, ...]) -> list[tuple[tuple[int, ...], sympy.Expr]]:
    """(index, expression) of every entry that is not identically zero, row-major."""
    return [(index, e) for index, e in zip(element_indices(output.shape), entries) if e != 0]


def expressions(f: OptimizedFunction) -> list[sympy.Expr]:
    """Every expression the function evaluates: temporaries, then output entries."""
    return [e for _, e in f.temporaries] + [e for entries in f.outputs for e in entries]


def used_symbols(f: OptimizedFunction) -> set[sympy.Symbol]:
    """The symbols (input elements, parameters, temporaries) its expressions read."""
    return {s for e in expressions(f) for s in e.free_symbols}


def element_text(i: InputSpec) -> str:
    """``q1 [rad], q2 [rad]``: the elements of a vector input with their units."""
    return ", ".join(f"{n} [{u}]" for n, u in zip(i.element_names, i.units))
