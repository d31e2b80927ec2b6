"""Sympy printer for the C backend: C99, double or float, literals exact to the target type."""

from __future__ import annotations

import numpy
import sympy
from sympy.codegen.ast import float32, float64, real
from sympy.printing.c import C99CodePrinter

from symkin.backends.printing import ArithmeticPrinterMixin

#: C type names of the precisions the backend emits.
C_TYPES = {"double": "double", "float": "float"}


class CPrinter(ArithmeticPrinterMixin, C99CodePrinter):
    """C99 printer for one precision (``"double"`` or ``"float"``).

    * numbers print as the shortest literal that reads back as the nearest double (or, for
      float, the nearest float with an ``f`` suffix), always with a decimal point or an
      exponent, so ``1/2`` can never become an integer division;
    * integer powers up to 16 print as repeated multiplication (``x*x``, ``1.0/(x*x)``),
      other powers as ``pow``/``powf``;
    * math functions get the precision's suffix (``sinf`` for float) from sympy's C99
      printer; anything C cannot express raises instead of printing a comment.
    """

    def __init__(self, precision: str = "double") -> None:
        if precision not in C_TYPES:
            raise ValueError(f"unknown precision {precision!r}; use one of {sorted(C_TYPES)}")
        self.precision = precision
        super().__init__({"type_aliases": {real: float32 if precision == "float" else float64}, "strict": True})
        self.sqrt_function = "sqrtf" if precision == "float" else "sqrt"

    def literal(self, value: float) -> str:
        if not numpy.isfinite(value):
            raise ValueError(f"cannot print the non-finite constant {value} in C")
        if self.precision == "float":
            text = str(numpy.float32(value))
            suffix = "f"
        else:
            text = repr(float(value))
            suffix = ""
        if not any(c in text for c in ".eE"):
            text += ".0"
        return text + suffix

    def _print_sign(self, expr: sympy.sign) -> str:
        # sympy's C printer subtracts two int comparisons; a floating result needs no conversion
        x = self._print(expr.args[0])
        one, zero = self.literal(1.0), self.literal(0.0)
        return f"({x} > {zero} ? {one} : ({x} < {zero} ? -{one} : {zero}))"

    def general_power(self, base: str, exponent: sympy.Expr) -> str:
        function = "powf" if self.precision == "float" else "pow"
        exponent_text = self.literal(float(exponent)) if exponent.is_Number else self._print(exponent)
        return f"{function}({base}, {exponent_text})"
