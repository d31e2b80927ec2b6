"""URDF files as model sources: what is read, and every unsupported construct gets a located error."""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest
import sympy

from conftest import MODELS_DIR, SYMKIN_CLI, reference_function
from symkin.derivation import Derivation
from symkin.errors import ModelError
from symkin.model import load_model
from symkin.model.coordinates import coordinate_range
from tolerances import DYNAMICS, KINEMATICS

ARM = """<?xml version="1.0"?>
<robot name="arm">
  <link name="world"/>
  <link name="base"/>
  <link name="l1">
    <inertial><origin xyz="0.1 0 0"/><mass value="1.5"/>
      <inertia ixx="0.001" iyy="0.002" izz="0.003" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <link name="l1_sensor"><inertial><origin xyz="0 0.05 0"/><mass value="0.2"/></inertial></link>
  <link name="l2"><inertial><origin xyz="0.05 0 0"/><mass value="0.5"/></inertial></link>
  <link name="slider"><inertial><mass value="0.25"/></inertial></link>
  <link name="tool"/>
  <joint name="mount" type="fixed"><parent link="world"/><child link="base"/>
    <origin xyz="0 0 0.5" rpy="0 0 3.141592653589793"/></joint>
  <joint name="j1" type="continuous"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/></joint>
  <joint name="sensor_mount" type="fixed"><parent link="l1"/><child link="l1_sensor"/>
    <origin xyz="0.1 0 0.02"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.2 0 0" rpy="1.5707963267948966 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-1.5" upper="1.5" effort="10" velocity="3"/></joint>
  <joint name="j3" type="prismatic"><parent link="l2"/><child link="slider"/>
    <origin xyz="0.1 0 0"/><axis xyz="1 0 0"/><limit lower="0" upper="0.2" effort="50" velocity="0.5"/></joint>
  <joint name="flange" type="fixed"><parent link="slider"/><child link="tool"/><origin xyz="0 0 0.05"/></joint>
</robot>
"""


