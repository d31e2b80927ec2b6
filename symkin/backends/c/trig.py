"""Constants of the vectorizable sine/cosine emitted into the C sources.

The batch entry points evaluate blocks of configurations lane by lane in loops that the
compiler vectorizes; a call to libm's sin/cos would stop that, so the generated C carries
its own branch-free ``sincos`` (used by the single-configuration functions too, so both
give the same bits):

1. Cody-Waite reduction: k = round(x * 2/pi) (by the 1.5 * 2^52 rounding trick),
   r = ((x - k*P1) - k*P2) - k*P3 with pi/2 = P1 + P2 + P3, where P1 and P2 have so few
   significant bits that k*P1 and k*P2 are exact for every |x| <= LIMIT;
2. Taylor polynomials of sin and cos on |r| <= pi/4, in Horner form in r^2, to the degree
   where the first omitted term is below half an ulp (r^19/19! < 1e-19 for double,
   r^13/13! < 1e-10 for float);
3. the quadrant k mod 4 selects and negates sin r / cos r with comparisons (blends).

Arguments beyond LIMIT (and NaN, inf) are recomputed with libm after the vector loop.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mpmath


@dataclass(frozen=True)
class TrigConstants:
    """Literals (as floats) of one precision's sincos."""

    two_over_pi: float
    pi_half_parts: tuple[float, float, float]
    round_magic: float
    limit: float
    sin_coefficients: tuple[float, ...]  # of r^3, r^5, ...
    cos_coefficients: tuple[float, ...]  # of r^2, r^4, ...


def _split_half_pi(bits: int) -> tuple[float, float, float]:
    """pi/2 = P1 + P2 + P3 with ``bits`` significant bits in P1 and P2 (exact binary values)."""
    with mpmath.workprec(300):
        rest = mpmath.pi / 2
        parts = []
        for _ in range(2):
            exponent = math.floor(math.log2(float(rest)))
            scale = mpmath.mpf(2) ** (bits - 1 - exponent)
            part = mpmath.floor(rest * scale) / scale
            parts.append(float(part))
            assert mpmath.mpf(parts[-1]) == part
            rest -= part
        return parts[0], parts[1], float(rest)


def constants(precision: str) -> TrigConstants:
    """The sincos constants of ``precision`` (``"double"`` or ``"float"``)."""
    if precision == "double":
        bits, magic, limit, sin_terms, cos_terms = 30, 1.5 * 2.0**52, 1e5, 8, 9
    else:
        bits, magic, limit, sin_terms, cos_terms = 12, 1.5 * 2.0**23, 2e3, 5, 6
    with mpmath.workprec(200):
        two_over_pi = float(2 / mpmath.pi)
    sin_c = tuple((-1.0) ** k / math.factorial(2 * k + 1) for k in range(1, sin_terms + 1))
    cos_c = tuple((-1.0) ** k / math.factorial(2 * k) for k in range(1, cos_terms + 1))
    return TrigConstants(two_over_pi, _split_half_pi(bits), magic, limit, sin_c, cos_c)
