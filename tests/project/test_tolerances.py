"""Every tolerance the suite asserts below 1e-12 is derived, not a literal (issue 18).

A literal like ``atol=1e-15`` is the last digits one CPU printed; the suite's tolerances are
multiples of eps named and derived in tests/tolerances.py (or written as such at the site,
``(len(f) + 7) * EPS``).  This test reads every test module and refuses a float literal below
1e-12 where it bounds a result: a tolerance keyword of assert_allclose / allclose / isclose /
pytest.approx, or the upper side of a comparison in an ``assert``.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from conftest import FOREIGN_ARITHMETIC
from symkin.backends.c.build import compiler_command

TESTS = Path(__file__).resolve().parents[1]
TOLERANCE_KEYWORDS = {"atol", "rtol", "abs", "rel"}
CHECKS = {"assert_allclose", "allclose", "isclose", "approx", "assert_array_almost_equal_nulp"}
SMALLEST_BARE = 1e-12


def _small_literals(node: ast.AST) -> list[ast.Constant]:
    return [n for n in ast.walk(node) if isinstance(n, ast.Constant) and isinstance(n.value, float)
            and 0.0 < abs(n.value) < SMALLEST_BARE]


def _call_name(call: ast.Call) -> str:
    func = call.func
    return func.attr if isinstance(func, ast.Attribute) else func.id if isinstance(func, ast.Name) else ""


def bare_tolerances(source: str) -> list[tuple[int, float]]:
    """(line, value) of every float literal below 1e-12 used as a tolerance in ``source``."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Call) and _call_name(node) in CHECKS:
            for keyword in node.keywords:
                if keyword.arg in TOLERANCE_KEYWORDS:
                    found += _small_literals(keyword.value)
        if isinstance(node, ast.Assert):
            for compare in (n for n in ast.walk(node.test) if isinstance(n, ast.Compare)):
                operands = [compare.left, *compare.comparators]
                for k, op in enumerate(compare.ops):
                    if isinstance(op, (ast.Lt, ast.LtE)):
                        found += _small_literals(operands[k + 1])
                    elif isinstance(op, (ast.Gt, ast.GtE)):
                        found += _small_literals(operands[k])
    return sorted({(n.lineno, n.value) for n in found})


def test_the_scanner_finds_bare_tolerances_and_passes_derived_ones():
    bare = ("np.testing.assert_allclose(a, b, atol=1e-15)\n"
            "assert x < 1e-14\n"
            "assert 1e-16 >= abs(y)\n"
            "assert v == pytest.approx(w, rel=2e-13)\n")
    assert [line for line, _ in bare_tolerances(bare)] == [1, 2, 3, 4]
    derived = ("np.testing.assert_allclose(a, b, atol=KINEMATICS * 0.3)\n"
               "assert x <= 8 * EPS\n"
               "assert v == pytest.approx(5e-17, rel=EPS)\n"  # an expected value, not a tolerance
               "assert textbook > 1e-12\n"
               "run(rtol=1e-13)\n")  # an integrator's target accuracy, not an assertion
    assert bare_tolerances(derived) == []


def test_no_test_asserts_a_bare_tolerance_below_1e_12():
    offenders = [f"{path.name}:{line}: {value:g}" for path in sorted(TESTS.rglob("*.py"))
                 for line, value in bare_tolerances(path.read_text())]
    assert not offenders, ("tolerances below 1e-12 must be derived (tests/tolerances.py):\n" + "\n".join(offenders))


def test_the_foreign_arithmetic_run_really_changes_the_arithmetic():
    """In the second run of `make test`, numpy dispatches no wide SIMD loop and the C backend contracts
    into FMAs (otherwise that run would repeat the first one and prove nothing)."""
    if not FOREIGN_ARITHMETIC:
        pytest.skip("the first run of make test: native arithmetic")
    from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__

    assert not any(__cpu_features__[feature] for feature in __cpu_dispatch__), __cpu_features__
    flags = compiler_command()
    assert "-ffp-contract=fast" in flags, flags
    assert "-march=native" in flags, flags
