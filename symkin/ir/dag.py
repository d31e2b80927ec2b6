"""Walks over sympy expressions as the DAGs they are in memory, not as trees.

sympy shares subexpressions between the expressions built from one another (the entries of
base_T_k are sums of products of the entries of base_T_(k-1)), but its recursive properties,
``free_symbols`` first, walk them as trees: on an n-joint chain that is exponential in n.
These walks visit each distinct node once.
"""

from __future__ import annotations

from collections.abc import Iterable

import sympy


def free_symbols(exprs: Iterable[sympy.Basic]) -> set[sympy.Symbol]:
    """The symbols ``exprs`` use, each distinct node visited once (``Basic.free_symbols`` walks the tree)."""
    seen: set[sympy.Basic] = set()
    found: set[sympy.Symbol] = set()
    stack = list(exprs)
    while stack:
        node = stack.pop()
        if node in seen:
            continue
        seen.add(node)
        if node.is_Symbol:
            found.add(node)
        elif not node.is_Atom:
            stack.extend(a for a in node.args if a not in seen)
    return found

