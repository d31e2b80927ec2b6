"""Sympy printer for jax.numpy code: the numpy backend's rules (:class:`symkin.backends.numpy.printer.BatchNumPyPrinter`)
with JAX's module and functions (sympy's ``JaxPrinter``)."""

from __future__ import annotations

from sympy.printing.numpy import JaxPrinter

from symkin.backends.numpy.printer import BatchNumPyPrinter


class BatchJaxPrinter(BatchNumPyPrinter, JaxPrinter):
    """jax.numpy printer: ``jax.numpy.sin(q1)``, ``jax.numpy.sqrt``, the shared literal, product and power rules."""

    sqrt_function = "jax.numpy.sqrt"
    array_module = "jax.numpy"
