"""Shared fixtures: example models, derivations, generated code and reference evaluators.

Compiled C goes to a per-session cache directory (``SYMKIN_CACHE_DIR``), so each model is
compiled once per test session (per xdist worker) and the user's cache is never touched.
"""

from __future__ import annotations

import functools
import json
import os
import sys
from pathlib import Path

# One BLAS thread per worker, as make test runs the suite (Makefile: ONE_BLAS_THREAD) and the symkin command runs
# (symkin.cli.BLAS_THREADS): the workers take the cores; set before numpy is first imported, for a bare pytest run.
for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")
# XLA compiles the JAX programs with LLVM's optimizations off (set before JAX is first imported, here and in the
# commands the tests run): the same HLO, fused by XLA's own passes, computed by slower machine code.  The tests check
# values, never speed, and a third of the JAX tests' time was LLVM optimizing code that runs once (issue 66's module:
# 120 s -> 100 s standalone, 69 s -> 48 s of it compiling).  A user's XLA_FLAGS is kept.
os.environ.setdefault("XLA_FLAGS", "--xla_backend_optimization_level=0")

import numpy as np  # after the BLAS threads are set
import pytest

from symkin import load
from symkin.backends import BACKENDS as REGISTERED_BACKENDS
from symkin.derivation import Derivation
from symkin.ir.evaluate import lambdify_spec
from symkin.ir.spec import FunctionSpec, combine_functions
from symkin.model import Model, load_model

#: ``make test`` runs the numerics-sensitive modules a second time on foreign arithmetic (Makefile:
#: FOREIGN_ARITHMETIC): numpy's wide SIMD loops switched off (NPY_DISABLE_CPU_FEATURES) and the C
#: backend built with ``-O2 -march=native -ffp-contract=fast`` (FMA contraction where the CPU has
#: it), so that no tolerance rests on the rounding of one code path.
FOREIGN_ARITHMETIC = os.environ.get("SYMKIN_TEST_ARITHMETIC") == "foreign"
#: tests/backends/test_golden.py is not among them: what symkin derive writes is exact symbolic work printed by
#: repr; the floating point in a derivation (symkin.dynamics.feasibility's eigenvalues, model/body_build's
#: inertia check) only decides whether a model is refused, so the foreign pass would derive every model
#: again (a minute and a half on a slow machine) to compare the same bytes.
NUMERICS_MODULES = {"test_stability", "test_backends_agree", "test_pinocchio", "test_dynamics_newton_euler",
                    "test_dynamics_ur10e", "test_numpy_backend", "test_tolerances"}

# Nothing the tests run may leave a __pycache__ in the checkout (nor the commands the tests run: they inherit the
# environment).  `make test` keeps the bytecode under a prefix outside it (PYTHONPYCACHEPREFIX, Makefile): each
# worker and each command of the suite then compiles symkin and the tests once, not every time.  Without a prefix,
# no bytecode is written.  (The loader never runs a generated module's bytecode: symkin.backends.numpy.loader.)
if not sys.pycache_prefix:
    sys.dont_write_bytecode = True
    os.environ["PYTHONDONTWRITEBYTECODE"] = "1"

ROOT = Path(__file__).resolve().parent.parent
MODELS_DIR = ROOT / "models"
GENERATED_DIR = ROOT / "generated"
EXAMPLE_MODELS = sorted(p.stem for p in MODELS_DIR.glob("*.yaml"))
#: The backends the example models' scenes emit into generated/ (every one of them emits these).
SCENE_BACKENDS = set.intersection(*(set(json.loads(path.read_text())["backends"])
                                    for path in GENERATED_DIR.glob("*/manifest.json")))
