"""The largest box and upright cylinder inside a device's usable workspace (issue 64: a workspace as a maker quotes
it).  Oracle: the DELTA's generated inverse kinematics, its joint limits and 1/kappa at random points of the box and
cylinder found (independent of the grid they were found on); refusals with their reasons.  That they are the
largest on their grid is tests/analysis/test_inscribed.py's (every box of small masks tried)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import GENERATED_DIR
from symkin import load, mechanism
from symkin.cli import main
from symkin.mechanism import feasibility, reach
from symkin.numerics.conditioning import inverse_condition_number
from symkin.rating import workspace_shapes
from tolerances import CLOSED_FORM


@pytest.fixture(scope="module")
def delta():
    return load(GENERATED_DIR / "delta")


def usable(model, points: np.ndarray) -> np.ndarray:
    q, reached = feasibility.feasible_configurations(reach.generated_inverse(model), points,
                                                     mechanism.joint_limits(model), mechanism.revolute_mask(model))
    out = reached.copy()
    out[reached] = inverse_condition_number(model.jacobian(q[reached], points[reached])) >= 0.05
    return out


def test_every_point_of_the_delta_s_box_and_cylinder_is_usable(delta):
    shapes = workspace_shapes.usable_shapes(delta, 0.05)
    rng = np.random.default_rng(64)
    box, cylinder = shapes.box, shapes.cylinder
    inside_box = rng.uniform(box.lower, box.upper, (4000, 3))
    assert usable(delta, inside_box).all()
    angle, radius = rng.uniform(0, 2 * np.pi, 4000), cylinder.radius * np.sqrt(rng.uniform(0, 1, 4000))
    inside_cylinder = np.column_stack([cylinder.centre[0] + radius * np.cos(angle),
                                       cylinder.centre[1] + radius * np.sin(angle),
                                       rng.uniform(cylinder.bottom, cylinder.top, 4000)])
    assert usable(delta, inside_cylinder).all()


def test_a_device_the_shapes_do_not_fit_says_why():
    planar = workspace_shapes.usable_shapes(load(GENERATED_DIR / "planar_2r"), 0.05)
    assert planar.lines() == ["workspace box and cylinder: not rated (the handle moves in 2 directions, not in x, y "
                              "and z)"]
    eye = workspace_shapes.usable_shapes(load(GENERATED_DIR / "agile_eye"), 0.05)
    assert "a handle that translates" in eye.not_rated


def test_the_datasheet_states_the_shapes_with_their_definition(tmp_path):
    out = tmp_path / "rate"
    assert main(["rate", str(GENERATED_DIR / "delta"), "--effort-limit", "0.3", "-n", "256", "--no-figure",
                 "-o", str(out)]) == 0
    record = json.loads((out / "datasheet.json").read_text())["workspace_shapes"]
    assert "largest axis-aligned box" in record["definition"]
    np.testing.assert_allclose(np.subtract(record["box"]["upper_m"], record["box"]["lower_m"]),
                               record["box"]["size_m"], rtol=0, atol=CLOSED_FORM)
    assert [round(1e3 * size) for size in record["box"]["size_m"]] == [124, 115, 99]     # docs/analysis.md
    summary = (out / "summary.txt").read_text()
    assert "workspace box: " in summary
    assert "the largest upright cylinder (axis along z) inside the usable workspace" in summary
    assert main(["rate", str(GENERATED_DIR / "delta"), "--effort-limit", "0.3", "-n", "256", "--no-figure",
                 "--shape-samples", "0", "-o", str(out)]) == 0
    assert "workspace box and cylinder: not rated (--shape-samples 0)" in (out / "summary.txt").read_text()