def _write(tmp_path, text, name="arm.urdf"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_a_chain_with_fixed_joints_branches_and_all_joint_types(tmp_path):
    model = load_model(_write(tmp_path, ARM))
    assert model.name == "arm"
    assert [(j.name, j.type.value, j.link) for j in model.joints] == [("j1", "R", "l1"), ("j2", "R", "l2"),
                                                                      ("j3", "P", "slider")]
    j1, j2, j3 = model.joints
    assert j1.limits is None  # continuous
    assert [float(v) for v in j2.limits] == [-1.5, 1.5]
    assert float(j3.effort_limit) == 50
    assert model.base
    assert model.tcp  # the fixed mount and flange
    # The sensor, fixed to l1 off the chain, moves with l1: its mass is a body of l1.
    assert sorted((b.link, float(b.mass)) for b in model.bodies) == [("l1", 0.2), ("l1", 1.5), ("l2", 0.5),
                                                                    ("slider", 0.25)]
    sensor = next(b for b in model.bodies if b.mass == 0.2 or float(b.mass) == 0.2)
    assert [float(c) for c in sensor.com] == [0.1, 0.05, 0.02]
    # The rpy of j2 is read as written (the decimal the file prints), and the TCP sits where the
    # frames say at q = 0:
    # (0, 0, 0.5) + Rz(pi) [(0.2, 0, 0) + Rx(pi/2) ((0.1, 0, 0) + (0, 0, 0.05))] = (-0.3, 0.05, 0.5).
    assert j2.before[-1].angle == sympy.Rational("1.5707963267948966")
    assert "angles as written" in model.description
    T = reference_function(model, Derivation(model)["fk"])(np.zeros(3))[0]
    np.testing.assert_allclose(T[:3, 3], [-0.3, 0.05, 0.5], rtol=0, atol=KINEMATICS)  # lengths < 1 m


def test_angles_are_snapped_to_multiples_of_pi_half_only_when_asked(tmp_path):
    path = _write(tmp_path, ARM)
    snapped = load_model(path, snap_angles=True)
    assert snapped.joints[1].before[-1].angle == sympy.pi / 2
    assert "snapped" in snapped.description
    # 3.14159265359 (a Kinova file's pi) is 2e-13 from pi: as written it stays that decimal.
    near = _write(tmp_path, ARM.replace("3.141592653589793", "3.14159265359"), "near.urdf")
    assert load_model(near).base[-1].angle == sympy.Rational("3.14159265359")
    assert load_model(near, snap_angles=True).base[-1].angle == sympy.pi


def test_the_tip_selects_the_chain(tmp_path):
    text = ARM.replace('<link name="tool"/>', '<link name="tool"/><link name="cam"/>').replace(
        "</robot>", '<joint name="cam_mount" type="fixed"><parent link="slider"/><child link="cam"/></joint></robot>')
    path = _write(tmp_path, text)
    whole = load_model(path)          # issue 61: no tip named - the whole tree, its task frame the first deepest leaf
    assert whole.dof == 3
    assert whole.tcp == load_model(path, tip="tool", chain=True).tcp
    assert load_model(path, tip="tool", chain=True).dof == 3
    assert load_model(path, tip="cam", chain=True).tcp == ()
    with pytest.raises(ModelError, match="tip link 'nope' is not a link"):
        load_model(path, tip="nope", chain=True)


def test_joints_off_the_chain_are_locked_and_their_links_lumped_into_the_chain(tmp_path):
    """Beyond the tip l2, the prismatic j3 is locked (at 0, or at --lock's value): the slider and the
    tool it carries become rigid parts of l2, as in Pinocchio's buildReducedModel."""
    path = _write(tmp_path, ARM)
    at_zero = load_model(path, tip="l2", chain=True)
    assert [j.name for j in at_zero.joints] == ["j1", "j2"]
    assert "locked: j3 = 0" in at_zero.description
    slider = next(b for b in at_zero.bodies if float(b.mass) == 0.25)
    assert slider.link == "l2"
    assert [float(c) for c in slider.com] == [0.1, 0.0, 0.0]
    moved = load_model(path, tip="l2", chain=True, locks={"j3": 0.15})
    slider = next(b for b in moved.bodies if float(b.mass) == 0.25)
    assert [float(c) for c in slider.com] == [0.25, 0.0, 0.0]  # 0.1 + 0.15 along the axis x
    with pytest.raises(ModelError, match="locked at 0.3, outside its limits"):
        load_model(path, tip="l2", chain=True, locks={"j3": 0.3})
    with pytest.raises(ModelError, match="--lock names 'j2', a joint of the chain"):
        load_model(path, tip="l2", chain=True, locks={"j2": 0.1})
    with pytest.raises(ModelError, match="unknown joint 'j9'"):
        load_model(path, tip="l2", chain=True, locks={"j9": 0.1})
    # A revolute joint off the chain, locked about a general axis: its body sits where the rotation puts it.
    text = ARM.replace("</robot>", '<link name="arm2"><inertial><origin xyz="0.1 0 0"/><mass value="0.3"/>'
                                   '</inertial></link><joint name="j4" type="revolute"><parent link="l1"/>'
                                   '<child link="arm2"/><axis xyz="0 0.6 0.8"/><limit lower="-2" upper="2"/>'
                                   '</joint></robot>')
    locked = load_model(_write(tmp_path, text, "branch.urdf"), tip="tool", chain=True, locks={"j4": 1.0})
    body = next(b for b in locked.bodies if float(b.mass) == 0.3)
    x, y, z, c, s = 0.0, 0.6, 0.8, np.cos(1.0), np.sin(1.0)  # Rodrigues: R e_x for the unit axis (0, 0.6, 0.8)
    expected = 0.1 * np.array([c + x * x * (1 - c), y * x * (1 - c) + z * s, z * x * (1 - c) - y * s])
    np.testing.assert_allclose([float(v) for v in body.com], expected, rtol=0, atol=KINEMATICS)


def test_joint_dynamics_become_friction(tmp_path):
    text = ARM.replace('<limit lower="-1.5" upper="1.5" effort="10" velocity="3"/>',
                       '<limit lower="-1.5" upper="1.5" effort="10" velocity="3"/><dynamics damping="0.25" friction="0.1"/>')
    text = text.replace('<child link="l1"/>', '<child link="l1"/><dynamics damping="0" friction="0"/>')
    model = load_model(_write(tmp_path, text))
    assert [(f.joint, f.viscous, f.coulomb) for f in model.friction] == [("j2", sympy.Rational(1, 4),
                                                                        sympy.Rational(1, 10))]
    with pytest.raises(ModelError, match="negative viscous friction") as info:
        load_model(_write(tmp_path, text.replace('damping="0.25"', 'damping="-0.25"'), "bad.urdf"))
    assert info.value.problems[0].line is not None


def test_mimic_joints_off_the_chain_follow_their_leader_and_on_the_chain_are_coupled(tmp_path):
    fingers = ARM.replace("</robot>", '<link name="f1"><inertial><origin xyz="0 0.01 0"/><mass value="0.1"/>'
                                      '</inertial></link><link name="f2"><inertial><mass value="0.1"/></inertial>'
                                      '</link><joint name="finger1" type="prismatic"><parent link="tool"/>'
                                      '<child link="f1"/><axis xyz="0 1 0"/><limit lower="0" upper="0.04"/></joint>'
                                      '<joint name="finger2" type="prismatic"><parent link="tool"/><child link="f2"/>'
                                      '<axis xyz="0 -1 0"/><limit lower="0" upper="0.08"/>'
                                      '<mimic joint="finger1" multiplier="2" offset="0.001"/></joint></robot>')
    path = _write(tmp_path, fingers, "hand.urdf")
    model = load_model(path, tip="tool", chain=True, locks={"finger1": 0.02})
    assert "finger1 = 0.02, finger2 = 0.041" in model.description
    f1, f2 = [b for b in model.bodies if float(b.mass) == 0.1]  # bodies in link order: f1, f2
    assert f1.link == f2.link == "slider"
    assert abs(float(f1.com[1]) - 0.03) < KINEMATICS  # 0.01 + 0.02 along +y
    assert abs(float(f2.com[1]) + 0.041) < KINEMATICS  # 2 * 0.02 + 0.001 along -y
    coupled = load_model(_write(tmp_path, ARM.replace('<axis xyz="1 0 0"/><limit', '<mimic joint="j2" '
                                                      'multiplier="0.5" offset="0.05"/><axis xyz="1 0 0"/><limit'),
                                "coupled.urdf"))
    assert [c.name for c in coupled.coordinates] == ["j1", "j2"]
    mimic = coupled.joints[2].coupling
    assert (mimic.leader, mimic.multiplier, mimic.offset) == ("j2", sympy.Rational(1, 2), sympy.Rational(1, 20))
    assert coupled.joints[2].follower
    # the slider's stroke [0, 0.2] bounds j2 through s = j2 / 2 + 0.05: j2 in [-0.1, 0.3]
    np.testing.assert_allclose(np.array(coordinate_range(coupled)), [[-np.pi, -0.1], [np.pi, 0.3]], rtol=0,
                               atol=KINEMATICS)


@pytest.mark.parametrize("edit, message", [
    (lambda t: t.replace('type="prismatic"', 'type="floating"'), "floating joint .* not supported"),
    (lambda t: t.replace('type="prismatic"', 'type="planar"'), "planar joint .* not supported"),
    (lambda t: t.replace('<axis xyz="1 0 0"/><limit', '<mimic joint="mount"/><axis xyz="1 0 0"/><limit'),
     "on the chain mimics 'mount', which is not a moving joint of the chain"),
    (lambda t: t.replace("</robot>", '<joint name="loop" type="fixed"><parent link="base"/><child link="l2"/>'
                                     "</joint></robot>"), "closed loop: link 'l2'"),
    (lambda t: t.replace('<child link="l2"/>', '<child link="l9"/>'), "unknown child link 'l9'"),
    (lambda t: t.replace('xyz="0.2 0 0"', 'xyz="0.2 0"'), "is not 3 number"),
    (lambda t: t.replace("</robot>", "<link name=\"l1\"/></robot>"), "duplicate link name 'l1'"),
    (lambda t: t.replace('<link name="l2">', '<link name="l2"').replace("<robot", "<robot "), "malformed XML"),
    (lambda t: t.replace('<?xml version="1.0"?>', '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "b">]>'),
     "refused: document type declarations"),
    (lambda t: t.replace('<mass value="0.5"/>', '<mass value="-0.5"/>'), "negative mass"),
])
def test_unsupported_or_malformed_urdfs_get_located_errors(tmp_path, edit, message):
    with pytest.raises(ModelError, match=message) as info:
        load_model(_write(tmp_path, edit(ARM)))
    assert all(p.line is not None for p in info.value.problems), info.value


def test_cli_derives_a_urdf_with_a_tip(tmp_path):
    path = _write(tmp_path, ARM)
    out = tmp_path / "out"
    run = subprocess.run(SYMKIN_CLI + ["derive", str(path), "--tip", "slider", "--chain", "-o", str(out), "--only",
                                       "fk,mass_matrix", "-q"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    from symkin import load

    arm = load(out / "arm")
    assert arm.mass_matrix(np.zeros(3)).shape == (3, 3)
    # What the <limit> elements declare reaches the manifest and the loaded model's info.
    limits = [(c.limits, c.velocity_limit, c.effort_limit) for c in arm.info.coordinates]
    assert limits == [(None, None, None), ((-1.5, 1.5), 3.0, 10.0), ((0.0, 0.2), 0.5, 50.0)]
    bad = subprocess.run(SYMKIN_CLI + ["derive", str(_write(tmp_path, ARM.replace('type="prismatic"', 'type="floating"'),
                                                            "bad.urdf")), "-o", str(out)],
                         capture_output=True, text=True)
    assert bad.returncode == 2
    assert "bad.urdf:" in bad.stderr
    assert "floating" in bad.stderr


def test_the_example_urdf_is_the_yaml_robot(models):
    urdf = load_model(MODELS_DIR / "ur10e.urdf")
    yaml = models["ur10e"]
    assert [float(b.mass) for b in urdf.bodies] == [float(b.mass.xreplace(yaml.parameter_values)) for b in yaml.bodies]
    d_urdf, d_yaml = Derivation(urdf), Derivation(yaml)
    rng = np.random.default_rng(50)
    q = rng.uniform(-3, 3, (3, 6))
    for name, args in (("fk", q[:1]), ("inverse_dynamics", q)):
        a = reference_function(urdf, d_urdf[name])(*args)[0]
        b = reference_function(yaml, d_yaml[name])(*args)[0]
        np.testing.assert_allclose(a, b, rtol=0, atol=DYNAMICS * max(1.0, np.abs(b).max()), err_msg=name)


def test_the_base_link_starts_the_chain(tmp_path):
    """--base l1: l1 is the fixed base, the chain is j2, j3; links outside l1's subtree are ignored."""
    path = _write(tmp_path, ARM)
    model = load_model(path, base="l1")
    assert [j.name for j in model.joints] == ["j2", "j3"]
    assert sorted(float(b.mass) for b in model.bodies) == [0.25, 0.5]  # l1 and its sensor no longer move
    with pytest.raises(ModelError, match="tip link 'l1' is not below the base link 'l2'"):
        load_model(path, base="l2", tip="l1", chain=True)
    with pytest.raises(ModelError, match="base link 'nope' is not a link"):
        load_model(path, base="nope")


def test_analysis_commands_take_a_urdf_as_a_model_file(tmp_path):
    """Issue 16: `symkin workspace robot.urdf` derived it on the fly like a YAML file instead of
    failing with "cannot read robot.urdf/manifest.json: Not a directory"."""
    run = subprocess.run(SYMKIN_CLI + ["workspace", str(MODELS_DIR / "ur10e.urdf"), "-n", "500",
                                       "-o", str(tmp_path / "ws.png")], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "ws.png").exists()
    assert "manifest.json" not in run.stderr


def test_odd_constant_frames_compose_to_numbers_and_agree_with_pinocchio(tmp_path, capsys):
    """Issue 29: a robot file's constant frames at angles such as -2.06791 (benchmarks/chain_models.py:
    fixed adapters between joints, chains of fixed covers lumped into each link) compose to numbers,
    evaluated once per cosine and sine, not to growing products of unevaluated trig (whose sign queries
    took minutes: the mass matrix of this chain did not finish in 100 s).  The emitted code holds no
    trig of a constant and stays small; Pinocchio, reading the same file, agrees."""
    import re
    import sys

    from conftest import ROOT
    from symkin.cli import main

    sys.path.insert(0, str(ROOT / "benchmarks"))
    from chain_models import chain_yaml, odd_frames_urdf

    n = 3
    path = _write(tmp_path, odd_frames_urdf(n), "odd_frames.urdf")
    dh = _write(tmp_path, chain_yaml(n), "chain.yaml")
    model = load_model(path, tip="tool", chain=True)
    assert all(sympy.sympify(v).is_Number for body in model.bodies for v in (*body.com, *body.inertia))
    out = tmp_path / "out"
    for source in ([str(path), "--tip", "tool", "--chain"], [str(dh)]):
        assert main(["derive", *source, "--only", "fk,jacobian,mass_matrix,inverse_dynamics", "--backend", "numpy",
                     "-o", str(out), "-q"]) == 0
    code = (out / f"odd_frames{n}" / f"odd_frames{n}.py").read_text()
    assert not re.search(r"\b(cos|sin)\(\s*-?[\d.(]", code), "a cosine or sine of a constant was emitted"
    # the same outputs of a generated DH chain of n joints (twists of 90 deg and 0.3 rad): general constant
    # rotations cost more terms (2.5 times the text at n = 3), products of trig of constants grow without bound
    assert len(code) < 4 * len((out / f"chain{n}" / f"chain{n}.py").read_text())
    capsys.readouterr()
    assert main(["crosscheck", str(path), "--tip", "tool", "--chain", "--samples", "5", "--backend", "numpy"]) == 0, \
        capsys.readouterr().out


def test_an_off_chain_joint_locks_at_0_clipped_into_its_limits_or_where_asked_within_them(tmp_path):
    """Issue 29: limits that exclude 0 clip the default lock (with a note naming the joint, its line and the
    option); an explicit lock outside the limits is still refused where the limits stand."""
    text = ARM.replace("</robot>", '<link name="b2"><inertial><mass value="0.1"/><origin xyz="0.1 0 0"/>'
                                   '</inertial></link><joint name="j4" type="revolute"><parent link="l1"/>'
                                   '<child link="b2"/><axis xyz="0 0 1"/><limit lower="0.5" upper="1"/></joint>'
                                   "</robot>")
    path = _write(tmp_path, text, "clipped.urdf")
    (note,) = load_model(path, tip="tool", chain=True).notes
    line = text[:text.index('<joint name="j4"')].count("\n") + 1
    assert note == (f"line {line}: joint 'j4' off the chain locked at 0.5, 0 clipped into its limits [0.5, 1] "
                    "(--lock j4=VALUE to choose)")
    assert load_model(path, tip="tool", chain=True, locks={"j4": 0.75}).notes == ()
    with pytest.raises(ModelError, match="'j4' is locked at 2, outside its limits"):
        load_model(path, tip="tool", chain=True, locks={"j4": 2.0})


VENDOR = """<?xml version="1.0"?>
<robot name="my-robot v2">
  <link name="/base_link"/>
  <link name="link.1"><inertial><mass value="1.0"/><origin xyz="0.1 0 0"/>
    <inertia ixx="0.001" iyy="0.002" izz="0.0025" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="8"><inertial><mass value="0.5"/><origin xyz="0.1 0 0.01"/>
    <inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="link_1"><inertial><mass value="0.2"/></inertial></link>
  <link name="tool0"/>
  <joint name="joint_0.0" type="revolute"><parent link="/base_link"/><child link="link.1"/>
    <axis xyz="0 0 1"/><limit lower="-1.5" upper="1.5" effort="10" velocity="2"/></joint>
  <joint name="'8'" type="revolute"><parent link="link.1"/><child link="8"/><origin xyz="0.2 0 0"/>
    <axis xyz="0 1 0"/><limit lower="-1.5" upper="1.5" effort="10" velocity="2"/></joint>
  <joint name="lambda" type="revolute"><parent link="8"/><child link="link_1"/><origin xyz="0.2 0 0"/>
    <axis xyz="1 0 0"/><limit lower="-1.5" upper="1.5" effort="10" velocity="2"/></joint>
  <joint name="flange" type="fixed"><parent link="link_1"/><child link="tool0"/><origin xyz="0.05 0 0"/></joint>
</robot>
"""


def test_vendor_names_derive_unedited_and_keep_their_names(tmp_path, capsys):
    """Issue 29: joint and link names that are not identifiers (pybullet's joint_0.0, ROS's /base_link, '8', a
    Python keyword) get code names by the documented rule (symkin.model.names.code_names; a clash with a name
    taken before gets _2), the file's names stay in the manifest, the page and the crosscheck's table, and
    Pinocchio, which reads the file's names, agrees."""
    import json

    from symkin.references.crosscheck import crosscheck
    from symkin.cli import main
    from symkin.model.names import code_names

    assert code_names(["a_b", "a.b", "a-b", "8", "lambda", "/x"], "joint") == {
        "a_b": "a_b", "a.b": "a_b_2", "a-b": "a_b_3", "8": "joint_8", "lambda": "lambda_", "/x": "x"}
    path = _write(tmp_path, VENDOR, "vendor.urdf")
    model = load_model(path)
    assert model.name == "vendor"  # the file's name: the robot's, my-robot v2, is not an identifier
    assert [j.name for j in model.joints] == ["joint_0_0", "joint_8", "lambda_"]
    assert [j.link for j in model.joints] == ["link_1_2", "link_8", "link_1"]  # link_1 is the file's own
    assert model.source_names == {"joints": {"joint_0_0": "joint_0.0", "joint_8": "'8'", "lambda_": "lambda"},
                                  "links": {"base_link": "/base_link", "link_1_2": "link.1", "link_8": "8"}}
    out = tmp_path / "out"
    assert main(["derive", str(path), "--backend", "numpy,js", "--only", "fk,frames,jacobian", "-o", str(out),
                 "-q"]) == 0
    manifest = json.loads((out / "vendor" / "manifest.json").read_text())
    assert [c.get("source_name") for c in manifest["model"]["coordinates"]] == ["joint_0.0", "'8'", "lambda"]
    assert main(["view", str(out / "vendor"), "-o", str(tmp_path / "page.html"), "--workspace", "64"]) == 0
    page = (tmp_path / "page.html").read_text()
    assert '"label":"joint_0.0"' in page
    assert '"label":"\\u00278\\u0027"' in page
    report = crosscheck(path, samples=3, backends=("numpy",))
    assert not report.failures, report.comparisons
    assert {"frame link.1", "frame 8", "frame link_1"} <= {c.quantity for c in report.comparisons}


def test_robot_files_are_told_by_their_content(tmp_path, capsys):
    """Issue 29: a URDF named .xml is read as a URDF; a xacro file (a .urdf that still holds xacro: macros)
    is expanded (tests/model/test_xacro.py); an MJCF file is read by MuJoCo's compiler (tests/model/test_mjcf.py); they
    were parsed as YAML and got YAML keys suggested. Their errors are the URDF reader's: exit code 2,
    located, nothing written."""
    from importlib.metadata import distribution

    from symkin.cli import main

    xml = _write(tmp_path, ARM, "arm.xml")
    arm_joints = [j.name for j in load_model(_write(tmp_path, ARM), tip="tool", chain=True).joints]
    assert [j.name for j in load_model(xml, tip="tool", chain=True).joints] == arm_joints
    robots = Path(distribution("example-robot-data").locate_file("cmeel.prefix/share/example-robot-data/robots"))
    macros = _write(tmp_path, ARM.replace('<robot name="arm">', '<robot name="arm" xmlns:xacro="http://ros.org/wiki/'
                                                                 'xacro"><xacro:property name="l" value="0.2"/>'),
                    "macros.urdf")
    assert [j.name for j in load_model(macros, tip="tool", chain=True).joints] == arm_joints
    mjcf = _write(tmp_path, '<mujoco model="arm"><worldbody><body name="b"/></worldbody></mujoco>', "arm_mjcf.xml")
    # the package's hector quadrotor: its macro is never called, so it expands to an empty robot (as xacro's does)
    for path, what in ((robots / "hector_description/robots/quadrotor_base.urdf.xacro", ":3:1: the robot has no links"),
                       (mjcf, ":1:1: the chain world -> b has no moving joint")):
        out = tmp_path / "out"
        assert main(["derive", str(path), "-o", str(out)]) == 2
        err = capsys.readouterr().err
        assert f"{path}{what}" in err, err
        assert "fix:" in err, err
        assert "did you mean" not in err
        assert not out.exists()
    # the URDF reader itself stops at a macro, located (one beyond what is sniffed, or text given directly)
    from symkin.model.urdf_source import urdf_document

    with pytest.raises(ModelError, match=r"macros.xml:4:\d+: a xacro element in a file read as a plain URDF") as raised:
        urdf_document(ARM.replace("<link name=\"world\"/>", "<link name=\"world\"/>\n<xacro:if value=\"1\"/>"),
                      "macros.xml")
    assert "fix: name the file .xacro" in str(raised.value)
    # an expanded URDF keeps its xmlns:xacro declaration and macros in comments: it is a URDF (the TALOS arm)
    assert load_model(robots / "talos_data/robots/talos_left_arm.urdf", tip="arm_left_7_link", chain=True).dof == 6


@pytest.mark.parametrize("written, read", [
    ("1.5707963267948966", "pi/2"), ("1.57079632679", "pi/2"), ("1.5708", "pi/2"), ("1.571", "pi/2"),
    ("3.14159", "pi"), ("-3.1416", "-pi"), ("6.28318530718", "2*pi"), ("4.71239", "3*pi/2"), ("0.7854", "pi/4"),
    ("1.0472", "pi/3"), ("0.5236", "pi/6"), ("2.0944", "2*pi/3"),
    ("2", "2"), ("1.57", "1.57"), ("1.5709", "1.5709"), ("0.1", "0.1"), ("0", "0"),   # not a rounding of one
])
def test_an_angle_is_snapped_where_it_is_a_multiple_of_pi_rounded_to_the_digits_written(written, read):
    """Issue 61: the stock UR10's 1.57079632679 is 4.9e-12 from pi/2, beyond the old 1e-12: snapping follows the
    digits written (at least four significant ones), for multiples of pi/2, pi/4, pi/3 and pi/6."""
    from symkin.model.urdf_source import snap_angle

    assert snap_angle(written) == read


def test_a_mimic_joint_on_a_side_branch_is_a_coupling_of_the_whole_tree(tmp_path):
    """Issue 61: the whole tree by default, also with a tip (the task frame: it does not cut the tree): the side
    branch is in the model and its mimic joint a coupling; with --chain to a tip that leaves it off the chain its
    links cannot be lumped (they move with a chain joint): refused, located."""
    text = ARM.replace("</robot>", '<link name="b2"/><joint name="j4" type="revolute"><parent link="l1"/>'
                                   '<child link="b2"/><axis xyz="0 0 1"/><mimic joint="j2"/></joint></robot>')
    path = _write(tmp_path, text)
    whole = load_model(path)
    assert [j.name for j in whole.joints][-1] == "j4"
    assert whole.joints[-1].coupling.leader == "j2"
    assert whole.dof == len(whole.joints) - 1
    framed = load_model(path, tip="l1")                      # the TCP on l1; j3 and j4 still move
    assert [j.name for j in framed.joints] == [j.name for j in whole.joints]
    assert framed.tip == "l1"
    whole_tree = r"arm\.urdf:2:1: at .lock. --lock j4: the model is the whole tree, where every joint moves\n *fix: add --chain"
    with pytest.raises(ModelError, match=whole_tree):
        load_model(path, tip="tool", locks={"j4": 0.1})
    with pytest.raises(ModelError, match="'j4' off the chain mimics 'j2', a joint of the chain") as info:
        load_model(path, tip="tool", chain=True)
    assert all(p.line is not None for p in info.value.problems)
