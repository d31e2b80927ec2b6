"""Typed, located access to a model document, and the value forms every section shares.

:class:`Reader` reads values from the composed YAML document and records every problem with
its place (file, line, key path) and its fix instead of raising; the shared forms: exact
expressions, 3-vectors, unit axes, frames (``xyz``/``rpy``), position limits.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Iterable
from typing import Any

import sympy

from symkin.errors import Problem
from symkin.model.expressions import ExpressionError, parse_expression
from symkin.model.names import name_problem
from symkin.model.schema import Op, Rotation, Translation, Vec3
from symkin.model.units import ANGLE, ANGULAR_SPEED, FORCE, LENGTH, SPEED, TORQUE
from symkin.model.yaml_source import Document, KeyPath, shorten

ZERO = sympy.Integer(0)
ONE = sympy.Integer(1)
X_AXIS: Vec3 = (ONE, ZERO, ZERO)
Y_AXIS: Vec3 = (ZERO, ONE, ZERO)
Z_AXIS: Vec3 = (ZERO, ZERO, ONE)


def describe(value: Any) -> str:
    if value is None:
        return "nothing"
    if isinstance(value, bool):
        return f"the boolean {value}"
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return f"a list of {len(value)}"
    return f"'{shorten(value)}'"


class Reader:
    """Typed access to document values that records located problems instead of raising."""

    def __init__(self, doc: Document):
        self.doc = doc
        self.problems: list[Problem] = []
        #: Names usable in expressions: parameter symbols and inlined derived parameters.
        self.names: dict[str, sympy.Expr] = {}
        #: Default value of every free parameter symbol (for physical plausibility checks).
        self.defaults: dict[sympy.Symbol, sympy.Expr] = {}
        #: Parameters whose own definition failed: uses of them are not reported again.
        self.invalid: set[str] = set()
        #: Links of joints whose definition failed: bodies on them are not reported as unknown.
        self.invalid_links: set[str] = set()
        #: joints declared but not built (their mistake is reported): sections naming them are not checked again
        self.invalid_joints: set[str] = set()
        #: Accept non-physical inertias with a note instead of refusing them (``allow_nonphysical:``).
        self.allow_nonphysical = False
        #: A serial model's non-physical inertias block only the outputs that use them (Model.nonphysical): the
        #: problems are kept here instead of failing the reading.
        self.defer_nonphysical = False
        self.nonphysical: list[Problem] = []
        #: Located notes on what the reading decided (Model.notes).
        self.notes: list[str] = []
        #: Every name the file gives (a parameter, joint, link, leg...) -> where, the first time (Model.declared_names).
        self.declared: dict[str, KeyPath] = {}
        #: The dimension of each parameter whose ``unit:`` names one (symkin.model.units), for the checks of
        #: :meth:`expr` where a value has a dimension (a length used as an angle is refused).
        self.dimensions: dict[sympy.Symbol, tuple[str, str]] = {}
        #: Names used but never declared: reported at their first use only.
        self.undeclared: set[str] = set()

    def note(self, path: KeyPath, message: str) -> None:
        """Record ``message`` about the element at ``path``, located by line and key but not by the file's
        path (notes go into the manifest, which is the same wherever the model file lies)."""
        problem = self.doc.problem(path, message, "")
        where = f"line {problem.line}, " if problem.line is not None else ""
        self.notes.append(f"{where}at '{problem.key}': {message}" if problem.key else f"{where}{message}")

    def fail(self, path: KeyPath, message: str, fix: str) -> None:
        """Record a problem once: a mistake in a chain shared by several legs is read once per leg, but is one
        mistake at one line."""
        problem = self.doc.problem(path, message, fix)
        if problem not in self.problems:
            self.problems.append(problem)

    def reported_under(self, key: str) -> bool:
        """Whether a problem was recorded at ``key`` or inside it (what follows from it is then not reported)."""
        return any(p.key == key or p.key.startswith(key + ".") or p.key.startswith(key + "[") for p in self.problems)

    def mapping(self, path: KeyPath, value: Any, required: Iterable[str] = (),
                optional: Iterable[str] = ()) -> dict[str, Any] | None:
        """``value`` as a mapping with only known keys and every required key."""
        required, optional = tuple(required), tuple(optional)
        if not isinstance(value, dict):
            self.fail(path, f"expected a mapping, got {describe(value)}",
                      f"write a mapping with the keys {', '.join(required + optional)}")
            return None
        allowed = tuple(dict.fromkeys(required + optional))
        for key in value:
            if key not in allowed:
                close = difflib.get_close_matches(key, allowed, n=1)
                hint = f"did you mean '{close[0]}'? " if close else ""
                self.fail(path + (key,), f"unknown key '{shorten(key)}'", f"{hint}allowed keys here: {', '.join(allowed)}")
        for key in required:
            if key not in value:
                self.fail(path, f"missing required key '{key}'", f"add '{key}:'")
        return value

    def sequence(self, path: KeyPath, value: Any, length: int | None = None, what: str = "items") -> list[Any] | None:
        if not isinstance(value, list):
            self.fail(path, f"expected a list of {what}, got {describe(value)}", f"write a YAML list of {what}")
            return None
        if length is not None and len(value) != length:
            self.fail(path, f"expected {length} {what}, got {len(value)}", f"write exactly {length} {what}")
            return None
        return value

    def string(self, path: KeyPath, value: Any) -> str | None:
        if not isinstance(value, str):
            self.fail(path, f"expected text, got {describe(value)}", "write text (quote it if needed)")
            return None
        return value

    def name(self, path: KeyPath, value: Any) -> str | None:
        problem = name_problem(value)
        if problem:
            self.fail(path, problem, "rename it, e.g. 'theta1', 'l1' or 'link2'")
            return None
        self.declared.setdefault(value, path)
        return value

    def expr(self, path: KeyPath, value: Any, names: dict[str, sympy.Expr] | None = None,
             dimension: str | None = None, bare: bool = False) -> sympy.Expr | None:
        """Parse the expression at ``path``; numbers are read from their raw text (exact decimals).  With a
        ``dimension``, a term that is a number times a parameter of another dimension is refused; with ``bare``, only
        a parameter standing alone (+- itself: where a number may carry a dimension, as the 0.04^2 of
        m * 0.04^2 / 12 for an inertia)."""
        parsed = self._parsed(path, value, names)
        if parsed is not None and dimension is not None:
            for term in sympy.Add.make_args(parsed):
                coefficient, symbol = term.as_coeff_Mul()
                if bare and abs(coefficient) != 1:
                    continue
                if symbol in self.dimensions and self.dimensions[symbol][0] != dimension:
                    found, unit = self.dimensions[symbol]
                    self.fail(path, f"'{symbol}' is {'an' if found[0] in 'aeiou' else 'a'} {found} (unit: {unit}) "
                              f"but is used here as {'an' if dimension[0] in 'aeiou' else 'a'} {dimension}",
                              f"use a parameter in a unit of {dimension}, or fix the unit of '{symbol}'")
                    return None
        return parsed

    def _parsed(self, path: KeyPath, value: Any, names: dict[str, sympy.Expr] | None) -> sympy.Expr | None:
        text = value
        if isinstance(value, (int, float)) and not isinstance(value, bool) and not (
                isinstance(value, float) and not math.isfinite(value)):
            text = self.doc.raw.get(path, value)  # .inf and .nan go to the parser as floats
        try:
            return parse_expression(text, self.names if names is None else names)
        except ExpressionError as err:
            if err.undefined_name is not None and err.undefined_name in self.undeclared:
                return None  # one missing parameter is one mistake: reported at its first use
            if err.undefined_name is not None and names is None and err.undefined_name not in self.invalid:
                self.undeclared.add(err.undefined_name)
            if err.undefined_name is not None and err.undefined_name in self.invalid:
                return None  # the parameter's own definition is already reported
            problem = self.doc.problem(path, f"invalid expression '{shorten(text)}': {err}", err.fix)
            if problem.column is not None and isinstance(text, str):
                problem = Problem(problem.file, problem.line, problem.column + err.column, problem.key,
                                  problem.message, problem.fix)
            self.problems.append(problem)
            return None

    def vector3(self, path: KeyPath, value: Any, dimension: str | None = None) -> Vec3 | None:
        """Three expressions (of ``dimension``, where given: :meth:`expr`)."""
        items = self.sequence(path, value, 3, "components")
        if items is None:
            return None
        parts = [self.expr(path + (i,), v, dimension=dimension) for i, v in enumerate(items)]
        if any(p is None for p in parts):
            return None
        return (parts[0], parts[1], parts[2])

    def default_value(self, expr: sympy.Expr) -> float | None:
        """Numeric value of ``expr`` at the parameters' defaults, or None if not numeric."""
        value = sympy.sympify(expr).xreplace(self.defaults)
        if value.free_symbols:
            return None
        try:
            return float(value)
        except TypeError:
            return None


