"""The closure frames' projector (issue 63): P B, P the orthogonal projector onto the complement of range(Phi_s), by QR
where Phi_s has full column rank and by the SVD's left null space where a passive motion is idle - the same
projector to rounding (eps times the condition number of Phi_s)."""

from __future__ import annotations

import numpy as np

from symkin.runtime.parallel import _complement_projections, _left_null_space
from tolerances import EPS


def test_the_qr_projection_is_the_left_null_spaces():
    rng = np.random.default_rng(63)
    A = rng.normal(size=(8, 18, 12))
    A[3, :, 5] = A[3, :, 2]                  # an idle passive motion: a dependent column
    A[5] *= 1e-3                             # scale does not matter
    task, actuated = rng.normal(size=(8, 18, 3)), rng.normal(size=(8, 18, 3))
    got_task, got_actuated = _complement_projections(A, task, actuated)
    N = _left_null_space(A)
    projector = np.einsum("kij,klj->kil", N, N)
    singular = np.linalg.svd(A, compute_uv=False)
    condition = singular[:, 0] / np.where(singular[:, -1] > 18 * EPS * singular[:, 0], singular[:, -1], singular[:, -2])
    for got, B in ((got_task, task), (got_actuated, actuated)):
        error = np.abs(got - projector @ B).max(axis=(1, 2)) / np.abs(B).max(axis=(1, 2))
        assert (error <= 64 * EPS * condition).all(), error / (EPS * condition)
        assert (np.abs(np.swapaxes(A, -1, -2) @ got).max(axis=(1, 2))
                <= 64 * EPS * condition * np.abs(A).max(axis=(1, 2)) * np.abs(B).max(axis=(1, 2))).all()


def test_without_passive_joints_nothing_is_projected_away():
    B = np.random.default_rng(1).normal(size=(4, 6, 3))
    (got,) = _complement_projections(np.zeros((4, 6, 0)), B)
    np.testing.assert_array_equal(got, B)
