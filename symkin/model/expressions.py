"""A small whitelisted parser for the expressions allowed in model files.

Model files write values such as ``0.1807``, ``l1/2``, ``-pi/2``, ``deg(90)`` or
``sqrt(3)*r/2``.  They are parsed here by a recursive-descent parser into sympy
expressions; nothing is ever passed to ``eval`` or ``sympify``.  The grammar::

    expr   := term (('+' | '-') term)*
    term   := unary (('*' | '/') unary)*
    unary  := ('+' | '-') unary | power
    power  := atom (('**' | '^') unary)?          # right associative: 2**3**2 = 2**9
    atom   := NUMBER | NAME | NAME '(' expr (',' expr)* ')' | '(' expr ')'

Numbers are read as exact decimals (``0.1807`` -> 1807/10000), so symbolic results stay
exact; ``pi`` is the only constant; functions come from :data:`FUNCTIONS`.  Names must be
in the ``names`` mapping handed to :func:`parse_expression` (the model's parameters).

Resource guards: the text length, the nesting depth, the number of digits of a literal
and the size of exponents are bounded, so that ``9**9**9`` or ``1e999999`` fail with a
clear message instead of hanging the derivation.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import sympy

MAX_LENGTH = 2000
MAX_DEPTH = 50
MAX_LITERAL_DIGITS = 40
MAX_DECIMAL_EXPONENT = 300
MAX_POWER = 64
MAX_MAGNITUDE = sympy.Integer(10) ** 300


def _degrees(x: sympy.Expr) -> sympy.Expr:
    """deg(x): x degrees in radians."""
    return x * sympy.pi / 180


#: Functions allowed in model expressions: name -> (arity, sympy constructor).
FUNCTIONS: dict[str, tuple[int, Callable[..., sympy.Expr]]] = {
    "sin": (1, sympy.sin),
    "cos": (1, sympy.cos),
    "tan": (1, sympy.tan),
    "asin": (1, sympy.asin),
    "acos": (1, sympy.acos),
    "atan": (1, sympy.atan),
    "atan2": (2, sympy.atan2),
    "sqrt": (1, sympy.sqrt),
    "exp": (1, sympy.exp),
    "log": (1, sympy.log),
    "abs": (1, sympy.Abs),
    "deg": (1, _degrees),
}

CONSTANTS: dict[str, sympy.Expr] = {"pi": sympy.pi}

#: Names a model may not use for its own symbols (they mean something in expressions).
RESERVED_NAMES = frozenset(FUNCTIONS) | frozenset(CONSTANTS)


class ExpressionError(ValueError):
    """The text is not a valid model expression.

    Attributes:
        column: 0-based offset in the expression text where the problem is.
        fix: a suggestion for the user.
    """

    def __init__(self, message: str, column: int, fix: str, undefined_name: str | None = None):
        super().__init__(message)
        self.column = column
        self.fix = fix
        self.undefined_name = undefined_name


@dataclass(frozen=True)
class _Token:
    kind: str  # NUMBER NAME OP END
    text: str
    pos: int


_TOKEN_RE = re.compile(
    r"\s*(?:(?P<NUMBER>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)"
    r"|(?P<NAME>[A-Za-z_][A-Za-z0-9_]*)"
    r"|(?P<OP>\*\*|[-+*/^(),]))"
)


def _tokenize(text: str) -> list[_Token]:
    tokens = []
    pos = 0
    while pos < len(text):
        if text[pos:].strip() == "":
            break
        match = _TOKEN_RE.match(text, pos)
        if not match or match.end() == pos:
            bad = len(text) - len(text[pos:].lstrip())
            raise ExpressionError(f"unexpected character '{text[bad]}'", bad,
                                  "expressions may use numbers, parameter names, + - * / ** ( ) and "
                                  f"the functions {', '.join(sorted(FUNCTIONS))}")
        kind = match.lastgroup
        assert kind is not None
        tokens.append(_Token(kind, match.group(kind), match.start(kind)))
        pos = match.end()
    tokens.append(_Token("END", "", len(text)))
    return tokens


class _Parser:
    def __init__(self, text: str, names: Mapping[str, sympy.Expr]):
        self.text = text
        self.names = names
        self.tokens = _tokenize(text)
        self.i = 0
        self.depth = 0

    @property
    def tok(self) -> _Token:
        return self.tokens[self.i]

    def _take(self) -> _Token:
        tok = self.tokens[self.i]
        self.i += 1
        return tok

    def _expect(self, text: str) -> None:
        if self.tok.text != text:
            found = self.tok.text or "end of expression"
            raise ExpressionError(f"expected '{text}' but found '{found}'", self.tok.pos,
                                  "check the parentheses and commas")
        self.i += 1

    def parse(self) -> sympy.Expr:
        value = self.expr()
        if self.tok.kind != "END":
            raise ExpressionError(f"unexpected '{self.tok.text}'", self.tok.pos,
                                  "an operator is probably missing before it")
        return value

    def _nested(self) -> None:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise ExpressionError(f"expression nested deeper than {MAX_DEPTH} levels", self.tok.pos,
                                  "simplify the expression")

    def expr(self) -> sympy.Expr:
        value = self.term()
        while self.tok.text in ("+", "-"):
            op = self._take().text
            rhs = self.term()
            value = value + rhs if op == "+" else value - rhs
        return value

    def term(self) -> sympy.Expr:
        value = self.unary()
        while self.tok.text in ("*", "/"):
            op = self._take()
            rhs = self.unary()
            if op.text == "/":
                if rhs.is_zero:
                    raise ExpressionError("division by zero", op.pos, "fix the denominator")
                value = value / rhs
            else:
                value = value * rhs
            _check_finite(value, op.pos)  # 1e300*1e300*1e300 is exact here, but no double holds it
        return value

    def unary(self) -> sympy.Expr:
        if self.tok.text in ("+", "-"):
            op = self._take().text
            self._nested()
            value = self.unary()
            self.depth -= 1
            return -value if op == "-" else value
        return self.power()

    def power(self) -> sympy.Expr:
        base = self.atom()
        if self.tok.text in ("**", "^"):
            op = self._take()
            self._nested()
            exponent = self.unary()
            self.depth -= 1
            return _checked_power(base, exponent, op.pos)
        return base

    def atom(self) -> sympy.Expr:
        tok = self._take()
        if tok.kind == "NUMBER":
            return _number(tok)
        if tok.text == "(":
            self._nested()
            value = self.expr()
            self._expect(")")
            self.depth -= 1
            return value
        if tok.kind == "NAME":
            if self.tok.text == "(":
                return self._call(tok)
            return self._name(tok)
        found = tok.text or "end of expression"
        raise ExpressionError(f"expected a number, a name or '(' but found '{found}'", tok.pos,
                              "complete the expression")

    def _call(self, name: _Token) -> sympy.Expr:
        if name.text not in FUNCTIONS:
            close = difflib.get_close_matches(name.text, FUNCTIONS, n=1)
            hint = f"did you mean '{close[0]}'? " if close else ""
            raise ExpressionError(f"unknown function '{name.text}'", name.pos,
                                  f"{hint}allowed functions: {', '.join(sorted(FUNCTIONS))}")
        arity, build = FUNCTIONS[name.text]
        self._expect("(")
        self._nested()
        args = [self.expr()]
        while self.tok.text == ",":
            self.i += 1
            args.append(self.expr())
        self._expect(")")
        self.depth -= 1
        if len(args) != arity:
            raise ExpressionError(f"{name.text}() takes {arity} argument(s), got {len(args)}", name.pos,
                                  f"call {name.text} with {arity} argument(s)")
        value = build(*args)
        _check_finite(value, name.pos)
        return value

    def _name(self, tok: _Token) -> sympy.Expr:
        if tok.text in CONSTANTS:
            return CONSTANTS[tok.text]
        if tok.text in self.names:
            return self.names[tok.text]
        if tok.text in FUNCTIONS:
            raise ExpressionError(f"'{tok.text}' is a function", tok.pos, f"call it: {tok.text}(...)")
        close = difflib.get_close_matches(tok.text, list(self.names) + list(CONSTANTS), n=1)
        hint = f"did you mean '{close[0]}'? Otherwise " if close else ""
        raise ExpressionError(f"undefined name '{tok.text}'", tok.pos,
                              f"{hint}declare '{tok.text}' under 'parameters:'", undefined_name=tok.text)


def _number(tok: _Token) -> sympy.Rational:
    """An exact rational from a decimal literal, within the size guards."""
    mantissa, _, exponent = tok.text.lower().partition("e")
    digits = mantissa.replace(".", "").lstrip("0")
    if len(digits) > MAX_LITERAL_DIGITS:
        raise ExpressionError(f"number literal with more than {MAX_LITERAL_DIGITS} digits", tok.pos,
                              "shorten the number")
    if exponent and abs(int(exponent)) > MAX_DECIMAL_EXPONENT:
        raise ExpressionError(f"decimal exponent {exponent} is out of range (|e| <= {MAX_DECIMAL_EXPONENT})",
                              tok.pos, "use a number of a physical size")
    return sympy.Rational(tok.text)


def _checked_power(base: sympy.Expr, exponent: sympy.Expr, pos: int) -> sympy.Expr:
    """base**exponent, allowing only small constant rational exponents."""
    if not exponent.is_Rational:
        raise ExpressionError("exponents must be constant numbers", pos,
                              "write the exponent as a number such as 2 or 1/2")
    exp_q = sympy.Rational(exponent)
    if abs(exp_q.p) > MAX_POWER or exp_q.q > MAX_POWER:
        raise ExpressionError(f"exponent {exp_q} is too large (numerator and denominator at most {MAX_POWER})",
                              pos, "use a smaller exponent")
    if base.is_zero and exp_q < 0:
        raise ExpressionError("zero raised to a negative power", pos, "fix the base")
    if base.is_Rational and exp_q.q == 1:
        b = sympy.Rational(base)
        # |b|**e is bounded before computing it: e*log10|b| must stay within the guard.
        size = max(len(str(abs(b.p))), len(str(b.q)))
        if size * abs(exp_q.p) > 300:
            raise ExpressionError("the power is too large", pos, "use a number of a physical size")
    value = base**exp_q
    _check_finite(value, pos)
    return value


def _check_finite(value: sympy.Expr, pos: int) -> None:
    if value.has(sympy.zoo, sympy.oo, -sympy.oo, sympy.nan):
        raise ExpressionError("the expression is infinite or undefined", pos, "fix the arguments")
    if value.is_number and value.is_extended_real is False:
        raise ExpressionError("the value is not a real number", pos, "fix the arguments (e.g. acos of a value outside [-1, 1])")
    if value.is_number and value.is_Rational and abs(value) > MAX_MAGNITUDE:
        raise ExpressionError("the value is too large", pos, "use a number of a physical size")
    if value.is_number and value.is_Rational and value != 0 and abs(value) < 1 / MAX_MAGNITUDE:
        raise ExpressionError("the value is too small (a double would round it to zero)", pos,
                              "use a number of a physical size")
    if not value.is_number and any(abs(c) > MAX_MAGNITUDE or (c != 0 and abs(c) < 1 / MAX_MAGNITUDE)
                                   for c in value.atoms(sympy.Rational)):
        raise ExpressionError("a coefficient is beyond what a double holds (|c| > 1e300 or < 1e-300)", pos,
                              "use numbers of a physical size")
    if value.is_number and not value.is_Rational and abs(value.evalf(15)) > MAX_MAGNITUDE:
        # exp(1000), exp(exp(10)): finite symbolically, but no double can hold them
        raise ExpressionError("the value is too large", pos, "use a number of a physical size")


def parse_expression(text: str | int | float, names: Mapping[str, sympy.Expr] | None = None) -> sympy.Expr:
    """Parse a model expression into a sympy expression.

    Args:
        text: the expression; ints are taken as-is, floats through their shortest repr.
        names: the names an expression may refer to (parameter symbols).

    Returns:
        The sympy expression, exact (numbers are rationals).

    Raises:
        ExpressionError: syntax error, unknown name/function, or a guard was hit.
    """
    if isinstance(text, bool):
        raise ExpressionError("expected a number or an expression, got a boolean", 0,
                              "write a number (YAML reads yes/no/on/off as booleans)")
    if isinstance(text, int):
        text = str(text)
    elif isinstance(text, float):
        if text != text or text in (float("inf"), float("-inf")):
            raise ExpressionError("the value is infinite or NaN", 0, "write a finite number")
        text = repr(text)
    if not isinstance(text, str):
        raise ExpressionError(f"expected a number or an expression, got {type(text).__name__}", 0,
                              "write a number or an expression such as 'l1/2'")
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"expression longer than {MAX_LENGTH} characters", 0, "simplify the expression")
    if not text.strip():
        raise ExpressionError("empty expression", 0, "write a number or an expression")
    return _Parser(text, names or {}).parse()
