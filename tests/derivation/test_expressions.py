"""The whitelisted expression parser: exact values, clear errors, bounded resources."""

from __future__ import annotations

import pytest
import sympy
from hypothesis import given, settings
from hypothesis import strategies as st

from symkin.model.expressions import ExpressionError, parse_expression

L1 = sympy.Symbol("l1", real=True)
NAMES = {"l1": L1}


@pytest.mark.parametrize("text,expected", [
    ("0.1807", sympy.Rational(1807, 10000)),
    ("l1/2", L1 / 2),
    ("-pi/2", -sympy.pi / 2),
    ("deg(90)", sympy.pi / 2),
    ("sqrt(3)*l1/2", sympy.sqrt(3) * L1 / 2),
    ("2**3**2", sympy.Integer(512)),
    ("-2**2", sympy.Integer(-4)),
    ("2^-1", sympy.Rational(1, 2)),
    ("1e3", sympy.Integer(1000)),
    (".5", sympy.Rational(1, 2)),
    ("atan2(1, 1)", sympy.pi / 4),
    ("(l1 + 1)*(l1 - 1)", (L1 + 1) * (L1 - 1)),
    (7, sympy.Integer(7)),
    (0.25, sympy.Rational(1, 4)),
])
def test_valid_expressions_are_exact(text, expected):
    assert sympy.simplify(parse_expression(text, NAMES) - expected) == 0


@pytest.mark.parametrize("text,message", [
    ("__import__('os')", "unexpected character"),
    ("l1.__class__", "unexpected character '.'"),
    ("lambda: 1", "unexpected character ':'"),
    ("eval(1)", "unknown function 'eval'"),
    ("l3", "undefined name 'l3'"),
    ("sin", "is a function"),
    ("cos(1, 2)", "takes 1 argument"),
    ("9**9**9", "too large"),
    ("10**64**2", "too large"),
    ("l1**l1", "exponents must be constant"),
    ("1e999", "out of range"),
    ("1" * 50, "more than 40 digits"),
    ("1/0", "division by zero"),
    ("log(0)", "infinite or undefined"),
    ("acos(2)", "not a real number"),
    ("(" * 60 + "1" + ")" * 60, "nested deeper"),
    ("l1 l1", "unexpected 'l1'"),
    ("", "empty expression"),
    (True, "boolean"),
    ("x" * 3000, "longer than"),
])
def test_invalid_expressions_are_refused(text, message):
    with pytest.raises(ExpressionError, match=message):
        parse_expression(text, NAMES)


@settings(max_examples=300, deadline=None)
@given(st.text(alphabet="0123456789.+-*/^()el1pisqrtcosn, _'\"[]{}:;=<>!@#$%&|~`\\", max_size=40))
def test_arbitrary_text_either_parses_or_raises_expression_error(text):
    try:
        value = parse_expression(text, NAMES)
    except ExpressionError:
        return
    assert isinstance(value, sympy.Expr)
    assert value.free_symbols <= {L1}


@settings(max_examples=200, deadline=None)
@given(st.decimals(allow_nan=False, allow_infinity=False, places=6, min_value=-1e6, max_value=1e6))
def test_decimal_literals_are_read_exactly(value):
    assert parse_expression(str(value)) == sympy.Rational(str(value))
