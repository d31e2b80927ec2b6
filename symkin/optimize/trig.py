"""Angle-sum expansion: sin and cos of sums of angles through the addition formulas.

A pure pass like those of :mod:`symkin.optimize.passes`; see :func:`expand_trig_sums`.
"""

from __future__ import annotations

import sympy

from symkin.ir.spec import FunctionSpec
from symkin.optimize.passes import map_spec, rebuild


#: Largest integer multiple of an angle expanded by :func:`expand_trig_sums` (sin(4q) -> ...).
MAX_ANGLE_MULTIPLE = 4


def _angle_terms(arg: sympy.Expr) -> tuple[sympy.Expr, list[tuple[sympy.Symbol, int]]] | None:
    """``arg`` = constant + sum of n_i * s_i (symbols s_i, small integers n_i), or None."""
    terms = sympy.Add.make_args(arg)
    constant = sympy.Add(*[t for t in terms if not t.free_symbols])
    parts = []
    for term in (t for t in terms if t.free_symbols):
        coefficient, symbol = term.as_coeff_Mul()
        if not (symbol.is_Symbol and coefficient.is_Integer and 1 <= abs(int(coefficient)) <= MAX_ANGLE_MULTIPLE):
            return None
        parts.append((symbol, int(coefficient)))
    if not parts or (len(parts) == 1 and parts[0][1] == 1 and constant == 0):
        return None  # sin(q) itself
    return constant, sorted(parts, key=lambda p: p[0].sort_key())


class _AngleSums:
    """sin and cos of angle sums built from sin and cos of single symbols, prefixes shared."""

    def __init__(self) -> None:
        self.pairs: dict[tuple, tuple[sympy.Expr, sympy.Expr]] = {}

    @staticmethod
    def add(a: tuple[sympy.Expr, sympy.Expr], b: tuple[sympy.Expr, sympy.Expr]) -> tuple[sympy.Expr, sympy.Expr]:
        (sa, ca), (sb, cb) = a, b
        return sa * cb + ca * sb, ca * cb - sa * sb

    def multiple(self, symbol: sympy.Symbol, n: int) -> tuple[sympy.Expr, sympy.Expr]:
        key = ((symbol, n),)
        if key not in self.pairs:
            if n < 0:
                s, c = self.multiple(symbol, -n)
                self.pairs[key] = (-s, c)
            elif n == 1:
                self.pairs[key] = (sympy.sin(symbol), sympy.cos(symbol))
            else:
                self.pairs[key] = self.add(self.multiple(symbol, n - 1), self.multiple(symbol, 1))
        return self.pairs[key]

    def sum(self, parts: list[tuple[sympy.Symbol, int]]) -> tuple[sympy.Expr, sympy.Expr]:
        key = tuple(parts)
        if key not in self.pairs:
            if len(parts) == 1:
                return self.multiple(*parts[0])
            self.pairs[key] = self.add(self.sum(parts[:-1]), self.multiple(*parts[-1]))
        return self.pairs[key]


def _definitions_of_angle_sums(spec: FunctionSpec) -> dict[sympy.Symbol, sympy.Expr]:
    """The definitions whose values are angle sums (``_w3 = q2 + q3``, ``_w4 = _w3 + q4``), written
    out in the symbols they add: trig of a definition is then expanded like trig of the sum."""
    sums: dict[sympy.Symbol, sympy.Expr] = {}
    for symbol, expr in spec.definitions:
        through = {s: sums[s] for s in expr.free_symbols if s in sums}
        value = expr.xreplace(through) if through else expr
        if not value.is_Symbol and _angle_terms(value) is not None:
            sums[symbol] = value
    return sums


def expand_trig_sums(spec: FunctionSpec) -> FunctionSpec:
    """Rewrite sin and cos of sums of angles through the angle-addition formulas.

    ``sin(q2 + q3 + q4)`` becomes ``sin(q2 + q3)*cos(q4) + cos(q2 + q3)*sin(q4)`` with
    ``sin(q2 + q3)`` itself expanded (prefixes of the sum, in a fixed symbol order, are
    shared, so CSE finds them once), likewise integer multiples (``sin(2*q)``) and constant
    offsets (``cos(q + pi/3)``, exact coefficients), also where the sum is a definition
    (``sin(_w4)`` with ``_w4 = q2 + q3 + q4``).  A function then calls sin and cos once
    per angle symbol and pays a few multiplications per sum instead: one sin/cos pair costs
    about as much time as 20-40 multiplications, so this trades a higher op count for speed.
    Applied before constant folding, so constant offsets stay exact.
    """
    sums = _AngleSums()
    angle_sums = _definitions_of_angle_sums(spec)

    def rewrite(expr: sympy.Expr) -> sympy.Expr | None:
        if not isinstance(expr, (sympy.sin, sympy.cos)):
            return None
        argument = rewrite_all(expr.args[0])
        through = {s: angle_sums[s] for s in argument.free_symbols if s in angle_sums}
        split = _angle_terms(argument.xreplace(through) if through else argument)
        if split is None:
            return None
        constant, parts = split
        pair = sums.sum(parts)
        if constant != 0:
            pair = sums.add(pair, (sympy.sin(constant), sympy.cos(constant)))
        return pair[0] if isinstance(expr, sympy.sin) else pair[1]

    memo: dict = {}

    def rewrite_all(expr: sympy.Expr) -> sympy.Expr:
        return rebuild(expr, rewrite, memo)

    return map_spec(spec, rewrite_all)
