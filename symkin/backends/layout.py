"""Language-neutral layout helpers shared by the backends."""

from __future__ import annotations

import itertools
import re

import sympy

from symkin.ir.spec import OutputSpec


def element_indices(shape: tuple[int, ...]) -> list[tuple[int, ...]]:
    """Row-major indices of an array of ``shape`` (``[()]`` for a scalar)."""
    return list(itertools.product(*(range(s) for s in shape)))


def nonzero_elements(output: OutputSpec, entries: tuple[sympy.Expr, ...]) -> list[tuple[tuple[int, ...], sympy.Expr]]:
    """(index, expression) of every entry that is not identically zero, row-major."""
    return [(index, e) for index, e in zip(element_indices(output.shape), entries) if e != 0]


def type_name(function_name: str, suffix: str = "Result") -> str:
    """CamelCase type name for a function's multi-output result, e.g. ``frames`` -> ``FramesResult``."""
    return "".join(part.capitalize() for part in re.split(r"_+", function_name) if part) + suffix


def shape_text(shape: tuple[int, ...], batch: str = "...") -> str:
    """Human-readable array shape with a leading batch, e.g. ``(..., 4, 4)``."""
    return "(" + ", ".join([batch] + [str(s) for s in shape]) + ")"
