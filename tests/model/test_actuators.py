"""Drives of serial joints (issue 30, actuators): a rotor of inertia J_m behind a gear of ratio N adds the
reflected inertia N^2 J_m to M's diagonal and N^2 J_m qdd to tau; exact against the seed's 2R arm, and
against Pinocchio's armature on the UR10e through `symkin crosscheck`."""

from __future__ import annotations

import pytest
import sympy

from conftest import MODELS_DIR
from symkin.references.crosscheck import crosscheck
from symkin.derivation import Derivation
from symkin.errors import ModelError
from symkin.model import coordinates, model_from_text
from tolerances import CLOSED_FORM

PLANAR = (MODELS_DIR / "planar_2r.yaml").read_text()
DRIVES = """
actuators:
  theta1: {rotor_inertia: J1, gear_ratio: N1}
  theta2: {rotor_inertia: J2}
"""
PARAMETERS = "  g: {value: 9.81, unit: m/s^2, doc: gravitational acceleration}\n"
DRIVE_PARAMETERS = PARAMETERS + "  J1: 1.2e-6\n  N1: 13.3\n  J2: 3.4e-6\n"


def _output(d: Derivation, name: str) -> sympy.Matrix:
    return sympy.Matrix(d[name].expanded_outputs()[0])


def test_the_reflected_rotor_inertia_adds_to_m_and_tau_exactly(derivations):
    model = model_from_text(PLANAR.replace(PARAMETERS, DRIVE_PARAMETERS) + DRIVES, "driven")
    plain = derivations["planar_2r"]
    driven = Derivation(model)
    J1, N1, J2 = (model.parameter(name).symbol for name in ("J1", "N1", "J2"))
    assert [a.reflected_inertia for a in model.actuators] == [N1 ** 2 * J1, J2]
    assert sympy.simplify(_output(driven, "mass_matrix") - _output(plain, "mass_matrix")) == \
        sympy.diag(N1 ** 2 * J1, J2)
    qdd = sympy.Matrix(coordinates.symbols(model, "qdd"))
    assert sympy.simplify(_output(driven, "inverse_dynamics") - _output(plain, "inverse_dynamics")) == \
        sympy.diag(N1 ** 2 * J1, J2) * qdd
    # V and G do not see a rotor whose gyroscopic coupling is neglected
    for name in ("coriolis_vector", "gravity_vector"):
        assert sympy.simplify(_output(driven, name) - _output(plain, name)) == sympy.zeros(2, 1)


def _driven_ur10e(path, options: str = "") -> object:
    """crosscheck of the UR10e with harmonic drives (ratio 101; rotor inertias of the size of its motors',
    illustrative) and the actuator ``options``."""
    path.write_text((MODELS_DIR / "ur10e.yaml").read_text() + "\nactuators:\n" + "".join(
        f"  q{i}: {{rotor_inertia: {j}, gear_ratio: 101{options}}}\n" for i, j in
        ((1, 3.3e-5), (2, 3.3e-5), (3, 1.9e-5), (4, 6.8e-6), (5, 6.8e-6), (6, 6.8e-6))))
    report = crosscheck(path, samples=3, backends=("numpy",), coriolis_matrix=False)
    assert not report.failures, report.comparisons
    assert {"mass_matrix", "coriolis_vector", "inverse_dynamics"} <= {c.quantity for c in report.comparisons}
    return report


def test_a_driven_arm_agrees_with_pinocchio_armature(tmp_path):
    _driven_ur10e(tmp_path / "ur10e_driven.yaml")


@pytest.mark.parametrize("drives, message", [
    ("actuators:\n  theta3: {rotor_inertia: 1}\n", "theta3"),
    ("actuators:\n  theta1: {rotor_inertia: 1, inertia: 2}\n", "inertia"),
    ("actuators:\n  theta1: {rotor_inertia: -1}\n", "negative rotor inertia"),
    ("actuators:\n  theta1: {rotor_inertia: 1, gear_ratio: 0}\n", "the gear ratio must be positive"),
])
def test_bad_drives_get_located_errors(drives, message):
    with pytest.raises(ModelError, match=message) as raised:
        model_from_text(PLANAR + drives, "driven", "driven.yaml")
    assert "driven.yaml:" in str(raised.value)


def test_coulomb_friction_may_differ_with_the_direction_of_motion(tmp_path):
    """Corke's Puma 560 has Tc+ != Tc- (issue 30): c+ opposes positive motion, c- negative motion, nothing at
    rest; smoothed, the same levels are reached through tanh. The numpy module and the C library agree."""
    import numpy as np

    from symkin import pipeline
    from symkin.runtime.loader import load

    text = PLANAR + """
friction:
  theta1: {viscous: 0.1, coulomb: {positive: 0.4, negative: 0.25}}
  theta2: {coulomb: {positive: 0.3, negative: 0.1}, smoothing_velocity: 0.01}
"""
    model = model_from_text(text, "asymmetric")
    request = pipeline.resolve_request(model, ("friction", "inverse_dynamics"), "numpy,c", None, False, "none")
    written = pipeline.write(pipeline.generate(model, request), tmp_path)
    qd = np.array([[1.0, 1.0], [-1.0, -1.0], [0.0, 0.0], [2.0, -0.005]])
    want = np.array([[0.5, 0.3], [-0.35, -0.1],  [0.0, 0.0],
                     [0.6, 0.1 * np.tanh(-0.5) + 0.1 * np.tanh(-0.5) ** 2 + 0.1 * np.tanh(-0.5)]])
    for backend in ("numpy", "c"):
        got = load(written, backend).friction(qd)
        np.testing.assert_allclose(got, want, rtol=0, atol=CLOSED_FORM)  # a few operations and one tanh on O(1)
    with pytest.raises(ModelError, match="negative Coulomb friction level"):
        model_from_text(text.replace("negative: 0.25", "negative: -0.25"), "asymmetric")


