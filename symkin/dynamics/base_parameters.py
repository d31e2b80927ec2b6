"""The base parameters of a serial chain: the identifiable combinations of its standard parameters, exactly.

Some columns of the regressor Y (:mod:`symkin.dynamics.regressor`) vanish for every motion (a link's
parameters that no joint can excite) and others are linear combinations of the rest (the mass of link j
acts on joint j-1 as a first moment of link j-1 does, a rotor inertia as the link's own I_zz does).  Only
the combinations pi_b = K pi are identifiable: with Y_b the columns of Y that are linearly independent,

    Y = Y_b K,   tau = Y pi = Y_b pi_b,   Y_b of full column rank

(Gautier and Khalil, "Direct calculation of minimum set of inertial parameters of serial robots", IEEE
Trans. Robot. Autom. 6(3), 1990; Khalil and Dombre, *Modeling, Identification and Control of Robots*,
2002, sec. 12.5).  K is found here without a float and without a threshold: Y is evaluated in exact
rational arithmetic at random rational states (joint angles where sine and cosine are rational,
(1 - t^2, 2t) / (1 + t^2); velocities, accelerations and the Coulomb shapes rational), the rows of those
samples stacked and brought to reduced row echelon form over the rationals (FLINT's ``fmpq_mat.rref``).
The pivot columns are the base columns; the echelon form's rows are K.  A dependency that the samples
show holds at those points only by accident has probability zero (Schwartz-Zippel: the columns' entries
are polynomials in the sampled values), and more samples than parameters are stacked.  The preferred
base columns are the earlier ones (links from the base out, inertial before drive parameters), so the
parameters of outer links and the rotor inertias are regrouped into inner ones, as in Khalil's rules.

The geometry is taken at the model's values (a parameter kept free enters at its default): a constant
whose sine or cosine is not rational (a URDF angle of 1.5708 rad; read it with ``--snap-angles``) or a
coupling with a non-integer ratio (a gyroscopic rotor's N q) cannot be evaluated exactly, and is refused.
"""

from __future__ import annotations

import random
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction

import flint
import symengine as se
import sympy

from symkin.errors import DerivationError
from symkin.model import coordinates, joint_kinds
from symkin.model.schema import Model

#: Samples stacked beyond the fewest that could reveal every parameter (rows = samples x coordinates).
EXTRA_SAMPLES = 4
#: Numerators and denominators of the sampled rationals: small, so that the exact arithmetic stays fast.
SAMPLE_RANGE = 97


@dataclass(frozen=True)
class BaseParameters:
    """The base parameters: pi_b = K pi, and the columns of Y that form Y_b.

    Attributes:
        names: the standard parameters' names (Y's columns).
        base: the indices of Y's columns that form Y_b (each base parameter is named after its column).
        combinations: K, rows of exact rationals (len(base) x len(names)): pi_b = K pi and Y = Y_b K.
    """

    names: tuple[str, ...]
    base: tuple[int, ...]
    combinations: tuple[tuple[Fraction, ...], ...]

    @property
    def base_names(self) -> tuple[str, ...]:
        """A base parameter is named after its column, with an ``R`` where it regroups others (``link1.mxR``)."""
        return tuple(self.names[b] + ("R" if sum(1 for k in row if k != 0) > 1 else "")
                     for b, row in zip(self.base, self.combinations))

    def equations(self) -> tuple[str, ...]:
        """Each base parameter as the combination it stands for: ``link1.mxR = link1.mx + 1/5 link2.m``."""
        lines = []
        for name, row in zip(self.base_names, self.combinations):
            terms = []
            for k, coefficient in enumerate(row):
                if coefficient == 0:
                    continue
                sign = "-" if coefficient < 0 else "+"
                size = abs(coefficient)
                terms.append(f"{sign} {'' if size == 1 else f'{size} '}{self.names[k]}")
            text = " ".join(terms)
            lines.append(f"{name} = {text[2:] if text.startswith('+ ') else text}")
        return tuple(lines)


def _unit_point(t: Fraction) -> tuple[Fraction, Fraction]:
    """(cos, sin) of the angle 2 atan(t): a rational point on the unit circle."""
    return (1 - t * t) / (1 + t * t), 2 * t / (1 + t * t)


def _power(point: tuple[Fraction, Fraction], n: int) -> tuple[Fraction, Fraction]:
    """(cos, sin) of n times the angle of ``point`` (de Moivre, exactly)."""
    c, s = point if n >= 0 else (point[0], -point[1])
    out = (Fraction(1), Fraction(0))
    for _ in range(abs(n)):
        out = (out[0] * c - out[1] * s, out[0] * s + out[1] * c)
    return out


