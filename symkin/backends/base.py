"""The interface every code generator implements."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    from symkin.ir.bundle import ModelCode


class Backend(Protocol):
    """A code generator: prints a :class:`ModelCode` and loads what it printed.

    Attributes:
        name: registry key (``numpy``, ``c``, ``casadi``).
    """

    name: str

    def emit(self, code: ModelCode) -> dict[str, str | bytes]:
        """Files to write, as {relative path: content}; content must be deterministic."""
        ...

    def load(self, directory: Path, manifest: dict[str, Any]) -> dict[str, Callable[..., Any]]:
        """The generated functions found in ``directory``, by function name."""
        ...
