"""Joint-chain (URDF-like) models, prismatic joints, general axes, base and TCP frames."""

from __future__ import annotations

import numpy as np
import pytest
import sympy

from conftest import MODELS_DIR, random_q, reference_function
from symkin.derivation import Derivation
from symkin.errors import ModelError
from symkin.model import coordinates, model_from_text
from tolerances import CLOSED_FORM, KINEMATICS, UR10E_SCALE

# The UR10e as a URDF-style chain with the joint origins of UR's ROS description
# (config/ur10e/default_kinematics.yaml, calibration residue of 1e-11 removed): its link
# frames are the modified DH frames, so base_T_tcp equals that of models/ur10e.yaml.
UR10E_CHAIN = """
name: ur10e_chain
parameters: {d1: 0.1807, a2: -0.6127, a3: -0.57155, d4: 0.17415, d5: 0.11985, d6: 0.11655}
serial:
  chain:
    - {axis: [0, 0, 1], name: q1, origin: {xyz: [0, 0, d1]}}
    - {axis: [0, 0, 1], name: q2, origin: {rpy: [pi/2, 0, 0]}}
    - {axis: [0, 0, 1], name: q3, origin: {xyz: [a2, 0, 0]}}
    - {axis: [0, 0, 1], name: q4, origin: {xyz: [a3, 0, d4]}}
    - {axis: [0, 0, 1], name: q5, origin: {xyz: [0, -d5, 0], rpy: [pi/2, 0, 0]}}
    - {axis: [0, 0, 1], name: q6, origin: {xyz: [0, d6, 0], rpy: [pi/2, pi, pi]}}
task_space: pose
"""


def test_urdf_style_chain_equals_the_dh_models(models, derivations):
    chain = model_from_text(UR10E_CHAIN)
    fk_chain = reference_function(chain, Derivation(chain)["fk"])
    fk_dh = reference_function(models["ur10e"], derivations["ur10e"]["fk"])
    J_chain = reference_function(chain, Derivation(chain)["jacobian"])
    J_dh = reference_function(models["ur10e"], derivations["ur10e"]["jacobian"])
    rng = np.random.default_rng(5)
    for _ in range(100):
        q = random_q(chain, rng)
        # positions and Jacobian columns are within UR10E_SCALE metres
        np.testing.assert_allclose(fk_chain(q)[0], fk_dh(q)[0], rtol=0, atol=KINEMATICS * UR10E_SCALE)
        np.testing.assert_allclose(J_chain(q)[0], J_dh(q)[0], rtol=0, atol=KINEMATICS * UR10E_SCALE)


POLAR_ARM = """
parameters: {h: 0.3, r0: 0.2, t: 0.05}
serial:
  base: {xyz: [0, 0, h]}
  chain:
    - {name: phi, type: R, axis: [0, 0, 1], link: turret}
    - {name: s, type: P, axis: [1, 0, 0], origin: {xyz: [r0, 0, 0]}, limits: [0, 0.5], link: slider}
  tcp: {xyz: [t, 0, 0]}
task_space: [x, y, z]
"""


def test_prismatic_joint_base_and_tcp_frames(derivations):
    model = model_from_text(POLAR_ARM)
    phi, s = coordinates.symbols(model, "q")
    h, r0, t = (model.parameter(n).symbol for n in ("h", "r0", "t"))
    d = Derivation(model)
    T = d["fk"].outputs[0].expr
    reach = r0 + s + t
    expected = sympy.Matrix([reach * sympy.cos(phi), reach * sympy.sin(phi), h])
    assert sympy.simplify(T[:3, 3] - expected) == sympy.zeros(3, 1)
    J = d["jacobian"].outputs[0].expr
    assert sympy.simplify(J - expected.jacobian([phi, s])) == sympy.zeros(3, 2)
    Jg = d["jacobian_geometric"].outputs[0].expr
    # The prismatic column is [axis; 0] with the axis turned by phi.
    assert sympy.simplify(Jg[:, 1] - sympy.Matrix([sympy.cos(phi), sympy.sin(phi), 0, 0, 0, 0])) == sympy.zeros(6, 1)


def _same_fk(a_text: str, b_text: str) -> None:
    a, b = model_from_text(a_text), model_from_text(b_text)
    fa, fb = reference_function(a, Derivation(a)["fk"]), reference_function(b, Derivation(b)["fk"])
    rng = np.random.default_rng(6)
    for _ in range(20):
        q = rng.uniform(-1, 1, a.dof)
        np.testing.assert_allclose(fa(q)[0], fb(q)[0], rtol=0, atol=KINEMATICS)  # links well under 1 m