class _ExactSample:
    """One random rational state and the exact value of every trigonometric and sign atom at it."""

    def __init__(self, model: Model, rng: random.Random):
        def rational() -> Fraction:
            return Fraction(rng.randint(-SAMPLE_RANGE, SAMPLE_RANGE), rng.randint(1, SAMPLE_RANGE))

        self.model = model
        self.q = {se.sympify(s): rational() for s in coordinates.symbols(model, "q")}
        self.points = {s: _unit_point(v) for s, v in self.q.items()}
        self.values: dict[se.Basic, se.Basic] = {}
        for group in ("qd", "qdd"):
            self.values.update({se.sympify(s): _rational(rational()) for s in coordinates.symbols(model, group)})
        self.values.update({se.sympify(p.symbol): se.sympify(p.value) for p in model.parameters})
        revolute = {se.sympify(s) for s, c in zip(coordinates.symbols(model, "q"), model.coordinates)
                    if joint_kinds.is_rotation(c.type)}
        self.values.update({s: _rational(v) for s, v in self.q.items() if s not in revolute})
        self._rational = rational

    def bind_atoms(self, trigonometric: Sequence[se.Basic], coulomb: Sequence[se.Basic], where: str) -> None:
        """Give every sin/cos of a joint angle its value, and every sign/tanh of a velocity (a joint's Coulomb
        shape, a function of nothing else in Y) a random one."""
        for atom in trigonometric:
            self.values[atom] = _rational(self._trigonometric(atom, where))
        for atom in coulomb:
            self.values[atom] = _rational(self._rational())

    def _trigonometric(self, atom: se.Basic, where: str) -> Fraction:
        argument = sympy.sympify(atom.args[0])
        point = (Fraction(1), Fraction(0))
        constant = argument
        for symbol, value in self.points.items():
            coefficient = argument.coeff(sympy.sympify(symbol))
            if coefficient == 0:
                continue
            if not coefficient.is_integer:
                raise DerivationError(
                    f"{where}: the joint angle {argument} is a non-integer multiple of a "
                    "coordinate (a coupling such as a gyroscopic rotor's N q), whose sine and cosine no rational "
                    "state makes rational; the exact base parameters need integer couplings")
            turned = _power(value, int(coefficient))
            point = (point[0] * turned[0] - point[1] * turned[1], point[0] * turned[1] + point[1] * turned[0])
            constant -= coefficient * sympy.sympify(symbol)
        c, s = sympy.cos(constant), sympy.sin(constant)
        if not (c.is_Rational and s.is_Rational) or constant.free_symbols:
            raise DerivationError(
                f"{where}: the constant angle {constant} has an irrational sine or cosine, so "
                "the regressor cannot be evaluated exactly; give angles as multiples of 90 deg where the design "
                "has them (a URDF: read it with --snap-angles)")
        point = (point[0] * Fraction(str(c)) - point[1] * Fraction(str(s)),
                 point[0] * Fraction(str(s)) + point[1] * Fraction(str(c)))
        return point[0] if isinstance(atom, se.cos) else point[1]


def _rational(value: Fraction) -> se.Basic:
    return se.Rational(value.numerator, value.denominator)


def _exact(value: se.Basic, where: str) -> flint.fmpq:
    if not isinstance(value, (se.Integer, se.Rational)):
        raise DerivationError(f"{where}: the regressor is not rational at a rational state ({value}): a constant of "
                              "the model is a floating-point number or irrational (a URDF's angles: read it with "
                              "--snap-angles; a model file: give exact values, e.g. 0.1807 or deg(90))")
    fraction = Fraction(str(value))
    return flint.fmpq(fraction.numerator, fraction.denominator)


def require_exact_constants(model: Model, constants: Sequence[se.Basic]) -> None:
    """Refuse a chain whose ``constants`` (its links' rotations and origins at q = 0 and the parameters'
    defaults) are not all rational, before any work: the exact elimination cannot use them.

    Raises:
        DerivationError: naming the fix.
    """
    defaults = {se.sympify(p.symbol): se.sympify(p.value) for p in model.parameters}
    defaults.update({se.sympify(q): se.Integer(0) for q in coordinates.symbols(model, "q")})  # the constant part
    for constant in constants:
        value = constant.xreplace(defaults)
        if not isinstance(value, (se.Integer, se.Rational)):
            raise DerivationError(
                f"{model.name}: base parameters: the constant {value} of the chain's geometry is not a rational "
                "number, which the exact elimination needs (a URDF's angles: read it with --snap-angles; a model "
                "file: exact lengths such as 0.1807 and angles of a multiple of 90 deg, such as deg(90))")


def base_parameters(model: Model, Y: Sequence[Sequence[se.Basic]], names: Sequence[str],
                    seed: int = 0) -> BaseParameters:
    """The base parameters of the regressor rows ``Y`` (coordinates x parameters, SymEngine), exactly.

    Raises:
        DerivationError: a constant or a coupling that rational arithmetic cannot evaluate (see the module
            docstring), with the fix.
    """
    rows, columns = len(Y), len(names)
    flat = [e for row in Y for e in row]
    rng = random.Random(seed)
    samples = -(-columns // max(rows, 1)) + EXTRA_SAMPLES
    entries: list[flint.fmpq] = []
    where = f"{model.name}: base parameters"
    symbolic = [e for e in flat if not e.is_number]
    trigonometric = sorted(set().union(*(e.atoms(se.sin, se.cos) for e in symbolic)), key=str)
    coulomb = sorted(set().union(*(e.atoms(se.sign, se.tanh) for e in symbolic)), key=str)
    for _ in range(samples):
        sample = _ExactSample(model, rng)
        sample.bind_atoms(trigonometric, coulomb, where)
        values = sample.values
        entries += [_exact(e.xreplace(values) if not e.is_number else e, where) for e in flat]
    stacked = flint.fmpq_mat(samples * rows, columns, entries)
    echelon, rank = stacked.rref()
    base, combinations = [], []
    for r in range(rank):
        row = [Fraction(int(echelon[r, c].p), int(echelon[r, c].q)) for c in range(columns)]
        base.append(next(c for c, v in enumerate(row) if v != 0))
        combinations.append(tuple(row))
    return BaseParameters(tuple(names), tuple(base), tuple(combinations))
