"""Names and shape texts shared by the emitters and the loaders (no sympy: the runtime uses it)."""

from __future__ import annotations

import re


def type_name(function_name: str, suffix: str = "Result") -> str:
    """CamelCase type name for a function's multi-output result, e.g. ``frames`` -> ``FramesResult``."""
    return "".join(part.capitalize() for part in re.split(r"_+", function_name) if part) + suffix


def shape_text(shape: tuple[int, ...] | list[int], batch: str = "...") -> str:
    """Human-readable array shape with a leading batch, e.g. ``(..., 4, 4)``."""
    return "(" + ", ".join([batch] + [str(s) for s in shape]) + ")"


def c_symbol(model_name: str, function_name: str, suffix: str = "") -> str:
    """Name of a generated C function, e.g. ``ur10e_fk``, ``ur10e_fk_batch_f32``."""
    return f"{model_name}_{function_name}{suffix}"


def casadi_file(model_name: str, function_name: str) -> str:
    """Name of a serialized CasADi function, e.g. ``ur10e_fk.casadi``."""
    return f"{model_name}_{function_name}.casadi"


def matrix_shape(shape: tuple[int, ...] | list[int]) -> tuple[int, int]:
    """The (rows, columns) of an output as a matrix: (r, c), (r,) -> (r, 1), () -> (1, 1)."""
    shape = tuple(shape)
    return (shape[0], shape[1]) if len(shape) == 2 else (shape[0], 1) if len(shape) == 1 else (1, 1)
