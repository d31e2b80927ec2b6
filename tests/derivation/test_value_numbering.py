"""Issue 12: no generated function evaluates the same right-hand side twice, or trig of a sum.

Read from the generated numpy modules (what users run; the C and CasADi code print the same
temporaries): within each function, every temporary's right-hand side is distinct.
"""

from __future__ import annotations

import collections
import re

import pytest

from conftest import EXAMPLE_MODELS, GENERATED_DIR

#: Known repeats, shortened by each step (a ratchet): empty since sympy's CSE results are value-numbered
#: too (optimize.cse._merge_repeats; the DELTA's closure Jacobians held 0.866...*x twice).
KNOWN_REPEATS: dict[tuple[str, str], int] = {}


def _functions(source: str) -> dict[str, str]:
    return {chunk.split("(", 1)[0]: chunk for chunk in re.split(r"\ndef ", source)[1:]}


@pytest.mark.parametrize("name", EXAMPLE_MODELS)
def test_no_function_evaluates_a_right_hand_side_twice(name):
    source = (GENERATED_DIR / name / f"{name}.py").read_text()
    for function, body in _functions(source).items():
        counts = collections.Counter(re.findall(r"^\s+_x\d+ = (.+)$", body, re.MULTILINE))
        repeats = sum(c - 1 for c in counts.values() if c > 1)
        assert repeats == KNOWN_REPEATS.get((name, function), 0), (
            function, [rhs for rhs, c in counts.items() if c > 1][:5])


@pytest.mark.parametrize("name", EXAMPLE_MODELS)
def test_each_angle_costs_one_sincos_and_no_function_calls_trig_of_a_sum(name):
    """sin and cos of the inputs come from the vectorized sincos helper; trig of sums (also through
    definitions: ``_w4 = q2 + q3 + q4``) is expanded by the addition formulas, so the only libm
    sin/cos calls in the C source are the helper's range-reduction fallback."""
    source = (GENERATED_DIR / name / f"{name}.c").read_text()
    calls = re.findall(r"\b(?:sin|cos)f?\(([^()]*)\)", source)
    assert set(calls) <= {"x[i]"}, sorted(set(calls))[:5]
