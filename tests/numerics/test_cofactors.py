"""symkin.numerics.cofactors: determinants and inverses of small matrices by cofactors, against LAPACK's."""

from __future__ import annotations

import numpy as np
import pytest
from tolerances import EPS

from symkin.numerics import cofactors


@pytest.mark.parametrize("size", [1, 2, 3, 4])
def test_cofactors_give_lapacks_determinant_and_inverse(size):
    """Random batches: det A to a few eps times the product of the rows' norms (Hadamard's bound, the scale of the
    expansion's terms), A^-1 to a few eps times kappa(A) |A^-1|, the batch shape kept."""
    A = np.random.default_rng(size).normal(size=(4, 5, size, size))
    scale = np.prod(np.linalg.norm(A, axis=-1), axis=-1)
    terms = float(np.prod(np.arange(1, size + 1)))  # k! products of k factors each
    assert cofactors.determinant(A, np).shape == (4, 5)
    assert np.all(np.abs(cofactors.determinant(A, np) - np.linalg.det(A)) <= 8 * size * terms * EPS * scale)
    inverse, reference = cofactors.inverse(A, np), np.linalg.inv(A)
    bound = 16 * size * terms * EPS * np.linalg.cond(A) * np.linalg.norm(reference, 2, axis=(-2, -1))
    assert inverse.shape == A.shape
    assert np.all(np.linalg.norm(inverse - reference, 2, axis=(-2, -1)) <= bound)


def test_a_singular_matrix_has_determinant_zero_exactly():
    """Integer entries: every product and sum exact, so a singular matrix's determinant is exactly 0."""
    A = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]])
    assert cofactors.determinant(A, np) == 0.0
