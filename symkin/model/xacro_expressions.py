"""xacro's expression language, evaluated without ``eval``: the ``${...}`` and ``$(...)`` of a text, and
the values of properties (issue 29).

The reference xacro evaluates ``${...}`` with Python's ``eval`` and exposes ``type`` and ``vars``,
through which any expression reaches any Python object. Here an expression is parsed with
:func:`ast.parse` (which runs nothing) and evaluated node by node over a closed set of node kinds:
numbers, strings, booleans, names of properties, arithmetic (``+ - * / // % **``), comparisons,
``and or not``, ``a if c else b``, subscripts of lists, tuples, dicts and strings, list/tuple/dict
literals, attributes of namespaces (``math.pi``, an included file's ``ns.name``, loaded YAML) and
calls with positional arguments of the functions of :data:`FUNCTIONS` (the math module's and a
few builtins such as ``min``, ``str``, ``radians``). Anything else (attributes of other values,
methods, lambdas, comprehensions, keyword arguments) is a located :class:`XacroFail`, as are
results beyond :data:`MAX_TEXT` characters and exponents beyond :data:`MAX_EXPONENT`.

Texts follow xacro 2: ``$${`` and ``$$(`` are literal; a text that is one ``${...}`` keeps its
value's type, any other is the concatenation of the pieces' texts (Python's ``str``, as xacro
prints numbers); a property's text becomes a number or boolean when it reads as one
(:func:`literal`).
"""

from __future__ import annotations

import ast
import math
import operator
import re
from collections.abc import Callable, Iterator
from typing import Any, Protocol, runtime_checkable

#: Characters of one evaluated text, and the largest exponent.
MAX_TEXT = 1_000_000
MAX_EXPONENT = 1024


class XacroFail(Exception):
    """A problem at one node: turned into a located :class:`Problem`."""

    def __init__(self, message: str, fix: str, node: Any = None):
        super().__init__(message)
        self.message, self.fix, self.node = message, fix, node



class Namespace(dict[Any, Any]):
    """A dict whose keys are also attributes (``math.pi``, ``ns.property``, loaded YAML)."""


#: The functions and constants an expression may name (xacro exposes the math module and these builtins).
FUNCTIONS: dict[str, Any] = {
    **{name: getattr(math, name) for name in (
        "acos", "acosh", "asin", "asinh", "atan", "atan2", "atanh", "ceil", "copysign", "cos", "cosh", "degrees",
        "exp", "fabs", "floor", "fmod", "hypot", "isclose", "isfinite", "isinf", "isnan", "log", "log10", "log2",
        "radians", "sin", "sinh", "sqrt", "tan", "tanh", "trunc")},
    "pi": math.pi, "e": math.e, "tau": math.tau, "inf": math.inf, "nan": math.nan,
    "abs": abs, "bool": bool, "float": float, "int": int, "len": len, "max": max, "min": min, "round": round,
    "str": str, "sum": sum, "list": list, "tuple": tuple, "sorted": sorted, "any": any, "all": all,
    "True": True, "False": False, "None": None,
}
FUNCTIONS["math"] = Namespace({k: v for k, v in FUNCTIONS.items() if k in dir(math)})

_BINARY: dict[type, Callable[[Any, Any], Any]] = {
    ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
    ast.FloorDiv: operator.floordiv, ast.Mod: operator.mod, ast.Pow: operator.pow}
_COMPARE: dict[type, Callable[[Any, Any], Any]] = {
    ast.Eq: operator.eq, ast.NotEq: operator.ne, ast.Lt: operator.lt, ast.LtE: operator.le, ast.Gt: operator.gt,
    ast.GtE: operator.ge, ast.In: lambda a, b: a in b, ast.NotIn: lambda a, b: a not in b,
    ast.Is: operator.is_, ast.IsNot: operator.is_not}
_UNARY: dict[type, Callable[[Any], Any]] = {ast.UAdd: operator.pos, ast.USub: operator.neg, ast.Not: operator.not_}


@runtime_checkable
class Scoped(Protocol):
    """A value whose attributes are properties (the ``ns`` of ``<xacro:include ns=...>``)."""

    def attribute(self, name: str, node: Any) -> Any:
        """The property ``name``, or a :class:`XacroFail` at ``node``."""


