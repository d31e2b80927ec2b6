"""The run-time mechanism of a loaded model in its actuated joints (symkin.mechanism.actuated, issue 62): one
object answers the assembly (the platform pose at the actuators) and the handle for an open chain, a closed-form
platform, a platform whose pose only Newton's method gives (the Stewart-Gough platform) and a hybrid device, and
binds the generated functions to the device's joints.

References: the closed-form ik (the pose the actuators were computed from: Newton must return it, to its tolerance
times the conditioning of the leg equations), the generated functions called with the pose by hand.
"""

from __future__ import annotations

import numpy as np
import pytest

from symkin.mechanism.actuated import Mechanism
from tolerances import KINEMATICS, NEWTON


def test_an_open_chain_has_no_pose_and_its_functions_take_its_joints_as_they_are(loaded):
    ur = loaded("ur10e", "numpy")
    arm = Mechanism(ur)
    q = np.random.default_rng(0).uniform(-1.0, 1.0, (4, 6))
    assert not arm.has_pose
    assert not arm.inverse_in_closed_form
    assert not arm.turns_only
    assert arm.assembles(q[0])
    assert arm.dof == 6
    assert arm.task_space == ur.info.task_space
    assert arm.function("mass_matrix") == ur.mass_matrix  # bound as it is: nothing to add
    np.testing.assert_array_equal(arm.handle_position(q, np.array([0, 1, 2])), ur.fk(q)[..., :3, 3])
    assert arm.info.coordinates == ur.info.coordinates


def test_a_platform_takes_its_pose_from_fk_and_its_functions_get_it(loaded):
    delta = loaded("delta", "numpy")
    platform = Mechanism(delta)
    q = np.radians([[-15.0, -10.0, -20.0], [-5.0, -25.0, -15.0]])
    p = delta.fk(q).position
    np.testing.assert_array_equal(platform.pose(q), p)
    assert platform.has_pose
    assert platform.inverse_in_closed_form
    assert platform.assembles(q[0])
    np.testing.assert_array_equal(platform.function("mass_matrix")(q), delta.mass_matrix(q, p))
    s, pose = platform.assembly(q)
    assert s.shape == (2, 0)
    np.testing.assert_array_equal(pose, p)
    # the declared branch: ik(fk(q)) = q, to the closed forms' rounding (KINEMATICS) amplified by kappa(J)
    kappa = max(np.linalg.cond(delta.jacobian(q, p)))
    np.testing.assert_allclose(platform.joints_at(p, q[0]), q, rtol=0, atol=kappa * KINEMATICS)
    assert platform.unassembled == "fk has no solution"


def test_a_platform_without_a_closed_form_fk_is_assembled_by_newton_along_a_run(loaded):
    """The Stewart-Gough platform: poses near home, their leg lengths by the closed-form ik, and Newton from the home
    pose (each row that does not converge from there, from the previous row's pose) returns them; the tolerance is
    Newton's stop times the leg equations' conditioning near home (kappa(J^-1) < 1e2 there: the rating's usable
    workspace starts at 1/kappa = 0.05)."""
    stewart = loaded("stewart", "numpy")
    platform = Mechanism(stewart)
    home = np.array(stewart.info.home, dtype=float)
    steps = np.linspace(0.0, 1.0, 5)[:, None] * np.array([0.01, -0.01, 0.02, 0.05, -0.03, 0.1])
    poses = home + steps
    q = stewart.ik(poses).joints
    kappa = max(np.linalg.cond(stewart.inverse_jacobian(q, poses)))
    assert kappa < 1e2
    np.testing.assert_allclose(platform.pose(q), poses, rtol=0, atol=kappa * NEWTON * max(1.0, np.abs(home).max()))
    assert platform.unassembled == "Newton's method on the leg equations does not converge"


def test_a_hybrid_device_binds_the_legs_and_the_wrist_and_its_handle_is_the_wrists(loaded):
    device = loaded("delta_wrist", "numpy")
    whole = Mechanism(device)
    legs, wrist = len(device.info.coordinates), len(device.info.wrist)
    assert whole.dof == legs + wrist
    assert whole.task_space == ("x", "y", "z", "wx", "wy", "wz")
    assert whole.info.coordinate_names == tuple(c.name for c in device.info.coordinates + device.info.wrist)
    z = np.concatenate([np.radians([-15.0, -10.0, -20.0]), [0.1, -0.2, 0.3]])
    p = device.fk(z[:legs]).position
    np.testing.assert_array_equal(whole.function("mass_matrix")(z), device.mass_matrix(z[:legs], p, z[legs:]))
    np.testing.assert_array_equal(whole.handle_position(z, np.array([0, 1, 2])),
                                  device.device_fk(p, z[legs:])[:3, 3])
    platform, angular = whole.split_conditioning(z)
    assert platform.shape == (3, 3)
    assert angular.shape == (3, wrist)


@pytest.mark.parametrize("name", ["planar_2r", "pantograph", "agile_eye"])
def test_every_mechanism_answers_the_handle(loaded, name):
    model = loaded(name, "numpy")
    mechanism = Mechanism(model)
    assert mechanism.turns_only == (name == "agile_eye")
    assert mechanism.task_space == model.info.task_space
    assert mechanism.task_jacobian_function == "jacobian"
    assert mechanism.handle_functions == {"fk", "jacobian"}
