"""`symkin crosscheck` and `symkin export` (issue 13): symkin against Pinocchio on the same robot.

The example models pass (YAML through the exported URDF, the UR10e's URDF as it is), a stock
Panda passes with its fingers locked open, and a reference that disagrees fails with exit 1
naming the quantity: an exported URDF whose forearm mass was edited, read with
--reference-urdf, proves the check can fail.  The export itself is checked by reading it back
with symkin's own URDF reader.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from conftest import MODELS_DIR, SYMKIN_CLI, reference_function
from symkin.references.crosscheck import crosscheck
from symkin.derivation import Derivation
from symkin.errors import ModelError
from symkin.model import load_model
from symkin.model.urdf_export import export_urdf
from sample_models import ROBOTS_DIR
from tolerances import DYNAMICS, EPS


@pytest.mark.parametrize("name", ["planar_2r.yaml", "ur10e.yaml", "ur10e_classic.yaml", "ur10e.urdf", "phantom_premium.yaml"])
def test_the_example_models_agree_with_pinocchio(name):
    report = crosscheck(MODELS_DIR / name, samples=5)
    names = {c.quantity for c in report.comparisons}
    assert {"fk", "jacobian_geometric", "mass_matrix", "coriolis_vector", "gravity_vector",
            "inverse_dynamics"} <= names
    assert any(n.startswith("frame ") for n in names)
    assert not report.failures, report.comparisons


def test_vanishing_quantities_are_judged_by_their_natural_size():
    """Issue 29: where a quantity vanishes (V of one joint, of a leg at rest) symkin's is exactly 0 and the
    reference's recursion leaves rounding (1e-27): relative to that noise the error was 1.0, a false failure.
    The double pendulum held at its first link, as shipped: every row passes."""
    from symkin.references.crosscheck import _normwise

    assert _normwise(np.zeros(1), np.array([1e-27])) == 1.0  # relative to the noise: the old false alarm
    assert _normwise(np.zeros(1), np.array([1e-27]), None, 2.5) == pytest.approx(4e-28)
    assert _normwise(np.zeros(1), np.array([0.3]), None, 2.5) == pytest.approx(0.12)  # a real difference stays
    report = crosscheck(ROBOTS_DIR / "double_pendulum_description/urdf/double_pendulum.urdf", samples=3,
                        urdf={"tip": "link1", "chain": True}, backends=("numpy",))
    assert not report.failures, report.comparisons


def test_friction_the_coriolis_matrix_and_the_c_code_are_checked():
    """Issue 29: the file's <dynamics> enter tau (Pinocchio's damping and friction added to its RNEA) and the
    friction row; C is checked through C qd = V and Mdot - 2C skew (Mdot = C_ref + C_ref^T); and the C
    library is checked as the numpy module is."""
    report = crosscheck(ROBOTS_DIR / "double_pendulum_description/urdf/double_pendulum.urdf", samples=3,
                        urdf={"tip": "link2", "chain": True})
    rows = {c.quantity: c for c in report.comparisons}
    for row in ("friction", "inverse_dynamics", "coriolis_matrix C qd", "coriolis_matrix Mdot - 2C skew"):
        assert row in rows, row
        assert f"{row} (c)" in rows, row
        assert not rows[row].note, row
    assert not report.failures, report.comparisons


def test_a_stock_robot_with_locked_fingers_passes_on_the_command_line():
    run = subprocess.run(SYMKIN_CLI + ["crosscheck", str(ROBOTS_DIR / "panda_description/urdf/panda.urdf"), "--tip",
                                       "panda_link8", "--chain", "--lock", "panda_finger_joint1=0.03", "--samples", "4"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert "mass_matrix" in run.stdout
    assert "FAIL" not in run.stdout
    assert "frame panda_link7" in run.stdout


def test_a_stock_arm_with_a_mimic_joint_on_the_chain_passes():
    """The PR2's left arm to its finger tip: the tip joint mimics the finger joint (a parallel-jaw finger),
    so the chain has 9 joints and 8 coordinates; the other finger joints follow the finger joint off the
    chain and are locked.  Pinocchio's reference has the follower free, set at q = a q_leader + b."""
    others = ["l_gripper_r_finger_joint", "l_gripper_l_parallel_root_joint", "l_gripper_r_parallel_root_joint",
              "l_gripper_r_finger_tip_joint"]
    report = crosscheck(ROBOTS_DIR / "pr2_description/urdf/pr2.urdf", samples=4,
                        urdf={"base": "torso_lift_link", "tip": "l_gripper_l_finger_tip_link", "chain": True,
                              "locks": {name: 0.2 for name in others}})
    assert not report.failures, report.comparisons
    assert {"mass_matrix", "coriolis_vector", "gravity_vector", "frame l_gripper_l_finger_tip_link"} <= \
        {c.quantity for c in report.comparisons}