def raw_text(r: Reader, path: KeyPath, value: Any) -> Any:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return r.doc.raw.get(path, value)
    return value


def ops(*ops: Op) -> tuple[Op, ...]:
    """Drop identity operations (zero angle, zero translation)."""
    kept = []
    for op in ops:
        if isinstance(op, Rotation) and op.angle == 0:
            continue
        if isinstance(op, Translation) and all(c == 0 for c in op.vector):
            continue
        kept.append(op)
    return tuple(kept)


def unit_axis(r: Reader, path: KeyPath, value: Any) -> Vec3 | None:
    vec = r.vector3(path, value)
    if vec is None:
        return None
    if any(c.free_symbols for c in vec):
        r.fail(path, "a joint axis must be made of numbers", "write the axis as numbers, e.g. [0, 0, 1]")
        return None
    norm = sympy.sqrt(sum(c**2 for c in vec))
    if norm == 0:
        r.fail(path, "the joint axis is the zero vector", "give the axis direction, e.g. [0, 0, 1]")
        return None
    return (vec[0] / norm, vec[1] / norm, vec[2] / norm)


def frame_ops(r: Reader, path: KeyPath, value: Any) -> tuple[Op, ...] | None:
    """A fixed frame {xyz: [...], rpy: [...]}: Trans(xyz) Rz(yaw) Ry(pitch) Rx(roll) (URDF convention).

    A list of such frames is their composition, applied in order (the fixed joints between
    two moving joints of a URDF chain).
    """
    if isinstance(value, list):
        parts = [frame_ops(r, path + (i,), item) for i, item in enumerate(value)]
        known = [part for part in parts if part is not None]
        return None if len(known) != len(parts) else tuple(op for part in known for op in part)
    section = r.mapping(path, value, optional=("xyz", "rpy"))
    if section is None:
        return None
    xyz = r.vector3(path + ("xyz",), section["xyz"], LENGTH) if "xyz" in section else (ZERO, ZERO, ZERO)
    rpy = r.vector3(path + ("rpy",), section["rpy"], ANGLE) if "rpy" in section else (ZERO, ZERO, ZERO)
    if xyz is None or rpy is None:
        return None
    roll, pitch, yaw = rpy
    return ops(Translation(xyz), Rotation(Z_AXIS, yaw), Rotation(Y_AXIS, pitch), Rotation(X_AXIS, roll))


