"""Code generators, registered by name.  Adding a backend touches this dict (and, to load what it
wrote, :data:`symkin.runtime.loader.LOADERS`)."""

from __future__ import annotations

from symkin.backends.base import Backend
from symkin.backends.c import CBackend
from symkin.backends.casadi import CasadiBackend
from symkin.backends.js import JavascriptBackend
from symkin.backends.numpy import NumpyBackend
from symkin.errors import SymkinError

BACKENDS: dict[str, Backend] = {
    "numpy": NumpyBackend(),
    "c": CBackend(),
    "casadi": CasadiBackend(),
    "js": JavascriptBackend(),
}


def get_backend(name: str) -> Backend:
    """The backend called ``name``.

    Raises:
        SymkinError: unknown backend.
    """
    try:
        return BACKENDS[name]
    except KeyError:
        raise SymkinError(f"unknown backend '{name}'; available: {', '.join(BACKENDS)}") from None
