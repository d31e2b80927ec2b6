"""Points of a parallel mechanism's closure over a prime field, for legs of any topology (the exact elimination of
base parameters, :mod:`symkin.parallel.base_parameters`, needs its states on the closure).

A leg with the distance form is one quadratic in its actuated variable at a drawn pose
(:class:`symkin.parallel.prime_field.Closure`).  A leg without it (the dual SCARA's, docs/model-format.md) couples
several joints: at the drawn pose p its closure rows (:mod:`symkin.parallel.closure`) are, after clearing their
denominators, polynomials in its unknowns - (C, S) = (cos, sin) of each revolute variable, with C^2 + S^2 = 1, and
each prismatic variable - whose coefficients are residues of the pose and the geometry.  That zero-dimensional
system is solved over GF(P) by elimination:

* triangularize: eliminate the unknowns one at a time, each by the resultants of the equations that hold it with a
  pivot (the one of least degree in it): every resultant lies in the system's ideal, so every solution is a zero
  of it (Cox, Little and O'Shea, Ideals, Varieties and Algorithms, ch. 3 sec. 6);
* back-substitute: the gcd of the equations univariate in some unknown at the values found so far, its roots in
  GF(P) (FLINT), each tried in turn (depth first) until every original equation vanishes.

Resultants may add roots that do not extend (their leading coefficients vanish there); those branches fail and
the next root is tried, so a point returned satisfies every equation - and, checked at the end, the rows'
denominators 1 + tr E do not vanish (the half-turn solutions of the orientation rows' numerators are not
assemblies).  Half of the poses have no point over GF(P) per square root the leg needs; they are redrawn, as the
distance legs' are.
"""

from __future__ import annotations

import dataclasses
import random
from collections.abc import Sequence
from dataclasses import dataclass

import flint
import sympy

from symkin.errors import DerivationError
from symkin.ir.spec import FunctionSpec, OutputSpec
from symkin.parallel.prime_field import FormulaEvaluator, NoPoint, PrimeField

#: Rows of the closure per leg (position, then orientation: :mod:`symkin.parallel.closure`).
ROWS_PER_LEG = 6
#: Terms of a resultant beyond which the elimination is refused as too large (the dual SCARA's legs need ~20).
MAX_TERMS = 20000


@dataclass(frozen=True)
class LegSystem:
    """One leg's closure as polynomials in its unknowns' generators - per unknown, (C, S) of a revolute variable or
    the prismatic variable itself: polynomial k is sum_m coefficient[m] * monomial[m], its coefficients the entries
    ``start[k]:start[k + 1]`` of the evaluator's output; the first ``equations`` are the rows' numerators (the
    circle equations C^2 + S^2 - 1 join them, with constant coefficients), the others the rows' denominators."""

    unknowns: tuple[sympy.Symbol, ...]
    rotations: tuple[bool, ...]
    monomials: tuple[tuple[tuple[int, ...], ...], ...]
    start: tuple[int, ...]
    equations: int

    @property
    def size(self) -> int:
        return sum(2 if r else 1 for r in self.rotations)


def _inlined(spec: FunctionSpec) -> list[sympy.Expr]:
    """The closure rows with every definition substituted (a leg's rows are small)."""
    definitions = dict(spec.definitions)
    rows = []
    for row in spec.outputs[0].expr:
        while row.free_symbols & definitions.keys():
            row = row.xreplace(definitions)
        rows.append(row)
    return rows


def _leg_polynomials(rows: Sequence[sympy.Expr], joints: set[sympy.Symbol], where: str
                     ) -> tuple[tuple[sympy.Symbol, ...], tuple[bool, ...], list[sympy.Poly], list[sympy.Poly]]:
    """(unknowns, rotation flags, the nonzero numerators and the non-constant denominators as polynomials over the
    unknowns' generators)."""
    fractions = [sympy.fraction(sympy.together(row)) for row in rows]
    unknowns = tuple(sorted(set().union(*(row.free_symbols for row in rows)) & joints, key=str))
    inside = {x for row in rows for atom in row.atoms(sympy.sin, sympy.cos) for x in atom.free_symbols}
    rotations = tuple(u in inside for u in unknowns)
    generators: list[sympy.Symbol] = []
    circle: dict[sympy.Expr, sympy.Symbol] = {}
    for k, (u, rotation) in enumerate(zip(unknowns, rotations)):
        if rotation:
            C, S = sympy.Dummy(f"C{k}"), sympy.Dummy(f"S{k}")
            circle.update({sympy.cos(u): C, sympy.sin(u): S})
            generators += [C, S]
        else:
            generators.append(u)
    polynomials: tuple[list[sympy.Poly], list[sympy.Poly]] = ([], [])
    for fraction in fractions:
        for kind, part in enumerate(fraction):
            # expand_trig splits the sums of angles; the pose's sines stay atoms, the unknowns' become (C, S)
            expanded = sympy.expand(sympy.expand(sympy.expand_trig(part), trig=False).xreplace(circle))
            left = {x for atom in expanded.atoms(sympy.sin, sympy.cos) for x in atom.free_symbols} & set(unknowns)
            outside = expanded.xreplace({a: sympy.Integer(1) for a in expanded.atoms(sympy.sin, sympy.cos)})
            if left or any(u in outside.free_symbols for u, r in zip(unknowns, rotations) if r):
                raise DerivationError(f"{where}: the closure of joint {sorted(map(str, left or unknowns))[0]} is not "
                                      "a polynomial in the sines and cosines of the revolute joints and the prismatic "
                                      "ones (a helical joint, or an angle that is a multiple of another), which the "
                                      "exact elimination needs")
            if not expanded.is_number:
                polynomials[kind].append(sympy.Poly(expanded, *generators))
            elif kind == 0 and expanded != 0:
                raise DerivationError(f"{where}: a closure row is a nonzero constant: the legs never close")
    return unknowns, rotations, polynomials[0], polynomials[1]


