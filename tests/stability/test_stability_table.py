"""The results table of docs/numerical-stability.md against a fresh run (issue 16: quoted figures are tested).

Each row quotes ``symkin bench stability models/NAME.yaml`` with the default options.  The
run is deterministic in its states, so the record counts must match exactly.  A non-finite value
comes out only where kappa eps >= 1 (tests/stability/test_stability.py checks that on native arithmetic):
there no digit of a double is certain, and whether a tiny pivot rounds to zero, so that a value
overflows, is up to the CPU's rounding (this count was 24 on one x86-64 machine and 25 on another
for the Stewart platform).  So the quoted non-finite count is checked against what the states allow:
it and the measured one lie between 0 and the number of records at kappa eps >= 1.
The error columns are maxima of rounding errors: another CPU (another libm, other SIMD
loops) rounds differently by a few ulps of each output, which moves a maximum by a small
factor at any condition number (the amplification kappa is the same, only the rounding it
amplifies differs); a changed formula or a lost digit moves it by orders of magnitude.  So a
quoted maximum must lie within :data:`DECADE` of the measured one, either way.
"""

from __future__ import annotations

import math
import re

import pytest
from conftest import EXAMPLE_MODELS, ROOT, STABILITY_SKIP, model_group, stability_run

from tolerances import EPS

#: a quoted maximum and the measured one may differ by this factor, either way (see above)
DECADE = 10.0
DOCUMENT = ROOT / "docs" / "numerical-stability.md"
NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?")



def quoted_rows() -> dict[str, dict[str, float]]:
    """model -> records, kappa_below_1e3, any_kappa, float32, nonfinite: the first number of each cell."""
    text = DOCUMENT.read_text()
    section = text[text.index("## Results"):]
    rows = {}
    for line in section.splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if len(cells) != 6 or cells[0] not in EXAMPLE_MODELS:
            continue
        values = [float(NUMBER.search(cell).group()) for cell in cells[1:]]
        rows[cells[0]] = dict(zip(("records", "kappa_below_1e3", "any_kappa", "float32", "nonfinite"), values))
    return rows


def test_the_table_has_a_row_per_example_model():
    assert sorted(quoted_rows()) == EXAMPLE_MODELS


def test_the_document_names_the_quantities_a_row_leaves_out():
    text = DOCUMENT.read_text()
    for name, skip in STABILITY_SKIP.items():
        assert f"symkin bench stability models/{name}.yaml --skip {','.join(skip)}" in text


# the runs are tests/stability/test_stability.py's too (conftest.stability_run): the same worker, the model's group
@pytest.mark.parametrize("name", [pytest.param(name, marks=model_group(name))
                                  for name in EXAMPLE_MODELS])
def test_quoted_figures_are_what_the_bench_measures(name):
    quoted = quoted_rows()[name]
    run = stability_run(name)                           # the defaults of `symkin bench stability`
    float64 = [r.error for r in run.records if r.family != "float32"]
    measured = {"records": len(run.records), "kappa_below_1e3": run.acceptance()[1],
                "any_kappa": max(e for e in float64 if math.isfinite(e)),
                "float32": max(r.error for r in run.select("float32")),
                "nonfinite": sum(math.isinf(r.error) for r in run.records)}
    assert quoted["records"] == measured["records"], f"{name}: the table quotes {quoted}, the bench measures {measured}"
    ill_posed = [r for r in run.records if r.kappa * EPS >= 1]         # no digit certain: rounding decides
    assert all(r.kappa * EPS >= 1 for r in run.records if math.isinf(r.error)), \
        f"{name}: a non-finite value where kappa eps < 1"
    assert quoted["nonfinite"] <= len(ill_posed), f"{name}: the table quotes {quoted}, {len(ill_posed)} records at " \
                                                   "kappa eps >= 1"
    assert measured["nonfinite"] <= len(ill_posed), f"{name}: the bench measures {measured}, {len(ill_posed)} records " \
                                                     "at kappa eps >= 1"
    for column in ("kappa_below_1e3", "any_kappa", "float32"):
        ratio = quoted[column] / measured[column]
        assert 1.0 / DECADE <= ratio <= DECADE, \
            f"{name}: {column} quoted {quoted[column]:.2g}, measured {measured[column]:.2g}: refresh the table"
