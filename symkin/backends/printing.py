"""Printing rules shared by the text backends (numpy, C): literals, products and powers.

:class:`ArithmeticPrinterMixin` goes in front of a sympy code printer and replaces its
number, product and power printing so that every text backend writes the same arithmetic:

* every number prints as the shortest literal that reads back as the nearest value of the
  target type (:meth:`literal`): exact-to-double, deterministic, never an integer division;
* a product prints its constant coefficient first and its negative powers as one
  denominator: ``-2.0*x*y/(z*z)``;
* ``x**n`` for a small integer n prints as repeated multiplication when
  :meth:`unroll_power` says so, ``x**(1/2)`` as the backend's square root, other powers
  through :meth:`general_power`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import sympy
from sympy.printing.precedence import PRECEDENCE

#: Largest exponent printed as repeated multiplication (the op count model uses the same bound).
from symkin.ir.opcount import MAX_UNROLLED_POWER

__all__ = ["ArithmeticPrinterMixin", "MAX_UNROLLED_POWER"]


class ArithmeticPrinterMixin:
    """Shared number, product and power printing (mix in before a sympy CodePrinter)."""

    #: Name of the square-root function in the target language.
    sqrt_function = "sqrt"

    if TYPE_CHECKING:  # provided by the sympy printer the mixin goes in front of
        def _print(self, expr: Any, **kwargs: Any) -> str: ...

    # -- hooks -------------------------------------------------------------------------

    def literal(self, value: float) -> str:
        """Source text of a floating-point constant."""
        return repr(value)

    def unroll_power(self, base: sympy.Expr, exponent: int) -> bool:
        """Whether ``base**exponent`` (|exponent| >= 2) prints as repeated multiplication."""
        return abs(exponent) <= MAX_UNROLLED_POWER

    def general_power(self, base: str, exponent: sympy.Expr) -> str:
        """Source text of ``base**exponent`` for a power that is not unrolled (``base`` is printed)."""
        exponent_text = str(int(exponent)) if exponent.is_Integer else self._operand(exponent)
        return f"{base}**{exponent_text}"

    # -- numbers -----------------------------------------------------------------------

    def _print_Float(self, expr: sympy.Float) -> str:
        return self.literal(float(expr))

    def _print_Rational(self, expr: sympy.Rational) -> str:
        return self.literal(float(expr))

    def _print_Integer(self, expr: sympy.Integer) -> str:
        return self.literal(float(expr))

    def _print_NumberSymbol(self, expr: sympy.Expr) -> str:
        return self.literal(float(expr))

    _print_Pi = _print_Exp1 = _print_EulerGamma = _print_GoldenRatio = _print_Catalan = _print_NumberSymbol

    # -- products and powers -----------------------------------------------------------

    def _operand(self, expr: sympy.Expr) -> str:
        """``expr`` as a factor that is safe next to ``*`` and ``/`` on both sides."""
        text = self._print(expr)
        if expr.is_Atom or expr.is_Function or (expr.is_Pow and not self._prints_as_product(expr)):
            return text
        return f"({text})"

    def _prints_as_product(self, expr: sympy.Pow) -> bool:
        exp = expr.exp
        return bool(exp.is_Integer and abs(int(exp)) >= 2 and self.unroll_power(expr.base, int(exp)))

    def _print_Mul(self, expr: sympy.Mul) -> str:
        coeff, factors = expr.as_coeff_mul()
        numerator, denominator = [], []
        for f in factors:
            if f.is_Pow and f.exp.is_Rational and f.exp.is_negative:
                denominator.append(f.base if f.exp == -1 else sympy.Pow(f.base, -f.exp, evaluate=False))
            else:
                numerator.append(f)
        sign = "-" if coeff.is_negative else ""
        coeff = abs(coeff)
        parts = [self.literal(float(coeff))] if coeff != 1 or not numerator else []
        parts += [self._factor(f) for f in numerator]
        text = "*".join(parts)
        if denominator:
            if len(denominator) == 1:
                text += "/" + self._operand(denominator[0])
            else:
                text += "/(" + "*".join(self._factor(f) for f in denominator) + ")"
        return sign + text

    def _factor(self, expr: sympy.Expr) -> str:
        """``expr`` as a factor of a product (parenthesized sums)."""
        return self.parenthesize(expr, PRECEDENCE["Mul"], strict=False)

    def _print_Pow(self, expr: sympy.Pow, rational: bool = False) -> str:
        base, exp = expr.base, expr.exp
        if exp.is_Integer and abs(int(exp)) >= 1 and (abs(int(exp)) == 1 or self.unroll_power(base, int(exp))):
            n = abs(int(exp))
            factor = self._operand(base) if n > 1 else self._print(base)
            product = "*".join([factor] * n)
            if exp > 0:
                return product
            return f"{self.literal(1.0)}/" + (f"({product})" if n > 1 else self._operand(base))
        if exp == sympy.Rational(1, 2):
            return f"{self.sqrt_function}({self._print(base)})"
        if exp == sympy.Rational(-1, 2):
            return f"{self.literal(1.0)}/{self.sqrt_function}({self._print(base)})"
        return self.general_power(self._operand(base), exp)

    def parenthesize(self, item: sympy.Expr, level: int, strict: bool = False) -> str:
        # An unrolled power is a product: give it the precedence of Mul, not of Pow.
        if isinstance(item, sympy.Pow) and self._prints_as_product(item):
            text = self._print(item)
            if item.exp < 0 or level > PRECEDENCE["Mul"] or (strict and level == PRECEDENCE["Mul"]):
                return f"({text})"
            return text
        return super().parenthesize(item, level, strict)  # type: ignore[misc]
