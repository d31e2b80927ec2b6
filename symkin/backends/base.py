"""The interface every code generator implements; one object per backend, registered in
:data:`symkin.backends.BACKENDS`."""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from symkin.ir.bundle import ModelCode


class Backend(Protocol):
    """A code generator: prints a :class:`ModelCode`, and names the module that loads what it wrote.

    A backend is one folder (``symkin/backends/<name>/``: the emitter, its printer, its loader) and one line of
    :data:`symkin.backends.BACKENDS`.

    Attributes:
        name: registry key (``numpy``, ``c``, ``casadi``, ``js``).
        loader: the dotted name of the module whose ``load(directory, info)`` returns {function name: Python
            function} for a model directory this backend wrote (:class:`~symkin.runtime.info.ModelInfo` ``info``),
            imported by :func:`symkin.runtime.loader.load` only when a model's code is loaded (it belongs to the
            runtime layer, and may import casadi or a compiler); None when Python does not load the code (the
            JavaScript runs in a browser or Node.js).
    """

    name: str
    loader: str | None

    def emit(self, code: ModelCode) -> dict[str, str | bytes]:
        """Files to write, as {relative path: content}; content must be deterministic.  Templates come from the
        shipped templates/ (``templates/<name>/``) or, for a backend added outside symkin, from its own folder
        (:func:`symkin.backends.templating.render_from`)."""
        ...

    def reserved_words(self) -> frozenset[str]:
        """The words its code cannot take as names: a model using one is refused before emitting, located in its
        file (:func:`symkin.pipeline.resolve_request`)."""
        ...
