"""Base parameters of legs without the distance form: the exact elimination of
:mod:`symkin.parallel.base_parameters` on the actuator-space regressor of :mod:`symkin.parallel.closure_dynamics`.

The actuators feel tau = Y(q, qd, qdd) pi with

    Y = W^T Y_z(z, W qd, W qdd + c),     W = [I; -A^-1 Phi_q],   c = [0; -A^-1 gamma],   A = [Phi_s Phi_p],

Y_z the regressor over all the mechanism's variables z = (q, s, p) (``closure_regressor``), W the velocities the
closure allows (zd = W qd solves Phi_z zd = 0) and c the accelerations it forces (Phi_z zdd + gamma = 0), as
:mod:`symkin.runtime.closure_dynamics` computes them in floating point.  Over GF(P) the same steps are exact: a
point of the closure from :class:`symkin.parallel.closure_points.ClosurePoints`, Phi_z and gamma evaluated there
by compiled programs, A^-1 by the reduced row echelon form of [A | b] over a row subset (the system is consistent
on the closure: any rows of full rank give its solution; a point where A loses rank is a singularity, redrawn).
Every step is a ring homomorphism of the exact values, so each linear dependency of Y's columns holds at these
residues, and :func:`symkin.parallel.base_parameters.field_base_parameters` finds the base parameters of Y, the
geometry kept symbolic.  As Y = W^T Y_z, the base columns of Y_z give the base regressor Y_z,b with
tau = W^T Y_z,b pi_b.  The count is checked in floating point as the distance legs' is: the rank of Y stacked over
states assembled about home (:func:`assembled_rank`).
"""

from __future__ import annotations

import dataclasses
import random

import flint
import numpy as np
import sympy

from symkin.dynamics.base_parameters import BaseParameters
from symkin.errors import DerivationError
from symkin.ir.evaluate import lambdify_spec
from symkin.ir.quantity import Deriving, quantity
from symkin.ir.spec import FunctionSpec, make_function
from symkin.model import coordinates
from symkin.parallel.assembly import assembler
from symkin.parallel.base_parameters import field_base_parameters
from symkin.parallel.base_regressor import CLOSURE_SAMPLES, CLOSURE_SPREAD, base_outputs, stacked_rank
from symkin.parallel.closure_dynamics import closure_regressor_spec, closure_terms, rate_inputs
from symkin.parallel.closure_points import ClosurePoints, entries_spec
from symkin.parallel.inputs import passive_symbols
from symkin.parallel.modular_program import ModularProgram
from symkin.parallel.prime_field import CLOSURE_DRAWS, FormulaEvaluator, NoPoint, PrimeField
from symkin.parallel.quantities import PARALLEL, closure_spec


