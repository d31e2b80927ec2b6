"""The stability harness: every generated quantity of a model against a 50-digit reference.

For each quantity the model can derive (every registered output, so dynamics quantities
join automatically once they are registered), the generated numpy code - derived with all
parameters as inputs, optimized and emitted exactly as ``symkin derive`` does - is
evaluated

* at random states (``random``),
* along paths into the singular configurations found by :mod:`symkin.stability.states`
  (``singular``),
* with every length parameter multiplied by 1e-3 ... 1e3 (``scale``),
* in float32, through :func:`~symkin.stability.ir_eval.compile_ir` (``float32``),

and compared with the un-optimized expressions evaluated in 50-digit ball arithmetic at the same inputs
(:class:`~symkin.stability.reference.BallReference`).  Each comparison is a
:class:`Record` with the normwise relative error and kappa, the condition number
sigma_max/sigma_min (seed sec. 4.2), computed from 50-digit values (by numpy's SVD of them rounded to doubles
where that is within 1e-8, :data:`DOUBLE_KAPPA`), of the matrix that
bounds the accuracy of the quantity: the matrix it inverts when its registration declares
one (``solves_with``: the mass matrix for forward dynamics, the task Jacobian for TCP forces
and operational-space dynamics), else the task Jacobian (:func:`conditioning_matrix`); a
parallel mechanism's quantity that inverts a matrix of its own is judged by the larger of that
kappa and the task matrix's, since its dynamics reach the actuators through J = J_x^-1 J_q.  A backward-stable evaluation has
an error of the order of kappa * eps, so this is the kappa to judge the error against.

Parallel mechanisms are checked at assembled states (p around the home pose, q = ik(p),
see :mod:`symkin.stability.states`, and the passive joints s solved from the loop closure by
Newton's method from a random start, where it converges), along paths into their singularities (the DELTA's
workspace boundary, the Stewart platform's interior singular poses), at length scales and in
float32 alike.  Their residual quantities (loop closure and leg equations, which vanish at
assembled states, so that any rounding would be a 100 % relative error) are evaluated with
q moved off the assembled state by up to :data:`OFF_MANIFOLD`.
"""

from __future__ import annotations

import functools
import itertools
import math
import tempfile
import zlib
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field

import mpmath
import numpy as np

from symkin import pipeline
from symkin.derivation import Derivation, emitted_quantities, registry
from symkin.model.schema import Model
from symkin.runtime import load
from symkin.runtime.info import GeneratedModel
from symkin.runtime.parallel import solve_closure
from symkin.stability.ik_forms import formula_errors
from symkin.stability.ir_eval import compile_ir, flatten_outputs
from symkin.stability.reference import DIGITS, BallReference, normwise_error
from symkin.stability.states import IK, parameter_values, random_states, singular_paths

SCALES = (1e-3, 1e-2, 1e-1, 1.0, 1e1, 1e2, 1e3)
EPS = float(np.finfo(np.float64).eps)
PATH_STEPS = tuple(10.0 ** -k for k in range(1, 13))
#: The acceptance criterion (issue 7): error <= max(BOUND, SOLVE_ULPS kappa eps) wherever kappa <
#: KAPPA_LIMIT (float64).  1e-13 = 450 eps: above the rounding of the deepest generated outputs
#: (dynamics of a 6-7 body chain: ~320 ulps of the largest entry, tests/tolerances.py DYNAMICS).  A
#: quantity that divides by the matrix of condition kappa (a solve, or the pantograph's 1 / J_q,ii near
#: its workspace boundary, a dot product that cancels) has a backward-stable error c kappa eps with c
#: a few roundings of the entries: c <= SOLVE_ULPS, which passes 1e-13 from kappa = 113 on.
BOUND = 1e-13
SOLVE_ULPS = 4.0
KAPPA_LIMIT = 1e3
#: Below this condition number, kappa is that of the reference rounded to doubles (numpy's SVD): rounding moves
#: each singular value by <= p(n) u sigma_max (two backward-stable steps, p(n) ~ 4n + sqrt(mn)), so kappa by a
#: relative p(n) u kappa < 1e-8 here, far below the factor of ten between the table's classes; above it, 50 digits.
DOUBLE_KAPPA = 1e6
#: Residual quantities (zero wherever the mechanism is assembled) are evaluated with q moved off
#: the assembled state by up to this fraction of max(|q|, 1), so that their relative error is
#: meaningful (and scales with the mechanism).
OFF_MANIFOLD = 0.2


