"""The interface every code generator implements (loading what it wrote is the runtime's:
:data:`symkin.runtime.loader.LOADERS`)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from symkin.ir.bundle import ModelCode


class Backend(Protocol):
    """A code generator: prints a :class:`ModelCode`.

    Attributes:
        name: registry key (``numpy``, ``c``, ``casadi``).
    """

    name: str

    def emit(self, code: ModelCode) -> dict[str, str | bytes]:
        """Files to write, as {relative path: content}; content must be deterministic."""
        ...
