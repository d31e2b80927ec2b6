"""Issue 35: asserts that say which part failed - a ratchet on ``assert a and b`` in the tests.

An assert that chains conditions with ``and`` reports only that the whole was false, not which part; write one
assert per condition (or ``np.all`` with the values in the message).  :data:`KNOWN_CHAINED` holds each test
file's count of such asserts (a ratchet: a file that gains one fails, a file that loses some must lower its
number); the table is empty now, and stays so.
"""

from __future__ import annotations

import ast
from pathlib import Path

TESTS = Path(__file__).resolve().parents[1]

#: Test file -> asserts of the form ``assert a and b`` it may hold (issue 35: 258 of 1717 asserts were; all were
#: split into one assert per condition, so none may come back).
KNOWN_CHAINED: dict[str, int] = {}


def chained_asserts(path: Path) -> int:
    """The asserts of ``path`` whose condition is an ``and`` of several conditions."""
    tree = ast.parse(path.read_text(), str(path))
    return sum(1 for node in ast.walk(tree)
               if isinstance(node, ast.Assert) and isinstance(node.test, ast.BoolOp) and isinstance(node.test.op, ast.And))


def test_no_test_file_gains_a_chained_assert_and_the_table_only_shrinks():
    found = {path.name: chained_asserts(path) for path in sorted(TESTS.rglob("*.py"))}
    gained = {name: count for name, count in found.items() if count > KNOWN_CHAINED.get(name, 0)}
    assert not gained, f"split these asserts into one per condition (file: chained asserts now): {gained}"
    lost = {name: found.get(name, 0) for name, known in KNOWN_CHAINED.items() if found.get(name, 0) < known}
    assert not lost, f"fewer chained asserts: lower KNOWN_CHAINED to {lost}"


def test_the_count_sees_chains_and_not_single_conditions(tmp_path):
    sample = tmp_path / "test_sample.py"
    sample.write_text("def test():\n    assert a and b\n    assert a\n    assert a or b\n    assert (a and b) or c\n")
    assert chained_asserts(sample) == 1
