"""jax.numpy whose LAPACK factorizations run in the order a program calls them (issue 66's device programs).

The rating's measures (:mod:`symkin.rating.on_device`) and the GCI's integrand
(:mod:`symkin.analysis.device_integrand`) call several batched factorizations that XLA may run concurrently;
:class:`InOrder` chains them through their data so that they cannot.
"""

from __future__ import annotations

from typing import Any


#: The functions of jax.numpy.linalg that call LAPACK on a CPU (a batched custom call each).
FACTORIZATIONS = frozenset({"cholesky", "cond", "det", "eig", "eigh", "eigvals", "eigvalsh", "inv", "lstsq", "pinv",
                            "qr", "slogdet", "solve", "svd"})


class InOrderLinalg:
    """jax.numpy.linalg whose factorizations run one after the other, in the order the program calls them.

    jaxlib's CPU LAPACK kernels (0.10) split a large batch over XLA's intra-op thread pool and block until its
    parts are done; two of them run concurrently by XLA on a pool of two threads (a 2-core machine) wait for each
    other's parts forever (a datasheet of 16 000 DELTA samples hung so, and the UR10e's GCI integrand, |det J| beside
    the SVD of J, at 10 000 configurations).  Each factorization here takes its matrix
    times 1 + 0 t, t the count of the previous factorization's finite entries (exactly its matrix: 0 t = 0 and
    1 x = x; XLA does not fold 0 t for floating-point t), so it starts only when the previous one has finished.
    """

    def __init__(self, linalg: Any, jnp: Any) -> None:
        self._linalg, self._jnp = linalg, jnp
        self._previous: Any = None

    def __getattr__(self, name: str) -> Any:
        function = getattr(self._linalg, name)
        if name not in FACTORIZATIONS:
            return function

        def in_order(matrix: Any, *args: Any, **kwargs: Any) -> Any:
            matrix = self._jnp.asarray(matrix)
            if self._previous is not None:
                matrix = matrix * (1.0 + 0.0 * self._previous)
            result = function(matrix, *args, **kwargs)
            first = result[0] if isinstance(result, tuple) else result
            self._previous = self._jnp.sum(self._jnp.isfinite(first)).astype(matrix.dtype)
            return result

        return in_order


class InOrder:
    """jax.numpy with :class:`InOrderLinalg` as its linalg: the array module a device program is traced with (one per
    trace: it holds the last factorization's result)."""

    def __init__(self, jnp: Any) -> None:
        self.linalg = InOrderLinalg(jnp.linalg, jnp)
        self._jnp = jnp

    def __getattr__(self, name: str) -> Any:
        return getattr(self._jnp, name)
