"""Sobol' sequences, plain or scrambled, in numpy: the points scipy.stats.qmc.Sobol draws, bit for bit.

scipy's engine lives in scipy.stats, whose import (all its distributions, about a second) every analysis command
paid for its sample points.  This module draws the same points (the same direction numbers, the same random
linear matrix scramble and digital shift from the same generator draws, the same order), so every figure quoted
from a scrambled QMC estimate stays as it was (tests/numerics/test_sobol.py compares them with scipy's).

The sequence (Bratley and Fox, ACM TOMS 14 (1988) 88-100, Algorithm 659, with the direction numbers of Joe and
Kuo 2008, :mod:`symkin.numerics.sobol_directions`): in dimension j the direction integers v_jk (k = 0 ... b-1,
b = :data:`BITS` digits) follow from the primitive polynomial x^s + a_1 x^(s-1) + ... + a_(s-1) x + 1 and the
initial m_1 ... m_s by

    m_k = 2 a_1 m_(k-1) XOR 4 a_2 m_(k-2) XOR ... XOR 2^s m_(k-s) XOR m_(k-s),     v_jk = m_(k+1) 2^(b-1-k),

and point i is the XOR of the v_jk over the set bits k of its Gray code i XOR (i >> 1) (Antonov and Saleev
1979), divided by 2^b.  The scramble (Matousek 1998; Owen 2003: random linear matrix scramble plus digital
shift) multiplies every direction integer, as a vector of digits, by a random lower-triangular binary matrix with
unit diagonal, and XORs every point with a random shift.
"""

from __future__ import annotations

import functools

import numpy as np

from symkin.numerics.sobol_directions import DIRECTIONS

#: Digits of every point (scipy's default): points are multiples of 2^-BITS.
BITS = 30
#: The largest dimension with direction numbers here.
MAX_DIMENSION = len(DIRECTIONS) + 1


@functools.lru_cache(maxsize=None)
def direction_integers(dimension: int) -> np.ndarray:
    """(dimension, BITS) the direction integers v_jk, the first digit most significant (see the module docstring);
    read-only, formed once per dimension (a QMC estimate draws 16 scrambles of one sequence).

    Raises:
        ValueError: more dimensions than :data:`MAX_DIMENSION`.
    """
    if not 1 <= dimension <= MAX_DIMENSION:
        raise ValueError(f"Sobol' points in {dimension} dimensions: between 1 and {MAX_DIMENSION} are available")
    m = np.ones((dimension, BITS), dtype=np.int64)
    for j, (polynomial, initial) in enumerate(DIRECTIONS[:dimension - 1], start=1):
        degree = polynomial.bit_length() - 1
        m[j, :degree] = initial
        for k in range(degree, BITS):
            value = m[j, k - degree] ^ (m[j, k - degree] << degree)
            for i in range(1, degree):
                if (polynomial >> (degree - i)) & 1:
                    value ^= m[j, k - i] << i
            m[j, k] = value
    v = (m << (BITS - 1 - np.arange(BITS))).astype(np.uint32)
    v.setflags(write=False)
    return v


def _scrambled(v: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(scrambled direction integers, shift): the linear matrix scramble and digital shift drawn from ``rng`` in
    scipy's order (the shift's digits, then the d lower-triangular matrices, least significant digit first)."""
    dimension = v.shape[0]
    shift_digits = rng.integers(0, 2, size=(dimension, BITS), dtype=np.uint32)
    shift = shift_digits @ (np.uint32(1) << np.arange(BITS, dtype=np.uint32))
    matrices = np.tril(rng.integers(0, 2, size=(dimension, BITS, BITS), dtype=np.uint32))
    matrices[:, np.arange(BITS), np.arange(BITS)] = 1
    # digit r (from the most significant) of a scrambled integer: the parity of row r of L times its digits
    digits = (v[:, :, None] >> (BITS - 1 - np.arange(BITS, dtype=np.uint32))) & 1  # (d, k, digit from the top)
    products = np.einsum("jrc,jkc->jkr", matrices.astype(np.int64), digits.astype(np.int64)) & 1
    scrambled = (products.astype(np.uint32) << (BITS - 1 - np.arange(BITS, dtype=np.uint32))).sum(axis=-1)
    return scrambled.astype(np.uint32), shift.astype(np.uint32)


class Sobol:
    """One Sobol' sequence in ``dimension`` dimensions: plain (``rng`` None) or scrambled by draws from ``rng``
    (as ``scipy.stats.qmc.Sobol(dimension, scramble=True, rng=rng)``, consuming the same draws)."""

    def __init__(self, dimension: int, rng: np.random.Generator | None = None):
        self.dimension = dimension
        v = direction_integers(dimension)
        self._v: np.ndarray = v
        self._shift: np.ndarray = np.zeros(dimension, dtype=np.uint32)
        if rng is not None:
            self._v, self._shift = _scrambled(v, rng)

    def integers(self, start: int, stop: int) -> np.ndarray:
        """(stop - start, dimension) points start ... stop - 1 as integers (the points times 2^BITS).

        Point B 2^K + r of an aligned block of 2^K is base(B) XOR T[r], since the Gray code of B 2^K + r is
        (gray(B) << K) XOR gray(r) XOR ((B & 1) << (K - 1)): T, the XOR of the directions over gray(r) for r < 2^K,
        is built by reflection (gray(2^k + r) = 2^k + gray(2^k - 1 - r)), and each block's base once.
        """
        if not 0 <= start <= stop <= 2**BITS:
            raise ValueError(f"Sobol' points {start} ... {stop - 1}: the sequence has 2^{BITS}")
        count = stop - start
        # a table of about the points asked for, at most 2^22 integers
        K = min(max(count - 1, 0).bit_length(), max(22 - (self.dimension - 1).bit_length(), 0))
        table = np.zeros((1 << K, self.dimension), dtype=np.uint32)
        for k in range(K):
            table[1 << k:2 << k] = table[(1 << k) - 1::-1] ^ self._v[:, k]
        blocks = np.arange(start >> K, ((max(stop, 1) - 1) >> K) + 1, dtype=np.int64)
        high = ((blocks ^ (blocks >> 1)) << K) ^ (((blocks & 1) << (K - 1)) if K else 0)
        base = np.broadcast_to(self._shift, (len(blocks), self.dimension)).copy()
        for k in range(max(K - 1, 0), BITS):  # the bits of gray(B) << K and bit K - 1
            base[(high >> k) & 1 == 1] ^= self._v[:, k]
        points = (base[:, None, :] ^ table[None]).reshape(-1, self.dimension)
        offset = start - (int(blocks[0]) << K)
        return points[offset:offset + count]

    def points(self, start: int, stop: int) -> np.ndarray:
        """(stop - start, dimension) points start ... stop - 1 in [0, 1)^dimension."""
        return self.integers(start, stop) * 2.0**-BITS