@dataclass(frozen=True)
class Record:
    """One quantity evaluated at one state.

    Attributes:
        quantity: the generated function.
        family: ``random``, ``singular``, ``scale`` or ``float32``.
        label: the path (``theta2 -> 0``) for singular states, else empty.
        parameter: t (distance to the singular value) for singular states, the length scale
            for ``scale``, 1 otherwise.
        kappa: condition number, at the state, of the matrix the quantity inverts, else of the
            task Jacobian (inf if singular, nan if the model has no such matrix).
        error: normwise relative error against the reference (inf: a non-finite value came out).
        state: the inputs it was evaluated at, ``((group, values), ...)`` (``q``, ``qd``, ``p``, ...),
            so that a failure on a machine nobody here has can be reproduced from its log.
    """

    quantity: str
    family: str
    label: str
    parameter: float
    kappa: float
    error: float
    state: tuple[tuple[str, tuple[float, ...]], ...] = ()


@dataclass
class StabilityRun:
    """All records of one model, plus what was checked."""

    model: str
    quantities: tuple[str, ...]
    skipped: dict[str, str]
    paths: list
    records: list[Record] = field(default_factory=list)
    #: closed-form IK angles along paths into singularities (:mod:`symkin.stability.ik_forms`)
    formulas: list = field(default_factory=list)

    def select(self, family: str | None = None, quantity: str | None = None) -> list[Record]:
        return [r for r in self.records if (family is None or r.family == family)
                and (quantity is None or r.quantity == quantity)]

    def acceptance(self, bound: float = BOUND, kappa_limit: float = KAPPA_LIMIT) -> tuple[bool, float]:
        """(every float64 record with kappa < kappa_limit has error <= :func:`allowed_error`, the largest such
        error)."""
        worst = self.worst(kappa_limit)
        error = 0.0 if worst is None else worst.error
        passed = all(r.error <= allowed_error(r.kappa, bound) for r in self.records
                     if r.family != "float32" and r.kappa < kappa_limit)
        return passed, error

    def worst(self, kappa_limit: float = KAPPA_LIMIT) -> Record | None:
        """The float64 record with the largest error where kappa < kappa_limit (None if there is none)."""
        return max((r for r in self.records if r.family != "float32" and r.kappa < kappa_limit),
                   key=lambda r: r.error, default=None)


def allowed_error(kappa: float, bound: float = BOUND) -> float:
    """The acceptance bound at condition number kappa: max(bound, SOLVE_ULPS kappa eps)."""
    return max(bound, SOLVE_ULPS * kappa * EPS) if math.isfinite(kappa) else bound


def _kappa(reference: BallReference | None, shape: tuple[int, ...], vectors: dict, parameters: dict) -> float:
    """sigma_max / sigma_min of a matrix output evaluated at 50 digits (inf at a singular state; nan without one,
    or where it is undefined): of its rounding to doubles where kappa < :data:`DOUBLE_KAPPA`, else at 50 digits."""
    if reference is None:
        return float("nan")
    exact = reference.exact({g: vectors[g] for g in reference.vector_names}, parameters)
    if any(mpmath.isnan(v) for v in exact):
        return float("nan")
    rows, columns = shape
    rounded = np.array([float(v) for v in exact]).reshape(rows, columns)
    if np.all(np.isfinite(rounded)):
        singular = np.linalg.svd(rounded, compute_uv=False)
        if singular[-1] > 0 and singular[0] < DOUBLE_KAPPA * singular[-1]:
            return float(singular[0] / singular[-1])
    with mpmath.workdps(DIGITS):
        J = mpmath.matrix([exact[i * columns:(i + 1) * columns] for i in range(rows)])
        singular = mpmath.svd_r(J, compute_uv=False)
        largest, smallest = max(singular), min(singular)
        return float("inf") if smallest == 0 else float(largest / smallest)


def assembled_passive(loaded: GeneratedModel, states: dict[str, np.ndarray]) -> np.ndarray:
    """The passive joints s that close every leg at the states' (q, p): Newton on the generated closure from
    the states' s, which stays where it does not converge (the closure's rotation rows, 2 tan(angle/2) of each
    leg's residual turn, are ill-conditioned at half turns that an assembled mechanism never visits)."""
    report = solve_closure(loaded, states["q"], states["s"], states["p"], unknowns=("s",))
    solved = np.asarray(report.solution["s"])
    return np.where(report.converged[..., None], solved, states["s"])


def _largest(kappas: Iterable[float]) -> float:
    """The largest of the defined condition numbers (nan if none is)."""
    defined = [k for k in kappas if not math.isnan(k)]
    return max(defined, default=float("nan"))


