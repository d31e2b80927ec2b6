"""The Stewart-Gough platform (models/stewart.yaml): closed-form IK, Newton FK with a convergence
report, inverse Jacobian and singularity measure."""

from __future__ import annotations

import numpy as np
import pytest

from symkin import load
from symkin.errors import GeneratedCodeError
from symkin.runtime.parallel import solve_closure, solve_fk
from tolerances import CLOSED_FORM, KINEMATICS, NEWTON, STEWART_SCALE, svd


@pytest.fixture(scope="module")
def stewart(generated_dir):
    return load(generated_dir / "stewart")


@pytest.fixture(scope="module")
def geometry(models):
    """Base joints A_i and platform joints b_i (platform frame), written out from the model's numbers."""
    values = {p.name: float(p.value) for p in models["stewart"].parameters}
    gb, gp = values["gamma_b"], values["gamma_p"]
    base = np.deg2rad([0, 0, 120, 120, 240, 240]) + np.array([-gb, gb] * 3)
    top = np.deg2rad([-60, 60, 60, 180, 180, 300]) + np.array([gp, -gp] * 3)
    A = values["r_b"] * np.stack([np.cos(base), np.sin(base), np.zeros(6)], -1)
    b = values["r_p"] * np.stack([np.cos(top), np.sin(top), np.zeros(6)], -1)
    return A, b


def rotation(rpy):
    """R = Rz(yaw) Ry(pitch) Rx(roll), batched."""
    r, p, y = np.moveaxis(np.asarray(rpy), -1, 0)
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.stack([np.stack([cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr], -1),
                     np.stack([sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], -1),
                     np.stack([-sp, cp * sr, cp * cr], -1)], -2)


def random_poses(rng, count):
    return np.column_stack([rng.uniform(-0.04, 0.04, (count, 2)), rng.uniform(0.19, 0.27, count),
                            rng.uniform(-0.2, 0.2, (count, 3))])


def test_ik_is_the_distance_between_the_joint_centres(stewart, geometry):
    A, b = geometry
    pose = random_poses(np.random.default_rng(21), 2000)
    B = pose[:, None, :3] + np.einsum("kij,lj->kli", rotation(pose[:, 3:]), b)
    ik = stewart.ik(pose)
    # a rotation, a sum and a norm of lengths <= STEWART_SCALE; the margin is the squared length,
    # rounded twice more on one side (sqrt, square)
    np.testing.assert_allclose(ik.joints, np.linalg.norm(B - A, axis=-1), rtol=0, atol=KINEMATICS * STEWART_SCALE)
    np.testing.assert_allclose(ik.margin, ik.joints**2, rtol=CLOSED_FORM)


def test_fk_recovers_random_poses_from_their_leg_lengths(stewart):
    rng = np.random.default_rng(22)
    pose = random_poses(rng, 3000)
    lengths = stewart.ik(pose).joints
    start = pose + rng.normal(0, [0.01, 0.01, 0.01, 0.03, 0.03, 0.03], pose.shape)
    report = solve_fk(stewart, lengths, start)
    assert report.all_converged
    np.testing.assert_allclose(report.solution, pose, rtol=0, atol=1e-12)
    assert report.iterations.max() <= 8
    assert np.max(report.residual) <= NEWTON * STEWART_SCALE
    assert np.max(report.step) <= 1e-12


def test_fk_reports_failure_instead_of_a_wrong_pose(stewart):
    rng = np.random.default_rng(23)
    pose = random_poses(rng, 50)
    lengths = stewart.ik(pose).joints
    # Leg lengths no pose can have (one leg three times as long): no convergence, NaN.
    impossible = lengths * [1, 1, 1, 1, 1, 3]
    report = solve_fk(stewart, impossible, pose, max_iterations=25)
    assert not report.converged.any()
    assert np.all(np.isnan(report.solution))
    assert np.all(report.iterations == 25)
    # A start in the base plane is singular (all legs horizontal): reported at once.
    report = solve_fk(stewart, lengths, np.zeros(6))
    assert not report.converged.any()
    assert np.all(np.isnan(report.solution))
    # From far starts some runs converge (perhaps to another assembly mode) and some fail, but
    # whatever converged has exactly the measured leg lengths.
    far = pose + rng.normal(0, [0.1, 0.1, 0.1, 0.8, 0.8, 0.8], pose.shape)
    report = solve_fk(stewart, lengths, far)
    done = report.converged
    np.testing.assert_allclose(stewart.ik(report.solution[done]).joints, lengths[done], atol=1e-12)
    assert np.all(np.isnan(report.solution[~done]))


def test_fk_starts_at_the_home_pose_by_default(stewart):
    pose = np.array([0.01, -0.01, 0.24, 0.05, -0.03, 0.08])
    report = solve_fk(stewart, stewart.ik(pose).joints)
    assert report.all_converged
    np.testing.assert_allclose(report.solution, pose, atol=1e-12)


