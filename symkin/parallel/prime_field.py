"""A derived formula evaluated exactly in a prime field GF(P): the arithmetic of the exact elimination of
parallel models' base parameters (:mod:`symkin.parallel.base_parameters`, whose docstring has why).

P is a random prime of about 61 bits, P = 3 mod 4 (a square root is then one power, x^((P+1)/4), and -1 has
none, so 1 + t^2 never vanishes), in which every radicand of the formula's constants has a square root;
each square root is sent to one of its roots mod P (both signs are embeddings: :meth:`PrimeField.embeddings`),
a sine and cosine of an angle to a point of the unit circle mod P ((1 - t^2, 2t) / (1 + t^2), integer
multiples by de Moivre), a Coulomb shape and every other input to random residues.  Every step is a ring
homomorphism of the exact values, so an identity of the formula holds at the residues.
"""

from __future__ import annotations

import itertools
import random
from collections.abc import Sequence
from dataclasses import dataclass

import sympy
from sympy.ntheory import factorint, nextprime

from symkin.errors import DerivationError
from symkin.ir.spec import FunctionSpec
from symkin.parallel.modular_program import ModularProgram

#: Bits of the random primes: residues fit a machine word, and a chance dependency has probability ~ 2^-50.
PRIME_BITS = 61
#: Square roots of the state a draw may need (each leg's closure, each root in the formula): each exists at about
#: half the draws, so a state takes 2^n draws on average; more than this is refused as too slow.
MAX_SQUARE_ROOTS = 6
#: States drawn before giving up (at MAX_SQUARE_ROOTS, a miss has a probability of about 1e-7).
CLOSURE_DRAWS = 1000