class Evaluator:
    """Evaluate one parsed expression over the closed set of node kinds of the module docstring.

    Args:
        lookup: the value of a property name, or None if no property has that name.
        load_yaml: the data of the YAML file named by ``load_yaml(NAME)``.
        node: where the expression was written (passed on in every :class:`XacroFail`).
    """

    def __init__(self, lookup: Callable[[str], Any], load_yaml: Callable[[Any], Any], node: Any):
        self.lookup, self.load_yaml, self.node = lookup, load_yaml, node

    def fail(self, what: str) -> XacroFail:
        return XacroFail(f"{what} is not allowed in a xacro expression here", "use arithmetic, comparisons, property "
                     "names and the math functions (symkin does not run Python from model files)", self.node)

    def eval(self, e: ast.expr) -> Any:
        try:
            return self._eval(e)
        except XacroFail:
            raise
        except (ArithmeticError, TypeError, ValueError, IndexError, KeyError) as exc:
            raise XacroFail(f"the expression fails: {type(exc).__name__}: {exc}", "fix the expression", self.node) from None

    def _eval(self, e: ast.expr) -> Any:
        if isinstance(e, ast.Constant):
            if isinstance(e.value, (int, float, str, bool)) or e.value is None:
                return e.value
            raise self.fail(f"the constant {type(e.value).__name__}")
        if isinstance(e, ast.Name):
            return self.name(e.id)
        if isinstance(e, ast.BinOp) and type(e.op) in _BINARY:
            left, right = self._eval(e.left), self._eval(e.right)
            return self.binary(e.op, left, right)
        if isinstance(e, ast.UnaryOp) and type(e.op) in _UNARY:
            return _UNARY[type(e.op)](self._eval(e.operand))
        if isinstance(e, ast.BoolOp):
            value = self._eval(e.values[0])
            for operand in e.values[1:]:
                if isinstance(e.op, ast.And) and not value or isinstance(e.op, ast.Or) and value:
                    return value
                value = self._eval(operand)
            return value
        if isinstance(e, ast.Compare) and all(type(op) in _COMPARE for op in e.ops):
            left = self._eval(e.left)
            for op, comparator in zip(e.ops, e.comparators):
                right = self._eval(comparator)
                if not _COMPARE[type(op)](left, right):
                    return False
                left = right
            return True
        if isinstance(e, ast.IfExp):
            return self._eval(e.body) if self._eval(e.test) else self._eval(e.orelse)
        if isinstance(e, (ast.List, ast.Tuple)):
            items = [self._eval(item) for item in e.elts]
            return items if isinstance(e, ast.List) else tuple(items)
        if isinstance(e, ast.Dict) and all(k is not None for k in e.keys):
            return Namespace({self._eval(k): self._eval(v) for k, v in zip(e.keys, e.values) if k is not None})
        if isinstance(e, ast.Subscript):
            container, index = self._eval(e.value), self._eval(e.slice)
            if not isinstance(container, (list, tuple, dict, str)) or isinstance(index, slice):
                raise self.fail("this subscript")
            return container[index]
        if isinstance(e, ast.Attribute):
            return self.attribute(self._eval(e.value), e.attr)
        if isinstance(e, ast.Call) and not e.keywords and not any(isinstance(a, ast.Starred) for a in e.args):
            return self.call(e)
        raise self.fail(f"'{ast.unparse(e)}' ({type(e).__name__})")

    def name(self, name: str) -> Any:
        value = self.lookup(name)
        if value is not None:
            return value
        if name in FUNCTIONS:
            return FUNCTIONS[name]
        if name == "xacro":
            return Namespace(load_yaml=LOAD_YAML)
        raise XacroFail(f"'{name}' is not a defined property", f"define <xacro:property name=\"{name}\" value=\"...\"/> "
                                                           "before its use, or pass it as a macro parameter", self.node)

    def attribute(self, value: Any, name: str) -> Any:
        if isinstance(value, Scoped):
            return value.attribute(name, self.node)
        if isinstance(value, Namespace) and name in value:
            return value[name]
        raise self.fail(f"the attribute '.{name}'")

    def call(self, e: ast.Call) -> Any:
        function = self._eval(e.func)
        args = [self._eval(a) for a in e.args]
        if function is LOAD_YAML:
            if len(args) != 1:
                raise self.fail("load_yaml with other than one argument")
            return self.load_yaml(args[0])
        if not any(function is f for f in FUNCTIONS.values() if callable(f)):
            raise self.fail("calling this value")
        if function in (list, tuple, sorted, sum, any, all, max, min) and any(isinstance(a, str) and len(a) > 10_000
                                                                              for a in args):
            raise self.fail("this call on a long text")
        return function(*args)

    def binary(self, op: ast.operator, left: Any, right: Any) -> Any:
        if isinstance(op, ast.Pow) and isinstance(left, (int, float)) and isinstance(right, (int, float)):
            if abs(right) > MAX_EXPONENT:
                raise XacroFail(f"the exponent {right} exceeds {MAX_EXPONENT}", "use a smaller exponent", self.node)
        if isinstance(op, ast.Mult) and (isinstance(left, (str, list, tuple)) or isinstance(right, (str, list, tuple))):
            count = right if isinstance(left, (str, list, tuple)) else left
            sized = left if isinstance(left, (str, list, tuple)) else right
            if isinstance(count, int) and count * len(sized) > MAX_TEXT:
                raise XacroFail(f"a repeated text grows beyond {MAX_TEXT} characters", "shorten it", self.node)
        result = _BINARY[type(op)](left, right)
        if isinstance(result, (str, list, tuple)) and len(result) > MAX_TEXT:
            raise XacroFail(f"a text grows beyond {MAX_TEXT} characters", "shorten it", self.node)
        return result