def test_fk_needs_the_generated_equations(generated_dir):
    arm = load(generated_dir / "planar_2r")
    with pytest.raises(GeneratedCodeError, match="constraints"):
        solve_fk(arm, np.zeros(2), np.zeros(2))


def test_inverse_jacobian_matches_finite_differences_of_ik(stewart):
    pose = random_poses(np.random.default_rng(24), 200)
    lengths = stewart.ik(pose).joints
    J_inv = stewart.inverse_jacobian(lengths, pose)
    h = 1e-6
    for j in range(6):
        step = np.zeros(6)
        step[j] = h
        fd = (stewart.ik(pose + step).joints - stewart.ik(pose - step).joints) / (2 * h)
        np.testing.assert_allclose(J_inv[:, :, j], fd, rtol=0, atol=1e-8)


def test_singularity_measure(stewart, geometry):
    """det J_x = det J_q det J^-1 (J_q = diag(l)); it vanishes where the platform lies in the base plane
    with the legs horizontal (all six constraint lines meet the vertical: vertical motion is free) and
    stays away from zero over the working poses."""
    pose = random_poses(np.random.default_rng(25), 2000)
    lengths = stewart.ik(pose).joints
    s = stewart.singularities(lengths, pose)
    np.testing.assert_allclose(s.det_Jq, np.prod(lengths, axis=-1), rtol=CLOSED_FORM)  # a product of six
    J_inv = stewart.inverse_jacobian(lengths, pose)
    np.testing.assert_allclose(s.det_Jx, np.linalg.det(J_inv) * s.det_Jq, rtol=1e-9)
    scale = np.prod(lengths, axis=-1) * 0.1**3  # rows (B - A)^T [I, -[Rb]x]: lengths and lever arms
    assert np.min(np.abs(s.det_Jx) / scale) > 1e-3
    flat = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.3])
    flat_lengths = stewart.ik(flat).joints
    # det J_x vanishes there to the rounding of its terms (the scale above: lengths and lever arms)
    flat_scale = np.prod(flat_lengths) * 0.1**3
    assert abs(stewart.singularities(flat_lengths, flat).det_Jx) <= KINEMATICS * flat_scale
    # A singular value of J^-1 vanishes there too (an independent numerical check): a backward-stable SVD
    singular = np.linalg.svd(stewart.inverse_jacobian(flat_lengths, flat), compute_uv=False)
    assert singular[-1] <= svd(6) * singular[0], singular


def test_generic_closure_agrees_with_the_distance_form(stewart, geometry):
    """The loop closure of the full UPS chains (30 passive joints) closes at the IK lengths, and its
    implicit Jacobians give the same inverse Jacobian as the distance form."""
    A, b = geometry
    pose = random_poses(np.random.default_rng(26), 100)
    lengths = stewart.ik(pose).joints
    B = pose[:, None, :3] + np.einsum("kij,lj->kli", rotation(pose[:, 3:]), b)
    # Start: U angles from the strut directions, S angles zero; leg frames are Rz(angle of A_i).
    angle = np.arctan2(A[:, 1], A[:, 0])
    d = B - A
    local_x = np.cos(angle) * d[..., 0] + np.sin(angle) * d[..., 1]
    local_y = -np.sin(angle) * d[..., 0] + np.cos(angle) * d[..., 1]
    u1 = np.arctan2(local_y, local_x)
    u2 = np.arctan2(-d[..., 2], np.hypot(local_x, local_y))
    s0 = np.concatenate([np.stack([u1[:, i], u2[:, i], 0 * u1[:, i], 0 * u1[:, i], 0 * u1[:, i]], -1)
                         for i in range(6)], axis=-1)
    report = solve_closure(stewart, lengths, s0, pose, unknowns=("s",))
    assert report.all_converged, report.residual.max()
    assert report.residual.max() <= NEWTON * STEWART_SCALE, report.residual.max()
    s = report.solution["s"]
    np.testing.assert_allclose(stewart.closure(lengths, s, pose), 0, atol=NEWTON * STEWART_SCALE)
    J = stewart.closure_jacobians(lengths, s, pose)
    # Phi_p dp + Phi_q dq + Phi_s ds = 0  ->  dq/dp from the columns of [Phi_q, Phi_s]
    X = -np.linalg.solve(np.concatenate([J.Phi_q, J.Phi_s], axis=-1), J.Phi_p)
    np.testing.assert_allclose(X[:, :6], stewart.inverse_jacobian(lengths, pose), atol=1e-10)
    # Forward kinematics through the closure (36 equations, 36 unknowns) from a nearby start.
    report = solve_closure(stewart, lengths, s + 0.02, pose + 0.005, unknowns=("p", "s"))
    assert report.all_converged
    np.testing.assert_allclose(report.solution["p"], pose, atol=1e-12)
