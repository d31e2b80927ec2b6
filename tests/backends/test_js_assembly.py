"""The generated inverse in JavaScript (issue 63): ``assemble_inverse`` of a model's script with ``closure`` and
``closure_jacobians`` - the viewer's solver of legs of any topology - against the run-time solver
(``symkin.runtime.parallel.solve_closure``, numpy linear algebra) with the same rules, and against the DELTA's
closed-form ik: the same convergence, the joints to the Newton tolerance times the condition number of
[Phi_q Phi_s], NaN where the legs do not close."""

from __future__ import annotations

import json

import numpy as np

from checks import delta_assemblies
from node_scripts import ITERATIONS, TOLERANCE, node_json, script_forward
from symkin import load
from symkin.mechanism.closure import MAX_STEP
from symkin.mechanism.continuation import STALL
from symkin.runtime.parallel import solve_closure


def script_inverse(module, targets: np.ndarray, q: np.ndarray, s: np.ndarray) -> list[dict]:
    """assemble_inverse(p, q, s, {}, options) of the script ``module`` at each target, evaluated by Node.js."""
    program = (f"const m = require({json.dumps(str(module))});"
               f"const targets = {json.dumps(targets.tolist())};"
               f"const options = {{max_iterations: {ITERATIONS}, tolerance: {TOLERANCE}, max_step: {MAX_STEP}, "
               f"stall: {STALL}}};"
               f"process.stdout.write(JSON.stringify(targets.map((p) => m.assemble_inverse(p, "
               f"{json.dumps(q.tolist())}, {json.dumps(s.tolist())}, {{}}, options))));")
    return node_json(program)


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


def test_the_scripts_forward_kinematics_and_jacobian_are_the_c_assemblys(generated_dir, loaded):
    """assemble and assembly_jacobian of generated/delta's script (the viewer's) against the C library's
    <model>_assemble and <model>_assembly_jacobian (GeneratedAssembly) from the same starts and the closed forms:
    the pose to the Newton tolerance times cond([Phi_s Phi_p]), J to 64 eps times it, the same refusal (0 steps and
    NaN) where the arms put the platform out of reach."""
    from symkin.runtime.assembly import GeneratedAssembly

    delta = loaded("delta", "c")
    assembly = GeneratedAssembly(delta)
    rng = np.random.default_rng(6303)
    q, s_exact, p_exact = delta_assemblies(delta, 8, rng)
    exact = p_exact[:-1]
    s0 = s_exact + rng.uniform(-0.05, 0.05, s_exact.shape)
    p0 = p_exact + rng.uniform(-0.01, 0.01, p_exact.shape)
    found = script_forward(generated_dir / "delta" / "delta.js", q, s0, p0)
    s, p = s0.copy(), p0.copy()
    steps, _ = assembly.assemble_batch(q, s, p)
    assert [f["steps"] > 0 for f in found] == (steps > 0).tolist()
    assert steps[-1] == 0
    assert np.isnan(found[-1]["p"]).all()
    assert np.isnan(found[-1]["s"]).all()
    assert np.isnan(found[-1]["J"]).all()
    for k in range(len(q) - 1):
        blocks = delta.closure_jacobians(q[k], s[k], p[k])
        singular = np.linalg.svd(np.hstack([blocks.Phi_s, blocks.Phi_p]), compute_uv=False)
        condition = singular[0] / singular[singular > singular[0] * 64 * np.finfo(float).eps][-1]
        np.testing.assert_allclose(found[k]["p"], p[k], rtol=0, atol=condition * TOLERANCE)
        np.testing.assert_allclose(found[k]["p"], exact[k], rtol=0, atol=condition * TOLERANCE)
        J = assembly.jacobian(q[k], s[k], p[k])
        np.testing.assert_allclose(found[k]["J"], J, rtol=0, atol=condition * 64 * np.finfo(float).eps * np.abs(J).max())
        assert abs(found[k]["steps"] - steps[k]) <= 1