class ClosureRegressorField:
    """Y = W^T Y_z(z, W qd, W qdd + c) mod P at random points of the closure (the module docstring), with the
    interface :func:`field_base_parameters` reads (:class:`symkin.parallel.base_parameters.RegressorField`)."""

    def __init__(self, d: Deriving, where: str):
        model = d.model
        assert model.parallel is not None
        self.where = where
        closure = d[closure_spec]
        self.n = len(model.coordinates)
        self.points = ClosurePoints(closure, len(model.parallel.legs),
                                    coordinates.symbols(model, "q") + passive_symbols(model), where)
        Phi, gamma = closure_terms(d)
        self.size = Phi.shape[1]
        self.jacobian = FormulaEvaluator(entries_spec(closure, list(Phi)), where)
        self.gamma = FormulaEvaluator(entries_spec(closure, list(gamma)), where)
        regressor = d[closure_regressor_spec]
        self.regressor = FormulaEvaluator(dataclasses.replace(regressor, outputs=regressor.outputs[:1]), where)
        self.columns = regressor.outputs[0].shape[1]
        self.shape: tuple[int, ...] = (self.n, self.columns)
        self.rates = [spec.symbols for spec in rate_inputs(model)]
        self.accelerations = [spec.symbols for spec in rate_inputs(model, "qdd")]
        parts = (self.points.coefficients, self.points.check, self.jacobian, self.gamma, self.regressor)
        if any(part.angle_parameters for part in parts):
            raise DerivationError(f"{where}: a parameter of the model is an angle of the closure or the regressor, "
                                  "which the exact elimination of legs without the distance form does not take "
                                  "yet; write its value into the model file in its place")
        self.geometry = sorted(set().union(*(part.geometry for part in parts)), key=str)
        self.radicands = sorted(set().union(*(part.radicands for part in parts)))

    def run(self, program: ModularProgram, field: PrimeField, values: dict[sympy.Expr, int]) -> list[int]:
        return self.regressor.run(program, field, values)

    def rows(self, field: PrimeField, rng: random.Random, geometry: dict[sympy.Symbol, int]) -> list[int]:
        """Y's entries (row-major, n x columns) at a random point of the closure and random rates."""
        for _ in range(CLOSURE_DRAWS):
            try:
                return self._rows(field, rng, geometry)
            except NoPoint:
                continue
        raise DerivationError(f"{self.where}: no pose of {CLOSURE_DRAWS} drawn closes every leg over a prime field "
                              "(please report it)")

    def _evaluate(self, evaluator: FormulaEvaluator, field: PrimeField, rng: random.Random,
                  values: dict[sympy.Expr, int], points: dict[sympy.Symbol, tuple[int, int]]) -> list[int]:
        return evaluator.run(evaluator.program, field, {
            **values, **evaluator.atom_values(field, rng, evaluator.functions, points)})

    def _rows(self, field: PrimeField, rng: random.Random, geometry: dict[sympy.Symbol, int]) -> list[int]:
        P, n = field.P, self.n
        values, points = self.points.draw(field, rng, geometry)
        Phi = self._evaluate(self.jacobian, field, rng, values, points)
        rows = len(Phi) // self.size
        A = [Phi[r * self.size + n:(r + 1) * self.size] for r in range(rows)]
        X = _solve(A, [[-v % P for v in Phi[r * self.size:r * self.size + n]] for r in range(rows)], P)
        qd, qdd = [field.residue(rng) for _ in range(n)], [field.residue(rng) for _ in range(n)]
        zd = qd + [sum(x * v for x, v in zip(row, qd)) % P for row in X]
        values.update(zip((s for group in self.rates for s in group), zd))
        gamma = self._evaluate(self.gamma, field, rng, values, points)
        c = [row[0] for row in _solve(A, [[-g % P] for g in gamma], P)]
        zdd = qdd + [(sum(x * v for x, v in zip(row, qdd)) + ci) % P for row, ci in zip(X, c)]
        values.update(zip((s for group in self.accelerations for s in group), zdd))
        Y_z = flint.nmod_mat(self.size, self.columns, self._evaluate(self.regressor, field, rng, values, points), P)
        W_T = flint.nmod_mat(n, self.size, [int(i == j) if j < n else X[j - n][i] for i in range(n)
                                            for j in range(self.size)], P)
        Y = W_T * Y_z
        return [int(Y[i, j]) for i in range(n) for j in range(self.columns)]


def _solve(A: list[list[int]], b: list[list[int]], P: int) -> list[list[int]]:
    """x with A x = b mod P (A of full column rank; the system consistent), by the reduced row echelon form of
    [A | b].

    Raises:
        NoPoint: A has not full column rank, or the system is inconsistent (a singular point of the closure).
    """
    k = len(A[0])
    augmented = flint.nmod_mat([a + r for a, r in zip(A, b)], P)
    echelon, rank = augmented.rref()
    if rank != k or any(int(echelon[i, i]) != 1 for i in range(k)):
        raise NoPoint
    return [[int(echelon[i, k + j]) for j in range(len(b[0]))] for i in range(k)]


@quantity("closure_base_parameters", "the base parameters pi_b = K pi of legs without the distance form, exact",
          emitted=False, mechanism=PARALLEL)
def _closure_base_parameters(d: Deriving) -> BaseParameters:
    """The actuator-space regressor's base parameters by modular elimination on the closure (module docstring),
    checked on the assembled mechanism (:func:`assembled_rank`)."""
    where = f"{d.model.name}: base parameters"
    names = d[closure_regressor_spec].outputs[0].elements
    found = field_base_parameters(ClosureRegressorField(d, where), names, where)
    rank = assembled_rank(d)
    if rank is not None and rank != len(found.base):
        raise DerivationError(
            f"{where}: the assembled mechanism's regressor has numerical rank {rank}, the exact elimination over a "
            f"prime field {len(found.base)} base columns (assembly modes whose dependencies differ); the regressor "
            "is derived, its base parameters not (docs/identification.md, 'Parallel mechanisms')")
    return found


