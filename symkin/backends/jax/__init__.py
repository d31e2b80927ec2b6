"""The JAX backend (issue 66): one importable module of pure, jit-compiled ``jax.numpy`` functions per model.

The same optimized functions as the numpy backend (one intermediate representation; the template differs): every
function is pure (its outputs are stacked, never written in place; on a CPU the entries of all its outputs are
computed in one loop, see docs/generated-code.md), float64 (the module enables JAX's 64-bit
mode), jit-compiled, and composes with ``jax.vmap``, ``jax.grad`` and ``jax.jacfwd``; on a GPU a batch stays on
the device.  JAX is an optional dependency (``pip install symkin[jax]``): the emitter needs none, the loader
(:mod:`symkin.backends.jax.loader`) imports it when a model's code is loaded.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from symkin.ir.bundle import ModelCode


class JaxBackend:
    """Emits ``<model>_jax.py``: pure, jit-compiled jax.numpy functions with docstrings."""

    name = "jax"
    loader: str | None = "symkin.backends.jax.loader"

    def emit(self, code: ModelCode) -> dict[str, str | bytes]:
        from symkin.backends.jax.emit import emit_jax_module

        return emit_jax_module(code)

    def reserved_words(self) -> frozenset[str]:
        """Python's keywords (the model reader refuses them already: :mod:`symkin.model.names`)."""
        from symkin.model.names import PYTHON_KEYWORDS

        return PYTHON_KEYWORDS
