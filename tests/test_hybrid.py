"""Hybrid devices (models/delta_wrist.yaml): a DELTA whose platform carries a 3R wrist.

Independent oracles: Pinocchio's kinematics of the same device built here joint by joint (the platform's
translation as three prismatic joints, then the wrist), the wrist written out as rotation matrices, finite
differences through the DELTA's closed-form fk, and the located errors of wrist sections that cannot work.
"""

from __future__ import annotations

import subprocess

import numpy as np
import pinocchio as pin
import pytest

from conftest import MODELS_DIR, SYMKIN_CLI
from symkin import load, load_model
from symkin.derivation import Derivation
from symkin.errors import DerivationError, ModelError
from tolerances import DELTA_SCALE, KINEMATICS

W, H = 0.05, 0.03  # wrist centre below the platform, grip point along the handle (models/delta_wrist.yaml)


@pytest.fixture(scope="module")
def device(generated_dir):
    return load(generated_dir / "delta_wrist")


def rot(axis: str, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return {"x": np.array([[1, 0, 0], [0, c, -s], [0, s, c]]), "y": np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
            "z": np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])}[axis]


def written_out(p: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """base_T_tcp: the platform at p (no rotation), down w to the wrist centre, Rz(psi1) Rx(psi2) Ry(psi3),
    the grip point h along the handle's y axis."""
    R = rot("z", psi[0]) @ rot("x", psi[1]) @ rot("y", psi[2])
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = p + np.array([0, 0, -W]) + R @ np.array([0, H, 0])
    return T


def pinocchio_device() -> tuple[pin.Model, int]:
    """The device as Pinocchio's serial chain in (x, y, z, psi1, psi2, psi3), and its TCP frame."""
    model = pin.Model()
    parent = 0
    for name, joint in (("x", pin.JointModelPX()), ("y", pin.JointModelPY()), ("z", pin.JointModelPZ())):
        parent = model.addJoint(parent, joint, pin.SE3.Identity(), name)
    wrist_centre = pin.SE3(np.eye(3), np.array([0, 0, -W]))
    parent = model.addJoint(parent, pin.JointModelRZ(), wrist_centre, "psi1")
    parent = model.addJoint(parent, pin.JointModelRX(), pin.SE3.Identity(), "psi2")
    parent = model.addJoint(parent, pin.JointModelRY(), pin.SE3.Identity(), "psi3")
    tool = model.addFrame(pin.Frame("tcp", parent, 0, pin.SE3(np.eye(3), np.array([0, H, 0])), pin.FrameType.OP_FRAME))
    return model, tool


def random_device_states(device, count: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q, p, psi): assembled DELTA poses around the home pose (q = ik(p)) and wrist angles within the limits."""
    rng = np.random.default_rng(seed)
    p = np.array([0, 0, -0.15]) + rng.uniform(-0.04, 0.04, (count, 3))
    q, margin = device.ik(p)
    keep = np.all(margin > 0, axis=-1)
    psi = rng.uniform(np.deg2rad([-120, -70, -160]), np.deg2rad([120, 70, 160]), (count, 3))
    return q[keep], p[keep], psi[keep]


def test_the_device_moves_by_its_platform_and_its_wrist(models):
    model = models["delta_wrist"]
    wrist = model.parallel.wrist
    assert [j.name for j in wrist.coordinates] == ["psi1", "psi2", "psi3"]
    assert model.task_space == ("x", "y", "z") and model.dof == 3  # the legs' actuators; the wrist's joints on top


def test_device_fk_and_jacobian_agree_with_pinocchio_and_the_written_out_wrist(device):
    q, p, psi = random_device_states(device, 60, seed=1)
    model, tool = pinocchio_device()
    data = model.createData()
    T = device.device_fk(p, psi)
    J_c = device.device_jacobian(p, psi)
    for k in range(len(p)):
        c = np.concatenate([p[k], psi[k]])
        pin.forwardKinematics(model, data, c)
        pin.updateFramePlacements(model, data)
        assert np.allclose(T[k], data.oMf[tool].homogeneous, rtol=0, atol=KINEMATICS * DELTA_SCALE)
        assert np.allclose(T[k], written_out(p[k], psi[k]), rtol=0, atol=KINEMATICS * DELTA_SCALE)
        J_pin = pin.computeFrameJacobian(model, data, c, tool, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        assert np.allclose(J_c[k], J_pin, rtol=0, atol=KINEMATICS * DELTA_SCALE)


def test_the_actuator_jacobian_is_the_chain_rule_through_the_platform(device):
    q, p, psi = random_device_states(device, 40, seed=2)
    J_a = device.device_actuator_jacobian(q, p, psi)
    J_c = device.device_jacobian(p, psi)
    J = device.jacobian(q, p)
    kappa = np.linalg.cond(J)
    chain_rule = np.concatenate([J_c[..., :3] @ J, J_c[..., 3:]], axis=-1)
    assert np.all(np.max(np.abs(J_a - chain_rule), axis=(-2, -1)) <= KINEMATICS * DELTA_SCALE * kappa)
    # finite differences of the TCP position through the DELTA's closed-form fk: p = fk(q), then the wrist
    h = 1e-6
    columns = []
    for e in np.eye(6):
        up, _ = device.fk(q + h * e[:3])
        down, _ = device.fk(q - h * e[:3])
        columns.append((device.device_fk(up, psi + h * e[3:])[..., :3, 3]
                        - device.device_fk(down, psi - h * e[3:])[..., :3, 3]) / (2 * h))
    # central differences: truncation h^2 |f'''| / 6 and rounding eps L / h, both below 1e-9 m per rad here
    assert np.allclose(J_a[..., :3, :], np.stack(columns, axis=-1), rtol=0, atol=1e-8)


def test_a_delta_without_wrist_has_no_device_quantities(models):
    with pytest.raises(DerivationError, match="carries no wrist"):
        Derivation(models["delta"])["device_fk"]


@pytest.mark.parametrize("edit, message", [
    (("- {name: psi1,", "- {name: theta1,"), "clashes with the variable 'theta1'"),
    (("link: fork2,", "link: platform,"), "the wrist link 'platform' is a name the platform's motion takes"),
    (("  chain:\n    - {name: psi1", "  chain:\n    - {name: psi1, parent: nowhere"), "hangs on 'nowhere'"),
    (("      inertia: {yy: m_handle", "      inertia: {yy: -m_handle"), "wrist.bodies[2].inertia"),
])
def test_a_wrist_that_cannot_work_is_a_located_error(tmp_path, edit, message):
    text = (MODELS_DIR / "delta_wrist.yaml").read_text()
    assert edit[0] in text
    path = tmp_path / "device.yaml"
    path.write_text(text.replace(edit[0], edit[1], 1))
    with pytest.raises(ModelError, match=message.replace("[", r"\[").replace("(", r"\(")):
        load_model(path)


def test_a_wrist_on_a_serial_chain_is_refused_on_the_command_line(tmp_path):
    path = tmp_path / "arm.yaml"
    path.write_text((MODELS_DIR / "planar_2r.yaml").read_text() + "\nwrist:\n  chain:\n    - {name: w1}\n")
    run = subprocess.run([*SYMKIN_CLI, "check", str(path)], capture_output=True, text=True)
    assert run.returncode == 2
    assert "a wrist is carried by a parallel platform" in run.stderr and "arm.yaml" in run.stderr
