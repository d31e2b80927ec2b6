"""The C backend: a C99 header and source per model.

Generation (``emit``) imports sympy and jinja2 lazily.  Loading is the runtime's
(:mod:`symkin.runtime.c_library`): the source is compiled once into a shared library cached by
content hash (:mod:`symkin.backends.c.build`) and bound with ctypes.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from symkin.ir.bundle import ModelCode


class CBackend:
    """Emits ``<model>.h`` and ``<model>.c``."""

    name = "c"

    def emit(self, code: ModelCode) -> dict[str, str | bytes]:
        from symkin.backends.c.emit import emit_sources

        return emit_sources(code)