def _conditioning_sources(solves_with: str | None, task_matrix: str, parallel: bool) -> tuple[str, ...]:
    """The matrices whose largest kappa judges a quantity: the one it inverts, else the task matrix; a
    parallel mechanism's dynamics reach the actuators through J = J_x^-1 J_q, so there the task matrix too."""
    if solves_with is None:
        return (task_matrix,)
    return (solves_with, task_matrix) if parallel else (solves_with,)


def _ik_of(loaded: GeneratedModel, derivation: Derivation) -> IK:
    """The generated ik taking every parameter of the run by keyword and passing on the ones it has
    (a model's mass parameters, say, are inputs of its dynamics but not of its ik)."""
    own = [i.name for i in derivation["ik"].parameter_inputs]
    ik = loaded.ik
    return lambda p, **parameters: ik(p, **{name: parameters[name] for name in own})


def conditioning_matrix(model: Model) -> str:
    """The task matrix whose kappa judges a quantity that inverts nothing: the task Jacobian J of a
    serial chain; the inverse Jacobian J^-1 = J_q^-1 J_x of a parallel mechanism (its closed
    form; kappa(J^-1) = kappa(J), and a Stewart platform's J = J_x^-1 J_q is a huge expression)."""
    return "jacobian" if model.parallel is None else "inverse_jacobian"


def _constant(value: float, _index: int) -> float:
    """The parameter of every state of a family evaluated at one value (its ``parameter_of``)."""
    return value


