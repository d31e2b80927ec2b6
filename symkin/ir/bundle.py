"""What the backends receive: every optimized function of one model plus its identity."""

from __future__ import annotations

from dataclasses import dataclass

from symkin.ir.spec import OptimizedFunction


@dataclass(frozen=True)
class ParameterInfo:
    """A model parameter as generated code sees it.

    Attributes:
        name: parameter name.
        default: default value as a double.
        unit: unit text.
        doc: description.
        fixed: True if folded into the code (then it is no input of any function).
    """

    name: str
    default: float
    unit: str
    doc: str
    fixed: bool


@dataclass(frozen=True)
class ModelCode:
    """The optimized functions of one model, ready to be printed by any backend.

    Attributes:
        name: model name (module/library name of the generated code).
        hash: model hash, ``sha256:<hex>``.
        description: model description.
        symkin_version: version of the generator.
        coordinates: joint coordinate names, in order.
        parameters: every model parameter.
        functions: the optimized functions, in request order (then the combined one).
        float32: also emit single-precision variants where the backend has them (C).
    """

    name: str
    hash: str
    description: str
    symkin_version: str
    coordinates: tuple[str, ...]
    parameters: tuple[ParameterInfo, ...]
    functions: tuple[OptimizedFunction, ...]
    float32: bool = False
