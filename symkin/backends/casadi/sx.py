"""Build CasADi SX expressions from the optimized IR (a sympy printer that returns SX).

Each CSE temporary becomes one SX node that every later use refers to, so the common
subexpressions of the optimized function stay shared in the CasADi graph (and in the C
that CasADi generates from it).  Numbers become exact doubles, integer powers up to 16
repeated multiplications (as in the C and numpy backends), ``x**(1/2)`` a square root.
"""

from __future__ import annotations

import functools
import operator
from collections.abc import Callable, Mapping

import casadi
import sympy
from sympy.printing.printer import Printer

from symkin.backends.printing import MAX_UNROLLED_POWER

#: sympy function -> casadi function of the same meaning.
FUNCTIONS: dict[str, Callable[..., casadi.SX]] = {
    "sin": casadi.sin, "cos": casadi.cos, "tan": casadi.tan,
    "asin": casadi.asin, "acos": casadi.acos, "atan": casadi.atan, "atan2": casadi.atan2,
    "sinh": casadi.sinh, "cosh": casadi.cosh, "tanh": casadi.tanh,
    "exp": casadi.exp, "log": casadi.log, "Abs": casadi.fabs, "sign": casadi.sign,
    "floor": casadi.floor, "ceiling": casadi.ceil,
}


class SXBuilder(Printer):
    """Turns sympy expressions into ``casadi.SX`` given the SX of every free symbol."""

    printmethod = "_casadi_sx"

    def __init__(self, symbols: Mapping[sympy.Symbol, casadi.SX]):
        super().__init__()
        self.symbols = dict(symbols)

    def bind(self, symbol: sympy.Symbol, value: casadi.SX) -> None:
        """Make ``symbol`` (a CSE temporary) stand for ``value`` in later expressions."""
        self.symbols[symbol] = value

    def doprint(self, expr: sympy.Expr) -> casadi.SX:
        return casadi.SX(self._print(sympy.sympify(expr)))

    def emptyPrinter(self, expr: sympy.Expr) -> casadi.SX:  # noqa: N802 (sympy's hook name)
        raise NotImplementedError(f"the CasADi backend cannot express {type(expr).__name__}: {expr}")

    def _print_Symbol(self, expr: sympy.Symbol) -> casadi.SX:
        try:
            return self.symbols[expr]
        except KeyError:
            raise NotImplementedError(f"the symbol {expr} is no input of the function") from None

    def _print_Number(self, expr: sympy.Number) -> float:
        return float(expr)

    _print_Integer = _print_Rational = _print_Float = _print_NumberSymbol = _print_Number

    def _print_Pi(self, expr: sympy.Expr) -> float:
        return float(expr)

    def _print_Add(self, expr: sympy.Add) -> casadi.SX:
        return functools.reduce(operator.add, (self._print(a) for a in expr.args))

    def _print_Mul(self, expr: sympy.Mul) -> casadi.SX | float:
        coeff, factors = expr.as_coeff_mul()
        numerator = [self._print(f) for f in factors if not (f.is_Pow and f.exp.is_Rational and f.exp.is_negative)]
        denominator = [self._print(sympy.Pow(f.base, -f.exp)) for f in factors
                       if f.is_Pow and f.exp.is_Rational and f.exp.is_negative]
        value = functools.reduce(operator.mul, numerator) if numerator else 1.0
        if coeff == -1:
            value = -value
        elif coeff != 1:
            value = float(coeff) * value
        if denominator:
            value = value / functools.reduce(operator.mul, denominator)
        return value

    def _print_Pow(self, expr: sympy.Pow) -> casadi.SX:
        base, exp = expr.base, expr.exp
        if exp.is_Integer and 1 <= abs(int(exp)) <= MAX_UNROLLED_POWER:
            b = self._print(base)
            product = functools.reduce(operator.mul, [b] * abs(int(exp)))
            return product if exp > 0 else 1.0 / product
        if exp == sympy.Rational(1, 2):
            return casadi.sqrt(self._print(base))
        if exp == sympy.Rational(-1, 2):
            return 1.0 / casadi.sqrt(self._print(base))
        return casadi.power(self._print(base), self._print(exp))

    def _print_Function(self, expr: sympy.Function) -> casadi.SX:
        name = type(expr).__name__
        if name not in FUNCTIONS:
            return self.emptyPrinter(expr)
        return FUNCTIONS[name](*[self._print(a) for a in expr.args])

    def _print_Max(self, expr: sympy.Max) -> casadi.SX:
        return functools.reduce(casadi.fmax, [self._print(a) for a in expr.args])

    def _print_Min(self, expr: sympy.Min) -> casadi.SX:
        return functools.reduce(casadi.fmin, [self._print(a) for a in expr.args])
