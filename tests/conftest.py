"""Shared fixtures: example models, derivations, generated code and reference evaluators.

Compiled C goes to a per-session cache directory (``SYMKIN_CACHE_DIR``), so each model is
compiled once per test session (per xdist worker) and the user's cache is never touched.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy

from symkin import load, pipeline
from symkin.derivation import Derivation
from symkin.ir.spec import FunctionSpec, combine_functions
from symkin.model import Model, load_model

ROOT = Path(__file__).resolve().parent.parent
MODELS_DIR = ROOT / "models"
GENERATED_DIR = ROOT / "generated"
EXAMPLE_MODELS = sorted(p.stem for p in MODELS_DIR.glob("*.yaml"))
BACKENDS = ("numpy", "c", "casadi")
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
    vectors = [list(i.symbols) for i in spec.vector_inputs]
    values = model.parameter_values
    fns = [sympy.lambdify(vectors, sympy.Matrix(o.expr).xreplace(values), modules=modules) for o in spec.outputs]
    shapes = [o.shape for o in spec.outputs]

    def evaluate(*args):
        return [np.asarray(fn(*args), dtype=float).reshape(shape) for fn, shape in zip(fns, shapes)]

    return evaluate


def function_spec(model: Model, derivation: Derivation, record: dict) -> FunctionSpec:
    """The un-optimized spec of the generated function described by a manifest ``record``
    (for the combined scene function: the combination of its parts)."""
    if record.get("combines"):
        return combine_functions(model, record["name"], derivation.functions(record["combines"]))
    return derivation[record["name"]]


def random_q(model: Model, rng: np.random.Generator, size=None) -> np.ndarray:
    """Random joint coordinates within +-pi (revolute) and +-0.5 m (prismatic)."""
    shape = (model.dof,) if size is None else tuple(np.atleast_1d(size)) + (model.dof,)
    return rng.uniform(-np.pi, np.pi, shape)


def batch_reference(model: Model, spec: FunctionSpec):
    """Plain lambdify of the un-optimized outputs (parameters at their defaults), vectorized.

    Returns f(*vectors) with vectors of shape (N, n) -> list of arrays (N,) + output shape.
    """
    vectors = [list(i.symbols) for i in spec.vector_inputs]
    values = model.parameter_values
    fns = [sympy.lambdify(vectors, [e.xreplace(values) for e in o.entries], modules="numpy") for o in spec.outputs]

    def evaluate(*args):
        n = len(args[0])
        columns = [[a[:, k] for k in range(a.shape[1])] for a in args]
        results = []
        for fn, out in zip(fns, spec.outputs):
            entries = [np.broadcast_to(np.asarray(e, dtype=float), (n,)) for e in fn(*columns)]
            results.append(np.stack(entries, axis=-1).reshape((n,) + out.shape))
        return results

    return evaluate


@pytest.fixture(scope="session", autouse=True)
def compile_cache(tmp_path_factory, worker_id) -> Path:
    """Compiled C libraries go to a session temp directory, never to the user's cache.

    The xdist workers share it (the cache locks while compiling), so each library is
    compiled once per test run.
    """
    base = tmp_path_factory.getbasetemp()
    path = (base.parent if worker_id != "master" else base) / "symkin-cache"
    path.mkdir(exist_ok=True)
    previous = os.environ.get("SYMKIN_CACHE_DIR")
    os.environ["SYMKIN_CACHE_DIR"] = str(path)
    yield path
    if previous is None:
        os.environ.pop("SYMKIN_CACHE_DIR", None)
    else:
        os.environ["SYMKIN_CACHE_DIR"] = previous


@pytest.fixture(scope="session")
def loaded(generated_dir):
    """loaded(model, backend): the generated functions, loaded (and compiled) once per session."""
    cache = {}

    def get(name: str, backend: str):
        if (name, backend) not in cache:
            cache[name, backend] = load(generated_dir / name, backend=backend)
        return cache[name, backend]

    return get


@pytest.fixture(scope="session")
def generated_dir(tmp_path_factory, models) -> Path:
    """All example models derived with their scenes into a session temp directory."""
    out = tmp_path_factory.mktemp("generated")
    for model in models.values():
        pipeline.write(pipeline.generate(model, pipeline.resolve_request(model)), out)
    return out
