"""Using generated code: :func:`load` a derived model directory (no sympy needed)."""

from symkin.runtime.loader import LoadedModel, load

__all__ = ["LoadedModel", "load"]