class PrimeField:
    """GF(P) with a chosen square root of each radicand prime (signs: +1 keeps the root found, -1 negates it)."""

    def __init__(self, P: int, radicands: Sequence[int], signs: Sequence[int]):
        self.P = P
        self.radicands = tuple(radicands)
        self.roots = {r: square_root_mod(r, P) * s % P for r, s in zip(radicands, signs)}

    @staticmethod
    def embeddings(rng: random.Random, radicands: Sequence[int]) -> list[PrimeField]:
        """A random prime P = 3 mod 4 in which every radicand has a square root, with each choice of the roots'
        signs (itertools.product order: the first keeps every root :func:`square_root_mod` finds)."""
        prime = nextprime(rng.getrandbits(PRIME_BITS) | (1 << (PRIME_BITS - 1)))
        while prime % 4 != 3 or any(pow(r, (prime - 1) // 2, prime) != 1 for r in radicands):
            prime = nextprime(prime)
        return [PrimeField(prime, radicands, signs) for signs in itertools.product((1, -1), repeat=len(radicands))]

    def inverse(self, x: int) -> int:
        if x % self.P == 0:
            raise ZeroDivisionError
        return pow(x, -1, self.P)

    def rational(self, value: sympy.Rational) -> int:
        return int(value.p) * self.inverse(int(value.q)) % self.P

    def square_root(self, value: sympy.Rational) -> int:
        """sqrt(n / d), value > 0, from the chosen roots of the primes that n and d hold to an odd power."""
        roots = []
        for n in (int(value.p), int(value.q)):
            root = 1
            for prime, k in factorint(n).items():
                root = root * pow(prime, k // 2, self.P) * (self.roots[prime] if k % 2 else 1) % self.P
            roots.append(root)
        return roots[0] * self.inverse(roots[1]) % self.P

    def constant(self, number: sympy.Expr) -> int:
        """A compiled formula's constant leaf (:attr:`ModularProgram.numbers`): a rational r, or r^(k/2), k odd,
        r > 0, as r^((k-1)/2) sqrt(r)."""
        if number.is_Rational:
            return self.rational(number)
        base, exponent = number.args
        whole, half = self.rational(base), (int(exponent.p) - 1) // 2
        return pow(whole if half >= 0 else self.inverse(whole), abs(half), self.P) * self.square_root(base) % self.P

    def residue(self, rng: random.Random) -> int:
        return rng.randrange(1, self.P)

    def circle(self, t: int) -> tuple[int, int]:
        """(cos, sin) of the angle 2 atan(t): ((1 - t^2), 2t) / (1 + t^2)."""
        inverse = self.inverse(1 + t * t)
        return (1 - t * t) * inverse % self.P, 2 * t * inverse % self.P

    def circle_point(self, rng: random.Random) -> tuple[int, int]:
        """(cos, sin) of a random angle."""
        while True:
            t = self.residue(rng)
            if (1 + t * t) % self.P:
                return self.circle(t)


def _radicands(number: sympy.Expr) -> set[int]:
    """The primes whose square roots a constant of Y holds (sqrt(12) = 2 sqrt(3): {3})."""
    found: set[int] = set()
    for power in number.atoms(sympy.Pow):
        base, exponent = power.args
        if base.is_Rational and exponent.is_Rational and exponent.q == 2:
            for n in (int(base.p), int(base.q)):
                found |= {p for p, k in factorint(abs(n)).items() if k % 2}
    return found


@dataclass(frozen=True)
class Closure:
    """A leg's closure f(q, p) = 0, which fixes its actuated variable q once the platform's pose p is drawn: a
    rotation's f is linear in (cos q, sin q) (a point turning about an axis), a translation's quadratic in q."""

    q: sympy.Symbol
    f: sympy.Expr
    rotation: bool


@dataclass(frozen=True)
class _Split:
    """A closure as A cos q + B sin q + C (a rotation) or A q^2 + B q + C (a translation): the coefficients free of
    q, and their sines and cosines."""

    q: sympy.Symbol
    rotation: bool
    coefficients: tuple[sympy.Expr, sympy.Expr, sympy.Expr]
    atoms: tuple[sympy.Expr, ...]


def _split(closure: Closure, where: str) -> _Split:
    """The coefficients of ``closure.f`` in (cos q, sin q) or q, by expanding each sine and cosine of q + r
    (cos(q + r) = cos q cos r - sin q sin r) and reducing sin^2 q = 1 - cos^2 q."""
    q = closure.q
    if closure.rotation:
        c, s = sympy.Dummy("c"), sympy.Dummy("s")
        turned = {}
        for atom in closure.f.atoms(sympy.sin, sympy.cos):
            n = sympy.expand(atom.args[0]).coeff(q)
            if n == 0:
                continue
            if n not in (1, -1):
                raise DerivationError(f"{where}: the closure of {q} holds {atom}, a multiple of the angle")
            r = sympy.expand(atom.args[0] - n * q)
            sn = n * s
            turned[atom] = c * sympy.cos(r) - sn * sympy.sin(r) if isinstance(atom, sympy.cos) else \
                sn * sympy.cos(r) + c * sympy.sin(r)
        f = sympy.expand(sympy.expand(closure.f.xreplace(turned)).subs(s ** 2, 1 - c ** 2))
        poly = sympy.Poly(f, c, s)
        monomials: list[tuple[int, ...]] = [(1, 0), (0, 1), (0, 0)]
    else:
        poly, monomials = sympy.Poly(sympy.expand(closure.f), q), [(2,), (1,), (0,)]
    if not set(poly.monoms()) <= set(monomials) or poly.free_symbols_in_domain & {q}:
        raise DerivationError(f"{where}: the closure of {q} is not linear in its cosine and sine (a rotation) or "
                              "quadratic in it (a translation), which the solution on the closure needs")
    A, B, C = (poly.coeff_monomial(m) for m in monomials)
    coefficients = (A, B, C)
    atoms = tuple(sorted(set().union(*(e.atoms(sympy.sin, sympy.cos) for e in coefficients)), key=str))
    return _Split(q, closure.rotation, coefficients, atoms)


def _outside_angles(expr: sympy.Expr) -> set[sympy.Symbol]:
    """The symbols of ``expr`` outside its sines and cosines (those inside are taken as the angles' points)."""
    angles = expr.atoms(sympy.sin, sympy.cos)
    return expr.xreplace({a: sympy.Integer(1) for a in angles}).free_symbols if angles else expr.free_symbols


class NoPoint(Exception):
    """The drawn state has no point over GF(P): a leg's closure or a square root in the formula needs the square
    root of a non-residue (about half the draws each)."""


class FormulaEvaluator:
    """Y's entries (and the definitions they need) evaluated mod P at one state and geometry, on the closures given
    (each leg's actuated variable solved from the drawn pose) or at independent inputs."""

    def __init__(self, spec: FunctionSpec, where: str, closures: Sequence[Closure] = ()):
        self.where = where
        self.closures = tuple(_split(c, where) for c in closures)
        Y = spec.outputs[0]
        self.shape = Y.shape
        self.entries = list(Y.expr)
        definitions = dict(spec.definitions)
        needed: dict[sympy.Symbol, sympy.Expr] = {}
        stack = [s for e in self.entries for s in e.free_symbols if s in definitions]
        while stack:
            s = stack.pop()
            if s not in needed:
                needed[s] = definitions[s]
                stack.extend(t for t in definitions[s].free_symbols if t in definitions)
        expressions = [needed[s] for s, _ in spec.definitions if s in needed] + self.entries + [
            e for c in self.closures for e in c.coefficients]
        self.functions = sorted(set().union(*(e.atoms(sympy.Function) for e in expressions)), key=str)
        inline = dict(needed)
        #: The definitions evaluated at a state, in order: those outside every sine and cosine (the angles' are
        #: inlined into them, whose values come from the angles' points; an angle may be a transcendental sum).
        outside = {s for e in self.entries for s in _outside_angles(e) if s in needed}
        for symbol, expr in reversed(spec.definitions):
            if symbol in outside:
                outside |= {s for s in _outside_angles(expr) if s in needed}
        self.definitions = [(s, e) for s, e in spec.definitions if s in outside]
        self.angles: dict[sympy.Function, tuple[dict[sympy.Symbol, int], sympy.Expr]] = {}
        inputs = {s for i in spec.inputs for s in i.symbols}
        parameters = {s for i in spec.inputs if i.kind == "parameter" for s in i.symbols}
        for atom in self.functions:
            if isinstance(atom, (sympy.sin, sympy.cos)):
                argument = atom.args[0]
                while argument.free_symbols & inline.keys():
                    argument = argument.xreplace(inline)
                self.angles[atom] = self._linear(sympy.expand(argument), inputs, atom)
            elif not isinstance(atom, (sympy.sign, sympy.tanh)):
                raise DerivationError(f"{where}: the regressor holds {atom}, which the exact elimination cannot "
                                      "evaluate (sines and cosines of the coordinates, Coulomb shapes only)")
        used = set().union(*(e.free_symbols for e in expressions)) - inline.keys()
        self.variables = sorted(used - parameters, key=str)
        #: Parameters in an angle (the Stewart platform's joint spacing): their value t stands for the angle
        #: 2 atan(t) in sines and cosines, and for itself elsewhere (an identity for every angle holds there too).
        in_angles = {x for coefficients, _ in self.angles.values() for x in coefficients}
        self.angle_parameters = sorted(in_angles & parameters, key=str)
        #: The variables inside some sine or cosine: each gets a point of the unit circle at a draw.
        self.angle_variables = sorted(in_angles & set(self.variables), key=str)
        self.geometry = sorted((used & parameters) | set(self.angle_parameters), key=str)
        roots = {x for e in expressions for x in e.atoms(sympy.Pow)
                 if x.args[1].is_Rational and x.args[1].q == 2 and not x.args[0].is_number}
        if len(self.closures) + len(roots) > MAX_SQUARE_ROOTS:
            raise DerivationError(
                f"{where}: a state of the regressor over a prime field needs {len(self.closures)} square roots for the "
                f"legs' closures and {len(roots)} in the formula (a leg's length or direction), a point at 1 in "
                f"2^{len(self.closures) + len(roots)} draws; more than {MAX_SQUARE_ROOTS} roots are not supported yet")
        self.radicands = sorted(set().union(*(_radicands(e) for e in expressions),
                                            *(_radicands(sympy.cos(c)) | _radicands(sympy.sin(c))
                                              for _, c in self.angles.values())))
        #: The definitions and Y's entries as one straight-line program, each closure's coefficients as one, and
        #: each program's constants in the last field.
        self.program = ModularProgram(self.definitions, self.entries, set(self.functions), where)
        #: The constant parts of the angles: cos c and sin c of each angle atom's constant c, in self.angles' order.
        self.angle_constants = ModularProgram(
            (), [v for _, c in self.angles.values() for v in self._cosine_and_sine(c)], set(), where)
        self.closure_programs = [ModularProgram((), c.coefficients, set(c.atoms), where) for c in self.closures]
        self._field_constants: dict[ModularProgram, tuple[PrimeField, list[int]]] = {}
        self._angle_values: tuple[PrimeField, list[int]] | None = None
        self._angle_index = {atom: k for k, atom in enumerate(self.angles)}

    def _linear(self, argument: sympy.Expr, variables: set[sympy.Symbol], atom: sympy.Expr
                ) -> tuple[dict[sympy.Symbol, int], sympy.Expr]:
        """``argument`` as sum_k n_k x_k + c, integer n_k over the inputs x_k and a constant c."""
        coefficients: dict[sympy.Symbol, int] = {}
        constant = argument
        for x in sorted(argument.free_symbols & variables, key=str):
            n = argument.coeff(x)
            if not n.is_Integer:
                raise DerivationError(f"{self.where}: the regressor holds {atom}, whose angle is not an integer "
                                      "combination of the coordinates and parameters, which the exact elimination "
                                      "needs")
            coefficients[x] = int(n)
            constant -= n * x
        return coefficients, constant

    def rows(self, field: PrimeField, rng: random.Random, geometry: dict[sympy.Symbol, int]) -> list[int]:
        """Y's entries (row-major) at a random state, mod P: on the closures (a pose redrawn until every leg's
        has a point, half of the draws per leg) or with every input drawn."""
        for _ in range(CLOSURE_DRAWS):
            values: dict[sympy.Expr, int] = dict(geometry)
            points = {x: field.circle_point(rng) for x in self.angle_variables}
            points.update({g: field.circle(geometry[g]) for g in self.angle_parameters})
            values.update({x: field.residue(rng) for x in self.variables})
            try:
                for closure, program in zip(self.closures, self.closure_programs):
                    self._close(field, rng, closure, program, values, points)
                values.update(self.atom_values(field, rng, self.functions, points))
                return self.run(self.program, field, values)
            except NoPoint:
                continue
        raise DerivationError(f"{self.where}: no pose of {CLOSURE_DRAWS} drawn closes every leg over a prime field "
                              "(please report it)")

    def run(self, program: ModularProgram, field: PrimeField, values: dict[sympy.Expr, int]) -> list[int]:
        """``program``'s outputs in ``field`` at ``values`` of its leaves (its constants computed once per field;
        a square root of the state that does not exist raises :class:`NoPoint`)."""
        cached = self._field_constants.get(program)
        if cached is None or cached[0] is not field:
            cached = (field, program.constants(field.constant))
            self._field_constants[program] = cached
        return program.run(values, cached[1], field.P, field.inverse, lambda x: _state_root(field.P, x))

    def atom_values(self, field: PrimeField, rng: random.Random, atoms: Sequence[sympy.Expr],
               points: dict[sympy.Symbol, tuple[int, int]]) -> dict[sympy.Expr, int]:
        """The sines and cosines among ``atoms`` at the angles' ``points`` (de Moivre), the Coulomb shapes drawn."""
        P = field.P
        if self._angle_values is None or self._angle_values[0] is not field:
            self._angle_values = (field, self.run(self.angle_constants, field, {}))
        constants = self._angle_values[1]
        out = {}
        for atom in atoms:
            if atom in self.angles:
                coefficients, _ = self.angles[atom]
                c, s = constants[2 * self._angle_index[atom]], constants[2 * self._angle_index[atom] + 1]
                for x, n in coefficients.items():
                    cx, sx = points[x] if n >= 0 else (points[x][0], -points[x][1] % P)
                    for _ in range(abs(n)):
                        c, s = (c * cx - s * sx) % P, (c * sx + s * cx) % P
                out[atom] = c if isinstance(atom, sympy.cos) else s
            else:
                out[atom] = field.residue(rng)
        return out

    def _close(self, field: PrimeField, rng: random.Random, closure: _Split, program: ModularProgram,
               values: dict[sympy.Expr, int], points: dict[sympy.Symbol, tuple[int, int]]) -> None:
        """Solve a leg's closure for its q at the drawn pose (its coefficients: ``program``), into ``points`` (a
        rotation) or ``values``."""
        P = field.P
        A, B, C = self.run(program, field, {**values, **self.atom_values(field, rng, closure.atoms, points)})
        if closure.rotation:  # A cos q + B sin q + C = 0: (C - A) t^2 + 2 B t + (A + C) = 0, t = tan(q/2)
            a, b, c = (C - A) % P, 2 * B % P, (A + C) % P
        else:  # A q^2 + B q + C = 0
            a, b, c = A, B, C
        discriminant = (b * b - 4 * a * c) % P
        if a == 0 or (discriminant and pow(discriminant, (P - 1) // 2, P) != 1):
            raise NoPoint
        t = (-b + square_root_mod(discriminant, P) * rng.choice((1, -1))) * field.inverse(2 * a) % P
        if not closure.rotation:
            values[closure.q] = t
        elif (1 + t * t) % P:
            points[closure.q] = field.circle(t)
        else:
            raise NoPoint

    def _cosine_and_sine(self, number: sympy.Expr) -> tuple[sympy.Expr, sympy.Expr]:
        """(cos c, sin c) of a constant part c of an angle, refused unless both are in a field Q(sqrt r_1, ...)."""
        cosine, sine = sympy.cos(number), sympy.sin(number)
        if number.free_symbols or cosine.has(sympy.pi, sympy.sin, sympy.cos) or sine.has(sympy.pi, sympy.sin,
                                                                                          sympy.cos):
            raise DerivationError(f"{self.where}: the constant {number} is not an angle whose sine and cosine are "
                                  "sums of products of rationals and square roots of rationals, which the exact "
                                  "elimination needs; give the model's constant angles as multiples of 15 deg where "
                                  "the design has them")
        return cosine, sine


def _state_root(P: int, x: int) -> int:
    """A square root of the state's residue x (a leg's length): a point of y^2 = x exists only for a residue.

    Raises:
        NoPoint: x is not a square mod P (the state is redrawn).
    """
    if x and pow(x, (P - 1) // 2, P) != 1:
        raise NoPoint
    return square_root_mod(x, P)


def square_root_mod(x: int, P: int) -> int:
    """A square root of the residue x modulo a prime P = 3 mod 4: x^((P + 1) / 4) (its square is x^((P + 1) / 2)
    = x x^((P - 1) / 2) = x by Euler's criterion)."""
    return pow(x, (P + 1) // 4, P)
