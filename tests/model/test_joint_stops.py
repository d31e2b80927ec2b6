"""Stops on combinations of joint coordinates (issue 64: the PHANToM's parallelogram, -65 deg <= q3 - q2 <= 55 deg).

Read as data with located errors; recorded in the manifest; and every analysis samples only the configurations
within them.  The oracle of the sampled set is written here: the planar 2R arm within 0 <= theta1, theta2 <= 90 deg
and theta1 + theta2 <= 90 deg covers the area l1 l2 int_0^{pi/2} (pi/2 - t) sin t dt = l1 l2 (pi/2 - 1) (the
joints' Jacobian determinant is l1 l2 sin theta2, q -> TCP one-to-one there).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import MODELS_DIR
from symkin.analysis import global_indices
from symkin.analysis.inverse import closed_form_inverse
from symkin.analysis.model_files import generated_model
from symkin.errors import ModelError
from symkin.mechanism import stops
from symkin.mechanism.working_mode import assemble
from symkin.model import model_from_text

PLANAR = (MODELS_DIR / "planar_2r.yaml").read_text()
#: the forearm's direction theta1 + theta2 kept within [0, 90 deg]
STOPPED = PLANAR + '\njoint_stops:\n  - {expression: "theta1 + theta2", limits: [0, deg(90)], doc: forearm}\n'


def test_a_stops_text_is_shown_on_one_line():
    text = STOPPED.replace('"theta1 + theta2"', '"theta1 +\\n\\t theta2"')
    (stop,) = model_from_text(text, file="arm.yaml").joint_stops
    assert stop.expression == "theta1 + theta2"


def test_a_stop_is_read_with_its_terms_and_bounds():
    (stop,) = model_from_text(STOPPED, file="arm.yaml").joint_stops
    assert [(name, float(a)) for name, a in stop.terms] == [("theta1", 1.0), ("theta2", 1.0)]
    assert float(stop.offset) == 0.0
    assert (float(stop.lower), float(stop.upper)) == (0.0, math.pi / 2)
    assert stop.expression == "theta1 + theta2"


@pytest.mark.parametrize(("stop", "message"), [
    ('{expression: "theta1 * theta2", limits: [0, 1]}', "is not affine in the coordinates"),
    ('{expression: "sin(theta1)", limits: [0, 1]}', "is not affine in the coordinates"),
    ('{expression: "theta9 - theta1", limits: [0, 1]}', "theta9"),
    ('{expression: "0.3", limits: [0, 1]}', "names no coordinate: it would bound nothing"),
    ('{expression: "theta1", limits: [1, 0]}', "the lower limit 1 is not below the upper limit 0"),
    ('{expression: "theta1", limits: [0, l1]}', "used here as an angle"),
    ('{expression: "theta1 - theta2", limits: [0.5, 1]}', "at the home configuration theta1 - theta2 = 0"),
    ('{expression: 3, limits: [0, 1]}', "a stop's expression is text"),
    ('{expression: "theta1", limit: [0, 1]}', "limit"),
    ('{expression: "__import__(\'os\')", limits: [0, 1]}', "invalid expression"),
])
def test_a_bad_stop_is_a_located_error(stop, message):
    text = PLANAR.replace("      - [theta2, R, 0, 0, l2, 0, [0, deg(90)]]",
                        "      - [theta2, R, 0, 0, l2, 0, [0, deg(90)]]\n  home: [0, 0]")
    with pytest.raises(ModelError, match=message) as error:
        model_from_text(text + f"\njoint_stops:\n  - {stop}\n", file="arm.yaml")
    assert "arm.yaml:" in str(error.value)
    assert "joint_stops" in str(error.value)


@pytest.fixture(scope="module")
def stopped_arm(tmp_path_factory):
    path = tmp_path_factory.mktemp("stops") / "planar_2r.yaml"
    path.write_text(STOPPED)
    return generated_model(str(path), outputs=("fk", "jacobian"))


def test_the_manifest_records_the_stop_at_the_defaults(stopped_arm):
    (record,) = stopped_arm.info.joint_stops
    assert record.coefficients == {"theta1": 1.0, "theta2": 1.0}
    assert record.limits == (0.0, math.pi / 2)
    table = stops.StopInequalities.of_model(stopped_arm)
    np.testing.assert_array_equal(table.rows, [[1.0, 1.0]])
    q = np.radians([[10.0, 70.0], [10.0, 85.0], [60.0, 30.0]])
    assert table.respected(q).tolist() == [True, False, True]


def test_the_workspace_and_the_gci_sample_only_configurations_within_the_stops(stopped_arm):
    """The sampled workspace lies within the stop; the joint domain's area (|det J| dq over the joint box, weighted
    by the stops) and the Cartesian box's (inverse kinematics within the limits and the stops) are both the
    closed form's, each within its own error estimate (and the quadrature's edge on the stop's diagonal)."""
    rng = np.random.default_rng(64)
    q = rng.uniform(0.0, math.pi / 2, size=(2000, 2))
    _, inside = assemble(stopped_arm, q)
    np.testing.assert_array_equal(inside, q.sum(axis=1) <= math.pi / 2 + 1e-9)
    exact = 0.1 * 0.1 * (math.pi / 2 - 1.0)
    joint = global_indices.workspace_measure(stopped_arm, samples=2 ** 14, seed=1)
    assert abs(joint.value - exact) <= 4 * joint.error
    box = (np.array([-0.1, 0.0]), np.array([0.2, 0.2]))
    cartesian = global_indices.workspace_measure(stopped_arm, samples=2 ** 14, seed=1, domain="cartesian",
                                                 inverse=closed_form_inverse(stopped_arm), box=box)
    assert abs(cartesian.value - exact) <= 4 * cartesian.error


def test_an_exported_urdf_says_which_stops_it_cannot_hold(tmp_path):
    from symkin.cli import main

    path, out = tmp_path / "planar_2r.yaml", tmp_path / "arm.urdf"
    path.write_text(STOPPED)
    assert main(["export", str(path), "-o", str(out)]) == 0
    assert f"joint stops of the model, which URDF cannot hold: 0.0 <= theta1 + theta2 <= {math.pi / 2!r}" in (
        out.read_text())
