"""numpy, C and CasADi give the numbers of the sympy expressions, with one calling convention.

Acceptance (issue 4): for every example model and every generated function, each backend
agrees with plain lambdify of the un-optimized sympy outputs at 1000 random points to a
relative 1e-12, plus the rounding a solve amplifies near singular matrices (eps times kappa^2,
see agreement_bound); wrong input shapes raise the same clear errors in every backend.
"""

from __future__ import annotations

import inspect
import subprocess
import sys

import numpy as np
import pytest

from conftest import (BACKENDS, EXAMPLE_MODELS, GENERATED_DIR, batch_reference, function_spec, random_inputs,
                      random_q, reference_group, relative_errors, worst_state)
from tolerances import CLOSED_FORM, DYNAMICS, EPS, KINEMATICS, UR10E_SCALE
from checks import record_agreement_bound
from reference_store import manifest_key, stored

POINTS = 1000




def _tuple(result):
    return result if isinstance(result, tuple) else (result,)


def sampled(name, records, seed, points, models, derivations, references=True) -> dict[str, list[list[np.ndarray]]]:
    """{generated function: [its random inputs, and with ``references`` the sympy reference's outputs]} of the
    manifest ``records`` at ``points`` states drawn from ``seed`` in their order, shared by make test's two passes
    (tests/reference_store.py)."""
    model = models[name]

    def compute() -> dict[str, np.ndarray]:
        rng, arrays = np.random.default_rng(seed), {}
        for record in records:
            spec = function_spec(model, derivations[name], record)
            inputs = random_inputs(model, spec, rng, points)
            arrays.update({f"{record['name']}/in{k}": value for k, value in enumerate(inputs)})
            if references:
                arrays.update({f"{record['name']}/out{k}": value
                               for k, value in enumerate(batch_reference(model, spec)(*inputs))})
        return arrays

    arrays = stored(manifest_key(GENERATED_DIR / name, seed, points, references), compute)
    counts = {"in": lambda r: sum(i["kind"] == "vector" for i in r["inputs"]),
              "out": lambda r: len(r["outputs"]) if references else 0}
    return {r["name"]: [[arrays[f"{r['name']}/{kind}{k}"] for k in range(count(r))] for kind, count in counts.items()]
            for r in records}


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", [reference_group(name) for name in EXAMPLE_MODELS])
def test_every_function_matches_the_sympy_expressions(name, backend, models, derivations, loaded):
    model = models[name]
    generated = loaded(name, backend)
    assert generated.backend == backend
    samples = sampled(name, generated.manifest["functions"], 11, POINTS, models, derivations)
    checked = []
    for record in generated.manifest["functions"]:
        inputs, want = samples[record["name"]]
        got = _tuple(getattr(generated, record["name"])(*inputs))
        assert len(got) == len(want)
        bound = record_agreement_bound(model, record, inputs, loaded(name, "numpy"))
        for g, w, out in zip(got, want, record["outputs"]):
            assert g.shape == w.shape == (POINTS,) + tuple(out["shape"])
            error = relative_errors(g, w)
            worst = int(np.argmax(error / bound))
            assert error[worst] < bound[worst], (record["name"], out["name"], f"error {error[worst]:.3g} > bound "
                                                 f"{bound[worst]:.3g}", worst_state(g, w, inputs))
        checked.append(record["name"])
    assert checked == list(generated.functions)
    assert "combined" in checked


def assert_close_at_scale(got, want):
    """Equal to DYNAMICS (the bound of the deepest outputs, tests/tolerances.py) times the output's
    largest entry: evaluation orders differ in rounding, and the dynamics outputs (hundreds of N m,
    thousands of rad/s^2) cancel to small entries, whose error is that of the large ones."""
    scale = float(np.nanmax(np.abs(want), initial=1.0))
    np.testing.assert_allclose(got, want, rtol=0, atol=DYNAMICS * scale)


@pytest.mark.parametrize("backend", ("c", "casadi"))
@pytest.mark.parametrize("name", EXAMPLE_MODELS)
def test_same_signatures_and_batch_semantics_as_numpy(name, backend, models, derivations, loaded):
    reference, other = loaded(name, "numpy"), loaded(name, backend)
    assert other.functions == reference.functions
    samples = sampled(name, reference.manifest["functions"], 5, 12, models, derivations, references=False)
    for record in reference.manifest["functions"]:
        function = record["name"]
        f_ref, f_other = getattr(reference, function), getattr(other, function)
        assert inspect.signature(f_other) == inspect.signature(f_ref)
        full = [v.reshape((3, 4) + v.shape[1:]) for v in samples[function][0]]
        for pick in (lambda a: a, lambda a: a[1, 2], lambda a: a[:, :1], lambda a: np.zeros((0, a.shape[-1]))):
            args = [pick(a) for a in full]
            want, got = _tuple(f_ref(*args)), _tuple(f_other(*args))
            assert type(got).__name__ == type(want).__name__
            for g, w in zip(got, want):
                assert g.shape == w.shape
                assert g.dtype == np.float64
                assert_close_at_scale(g, w)