class ClosurePoints:
    """Draws points of the whole closure over GF(P): the platform's pose at random (its angles on the unit circle),
    then each leg's unknowns by :func:`leg_point`.

    Attributes:
        legs: each leg's system.
        coefficients: the evaluator of every leg's coefficients at a pose (and the geometry).
        check: the evaluator of the closure's numerators and denominators at a point (every numerator zero, no
            denominator zero).
    """

    def __init__(self, closure: FunctionSpec, legs: int, joints: Sequence[sympy.Symbol], where: str):
        self.where = where
        rows = _inlined(closure)
        joint_set = set(joints)
        self.legs: list[LegSystem] = []
        coefficients: list[sympy.Expr] = []
        numerators: list[sympy.Expr] = []
        denominators: list[sympy.Expr] = []
        seen: set[sympy.Symbol] = set()
        for leg in range(legs):
            leg_rows = rows[ROWS_PER_LEG * leg:ROWS_PER_LEG * (leg + 1)]
            unknowns, rotations, equations, leg_denominators = _leg_polynomials(leg_rows, joint_set, where)
            if seen & set(unknowns):
                raise DerivationError(f"{where}: joint {sorted(map(str, seen & set(unknowns)))[0]} closes two legs")
            seen |= set(unknowns)
            start = [len(coefficients)]
            for polynomial in equations + leg_denominators:
                coefficients += polynomial.coeffs()
                start.append(len(coefficients))
            self.legs.append(LegSystem(unknowns, rotations, tuple(tuple(p.monoms()) for p in equations
                                                                  + leg_denominators), tuple(start), len(equations)))
            for numerator, denominator in (sympy.fraction(sympy.together(row)) for row in leg_rows):
                numerators.append(numerator)
                denominators.append(denominator)
        if set(joints) - seen:
            raise DerivationError(f"{where}: joint {sorted(map(str, set(joints) - seen))[0]} is in no leg's closure")
        self.coefficients = FormulaEvaluator(entries_spec(closure, coefficients), where)
        self.check = FormulaEvaluator(entries_spec(closure, numerators + denominators), where)
        self._numerators = len(numerators)

    def draw(self, field: PrimeField, rng: random.Random, geometry: dict[sympy.Symbol, int]
             ) -> tuple[dict[sympy.Expr, int], dict[sympy.Symbol, tuple[int, int]]]:
        """(values, points) at a random point of the closure: residues of the pose's positions, the prismatic
        joints and ``geometry``; the unit-circle points of the pose's angles and the revolute joints.

        Raises:
            NoPoint: some leg has no point over GF(P) at the pose drawn (redraw).
        """
        values: dict[sympy.Expr, int] = dict(geometry)
        values.update({x: field.residue(rng) for x in self.coefficients.variables})
        points = {x: field.circle_point(rng) for x in self.coefficients.angle_variables}
        numbers = self.coefficients.run(self.coefficients.program, field, {
            **values, **self.coefficients.atom_values(field, rng, self.coefficients.functions, points)})
        for leg in self.legs:
            solution = leg_point(leg, numbers, field.P, rng, self.where)
            k = 0
            for u, rotation in zip(leg.unknowns, leg.rotations):
                if rotation:
                    points[u] = (solution[k], solution[k + 1])
                    values[u] = field.residue(rng)  # a revolute variable enters only through its sine and cosine
                else:
                    values[u] = solution[k]
                k += 2 if rotation else 1
        checked = self.check.run(self.check.program, field, {
            **values, **self.check.atom_values(field, rng, self.check.functions, points)})
        if any(checked[:self._numerators]):
            raise DerivationError(f"{self.where}: a point found over a prime field does not close the legs "
                                  "(please report it)")
        if not all(checked[self._numerators:]):
            raise NoPoint  # a half turn of an orientation row: not an assembly
        return values, points


