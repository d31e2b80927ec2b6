"""Conversions between sympy, symkin's public expression type, and SymEngine, its fast engine.

SymEngine (C++) builds, differentiates and CSE-reduces large expression graphs orders of
magnitude faster than sympy.  symkin uses it inside the dynamics derivation and the CSE of
large straight-line programs, and converts results back with :func:`to_sympy`:

* symbols are mapped *by name* to the caller's sympy symbols (SymEngine drops assumptions
  such as ``real=True``, and sympy symbols with other assumptions are different symbols);
* every distinct SymEngine node is converted once (memoized), so shared subexpressions cost
  one conversion;
* sums and products are rebuilt from their arguments as SymEngine ordered them
  (``_from_args``): SymEngine has already flattened them and combined numbers, so sympy's
  canonicalization, the dominant cost of a conversion, is skipped.  The result is a valid
  sympy expression, equal in value; its argument order is SymEngine's (deterministic for a
  given SymEngine version, which requirements/constraints.txt pins).
* numbers stay exact (Integer, Rational) and constants map to sympy's (pi, E).
"""

from __future__ import annotations

from collections.abc import Mapping

import symengine as se
import sympy

from symkin.expression_dag import post_order

_FUNCTIONS = {name: getattr(sympy, name) for name in (
    "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "exp", "log", "sign", "Abs")}
_CONSTANTS = {"Pi": sympy.pi, "E": sympy.E}


_SE_FUNCTIONS = {getattr(sympy, name): getattr(se, name) for name in _FUNCTIONS}


def to_symengine(expr: sympy.Expr, memo: dict[sympy.Basic, se.Basic] | None = None) -> se.Basic:
    """A sympy expression as a SymEngine one (symbols keep their names, assumptions are dropped).

    Every distinct sympy node is converted once (``memo``, which callers may share across
    expressions): the products of transforms along a long chain are DAGs whose trees are
    exponentially larger, and ``symengine.sympify`` walks the tree.  Sums, products, powers
    and the functions of :data:`_FUNCTIONS` are rebuilt from their converted arguments, so
    SymEngine canonicalizes them as ``sympify`` would; any other node (numbers, constants)
    goes through ``sympify`` whole.
    """
    memo = {} if memo is None else memo

    def convert(node: sympy.Basic) -> se.Basic:
        rebuild = _rebuilder(node)
        return se.sympify(node) if rebuild is None else rebuild(*[memo[a] for a in node.args])

    post_order([expr], memo, convert, children=lambda node: () if _rebuilder(node) is None else node.args)
    return memo[expr]


def _rebuilder(node: sympy.Basic):
    """The SymEngine constructor of a sympy node rebuilt from its arguments, None for a leaf."""
    if node.is_Atom:
        return None
    if node.is_Add:
        return se.Add
    if node.is_Mul:
        return se.Mul
    if node.is_Pow:
        return se.Pow
    return _SE_FUNCTIONS.get(node.func)


class SympyConverter:
    """Converts SymEngine expressions to sympy with a symbol table and a memo shared across calls.

    Args:
        symbols: the sympy symbols to use, by name; any other symbol becomes a plain real
            ``sympy.Symbol`` of the same name.
    """

    def __init__(self, symbols: Mapping[str, sympy.Symbol]):
        self.symbols = dict(symbols)
        self._memo: dict[se.Basic, sympy.Expr] = {}

    def __call__(self, expr: se.Basic) -> sympy.Expr:
        memo = self._memo
        post_order([expr], memo, lambda node: self._convert(node, [memo[a] for a in node.args]))
        return memo[expr]

    def _convert(self, node: se.Basic, args: list[sympy.Expr]) -> sympy.Expr:
        kind = type(node).__name__
        if node.is_Symbol:
            name = str(node)
            if name not in self.symbols:
                self.symbols[name] = sympy.Symbol(name, real=True)
            return self.symbols[name]
        if node.is_Integer:
            return sympy.Integer(int(node))
        if node.is_Rational:
            return sympy.Rational(int(node.p), int(node.q))
        if kind == "RealMPFR":  # a folded constant (symkin.optimize.passes.fold_constants)
            return sympy.Float(str(node), len(str(node)))
        if kind == "RealDouble":
            return sympy.Float(float(node))
        if kind in _CONSTANTS:
            return _CONSTANTS[kind]
        if kind == "Add":
            return sympy.Add._from_args(args)
        if kind == "Mul":
            return sympy.Mul._from_args(args)
        if kind == "Pow":
            return sympy.Pow(*args)
        if kind in _FUNCTIONS:
            return _FUNCTIONS[kind](*args)
        raise NotImplementedError(f"cannot convert the SymEngine node {kind} ({node}) to sympy")