@pytest.mark.parametrize("backend", BACKENDS)
def test_parameters_broadcast_against_the_batch(backend, loaded):
    arm, reference = loaded("planar_2r", backend), loaded("planar_2r", "numpy")
    q = np.array([[0.3, 0.4], [0.1, 0.2]])
    for kwargs in ({"l1": np.array([0.1, 0.2]), "l2": 0.3}, {"l1": np.array([[0.1], [0.2], [0.4]])},
                   {"l2": 0.25}):
        # the planar FK is a closed form of two terms; positions scale with the reach (< 1 m)
        np.testing.assert_allclose(arm.fk(q, **kwargs), reference.fk(q, **kwargs), rtol=0, atol=CLOSED_FORM)
        np.testing.assert_allclose(arm.fk(q[0], **kwargs), reference.fk(q[0], **kwargs), rtol=0, atol=CLOSED_FORM)
    t1, t2 = q[1]
    assert arm.fk(q, l1=np.array([0.1, 0.2]), l2=0.3)[1, 0, 3] == pytest.approx(
        0.2 * np.cos(t1) + 0.3 * np.cos(t1 + t2), abs=CLOSED_FORM * 0.5)  # terms <= l1 + l2 = 0.5 m
    bound = arm.bind(l1=0.2, l2=0.2)
    # at q = 0 the entries are sums of sin(0) = 0 and cos(0) = 1 times lengths: one rounding of 0.4 m
    np.testing.assert_allclose(bound.jacobian([0, 0]), [[0, 0], [0.4, 0.2]], rtol=0, atol=EPS * 0.4)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("bad", [np.zeros(5), np.zeros((3, 7)), 1.0, [[1, 2, 3]]])
def test_wrong_input_shape_raises_the_same_clear_error(backend, bad, loaded):
    ur = loaded("ur10e", backend)
    with pytest.raises(ValueError, match=r"^fk\(\): 'q' must have shape \(\.\.\., 6\), got \(") as error:
        ur.fk(bad)
    with pytest.raises(ValueError) as numpy_error:
        loaded("ur10e", "numpy").fk(bad)
    assert str(error.value) == str(numpy_error.value)


@pytest.mark.parametrize("backend", BACKENDS)
def test_missing_or_unknown_arguments_raise_the_same_type_errors(backend, loaded):
    ur, reference = loaded("ur10e", backend), loaded("ur10e", "numpy")
    for call in (lambda m: m.fk(), lambda m: m.fk(np.zeros(6), d7=1.0), lambda m: m.fk(np.zeros(6), 0.2),
                 lambda m: m.jacobian(np.zeros(6), np.zeros(6))):
        with pytest.raises(TypeError) as error:
            call(ur)
        with pytest.raises(TypeError) as numpy_error:
            call(reference)
        assert str(error.value) == str(numpy_error.value)
    with pytest.raises(ValueError, match="do not broadcast") as error:
        ur.fk(np.zeros((4, 6)), d1=np.ones(3))
    with pytest.raises(ValueError) as numpy_error:
        reference.fk(np.zeros((4, 6)), d1=np.ones(3))
    assert str(error.value) == str(numpy_error.value)


@pytest.mark.parametrize("backend", ("c", "casadi"))
def test_loading_does_not_import_sympy(backend, generated_dir, compile_cache):
    code = ("import sys, numpy as np; from symkin import load; "
            f"m = load({str(generated_dir / 'ur10e')!r}, backend={backend!r}); m.fk(np.zeros(6)); "
            "m.combined(np.zeros((3, 6)), np.zeros((3, 6))); print('sympy' in sys.modules, 'jinja2' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "False"]


def test_results_are_fresh_arrays(loaded):
    """Outputs never share memory with each other or between calls (the C binding reuses scratch memory)."""
    for backend in BACKENDS:
        ur = loaded("ur10e", backend)
        first = ur.fk(np.zeros(6))
        ur.fk(np.ones(6))
        np.testing.assert_array_equal(first, loaded("ur10e", "numpy").fk(np.zeros(6)))
        result = ur.combined(np.zeros(6), np.zeros(6))
        result.base_T_tcp[:] = 7.0
        assert not np.any(result.J == 7.0)
        assert not np.any(result.M == 7.0)


def test_large_batches_are_evaluated_in_chunks_with_the_same_results(loaded, models):
    """numpy evaluates batches above its chunk size piecewise; results equal the C backend's."""
    numpy_ur, c_ur = loaded("ur10e", "numpy"), loaded("ur10e", "c")
    q = random_q(models["ur10e"], np.random.default_rng(9), (3, 5000))
    qd = np.random.default_rng(10).uniform(-1, 1, q.shape)
    d6 = np.linspace(0.1, 0.2, 5000)
    for kwargs in ({}, {"d6": d6}, {"d6": d6[:, None].T}):
        got, want = numpy_ur.combined(q, qd, **kwargs), c_ur.combined(q, qd, **kwargs)
        assert type(got).__name__ == "CombinedResult"
        for g, w in zip(got, want):
            assert g.shape == w.shape
            assert_close_at_scale(g, w)
    assert numpy_ur.fk(q[0, :3000]).shape == (3000, 4, 4)


@pytest.mark.parametrize("backend", ("c", "casadi"))
def test_concurrent_calls_from_threads_are_independent(backend, loaded, models):
    """The single-configuration paths reuse per-thread scratch memory; threads must not mix results."""
    from concurrent.futures import ThreadPoolExecutor

    ur, reference = loaded("ur10e", backend), loaded("ur10e", "numpy")
    q = random_q(models["ur10e"], np.random.default_rng(12), 400)

    def work(offset):
        return [ur.jacobian(q[k], a2=-0.6 - 0.001 * k) for k in range(offset, 400, 4)]

    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(work, range(4)))
    for offset, got in enumerate(results):
        for k, J in zip(range(offset, 400, 4), got):
            # UR10e Jacobian entries (threads must not change a bit; mixing would be O(1))
            np.testing.assert_allclose(J, reference.jacobian(q[k], a2=-0.6 - 0.001 * k), rtol=0, atol=KINEMATICS * UR10E_SCALE)