def _load_yaml_marker() -> None:  # pragma: no cover - a marker, never called
    """``xacro.load_yaml(FILE)``: handled by the evaluator (reads a .yaml file with the safe loader)."""


LOAD_YAML = _load_yaml_marker
FUNCTIONS["load_yaml"] = LOAD_YAML


def namespaced(value: Any) -> Any:
    """Loaded YAML data with its mappings as :class:`Namespace` (their keys are attributes, as in xacro)."""
    if isinstance(value, dict):
        return Namespace({k: namespaced(v) for k, v in value.items()})
    if isinstance(value, list):
        return [namespaced(v) for v in value]
    return value


def pieces(text: str, node: Any) -> Iterator[tuple[str, str]]:
    """(kind, body) of ``text``: ``text`` literals, ``${`` expressions, ``$(`` substitutions."""
    i, start, n = 0, 0, len(text)
    literal: list[str] = []
    while i < n:
        if text.startswith("$${", i) or text.startswith("$$(", i):
            literal.append(text[start:i] + text[i + 1:i + 3])
            i += 3
            start = i
            continue
        if text.startswith("${", i) or text.startswith("$(", i):
            opener, closer = text[i + 1], "}" if text[i + 1] == "{" else ")"
            depth, j, quote = 1, i + 2, ""
            while j < n and depth:
                c = text[j]
                if quote:
                    quote = "" if c == quote else quote
                elif c in "'\"":
                    quote = c
                elif c == opener:
                    depth += 1
                elif c == closer:
                    depth -= 1
                j += 1
            if depth:
                raise XacroFail(f"'{text[i:i + 40]}' has no closing '{closer}'", f"close it with '{closer}'", node)
            literal.append(text[start:i])
            if "".join(literal):
                yield "text", "".join(literal)
            literal = []
            yield "$" + opener, text[i + 2:j - 1]
            i = start = j
            continue
        i += 1
    literal.append(text[start:])
    if "".join(literal) or not text:
        yield "text", "".join(literal)




def literal(value: Any) -> Any:
    """A property's text as xacro reads it: quoted text unquoted, numbers and true/false typed."""
    if not isinstance(value, str):
        return value
    if len(value) >= 2 and value[0] == value[-1] == "'":
        return value[1:-1]
    if "_" in value:
        return value
    for convert in (int, float):
        try:
            return convert(value)
        except ValueError:
            pass
    return {"true": True, "True": True, "false": False, "False": False}.get(value, value)


def boolean(value: Any, node: Any) -> bool:
    if isinstance(value, str):
        if value in ("true", "True"):
            return True
        if value in ("false", "False"):
            return False
        try:
            return bool(int(value))
        except ValueError:
            try:
                return bool(float(value))
            except ValueError:
                pass
        raise XacroFail(f"the condition '{value}' is neither true nor false", "write true, false, 1 or 0", node)
    return bool(value)


def as_text(value: Any) -> str:
    """A value as xacro writes it into the text (Python's str)."""
    return str(value)
