"""Language-neutral layout helpers shared by the backends."""

from __future__ import annotations

import itertools

import sympy

from symkin.backends.naming import shape_text, type_name
from symkin.ir.spec import OutputSpec

__all__ = ["element_indices", "nonzero_elements", "shape_text", "type_name"]


def element_indices(shape: tuple[int, ...]) -> list[tuple[int, ...]]:
    """Row-major indices of an array of ``shape`` (``[()]`` for a scalar)."""
    return list(itertools.product(*(range(s) for s in shape)))


def nonzero_elements(output: OutputSpec, entries: tuple[sympy.Expr, ...]) -> list[tuple[tuple[int, ...], sympy.Expr]]:
    """(index, expression) of every entry that is not identically zero, row-major."""
    return [(index, e) for index, e in zip(element_indices(output.shape), entries) if e != 0]
