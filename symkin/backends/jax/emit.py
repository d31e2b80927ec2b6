"""Printing of the JAX module from the optimized functions (see templates/jax/module.py.j2): the numpy module's
context (:mod:`symkin.backends.numpy.emit`) with JAX's printer, and each output as its row-major entries, which
the template stacks instead of writing them into an array."""

from __future__ import annotations

from typing import Any

from symkin.backends.jax.printer import BatchJaxPrinter
from symkin.backends.numpy.emit import function_context, module_context
from symkin.backends.templating import render
from symkin.ir.bundle import ModelCode
from symkin.ir.spec import OptimizedFunction

TEMPLATE = "jax/module.py.j2"


def _stacked_outputs(f: OptimizedFunction, printer: BatchJaxPrinter) -> list[dict[str, Any]]:
    """Each output's name, shape and entries, row-major and printed (None where identically zero)."""
    return [{"name": out.name, "local": f"_out_{out.name}", "shape": repr(tuple(out.shape)),
             "entries": [None if e == 0 else printer.doprint(e) for e in entries]}
            for out, entries in zip(f.spec.outputs, f.outputs)]


def emit_jax_module(code: ModelCode) -> dict[str, str | bytes]:
    """{<model>_jax.py: module text} for ``code``."""
    printer = BatchJaxPrinter()
    functions = [function_context(f, printer) | {"outputs": _stacked_outputs(f, printer)} for f in code.functions]
    return {f"{code.name}_jax.py": render(TEMPLATE, **module_context(code, TEMPLATE), functions=functions)}
