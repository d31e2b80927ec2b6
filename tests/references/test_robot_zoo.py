"""Stock robot files in, unedited: every serial arm of the ``example-robot-data`` package
derives and agrees with Pinocchio (issue 13).

The URDFs are the package's, as shipped (grippers, heads, cameras, mimic fingers and all);
nobody here wrote or edited them.  symkin reads each with a tip link (or its default tip),
locks every joint off the chain at 0 and lumps what it carries into the chain
(:mod:`symkin.model.urdf_source`).  Pinocchio reads the same file whole; its quantities for
the chain are those of its reduced model (``buildReducedModel`` with the same joints locked
at the same values): the chain's rows and columns of M and J, and of V + G with the locked
joints at rest, at the configuration with the locked joints at 0.  The comparison uses the
full model's blocks rather than ``buildReducedModel`` itself, which refuses files with two
frames of one name (the SO-100 arm).

Both sides are exact methods (symbolic Lagrange-equivalent derivation; CRBA/RNEA) on chains
of <= 7 joints, so they differ by rounding only: KINEMATICS and DYNAMICS of
tests/tolerances.py, normwise relative to the reference.  A missing package is a failure,
not a skip: ``example-robot-data`` is a test dependency (pyproject's test extra).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from conftest import reference_function
from symkin.derivation import Derivation
from symkin.model import load_model
from tolerances import DYNAMICS, KINEMATICS
from sample_models import ROBOTS_DIR


#: (file under the package's robots/, tip link or None for symkin's default tip, joints symkin keeps).
ZOO = [
    ("panda_description/urdf/panda.urdf", "panda_link8", 7),  # hand and mimic fingers beyond the tip
    ("z1_description/urdf/z1.urdf", "link06", 6),  # the gripper joint branches off the chain
    ("ur_description/urdf/ur3_robot.urdf", "tool0", 6),
    ("ur_description/urdf/ur5_robot.urdf", "tool0", 6),
    ("ur_description/urdf/ur10_robot.urdf", "tool0", 6),
    ("kinova_description/robots/kinova.urdf", "j2s6s200_end_effector", 6),  # two fingers, finger tips
    ("talos_data/robots/talos_left_arm.urdf", "arm_left_7_link", 6),  # the gripper and its mimic joints
    ("baxter_description/urdf/baxter.urdf", "left_hand_link", 7),  # head, sonar, right arm, grippers
    ("so_arm_description/urdf/so100.urdf", None, 6),
    ("so_arm_description/urdf/so101.urdf", None, 6),
    ("xarm_description/urdf/xarm7.urdf", None, 7),
]


def _normwise(got: np.ndarray, want: np.ndarray) -> float:
    return float(np.linalg.norm(np.asarray(got) - want) / np.linalg.norm(want))


@pytest.mark.parametrize("file, tip, dof", ZOO, ids=[Path(f).stem for f, _, _ in ZOO])
def test_a_stock_robot_file_derives_and_agrees_with_pinocchio(file, tip, dof):
    path = ROBOTS_DIR / file
    model = load_model(path, tip=tip, chain=True)
    assert model.dof == dof
    d = Derivation(model)
    fk, J = reference_function(model, d["fk"]), reference_function(model, d["jacobian_geometric"])
    M, V, G = (reference_function(model, d[name]) for name in ("mass_matrix", "coriolis_vector", "gravity_vector"))
    full = pin.buildModelFromUrdf(str(path))
    data = full.createData()
    chain = [full.joints[full.getJointId(j.name)] for j in model.joints]
    columns = [joint.idx_v for joint in chain]
    frame = full.getFrameId(tip or model.joints[-1].link)
    # <dynamics damping friction> as Pinocchio reads it (model.damping, model.friction), exactly
    friction = {f.joint: (float(f.viscous), float(f.coulomb)) for f in model.friction}
    assert [friction.get(j.name, (0.0, 0.0)) for j in model.joints] == \
        [(full.damping[c], full.friction[c]) for c in columns], file
    rng = np.random.default_rng(13)
    for _ in range(5):
        q, qd = rng.uniform(-1.5, 1.5, dof), rng.uniform(-1.0, 1.0, dof)
        q_full, v_full = pin.neutral(full), np.zeros(full.nv)  # locked joints at 0, at rest
        for joint, angle, rate in zip(chain, q, qd):
            q_full[joint.idx_q:joint.idx_q + joint.nq] = [np.cos(angle), np.sin(angle)] if joint.nq == 2 else [angle]
            v_full[joint.idx_v] = rate
        pin.forwardKinematics(full, data, q_full)
        pin.updateFramePlacements(full, data)
        mass = pin.crba(full, data, q_full)
        mass = (np.triu(mass) + np.triu(mass, 1).T)[np.ix_(columns, columns)]
        jacobian = pin.computeFrameJacobian(full, data, q_full, frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        assert _normwise(fk(q)[0], data.oMf[frame].homogeneous) < KINEMATICS, (file, "fk", q)
        assert _normwise(J(q)[0], jacobian[:, columns]) < KINEMATICS, (file, "J", q)
        assert _normwise(M(q)[0], mass) < DYNAMICS, (file, "M", q)
        assert _normwise(G(q)[0], pin.computeGeneralizedGravity(full, data, q_full)[columns]) < DYNAMICS, (file, "G")
        assert _normwise(V(q, qd)[0] + G(q)[0], pin.nonLinearEffects(full, data, q_full, v_full)[columns]) < DYNAMICS


#: The zoo's arms whose files hold no joint off the chain (Pinocchio's model is the chain itself, fixed joints
#: merged into their parents as symkin lumps them): their bodies are the same, parameter for parameter.
WHOLE_CHAINS = [entry for entry in ZOO if Path(entry[0]).stem in ("ur3_robot", "ur5_robot", "ur10_robot", "kinova",
                                                                    "so100", "so101", "xarm7")]


@pytest.mark.parametrize("file, tip, dof", WHOLE_CHAINS, ids=[Path(f).stem for f, _, _ in WHOLE_CHAINS])
def test_the_regressor_of_a_stock_arm_is_pinocchios(file, tip, dof):
    """Issue 33's reference on files nobody here wrote: symkin's regressor Y (its 10 inertial columns per link,
    Pinocchio's order) is computeJointTorqueRegressor's, joint for joint, and pi's inertial entries are each body's
    toDynamicParameters (a URDF's joint frame is its child link's: the same origin and axes), to DYNAMICS of the
    torques' scale (a chain of <= 7 joints, tests/tolerances.py)."""
    path = ROBOTS_DIR / file
    model = load_model(path, tip=tip, chain=True)
    full = pin.buildModelFromUrdf(str(path))
    assert full.nv == model.dof == dof, file
    data = full.createData()
    chain = [full.joints[full.getJointId(j.name)] for j in model.joints]
    rows = [joint.idx_v for joint in chain]
    columns = [10 * (full.getJointId(j.name) - 1) + k for j in model.joints for k in range(10)]
    Y_pi = reference_function(model, Derivation(model)["regressor"])
    rng = np.random.default_rng(33)
    for _ in range(3):
        q, qd, qdd = rng.uniform(-1.5, 1.5, dof), rng.uniform(-1, 1, dof), rng.uniform(-3, 3, dof)
        q_full, v_full, a_full = pin.neutral(full), np.zeros(full.nv), np.zeros(full.nv)
        for joint, angle, rate, acceleration in zip(chain, q, qd, qdd):
            q_full[joint.idx_q:joint.idx_q + joint.nq] = [np.cos(angle), np.sin(angle)] if joint.nq == 2 else [angle]
            v_full[joint.idx_v], a_full[joint.idx_v] = rate, acceleration
        want = pin.computeJointTorqueRegressor(full, data, q_full, v_full, a_full)[np.ix_(rows, columns)]
        Y, pi = Y_pi(q, qd, qdd)
        scale = float(np.max(np.abs(want)))
        np.testing.assert_allclose(Y[:, :10 * dof], want, rtol=0, atol=DYNAMICS * scale, err_msg=file)
    bodies = np.concatenate([full.inertias[full.getJointId(j.name)].toDynamicParameters() for j in model.joints])
    np.testing.assert_allclose(pi[:10 * dof], bodies, rtol=0, atol=DYNAMICS * float(np.max(np.abs(bodies))),
                               err_msg=file)


def test_the_zoo_reads_every_serial_arm_the_package_ships():
    """The issue's list: panda, z1, ur3/5/10, kinova, talos arm, baxter arm, so-arm, xarm."""
    shipped = {p.relative_to(ROBOTS_DIR).as_posix() for p in ROBOTS_DIR.rglob("*.urdf")}
    assert {file for file, _, _ in ZOO} <= shipped
    for family in ("panda", "z1", "ur3", "ur5", "ur10", "kinova", "talos", "baxter", "so100", "xarm"):
        assert any(family in file for file, _, _ in ZOO), family


@pytest.mark.parametrize("file, tip, dof", ZOO, ids=[Path(f).stem for f, _, _ in ZOO])
def test_symkin_crosscheck_passes_on_every_zoo_robot(file, tip, dof):
    """Issue 13's acceptance, through the command's own code: its table for every zoo robot passes
    (frames of every link, J, M, V, G, and tau where the file declares no joint friction)."""
    from symkin.references.crosscheck import crosscheck

    # the C library and the Coriolis matrix: test_crosscheck (deriving C for every zoo arm costs a minute)
    report = crosscheck(ROBOTS_DIR / file, samples=3, urdf={"tip": tip, "chain": True}, backends=("numpy",), coriolis_matrix=False)
    assert not report.failures, report.comparisons
    assert {"fk", "jacobian_geometric", "mass_matrix", "coriolis_vector", "gravity_vector"} <= \
        {c.quantity for c in report.comparisons}


def test_off_chain_joints_whose_limits_exclude_0_lock_at_the_nearest_limit():
    """Issue 29: iCub's right elbow (limits [0.0959931, 1.85005]) is locked, unasked, at its lower limit and
    the reading says so; its head's lone product of inertia of 2.4e-35 is rounding, not a refusal.  The
    left arm, as shipped, agrees with Pinocchio reduced at the same locks."""
    from symkin.references.crosscheck import crosscheck

    path = ROBOTS_DIR / "icub_description/robots/icub_reduced.urdf"
    model = load_model(path, tip="l_hand_dh_frame", chain=True)
    clipped = [note for note in model.notes if "'r_elbow'" in note]
    assert len(clipped) == 1
    assert "locked at 0.0959931" in clipped[0]
    assert "--lock r_elbow=VALUE" in clipped[0]
    report = crosscheck(path, samples=3, urdf={"tip": "l_hand_dh_frame", "chain": True}, backends=("numpy",))
    assert not report.failures, report.comparisons


def test_non_physical_inertias_are_refused_or_accepted_with_a_note(tmp_path, capsys):
    """Issue 29: romeo_small's wrist inertias violate the triangle inequality by up to 340 %: the outputs that use
    them are refused with a located message that names --allow-nonphysical (issue 61: only those - its kinematics
    derive, noted); with it, the arm's dynamics derive, the notes are printed and kept in the manifest, and Pinocchio
    (which loads the file as it is) agrees."""
    import json

    from symkin.references.crosscheck import crosscheck
    from symkin.cli import main

    path = str(ROBOTS_DIR / "romeo_description/urdf/romeo_small.urdf")
    assert main(["check", path, "--tip", "l_gripper", "--chain"]) == 0                   # the scene: fk and J
    assert main(["derive", path, "--tip", "l_gripper", "--chain", "--only", "fk,jacobian", "-o", str(tmp_path / "kin")]) == 0
    assert "not physical" in capsys.readouterr().out                           # noted
    assert main(["derive", path, "--tip", "l_gripper", "--chain", "--only", "mass_matrix", "-o", str(tmp_path / "m")]) == 2
    assert not (tmp_path / "m").exists()
    err = capsys.readouterr().err
    assert f"{path}:547:" in err
    assert "not physical" in err
    assert "--allow-nonphysical" in err
    out = tmp_path / "out"
    assert main(["derive", path, "--tip", "l_gripper", "--chain", "--allow-nonphysical", "--only", "fk", "-o", str(out)]) == 0
    printed = [line for line in capsys.readouterr().out.splitlines() if line.startswith("  note:")]
    manifest = json.loads((out / "romeo" / "manifest.json").read_text())
    assert len(printed) == len(manifest["model"]["notes"]) == 2
    assert all("not physical" in note and "line " in note and path not in note for note in manifest["model"]["notes"])
    report = crosscheck(path, samples=3, urdf={"tip": "l_gripper", "chain": True, "allow_nonphysical": True}, backends=("numpy",))
    assert not report.failures, report.comparisons
