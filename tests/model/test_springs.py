"""Joint springs (issue 61: every MJCF option that changes the model is honoured): ``springs:`` gives a joint the
potential 1/2 k (theta - theta_0)^2, whose force k (theta - theta_0) is part of G and tau; exact against the seed's
2R arm, against MuJoCo's ``qfrc_spring`` through ``symkin crosscheck`` on MJCF files (gymnasium's cheetah as
shipped, and a file with slide springs and ``springref``), and refused located where symkin cannot carry them."""

from __future__ import annotations

from importlib.metadata import distribution
from pathlib import Path

import pytest
import sympy

from conftest import MODELS_DIR
from symkin.references.crosscheck import crosscheck
from symkin.derivation import Derivation
from symkin.errors import DerivationError, ModelError
from symkin.model import coordinates, load_model, model_from_text
from symkin.model.urdf_export import export_urdf

ASSETS = Path(distribution("gymnasium").locate_file("gymnasium/envs/mujoco/assets"))
PLANAR = (MODELS_DIR / "planar_2r.yaml").read_text()
SPRINGS = """
springs:
  theta1: {stiffness: k1, reference: rest1}
  theta2: {stiffness: k2}
"""
SPRING_PARAMETERS = ("  g: {value: 9.81, unit: m/s^2, doc: gravitational acceleration}\n"
                     "  k1: {value: 0.5, unit: N*m/rad}\n  rest1: {value: 30, unit: deg}\n  k2: 0.2\n")


def _output(d: Derivation, name: str) -> sympy.Matrix:
    return sympy.Matrix(d[name].expanded_outputs()[0])


def test_a_spring_adds_its_force_to_g_and_tau_and_its_energy_to_u_exactly(derivations):
    text = PLANAR.replace("  g: {value: 9.81, unit: m/s^2, doc: gravitational acceleration}\n", SPRING_PARAMETERS)
    model = model_from_text(text + SPRINGS, "sprung")
    plain, sprung = derivations["planar_2r"], Derivation(model)
    k1, rest1, k2 = (model.parameter(name).symbol for name in ("k1", "rest1", "k2"))
    theta1, theta2 = coordinates.symbols(model, "q")
    force = sympy.Matrix([k1 * (theta1 - rest1), k2 * theta2])
    for name in ("gravity_vector", "inverse_dynamics"):
        assert sympy.simplify(_output(sprung, name) - _output(plain, name) - force) == sympy.zeros(2, 1)
    energy = _output(sprung, "potential_energy")[0] - _output(plain, "potential_energy")[0]
    assert sympy.simplify(energy - k1 * (theta1 - rest1) ** 2 / 2 - k2 * theta2 ** 2 / 2) == 0
    # G stays du/dq with the springs' potential in u
    u = _output(sprung, "potential_energy")[0]
    assert sympy.simplify(sympy.Matrix([u.diff(t) for t in (theta1, theta2)]) - _output(sprung, "gravity_vector")) \
        == sympy.zeros(2, 1)
    assert "joint springs" in sprung["gravity_vector"].doc
    with pytest.raises(DerivationError, match=r"theta1, theta2 carry springs .* subtract their torques"):
        sprung["regressor"]
    # a URDF cannot hold them: the export says so instead of dropping them unseen
    assert "joint springs of the model, which URDF cannot hold: theta1 (k = 0.5, theta_0 = 0.5235987755982989)" \
        in export_urdf(model)


def test_springs_alone_give_a_weightless_arm_its_g():
    text = PLANAR.replace("gravity: [0, -g, 0]\n", "")
    text = text.replace("  g: {value: 9.81, unit: m/s^2, doc: gravitational acceleration}\n", "")
    model = model_from_text(text + "springs:\n  theta2: {stiffness: 3, reference: 0.1}\n", "weightless")
    theta2 = coordinates.symbols(model, "q")[1]
    want = sympy.Matrix([0, 3 * (theta2 - sympy.Rational(1, 10))])
    assert sympy.simplify(_output(Derivation(model), "gravity_vector") - want) == sympy.zeros(2, 1)


@pytest.mark.parametrize("springs, message", [
    ("springs:\n  theta3: {stiffness: 1}\n", "theta3"),
    ("springs:\n  theta1: {reference: 1}\n", "missing required key 'stiffness'"),
    ("springs:\n  theta1: {stiffness: -1}\n", "negative spring stiffness"),
    ("springs:\n  theta1: {stiffness: l1}\n", "'l1' is a length .* used here as an angular stiffness"),
])
def test_bad_springs_get_located_errors(springs, message):
    with pytest.raises(ModelError, match=message) as raised:
        model_from_text(PLANAR + springs, "sprung", "sprung.yaml")
    assert "sprung.yaml:" in str(raised.value)


def test_a_parallel_model_s_springs_are_refused_located():
    text = (MODELS_DIR / "delta.yaml").read_text() + "\nsprings:\n  theta1: {stiffness: 1}\n"
    with pytest.raises(ModelError, match=r"delta\.yaml:\d+:\d+: .*springs.*serial chains and trees"):
        model_from_text(text, "delta", "delta.yaml")


#: two hinges and a slide with springs about springref (one of them off zero, one on a joint with ref), gravity on.
SPRUNG_MJCF = """<mujoco model="sprung">
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="cart">
      <joint name="slide" type="slide" axis="1 0 0" stiffness="40" springref="0.05"/>
      <geom type="box" size="0.05 0.04 0.03" mass="1.3"/>
      <body name="arm" pos="0 0 0.1">
        <joint name="hinge" type="hinge" axis="0 1 0" stiffness="2.5" springref="0.3" ref="0.2"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02" mass="0.4"/>
        <body name="hand" pos="0.3 0 0">
          <joint name="wrist" type="hinge" axis="0 0 1" stiffness="0.7"/>
          <geom type="sphere" size="0.03" mass="0.2" pos="0.05 0 0"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.mark.parametrize("source", ["half_cheetah.xml", "sprung"])
def test_mjcf_joint_springs_agree_with_mujoco(source, tmp_path):
    """MuJoCo's passive spring force -k (qpos - qpos_spring) is symkin's k (theta - theta_0) in G: the cheetah read
    with no flag (its six leg joints carry springs), and a file with a slide spring and a springref off zero."""
    path = ASSETS / source
    if source == "sprung":
        path = tmp_path / "sprung.xml"
        path.write_text(SPRUNG_MJCF)
    model = load_model(path)
    assert model.springs
    assert not any("spring" in note for note in model.notes)
    report = crosscheck(path, samples=3, backends=("numpy",), coriolis_matrix=False)
    rows = {c.quantity for c in report.comparisons}
    assert {"gravity_vector", "inverse_dynamics", "coriolis_vector + gravity_vector (MuJoCo)"} <= rows, rows
    assert not report.failures, report.comparisons
