"""A parallel model's base parameters and base regressor: the quantities over :mod:`symkin.parallel.base_parameters`.

The exact elimination works on the regressor's formula at the legs' closure over a prime field.  Its count is
checked independently on the mechanism assembled in floating point: the regressor stacked over states about the
home pose (q from the closure by Gauss-Newton, :mod:`symkin.parallel.assembly`) must have the numerical rank of
the base columns, or the base parameters are refused with the reason (a closure whose branches differ, which the
prime field mixes).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import sympy

from symkin.dynamics.base_parameters import BaseParameters
from symkin.errors import DerivationError
from symkin.ir.evaluate import lambdify_spec
from symkin.ir.quantity import Deriving, quantity
from symkin.ir.spec import FunctionSpec, OutputSpec
from symkin.parallel.assembly import assembler
from symkin.parallel.base_parameters import modular_base_parameters
from symkin.parallel.prime_field import Closure
from symkin.parallel.quantities import PARALLEL, reduced_legs
from symkin.parallel.regressor import reduced_regressor, regressor_columns


@quantity("base_parameters", "the base parameters pi_b = K pi and the columns of Y_b, exact", emitted=False,
          mechanism=PARALLEL)
def _base_parameters(d: Deriving) -> BaseParameters:
    """The regressor's base parameters by modular elimination (:mod:`symkin.parallel.base_parameters`), checked
    on the assembled mechanism (:func:`closure_rank`)."""
    where = f"{d.model.name}: base parameters"
    closures = [Closure(leg.q, leg.constraint, leg.rotation) for leg in d[reduced_legs]]
    found = modular_base_parameters(d[reduced_regressor], d[regressor_columns].names, where, closures)
    rank = closure_rank(d, len(found.base))
    if rank < len(found.base):
        raise DerivationError(
            f"{where}: the assembled mechanism adds {len(found.base) - rank} linear dependencies among the "
            f"regressor's columns (numerical rank {rank} of the {len(found.base)} columns independent over a prime "
            "field), which the exact elimination does not find (assembly modes whose dependencies differ); the "
            "regressor is derived, its base parameters not (docs/identification.md, 'Parallel mechanisms')")
    return found


#: Assembled states sampled per regressor column, and the poses' spread about home (m or rad): generic poses, far
#: enough apart that the stacked regressor's rank shows, close enough to home that the legs assemble.
CLOSURE_SAMPLES, CLOSURE_SPREAD = 2, 0.02
#: A singular value of the column-equilibrated stack above this fraction of the largest counts towards the rank:
#: rounding leaves ~1e-15 in a column that depends on the others, a generic independent one stands at 1e-6 or more.
CLOSURE_RANK_TOLERANCE = 1e-10


def closure_rank(d: Deriving, base: int) -> int:
    """The numerical rank of the regressor stacked over assembled states about the home pose (q from the closure by
    Gauss-Newton, random rates and wrist states); ``base`` when the model has no home pose to start from (the
    exact count stands unchecked)."""
    model = d.model
    home = model.parallel.home  # type: ignore[union-attr]
    if home is None:
        return base
    values = model.parameter_values
    spec = dataclasses.replace(d[reduced_regressor], outputs=d[reduced_regressor].outputs[:1])  # Y alone, not pi
    rows, columns = spec.outputs[0].shape
    rng = np.random.default_rng(0)
    centre = np.array([float(sympy.sympify(e).xreplace(values)) for e in home])
    # lambdify keeps the definitions as temporaries; SymEngine's substitution into the entries would write out the
    # Stewart platform's Gram-Schmidt solve (1 157 definitions) as trees too deep to evaluate
    function = lambdify_spec(spec, [list(i.symbols) for i in spec.vector_inputs], "numpy", values)
    assemble = assembler(d)
    stacked = []
    for _ in range(CLOSURE_SAMPLES * columns // max(rows, 1) + 1):
        p = centre + rng.uniform(-CLOSURE_SPREAD, CLOSURE_SPREAD, centre.shape)
        assembled = assemble(p)
        if assembled is None:
            continue
        state = {"q": assembled[0], "p": p}
        arguments = [state[i.name] if i.name in state else rng.normal(size=len(i.symbols)) for i in spec.vector_inputs]
        stacked.append(np.asarray(function(*arguments), dtype=float).reshape(rows, columns))
    return stacked_rank(stacked, columns)


def stacked_rank(stacked: list[np.ndarray], columns: int) -> int:
    """The numerical rank of the regressors ``stacked`` (one per state) on top of each other, each column scaled to
    unit norm (a zero column dropped); a singular value counts above :data:`CLOSURE_RANK_TOLERANCE` of the largest."""
    Y = np.concatenate(stacked) if stacked else np.zeros((0, columns))
    norms = np.linalg.norm(Y, axis=0)
    singular = np.linalg.svd(Y[:, norms > 0] / norms[norms > 0], compute_uv=False) if Y.size else np.zeros(0)
    return int(np.sum(singular > CLOSURE_RANK_TOLERANCE * singular.max(initial=0.0)))


def base_outputs(Y: OutputSpec, pi: OutputSpec, found: BaseParameters, symbols: dict[sympy.Symbol, sympy.Symbol],
                 doc: str) -> list[OutputSpec]:
    """[Y_b, pi_b]: the base columns of the regressor ``Y`` (``doc`` says what they are) and pi_b = K pi, K's
    geometry (plain symbols) replaced by the model's (``symbols``)."""
    rows, columns = Y.shape
    Y_b = sympy.ImmutableMatrix(rows, len(found.base), [Y.expr[i * columns + b] for i in range(rows) for b in found.base])
    pi_b = sympy.ImmutableMatrix([sum((k.xreplace(symbols) * pi.expr[c] for c, k in enumerate(row) if k != 0),
                                      sympy.Integer(0)) for row in found.combinations])
    return [OutputSpec("Y_b", Y_b, doc, shape=(rows, len(found.base)), elements=found.base_names),
            OutputSpec("pi_b", pi_b, "the model's base parameters (the identifiable combinations)",
                       shape=(len(found.base),), elements=found.base_names)]


@quantity("base_regressor", "base regressor Y_b(q, p, qd, qdd) (full column rank) with tau = Y_b pi_b, and the "
          "model's pi_b = K pi", mechanism=PARALLEL, kappa_degree=4)
def _base_regressor(d: Deriving) -> FunctionSpec:
    """Y_b, the regressor's base columns, and the model's pi_b, named by the base parameters' names; K's rows are
    the equations in the function's doc (as the serial base regressor's)."""
    full, found = d[reduced_regressor], d[_base_parameters]
    symbols = {sympy.Symbol(str(s)): s for i in full.inputs for s in i.symbols}  # K's geometry: plain symbols
    return dataclasses.replace(
        full, name="base_regressor", summary="Base regressor: tau = Y_b(q, p, qd, qdd) pi_b, Y_b of full column rank.",
        doc="The regressor's linearly independent columns (Khalil and Dombre 2002, sec. 14.4), found by a modular "
            "echelon form of the formula at random states of the assembled mechanism over a prime field "
            "(symkin.parallel.base_parameters): Y = Y_b K and "
            "pi_b = K pi with K exact for every value of the model's parameters: " + "; ".join(found.equations())
            + ". Evaluate at a consistent pair q, p (p = fk(q) or q = ik(p)).",
        outputs=tuple(base_outputs(full.outputs[0], full.outputs[1], found, symbols, "base regressor: full column rank")))
