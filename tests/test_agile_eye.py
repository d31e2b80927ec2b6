"""The Agile Eye (models/agile_eye.yaml): a spherical 3-RRR platform, the distance form on the unit sphere.

Independent oracles: the Agile Eye's inverse kinematics in closed form from the rotation matrix (each leg's
middle axis perpendicular to its platform axis: theta_1 = atan2(-R23, R33), theta_2 = atan2(-R31, R11),
theta_3 = atan2(-R12, R22); Bonev, Chablat and Wenger 2006), finite differences of it, and rotation matrices
composed here with numpy.
"""

from __future__ import annotations

import os
import subprocess

import numpy as np
import pytest

from symkin import load, load_model
from symkin.analysis import orientations
from symkin.errors import DerivationError
from symkin.derivation import Derivation
from symkin.model.schema import PlatformMotion
from symkin.runtime.parallel import solve_fk
from symkin.structure.mobility import model_mobility
from conftest import MODELS_DIR, SYMKIN_CLI
from tolerances import CLOSED_FORM, KINEMATICS, NEWTON


@pytest.fixture(scope="module")
def eye(generated_dir):
    return load(generated_dir / "agile_eye")


def rotation(p):
    """R = Rz(yaw) Ry(pitch) Rx(roll) of rows p = (roll, pitch, yaw)."""
    roll, pitch, yaw = np.moveaxis(np.asarray(p), -1, 0)
    c, s = np.cos, np.sin
    return np.stack([
        np.stack([c(yaw) * c(pitch), c(yaw) * s(pitch) * s(roll) - s(yaw) * c(roll),
                  c(yaw) * s(pitch) * c(roll) + s(yaw) * s(roll)], axis=-1),
        np.stack([s(yaw) * c(pitch), s(yaw) * s(pitch) * s(roll) + c(yaw) * c(roll),
                  s(yaw) * s(pitch) * c(roll) - c(yaw) * s(roll)], axis=-1),
        np.stack([-s(pitch), c(pitch) * s(roll), c(pitch) * c(roll)], axis=-1)], axis=-2)


def agile_eye_ik(p):
    R = rotation(p)
    return np.stack([np.arctan2(-R[..., 1, 2], R[..., 2, 2]), np.arctan2(-R[..., 2, 0], R[..., 0, 0]),
                     np.arctan2(-R[..., 0, 1], R[..., 1, 1])], axis=-1)


def random_orientations(seed, count, spread=0.5):
    return np.random.default_rng(seed).uniform(-spread, spread, (count, 3))


def test_the_model_is_spherical_with_lambda_three(models):
    parallel = models["agile_eye"].parallel
    assert parallel.motion is PlatformMotion.SPHERICAL
    assert parallel.coordinates == ("roll", "pitch", "yaw")
    report = model_mobility(models["agile_eye"])
    assert (report.lam, report.bodies, report.joints, report.mobility) == (3, 8, 9, 3)


def test_inverse_kinematics_is_the_agile_eyes_closed_form(eye):
    p = random_orientations(1, 500)
    q, margin = eye.ik(p)
    assert np.all(margin > 0)
    assert np.max(np.abs(q - agile_eye_ik(p))) <= 4 * CLOSED_FORM


def test_the_home_orientation_is_isotropic(eye):
    p = np.zeros(3)
    q = eye.ik(p).joints
    assert np.allclose(q, 0.0, atol=CLOSED_FORM)
    assert np.allclose(eye.jacobian(q, p), np.eye(3), atol=CLOSED_FORM)


def test_inverse_jacobian_matches_finite_differences_of_the_closed_form(eye):
    p = random_orientations(2, 40)
    h = 1e-6
    J_fd = np.stack([(agile_eye_ik(p + h * e) - agile_eye_ik(p - h * e)) / (2 * h) for e in np.eye(3)], axis=-1)
    J_inv = eye.inverse_jacobian(agile_eye_ik(p), p)
    # central differences: truncation h^2 |q'''| / 6 ~ 1e-12, rounding eps / h ~ 2e-10
    assert np.allclose(J_inv, J_fd, rtol=0, atol=1e-8)
    assert np.allclose(np.einsum("...ij,...jk->...ik", eye.jacobian(agile_eye_ik(p), p), J_inv), np.eye(3), atol=1e-9)


def test_forward_kinematics_by_newton_returns_the_orientation(eye):
    p = random_orientations(3, 200)
    q = eye.ik(p).joints
    report = solve_fk(eye, q, np.zeros(3))
    assert report.all_converged
    kappa = np.linalg.cond(eye.inverse_jacobian(q, p))
    error = np.max(np.abs(rotation(report.solution) - rotation(p)), axis=(-2, -1))
    assert np.all(error <= NEWTON * kappa)


def passive_joints(q, p):
    """Each leg's middle and top angles by hand: leg k's axes are x, y, z permuted cyclically (P_k maps x to its
    actuator axis), so P_k^T R P_k = Rx(theta) Ry(s1) Rz(s2) and Rx(theta)^T P_k^T R P_k = Ry(s1) Rz(s2) =
    [[c1 c2, -c1 s2, s1], [s2, c2, 0], [-s1 c2, s1 s2, c1]]."""
    R = rotation(p)
    e = np.eye(3)
    s = []
    for k, theta in enumerate(q):
        P = np.stack([e[k], e[(k + 1) % 3], e[(k + 2) % 3]], axis=-1)
        M = rotation(np.array([theta, 0.0, 0.0])).T @ P.T @ R @ P
        s += [np.arctan2(M[0, 2], M[2, 2]), np.arctan2(M[1, 0], M[1, 1])]
    return np.array(s)


