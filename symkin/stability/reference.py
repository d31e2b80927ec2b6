"""High-precision reference values: the un-optimized sympy expressions evaluated by mpmath.

The reference is independent of everything the generated code goes through (parameter and
constant folding, CSE, the printer, floating point): the expressions exactly as derived
are lambdified for mpmath and evaluated at 50 significant digits, at exactly the float
inputs the generated code receives.  Values come back as double-doubles ``(hi, lo)`` with
hi + lo equal to the reference to about 1e-32, so that errors down to 1e-17 are measured
without the rounding of the reference getting in the way.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping

import mpmath
import numpy as np
from symkin.ir.evaluate import lambdify_spec
from symkin.ir.spec import FunctionSpec

#: Working precision of the reference (significant decimal digits).
DIGITS = 50

#: Distinct (argument, precision) pairs each memoized function keeps.
MEMO_SIZE = 1 << 14


def _memoized(function: Callable[[object], object]) -> Callable[[object], object]:
    """``function`` with its values kept per (argument, working precision): the expanded expressions
    of a state call sin and cos of the same few angles thousands of times, and mpmath's are slow."""
    cached = functools.lru_cache(maxsize=MEMO_SIZE)(lambda x, _precision: function(x))
    return lambda x: cached(x, mpmath.mp.prec)


#: The namespace in front of mpmath's for the reference: the same functions, memoized.
MEMOIZED = {"sin": _memoized(mpmath.sin), "cos": _memoized(mpmath.cos)}


class MpmathReference:
    """Evaluate a function spec's outputs at ``DIGITS`` digits.

    Args:
        spec: the derived (un-optimized) function.
    """

    def __init__(self, spec: FunctionSpec):
        self.spec = spec
        self.vector_names = tuple(i.name for i in spec.vector_inputs)
        self.parameter_names = tuple(i.name for i in spec.parameter_inputs)
        symbols = [s for i in spec.vector_inputs for s in i.symbols] + [i.symbols[0] for i in spec.parameter_inputs]
        self._function = lambdify_spec(spec, symbols, modules=[MEMOIZED, "mpmath"])
        self.size = sum(len(out.entries) for out in spec.outputs)

    def exact(self, vectors: Mapping[str, np.ndarray], parameters: Mapping[str, float]) -> list:
        """The outputs (flattened, row-major, outputs in order) as mpmath reals.

        An output that comes out complex (the square root of a negative discriminant: a
        parallel mechanism that does not assemble at these exact inputs) is undefined there:
        NaN, as the generated code flags it.
        """
        args = [mpmath.mpf(float(v)) for name in self.vector_names for v in np.asarray(vectors[name], dtype=float)]
        args += [mpmath.mpf(float(parameters[name])) for name in self.parameter_names]
        with mpmath.workdps(DIGITS):
            values = self._function(*args)
            return [_real_or_nan(values[k]) for k in range(self.size)]

    def __call__(self, vectors: Mapping[str, np.ndarray], parameters: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
        """(hi, lo) double-double arrays of the flattened outputs at one state."""
        exact = self.exact(vectors, parameters)
        with mpmath.workdps(DIGITS):
            hi = np.array([float(v) for v in exact])
            lo = np.array([float(v - mpmath.mpf(h)) for v, h in zip(exact, hi)])
        return hi, lo


def _real_or_nan(value: object) -> mpmath.mpf:
    """A real mpmath value; a complex one with a non-negligible imaginary part is NaN."""
    if isinstance(value, mpmath.mpc):
        if abs(value.imag) > mpmath.mpf(10) ** (10 - DIGITS) * max(abs(value.real), 1):
            return mpmath.mpf("nan")
        return mpmath.mpf(value.real)
    return mpmath.mpf(value)


def normwise_error(computed: np.ndarray, hi: np.ndarray, lo: np.ndarray) -> float:
    """|computed - reference|_2 / |reference|_2 for one state (reference = hi + lo).

    An exactly zero reference gives 0 if the computed value is zero too, else inf; a
    non-finite computed value gives inf, except where the reference is undefined (NaN)
    too: an entry that both flag as undefined agrees and is left out.
    """
    computed = np.asarray(computed, dtype=float)
    undefined = np.isnan(hi)
    if np.any(np.isfinite(computed[undefined])):
        return float("inf")  # a value where none exists: silent garbage
    computed, hi, lo = computed[~undefined], hi[~undefined], lo[~undefined]
    if not np.all(np.isfinite(computed)):
        return float("inf")
    difference = (computed - hi) - lo
    norm = float(np.linalg.norm(hi))
    error = float(np.linalg.norm(difference))
    if norm == 0.0:
        return 0.0 if error == 0.0 else float("inf")
    return error / norm
