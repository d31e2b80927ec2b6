"""High-precision reference values: the un-optimized sympy expressions evaluated in ball arithmetic.

The reference is independent of everything the generated code goes through (parameter and
constant folding, CSE, the printer, floating point): the expressions exactly as derived are
lambdified (with sympy's mpmath printer) onto FLINT's arb ball arithmetic (python-flint) and
evaluated with 256-bit midpoints (77 significant digits; at least 50 are kept), at exactly the float
inputs the generated code receives.  Each operation rounds its midpoint as mpmath would, in C: 4 to 9
times faster per state than mpmath at 50 digits on the Stewart platform's functions, the two agreeing
to 1e-48 (benchmarks/bench_reference.py), which is what makes the thousands of states of
``symkin bench stability`` cheap (the Stewart platform's default run: 25 s instead of 41 s, the rest
being code generation and the condition numbers).  A ball's
radius bounds the midpoint's error; 170 bits (50 digits) let it grow over the longest programs near
singularities (kappa 1e14) until a divisor's ball held zero, 256 bits do not.  Values come back
as double-doubles ``(hi, lo)`` with hi + lo equal to the reference to about 1e-32, so that errors
down to 1e-17 are measured without the rounding of the reference getting in the way; as mpmath
values (:meth:`BallReference.exact`) for the condition numbers.

An operation without a real value (the square root of a negative discriminant: a parallel mechanism
that does not assemble at these exact inputs, a division by zero) gives arb's indeterminate ball,
which comes back as NaN, as the generated code flags it.  Integer powers are products
(:func:`_integer_power`): arb's general power of a ball that holds zero (a value that is zero in
exact arithmetic, reached with a radius, such as the components of a hybrid device's twist that its
geometry cancels) is indeterminate, while x^2 of [0 +- r] is [0 +- r^2].
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import flint
import mpmath
import numpy as np
from sympy.printing.pycode import MpmathPrinter

from symkin.ir.evaluate import REFERENCE_PRINTER_SETTINGS, lambdify_spec
from symkin.ir.spec import FunctionSpec

#: Digits the reference keeps (and the condition numbers' SVD works at), and its midpoints' bits.
DIGITS = 50
PRECISION = 256


def _number(value: int | tuple[int, int, int, int]) -> flint.arb:
    """sympy's mpmath printer writes numbers as ``mpf(n)`` and ``mpf((sign, mantissa, exponent, bits))``."""
    if isinstance(value, tuple):
        sign, mantissa, exponent, _ = value
        exact = flint.arb(mantissa) * flint.arb(2) ** exponent  # a power of two times an integer: exact
        return -exact if sign else exact
    return flint.arb(value)


def _sign(x: flint.arb) -> flint.arb:
    return flint.arb(int(x > 0) - int(x < 0)) if x.is_finite() else flint.arb("nan")


def _ball(value: flint.arb | int | float) -> flint.arb:
    """An arb value (a printed constant such as 0 or the 2 of sqrt(2) is a Python number)."""
    return value if isinstance(value, flint.arb) else flint.arb(value)


def _integer_power(x: flint.arb | int | float, n: int) -> flint.arb:
    """x^n by repeated squaring (n an integer; negative: the reciprocal)."""
    base, exponent, result = _ball(x), abs(int(n)), flint.arb(1)
    while exponent:
        if exponent & 1:
            result = result * base
        base, exponent = base * base, exponent >> 1
    return result if n >= 0 else 1 / result


class _BallPrinter(MpmathPrinter):
    """sympy's mpmath printer, integer powers written as :func:`_integer_power` calls."""

    def _print_Pow(self, expr, rational=False):  # noqa: N802 - sympy's printer protocol
        if expr.exp.is_Integer and expr.exp != -1:
            return f"ipow({self._print(expr.base)}, {int(expr.exp)})"
        return super()._print_Pow(expr, rational=rational)


def _unary(method: str) -> Callable[[flint.arb | int | float], flint.arb]:
    """The arb method ``method`` as a function of one argument, numbers included."""
    return lambda x: getattr(_ball(x), method)()


with flint.ctx.workprec(PRECISION):
    #: The names the printed expressions use, on arb balls.
    NAMESPACE: dict[str, object] = {
        name: _unary(name) for name in ("sqrt", "sin", "cos", "tan", "asin", "acos", "atan", "exp", "log",
                                        "sinh", "cosh", "tanh")}
    NAMESPACE.update({"mpf": _number, "pi": flint.arb.pi(), "sign": _sign, "ipow": _integer_power,
                      "atan2": lambda y, x: flint.arb.atan2(_ball(y), _ball(x))})


#: States whose outputs a reference keeps (the largest batch of states the stability run evaluates at once).
RECENT = 64


class BallReference:
    """Evaluate a function spec's outputs at ``DIGITS`` digits.

    Args:
        spec: the derived (un-optimized) function.
    """

    def __init__(self, spec: FunctionSpec):
        self.spec = spec
        self.vector_names = tuple(i.name for i in spec.vector_inputs)
        self.parameter_names = tuple(i.name for i in spec.parameter_inputs)
        symbols = [s for i in spec.vector_inputs for s in i.symbols] + [i.symbols[0] for i in spec.parameter_inputs]
        self._function = lambdify_spec(spec, symbols, modules=[NAMESPACE, "mpmath"],
                                       printer=_BallPrinter(dict(REFERENCE_PRINTER_SETTINGS, user_functions={})))
        self.size = sum(len(out.entries) for out in spec.outputs)
        self._recent: dict[tuple[float, ...], list[flint.arb]] = {}

    def balls(self, vectors: Mapping[str, np.ndarray], parameters: Mapping[str, float]) -> list[flint.arb]:
        """The outputs (flattened, row-major, outputs in order) as arb balls; NaN where undefined.  The last
        :data:`RECENT` states' are kept: a matrix output is evaluated for its condition number and then checked at
        the same states."""
        key = tuple(float(v) for name in self.vector_names for v in np.asarray(vectors[name], dtype=float))
        key += tuple(float(parameters[name]) for name in self.parameter_names)
        if key not in self._recent:
            if len(self._recent) >= RECENT:
                self._recent.clear()
            with flint.ctx.workprec(PRECISION):
                values = self._function(*(flint.arb(v) for v in key))
                self._recent[key] = [_ball(values[k]) for k in range(self.size)]
        return self._recent[key]

    def exact(self, vectors: Mapping[str, np.ndarray], parameters: Mapping[str, float]) -> list[mpmath.mpf]:
        """The outputs' midpoints as mpmath reals (exactly), NaN where undefined."""
        return [_to_mpmath(v) for v in self.balls(vectors, parameters)]

    def __call__(self, vectors: Mapping[str, np.ndarray], parameters: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
        """(hi, lo) double-double arrays of the flattened outputs at one state."""
        balls = self.balls(vectors, parameters)
        hi = np.array([float(v.mid()) if v.is_finite() else np.nan for v in balls])
        with flint.ctx.workprec(PRECISION):
            lo = np.array([float(v.mid() - flint.arb(h)) if v.is_finite() else np.nan for v, h in zip(balls, hi)])
        return hi, lo


def _to_mpmath(value: flint.arb) -> mpmath.mpf:
    """The midpoint as an mpmath real, exactly (made at the midpoint's precision, whatever mpmath's is)."""
    if not value.is_finite():
        return mpmath.mpf("nan")
    mantissa, exponent = value.mid().man_exp()
    with mpmath.workprec(PRECISION):
        return mpmath.ldexp(mpmath.mpf(int(mantissa)), int(exponent))


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
