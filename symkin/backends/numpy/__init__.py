"""The numpy backend: one importable, vectorized Python module per model.

The emitter is imported only when code is generated; loading is the runtime's
(:mod:`symkin.runtime.numpy_module`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from symkin.ir.bundle import ModelCode


class NumpyBackend:
    """Emits ``<model>.py``: vectorized numpy functions with docstrings."""

    name = "numpy"

    def emit(self, code: ModelCode) -> dict[str, str | bytes]:
        from symkin.backends.numpy.emit import emit_module

        return emit_module(code)