def test_the_closure_vanishes_at_the_assembly(eye):
    """At q = ik(p) and the passive joints found by hand, every leg's end frame is the platform's."""
    p = np.array([0.2, -0.1, 0.3])
    q = eye.ik(p).joints
    phi = eye.closure(q, passive_joints(q, p), p)
    assert np.max(np.abs(phi)) <= KINEMATICS
    # and a passive joint off by 1e-3 rad shows in the residual
    moved = passive_joints(q, p) + np.eye(6)[3] * 1e-3
    assert np.max(np.abs(eye.closure(q, moved, p))) > 1e-4


def test_a_leg_whose_axis_misses_the_centre_has_no_distance_form(tmp_path):
    text = (MODELS_DIR / "agile_eye.yaml").read_text().replace(
        "{name: mid, type: R, axis: [0, 1, 0]}", "{name: mid, type: R, axis: [0, 1, 0], origin: {xyz: [0.01, 0, 0]}}", 1)
    (tmp_path / "bent.yaml").write_text(text)
    with pytest.raises(DerivationError, match="does not pass through the centre"):
        Derivation(load_model(tmp_path / "bent.yaml"))["ik"]


def test_orientation_workspace_measure_matches_uniformly_random_rotations(eye):
    """Rotations drawn uniformly from SO(3) (scipy's Haar sampler), reachable where every leg's closed-form angle
    lies within its +-60 deg limits: the fraction times 8 pi^2 against the |cos pitch| integral over the chart."""
    from scipy.spatial.transform import Rotation

    yaw_pitch_roll = Rotation.random(200_000, random_state=5).as_euler("ZYX")
    q = agile_eye_ik(yaw_pitch_roll[:, ::-1])
    reachable = np.all(np.abs(q) <= np.deg2rad(60.0), axis=-1)
    fraction = reachable.mean()
    monte_carlo = fraction * orientations.SO3_MEASURE
    sigma = orientations.SO3_MEASURE * np.sqrt(fraction * (1 - fraction) / len(q))
    result = orientations.orientation_gci(eye, samples=2**16, seed=0)
    assert abs(result.measure.value - monte_carlo) <= 4 * sigma + result.measure.error
    assert 0 < result.value.value < 1


def test_the_gci_command_states_the_measure_of_orientations(generated_dir):
    run = subprocess.run([*SYMKIN_CLI, "gci", str(generated_dir / "agile_eye"), "--samples", "4096"],
                         capture_output=True, text=True, env=dict(os.environ, SYMKIN_QUIET="1"))
    assert run.returncode == 0, run.stderr
    assert "rad^3" in run.stdout
    assert "invariant measure of SO(3)" in run.stdout
    refused = subprocess.run([*SYMKIN_CLI, "gci", str(generated_dir / "agile_eye"), "--map", "map.png"],
                             capture_output=True, text=True)
    assert refused.returncode == 2
    assert "spherical platform" in refused.stderr


def test_the_orientation_cloud_holds_the_reachable_orientations_with_their_conditioning(eye):
    p, values = orientations.orientation_cloud(eye, 4096, seed=1)
    q, margin = eye.ik(p)
    assert np.all(np.isfinite(q))
    assert np.all(np.abs(q) <= np.deg2rad(60) * (1 + CLOSED_FORM))  # the actuators' limits of models/agile_eye.yaml
    # the cloud's values are (|cos pitch| 1/kappa) / |cos pitch| of the integrand: one rounding
    np.testing.assert_allclose(values, orientations.inverse_condition(eye, q, p), rtol=CLOSED_FORM, atol=0)
    # 8.9 % of SO(3) in the Haar measure; the chart's uniform density puts more of the samples near pitch = 0
    assert 0.05 < len(p) / 4096 < 0.2


def test_the_workspace_command_draws_the_orientations_and_states_their_measure(eye, generated_dir, tmp_path):
    figure = tmp_path / "eye.png"
    run = subprocess.run([*SYMKIN_CLI, "workspace", str(generated_dir / "agile_eye"), "-n", "4096", "-o", str(figure)],
                         capture_output=True, text=True, env=dict(os.environ, SYMKIN_QUIET="1"))
    assert run.returncode == 0, run.stderr
    measure = orientations.orientation_gci(eye, samples=4096, seed=0).measure
    assert f"orientation workspace {measure.value:.4g} +- {measure.error:.2g} rad^3" in run.stdout
    assert figure.stat().st_size > 0
    refused = subprocess.run([*SYMKIN_CLI, "workspace", str(generated_dir / "agile_eye"),
                              "--map", str(tmp_path / "m.png"), "-o", str(tmp_path / "w.png")],
                             capture_output=True, text=True)
    assert refused.returncode == 2
    assert "spherical platform" in refused.stderr
    assert not (tmp_path / "m.png").exists()
    assert not (tmp_path / "w.png").exists()
