"""The JavaScript backend: one dependency-free script per model, for browsers and Node.js.

The emitter is imported only when code is generated.  The module is evaluated in the page of
``symkin view`` (:mod:`symkin.viewer`) and, in the tests, under Node.js.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from symkin.ir.bundle import ModelCode


class JavascriptBackend:
    """Emits ``<model>.js``: one function per generated function, single configuration, in doubles."""

    name = "js"
    loader: str | None = None  # the script runs in a browser (symkin view) or Node.js, not in Python

    def emit(self, code: ModelCode) -> dict[str, str | bytes]:
        from symkin.backends.js.emit import emit_script

        return emit_script(code)

    def reserved_words(self) -> frozenset[str]:
        """ECMAScript's reserved words (the model reader refuses them already: :mod:`symkin.model.names`)."""
        from symkin.model.names import JS_KEYWORDS

        return JS_KEYWORDS