def assembled_rank(d: Deriving) -> int | None:
    """The numerical rank of Y = W^T Y_z stacked over states assembled about the home pose (random rates), the
    columns equilibrated; None without a home pose."""
    model = d.model
    assert model.parallel is not None
    if model.parallel.home is None:
        return None
    values = model.parameter_values
    n = len(model.coordinates)
    Phi, gamma = closure_terms(d)
    closure = d[closure_spec]
    z = [list(i.symbols) for i in closure.vector_inputs]
    rates = [list(spec.symbols) for spec in rate_inputs(model)]
    jacobian = lambdify_spec(entries_spec(closure, list(Phi)), z, "numpy", values)
    acceleration = lambdify_spec(entries_spec(closure, list(gamma)), z + rates, "numpy", values)
    regressor = d[closure_regressor_spec]
    Y_z = lambdify_spec(dataclasses.replace(regressor, outputs=regressor.outputs[:1]),
                        [list(i.symbols) for i in regressor.vector_inputs], "numpy", values)
    size, columns = Phi.shape[1], regressor.outputs[0].shape[1]
    rng = np.random.default_rng(0)
    centre = np.array([float(sympy.sympify(e).xreplace(values)) for e in model.parallel.home])
    assemble = assembler(d)
    stacked = []
    for _ in range(CLOSURE_SAMPLES * columns // n + 1):
        p = centre + rng.uniform(-CLOSURE_SPREAD, CLOSURE_SPREAD, centre.shape)
        assembled = assemble(p)
        if assembled is None:
            continue
        q, s = assembled
        Phi_z = np.asarray(jacobian(q, s, p), dtype=float).reshape(-1, size)
        A_plus = np.linalg.pinv(Phi_z[:, n:])
        W = np.vstack([np.eye(n), -A_plus @ Phi_z[:, :n]])
        qd, qdd = rng.normal(size=n), rng.normal(size=n)
        zd = W @ qd
        split = np.cumsum([len(r) for r in rates])[:-1]
        g = np.asarray(acceleration(q, s, p, *np.split(zd, split)), dtype=float)
        zdd = W @ qdd + np.concatenate([np.zeros(n), -A_plus @ g])
        Y = np.asarray(Y_z(q, s, p, *np.split(zd, split), *np.split(zdd, split)), dtype=float).reshape(size, columns)
        stacked.append(W.T @ Y)
    return stacked_rank(stacked, columns)


@quantity("closure_base_regressor", "base regressor Y_z,b(z, zd, zdd) of legs without the distance form (tau = W^T "
          "Y_z,b pi_b, full column rank), and the model's pi_b = K pi", mechanism=PARALLEL, kappa_degree=4)
def _closure_base_regressor(d: Deriving) -> FunctionSpec:
    """The base columns of Y_z and pi_b, named by the base parameters' names; K's rows are the equations in the
    function's doc."""
    full, found = d[closure_regressor_spec], d[_closure_base_parameters]
    symbols = {sympy.Symbol(p.name): p.symbol for p in d.model.parameters}  # K's geometry: plain symbols
    return make_function(
        d.model, "closure_base_regressor",
        "Base regressor of legs without the distance form: tau = W^T Y_z,b pi_b.",
        "The columns of closure_regressor's Y_z whose images Y = W^T Y_z on the closure are linearly "
        "independent (Khalil and Dombre 2002, sec. 14.4), found by a modular echelon form of Y at random "
        "points of the closure over a prime field (symkin.parallel.closure_base): Y = W^T Y_z,b K and "
        "pi_b = K pi with K exact for every value of the model's parameters: " + "; ".join(found.equations())
        + ". With zd = W qd and zdd = W qdd + c at an assembled state, tau = W^T Y_z,b pi_b "
        "(symkin.runtime.closure_dynamics.closure_regressor).",
        full.vector_inputs, base_outputs(full.outputs[0], full.outputs[1], found, symbols, "base columns of Y_z"), full.definitions)
