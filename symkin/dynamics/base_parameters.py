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

The model's parameters that enter Y (lengths, offsets, gravity) stay symbols: K is exact for every value
of them, as the generated functions take them (a base regressor evaluated at another link length than the
default keeps Y_b pi_b = Y pi).  The echelon form is taken at two random rational values of those
parameters (nonzero, from a wide range); the pivots and the support of each column of K (which base
parameters a standard one regroups into) come from it, and each dependent column is then solved
symbolically from as many sampled rows as its support has entries, Y_S(q, P) k_j(P) = Y_j(q, P), over the
rational functions of P (sympy's DomainMatrix).  The result is checked against both echelon forms exactly.
For a serial chain these are Khalil's regrouping rules with the geometry kept: link 2's mass enters link
1's first moment as l1 m2 and its inertia as l1^2 m2, for any l1.

A constant angle whose sine or cosine is not rational (a URDF angle of 1.5708 rad; read it with
``--snap-angles``), an angle kept as a parameter, or a coupling with a non-integer ratio (a gyroscopic
rotor's N q) cannot be evaluated exactly, and is refused.
"""

from __future__ import annotations

import random
from collections.abc import Mapping, Sequence
from typing import Any
from dataclasses import dataclass
from fractions import Fraction

import flint
import numpy as np
import symengine as se
import sympy
from sympy.polys.matrices import DomainMatrix
from sympy.polys.rings import ring as sympy_ring

from symkin.errors import DerivationError, ModelDataError, Problem
from symkin.model import coordinates
from symkin.model.schema import Model

#: Samples stacked beyond the fewest that could reveal every parameter (rows = samples x coordinates).
EXTRA_SAMPLES = 4
#: Numerators and denominators of the sampled rationals: small, so that the exact arithmetic stays fast.
SAMPLE_RANGE = 97
#: Numerators and denominators of the parameters' sampled values (nonzero): wide, so that a regrouping
#: coefficient vanishes at them only by a negligible chance.
PARAMETER_RANGE = 10007


@dataclass(frozen=True)
class BaseParameters:
    """The base parameters: pi_b = K pi, and the columns of Y that form Y_b.

    Attributes:
        names: the standard parameters' names (Y's columns).
        base: the indices of Y's columns that form Y_b (each base parameter is named after its column).
        combinations: K (len(base) x len(names)), exact: sympy numbers, or rational functions of the model's
            parameters named in ``geometry`` where those enter Y; pi_b = K pi and Y = Y_b K for every value of them.
        geometry: the names of the model's parameters that K depends on (empty: K is a matrix of rationals).
    """

    names: tuple[str, ...]
    base: tuple[int, ...]
    combinations: tuple[tuple[sympy.Expr, ...], ...]
    geometry: tuple[str, ...] = ()

    @property
    def base_names(self) -> tuple[str, ...]:
        """A base parameter is named after its column, with an ``R`` where it regroups others (``link1.mxR``)."""
        return tuple(self.names[b] + ("R" if sum(1 for k in row if k != 0) > 1 else "")
                     for b, row in zip(self.base, self.combinations))

    def equations(self) -> tuple[str, ...]:
        """Each base parameter as the combination it stands for: ``link1.mxR = link1.mx + l1 link2.m``."""
        lines = []
        for name, row in zip(self.base_names, self.combinations):
            terms = []
            for k, coefficient in enumerate(row):
                if coefficient == 0:
                    continue
                negative = coefficient.could_extract_minus_sign()
                size = -coefficient if negative else coefficient
                factor = "" if size == 1 else f"({size}) " if isinstance(size, sympy.Add) else f"{size} "
                terms.append(f"{'-' if negative else '+'} {factor}{self.names[k]}")
            text = " ".join(terms)
            lines.append(f"{name} = {text[2:] if text.startswith('+ ') else text}")
        return tuple(lines)

    def evaluate(self, values: Mapping[str, float]) -> np.ndarray:
        """K as floats at the values of its ``geometry`` (keyed by parameter name; a model's defaults:
        ``{p.name: p.value for p in model.parameters}``).

        Raises:
            ValueError: ``values`` misses a parameter K depends on (named, with the ones it needs).
        """
        missing = [name for name in self.geometry if name not in values]
        if missing:
            raise ValueError(f"K depends on {', '.join(self.geometry)}: give the value of {', '.join(missing)}")
        symbols = [sympy.Symbol(name) for name in self.geometry]
        point = {symbol: sympy.sympify(values[name]) for symbol, name in zip(symbols, self.geometry)}
        return np.array([[float(k.xreplace(point)) for k in row] for row in self.combinations], dtype=float)


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
        revolute = {se.sympify(s) for s, c in zip(coordinates.symbols(model, "q"), model.coordinates)
                    if c.turns}
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
        ModelDataError: the model file's data is the cause (bad input, exit 2), naming the fix.
    """
    defaults = {se.sympify(p.symbol): se.sympify(p.value) for p in model.parameters}
    defaults.update({se.sympify(q): se.Integer(0) for q in coordinates.symbols(model, "q")})  # the constant part
    for constant in constants:
        value = constant.xreplace(defaults)
        if not isinstance(value, (se.Integer, se.Rational)):
            raise ModelDataError([Problem(
                model.source, None, None, "", f"{model.name}: base parameters: the constant {value} of the chain's "
                "geometry is not a rational number, which the exact elimination needs",
                "a URDF's angles: read it with --snap-angles; a model file: exact lengths such as 0.1807 and "
                "angles of a multiple of 90 deg, such as deg(90)")])


def base_parameters(model: Model, Y: Sequence[Sequence[se.Basic]], names: Sequence[str],
                    seed: int = 0) -> BaseParameters:
    """The base parameters of the regressor rows ``Y`` (coordinates x parameters, SymEngine), exactly, with the
    model's parameters that enter Y kept as symbols (the module docstring has the method).

    Raises:
        DerivationError: a constant or a coupling that rational arithmetic cannot evaluate (see the module
            docstring), with the fix.
    """
    rows, columns = len(Y), len(names)
    flat = [e for row in Y for e in row]
    rng = random.Random(seed)
    samples = -(-columns // max(rows, 1)) + EXTRA_SAMPLES
    where = f"{model.name}: base parameters"
    symbolic = [e for e in flat if not e.is_number]
    atoms = set().union(*(e.atoms(se.sin, se.cos, se.sign, se.tanh) for e in symbolic))
    trigonometric = sorted((a for a in atoms if isinstance(a, (se.sin, se.cos))), key=str)
    coulomb = sorted((a for a in atoms if isinstance(a, (se.sign, se.tanh))), key=str)
    stacked: list[se.Basic] = []  # the samples' rows: Y at rational states, a function of the parameters only
    for _ in range(samples):
        sample = _ExactSample(model, rng)
        sample.bind_atoms(trigonometric, coulomb, where)
        stacked += [e.xreplace(sample.values) if not e.is_number else e for e in flat]
    geometry = _entering_parameters(model, stacked, where)
    if not geometry:
        only = _Echelon(stacked, samples * rows, columns, {}, where)
        combinations = tuple(tuple(sympy.Rational(k.numerator, k.denominator) for k in row) for row in only.K)
        return BaseParameters(tuple(names), only.base, combinations)
    echelons = [_Echelon(stacked, samples * rows, columns, _parameter_point(geometry, rng), where) for _ in range(2)]
    first, second = echelons
    if first.base != second.base:
        raise DerivationError(f"{where}: the base columns differ between two random values of the parameters "
                              f"{', '.join(map(str, geometry))} (a special value drawn by chance: please report it)")
    K = _symbolic_combinations(stacked, columns, echelons, geometry)
    for echelon in echelons:
        point = {sympy.Symbol(str(p)): sympy.Rational(v.numerator, v.denominator) for p, v in echelon.point.items()}
        if any(k.xreplace(point) != sympy.Rational(e.numerator, e.denominator)
               for row, exact in zip(K, echelon.K) for k, e in zip(row, exact)):
            raise DerivationError(f"{where}: the symbolic regrouping disagrees with the echelon form at a sampled "
                                  "value of the parameters (a special value drawn by chance: please report it)")
    depends = sorted({str(symbol) for row in K for k in row for symbol in k.free_symbols})
    return BaseParameters(tuple(names), first.base, K, tuple(depends))


def _entering_parameters(model: Model, stacked: Sequence[se.Basic], where: str) -> list[se.Symbol]:
    """The model's parameters left in the sampled rows (outside every sine, cosine and Coulomb shape)."""
    left = sorted(set().union(*(e.free_symbols for e in stacked if not e.is_number)), key=str)
    known = {str(p.symbol) for p in model.parameters}
    strangers = [str(s) for s in left if str(s) not in known]
    if strangers:
        raise DerivationError(f"{where}: the regressor keeps the symbols {', '.join(strangers)} at a sampled state, "
                              "which are neither coordinates nor the model's parameters")
    return left


def _parameter_point(geometry: Sequence[se.Symbol], rng: random.Random) -> dict[se.Symbol, Fraction]:
    """A random nonzero rational value of each parameter, from a range wide enough that a polynomial of the
    regrouping vanishes there only by a chance of about its degree in PARAMETER_RANGE."""
    return {p: Fraction(rng.choice((-1, 1)) * rng.randint(1, PARAMETER_RANGE), rng.randint(1, PARAMETER_RANGE))
            for p in geometry}


class _Echelon:
    """The sampled rows at one value of the parameters, brought to reduced row echelon form over the rationals."""

    def __init__(self, stacked: Sequence[se.Basic], rows: int, columns: int, point: dict[se.Symbol, Fraction],
                 where: str):
        values = {p: _rational(v) for p, v in point.items()}
        self.point = point
        self.matrix = flint.fmpq_mat(rows, columns, [_exact(e.xreplace(values) if not e.is_number else e, where)
                                                     for e in stacked])
        echelon, rank = self.matrix.rref()
        self.K = [[Fraction(int(echelon[r, c].p), int(echelon[r, c].q)) for c in range(columns)]
                  for r in range(rank)]
        self.base = tuple(next(c for c, v in enumerate(row) if v != 0) for row in self.K)

    def independent_rows(self, columns: Sequence[int]) -> list[int]:
        """As many rows as ``columns`` on which those columns are linearly independent."""
        block = flint.fmpq_mat([[self.matrix[r, c] for r in range(self.matrix.nrows())] for c in columns])
        echelon, rank = block.rref()
        return [next(r for r in range(echelon.ncols()) if echelon[i, r] != 0) for i in range(rank)]


def _symbolic_combinations(stacked: Sequence[se.Basic], columns: int, echelons: Sequence[_Echelon],
                           geometry: Sequence[se.Symbol]) -> tuple[tuple[sympy.Expr, ...], ...]:
    """K over the rational functions of the parameters: the dependent columns j of one support S (the base
    parameters they regroup into) solved together from |S| sampled rows, Y_S k_j = Y_j (the rows on which Y_S
    has full rank at the first sampled value); the rows' entries are polynomials in the parameters."""
    first = echelons[0]
    base, rank = first.base, len(first.base)
    polynomials, *_ = sympy_ring([str(p) for p in geometry], sympy.QQ)
    domain = polynomials.to_domain()

    def entry(row: int, column: int) -> Any:
        return polynomials.from_expr(sympy.sympify(se.expand(stacked[row * columns + column])))

    K = [[sympy.Integer(1 if c == b else 0) for c in range(columns)] for b in base]
    groups: dict[tuple[int, ...], list[int]] = {}
    for j in range(columns):
        support = tuple(r for r in range(rank) if j not in base and any(e.K[r][j] != 0 for e in echelons))
        if support:
            groups.setdefault(support, []).append(j)
    for support, dependent in groups.items():
        picked = first.independent_rows([base[r] for r in support])
        system = DomainMatrix([[entry(row, base[r]) for r in support] for row in picked], (len(picked), len(support)),
                              domain)
        rhs = DomainMatrix([[entry(row, j) for j in dependent] for row in picked], (len(picked), len(dependent)),
                           domain)
        solution = system.to_field().lu_solve(rhs.to_field()).to_Matrix()
        for i, r in enumerate(support):
            for k, j in enumerate(dependent):
                K[r][j] = sympy.factor_terms(solution[i, k])
    return tuple(tuple(row) for row in K)
