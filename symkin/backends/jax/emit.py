"""Printing of the JAX module from the optimized functions: the numpy module's contexts
(:mod:`symkin.backends.numpy.emit`) printed by JAX's printer, rendered by templates/jax/module.py.j2 (which extends the
numpy module's template: the same module, each output stacked from its entries instead of written in place)."""

from __future__ import annotations

from symkin.backends.jax.printer import BatchJaxPrinter
from symkin.backends.numpy.emit import function_context, module_context
from symkin.backends.templating import render
from symkin.ir.bundle import ModelCode

TEMPLATE = "jax/module.py.j2"


def emit_jax_module(code: ModelCode) -> dict[str, str | bytes]:
    """{<model>_jax.py: module text} for ``code``."""
    printer = BatchJaxPrinter()
    functions = [function_context(f, printer) for f in code.functions]
    return {f"{code.name}_jax.py": render(TEMPLATE, **module_context(code, TEMPLATE), array=printer.array_module,
                                          functions=functions)}
