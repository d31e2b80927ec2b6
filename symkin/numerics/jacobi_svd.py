"""Singular values of a batch of small matrices by one-sided Jacobi, in jax.numpy: a device program's SVD that calls
no LAPACK kernel.

One-sided (Hestenes) Jacobi orthogonalizes the columns of A (m x n, m >= n; a wide matrix's transpose) by plane
rotations.  For a pair of columns (a_i, a_j), with alpha = |a_i|^2, beta = |a_j|^2 and gamma = a_i . a_j,

    zeta = (beta - alpha) / (2 gamma),   t = sign(zeta) / (|zeta| + sqrt(1 + zeta^2)),   c = 1 / sqrt(1 + t^2),
    s = c t,   (a_i, a_j) <- (c a_i - s a_j, s a_i + c a_j)

makes them orthogonal; cyclic sweeps over every pair converge quadratically, and once no pair has
|gamma| > m eps sqrt(alpha beta) the columns' norms are the singular values (Hestenes 1958; Demmel and Veselic,
"Jacobi's method is more accurate than QR", SIAM J. Matrix Anal. Appl. 13(4), 1992: each within a few eps of
sigma_max, as LAPACK's).  Each matrix is first divided by its largest entry (no overflow or underflow in |a|^2).  A
batch sweeps until no matrix of it rotates any more (:data:`SWEEPS_PER_STEP` sweeps per step of the loop, at most
:data:`MAX_SWEEPS`; a random 6 x 6 takes 7 or 8).

Why: XLA's batched SVD on a CPU is LAPACK's gesdd matrix by matrix (for the UR10e's 6 x 6 Jacobians about as long as
numpy's), where these sweeps are a few dozen operations per pair of columns over the whole batch, fused by XLA into
one loop per step (:func:`in_one_loop`) - on a CPU's vector units or a GPU's threads alike - and, calling no LAPACK
kernel, they need no place in the order of :mod:`symkin.numerics.ordered_linalg`.  The UR10e's GCI integrand on
JAX's CPU device takes 1.4 us per configuration so against 3.3 us on the host (C's J, numpy's SVD;
benchmarks/bench_jax.py); it took 3.5 us with XLA's SVD.
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: Sweeps over every pair of columns in one step of the loop (unrolled: fewer steps, a longer compile).
SWEEPS_PER_STEP = 2
#: Sweeps after which the iteration stops whether or not every pair has converged.
MAX_SWEEPS = 32


def in_one_loop(values: tuple[Any, ...]) -> tuple[Any, ...]:
    """``values`` (jax.numpy arrays of one shape), computed in one loop by XLA's CPU compiler: a variadic reduce over
    the pairs (value, -0.0), exact (-0.0 + v = v for every v).  Otherwise XLA gives each output a loop of its own,
    each recomputing the subexpressions they share (the generated JAX modules do the same: their _in_one_loop)."""
    import jax
    import jax.numpy as jnp

    pairs = tuple(jnp.stack([v, jnp.full_like(v, -0.0)], axis=-1) for v in values)
    zeros = tuple(jnp.float64(-0.0) for _ in values)
    return tuple(jax.lax.reduce(pairs, zeros, lambda a, b: tuple(x + y for x, y in zip(a, b)),
                                (pairs[0].ndim - 1,)))


def jacobi_singular_values(A: Any) -> Any:
    """The min(m, n) singular values, unsorted, of each matrix of a batch A (N, m, n) in jax.numpy; NaN for a matrix
    with an entry that is not finite.  Not differentiable in reverse mode (a while loop)."""
    import jax
    import jax.numpy as jnp

    m, n = A.shape[-2:]
    if m < n:
        A, m, n = jnp.swapaxes(A, -1, -2), n, m
    largest = jnp.max(jnp.abs(A), axis=(-2, -1))
    finite = jnp.isfinite(largest)
    unit = jnp.where(finite & (largest > 0), largest, 1.0)
    scaled = jnp.where(finite[:, None, None], A / unit[:, None, None], 0.0)
    tolerance = m * np.finfo(np.float64).eps
    pairs = [(i, j) for i in range(n - 1) for j in range(i + 1, n)]

    def step(state: tuple[tuple[Any, ...], Any, Any]) -> tuple[tuple[Any, ...], Any, Any]:
        entries, _, sweeps = state
        columns = [list(entries[k * m:(k + 1) * m]) for k in range(n)]
        for _ in range(SWEEPS_PER_STEP):
            rotations = jnp.zeros(A.shape[:1])   # the last sweep's decide whether another step follows
            for i, j in pairs:
                a, b = columns[i], columns[j]
                alpha, beta = sum(x * x for x in a), sum(y * y for y in b)
                gamma = sum(x * y for x, y in zip(a, b))
                rotate = jnp.abs(gamma) > tolerance * jnp.sqrt(alpha * beta)
                rotations = rotations + rotate
                zeta = (beta - alpha) / (2.0 * jnp.where(rotate, gamma, 1.0))
                t = jnp.where(zeta == 0, 1.0, jnp.sign(zeta) / (jnp.abs(zeta) + jnp.sqrt(1.0 + zeta * zeta)))
                c = jnp.where(rotate, 1.0 / jnp.sqrt(1.0 + t * t), 1.0)
                s = jnp.where(rotate, t, 0.0) * c
                columns[i] = [c * x - s * y for x, y in zip(a, b)]
                columns[j] = [s * x + c * y for x, y in zip(a, b)]
        computed = in_one_loop(tuple(x for column in columns for x in column) + (rotations,))
        return computed[:-1], jnp.max(computed[-1]), sweeps + SWEEPS_PER_STEP

    start = (tuple(scaled[:, r, k] for k in range(n) for r in range(m)), jnp.asarray(1.0), jnp.asarray(0))
    entries, _, _ = jax.lax.while_loop(lambda state: (state[1] > 0) & (state[2] < MAX_SWEEPS), step, start)
    norms = [jnp.sqrt(sum(x * x for x in entries[k * m:(k + 1) * m])) for k in range(n)]
    return jnp.where(finite[:, None], jnp.stack(norms, axis=-1) * unit[:, None], jnp.nan)
