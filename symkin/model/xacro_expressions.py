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
methods, lambdas, comprehensions, keyword arguments) is a located :class:`XacroFail`.

Every operation is bounded by the size of its result *before* it is built (issue 59): an integer of more than
:data:`MAX_INTEGER_BITS` bits (``2**1024**1024``, ``round(1, -10**9)``), a text, list or nested value whose
:func:`weight` exceeds :data:`MAX_TEXT` (``[[0]*10**6]*10**6`` shares one list a million times: its weight, like
its text, is 10^12), a value nested deeper than :data:`MAX_NESTING`, a ``%`` format with a width or precision
beyond :data:`MAX_TEXT` - each is a located :class:`XacroFail`, and so is an expression nested too deeply for
the parser.

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
#: Bits of an integer (1233 decimal digits: far beyond any robot's number, far below Python's int-to-str limit).
MAX_INTEGER_BITS = 4096
#: Nesting of lists, tuples and mappings in a value.
MAX_NESTING = 100
#: The widths and precisions of a ``%`` format (``'%01000000000d' % 0``).
_FORMAT_NUMBERS = re.compile(r"%[-+ #0]*(\d*)(?:\.(\d+))?")


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
        except RecursionError:
            raise XacroFail("the expression nests too deeply", "split it into properties", self.node) from None
        except (ArithmeticError, TypeError, ValueError, IndexError, KeyError) as exc:
            raise XacroFail(f"the expression fails: {type(exc).__name__}: {exc}", "fix the expression", self.node) from None

    def _eval(self, e: ast.expr) -> Any:
        value = self._evaluated(e)
        if weight(value, self.node) > MAX_TEXT:
            raise XacroFail(f"a value grows beyond {MAX_TEXT} characters or items", "shorten it", self.node)
        return value

    def _evaluated(self, e: ast.expr) -> Any:
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
        if function is round and len(args) == 2 and isinstance(args[1], int) and abs(args[1]) > 400:
            raise XacroFail(f"round to {args[1]} digits", "round to at most 400 digits", self.node)
        if function is sum and len(args) == 2 and not isinstance(args[1], (int, float)):
            raise self.fail("sum with a start value other than a number")
        if function in (float, int) and args and isinstance(args[0], str) and len(args[0]) > 400:
            raise XacroFail("a number written with more than 400 characters", "write the number shorter", self.node)
        return function(*args)

    def binary(self, op: ast.operator, left: Any, right: Any) -> Any:
        if isinstance(op, ast.Pow) and isinstance(left, (int, float)) and isinstance(right, (int, float)):
            if abs(right) > MAX_EXPONENT:
                raise XacroFail(f"the exponent {right} exceeds {MAX_EXPONENT}", "use a smaller exponent", self.node)
            if isinstance(left, int) and isinstance(right, int) and right > 0 and \
                    abs(left).bit_length() * right > MAX_INTEGER_BITS:
                raise XacroFail(f"a power with more than {MAX_INTEGER_BITS} bits", "use smaller numbers", self.node)
        if isinstance(op, ast.Mult) and isinstance(left, int) and isinstance(right, int) and \
                abs(left).bit_length() + abs(right).bit_length() > MAX_INTEGER_BITS + 1:
            raise XacroFail(f"a product with more than {MAX_INTEGER_BITS} bits", "use smaller numbers", self.node)
        if isinstance(op, ast.Mod) and isinstance(left, str):
            for width, precision in _FORMAT_NUMBERS.findall(left):
                if len(width) > 6 or len(precision) > 6 or int(width or 0) + int(precision or 0) > MAX_TEXT:
                    raise XacroFail(f"a format grows beyond {MAX_TEXT} characters", "use a smaller width",
                                    self.node)
        if isinstance(op, ast.Mult) and (isinstance(left, (str, list, tuple)) or isinstance(right, (str, list, tuple))):
            count = right if isinstance(left, (str, list, tuple)) else left
            sized = left if isinstance(left, (str, list, tuple)) else right
            if isinstance(count, int) and count * len(sized) > MAX_TEXT:
                raise XacroFail(f"a repeated text grows beyond {MAX_TEXT} characters", "shorten it", self.node)
        result = _BINARY[type(op)](left, right)
        if isinstance(result, (str, list, tuple)) and len(result) > MAX_TEXT:
            raise XacroFail(f"a text grows beyond {MAX_TEXT} characters", "shorten it", self.node)
        return result


def weight(value: Any, node: Any = None) -> int:
    """A bound on the size of ``value`` as text and in memory: characters of a text, a hundredth of the bits of an
    integer, one per number, and for a list, tuple or mapping one plus its items' weights, a shared item counted at
    every use (its text repeats it), computed once per object.

    Raises:
        XacroFail: an integer beyond :data:`MAX_INTEGER_BITS` bits, or a value nested deeper than
            :data:`MAX_NESTING` (iterative: no recursion, however deep the value).
    """
    known: dict[int, int] = {}
    stack: list[tuple[Any, int, bool]] = [(value, 0, False)]
    while stack:
        item, depth, expanded = stack.pop()
        if isinstance(item, (list, tuple, dict)):
            if id(item) in known:
                continue
            if depth > MAX_NESTING:
                raise XacroFail(f"a value nests deeper than {MAX_NESTING} levels", "flatten it", node)
            children = [*item.keys(), *item.values()] if isinstance(item, dict) else item
            if not expanded:
                stack.append((item, depth, True))
                stack.extend((child, depth + 1, False) for child in children)
                continue
            known[id(item)] = min(1 + sum(_weight_of(child, known) for child in children), MAX_TEXT + 1)
        elif isinstance(item, int) and not isinstance(item, bool) and item.bit_length() > MAX_INTEGER_BITS:
            raise XacroFail(f"an integer of more than {MAX_INTEGER_BITS} bits", "use smaller numbers", node)
    return _weight_of(value, known)


def _weight_of(item: Any, known: dict[int, int]) -> int:
    if isinstance(item, (list, tuple, dict)):
        return known[id(item)]
    if isinstance(item, str):
        return len(item)
    if isinstance(item, int) and not isinstance(item, bool):
        return 1 + item.bit_length() // 100
    return 1


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
