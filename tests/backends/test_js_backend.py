"""The JavaScript backend (issue 19): the generated module, run under Node.js, gives numpy's numbers.

Acceptance: for every example model and every generated function, the JavaScript module
evaluated under Node.js at random states agrees with the numpy module to a relative 1e-12
(plus, for the functions that solve with a matrix, the rounding the solve amplifies near
singular matrices: the same bound as numpy against C, tests/backends/test_backends_agree.py).  Node.js is
part of the test environment: a machine without it fails here instead of skipping.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from conftest import EXAMPLE_MODELS, function_spec, random_inputs, relative_errors, worst_state
from checks import agreement_bound

POINTS = 200
EVALUATOR = Path(__file__).resolve().parents[1] / "js" / "evaluate.js"


def node() -> str:
    path = shutil.which("node")
    assert path, "Node.js is needed to test the JavaScript backend: install it (Debian: apt-get install nodejs)"
    return path


def run_node(module: Path, calls: list[dict]) -> list:
    """Each call's outputs (flattened row-major) or {"error": message}, evaluated by tests/js/evaluate.js."""
    request = json.dumps({"module": str(module.resolve()), "calls": calls})
    done = subprocess.run([node(), str(EVALUATOR)], input=request, capture_output=True, text=True, check=True)
    return json.loads(done.stdout, parse_constant=float)


def _numbers(flat: list) -> np.ndarray:
    return np.array([float(v) for v in flat])


@pytest.mark.parametrize("name", EXAMPLE_MODELS)
def test_every_function_matches_numpy_under_node(name, models, derivations, generated_dir, loaded):
    model, reference = models[name], loaded(name, "numpy")
    rng = np.random.default_rng(19)
    calls, expected = [], []
    for record in reference.manifest["functions"]:
        spec = function_spec(model, derivations[name], record)
        inputs = random_inputs(model, spec, rng, POINTS)
        want = getattr(reference, record["name"])(*inputs)
        want = want if isinstance(want, tuple) else (want,)
        calls += [{"function": record["name"], "args": [v[k].tolist() for v in inputs]} for k in range(POINTS)]
        expected.append((record, spec, inputs, want))
    results = iter(run_node(generated_dir / name / f"{name}.js", calls))
    for record, spec, inputs, want in expected:
        got_rows = [next(results) for _ in range(POINTS)]
        bound = agreement_bound(model, spec, inputs, reference)
        for k, (w, out) in enumerate(zip(want, record["outputs"])):
            got = np.stack([_numbers(row[k]) for row in got_rows]).reshape(w.shape)
            error = relative_errors(got, w)
            worst = int(np.argmax(error / bound))
            assert error[worst] < bound[worst], (record["name"], out["name"], f"error {error[worst]:.3g} > bound "
                                                 f"{bound[worst]:.3g}", worst_state(got, w, inputs))


def test_parameters_are_an_optional_object_with_the_defaults(generated_dir, loaded):
    arm = loaded("planar_2r", "numpy")
    q = [0.3, 0.4]
    module = generated_dir / "planar_2r" / "planar_2r.js"
    default, longer, bad_size, unknown, not_a_number = run_node(module, [
        {"function": "fk", "args": [q]},
        {"function": "fk", "args": [q], "params": {"l1": 0.25}},
        {"function": "fk", "args": [[0.3]]},
        {"function": "fk", "args": [q], "params": {"l3": 1.0}},
        {"function": "fk", "args": [q], "params": {"l1": "long"}},
    ])
    np.testing.assert_array_equal(_numbers(default[0]), arm.fk(q).ravel())
    np.testing.assert_allclose(_numbers(longer[0]), arm.fk(q, l1=0.25).ravel(), rtol=0, atol=8 * np.finfo(float).eps)
    assert bad_size == {"error": "fk(): 'q' must be an array of 2 numbers, got [0.3]"}
    assert unknown == {"error": "fk(): unknown parameter 'l3'; it takes l1, l2"}
    assert "parameter 'l1' is not a number" in not_a_number["error"]


def test_the_module_describes_itself_and_loads_as_a_browser_script(generated_dir):
    """Metadata for the viewer (names, defaults, shapes); as a classic script it sets globalThis.symkin[name]."""
    module = (generated_dir / "delta" / "delta.js").resolve()
    script = (f"const vm = require('vm'); const context = {{}}; vm.createContext(context);"
              f"vm.runInContext(require('fs').readFileSync({json.dumps(str(module))}, 'utf8'), context);"
              "const m = context.symkin.delta;"
              "console.log(JSON.stringify([m.MODEL_NAME, m.COORDINATES, m.PARAMETERS.a, m.FUNCTIONS.ik, "
              "Object.isFrozen(m)]));")
    out = subprocess.run([node(), "-e", script], capture_output=True, text=True, check=True).stdout
    name, coordinates, a, ik, frozen = json.loads(out)
    assert (name, coordinates, a, frozen) == ("delta", ["theta1", "theta2", "theta3"], 0.1, True)
    assert ik == {"inputs": ["p"], "parameters": ["r_base", "r_tcp", "a", "b"],
                  "outputs": {"joints": [3], "margin": [3]}}
