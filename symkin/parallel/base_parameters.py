"""The base parameters of a parallel mechanism's regressor, exactly, by modular arithmetic.

A serial chain's regressor is rational at rational states (:mod:`symkin.dynamics.base_parameters`).  A
parallel mechanism's is not: its legs stand at constant angles whose sines are irrational (the DELTA's
120 deg: sqrt(3)/2), so at a rational state Y lies in a number field Q(sqrt r_1, ..., sqrt r_m), and rational
arithmetic in that field with the geometry kept symbolic is far too slow (minutes for the DELTA).  Here Y is
evaluated in the prime field GF(P) instead (:mod:`symkin.parallel.prime_field`), P a random prime of about 61
bits in which every radicand r_i has a square root: each sqrt r_i is sent to one of its roots mod P, the
platform's angles to random points of the unit circle mod P ((1 - t^2, 2t) / (1 + t^2)), its positions, the
rates and the geometry (the model's parameters that enter Y) to random residues, and each leg's actuated
variable to a root of its closure at that pose (a quadratic; its square root exists mod P at half the poses,
the others are redrawn).  That is a point of the assembled mechanism over GF(P), and evaluating Y there a ring
homomorphism of the exact values, so every linear dependency of Y's columns on the closure holds mod P; one
seen mod P at random points holds exactly but with a probability of order (degree) / P (Schwartz-Zippel; the
same argument as the rational samples of the serial method, with far more room).  On the closure matters: the
Agile Eye's formula has 31 columns independent for every (q, p), 28 on the closure.  The base parameters'
quantity (:mod:`symkin.parallel.base_regressor`) still compares the count with the numerical rank of Y stacked
over states assembled in floating point.

The base columns are the pivots of the reduced row echelon form of the stacked samples mod P (the earlier
columns preferred, as in the serial method); its rows are K(G) mod P at the geometry G drawn.  K depends on
G (the DELTA's elbow masses regroup as a m_C and a^2 m_C): each entry is taken as a polynomial in the
parameters it depends on (those whose change moves it), of the least total degree that fits, interpolated
from the echelon forms at as many values of G as it has monomials and checked at two more - or, where none of
that degree fits, as a ratio N/D of polynomials (the dual SCARA's bar regroups hand inertia with 1/e), the
coefficients of N and D the null space of the linearized conditions N(G_k) = K(G_k) D(G_k) (multivariate
rational interpolation, e.g. Cuyt and Lee 2011), D's first nonzero coefficient scaled to 1; each coefficient,
an element of the number field, is recovered from its images under the 2^m choices of the roots' signs
(their signed sums give its coordinates on the products of square roots) by rational reconstruction.  The
result is verified with an independent prime: Y_j = Y_b K_j at fresh states and geometry.
"""

from __future__ import annotations

import itertools
import random
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol

import flint
import sympy

from symkin.dynamics.base_parameters import EXTRA_SAMPLES, BaseParameters
from symkin.errors import DerivationError
from symkin.ir.spec import FunctionSpec
from symkin.parallel.modular_program import ModularProgram
from symkin.parallel.prime_field import Closure, FormulaEvaluator, PrimeField

#: The highest total degree (of N plus D where an entry of K is N/D) in the geometry tried before giving up.
MAX_DEGREE = 6
#: Values of the geometry at which a fitted entry of K is checked beyond those it was fitted to.
CHECK_POINTS = 2


class RegressorField(Protocol):
    """A regressor evaluated mod P at random states on the closure (:class:`FormulaEvaluator`, or
    :class:`symkin.parallel.closure_base.ClosureRegressorField` for legs without the distance form)."""

    shape: tuple[int, ...]
    geometry: list[sympy.Symbol]
    radicands: list[int]

    def rows(self, field: PrimeField, rng: random.Random, geometry: dict[sympy.Symbol, int]) -> list[int]:
        """Y's entries, row-major, at a random state and ``geometry``."""

    def run(self, program: ModularProgram, field: PrimeField, values: dict[sympy.Expr, int]) -> list[int]:
        """``program``'s outputs at ``values`` of its leaves."""


@dataclass
class _Echelon:
    """The stacked samples' reduced row echelon form mod P at one geometry: the pivots and K mod P."""

    base: tuple[int, ...]
    K: list[list[int]]


