"""Walks over sympy expressions as the DAGs they are in memory, not as trees.

sympy shares subexpressions between the expressions built from one another (the entries of
base_T_k are sums of products of the entries of base_T_(k-1)), but its recursive properties,
``free_symbols`` first, walk them as trees: on an n-joint chain that is exponential in n.
These walks visit each distinct node once; they work on sympy and SymEngine expressions alike.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import Any

import sympy

#: Size of a batch of expressions, counted as a tree (every occurrence of a node), above which
#: the shared nodes are named (:func:`name_shared_nodes`) before ``symengine.cse`` runs.
#: SymEngine's CSE grows much faster than the DAG on deep graphs: the mass matrix of a
#: generated 24-joint chain (6 622 distinct nodes, 1e15 as a tree) takes it 2 s, at 28 joints
#: 23 s.  The example models' graphs are far below (UR10e mass matrix: 1.3e4), so their code is
#: unchanged.
VALUE_NUMBERING_TREE_SIZE = 1_000_000


def distinct_nodes(exprs: Iterable[Any]) -> Iterator[Any]:
    """Every distinct node under ``exprs``, once each (depth first; the order is not specified)."""
    seen: set[Any] = set()
    stack = list(exprs)
    while stack:
        node = stack.pop()
        if node in seen:
            continue
        seen.add(node)
        yield node
        stack.extend(a for a in node.args if a not in seen)


def free_symbols(exprs: Iterable[sympy.Basic]) -> set[sympy.Symbol]:
    """The symbols ``exprs`` use, each distinct node visited once (``Basic.free_symbols`` walks the tree)."""
    return {node for node in distinct_nodes(exprs) if node.is_Symbol}


def post_order(roots: Iterable[Any], memo: dict, visit: Callable[[Any], Any],
               children: Callable[[Any], Sequence[Any]] = lambda node: node.args) -> None:
    """``memo[node] = visit(node)`` for every node under ``roots`` not yet in ``memo``, children first
    (iterative: deep graphs must not hit the recursion limit)."""
    for root in roots:
        stack = [root]
        while stack:
            node = stack[-1]
            if node in memo:
                stack.pop()
                continue
            pending = [a for a in children(node) if a not in memo]
            if pending:
                stack.extend(pending)
                continue
            stack.pop()
            memo[node] = visit(node)


def tree_size(exprs: Sequence[Any]) -> int:
    """Number of nodes of ``exprs`` counted at every occurrence (computed on the DAG, each node once)."""
    sizes: dict[Any, int] = {}
    post_order(exprs, sizes, lambda node: 1 + sum(sizes[a] for a in node.args))
    return sum(sizes[root] for root in exprs)


def name_shared_nodes(exprs: Sequence[Any], name: Callable[[Any], Any]) -> list[Any]:
    """Value numbering: every non-atomic node that occurs more than once in the DAG of ``exprs``
    is replaced by ``name(node)`` (called children first, so a name's value uses earlier names
    only), and ``exprs`` are rebuilt on those names.

    Linear in the number of distinct nodes.  A node's uses are the argument slots that hold it
    in distinct parents, plus one per root, so a subexpression shared anywhere in the graph is
    evaluated once.
    """
    uses: dict[Any, int] = {}
    for root in exprs:
        uses[root] = uses.get(root, 0) + 1
    for node in distinct_nodes(exprs):
        for arg in node.args:
            uses[arg] = uses.get(arg, 0) + 1
    rebuilt: dict[Any, Any] = {}

    def visit(node: Any) -> Any:
        if node.is_Atom:
            return node
        value = node.func(*[rebuilt[a] for a in node.args])
        return name(value) if uses[node] > 1 else value

    post_order(exprs, rebuilt, visit)
    return [rebuilt[root] for root in exprs]


def name_shared_nodes_of_deep_graphs(exprs: Sequence[Any], name: Callable[[Any], Any]) -> list[Any]:
    """:func:`name_shared_nodes` where ``exprs`` are deeper than :data:`VALUE_NUMBERING_TREE_SIZE`
    as a tree, ``exprs`` unchanged otherwise (the example models' code stays as it was)."""
    return name_shared_nodes(exprs, name) if tree_size(exprs) > VALUE_NUMBERING_TREE_SIZE else list(exprs)
