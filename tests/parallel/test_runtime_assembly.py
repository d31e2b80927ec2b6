"""The generated assembly's interface on the run-time solver (issue 63: numpy, batched): ``RuntimeAssembly`` of a
model loaded with the numpy backend against the C library's ``<model>_assemble_batch`` and
``<model>_assembly_jacobian_batch`` (``GeneratedAssembly``) from the same starts, and the DELTA's closed forms: the
pose to the Newton tolerance times cond([Phi_s Phi_p]), J to 64 eps times it, the same refusal (0 steps, NaN) out of
reach.  The flag of a possible jump of solution branch (a correction above the tolerance that does not halve the one
before: the start outside its Newton-Kantorovich region) on Newton's classic divergent case, atan(x) = 0 from
|x0| > 1.39."""

from __future__ import annotations

import numpy as np
import pytest

from checks import delta_assemblies
from symkin.errors import GeneratedCodeError
from symkin.newton import newton_iterate
from symkin.runtime.assembly import GeneratedAssembly, RuntimeAssembly


@pytest.fixture(scope="module")
def delta(loaded):
    """generated/delta on numpy and on C, and 10 samples (and one out of reach) with starts near them."""
    numpy_model, c_model = loaded("delta", "numpy"), loaded("delta", "c")
    rng = np.random.default_rng(6304)
    q, s, p = delta_assemblies(numpy_model, 10, rng)
    return numpy_model, c_model, q, s + rng.uniform(-0.05, 0.05, s.shape), p + rng.uniform(-0.01, 0.01, p.shape), p


def test_the_run_time_assembly_gives_the_c_assemblys_poses_and_jacobians(delta):
    numpy_model, c_model, q, s0, p0, exact = delta
    runtime, generated = RuntimeAssembly(numpy_model), GeneratedAssembly(c_model)
    s, p, s_c, p_c = s0.copy(), p0.copy(), s0.copy(), p0.copy()
    steps, _ = runtime.assemble_batch(q, s, p)
    steps_c, _ = generated.assemble_batch(q, s_c, p_c)
    assert ((steps > 0) == (steps_c > 0)).all()
    assert steps[-1] == 0                                           # out of reach: refused, NaN
    assert np.isnan(p[-1]).all()
    assert np.isnan(s[-1]).all()
    J, J_c = runtime.jacobian_batch(q[:-1], s[:-1], p[:-1]), generated.jacobian_batch(q[:-1], s_c[:-1], p_c[:-1])
    for k in range(len(q) - 1):
        blocks = numpy_model.closure_jacobians(q[k], s[k], p[k])
        singular = np.linalg.svd(np.hstack([blocks.Phi_s, blocks.Phi_p]), compute_uv=False)
        condition = singular[0] / singular[-1]
        np.testing.assert_allclose(p[k], p_c[k], rtol=0, atol=condition * 1e-12)
        np.testing.assert_allclose(p[k], exact[k], rtol=0, atol=condition * 1e-12)
        np.testing.assert_allclose(J[k], J_c[k], rtol=0, atol=condition * 64 * np.finfo(float).eps * np.abs(J_c[k]).max())
    one_s, one_p = s0[0].copy(), p0[0].copy()
    assert runtime.assemble(q[0], one_s, one_p)[0] == steps[0]    # one sample: the batch's first
    np.testing.assert_array_equal(one_p, p[0])
    np.testing.assert_array_equal(runtime.jacobian(q[0], s[0], p[0]), J[0])
    assert np.isnan(runtime.jacobian(q[0], np.full_like(s[0], np.nan), p[0])).all()


def test_a_correction_that_does_not_halve_is_flagged_as_a_possible_jump():
    """Newton on atan(x) = 0 converges from |x0| < 1.39 (each correction a fraction of the last) and diverges beyond
    (each correction larger than the last): only the latter leaves the start's Newton-Kantorovich region."""
    def equations(x, rows):
        return np.arctan(x), (1.0 / (1.0 + x ** 2))[..., None]

    with np.errstate(over="ignore"):    # the divergent iterates grow past a double's range
        report = newton_iterate(np.array([[0.5], [1.5]]), equations, tol=1e-12, max_iterations=20)
    assert report.converged.tolist() == [True, False]
    assert report.left_region.tolist() == [False, True]


def test_a_model_without_its_closure_is_refused_with_the_fix(loaded):
    with pytest.raises(GeneratedCodeError, match="derive the model with closure"):
        RuntimeAssembly(loaded("ur10e", "numpy"))