def test_a_dh_row_may_flip_its_joint(derivations):
    """RTB's 'flip' (the Kinova Jaco): the joint turns by -q, written as the coupling '-theta2'."""
    flipped = model_from_text(PLANAR.replace("      - [theta2, R, 0, 0, l2, 0, [0, deg(90)]]",
                                             "      - {name: theta2, type: R, theta: 0, d: 0, a: l2, alpha: 0, "
                                             "coupling: -theta2}"), "flipped")
    q1, q2 = coordinates.symbols(flipped, "q")
    plain = _output(derivations["planar_2r"], "fk")
    assert sympy.simplify(_output(Derivation(flipped), "fk") - plain.subs(q2, -q2)) == sympy.zeros(*plain.shape)


def test_a_motor_s_torque_constant_and_currents_give_the_joint_s_effort_limits(tmp_path):
    """N K_t I_peak is the joint's effort limit unless it declares one; N K_t I_cont is in the manifest."""
    import json

    from symkin.cli import main

    text = PLANAR + """
actuators:
  theta1: {rotor_inertia: 1e-6, gear_ratio: 13.3, torque_constant: 0.0234, peak_current: 2.5,
           continuous_current: 0.8}
  theta2: {torque_constant: 0.0234, peak_current: 2.5}
"""
    text = text.replace("      - [theta2, R, 0, 0, l2, 0, [0, deg(90)]]",
                        "      - {name: theta2, type: R, theta: 0, d: 0, a: l2, alpha: 0, effort_limit: 0.05}")
    model = model_from_text(text, "driven")
    assert [float(j.effort_limit) for j in model.joints] == [pytest.approx(13.3 * 0.0234 * 2.5, rel=CLOSED_FORM), 0.05]
    path = tmp_path / "driven.yaml"
    path.write_text(text)
    assert main(["derive", str(path), "--only", "fk", "-o", str(tmp_path / "out"), "-q"]) == 0
    record = json.loads((tmp_path / "out" / "planar_2r" / "manifest.json").read_text())["model"]["coordinates"][0]
    assert record["continuous_effort_limit"] == pytest.approx(13.3 * 0.0234 * 0.8, rel=CLOSED_FORM)
    with pytest.raises(ModelError, match="a current limit needs the motor's torque constant"):
        model_from_text(PLANAR + "actuators:\n  theta1: {peak_current: 2}\n", "driven")


def test_urdf_transmissions_give_the_chain_s_gear_ratios():
    """The PR2's arm as shipped: one-joint transmissions give |mechanicalReduction| (negative ones turn the motor
    the other way); its wrist differential couples two joints and gives none."""
    from symkin.model import load_model
    from sample_models import ROBOTS_DIR

    model = load_model(ROBOTS_DIR / "pr2_description/urdf/pr2.urdf", base="torso_lift_link", tip="l_gripper_palm_link", chain=True)
    ratios = {a.joint: float(a.gear_ratio) for a in model.actuators}
    # the decimals of the file, read exactly and rounded once: equal to the literals
    assert ratios["l_shoulder_pan_joint"] == 63.1552452977
    assert ratios["l_upper_arm_roll_joint"] == 32.6525111499
    assert "l_wrist_flex_joint" not in ratios
    assert all(float(a.rotor_inertia) == 0 for a in model.actuators)


def test_gyroscopic_rotors_couple_with_the_links_that_carry_them(derivations):
    """With 'gyroscopic: true' the rotor of theta2 spins on link 1 at qd1 + N2 qd2 (parallel axes): its kinetic
    energy 1/2 J2 (qd1 + N2 qd2)^2 adds J2 [[1, N2], [N2, N2^2]] to M; theta1's rotor sits on the base: J1 N1^2."""
    text = PLANAR.replace(PARAMETERS, DRIVE_PARAMETERS + "  N2: 7\n") + """
actuators:
  theta1: {rotor_inertia: J1, gear_ratio: N1, gyroscopic: true}
  theta2: {rotor_inertia: J2, gear_ratio: N2, gyroscopic: true}
"""
    model = model_from_text(text, "rotors")
    assert [j.name for j in model.joints] == ["theta1_rotor", "theta1", "theta2_rotor", "theta2"]
    assert [c.name for c in model.coordinates] == ["theta1", "theta2"]
    J1, N1, J2, N2 = (model.parameter(name).symbol for name in ("J1", "N1", "J2", "N2"))
    extra = sympy.Matrix([[N1 ** 2 * J1 + J2, N2 * J2], [N2 * J2, N2 ** 2 * J2]])
    driven = Derivation(model)
    assert sympy.simplify(_output(driven, "mass_matrix") - _output(derivations["planar_2r"], "mass_matrix")) == extra
    for name in ("coriolis_vector", "gravity_vector"):
        assert sympy.simplify(_output(driven, name) - _output(derivations["planar_2r"], name)) == sympy.zeros(2, 1)


def test_gyroscopic_rotors_of_a_spatial_arm_agree_with_pinocchio(tmp_path):
    """The UR10e's rotors as bodies on the links before their joints (Pinocchio: the exported rotor joints set to
    N q, M and tau projected through A), where the coupling terms of z . w_carrier do not vanish."""
    _driven_ur10e(tmp_path / "ur10e_rotors.yaml", ", gyroscopic: true")