#: Backends whose generated code the suite tests in a module of its own, not beside the others: the JAX modules in
#: generated/ (every scene emits them) are checked by tests/backends/test_jax_backend.py, which runs most of them op by
#: op - XLA compiling every function of every example model, as the shared tests would, takes longer than the suite
#: has (the UR10e's scene about half a minute on a CPU: benchmarks/bench_jax.py --compile).
OWN_MODULE_BACKENDS = ("jax",)
#: The backends whose code Python loads, from the one registry: a backend added there and to the scenes is tested
#: with the others on generated/ (but :data:`OWN_MODULE_BACKENDS`).
BACKENDS = tuple(name for name, backend in REGISTERED_BACKENDS.items()
                 if backend.loader is not None and name in SCENE_BACKENDS and name not in OWN_MODULE_BACKENDS)


def model_group(name: str):
    """The xdist group of the tests that derive the example model ``name`` symbolically: they share one worker,
    and so its derivation (:func:`shared_derivation`: the Stewart platform's quantities take seconds), its stability
    run (:func:`stability_run`) and the lambdified references of its generated functions (:func:`lambdified`)."""
    return pytest.mark.xdist_group(f"model-{name}")


def reference_group(name: str):
    """``name`` as a parameter of a test comparing generated code with the model's symbolic references
    (tests/backends/test_numpy_backend.py, tests/backends/test_backends_agree.py), in the model's group
    (:func:`model_group`)."""
    return pytest.param(name, marks=model_group(name))
SYMKIN_CLI = [sys.executable, "-m", "symkin"]


@pytest.fixture(scope="session")
def models() -> dict[str, Model]:
    """Every example model, loaded once."""
    return {name: load_model(MODELS_DIR / f"{name}.yaml") for name in EXAMPLE_MODELS}


@functools.lru_cache(maxsize=None)
def shared_derivation(model: Model) -> Derivation:
    """The derivation graph of ``model`` shared by every test of a worker (quantities are memoized)."""
    return Derivation(model)


#: The quantities a model's row of docs/numerical-stability.md leaves out (`symkin bench stability ... --skip`): the
#: Stewart platform's derivatives of the dynamics (about 100 s of a 2-core suite: 50-digit references of six legs'
#: J_x^-1 through a QR); the DELTA's, pantograph's and Agile Eye's runs check the same derivation, and
#: tests/derivation/test_parallel_dynamics_derivatives.py the Stewart platform's against differences.
STABILITY_SKIP = {"stewart": ("inverse_dynamics_derivatives", "forward_dynamics_derivatives", "gravity_derivatives")}


@functools.lru_cache(maxsize=None)
def stability_run(name: str):
    """``symkin bench stability models/<name>.yaml`` at its defaults (but :data:`STABILITY_SKIP`), once per worker: the run that
    docs/numerical-stability.md quotes (tests/stability/test_stability_table.py) and, on native arithmetic, the one
    tests/stability/test_stability.py judges (both modules' tests of a model share the model's xdist group,
    :func:`model_group`), on the worker's shared derivation of the model (:func:`shared_derivation`)."""
    from symkin.stability import run_stability

    model = load_model(MODELS_DIR / f"{name}.yaml")
    return run_stability(model, skip=STABILITY_SKIP.get(name, ()), derivation=shared_derivation(model))


@pytest.fixture(scope="session")
def derivations(models: dict[str, Model]) -> dict[str, Derivation]:
    """One shared derivation graph per example model (quantities are memoized across tests)."""
    return {name: shared_derivation(model) for name, model in models.items()}


#: (id of a spec, modules) -> (the spec, its lambdified function): the reference of a generated function is
#: printed and compiled once per worker (the Stewart platform's take 9 s), however many tests evaluate it; the
#: spec is kept so that its id is not reused.
_LAMBDIFIED: dict[tuple[int, str], tuple[FunctionSpec, object]] = {}


def lambdified(model: Model, spec: FunctionSpec, modules: str = "numpy"):
    """``lambdify_spec`` of ``spec``'s vector inputs with ``model``'s parameter values, once per spec and modules."""
    cached = _LAMBDIFIED.get((id(spec), modules))
    if cached is None or cached[0] is not spec:
        cached = (spec, lambdify_spec(spec, [list(i.symbols) for i in spec.vector_inputs], modules,
                                      model.parameter_values))
        _LAMBDIFIED[(id(spec), modules)] = cached
    return cached[1]