def entries_spec(closure: FunctionSpec, entries: Sequence[sympy.Expr]) -> FunctionSpec:
    """The closure's inputs with ``entries`` as the one output (an evaluator's formula)."""
    return dataclasses.replace(closure, definitions=(), outputs=(
        OutputSpec("entries", sympy.ImmutableMatrix(list(entries)), "", shape=(len(entries),)),))


def leg_point(leg: LegSystem, numbers: Sequence[int], P: int, rng: random.Random, where: str) -> list[int]:
    """A solution of ``leg``'s equations with its coefficients ``numbers`` (the module docstring's elimination), in
    the order of its generators.

    Raises:
        NoPoint: the equations have no solution over GF(P) (or none that the elimination reaches).
    """
    names = tuple(f"u{k}" for k in range(leg.size))
    context = flint.nmod_mpoly_ctx.get(names, ordering="lex", modulus=P)
    polynomials = [context.from_dict({m: numbers[leg.start[k] + i] for i, m in enumerate(monomials)})
                   for k, monomials in enumerate(leg.monomials)]
    equations, denominators = polynomials[:leg.equations], polynomials[leg.equations:]
    k = 0
    for rotation in leg.rotations:
        if rotation:
            C, S = context.gen(k), context.gen(k + 1)
            equations.append(C * C + S * S - 1)
        k += 2 if rotation else 1
    solution = _back_substitute(context, equations + _eliminants(context, equations, where), denominators, {}, rng)
    if solution is None:
        raise NoPoint
    return [solution[i] for i in range(leg.size)]


def _eliminants(context: flint.nmod_mpoly_ctx, equations: Sequence[flint.nmod_mpoly], where: str
                ) -> list[flint.nmod_mpoly]:
    """The resultants of the triangularization: each unknown in turn (the one fewest equations hold, then of least
    degree) eliminated from the equations that hold it by their resultants with a pivot."""
    names = context.names()
    system = [f for f in equations if not f.is_zero()]
    found: list[flint.nmod_mpoly] = []
    remaining = set(range(len(names)))
    while len(remaining) > 1:
        candidates = [(len(having), min(f.degrees()[v] for f in having), v, having) for v in sorted(remaining)
                      if (having := [f for f in system if f.degrees()[v]])]
        if not candidates:
            break
        _, _, v, having = min(candidates, key=lambda c: c[:3])
        pivot = min(having, key=lambda f: (f.degrees()[v], f.total_degree(), len(f)))
        system = [f for f in system if not f.degrees()[v]]
        for f in having:
            if f is pivot:
                continue
            resultant = f.resultant(pivot, names[v])
            if len(resultant) > MAX_TERMS:
                raise DerivationError(f"{where}: a leg's closure is too large for the elimination over a prime "
                                      f"field (a resultant of {len(resultant)} terms)")
            if not resultant.is_zero():
                system.append(resultant)
                found.append(resultant)
        remaining.discard(v)
    return found


def _back_substitute(context: flint.nmod_mpoly_ctx, equations: Sequence[flint.nmod_mpoly],
                     denominators: Sequence[flint.nmod_mpoly], known: dict[int, int], rng: random.Random
                     ) -> dict[int, int] | None:
    """Values of the unknowns extending ``known`` (already substituted into ``equations``) at which every equation
    vanishes and no denominator, or None."""
    names = context.names()
    left = [f for f in equations if not f.is_zero()]
    if any(f.is_constant() for f in left):
        return None
    if len(known) == len(names):
        substitution: dict[str | int, int] = {names[i]: v for i, v in known.items()}
        return known if all(not f.subs(substitution).is_zero() for f in denominators) else None
    univariate: dict[int, list[flint.nmod_mpoly]] = {}
    for g in left:
        used = [i for i, degree in enumerate(g.degrees()) if degree]
        if len(used) == 1:
            univariate.setdefault(used[0], []).append(g)
    if not univariate:
        return None
    i = min(univariate, key=lambda v: (min(g.degrees()[v] for g in univariate[v]), v))
    common = univariate[i][0]
    for g in univariate[i][1:]:
        common = common.gcd(g)
    coefficients = [0] * (common.degrees()[i] + 1)
    for monomial, c in zip(common.monoms(), common.coeffs()):
        coefficients[monomial[i]] = int(c)
    roots = [int(r) for r, _ in flint.nmod_poly(coefficients, context.modulus()).roots()]
    rng.shuffle(roots)
    for root in roots:
        found = _back_substitute(context, [f.subs({names[i]: root}) if f.degrees()[i] else f for f in left],
                                 denominators, {**known, i: root}, rng)
        if found is not None:
            return found
    return None