def test_modified_dh_prismatic_row_matches_the_chain_form():
    """Rows Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i) Tz(d_i + q_i), written out as URDF-style origins.

    Rz(th) commutes with Tz, so it moves into the next joint's origin:
    Rz(th) Rx(-pi/3) Tx(0.2) = Trans(Rz(th) [0.2, 0, 0]) Rz(th) Rx(-pi/3), i.e. rpy [-pi/3, 0, th].
    """
    _same_fk("""
parameters: {a: 0.1, th: 0.3}
serial:
  dh:
    convention: modified
    rows:
      - [q1, R, 0, 0, 0, 0]
      - {name: q2, type: P, alpha: pi/2, a: a, theta: th, d: 0.05}
      - {name: q3, type: R, alpha: -pi/3, a: 0.2, theta: 0, d: 0}
task_space: position
""", """
parameters: {a: 0.1, th: 0.3}
serial:
  chain:
    - {axis: [0, 0, 1], name: q1}
    - {axis: [0, 0, 1], name: q2, type: P, origin: {xyz: [a, 0, 0], rpy: [pi/2, 0, 0]}, offset: 0.05}
    - {axis: [0, 0, 1], name: q3, origin: {xyz: [0.2*cos(th), 0.2*sin(th), 0], rpy: [-pi/3, 0, th]}}
task_space: position
""")


def test_classic_dh_prismatic_row_matches_the_chain_form():
    """Row Rz(theta) Tz(d + q) Tx(a) Rx(alpha): the Tx Rx part becomes the next joint's origin."""
    _same_fk("""
parameters: {a: 0.1, th: 0.3}
serial:
  dh:
    convention: classic
    rows:
      - {name: q1, type: P, theta: th, d: 0.05, a: a, alpha: pi/2}
      - [q2, R, 0, 0, 0, 0]
task_space: position
""", """
parameters: {a: 0.1, th: 0.3}
serial:
  chain:
    - {axis: [0, 0, 1], name: q1, type: P, origin: {rpy: [0, 0, th]}, offset: 0.05}
    - {axis: [0, 0, 1], name: q2, origin: {xyz: [a, 0, 0], rpy: [pi/2, 0, 0]}}
task_space: position
""")


def test_rotation_about_a_general_axis():
    model = model_from_text("serial:\n  chain:\n    - {name: th, axis: [1, 2, 2]}\ntask_space: pose\n")
    (th,) = coordinates.symbols(model, "q")
    R = sympy.Matrix(Derivation(model)["fk"].outputs[0].expr)[:3, :3]
    axis = sympy.Matrix([1, 2, 2]) / 3
    for value in (0.3, 1.7, -2.9):
        Rv = np.array(R.subs(th, value), dtype=float)
        # Rv's entries are rounded once each; unit rows and columns: products of 3 terms are closed forms,
        # the LU determinant takes ~n^3 = 27 roundings (KINEMATICS), and the axis read from
        # R - R^T is divided by 2 sin(value) >= 0.47, which doubles its error.
        np.testing.assert_allclose(Rv @ Rv.T, np.eye(3), rtol=0, atol=CLOSED_FORM)
        assert abs(np.linalg.det(Rv) - 1) <= KINEMATICS
        np.testing.assert_allclose(Rv @ np.array(axis, dtype=float).ravel(), np.array(axis, dtype=float).ravel(),
                                   rtol=0, atol=CLOSED_FORM)
        assert abs((np.trace(Rv) - 1) / 2 - np.cos(value)) <= CLOSED_FORM
        vee = np.array([Rv[2, 1] - Rv[1, 2], Rv[0, 2] - Rv[2, 0], Rv[1, 0] - Rv[0, 1]]) / (2 * np.sin(value))
        np.testing.assert_allclose(vee, np.array(axis, dtype=float).ravel(), rtol=0, atol=2 * CLOSED_FORM / 0.47)


@pytest.mark.parametrize("text, line, message", [
    ("serial:\n  chain:\n    - {name: q1, axis: [1, 0, 0]}\n    - {name: q2, type: P}\ntask_space: position\n",
     4, "the joint 'q2' has no axis"),
    ((MODELS_DIR / "pantograph.yaml").read_text().replace("{name: elbow, type: R, axis: [0, 0, 1], ",
                                                          "{name: elbow, type: R, "), 56, "the R joint 'elbow' has no axis"),
])
def test_a_joint_without_an_axis_is_refused_where_no_convention_fixes_it(text, line, message):
    """Issue 60, point 2: a chain or leg joint without 'axis' silently turned about z (URDF's default is x); it is
    refused at its line with the fix. A DH row keeps z: that is the convention."""
    with pytest.raises(ModelError) as raised:
        model_from_text(text)
    first = raised.value.problems[0]
    assert (first.line, message in first.message, "add 'axis: [0, 0, 1]'" in first.fix) == (line, True, True), \
        str(raised.value)
