"""The volume of a working mode continued through the loop closure is unbiased, and its home assembly is reported
and can be declared (issue 60).

The device: the DELTA of models/delta.yaml with its parallelograms written as revolute pairs (docs/model-format.md,
"A parallelogram in a leg"), so that its legs have no distance form and its workspace is the flood of
symkin.analysis.continued_workspace.  The independent reference: a Monte Carlo of the same device's closed-form
inverse kinematics (the distance form of generated/delta: the knee outwards, the arms within their limits) over
the flood's box.  Counting cells, or bracketing between the interior and all reached cells, was 30 % low on this
grid; the printed volume and its 95 % error bar must cover the reference.  The home assembly: the rule (q = s = 0,
then fixed random starts) is reported with the joint values it reached; ``parallel.home_assembly`` names another.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from sample_models import closure_delta_text
from symkin import load, pipeline
from symkin.analysis.continued_workspace import continued_workspace, working_mode_measure
from symkin.cli import main
from symkin.model import ModelError, model_from_text

#: Cells a side of the flood (coarse: the band of boundary cells is a large share, the test of the estimator).
CELLS = 16
#: Points of the reference Monte Carlo.
REFERENCE_SAMPLES = 1_000_000


def derived(text: str, directory):
    model = model_from_text(text, file="closure_delta.yaml")
    request = pipeline.resolve_request(model, "closure,closure_jacobians", fixed="all")
    return load(pipeline.write(pipeline.generate(model, request), directory))


@pytest.fixture(scope="module")
def closure_delta(tmp_path_factory):
    return derived(closure_delta_text(), tmp_path_factory.mktemp("closure_delta"))


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
    found = continued_workspace(closure_delta, cells=CELLS)
    estimate = working_mode_measure(closure_delta, found)
    reference, reference_error = reference_volume(load(generated_dir / "delta"), *found.box)
    assert reference > 0.004        # the DELTA's 5 litres, not a few cells
    # the two 95 % intervals' difference: a fixed seed, so the outcome does not vary from run to run
    assert abs(estimate.value - reference) <= np.hypot(estimate.error, reference_error), (estimate, reference)
    assert estimate.error <= 0.02 * reference                        # an error bar that says something
    bracket = found.occupancy.measure()                              # the old estimate: its midpoint far off
    assert abs(bracket.value - reference) > 10 * np.hypot(estimate.error, reference_error)


#: A declared start that flips leg 1's parallelogram description: its rods' swing and sway by half a turn (the same
#: rods, another solution of the closure; q = s = 0 reaches swing1 = 0).
FLIPPED = "  home_assembly: {swing1: deg(170), sway1: deg(170)}\n"


def test_the_home_assembly_is_reported_and_the_declared_one_is_used(closure_delta, tmp_path, capsys):
    """symkin workspace reports the home assembly with the start that reached it and every joint's value; a
    declared parallel.home_assembly is where the solve starts (its values in the manifest), and the report says so."""
    from symkin.mechanism.closure import solve_home_assembly

    default = solve_home_assembly(closure_delta)
    assert default.start == "q = s = 0"
    np.testing.assert_allclose(np.degrees(default.q), -39.28, atol=0.01)   # models/delta.yaml: 39 deg down at home
    text = closure_delta_text().replace("  home: [0, 0, -0.15]\n", "  home: [0, 0, -0.15]\n" + FLIPPED)
    flipped = derived(text, tmp_path / "flipped")
    assert flipped.info.home_assembly == pytest.approx({"swing1": np.radians(170), "sway1": np.radians(170)})
    declared = solve_home_assembly(flipped)
    assert declared.start == "the declared parallel.home_assembly"
    np.testing.assert_allclose(declared.q, default.q, atol=1e-9)             # the same arms ...
    names = list(flipped.info.functions["closure"].inputs[1].elements)
    assert abs(np.degrees(declared.s[names.index("swing1")])) == pytest.approx(180, abs=1e-6)   # ... leg 1 flipped
    (tmp_path / "flipped.yaml").write_text(text)
    assert main(["workspace", str(tmp_path / "flipped.yaml"), "-n", "512", "--no-figure"]) == 0
    out = capsys.readouterr().out
    assert "home assembly (Gauss-Newton at the home pose from the declared parallel.home_assembly): " \
           "theta1 = -39.28 deg" in out
    assert "swing1 = 180 deg" in out


@pytest.mark.parametrize("declared, message, fix", [
    ("{swng1: 0.1}", "no leg joint variable named 'swng1'", "did you mean 'swing1'?"),
    ("{swing1: b}", "", "angle"),                                          # a length as an angle
    ("[0.1]", "expected a mapping of leg joint variables", "home_assembly: {knee1"),
])
def test_a_declared_home_assembly_is_checked_where_it_stands(declared, message, fix):
    text = closure_delta_text().replace("  home: [0, 0, -0.15]\n",
                                        f"  home: [0, 0, -0.15]\n  home_assembly: {declared}\n")
    with pytest.raises(ModelError) as error:
        model_from_text(text, file="bad.yaml")
    assert len(error.value.problems) == 1
    assert message in str(error.value)
    assert fix in str(error.value)
    assert "bad.yaml:" in str(error.value)
    assert "home_assembly" in str(error.value)
