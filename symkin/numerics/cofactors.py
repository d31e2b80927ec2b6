"""Determinants and inverses of batches of small matrices by cofactors: arithmetic only, in any array module.

For the n x n matrices of a device program with n <= 3 or so (an actuator-space mass matrix, the principal minors of
an apparent-mass bound: :mod:`symkin.design.box_gradient_solving`), Laplace's expansion costs a few products and calls
no LAPACK kernel - on a CPU jaxlib's kernels must otherwise run in order (:mod:`symkin.numerics.ordered_linalg`), and
jax.jacfwd differentiates the arithmetic as it stands.  The cost grows as n!: not for large matrices.
"""

from __future__ import annotations

from typing import Any


def determinant(A: Any, xp: Any) -> Any:
    """det A of a batch (..., k, k) by Laplace's expansion along the first row, in the array module ``xp``."""
    k = A.shape[-1]
    if k == 1:
        return A[..., 0, 0]
    return sum((-1) ** j * A[..., 0, j] * determinant(xp.delete(A[..., 1:, :], j, axis=-1), xp) for j in range(k))


def inverse(A: Any, xp: Any) -> Any:
    """A^-1 = adj(A) / det A of a batch (..., k, k), the adjugate by cofactors (:func:`determinant`)."""
    k = A.shape[-1]
    if k == 1:
        return 1.0 / A
    rows = [xp.stack([(-1) ** (i + j) * determinant(xp.delete(xp.delete(A, i, axis=-2), j, axis=-1), xp)
                      for j in range(k)], axis=-1) for i in range(k)]
    return xp.swapaxes(xp.stack(rows, axis=-2), -1, -2) / determinant(A, xp)[..., None, None]
