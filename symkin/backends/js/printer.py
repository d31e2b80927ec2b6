"""Sympy printer for the JavaScript backend (ES2020, IEEE doubles: ``Number``)."""

from __future__ import annotations

import math

import sympy
from sympy.printing.jscode import JavascriptCodePrinter

from symkin.backends.printing import ArithmeticPrinterMixin


class JsPrinter(ArithmeticPrinterMixin, JavascriptCodePrinter):
    """JavaScript printer with the shared literal, product and power rules (symkin.backends.printing).

    Numbers print as Python's shortest round-trip repr, which JavaScript reads back as the same
    double (both follow the shortest-round-trip rule of Steele & White / Ryu); integer powers up
    to 16 print as repeated multiplication, other powers as ``Math.pow``; functions map to
    ``Math`` (sympy's table).  Sums keep their argument order (``order="none"``), as in the
    other backends, so the module is deterministic.
    """

    sqrt_function = "Math.sqrt"

    def __init__(self) -> None:
        super().__init__({"order": "none", "strict": True})

    def literal(self, value: float) -> str:
        if not math.isfinite(value):
            raise ValueError(f"cannot print the non-finite constant {value} in JavaScript")
        return repr(float(value))

    def general_power(self, base: str, exponent: sympy.Expr) -> str:
        exponent_text = self.literal(float(exponent)) if exponent.is_Number else self._print(exponent)
        return f"Math.pow({base}, {exponent_text})"

    def _print_Max(self, expr: sympy.Max) -> str:
        return "Math.max(" + ", ".join(self._print(a) for a in expr.args) + ")"

    def _print_Min(self, expr: sympy.Min) -> str:
        return "Math.min(" + ", ".join(self._print(a) for a in expr.args) + ")"
