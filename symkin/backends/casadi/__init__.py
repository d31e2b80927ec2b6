"""The CasADi backend: one serialized, named ``casadi.Function`` per generated function.

The loader (:mod:`symkin.backends.casadi.loader`, runtime layer: casadi and numpy only, no
sympy) deserializes the functions and wraps them with the numpy backend's calling
semantics; the raw ``casadi.Function`` stays available as the ``casadi`` attribute of each
wrapper, for optimization problems, ``map``, derivatives and CasADi's own C generation.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from symkin.ir.bundle import ModelCode


class CasadiBackend:
    """Emits ``<model>_<function>.casadi`` files."""

    name = "casadi"
    loader: str | None = "symkin.backends.casadi.loader"

    def emit(self, code: ModelCode) -> dict[str, str | bytes]:
        from symkin.backends.casadi.emit import emit_functions

        return emit_functions(code)

    def reserved_words(self) -> frozenset[str]:
        """None: a CasADi function's inputs and outputs are named by strings."""
        return frozenset()
