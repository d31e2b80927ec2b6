"""Sympy printer for numpy code that evaluates elementwise over any batch shape."""

from __future__ import annotations

import sympy
from sympy.printing.numpy import NumPyPrinter
from sympy.printing.precedence import PRECEDENCE, precedence

#: Integer powers up to this exponent are printed as repeated multiplication.
MAX_UNROLLED_POWER = 4


class BatchNumPyPrinter(NumPyPrinter):
    """numpy printer with exact-to-double literals and cheap integer powers.

    * numbers print as the shortest repr of the nearest double (``0.1807``), so literals
      round-trip and files are deterministic;
    * ``x**2`` prints as ``x*x`` (and up to ``x**4``) when x is a symbol, ``1/x`` for
      ``x**-1``, ``numpy.sqrt`` for ``x**(1/2)``;
    * sums print their terms in the expression's own (deterministic) argument order
      (``order="none"``): sorting the terms of every sum for display cost seconds on the
      thousands of temporaries of the dynamics, for no change in the computed value.
    """

    def __init__(self) -> None:
        super().__init__({"fully_qualified_modules": True, "inline": True, "order": "none"})

    def _print_Float(self, expr: sympy.Float) -> str:
        return repr(float(expr))

    def _print_Rational(self, expr: sympy.Rational) -> str:
        return repr(float(expr))

    def _print_Integer(self, expr: sympy.Integer) -> str:
        return str(int(expr))

    def _print_Mul(self, expr: sympy.Mul) -> str:
        coeff, rest = expr.as_coeff_Mul()
        if coeff.is_Number and coeff not in (1, -1) and rest != 1:
            sign = "-" if coeff < 0 else ""
            return f"{sign}{self._print(abs(coeff))}*{self.parenthesize(rest, PRECEDENCE['Mul'], strict=True)}"
        return super()._print_Mul(expr)

    def _print_Pow(self, expr: sympy.Pow, rational: bool = False) -> str:
        base, exp = expr.base, expr.exp
        prec = precedence(expr)
        if exp.is_Integer and 0 < abs(int(exp)) <= MAX_UNROLLED_POWER and base.is_Symbol:
            product = "*".join([self._print(base)] * abs(int(exp)))
            return product if exp > 0 else f"1/({product})" if abs(int(exp)) > 1 else f"1/{self._print(base)}"
        if exp == -1:
            return f"1/{self.parenthesize(base, PRECEDENCE['Pow'])}"
        if exp == sympy.Rational(1, 2):
            return f"numpy.sqrt({self._print(base)})"
        if exp == sympy.Rational(-1, 2):
            return f"1/numpy.sqrt({self._print(base)})"
        if exp.is_Rational:
            return f"{self.parenthesize(base, prec)}**{repr(float(exp))}" if not exp.is_Integer else \
                f"{self.parenthesize(base, prec)}**{int(exp)}"
        return super()._print_Pow(expr, rational=rational)