def test_a_reference_that_disagrees_fails_naming_the_quantity(tmp_path):
    exported = tmp_path / "ur10e.urdf"
    assert subprocess.run(SYMKIN_CLI + ["export", str(MODELS_DIR / "ur10e.yaml"), "-o", str(exported)]).returncode == 0
    text = exported.read_text()
    edited = tmp_path / "edited.urdf"
    forearm_mass = '<link name="forearm__body2">\n    <inertial><mass value="'
    assert forearm_mass in text
    edited.write_text(text.replace(forearm_mass + "3.989", forearm_mass + "4.2"))
    run = subprocess.run(SYMKIN_CLI + ["crosscheck", str(MODELS_DIR / "ur10e.yaml"), "--reference-urdf", str(edited),
                                       "--samples", "3"], capture_output=True, text=True)
    assert run.returncode == 1, run.stdout + run.stderr
    assert "crosscheck failed" in run.stderr
    assert "mass_matrix" in run.stderr
    assert "fk (" not in run.stderr


def test_the_exported_urdf_reads_back_as_the_same_robot(tmp_path):
    """symkin's own reader on the exported file: the same M and tau as the YAML model."""
    yaml = load_model(MODELS_DIR / "ur10e.yaml")
    path = tmp_path / "ur10e.urdf"
    path.write_text(export_urdf(yaml))
    urdf = load_model(path, tip="tcp", chain=True)
    assert [j.name for j in urdf.joints] == [j.name for j in yaml.joints]
    rng = np.random.default_rng(3)
    for _ in range(4):
        q, qd, qdd = (rng.uniform(-2, 2, 6) for _ in range(3))
        for name, args in (("mass_matrix", (q,)), ("inverse_dynamics", (q, qd, qdd))):
            a = reference_function(urdf, Derivation(urdf)[name])(*args)[0]
            b = reference_function(yaml, Derivation(yaml)[name])(*args)[0]
            assert np.max(np.abs(a - b)) <= DYNAMICS * np.max(np.abs(b)), name


def test_a_model_file_named_with_dashes_exports_a_well_formed_urdf(tmp_path):
    """The exported URDF's comment names the model file, hostile text: 'my--arm.yaml' once made the document
    malformed (XML allows no '--' in a comment); it reads back with its comment in one piece."""
    path = tmp_path / "my--arm-->.yaml"
    path.write_text((MODELS_DIR / "planar_2r.yaml").read_text())
    exported = tmp_path / "arm.urdf"
    exported.write_text(export_urdf(load_model(path)))
    assert [j.name for j in load_model(exported, tip="tcp", chain=True).joints] == ["theta1", "theta2"]


def test_export_refuses_a_parallel_model_and_crosscheck_says_when_pinocchio_is_missing(tmp_path, monkeypatch):
    run = subprocess.run(SYMKIN_CLI + ["export", str(MODELS_DIR / "delta.yaml"), "-o", str(tmp_path / "d.urdf")],
                         capture_output=True, text=True)
    assert run.returncode == 2
    assert "closed loops" in run.stderr
    assert not (tmp_path / "d.urdf").exists()
    monkeypatch.setitem(sys.modules, "pinocchio", None)  # import pinocchio raises ImportError
    with pytest.raises(ModelError, match="'pinocchio' is not installed"):
        crosscheck(MODELS_DIR / "planar_2r.yaml", samples=1)