def _echelon(evaluator: RegressorField, field: PrimeField, geometry: dict[sympy.Symbol, int], seed: int) -> _Echelon:
    """The samples stacked until EXTRA_SAMPLES states in a row add no rank (a random state's rows fall in the span
    of the others' short of the rank with a probability of order degree / P), in reduced row echelon form: far
    fewer states than columns / rows where many columns depend on the others (the dual SCARA's 96 columns, rank 24
    from 4 rows a state), at most that many plus EXTRA_SAMPLES."""
    rows, columns = evaluator.shape
    limit = -(-columns // max(rows, 1)) + EXTRA_SAMPLES
    rng = random.Random(seed)
    stacked: list[int] = []
    rank = unchanged = samples = 0
    while unchanged < EXTRA_SAMPLES and samples < limit:
        stacked += evaluator.rows(field, rng, geometry)
        samples += 1
        grown = flint.nmod_mat(samples * rows, columns, stacked, field.P).rank()
        unchanged, rank = (unchanged + 1 if grown == rank else 0), grown
    echelon, rank = flint.nmod_mat(samples * rows, columns, stacked, field.P).rref()
    K = [[int(echelon[r, c]) for c in range(columns)] for r in range(rank)]
    return _Echelon(tuple(next(c for c, v in enumerate(row) if v) for row in K), K)


def _reconstruct(value: int, P: int) -> sympy.Rational | None:
    """The rational n/d with |n|, d <= sqrt(P/2) that is ``value`` mod P (Wang's rational reconstruction)."""
    bound = int((P // 2) ** 0.5)
    r0, r1, s0, s1 = P, value % P, 0, 1
    while r1 > bound:
        quotient = r0 // r1
        r0, r1, s0, s1 = r1, r0 - quotient * r1, s1, s0 - quotient * s1
    if s1 == 0 or abs(s1) > bound:
        return None
    return sympy.Rational(r1, s1)


def modular_base_parameters(spec: FunctionSpec, names: Sequence[str], where: str, closures: Sequence[Closure] = (),
                            seed: int = 0) -> BaseParameters:
    """The base parameters of the parallel regressor ``spec`` (its first output Y, columns ``names``), exactly,
    with the geometry that enters Y kept as symbols (the module docstring has the method), at states on the
    legs' ``closures``.

    Raises:
        DerivationError: an atom or constant the modular evaluation cannot take, or a dependency of K on the
            geometry that is not a ratio of polynomials of total degree <= MAX_DEGREE, with the fix.
    """
    return field_base_parameters(FormulaEvaluator(spec, where, closures), names, where, seed)


def field_base_parameters(evaluator: RegressorField, names: Sequence[str], where: str, seed: int = 0
                          ) -> BaseParameters:
    """The base parameters of the regressor that ``evaluator`` evaluates mod P (columns ``names``)."""
    rng = random.Random(seed)
    embeddings = PrimeField.embeddings(rng, evaluator.radicands)
    field = embeddings[0]
    geometry = evaluator.geometry

    def draw() -> dict[sympy.Symbol, int]:
        return {g: field.residue(rng) for g in geometry}

    first_point = draw()
    first = _echelon(evaluator, field, first_point, seed)
    dependent = [(r, j) for r, row in enumerate(first.K) for j, v in enumerate(row) if j not in first.base and v]
    moved: dict[tuple[int, int], list[sympy.Symbol]] = {key: [] for key in dependent}
    for g in geometry:
        nudged = _echelon(evaluator, field, {**first_point, g: field.residue(rng)}, seed)
        if nudged.base != first.base:
            raise DerivationError(f"{where}: the base columns differ between two random values of the geometry (a "
                                  "special value drawn by chance: please report it)")
        for r, j in dependent:
            if nudged.K[r][j] != first.K[r][j]:
                moved[(r, j)].append(g)
    samples = _Samples(evaluator, embeddings, seed, draw, first_point, first, where)
    combinations = [[sympy.Integer(1 if c == b else 0) for c in range(len(names))] for b in first.base]
    for r, j in dependent:
        combinations[r][j] = _fitted(samples, (r, j), moved[(r, j)], f"{where}: K[{names[first.base[r]]}, {names[j]}]")
    found = BaseParameters(tuple(names), first.base, tuple(tuple(row) for row in combinations),
                           tuple(sorted({str(s) for row in combinations for k in row for s in k.free_symbols})))
    _verify(evaluator, found, random.Random(seed + 1), where)
    return found


class _Samples:
    """The echelon forms at the k-th value of the geometry (the first given, the others drawn when first asked for),
    one per embedding."""

    def __init__(self, evaluator: RegressorField, embeddings: list[PrimeField], seed: int,
                 draw: Callable[[], dict[sympy.Symbol, int]], first_point: dict[sympy.Symbol, int], first: _Echelon,
                 where: str):
        self.evaluator, self.embeddings, self.seed, self.draw, self.where = evaluator, embeddings, seed, draw, where
        self.points = [first_point]
        self.echelons = [[first] + [_echelon(evaluator, e, first_point, seed) for e in embeddings[1:]]]
        self._check(first.base)

    def _check(self, base: tuple[int, ...]) -> None:
        if any(e.base != base for e in self.echelons[-1]):
            raise DerivationError(f"{self.where}: the base columns differ between random values of the geometry or "
                                  "choices of the square roots (please report it)")

    def point(self, k: int) -> dict[sympy.Symbol, int]:
        while len(self.points) <= k:
            self.points.append(self.draw())
            self.echelons.append([_echelon(self.evaluator, e, self.points[-1], self.seed) for e in self.embeddings])
            self._check(self.echelons[0][0].base)
        return self.points[k]

    def value(self, k: int, embedding: int, entry: tuple[int, int]) -> int:
        self.point(k)
        return self.echelons[k][embedding].K[entry[0]][entry[1]]


def _fitted(samples: _Samples, entry: tuple[int, int], variables: Sequence[sympy.Symbol], where: str) -> sympy.Expr:
    """An entry of K as a rational function N/D of ``variables`` (a polynomial where D = 1): the least total degree
    deg N + deg D, the polynomials first, whose interpolation at the first points also fits the next CHECK_POINTS,
    its coefficients taken from the embeddings' images to the number field."""
    field, radicands = samples.embeddings[0], samples.evaluator.radicands
    plain = [sympy.Symbol(str(v)) for v in variables]  # as the serial K's: BaseParameters.evaluate's keys
    for total in range((MAX_DEGREE if variables else 0) + 1):
        for denominator_degree in range(total + 1):
            numerator = _monomials(len(variables), total - denominator_degree)
            denominator = _monomials(len(variables), denominator_degree)
            fit = (_polynomial_fit(samples, entry, variables, numerator) if not denominator_degree else
                   _rational_fit(samples, entry, variables, numerator, denominator))
            if fit is None:
                continue
            monomials = numerator + (denominator if denominator_degree else [])
            terms = [sympy.Mul(*(v ** e for v, e in zip(plain, m))) for m in monomials]
            value = [_number(field, radicands, [c[i] for c in fit], where) * t for i, t in enumerate(terms)]
            if not denominator_degree:
                return sum(value, sympy.Integer(0))
            return sum(value[:len(numerator)], sympy.Integer(0)) / sum(value[len(numerator):], sympy.Integer(0))
    raise DerivationError(f"{where}: depends on the geometry ({', '.join(map(str, variables))}) otherwise than as a "
                          f"ratio of polynomials of total degree <= {MAX_DEGREE} (a sine of an angle), which the "
                          "exact regrouping does not represent yet; write those parameters' values into the model "
                          "file in their place")


def _monomials(count: int, degree: int) -> list[tuple[int, ...]]:
    return [m for m in itertools.product(range(degree + 1), repeat=count) if sum(m) <= degree]


def _polynomial_fit(samples: _Samples, entry: tuple[int, int], variables: Sequence[sympy.Symbol],
                    monomials: list[tuple[int, ...]]) -> list[list[int]] | None:
    """Per embedding, the coefficients of the polynomial on ``monomials`` through the entry's values at the first
    points, if it also fits the next CHECK_POINTS (None otherwise)."""
    P = samples.embeddings[0].P
    checks = CHECK_POINTS if variables else 0  # without geometry every draw is the first: nothing to check

    def row(k: int) -> list[int]:
        return [_monomial(samples.point(k), variables, m, P) for m in monomials]

    count = len(monomials)
    try:
        inverse = flint.nmod_mat([row(k) for k in range(count)], P).inv()
    except ZeroDivisionError:
        return None
    per_embedding = []
    for s in range(len(samples.embeddings)):
        coefficients = inverse * flint.nmod_mat([[samples.value(k, s, entry)] for k in range(count)], P)
        fits = all(sum(int(c) * x for c, x in zip((coefficients[i, 0] for i in range(count)), row(k))) % P
                   == samples.value(k, s, entry) for k in range(count, count + checks))
        if not fits:
            return None
        per_embedding.append([int(coefficients[i, 0]) for i in range(count)])
    return per_embedding


def _rational_fit(samples: _Samples, entry: tuple[int, int], variables: Sequence[sympy.Symbol],
                  numerator: list[tuple[int, ...]], denominator: list[tuple[int, ...]]) -> list[list[int]] | None:
    """Per embedding, the coefficients (N's, then D's) of N/D through the entry's values v at the first points -
    the one-dimensional null space of N(G_k) - v_k D(G_k) = 0, scaled so that D's first coefficient that is not
    zero is 1 - if it also fits the next CHECK_POINTS (D not zero there; None otherwise)."""
    P = samples.embeddings[0].P
    count = len(numerator) + len(denominator)

    def row(k: int, s: int) -> list[int]:
        value = samples.value(k, s, entry)
        return ([_monomial(samples.point(k), variables, m, P) for m in numerator]
                + [-value * _monomial(samples.point(k), variables, m, P) % P for m in denominator])

    per_embedding: list[list[int]] = []
    pivot = None
    for s in range(len(samples.embeddings)):
        null, nullity = flint.nmod_mat([row(k, s) for k in range(count - 1)], P).nullspace()
        if nullity != 1:
            return None
        vector = [int(null[i, 0]) for i in range(count)]
        if pivot is None:
            pivot = next((i for i in range(len(numerator), count) if vector[i]), None)
        if pivot is None or not vector[pivot]:
            return None
        scale = pow(vector[pivot], -1, P)
        vector = [v * scale % P for v in vector]
        for k in range(count - 1, count - 1 + CHECK_POINTS):
            point = samples.point(k)
            N, D = (sum(c * _monomial(point, variables, m, P) for c, m in zip(part, monomials)) % P
                    for part, monomials in ((vector[:len(numerator)], numerator), (vector[len(numerator):], denominator)))
            if not D or N != samples.value(k, s, entry) * D % P:
                return None
        per_embedding.append(vector)
    return per_embedding


def _monomial(point: dict[sympy.Symbol, int], variables: Sequence[sympy.Symbol], powers: Sequence[int], P: int) -> int:
    out = 1
    for v, e in zip(variables, powers):
        out = out * pow(point[v], e, P) % P
    return out


def _number(field: PrimeField, radicands: Sequence[int], images: Sequence[int], where: str) -> sympy.Expr:
    """The element of Q(sqrt r_1, ...) whose images under the sign choices (itertools.product order) are ``images``:
    its coordinate on prod_{i in S} sqrt r_i is the signed mean of the images over prod_{i in S} root_i."""
    P = field.P
    signs = list(itertools.product((1, -1), repeat=len(radicands)))
    total = sympy.Integer(0)
    for subset in itertools.product((0, 1), repeat=len(radicands)):
        mean = 0
        for sign, image in zip(signs, images):
            weight = 1
            for s, inside in zip(sign, subset):
                weight *= s if inside else 1
            mean = (mean + weight * image) % P
        root = 1
        for r, inside in zip(radicands, subset):
            root = root * (field.roots[r] if inside else 1) % P
        coordinate = _reconstruct(mean * field.inverse(len(signs) * root % P) % P, P)
        if coordinate is None:
            raise DerivationError(f"{where}: a coefficient is not a rational of moderate size (please report it)")
        total += coordinate * sympy.Mul(*(sympy.sqrt(r) for r, inside in zip(radicands, subset) if inside))
    return total


def _verify(evaluator: RegressorField, found: BaseParameters, rng: random.Random, where: str) -> None:
    """Y_j = Y_b K_j for every column at fresh states and geometry, with an independent prime and either sign of
    each square root."""
    rows, columns = evaluator.shape
    entries = ModularProgram((), [k for row in found.combinations for k in row], set(), where)  # polynomials in G
    for embedding in PrimeField.embeddings(rng, evaluator.radicands):
        geometry = {g: embedding.residue(rng) for g in evaluator.geometry}
        flat = evaluator.run(entries, embedding, {sympy.Symbol(str(g)): v for g, v in geometry.items()})
        K = [flat[r * columns:(r + 1) * columns] for r in range(len(found.combinations))]
        for _ in range(EXTRA_SAMPLES):
            Y = evaluator.rows(embedding, rng, geometry)
            for i in range(rows):
                for j in range(columns):
                    rebuilt = sum(Y[i * columns + b] * K[r][j] for r, b in enumerate(found.base)) % embedding.P
                    if rebuilt != Y[i * columns + j]:
                        raise DerivationError(f"{where}: the regrouping fails a check with another prime at column "
                                              f"{found.names[j]} (please report it)")