def reference_function(model: Model, spec: FunctionSpec, modules: str = "numpy"):
    """Plain lambdify of the un-optimized outputs, parameters at their defaults.

    Returns f(*vectors) -> list of arrays (one per output, shaped as declared).
    """
    fn = lambdified(model, spec, modules)
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


def relative_errors(got: np.ndarray, want: np.ndarray) -> np.ndarray:
    """Per batch entry (leading axis): max |got - want| / max(1, max |want|) over the entry's values.
    NaN (no real solution, e.g. an unreachable DELTA point) must be in both at the same places."""
    got, want = np.asarray(got, dtype=float), np.asarray(want, dtype=float)
    assert np.array_equal(np.isnan(got), np.isnan(want)), "NaN at different places"
    got, want = np.where(np.isnan(want), 0.0, got), np.where(np.isnan(want), 0.0, want)
    axes = tuple(range(1, want.ndim))
    scale = np.maximum(1.0, np.max(np.abs(want), axis=axes)) if axes else np.maximum(1.0, np.abs(want))
    diff = np.max(np.abs(got - want), axis=axes) if axes else np.abs(got - want)
    return diff / scale


def relative_error(got: np.ndarray, want: np.ndarray) -> float:
    """The worst of :func:`relative_errors` over the batch."""
    return float(np.max(relative_errors(got, want), initial=0.0))


def worst_state(got: np.ndarray, want: np.ndarray, inputs: list[np.ndarray]) -> dict:
    """For a failure message: the batch index whose entry of ``got`` is farthest from ``want``, and its inputs."""
    got, want = np.asarray(got, dtype=float), np.asarray(want, dtype=float)
    axes = tuple(range(1, want.ndim))
    diff = np.nan_to_num(np.abs(got - want), nan=np.inf)
    k = int(np.argmax(np.max(diff, axis=axes) if axes else diff))
    return {"index": k, "inputs": [np.asarray(a)[k].tolist() for a in inputs], "got": got[k].tolist(),
            "want": want[k].tolist()}


#: (id of a derivation, combined function, its parts) -> (the derivation, the combined spec): one object per
#: combination, so that its reference is lambdified once (:func:`lambdified`).
_COMBINED: dict[tuple[int, str, tuple[str, ...]], tuple[Derivation, FunctionSpec]] = {}


def function_spec(model: Model, derivation: Derivation, record: dict) -> FunctionSpec:
    """The un-optimized spec of the generated function described by a manifest ``record``
    (for the combined scene function: the combination of its parts, built once per derivation)."""
    if record.get("combines"):
        key = (id(derivation), record["name"], tuple(record["combines"]))
        cached = _COMBINED.get(key)
        if cached is None or cached[0] is not derivation:
            cached = (derivation, combine_functions(model, record["name"], derivation.functions(record["combines"])))
            _COMBINED[key] = cached
        return cached[1]
    return derivation[record["name"]]


def random_q(model: Model, rng: np.random.Generator, size=None) -> np.ndarray:
    """Random joint coordinates within +-pi (revolute) and +-0.5 m (prismatic)."""
    shape = (model.dof,) if size is None else tuple(np.atleast_1d(size)) + (model.dof,)
    return rng.uniform(-np.pi, np.pi, shape)


@functools.lru_cache(maxsize=None)
def _home_joints(model: Model) -> tuple[float, ...]:
    spec = shared_derivation(model)["ik"]
    fn = lambdify_spec(spec, [list(spec.vector_inputs[0].symbols)], "numpy", model.parameter_values)
    home = [float(e.xreplace(model.parameter_values)) for e in model.parallel.home]
    return tuple(float(v) for v in fn(home)[:model.dof])


def home_joints(model: Model) -> np.ndarray:
    """The actuated joints of a parallel mechanism at its home pose (the un-optimized closed-form IK)."""
    return np.array(_home_joints(model))