def position_limits(r: Reader, path: KeyPath, value: Any, revolute: bool | None = None
                    ) -> tuple[sympy.Expr, sympy.Expr] | None:
    """Position limits ``[lower, upper]`` (expressions, lower < upper at the default values), or None; angles of a
    ``revolute`` motion, lengths of a sliding one (None: unchecked)."""
    bounds = r.sequence(path, value, 2, "bounds [lower, upper]")
    if bounds is None:
        return None
    dimension = None if revolute is None else ANGLE if revolute else LENGTH
    lower = r.expr(path + (0,), bounds[0], dimension=dimension)
    upper = r.expr(path + (1,), bounds[1], dimension=dimension)
    if lower is None or upper is None:
        return None
    lo, hi = r.default_value(lower), r.default_value(upper)
    if lo is not None and hi is not None and not lo < hi:
        r.fail(path, f"the lower limit {lower} is not below the upper limit {upper}",
               "write the limits as [lower, upper]")
        return None
    return lower, upper


def positive_limit(r: Reader, path: KeyPath, value: Any, revolute: bool | None = None) -> sympy.Expr | None:
    """A velocity or effort limit (``path`` ends in velocity_limit or effort_limit): an expression whose default
    value is positive (None, reported, if not), of the dimension the joint's motion gives (None: unchecked)."""
    kinds = {"velocity_limit": (ANGULAR_SPEED, SPEED), "effort_limit": (TORQUE, FORCE)}
    name = str(path[-1]).replace("actuator_", "")
    dimension = None if revolute is None or name not in kinds else kinds[name][0 if revolute else 1]
    expr = r.expr(path, value, dimension=dimension)
    numeric = r.default_value(expr) if expr is not None else None
    if expr is not None and numeric is not None and numeric <= 0:
        r.fail(path, f"{path[-1]} must be positive, got {expr}", "write a positive number")
        return None
    return expr
