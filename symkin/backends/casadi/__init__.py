"""The CasADi backend: one serialized, named ``casadi.Function`` per generated function.

Loading needs casadi and numpy only (no sympy): :mod:`symkin.backends.casadi.binding`
deserializes the functions and wraps them with the numpy backend's calling semantics; the
raw ``casadi.Function`` stays available as the ``casadi`` attribute of each wrapper, for
optimization problems, ``map``, derivatives and CasADi's own C generation.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from symkin.ir.bundle import ModelCode


class CasadiBackend:
    """Emits ``<model>_<function>.casadi`` files; loads them as wrapped casadi.Functions."""

    name = "casadi"

    def emit(self, code: ModelCode) -> dict[str, str | bytes]:
        from symkin.backends.casadi.emit import emit_functions

        return emit_functions(code)

    def load(self, directory: Path, manifest: dict[str, Any]) -> dict[str, Callable[..., Any]]:
        from symkin.backends.casadi.binding import bind_functions

        return bind_functions(Path(directory), manifest)