@functools.lru_cache(maxsize=None)
def _home_passive(model: Model) -> tuple[float, ...]:
    """The passive joints that close the legs at the home pose: Gauss-Newton on the un-optimized closure from 0."""
    derivation = shared_derivation(model)
    closure, jacobians = derivation["closure"], derivation["closure_jacobians"]
    symbols = [list(i.symbols) for i in closure.vector_inputs]
    phi = lambdify_spec(closure, symbols, "numpy", model.parameter_values)
    phi_s = lambdify_spec(jacobians, symbols, "numpy", model.parameter_values)
    q = list(home_joints(model))
    p = [float(e.xreplace(model.parameter_values)) for e in model.parallel.home]
    s = np.zeros(len(symbols[1]))
    rows = len(phi(q, list(s), p))
    for _ in range(50):
        values = np.array(phi(q, list(s), p), dtype=float)
        flat = np.array(phi_s(q, list(s), p), dtype=float)
        block = flat[rows * len(p) + rows * len(q):].reshape(rows, len(s))  # Phi_p, Phi_q, then Phi_s
        step = np.linalg.lstsq(block, -values, rcond=None)[0]
        s = s + step
        if np.max(np.abs(step)) < 1e-14:
            break
    angles = np.array([unit == "rad" for unit in closure.vector_inputs[1].units])
    s = np.where(angles, np.angle(np.exp(1j * s)), s)  # an assembly's angles, within (-pi, pi]
    return tuple(float(v) for v in s)


def home_passive(model: Model) -> np.ndarray:
    """The passive joint variables s of a parallel mechanism assembled at its home pose."""
    return np.array(_home_passive(model))


def random_inputs(model: Model, spec: FunctionSpec, rng: np.random.Generator, size: int) -> list[np.ndarray]:
    """Random values of every vector input of ``spec``: q as :func:`random_q` (for a parallel
    mechanism within 0.3 of its joints at the home pose, near assembled states), the passive joints s
    within +-0.5 rad of those that close the legs at the home pose (the closure's orientation rows are
    2 tan(angle/2) axis of the orientation error, which grows without bound - with its rounding error -
    towards half turns, where a pantograph's legs would be at random passive joints), the platform
    pose p within 2 cm / 0.1 rad of the model's home pose."""
    values = []
    for vector in spec.vector_inputs:
        if vector.name == "q" and model.parallel is not None:
            values.append(home_joints(model) + rng.uniform(-0.3, 0.3, (size, model.dof)))
        elif vector.name == "q":
            values.append(random_q(model, rng, size))
        elif vector.name == "p":
            home = np.array([float(e.xreplace(model.parameter_values)) for e in model.parallel.home])
            spread = np.where([u == "m" for u in vector.units], 0.02, 0.1)
            values.append(home + rng.uniform(-1, 1, (size, len(home))) * spread)
        elif vector.name == "s":
            values.append(home_passive(model) + rng.uniform(-0.5, 0.5, (size, len(vector.symbols))))
        else:
            values.append(rng.uniform(-0.5, 0.5, (size, len(vector.symbols))))
    return values


