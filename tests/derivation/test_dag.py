"""DAG walks (symkin.expression_dag): sizes and value numbering that visit each distinct node once (issue 12)."""

from __future__ import annotations

import math

import symengine as se
import sympy

from symkin.expression_dag import free_symbols, name_shared_nodes, tree_size
from tolerances import CLOSED_FORM


def _doubling(depth: int):
    """e_0 = x, e_(k+1) = sin(e_k) * e_k + y: depth + 1 distinct Adds, a tree of 2^depth copies."""
    x, y = se.symbols("x y")
    e = x
    for _ in range(depth):
        e = se.sin(e) * e + y
    return e, x, y


def test_tree_size_counts_every_occurrence_without_walking_the_tree():
    # nodes(e_k) = 1 (Add) + 1 (y) + 1 (Mul) + 1 (sin) + 2 nodes(e_(k-1)), nodes(e_0) = 1
    e, _, _ = _doubling(60)  # 2^60 copies: only a DAG walk finishes
    expected = 1
    for _ in range(60):
        expected = 4 + 2 * expected
    assert tree_size([e]) == expected


def test_value_numbering_names_each_shared_node_once_and_keeps_the_value():
    e, x, y = _doubling(40)
    program: list[tuple[se.Symbol, se.Basic]] = []

    def name(value):
        program.append((se.Symbol(f"_v{len(program)}"), value))
        return program[-1][0]

    (reduced,) = name_shared_nodes([e], name)
    assert len(program) == 39  # e_1 .. e_39, each used twice by its parent (e_0 = x is an atom, e_40 the root)
    assert all(tree_size([value]) <= 6 for _, value in program)
    values = {x: se.Float(0.3), y: se.Float(-0.2)}
    for symbol, value in program:  # children first: every name is defined before its use
        values[symbol] = value.xreplace(values)
    got = float(reduced.xreplace(values))
    direct = 0.3
    for _ in range(40):  # the same recursion in floats, the same operations in the same order
        direct = math.sin(direct) * direct - 0.2
    assert abs(got - direct) <= 40 * CLOSED_FORM * max(1.0, abs(direct))


def test_free_symbols_of_a_deep_sympy_dag():
    x, y, z = sympy.symbols("x y z")
    e = x
    for _ in range(200):  # sympy's own free_symbols would walk 2^200 nodes
        e = sympy.Mul(e, e + y, evaluate=False)
    assert free_symbols([e, z + 1]) == {x, y, z}
