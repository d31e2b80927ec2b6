"""Issue 33: the model file with identified values (symkin.identification.identified_model, `symkin identify` writes it).

References: the rewritten file, read back by the model reader and derived, has exactly the standard parameters it
was written from (bodies moved from the joint frames F_i into rotated and shifted link frames, rotor inertia
through the gear ratio, asymmetric Coulomb levels); least squares' nearest standard parameters reproduce the base
estimate and keep what the run cannot see at the model's values; an estimate that is no body is refused by the
reader's own checks.
"""

from __future__ import annotations

import subprocess
from importlib.metadata import distribution
from pathlib import Path

import numpy as np
import pytest
import sympy
import yaml

from conftest import SYMKIN_CLI
from symkin.identification import identified_model, implied_parameters
from symkin.derivation import Derivation
from symkin.dynamics.quantities import newton_euler_links
from symkin.dynamics.parameter_names import INERTIAL
from symkin.dynamics.regressor import parameter_names, standard_parameters
from symkin.model import load_model, model_from_text
from symkin.model.urdf_export import xml_comment
from identification_runs import arm, excitation, simulated_run, write_run  # noqa: F401 (the module fixture arm)
from sample_models import DRIVEN
from tolerances import EPS

#: A spatial 3R arm (classic DH with twists, so every link frame is rotated and shifted in its joint frame)
#: with rigid bodies given through inertia_rpy and origin, a geared drive and direction-dependent friction.
SPATIAL = """
name: spatial
parameters:
  a1: 0.25
  N1: 12
serial:
  dh:
    convention: classic
    rows:
      - [q1, R, 0, 0.3, a1, pi/2]
      - [q2, R, 0.2, 0.05, 0.4, -pi/3]
      - [q3, P, 0.1, 0, 0.1, pi/4]
bodies:
  - {link: link1, mass: 2.0, com: [-0.1, 0.02, 0.01], inertia: {xx: 0.02, yy: 0.03, zz: 0.025, xy: 0.001}}
  - {link: link1, mass: 0.5}
  - {link: link2, mass: 1.5, com: [-0.2, 0, 0.03], inertia_rpy: [0.1, -0.2, 0.3],
     inertia: {xx: 0.01, yy: 0.05, zz: 0.045, yz: -0.002}}
  - {link: link3, mass: 0.4, origin: {xyz: [0, 0.02, -0.05], rpy: [0.3, 0, 0]},
     inertia: {xx: 0.002, yy: 0.002, zz: 0.001}}
gravity: [0, 0, -9.81]
actuators:
  q1: {rotor_inertia: 1e-5, gear_ratio: N1}
friction:
  q2: {viscous: 0.1, coulomb: {positive: 0.3, negative: 0.2}}
"""
#: The same arm's other bodies, drives and friction: the "identified" values the file is rewritten with.
OTHER = (SPATIAL.replace("mass: 2.0, com: [-0.1, 0.02, 0.01]", "mass: 2.6, com: [-0.12, 0.03, 0.0]")
         .replace("inertia_rpy: [0.1, -0.2, 0.3]", "inertia_rpy: [0.5, 0.2, -0.1]")
         .replace("xyz: [0, 0.02, -0.05]", "xyz: [0.01, 0.03, -0.04]")
         .replace("rotor_inertia: 1e-5", "rotor_inertia: 3e-5")
         .replace("{viscous: 0.1, coulomb: {positive: 0.3, negative: 0.2}}", "{viscous: 0.15, coulomb: 0.25}"))


def standard_values(model) -> np.ndarray:
    """The model's standard parameters pi (the regressor's columns) as numbers."""
    values = standard_parameters(model, Derivation(model)[newton_euler_links])
    defaults = {sympy.Symbol(p.name): p.value for p in model.parameters}  # SymEngine drops the assumptions
    return np.array([float(sympy.sympify(v).xreplace(defaults)) for v in values])


