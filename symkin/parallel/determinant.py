"""Determinants and adjugates of symbolic matrices by Laplace expansion with shared minors.

Expanding along the first remaining row, every minor is identified by its rows and
columns; memoizing them turns the n! terms of the Laplace expansion into about n 2^n
operations on shared subexpressions (64 minors for a 6x6 determinant), which the common
subexpression elimination then evaluates once each.  Unlike Gaussian elimination this
introduces no divisions, so the result is a polynomial in the entries and vanishes exactly
where the matrix is singular.
"""

from __future__ import annotations

import sympy

Key = tuple[tuple[int, ...], tuple[int, ...]]


def _minor(M: sympy.Matrix, rows: tuple[int, ...], cols: tuple[int, ...], memo: dict[Key, sympy.Expr]) -> sympy.Expr:
    if not rows:
        return sympy.Integer(1)
    key = (rows, cols)
    if key not in memo:
        terms = []
        for k, c in enumerate(cols):
            entry = M[rows[0], c]
            if entry != 0:
                terms.append((-1) ** k * entry * _minor(M, rows[1:], cols[:k] + cols[k + 1:], memo))
        memo[key] = sympy.Add(*terms)
    return memo[key]


def determinant(M: sympy.Matrix) -> sympy.Expr:
    """det(M) of a square matrix."""
    n = M.shape[0]
    return _minor(M, tuple(range(n)), tuple(range(n)), {})


def adjugate(M: sympy.Matrix) -> sympy.Matrix:
    """adj(M), so that M adj(M) = det(M) I; entry (j, i) is the (i, j) cofactor."""
    n = M.shape[0]
    memo: dict[Key, sympy.Expr] = {}
    rows = tuple(range(n))
    adj = sympy.zeros(n, n)
    for i in range(n):
        for j in range(n):
            adj[j, i] = (-1) ** (i + j) * _minor(M, rows[:i] + rows[i + 1:], rows[:j] + rows[j + 1:], memo)
    return adj