def batch_reference(model: Model, spec: FunctionSpec):
    """Plain lambdify of the un-optimized outputs (parameters at their defaults), vectorized.

    Returns f(*vectors) with vectors of shape (N, n) -> list of arrays (N,) + output shape.
    """
    fn = lambdified(model, spec)

    def evaluate(*args):
        n = len(args[0])
        flat = [np.broadcast_to(np.asarray(e, dtype=float), (n,)) for e in fn(*([a[:, k] for k in range(a.shape[1])]
                                                                               for a in args))]
        results, start = [], 0
        for out in spec.outputs:
            size = int(np.prod(out.shape)) if out.shape else 1
            results.append(np.stack(flat[start:start + size], axis=-1).reshape((n,) + out.shape))
            start += size
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
    path.mkdir(mode=0o700, exist_ok=True)  # the cache must be private (symkin.cache_trust)
    previous = {name: os.environ.get(name) for name in ("SYMKIN_CACHE_DIR", "SYMKIN_CFLAGS", "SYMKIN_C_ENTRY",
                                                        "SYMKIN_CACHE_SECRET")}
    os.environ["SYMKIN_CACHE_DIR"] = str(path)
    # the secret that seals cache entries, beside the cache (never the user's ~/.config)
    os.environ["SYMKIN_CACHE_SECRET"] = str(path.parent / "symkin-cache-secret")
    # The suite checks values and interfaces, which do not depend on the optimization level
    # (IEEE arithmetic, -std=c99: no contraction into FMAs, no fast-math); -O3 takes a minute on
    # the UR10e's dynamics and several on the Stewart platform's closure Jacobians.  The
    # issue's strict -O3 compile is its own test (test_c_backend.py).
    os.environ.setdefault("SYMKIN_CFLAGS", "-O0")
    # The C backend's functions are its ctypes ones here: the compiled CPython entry points over them (an
    # extension module per library: half a second of numpy's headers per build) are checked against them for
    # every example model and function by tests/backends/test_c_entry_points.py, which turns them on.
    os.environ.setdefault("SYMKIN_C_ENTRY", "ctypes")
    yield path
    for name, value in previous.items():
        if value is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = value


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
def generated_dir() -> Path:
    """The committed generated/: every example model derived with its scene.  tests/backends/test_golden.py checks
    that it is byte for byte what `symkin derive` gives now, so the tests read it instead of deriving every
    model again in each worker (and no test writes into it: copy it first)."""
    return GENERATED_DIR


#: Modules whose tests take longest (the 50-digit stability runs, the documents run as written): collected
#: first, so that the workers start them first and never end the session with one of them while the other
#: worker waits (xdist hands out tests in collection order).
LONG_FIRST = ("test_stability_table", "test_stability", "test_docs")
#: Modules collected last, in one xdist group: JAX starts threads when imported, and a worker that has imported it
#: should start no process afterwards (JAX warns that os.fork may then deadlock).
LAST = ("test_jax_backend",)


def pytest_ignore_collect(collection_path: Path, config) -> bool | None:
    """On foreign arithmetic only the numerics-sensitive modules are imported: the others' tests would be deselected
    (``-m numerics``) after each worker imported them all (a few seconds per worker)."""
    if FOREIGN_ARITHMETIC and collection_path.suffix == ".py" and collection_path.name.startswith("test_"):
        return collection_path.stem not in NUMERICS_MODULES or None
    return None


def pytest_collection_modifyitems(config, items):
    """Mark the numerics-sensitive modules ``numerics`` (the foreign-arithmetic run selects them), put the
    longest modules first (:data:`LONG_FIRST`) and those that import JAX last (:data:`LAST`)."""
    for item in items:
        if item.module.__name__.rsplit(".", 1)[-1] in NUMERICS_MODULES:
            item.add_marker(pytest.mark.numerics)

    def rank(item: pytest.Item) -> int:
        module = item.module.__name__.rsplit(".", 1)[-1]
        if module in LAST:
            return len(LONG_FIRST) + 1
        return LONG_FIRST.index(module) if module in LONG_FIRST else len(LONG_FIRST)

    items.sort(key=rank)  # stable: the order within and between the other modules is kept
    _tag_xdist_groups(config, items)


def _tag_xdist_groups(config, items) -> None:
    """In an xdist worker under ``--dist loadgroup``, end the node id of each test marked ``xdist_group`` with
    ``@<group>``, as pytest-xdist does: xdist 3.8 writes it to ``Item._nodeid``, which pytest 9 no longer reads
    (a node id is ``Item._id``), so every group was spread over the workers and each session fixture of a
    group (tests/stability/test_stability.py's runs) was computed once per worker."""
    if not getattr(config.option, "loadgroup", False):
        return
    try:
        from _pytest.nodeid import coerce_node_id
    except ImportError:  # an older pytest: xdist's own tag works
        return
    for item in items:
        names = sorted({str(mark.args[0] if mark.args else mark.kwargs.get("name", "default"))
                        for mark in item.iter_markers("xdist_group")})
        if names and "@" not in item.nodeid and hasattr(item, "_id"):
            item._id = coerce_node_id(f"{item.nodeid}@{'_'.join(names)}")
