"""Sympy printer for numpy code that evaluates elementwise over any batch shape."""

from __future__ import annotations

import sympy
from sympy.printing.numpy import NumPyPrinter

from symkin.backends.printing import ArithmeticPrinterMixin

#: Integer powers of symbols up to this exponent are printed as repeated multiplication
#: (beyond it, or for compound bases, ``**`` avoids numpy temporaries).
MAX_UNROLLED_ARRAY_POWER = 4


class BatchNumPyPrinter(ArithmeticPrinterMixin, NumPyPrinter):
    """numpy printer with the shared literal, product and power rules (see symkin.backends.printing).

    Numbers print as the shortest repr of the nearest double (``0.1807``); ``x**2`` prints
    as ``x*x`` for a symbol x (each ``*`` on arrays costs a temporary, so only up to
    ``x**4``), ``numpy.sqrt`` for ``x**(1/2)``. Sums print their terms in the
    expression's own (deterministic) argument order (``order="none"``): sorting the terms of
    every sum for display cost seconds on the thousands of temporaries of the dynamics.
    """

    sqrt_function = "numpy.sqrt"
    #: The array module the printed code calls (``numpy.maximum``, ``numpy.shape``).
    array_module = "numpy"

    def __init__(self) -> None:
        super().__init__({"fully_qualified_modules": True, "inline": True, "order": "none"})

    def unroll_power(self, base: sympy.Expr, exponent: int) -> bool:
        return base.is_Symbol and abs(exponent) <= MAX_UNROLLED_ARRAY_POWER

    def _nested(self, function: str, args: tuple[sympy.Expr, ...]) -> str:
        text = self._print(args[0])
        for arg in args[1:]:
            text = f"{function}({text}, {self._print(arg)})"
        return text

    def _print_Max(self, expr: sympy.Max) -> str:
        return self._nested(f"{self.array_module}.maximum", expr.args)

    def _print_Min(self, expr: sympy.Min) -> str:
        return self._nested(f"{self.array_module}.minimum", expr.args)
