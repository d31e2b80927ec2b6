"""Issue 60, point 3: one mistake, one error - at its source line, with a "did you mean", and nothing of what
follows from it.

Reference: stock example models (models/stewart.yaml: a chain shared by six legs; models/pantograph.yaml,
models/planar_2r.yaml) with one typical mistake each; before, a typo in the shared chain printed the right
message six times and then its consequences (0 active joints, ...), a missing parameter one error per use.
"""

from __future__ import annotations

import pytest

from conftest import MODELS_DIR
from symkin.errors import ModelError
from symkin.model import load_model

CASES = [
    # (model, old, new, line of the mistake, message, fix)
    ("stewart", "axis: [1, 0, 0], active: true, limits", "axis: [1, 0, 0], actve: true, limits", 42,
     "unknown key 'actve'", "did you mean 'active'?"),
    ("stewart", "  r_b: {value: 0.2, unit: m, doc: radius of the circle of the base joints}\n", "", 44,
     "undefined name 'r_b'", "did you mean 'r_p'?"),
    ("stewart", "{chain: ups, base: {radius: r_b, angle: -gamma_b}", "{chain: upss, base: {radius: r_b, angle: -gamma_b}",
     45, "unknown chain 'upss'", "did you mean 'ups'?"),
    ("planar_2r", "l1: {value: 0.1, unit: m,", "l1: {value: 100, unit: milimetre,", 20, "unknown unit 'milimetre'",
     "did you mean"),
    ("pantograph", "{name: elbow, type: R, axis: [0, 0, 1], ", "{name: elbow, type: R, ", 56,
     "the R joint 'elbow' has no axis", "add 'axis: [0, 0, 1]'"),
]


@pytest.mark.parametrize("model, old, new, line, message, fix", CASES, ids=[c[4] for c in CASES])
def test_a_single_mistake_is_a_single_located_error(tmp_path, model, old, new, line, message, fix):
    text = (MODELS_DIR / f"{model}.yaml").read_text()
    assert old in text
    path = tmp_path / f"{model}.yaml"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(ModelError) as raised:
        load_model(path)
    assert len(raised.value.problems) == 1, str(raised.value)
    problem = raised.value.problems[0]
    assert problem.line == line, str(problem)
    assert message in problem.message, str(problem)
    assert fix in problem.fix, str(problem)
