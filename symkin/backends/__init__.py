"""Code generators, registered by name.  Adding a backend is a folder ``symkin/backends/<name>/`` (its emitter,
printer and loader, :class:`~symkin.backends.base.Backend`) and one line of this dict."""

from __future__ import annotations

from symkin.backends.base import Backend
from symkin.backends.c import CBackend
from symkin.backends.casadi import CasadiBackend
from symkin.backends.jax import JaxBackend
from symkin.backends.js import JavascriptBackend
from symkin.backends.numpy import NumpyBackend
from symkin.errors import SymkinError

BACKENDS: dict[str, Backend] = {
    "numpy": NumpyBackend(),
    "c": CBackend(),
    "casadi": CasadiBackend(),
    "js": JavascriptBackend(),
    "jax": JaxBackend(),
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
