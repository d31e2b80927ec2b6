"""The isotropic force of symkin.rating.forces (issue 14, seed sec. 4.2 / Table 8.5).

Oracles: the planar arm's closed form (J's columns have lengths |p| and l2, so
f_iso = min(tau1 / |p|, tau2 / l2)); the direction that attains it, along which the binding
actuator reaches its limit exactly (tau = J^T F through the generated DELTA Jacobian); and a
dense sweep of directions, none of which gives less.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import GENERATED_DIR, ROOT
from symkin import load
from symkin.rating import forces
from symkin import mechanism
from symkin.cli import main
from symkin.errors import ModelError
from symkin.model import model_from_text
from tolerances import KINEMATICS

EPS = np.finfo(float).eps


def test_the_planar_arm_against_its_closed_form():
    arm = load(GENERATED_DIR / "planar_2r")
    q = np.random.default_rng(20).uniform(0, np.pi / 2, (200, 2))
    p = mechanism.tcp_positions(arm, q)
    got = forces.isotropic_force(arm.jacobian(q), [1.0, 2.0])
    want = np.minimum(1.0 / np.linalg.norm(p, axis=-1), 2.0 / 0.1)
    np.testing.assert_allclose(got, want, rtol=8 * EPS, atol=0)


def test_the_delta_reaches_an_effort_limit_exactly_along_the_worst_direction():
    delta = load(GENERATED_DIR / "delta")
    limits = np.array([0.4, 0.5, 0.6])
    p = np.array([[0.0, 0.0, -0.15], [0.03, -0.02, -0.17], [-0.05, 0.04, -0.12]])
    q = delta.ik(p).joints
    J = delta.jacobian(q, p)
    f_iso = forces.isotropic_force(J, limits)
    columns = np.linalg.norm(J, axis=-2)
    binding = np.argmin(limits / columns, axis=-1)
    for k in range(len(p)):
        u = J[k][:, binding[k]] / columns[k, binding[k]]
        tau = J[k].T @ (f_iso[k] * u)
        assert abs(tau[binding[k]] - limits[binding[k]]) <= KINEMATICS * limits.max()
        assert np.all(np.abs(tau) <= limits * (1 + KINEMATICS))
        # no direction of a dense sweep gives less than f_iso
        rng = np.random.default_rng(k)
        directions = rng.normal(size=(20000, 3))
        directions /= np.linalg.norm(directions, axis=-1, keepdims=True)
        assert forces.directional_force(J[k], limits, directions).min() >= f_iso[k] * (1 - KINEMATICS)


def test_effort_limits_must_be_positive():
    with pytest.raises(ValueError, match="must be positive"):
        forces.isotropic_force(np.eye(2), [1.0, 0.0])


def test_cli_force_map(tmp_path, capsys):
    figure = tmp_path / "force.png"
    assert main(["workspace", str(GENERATED_DIR / "delta"), "--no-figure", "--force-map", str(figure),
                 "--effort-limit", "0.5"]) == 0
    out = capsys.readouterr().out
    assert "isotropic force: min " in out
    assert figure.stat().st_size > 0


@pytest.mark.parametrize("model, arguments, message", [
    ("planar_2r", [], "declares no effort limit for every actuator"),
    ("planar_2r", ["--effort-limit", "1,2,3"], "give one value or 2"),
    ("ur10e", ["--effort-limit", "100"], "is not translations only"),
])
def test_cli_force_map_bad_input_exits_with_code_2(tmp_path, capsys, model, arguments, message):
    with pytest.raises(SystemExit) as exit_info:
        main(["workspace", str(GENERATED_DIR / model), "--no-figure", "-n", "1000", "--force-map",
              str(tmp_path / "f.png"), *arguments])
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err


def test_a_delta_that_declares_its_actuators_effort_limits_needs_no_option(tmp_path, capsys):
    text = (ROOT / "models" / "delta.yaml").read_text().replace(
        "actuator_limits: [deg(-90), deg(60)]",
        "actuator_limits: [deg(-90), deg(60)]\n    actuator_effort_limit: 0.5\n    actuator_velocity_limit: 20")
    model = tmp_path / "delta.yaml"
    model.write_text(text)
    assert main(["workspace", str(model), "--no-figure", "--force-map", str(tmp_path / "f.png")]) == 0
    declared = capsys.readouterr().out.split("isotropic force: ")[1].split("\n")[0]
    assert main(["workspace", str(GENERATED_DIR / "delta"), "--no-figure", "--force-map", str(tmp_path / "g.png"),
                 "--effort-limit", "0.5"]) == 0
    assert capsys.readouterr().out.split("isotropic force: ")[1].split("\n")[0] == declared
    passive = text.replace("    actuator_effort_limit: 0.5\n", "")
    assert [c.effort_limit for c in model_from_text(passive).coordinates] == [None] * 3


def test_an_effort_limit_on_a_passive_leg_joint_is_a_located_error():
    with pytest.raises(ModelError, match="'effort_limit' is the actuator's") as error:
        model_from_text((ROOT / "models" / "stewart.yaml").read_text().replace(
            "type: S}", "type: S, effort_limit: 100}", 1))
    assert error.value.problems[0].line is not None
