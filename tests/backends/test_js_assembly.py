"""The generated inverse in JavaScript (issue 63): ``assemble_inverse`` of a model's script with ``closure`` and
``closure_jacobians`` - the viewer's solver of legs of any topology - against the run-time solver
(``symkin.runtime.parallel.solve_closure``, numpy linear algebra) with the same rules, and against the DELTA's
closed-form ik: the same convergence, the joints to the Newton tolerance times the condition number of
[Phi_q Phi_s], NaN where the legs do not close."""

from __future__ import annotations

import json
import shutil
import subprocess

import numpy as np

from symkin import load
from symkin.mechanism.closure import MAX_STEP
from symkin.mechanism.continuation import STALL
from symkin.runtime.parallel import solve_closure

#: Gauss-Newton's step tolerance and its bound on the steps (the runtime's defaults).
TOLERANCE, ITERATIONS = 1e-12, 50


def script_inverse(module, targets: np.ndarray, q: np.ndarray, s: np.ndarray) -> list[dict]:
    """assemble_inverse(p, q, s, {}, options) of the script ``module`` at each target, evaluated by Node.js."""
    program = (f"const m = require({json.dumps(str(module))});"
               f"const targets = {json.dumps(targets.tolist())};"
               f"const options = {{max_iterations: {ITERATIONS}, tolerance: {TOLERANCE}, max_step: {MAX_STEP}, "
               f"stall: {STALL}}};"
               f"process.stdout.write(JSON.stringify(targets.map((p) => m.assemble_inverse(p, "
               f"{json.dumps(q.tolist())}, {json.dumps(s.tolist())}, {{}}, options))));")
    node = shutil.which("node")
    assert node, "Node.js is needed to test the JavaScript backend: install it (Debian: apt-get install nodejs)"
    out = subprocess.run([node, "-e", program], capture_output=True, text=True, check=True).stdout
    return [{key: np.array(value, dtype=float) if isinstance(value, list) else value for key, value in found.items()}
            for found in json.loads(out.replace("null", "NaN"))]


def test_the_scripts_inverse_is_the_runtime_solvers_and_the_closed_form(generated_dir):
    delta = load(generated_dir / "delta")
    home = np.asarray(delta.info.home, dtype=float)
    q0 = np.asarray(delta.ik(home).joints)
    s0 = solve_closure(delta, q0, np.zeros(delta.info.functions["closure"].inputs[1].shape[0]), home,
                       unknowns=("s",)).solution["s"]
    rng = np.random.default_rng(63)
    targets = np.vstack([home + rng.uniform(-0.03, 0.03, (10, 3)), home + [[0.0, 0.0, -0.5]]])
    found = script_inverse(generated_dir / "delta" / "delta.js", targets, q0, s0)
    reference = solve_closure(delta, q0, s0, targets, unknowns=("q", "s"), tol=TOLERANCE, max_iterations=ITERATIONS,
                              max_step=MAX_STEP, stall=STALL)
    assert [f["steps"] > 0 for f in found] == reference.converged.tolist()
    assert reference.converged[:10].all()
    assert np.isnan(found[10]["q"]).all()
    for k in range(10):
        _, Phi_q, Phi_s = (np.asarray(b) for b in delta.closure_jacobians(found[k]["q"], found[k]["s"], targets[k]))
        singular = np.linalg.svd(np.hstack([Phi_q, Phi_s]), compute_uv=False)
        condition = singular[0] / singular[singular > singular[0] * 64 * np.finfo(float).eps][-1]
        np.testing.assert_allclose(found[k]["q"], reference.solution["q"][k], rtol=0, atol=condition * TOLERANCE)
        np.testing.assert_allclose(found[k]["s"], reference.solution["s"][k], rtol=0, atol=condition * TOLERANCE)
        np.testing.assert_allclose(found[k]["q"], delta.ik(targets[k]).joints, rtol=0, atol=condition * TOLERANCE)
        assert abs(found[k]["steps"] - reference.iterations[k]) <= 1