def test_the_rewritten_file_has_exactly_the_parameters_it_was_written_from(tmp_path):
    path = tmp_path / "spatial.yaml"
    path.write_text(SPATIAL)
    model = model_from_text(SPATIAL, "spatial")
    names = parameter_names(model)
    target = standard_values(model_from_text(OTHER, "spatial"))
    everything = np.ones(len(names), dtype=bool)
    updated = identified_model.updated_model(path, model, names, target, everything,
                                             {"method": "wls", "data": "run.csv", "samples": 900})
    written = model_from_text(updated.text, "spatial")
    found = standard_values(written)
    assert np.all(np.abs(found - target) <= 64 * EPS * np.max(np.abs(target))), dict(zip(names, found - target))
    assert updated.links == ("link1", "link2", "link3")
    assert [b.link for b in written.bodies] == ["link1", "link2", "link3"]      # link1's two bodies became one
    assert any("identified by symkin identify (wls) from run.csv, 900 samples" in n for n in written.notes)
    assert written.joints[0].name == "q1"                                        # the rest of the file kept


def test_what_the_run_cannot_see_keeps_the_models_values_and_the_rest_the_base_estimate():
    """Least squares' nearest standard parameters: K pi = pi_b, and columns K does not reach keep the prior."""
    rng = np.random.default_rng(3)
    K = np.zeros((4, 9))
    K[:, :6] = rng.normal(size=(4, 6))                                          # columns 6, 7, 8: not identifiable
    prior, base = rng.uniform(0.5, 2.0, 9), rng.normal(size=4)
    pi = implied_parameters.nearest_standard(K, base, prior)
    assert np.allclose(K @ pi, base, rtol=0, atol=64 * EPS * np.max(np.abs(K)) * np.max(np.abs(pi)))
    assert np.array_equal(pi[6:], prior[6:])
    assert list(implied_parameters.identifiable(K)) == [True] * 6 + [False] * 3


def test_an_estimate_that_is_no_body_is_refused_with_the_readers_reason(tmp_path):
    path = tmp_path / "spatial.yaml"
    path.write_text(SPATIAL)
    model = model_from_text(SPATIAL, "spatial")
    names = parameter_names(model)
    values = standard_values(model)
    values[names.index("link2.Izz")] = -1.0
    with pytest.raises(identified_model.NotUpdated, match=r"bodies\[1\]\.inertia: the inertia tensor is not physical"):
        identified_model.updated_model(path, model, names, values, np.ones(len(names), dtype=bool),
                                       {"method": "ols", "data": "run.csv", "samples": 900})


