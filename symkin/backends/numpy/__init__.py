"""The numpy backend: one importable, vectorized Python module per model.

The emitter is imported only when code is generated; the loader (:mod:`symkin.backends.numpy.loader`, runtime
layer: no sympy, no jinja2) only when a model's code is loaded.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from symkin.ir.bundle import ModelCode


class NumpyBackend:
    """Emits ``<model>.py``: vectorized numpy functions with docstrings."""

    name = "numpy"
    loader: str | None = "symkin.backends.numpy.loader"

    def emit(self, code: ModelCode) -> dict[str, str | bytes]:
        from symkin.backends.numpy.emit import emit_module

        return emit_module(code)

    def reserved_words(self) -> frozenset[str]:
        """Python's keywords (the model reader refuses them already: :mod:`symkin.model.names`)."""
        from symkin.model.names import PYTHON_KEYWORDS

        return PYTHON_KEYWORDS
