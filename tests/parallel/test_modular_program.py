"""The straight-line programs over GF(P) of the parallel base parameters (symkin.parallel.modular_program), against
exact rational arithmetic: a formula with definitions, sums, products of several factors, negative and half-integer
powers, rational constants and a function atom, at integer states whose square roots are integers, gives the
residue of its exact rational value."""

from __future__ import annotations

import pytest
import sympy

from symkin.errors import DerivationError
from symkin.parallel.modular_program import ModularProgram

P = 2 ** 60 + 91   # a prime, 3 mod 4, in which 3 has square roots


def _residue(value: sympy.Rational) -> int:
    return int(value.p) * pow(int(value.q), -1, P) % P


def test_a_program_gives_the_residues_of_the_exact_values():
    x, y, z, w1, w2 = sympy.symbols("x y z w1 w2")
    atom = sympy.cos(z)
    definitions = [(w1, x * y - sympy.Rational(3, 7) * x ** 2), (w2, w1 + atom * y ** -2)]
    outputs = [w1 * w2 * x * (y + 1), w2 ** 3 / (x + y), sympy.sqrt(x * y) * w1 + sympy.sqrt(3) / 2,
               (x * y) ** sympy.Rational(-3, 2) + w2, sympy.Integer(5)]
    program = ModularProgram(definitions, outputs, {atom}, "test")
    assert set(program.leaves) == {x, y, atom}
    values = {x: sympy.Integer(4), y: sympy.Integer(9), atom: sympy.Rational(1, 2)}
    exact = [e.xreplace(dict(definitions[::-1])).xreplace(dict(definitions)).xreplace(values) for e in outputs]
    roots = {36: 6, 3: pow(3, (P + 1) // 4, P)}  # x y = 36; sqrt(3) mod P: one of its two roots

    def root(value: int) -> int:
        return roots[value]

    residues = program.run({k: _residue(v) for k, v in values.items()},
                           program.constants(lambda n: _residue(n) if n.is_Rational else
                                             _residue(n / sympy.sqrt(3)) * roots[3] % P), P,
                           lambda v: pow(v, -1, P), root)
    assert pow(roots[3], 2, P) == 3
    expected = [_residue(sympy.nsimplify(e)) if not e.has(sympy.sqrt(3)) else
                (_residue(e.coeff(sympy.sqrt(3))) * roots[3] + _residue(e.subs(sympy.sqrt(3), 0))) % P for e in exact]
    assert residues == expected
    assert all(n.is_Rational or (n.is_Pow and n.args[0].is_Rational) for n in program.numbers)  # sqrt(3)/2: 2 leaves


def test_a_constant_outside_the_fields_of_square_roots_of_rationals_is_refused():
    """The leaves' residues are a rational's and a rational's root's; a nested root or a transcendental constant
    has no place in Q(sqrt r_1, ...) and is refused with the reason, not given a root of the state."""
    x = sympy.Symbol("x")
    for constant in (sympy.sqrt(2 + sympy.sqrt(3)), sympy.pi, sympy.cos(1)):
        with pytest.raises(DerivationError, match="which the exact elimination cannot evaluate"):
            ModularProgram((), [x * constant], set(), "test")