def run_stability(model: Model, *, samples: int = 32, float32_samples: int = 16, scale_samples: int = 6,
                  scales: Sequence[float] = SCALES, steps: Sequence[float] = PATH_STEPS,
                  quantities: Sequence[str] | None = None, skip: Sequence[str] = (), max_paths: int = 8,
                  seed: int = 0, progress: Callable[[str], None] = lambda _stage: None,
                  derivation: Derivation | None = None) -> StabilityRun:
    """Check every generated quantity of ``model`` against the 50-digit reference (see the module docstring).

    Args:
        model: the model.
        samples: random states at the default parameters.
        float32_samples: random states evaluated in float32.
        scale_samples: random states per length scale.
        scales: length scales.
        steps: distances t to the singular value along each singular path.
        quantities: the quantities to check (default: every one the model can derive).
        skip: quantities to leave out of those.
        max_paths: at most this many singular paths.
        seed: random seed (the run is deterministic).
        progress: called with a description of each stage.
        derivation: ``model``'s derivation graph, whose quantities the run reuses and adds to (default: a new one).
    """
    unknown = sorted(set(skip) - set(emitted_quantities()))
    if unknown:
        raise ValueError(f"skip: no quantity {', '.join(unknown)}; choose from {', '.join(emitted_quantities())}")
    rng = np.random.default_rng(seed)
    derivation = Derivation(model) if derivation is None else derivation
    names, skipped = derivation.available([name for name in quantities or emitted_quantities(model.mechanism)
                                           if name not in skip])
    task_matrix = conditioning_matrix(model)
    has_jacobian = bool(derivation.available([task_matrix])[0])
    # also what the run itself evaluates: the conditioning matrix, fk and the geometric Jacobian of a
    # serial chain for the closed-form IK section, a parallel mechanism's ik (even when --only leaves them out)
    support = [task_matrix] if has_jacobian else []
    if model.parallel is None:
        support += derivation.available(["fk", "jacobian_geometric"])[0]
    else:
        support += derivation.available(["ik"])[0]  # the sampler's q = ik(p)
        if any(i.name == "s" for name in names for i in derivation[name].vector_inputs):
            support += derivation.available(["closure", "closure_jacobians"])[0]  # the sampler's assembled s
    generated = tuple(names) + tuple(dict.fromkeys(name for name in support if name not in names))
    progress("generating code")
    generation = pipeline.generate(model, pipeline.Request(generated, (), ("numpy",)), derivation=derivation)
    optimized = {f.name: f for f in generation.functions}
    references = {name: BallReference(derivation[name]) for name in names}
    definitions = registry(model.mechanism)
    conditioning = {name: _conditioning_sources(definitions[name].solves_with, task_matrix, model.parallel is not None)
                    for name in names}
    residual = [name for name in names if definitions[name].residual]
    regular = [name for name in names if not definitions[name].residual]
    kappa_sources: dict[str, tuple[BallReference | None, tuple[int, ...]]] = {}
    for source in sorted({source for sources in conditioning.values() for source in sources}):
        if source == task_matrix and not has_jacobian:
            kappa_sources[source] = (None, ())
        else:
            kappa_sources[source] = (references.get(source) or BallReference(derivation[source]),
                                     derivation[source].outputs[0].shape)
    with tempfile.TemporaryDirectory(prefix="symkin-stability-") as tmp:
        loaded = load(pipeline.write(generation, tmp))
        functions = {name: getattr(loaded, name) for name in names}
        shapes = {name: [o.shape for o in derivation[name].outputs] for name in names}
        sizes = {i.name: len(i.symbols) for name in names for i in derivation[name].vector_inputs}
        run = StabilityRun(model.name, tuple(names), skipped, [])
        ik = _ik_of(loaded, derivation) if model.parallel is not None else None

        calls = itertools.count()

        def states_at(count: int, scale: float = 1.0, moved: dict[str, np.ndarray] | None = None
                      ) -> dict[str, np.ndarray]:
            """Random states, plus any input group they lack in [-0.5, 0.5]: the passive joint variables s from
            the run's stream, every other group (forces, efforts) from a generator of its own (seed, group,
            call), so that a quantity with a new input group leaves the states of the others as they were.
            ``moved`` replaces groups (a path's q and p) before the passive joints are solved from the loop
            closure (:func:`assembled_passive`)."""
            states = random_states(model, count, rng, scale=scale, ik=ik)
            call = next(calls)
            for group, size in sizes.items():
                if group not in states:
                    source = rng if group == "s" else np.random.default_rng([seed, zlib.crc32(group.encode()), call])
                    states[group] = source.uniform(-0.5, 0.5, size=(count, size))
            states.update(moved or {})
            if "s" in sizes:
                states["s"] = assembled_passive(loaded.bind(**parameter_values(model, scale)), states)
            return states

        def check(family: str, states: dict[str, np.ndarray], parameters: dict[str, float], label: str = "",
                  parameter_of: Callable[[int], float] = lambda _k: 1.0, dtype: type = np.float64) -> None:
            evaluate(family, states, parameters, label, parameter_of, dtype, regular)
            if residual:
                q = states["q"]
                off = dict(states, q=q + OFF_MANIFOLD * np.maximum(np.abs(q), 1.0) * rng.uniform(-1, 1, q.shape))
                evaluate(family, off, parameters, label, parameter_of, dtype, residual)

        def evaluate(family: str, states: dict[str, np.ndarray], parameters: dict[str, float], label: str,
                     parameter_of: Callable[[int], float], dtype: type, quantities: list[str]) -> None:
            count = len(states["q"])
            kappas = {source: [_kappa(reference, shape, {g: v[k] for g, v in states.items()}, parameters)
                               for k in range(count)]
                      for source, (reference, shape) in kappa_sources.items()}
            for name in quantities:
                spec_vectors = [i.name for i in derivation[name].vector_inputs]
                params = {i.name: parameters[i.name] for i in derivation[name].parameter_inputs}
                if dtype is np.float64:
                    with np.errstate(invalid="ignore", divide="ignore"):  # NaN/inf flags are what is checked
                        values = functions[name](*(states[g] for g in spec_vectors), **params)
                    computed = flatten_outputs(values, shapes[name])
                else:
                    computed = compile_ir(optimized[name], dtype)({g: states[g] for g in spec_vectors}, params)
                for k in range(count):
                    hi, lo = references[name]({g: states[g][k] for g in spec_vectors}, parameters)
                    state = tuple((g, tuple(float(v) for v in np.ravel(states[g][k]))) for g in spec_vectors)
                    run.records.append(Record(name, family, label, parameter_of(k), definitions[name].kappa_degree
                                              * _largest(kappas[s][k] for s in conditioning[name]),
                                              normwise_error(computed[k].astype(np.float64), hi, lo), state))

        defaults = parameter_values(model)
        progress("random states")
        check("random", states_at(samples), defaults)
        if has_jacobian:
            progress("finding singular configurations")
            run.paths = singular_paths(model, getattr(loaded, task_matrix), rng, max_paths, ik=ik, reach=max(steps))
            for path in run.paths:
                progress(f"path {path.label}")
                states = states_at(len(steps), moved=path.states(np.asarray(steps)))
                check("singular", states, defaults, path.label, lambda k: steps[k])
        for scale in scales:
            progress(f"length scale {scale:g}")
            check("scale", states_at(scale_samples, scale), parameter_values(model, scale),
                  parameter_of=functools.partial(_constant, scale))
        progress("closed-form IK near singularities")
        run.formulas = formula_errors(loaded, steps)
        progress("float32")
        states32 = {g: v.astype(np.float32).astype(np.float64) for g, v in states_at(float32_samples).items()}
        params32 = {k: float(np.float32(v)) for k, v in defaults.items()}
        check("float32", states32, params32, dtype=np.float32)
    return run