def test_identify_writes_the_identified_model_file(arm, tmp_path):  # noqa: F811 (the fixture)
    """On the model file: the consistent estimate becomes identified.yaml, which loads and carries it."""
    import json

    t, q, qd, qdd, tau = simulated_run(arm)
    (tmp_path / "driven.yaml").write_text(DRIVEN)
    data = write_run(tmp_path / "run.csv", ["theta1", "theta2"], t, q, tau, qd, qdd)
    result = subprocess.run(SYMKIN_CLI + ["identify", str(tmp_path / "driven.yaml"), str(data), "--method",
                                          "consistent", "--no-figure", "-o", str(tmp_path / "out")],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    written = load_model(tmp_path / "out" / "identified.yaml")
    record = json.loads((tmp_path / "out" / "estimate.json").read_text())["standard"]["parameters"]
    estimate = np.array([record[name] for name in parameter_names(written)])
    found = standard_values(written)
    assert np.all(np.abs(found - estimate) <= 64 * EPS * np.max(np.abs(estimate)))
    assert "identified.yaml" in (tmp_path / "out" / "summary.txt").read_text()


def test_hostile_file_names_stay_data(tmp_path):
    """A data file name with a newline and YAML in it is quoted text of the section, never a key of the file."""
    path = tmp_path / "spatial.yaml"
    path.write_text(SPATIAL)
    model = model_from_text(SPATIAL, "spatial")
    names = parameter_names(model)
    hostile = "run.csv\nallow_nonphysical: true\n# "
    updated = identified_model.updated_model(path, model, names, standard_values(model), np.ones(len(names), bool),
                                             {"method": "ols", "data": hostile, "samples": 900})
    written = model_from_text(updated.text, "spatial")
    document = yaml.safe_load(updated.text)
    assert "allow_nonphysical" not in document
    assert document["identified"]["data"] == hostile
    assert any(hostile in note for note in written.notes)


def test_the_combinations_come_from_states_spread_over_the_run_or_from_all_where_those_miss_a_parameter():
    """K of Y = Y_b K from COMBINATION_STATES evenly spread states equals K from all of them (the identity holds at
    every state); where the spread states leave a base parameter unexcited (its column zero there), all are taken."""
    rng = np.random.default_rng(5)
    count, n, b, P = 4 * implied_parameters.COMBINATION_STATES + 3, 2, 3, 5
    K = rng.normal(size=(b, P))
    Y_b = rng.normal(size=(count, n, b))
    np.testing.assert_allclose(implied_parameters.combinations(Y_b @ K, Y_b), K, rtol=0, atol=64 * EPS)
    spread = np.unique(np.linspace(0, count - 1, implied_parameters.COMBINATION_STATES).astype(int))
    Y_b[spread, :, 2] = 0.0  # the third base parameter moves only between the spread states
    np.testing.assert_allclose(implied_parameters.combinations(Y_b @ K, Y_b), K, rtol=0, atol=64 * EPS)


#: A stock URDF nobody here wrote: the 3-joint finger of the TriFinger (example-robot-data, shipped with Pinocchio).
FINGER = Path(distribution("example-robot-data").locate_file(
    "cmeel.prefix/share/example-robot-data/robots/finger_edu_description/robots/finger_edu.urdf"))


def test_a_robot_files_identified_values_come_back_as_a_symkin_model_and_a_urdf(tmp_path):
    """A URDF's estimate is written twice: identified.yaml (its chain as a symkin model, the robot file named in
    identified:) and identified.urdf (symkin's URDF of it, its TCP the link tcp).  Both, read back, have exactly the
    standard parameters they were written from (every link's scaled by 1.3, viscous and Coulomb friction), but the
    rotor inertia, which a URDF cannot carry: identified.urdf's comment says it is in identified.yaml only."""
    model = load_model(FINGER)
    names = parameter_names(model)
    target = standard_values(model)
    target[[k for k, name in enumerate(names) if name.rsplit(".", 1)[1] in INERTIAL]] *= 1.3
    for joint in model.joints:
        target[names.index(f"{joint.name}.fv")] = 0.05
        target[names.index(f"{joint.name}.fc")] = 0.02
    rotor = names.index(f"{model.joints[0].name}.Ia")
    target[rotor] = 1e-4
    updated = identified_model.updated_model(FINGER, model, names, target, np.ones(len(names), dtype=bool),
                                             {"method": "consistent", "data": "run.csv", "samples": 900})
    as_yaml = model_from_text(updated.text, model.name)
    tolerance = 64 * EPS * np.max(np.abs(target))
    assert np.all(np.abs(standard_values(as_yaml) - target) <= tolerance)
    assert any("(the chain of the robot file finger_edu.urdf)" in note for note in as_yaml.notes)
    assert updated.urdf is not None
    (tmp_path / "identified.urdf").write_text(updated.urdf)
    as_urdf = load_model(tmp_path / "identified.urdf", tip="tcp", chain=True)
    assert parameter_names(as_urdf) == names
    difference = standard_values(as_urdf) - target
    assert np.all(np.abs(np.delete(difference, rotor)) <= tolerance)
    assert difference[rotor] == -1e-4
    assert f"in identified.yaml only: the rotor inertias of {model.joints[0].name} -->" in updated.urdf


def test_identify_on_a_urdf_writes_identified_yaml_and_urdf(tmp_path):
    """`symkin identify finger_edu.urdf` with a run its own dynamics made, with viscous and Coulomb friction added:
    identified.urdf carries estimate.json's consistent standard parameters, as far as a URDF can."""
    import json

    from symkin import derive, load

    finger = load(derive(str(FINGER), str(tmp_path / "generated"), outputs=["inverse_dynamics"]))
    names = list(finger.info.coordinate_names)
    t, q, qd, qdd = excitation(len(names), 2)
    tau = finger.inverse_dynamics(q, qd, qdd) + 0.05 * qd + 0.02 * np.sign(qd)
    data = write_run(tmp_path / "run.csv", names, t, q, tau, qd, qdd)
    result = subprocess.run(SYMKIN_CLI + ["identify", str(FINGER), str(data), "--method", "consistent",
                                          "--no-figure", "-o", str(tmp_path / "out")], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert "identified.urdf: the same as a URDF" in (tmp_path / "out" / "summary.txt").read_text()
    written = load_model(tmp_path / "out" / "identified.urdf", tip="tcp", chain=True)
    record = json.loads((tmp_path / "out" / "estimate.json").read_text())["standard"]["parameters"]
    estimate = np.array([record[name] for name in parameter_names(written)])
    # what a URDF carries: the inertials and the viscous friction; the estimate's Coulomb offset makes the levels
    # direction-dependent, and the comment says that only the positive one is written
    carried = [k for k, name in enumerate(parameter_names(written)) if name.rsplit(".", 1)[1] in (*INERTIAL, "fv")]
    found = standard_values(written)
    assert np.all(np.abs(found[carried] - estimate[carried]) <= 64 * EPS * np.max(np.abs(estimate)))
    assert "the direction-dependent Coulomb levels of" in (tmp_path / "out" / "identified.urdf").read_text()


@pytest.mark.parametrize("text", ["my--arm.yaml", "a-->b", "x-", "---", "ok"])
def test_an_xml_comment_stays_one_comment_whatever_it_holds(text):
    """A file name in a URDF's comment: '--' is not allowed inside one, '-->' would end it; the parser sees one
    comment and the text with every '--' split."""
    import xml.etree.ElementTree as ElementTree

    parser = ElementTree.XMLParser(target=ElementTree.TreeBuilder(insert_comments=True))
    root = ElementTree.fromstring(f"<robot>{xml_comment(text)}</robot>", parser=parser)
    (comment,) = list(root)
    assert comment.text.strip().replace("- -", "--").replace("- -", "--") == text.strip()


#: Two links whose second joint's frame is turned by pi/2 written to five digits (1.5708), as stock files write it.
ROUNDED_ANGLE_ARM = """<?xml version="1.0"?>
<robot name="rounded">
  <link name="base"/>
  <link name="upper"><inertial><origin xyz="0.15 0 0"/><mass value="1.2"/>
    <inertia ixx="0.002" iyy="0.01" izz="0.011" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="fore"><inertial><origin xyz="0.1 0.01 0"/><mass value="0.6"/>
    <inertia ixx="0.001" iyy="0.004" izz="0.0045" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="20" velocity="3"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/>
    <origin xyz="0.3 0 0" rpy="1.5708 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="3"/></joint>
</robot>
"""


def test_identify_on_a_urdf_with_rounded_angles_suggests_snapping_them_and_then_works(tmp_path):
    """Issue 61: a URDF whose angles are multiples of pi/2 rounded to the digits written has no exact base
    parameters as written; `symkin identify` says to read it with --snap-angles (exit 2, nothing written), and
    with the option identifies the run the snapped model's own dynamics made."""
    from symkin import derive, load

    path = tmp_path / "rounded.urdf"
    path.write_text(ROUNDED_ANGLE_ARM)
    arm = load(derive(load_model(path, snap_angles=True), str(tmp_path / "generated"), outputs=["inverse_dynamics"]))
    names = list(arm.info.coordinate_names)
    t, q, qd, qdd = excitation(len(names), 3)
    data = write_run(tmp_path / "run.csv", names, t, q, arm.inverse_dynamics(q, qd, qdd), qd, qdd)
    command = SYMKIN_CLI + ["identify", str(path), str(data), "--method", "ols", "--no-figure", "--no-cache"]
    refused = subprocess.run(command + ["-o", str(tmp_path / "as-written")], capture_output=True, text=True)
    assert refused.returncode == 2, refused.stderr
    assert "--snap-angles" in refused.stderr
    assert not (tmp_path / "as-written").exists()
    snapped = subprocess.run(command + ["--snap-angles", "-o", str(tmp_path / "snapped")], capture_output=True,
                             text=True)
    assert snapped.returncode == 0, snapped.stderr
    import json

    record = json.loads((tmp_path / "snapped" / "estimate.json").read_text())
    # the run is the snapped model's own dynamics without noise: the held-out torques are predicted to rounding
    # (a millionth of the torques' size leaves room for the conditioning of the least squares)
    scale = float(np.sqrt(np.mean(arm.inverse_dynamics(q, qd, qdd) ** 2)))
    assert max(record["validation"]["rms"].values()) <= 1e-6 * scale
