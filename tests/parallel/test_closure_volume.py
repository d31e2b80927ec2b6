"""The volume of a working mode continued through the loop closure is unbiased (issue 60).

The device: the DELTA of models/delta.yaml with its parallelograms written as revolute pairs (docs/model-format.md,
"A parallelogram in a leg"), so that its legs have no distance form and its workspace is the flood of
symkin.analysis.closure_workspace.  The independent reference: a Monte Carlo of the same device's closed-form
inverse kinematics (the distance form of generated/delta: the knee outwards, the arms within their limits) over
the flood's box.  Counting cells, or bracketing between the interior and all reached cells, was 30 % low on this
grid; the printed volume and its 95 % error bar must cover the reference.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from sample_models import closure_delta_text
from symkin import load, pipeline
from symkin.analysis.closure_workspace import closure_workspace, working_mode_measure
from symkin.model import model_from_text

#: Cells a side of the flood (coarse: the band of boundary cells is a large share, the test of the estimator).
CELLS = 16
#: Points of the reference Monte Carlo.
REFERENCE_SAMPLES = 1_000_000


@pytest.fixture(scope="module")
def closure_delta(tmp_path_factory):
    model = model_from_text(closure_delta_text(), file="closure_delta.yaml")
    request = pipeline.resolve_request(model, "closure,closure_jacobians", fixed="all")
    return load(pipeline.write(pipeline.generate(model, request), tmp_path_factory.mktemp("closure_delta")))


def reference_volume(delta, lower: np.ndarray, upper: np.ndarray) -> tuple[float, float]:
    """(volume, 95 % half-width) of the points of the box whose closed-form ik is real with every arm within
    [-90, 60] deg (models/delta.yaml's actuator limits)."""
    points = lower + np.random.default_rng(1).random((REFERENCE_SAMPLES, 3)) * (upper - lower)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # NaN where the spheres do not meet
        q = np.asarray(delta.ik(points).joints, dtype=float)
    low, high = np.radians(-90.0), np.radians(60.0)
    inside = np.all(np.isfinite(q) & (q >= low) & (q <= high), axis=1)
    box, share = float(np.prod(upper - lower)), float(np.mean(inside))
    return box * share, 1.96 * box * np.sqrt(share * (1 - share) / REFERENCE_SAMPLES)


def test_the_working_modes_volume_covers_a_monte_carlo_of_the_closed_form(closure_delta, generated_dir):
    found = closure_workspace(closure_delta, cells=CELLS)
    estimate = working_mode_measure(closure_delta, found)
    reference, reference_error = reference_volume(load(generated_dir / "delta"), *found.box)
    assert reference > 0.004        # the DELTA's 5 litres, not a few cells
    # the two 95 % intervals' difference: a fixed seed, so the outcome does not vary from run to run
    assert abs(estimate.value - reference) <= np.hypot(estimate.error, reference_error), (estimate, reference)
    assert estimate.error <= 0.02 * reference                        # an error bar that says something
    bracket = found.occupancy.measure()                              # the old estimate: its midpoint far off
    assert abs(bracket.value - reference) > 10 * np.hypot(estimate.error, reference_error)
