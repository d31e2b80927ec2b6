"""The generated assembly of K samples in one call (issue 63: C single and batch): ``<model>_assemble_batch`` and
``<model>_assembly_jacobian_batch`` through :meth:`GeneratedAssembly.assemble_batch` and
:meth:`GeneratedAssembly.jacobian_batch`.

References: the single-sample functions (the same C function per sample: equal bit for bit) and the DELTA's
generated closed forms (``fk``, ``jacobian``) of generated/delta, whose closure is solved by its generated assembly
(the DELTA modelled both ways); a sample whose legs cannot close gives 0 steps and NaN without touching the others.
"""

from __future__ import annotations

import numpy as np
import pytest

from checks import delta_assemblies
from symkin.runtime.assembly import GeneratedAssembly


@pytest.fixture(scope="module")
def delta(loaded):
    """generated/delta loaded with the C backend, its generated assembly, and 12 assembled samples (q, s, p) plus one
    whose arms put the platform out of reach (the closed-form fk's spheres do not meet)."""
    model = loaded("delta", "c")
    return (model, GeneratedAssembly(model), *delta_assemblies(model, 12, np.random.default_rng(6301)))


def test_a_batch_assembles_each_sample_from_its_own_start_as_one_call_does(delta):
    model, assembly, q, s_exact, p_exact = delta
    rng = np.random.default_rng(6302)
    s0 = s_exact + rng.uniform(-0.05, 0.05, s_exact.shape)
    p0 = p_exact + rng.uniform(-0.01, 0.01, p_exact.shape)
    s, p = s0.copy(), p0.copy()
    steps, residual = assembly.assemble_batch(q, s, p)
    for k in range(len(q)):
        s1, p1 = s0[k].copy(), p0[k].copy()
        assert assembly.assemble(q[k], s1, p1) == (steps[k], residual[k])
        np.testing.assert_array_equal(p[k], p1)
        np.testing.assert_array_equal(s[k], s1)
    assert np.all(steps[:-1] >= 1)
    np.testing.assert_allclose(p[:-1], p_exact[:-1], rtol=0, atol=1e-12)      # the closed-form fk
    assert steps[-1] == 0                                                       # out of reach: refused, NaN
    assert np.isnan(p[-1]).all()
    assert np.isnan(s[-1]).all()


def test_a_batch_of_jacobians_is_the_closed_forms_and_each_call_s(delta):
    model, assembly, q, s, p = delta
    J = assembly.jacobian_batch(q[:-1], s[:-1], p[:-1])
    assert J.shape == (len(q) - 1, 3, 3)
    for k in range(len(q) - 1):
        np.testing.assert_array_equal(J[k], assembly.jacobian(q[k], s[k], p[k]))
    closed = model.jacobian(q[:-1], p[:-1])
    np.testing.assert_allclose(J, closed, rtol=0, atol=1e-10 * np.abs(closed).max())
    nan = np.full_like(s[:1], np.nan)       # a failed assembly's passive joints (the DELTA's Phi_p is constant)
    assert np.isnan(assembly.jacobian_batch(q[:1], nan, p[:1])).all()           # no assembly: NaN, not a number


def test_a_batch_of_the_wrong_shape_or_type_is_refused_naming_the_array(delta):
    _, assembly, q, s, p = delta
    with pytest.raises(ValueError, match=r"'s' must be a writable float64 C-contiguous array of shape \(13, "):
        assembly.assemble_batch(q, s[:-1].copy(), p.copy())
    with pytest.raises(ValueError, match="'q' must be a float64 C-contiguous array of shape"):
        assembly.jacobian_batch(q.astype(np.float32), s, p)
