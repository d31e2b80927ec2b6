"""A formula over GF(P) compiled once into straight-line Python: the prime-field evaluation of a regressor at many
states (:mod:`symkin.parallel.prime_field`) without walking its sympy trees at each one, and the one evaluator of
that arithmetic (each leg's closure coefficients, the angles' constant sines and cosines and the entries of K at
the verification draws are programs too).

The definitions (in order) and the outputs form one DAG, each distinct subexpression a node; the program computes
the nodes in order with integer arithmetic mod P and returns the outputs' residues.  Its inputs are the leaves'
residues (symbols and function atoms: the state, the geometry, the angles' sines and cosines), the field's
constants (rationals and a rational's powers k/2, whose residues depend on the prime and on the roots chosen:
:meth:`ModularProgram.constants`; a composite number such as sqrt(3)/2 is computed from them like any node) and
two field operations: the inverse and a square root of the state (which may
not exist: the caller's exception).  The Python source holds only node numbers, small exponents and the operators
``+ * % pow``, built from the trees' structure: no name or text of a model enters it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import sympy

from symkin.errors import DerivationError


class ModularProgram:
    """The outputs of ``definitions`` and ``outputs`` mod P as one compiled function (module docstring).

    Attributes:
        leaves: the symbols and function atoms the program reads, in the order of :meth:`run`'s values.
        numbers: the constant leaves (a rational, or a rational to a power k/2), whose residues :meth:`run` takes per
            field.
    """

    def __init__(self, definitions: Sequence[tuple[sympy.Symbol, sympy.Expr]], outputs: Sequence[sympy.Expr],
                 atoms: set[sympy.Expr], where: str):
        self.where = where
        self.atoms = atoms
        self.leaves: list[sympy.Expr] = []
        self.numbers: list[sympy.Expr] = []
        self._nodes: dict[sympy.Expr, str] = {}
        self._lines: list[str] = []
        for symbol, expr in definitions:
            self._nodes[symbol] = self._node(expr)
        results = [self._node(e) for e in outputs]
        source = "def program(v, c, P, inv, root):\n    " + "\n    ".join(
            self._lines + [f"return [{', '.join(results)}]"]) + "\n"
        namespace: dict[str, Any] = {}
        exec(compile(source, f"<{where}: modular program>", "exec"), namespace)  # noqa: S102 - our own source
        self._program = namespace["program"]

    def _node(self, expr: sympy.Expr) -> str:
        """The name of ``expr``'s value in the program (its lines emitted once, operands first)."""
        if expr in self._nodes:
            return self._nodes[expr]
        if expr in self.atoms or isinstance(expr, sympy.Symbol):
            name = f"v[{len(self.leaves)}]"
            self.leaves.append(expr)
        elif expr.is_Rational or (expr.is_Pow and expr.args[0].is_Rational and expr.args[0] > 0
                                  and expr.args[1].is_Rational and expr.args[1].q == 2):
            name = f"c[{len(self.numbers)}]"
            self.numbers.append(expr)
        else:
            operation = self._operation(expr)  # its operands' lines first: they take the numbers before it
            name = f"t{len(self._lines)}"
            self._lines.append(f"{name} = {operation}")
        self._nodes[expr] = name
        return name

    def _operation(self, expr: sympy.Expr) -> str:
        """The right-hand side computing ``expr`` from its operands' nodes."""
        if expr.is_Add:
            return f"({' + '.join(self._node(a) for a in expr.args)}) % P"
        if expr.is_Mul:
            return " * ".join(self._node(a) for a in expr.args[:2]) + "".join(
                f" % P * {self._node(a)}" for a in expr.args[2:]) + " % P"
        if expr.is_Pow and expr.args[1].is_Integer:
            base, n = self._node(expr.args[0]), int(expr.args[1])
            return f"pow({base}, {n}, P)" if n >= 0 else f"pow(inv({base}), {-n}, P)"
        if expr.is_Pow and expr.args[1].is_Rational and expr.args[1].q == 2 and not expr.args[0].is_number:
            base, half = self._node(expr.args[0]), (int(expr.args[1].p) - 1) // 2  # b^(k/2) = b^((k-1)/2) sqrt(b)
            power = f"pow({base}, {half}, P)" if half >= 0 else f"pow(inv({base}), {-half}, P)"
            return f"{power} * root({base}) % P"
        raise DerivationError(f"{self.where}: the regressor holds {expr}, which the exact elimination cannot "
                              "evaluate (a transcendental constant, a root other than a square root, or a square "
                              "root of a constant other than a positive rational)")

    def constants(self, residue: Callable[[sympy.Expr], int]) -> list[int]:
        """The residues of :attr:`numbers` in one field (``residue``: the field's value of a constant)."""
        return [residue(number) for number in self.numbers]

    def run(self, values: Mapping[sympy.Expr, int], constants: Sequence[int], P: int, inverse: Callable[[int], int],
            root: Callable[[int], int]) -> list[int]:
        """The outputs' residues at ``values`` of the leaves (``constants``: :meth:`constants` of the same field)."""
        return self._program([values[leaf] for leaf in self.leaves], constants, P, inverse, root)
