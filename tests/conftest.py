"""Shared fixtures: example models, derivations, generated code and reference evaluators."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from symkin import pipeline
from symkin.derivation import Derivation
from symkin.ir.evaluate import lambdify_spec
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

    Returns f(*vectors) -> list of arrays (one per output, shaped as declared).
    """
    fn = lambdify_spec(spec, [list(i.symbols) for i in spec.vector_inputs], modules, model.parameter_values)
    shapes = [o.shape for o in spec.outputs]

    def evaluate(*args):
        flat = fn(*args)
        out, start = [], 0
        for shape in shapes:
            size = int(np.prod(shape)) if shape else 1
            out.append(np.array(flat[start:start + size], dtype=float if modules == "numpy" else object).reshape(shape))
            start += size
        return out

    return evaluate


def random_q(model: Model, rng: np.random.Generator, size=None) -> np.ndarray:
    """Random joint coordinates within +-pi (revolute) and +-0.5 m (prismatic)."""
    shape = (model.dof,) if size is None else tuple(np.atleast_1d(size)) + (model.dof,)
    return rng.uniform(-np.pi, np.pi, shape)


@pytest.fixture(scope="session")
def generated_dir(tmp_path_factory, models) -> Path:
    """All example models derived with their scenes into a session temp directory."""
    out = tmp_path_factory.mktemp("generated")
    for model in models.values():
        pipeline.write(pipeline.generate(model, pipeline.resolve_request(model)), out)
    return out
