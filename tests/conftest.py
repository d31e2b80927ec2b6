"""Shared fixtures: example models, derivations, generated code and reference evaluators."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import sympy

from symkin import pipeline
from symkin.derivation import Derivation
from symkin.ir.spec import FunctionSpec
from symkin.model import Model, load_model

ROOT = Path(__file__).resolve().parent.parent
MODELS_DIR = ROOT / "models"
GENERATED_DIR = ROOT / "generated"
EXAMPLE_MODELS = sorted(p.stem for p in MODELS_DIR.glob("*.yaml"))
SYMKIN_CLI = [sys.executable, "-m", "symkin"]


@pytest.fixture(scope="session")
def models() -> dict[str, Model]:
    """Every example model, loaded once."""
    return {name: load_model(MODELS_DIR / f"{name}.yaml") for name in EXAMPLE_MODELS}


@pytest.fixture(scope="session")
def derivations(models: dict[str, Model]) -> dict[str, Derivation]:
    """One shared derivation graph per example model (quantities are memoized across tests)."""
    return {name: Derivation(model) for name, model in models.items()}


def reference_function(model: Model, spec: FunctionSpec, modules: str = "numpy"):
    """Plain lambdify of the un-optimized outputs, parameters at their defaults.

    Returns f(*vectors) -> list of arrays (one per output, shaped as declared).  Very large outputs
    (a Laplace-expanded 6x6 determinant, the Stewart-Gough closure Jacobians: over 20000 operations)
    are lambdified with sympy's own common-subexpression option, which only changes how the same
    expression is evaluated; printing and evaluating them as one flat expression takes minutes.
    """
    from symkin.optimize import spec_op_count

    vectors = [list(i.symbols) for i in spec.vector_inputs]
    values = model.parameter_values
    large = spec_op_count(spec) > 20000
    fns = [sympy.lambdify(vectors, sympy.Matrix(o.expr).xreplace(values), modules=modules, cse=large)
           for o in spec.outputs]
    shapes = [o.shape for o in spec.outputs]

    def evaluate(*args):
        return [np.asarray(fn(*args), dtype=float).reshape(shape) for fn, shape in zip(fns, shapes)]

    return evaluate


def random_q(model: Model, rng: np.random.Generator, size=None) -> np.ndarray:
    """Random joint coordinates within +-pi (revolute) and +-0.5 m (prismatic)."""
    shape = (model.dof,) if size is None else tuple(np.atleast_1d(size)) + (model.dof,)
    return rng.uniform(-np.pi, np.pi, shape)


def random_inputs(model: Model, spec: FunctionSpec, rng: np.random.Generator, size: int) -> list[np.ndarray]:
    """Random values of every vector input of ``spec``: q as :func:`random_q`, the passive joints s
    within +-0.5 rad (the closure's orientation rows are 2 tan(angle/2) axis of the orientation
    error, which grows without bound - with its rounding error - towards half turns), the platform
    pose p within 2 cm / 0.1 rad of the model's home pose."""
    values = []
    for vector in spec.vector_inputs:
        if vector.name == "q":
            values.append(random_q(model, rng, size))
        elif vector.name == "p":
            home = np.array([float(e.xreplace(model.parameter_values)) for e in model.parallel.home])
            spread = np.where([u == "m" for u in vector.units], 0.02, 0.1)
            values.append(home + rng.uniform(-1, 1, (size, len(home))) * spread)
        else:
            values.append(rng.uniform(-0.5, 0.5, (size, len(vector.symbols))))
    return values


@pytest.fixture(scope="session")
def generated_dir(tmp_path_factory, models) -> Path:
    """All example models derived with their scenes into a session temp directory."""
    out = tmp_path_factory.mktemp("generated")
    for model in models.values():
        pipeline.write(pipeline.generate(model, pipeline.resolve_request(model)), out)
    return out
