"""The C backend: a C99 header and source per model, compiled and loaded on demand.

Generation (``emit``) imports sympy and jinja2 lazily; loading (``load``) needs only the
standard library, numpy and a C compiler: the source is compiled once into a shared
library cached by content hash (see :mod:`symkin.backends.c.build`) and bound with ctypes
(:mod:`symkin.backends.c.binding`).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from symkin.ir.bundle import ModelCode


class CBackend:
    """Emits ``<model>.h`` and ``<model>.c``; loads them through a cached shared library."""

    name = "c"

    def emit(self, code: ModelCode) -> dict[str, str | bytes]:
        from symkin.backends.c.emit import emit_sources

        return emit_sources(code)

    def load(self, directory: Path, manifest: dict[str, Any]) -> dict[str, Callable[..., Any]]:
        from symkin.backends.c.binding import bind_library

        return bind_library(Path(directory), manifest)
