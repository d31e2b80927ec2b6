"""The C backend: a C99 header and source per model.

Generation (``emit``) imports sympy and jinja2 lazily.  The loader (:mod:`symkin.backends.c.loader`, runtime
layer) compiles the source once into a shared library cached by content hash (:mod:`symkin.backends.c.build`),
binds it with ctypes and, where it can build one, a CPython extension of compiled entry points
(:mod:`symkin.backends.c.loader_entry_points`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from symkin.ir.bundle import ModelCode


class CBackend:
    """Emits ``<model>.h`` and ``<model>.c``."""

    name = "c"
    loader: str | None = "symkin.backends.c.loader"

    def emit(self, code: ModelCode) -> dict[str, str | bytes]:
        from symkin.backends.c.emit import emit_sources

        return emit_sources(code)

    def reserved_words(self) -> frozenset[str]:
        """C's keywords (the model reader refuses them already: :mod:`symkin.model.names`)."""
        from symkin.model.names import C_KEYWORDS

        return C_KEYWORDS