def generated_chain(joints: int, seed: int) -> str:
    """A URDF chain nobody here wrote by hand: ``joints`` joints (every third prismatic) about random unit axes
    (tilted, not along x, y or z), placed at random origins and rotations, each link a random physical body."""
    rng = np.random.default_rng(seed)
    links, chain, parent = ['<link name="base"/>'], [], "base"
    for k in range(1, joints + 1):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        xyz, rpy = rng.uniform(-0.2, 0.2, 3), rng.uniform(-np.pi, np.pi, 3)
        moments, com, mass = rng.uniform(0.5, 1.0, 3) * 1e-3, rng.uniform(-0.05, 0.05, 3), rng.uniform(0.2, 1.0)
        kind = "prismatic" if k % 3 == 0 else "revolute"
        text = lambda v: " ".join(f"{x:.6f}" for x in v)  # noqa: E731
        links.append(f'<link name="l{k}"><inertial><origin xyz="{text(com)}"/><mass value="{mass:.6f}"/>'
                     f'<inertia ixx="{moments[0]:.6e}" iyy="{moments[1]:.6e}" izz="{moments[2]:.6e}" ixy="0" ixz="0" '
                     'iyz="0"/></inertial></link>')
        chain.append(f'<joint name="j{k}" type="{kind}"><parent link="{parent}"/><child link="l{k}"/>'
                     f'<origin xyz="{text(xyz)}" rpy="{text(rpy)}"/><axis xyz="{text(axis)}"/>'
                     '<limit lower="-1" upper="1" effort="10" velocity="1"/></joint>')
        parent = f"l{k}"
    return '<?xml version="1.0"?>\n<robot name="generated">\n' + "\n".join(links + chain) + "\n</robot>\n"


@pytest.mark.parametrize("joints", [1, 3, 8])
def test_a_generated_chain_of_any_length_with_tilted_axes_agrees_with_pinocchio(joints, tmp_path):
    """Issue 61: a one-joint URDF with a tilted axis ended in a traceback (Pinocchio returns its 6 x 1 Jacobian as a
    vector); chains of 1 to 8 joints agree with Pinocchio on fk, every frame, J and the dynamics."""
    path = tmp_path / f"chain{joints}.urdf"
    path.write_text(generated_chain(joints, seed=joints))
    report = crosscheck(path, samples=3, backends=("numpy",), coriolis_matrix=False)
    assert not report.failures, report
    assert {"fk", "jacobian_geometric", "mass_matrix", "inverse_dynamics"} <= {c.quantity for c in report.comparisons}


def test_crosscheck_feeds_pinocchio_the_snapped_geometry():
    """Issue 61: with --snap-angles symkin reads the UR10's 1.57079632679 as pi/2; Pinocchio reads the same file
    with those angles rewritten as the doubles nearest the multiples, so the two agree to rounding, not to 5e-12."""
    path = ROBOTS_DIR / "ur_description/urdf/ur10_robot.urdf"
    report = crosscheck(path, samples=3, backends=("numpy",), coriolis_matrix=False,
                        urdf={"tip": "tool0", "snap_angles": True})
    assert not report.failures, report
    assert max(c.error for c in report.comparisons) < 64 * EPS      # rounding, not the 4.9e-12 of the file


@pytest.mark.parametrize("file, joints, dof", [
    ("panda_description/urdf/panda.urdf", 9, 8),            # the arm and its fingers, the second mimicking the first
    ("baxter_description/urdf/baxter.urdf", 19, 17),        # head, two arms, two grippers with mimic fingers
])
def test_a_stock_whole_tree_with_mimic_joints_passes_with_no_flags(file, joints, dof):
    """Issue 61: 'symkin crosscheck baxter.urdf' stopped at 'name the tip' and, with --tip and --branch, at the
    grippers' mimic joints; without --tip a robot file is the whole tree, its mimic joints couplings, and it agrees
    with Pinocchio's model of the whole file, every link's pose and Jacobian included."""
    model = load_model(ROBOTS_DIR / file)
    assert (len(model.joints), model.dof) == (joints, dof)
    report = crosscheck(ROBOTS_DIR / file, samples=2, backends=("numpy",), coriolis_matrix=False)
    assert not report.failures, report
    # every link's Jacobian (frame_jacobians), not only the TCP's, against Pinocchio's frame Jacobian
    checked = {c.quantity for c in report.comparisons if c.quantity.startswith("frame_jacobians ")}
    assert len(checked) == joints, checked
