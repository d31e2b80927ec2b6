"""Straight-line programs built with SymEngine and handed to the IR as sympy definitions.

The dynamics are large shared graphs: every entry of the mass matrix reuses the same link
rotations and lever arms, the Christoffel symbols reuse the derivatives of M, a solve on M
reuses its factors.  SymEngine (C++) builds and differentiates such graphs two orders of
magnitude faster than sympy and keeps the sharing (subexpressions are reference-counted
nodes).  A :class:`Program` collects the values a function needs as named assignments:

* :meth:`Program.bind` runs ``symengine.cse`` over a batch of large expressions and keeps
  the common subexpressions as assignments, returning small expressions of them;
* :meth:`Program.let` names one value (a pivot, a factor of a solve);
* :meth:`Program.to_sympy` converts the assignments that the outputs need, one small
  expression at a time, into the sympy ``definitions`` of a
  :class:`~symkin.ir.spec.FunctionSpec` (sympy stays the public expression type);
* a :class:`ProgramMap` is a column map (:class:`~symkin.ir.spec.ColumnMap`) over a program's
  values: a small program of its own applied to r columns of them.

Converting the graphs directly into sympy trees instead would repeat every shared
subexpression at every use (the UR10e Coriolis matrix grows to about a million operations
that way); the program form keeps it at a few thousand.  ``symengine.cse`` is deterministic
(it does not depend on Python's hash seed), so generated code stays byte-identical.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import symengine as se
import sympy

from symkin.expression_dag import name_shared_nodes_of_deep_graphs
from symkin.ir.spec import DEFINITION_PREFIX, MAP_BODY_PREFIX, ColumnMap, map_targets
from symkin.symengine_bridge import SympyConverter, to_symengine


def se_vector(values: Iterable[sympy.Expr]) -> list[se.Basic]:
    """Entries of a sympy vector (or any iterable of expressions) as SymEngine expressions."""
    return [to_symengine(v) for v in values]


def se_matrix(matrix: sympy.MatrixBase) -> list[list[se.Basic]]:
    """A sympy matrix as a list of rows of SymEngine expressions."""
    return [[to_symengine(matrix[i, j]) for j in range(matrix.shape[1])] for i in range(matrix.shape[0])]


class Program:
    """Named assignments ``(symbol, expression)`` in evaluation order (see the module docstring)."""

    def __init__(self) -> None:
        self.assignments: list[tuple[se.Symbol, se.Basic]] = []

    def _append(self, expr: se.Basic) -> se.Symbol:
        symbol = se.Symbol(f"{DEFINITION_PREFIX}{len(self.assignments)}")
        self.assignments.append((symbol, expr))
        return symbol

    def let(self, expr: se.Basic) -> se.Basic:
        """Name ``expr``; symbols and numbers are returned unchanged."""
        expr = se.sympify(expr)
        if expr.is_Atom:
            return expr
        return self._append(expr)

    def bind(self, exprs: Sequence[se.Basic]) -> list[se.Basic]:
        """Pull the common subexpressions of ``exprs`` into assignments; returns the reduced expressions.

        Deep graphs (over :data:`~symkin.expression_dag.VALUE_NUMBERING_TREE_SIZE`) are value-numbered
        first (:func:`~symkin.expression_dag.name_shared_nodes`), so that ``symengine.cse`` sees small
        expressions.
        """
        exprs = name_shared_nodes_of_deep_graphs([se.sympify(e) for e in exprs], self._append)
        temporaries, reduced = se.cse(exprs)
        rename: dict[se.Basic, se.Basic] = {}

        def renamed(expr: se.Basic) -> se.Basic:
            # Substitute only the symbols that occur (a large mapping costs at every call).
            used = {s: rename[s] for s in expr.free_symbols if s in rename}
            return expr.xreplace(used) if used else expr

        for symbol, expr in temporaries:
            rename[symbol] = self._append(renamed(expr))
        return [renamed(e) for e in reduced]

    def jacobian(self, outputs: Sequence[se.Basic], variables: Sequence[se.Symbol]) -> list[se.Basic]:
        """Row-major d outputs_i / d variables_j of the program's outputs (expressions of the inputs and
        assignments, e.g. what :meth:`bind` returned), by automatic differentiation of the straight-line program
        (Griewank and Walther, Evaluating Derivatives, 2nd ed., chs. 3-4), its result named in the program so that
        every later use shares it: forward mode (each assignment's gradient formed once from its operands'
        gradients, O(len(variables)) times the program) where there are fewer variables than outputs, else
        reverse mode (one adjoint sweep per output, each assignment's adjoint the sum of its uses' partials times
        their adjoints, O(len(outputs)) times the program)."""
        if len(outputs) < len(variables):
            return self._reverse_jacobian(outputs, variables)
        return self._forward_jacobian(outputs, variables)

    def _forward_jacobian(self, outputs: Sequence[se.Basic], variables: Sequence[se.Symbol]) -> list[se.Basic]:
        index = {x: k for k, x in enumerate(variables)}
        position = {symbol: k for k, (symbol, _) in enumerate(self.assignments)}
        gradients: dict[se.Basic, dict[int, se.Basic]] = {}

        def gradient(expr: se.Basic) -> dict[int, se.Basic]:
            found: dict[int, se.Basic] = {}
            for symbol in sorted(expr.free_symbols, key=lambda s: (index.get(s, -1), position.get(s, -1))):
                if symbol in index:
                    found[index[symbol]] = found.get(index[symbol], se.Integer(0)) + se.diff(expr, symbol)
                elif gradients.get(symbol):
                    partial = se.diff(expr, symbol)
                    for k, through in gradients[symbol].items():
                        found[k] = found.get(k, se.Integer(0)) + partial * through
            return {k: found[k] for k in sorted(found) if found[k] != 0}

        for symbol, expr in list(self.assignments):
            gradients[symbol] = {k: self.let(value) for k, value in gradient(expr).items()}
        rows = [gradient(se.sympify(output)) for output in outputs]
        return [row.get(k, se.Integer(0)) for row in rows for k in range(len(variables))]

    def _reverse_jacobian(self, outputs: Sequence[se.Basic], variables: Sequence[se.Symbol]) -> list[se.Basic]:
        program = list(self.assignments)  # the sweeps run over these; the adjoints they name come after
        position = {symbol: k for k, (symbol, _) in enumerate(program)}
        wanted = set(variables)
        rows = []
        for output in outputs:
            output = se.sympify(output)
            adjoint: dict[se.Basic, se.Basic] = {}

            def spread(expr: se.Basic, weight: se.Basic) -> None:
                for symbol in sorted(expr.free_symbols, key=lambda s: (position.get(s, -1), str(s))):
                    if symbol in position or symbol in wanted:
                        adjoint[symbol] = adjoint.get(symbol, se.Integer(0)) + se.diff(expr, symbol) * weight

            spread(output, se.Integer(1))
            for symbol, expr in reversed(program):
                weight = adjoint.pop(symbol, None)
                if weight is not None and weight != 0:
                    spread(expr, self.let(weight))
            rows.append([adjoint.get(x, se.Integer(0)) for x in variables])
        return [entry for row in rows for entry in row]

    def substitute(self, start: int, values: dict[se.Basic, se.Basic]) -> None:
        """Replace symbols by ``values`` in the assignments from position ``start`` on: evaluate what was built
        there at given values of those symbols (a derivative program at the accelerations a solve gave)."""
        self.assignments[start:] = [(symbol, expr.xreplace(values)) for symbol, expr in self.assignments[start:]]

    def to_sympy(self, outputs: Sequence[se.Basic], convert: SympyConverter) -> tuple[
            tuple[tuple[sympy.Symbol, sympy.Expr], ...], list[sympy.Expr]]:
        """The definitions the ``outputs`` need and the outputs, as sympy expressions.

        Args:
            outputs: SymEngine expressions of inputs and assignments.
            convert: the converter, with the sympy symbols of the inputs (model symbols
                carry assumptions such as ``real=True`` that SymEngine does not keep; they
                are restored by name).  Its memo may be shared by several programs.

        Returns:
            (definitions, outputs): assignments no output depends on are dropped.
        """
        index = {symbol: k for k, (symbol, _) in enumerate(self.assignments)}
        needed = [False] * len(self.assignments)
        stack = [s for e in outputs for s in se.sympify(e).free_symbols if s in index]
        while stack:
            k = index[stack.pop()]
            if not needed[k]:
                needed[k] = True
                stack.extend(s for s in self.assignments[k][1].free_symbols if s in index)
        definitions = tuple((convert(symbol), convert(expr))
                            for k, (symbol, expr) in enumerate(self.assignments) if needed[k])
        return definitions, [convert(se.sympify(e)) for e in outputs]


@dataclass(frozen=True)
class ProgramMap:
    """A column map in SymEngine form: ``body`` (a program over the symbols ``shared_symbols`` and ``parameters``)
    giving ``results`` for each of the ``columns``, whose values, like ``shared_values``, are a program's; the
    outputs use the results of column c as ``targets[c]`` (:func:`~symkin.ir.spec.map_targets`)."""

    shared_symbols: tuple[se.Symbol, ...]
    shared_values: tuple[se.Basic, ...]
    parameters: tuple[se.Symbol, ...]
    body: Program
    results: tuple[se.Basic, ...]
    columns: tuple[tuple[se.Basic, ...], ...]
    targets: tuple[tuple[se.Symbol, ...], ...]

    @staticmethod
    def symbols(prefix: str, count: int) -> tuple[se.Symbol, ...]:
        """``count`` body symbols ``<prefix><k>`` (:data:`~symkin.ir.spec.MAP_SHARED_PREFIX`, ...)."""
        return tuple(se.Symbol(f"{prefix}{k}") for k in range(count))

    @staticmethod
    def target_symbols(number: int, columns: int, results: int) -> tuple[tuple[se.Symbol, ...], ...]:
        """The SymEngine form of :func:`~symkin.ir.spec.map_targets`."""
        return tuple(tuple(se.Symbol(t.name) for t in column) for column in map_targets(number, columns, results))

    def values(self) -> list[se.Basic]:
        """The values it reads from the function's program, in the order of
        :meth:`~symkin.ir.spec.ColumnMap.values`."""
        return list(self.shared_values) + [c[k] for k in range(len(self.parameters)) for c in self.columns]

    def to_sympy(self, values: Sequence[sympy.Expr]) -> ColumnMap:
        """The :class:`~symkin.ir.spec.ColumnMap`, given :meth:`values` converted (in order); the body's
        assignments renamed ``_u<k>``."""
        definitions, results = self.body.to_sympy(self.results, SympyConverter({}))
        body_names = {symbol: sympy.Symbol(f"{MAP_BODY_PREFIX}{k}", real=True)
                      for k, (symbol, _) in enumerate(definitions)}
        body = tuple((body_names[symbol], expr.xreplace(body_names)) for symbol, expr in definitions)
        symbol = lambda s: sympy.Symbol(s.name, real=True)  # noqa: E731 - as the converter names a new symbol
        width, shared = len(self.parameters), len(self.shared_symbols)
        count = len(self.columns)
        columns = [values[shared + c:shared + width * count:count] for c in range(count)]
        return ColumnMap(
            shared=tuple((symbol(s), v) for s, v in zip(self.shared_symbols, values[:shared])),
            parameters=tuple(symbol(p) for p in self.parameters),
            body=body, results=tuple(r.xreplace(body_names) for r in results),
            columns=tuple(tuple(column) for column in columns),
            targets=tuple(tuple(sympy.Symbol(t.name, real=True) for t in column) for column in self.targets))


def cross(u: Sequence[se.Basic], v: Sequence[se.Basic]) -> list[se.Basic]:
    """u x v of 3-vectors."""
    return [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]


def dot(u: Sequence[se.Basic], v: Sequence[se.Basic]) -> se.Basic:
    """u . v."""
    return sum((a * b for a, b in zip(u, v)), se.Integer(0))


def mat_vec(A: Sequence[Sequence[se.Basic]], v: Sequence[se.Basic]) -> list[se.Basic]:
    """A v."""
    return [dot(row, v) for row in A]
