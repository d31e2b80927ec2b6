"""The closure in CasADi (issue 62's CasADi counterpart of the run-time assembly; issue 63's differentiable fk and J
of legs of any topology): :class:`symkin.mechanism.casadi_assembly.CasadiAssembly` on the Novint Falcon's legs
without the distance form.

References: the run-time Gauss-Newton of the same generated closure (``solve_closure`` and ``closure_velocities``,
numpy linear algebra) at assembled states along a warm-started path, to the Newton tolerance times the condition
number of [Phi_s Phi_p]; CasADi's derivative of the rootfinder's p against the function's J (the implicit-function
theorem both ways) and against central differences of the assembly; an unreachable pose gives NaN, never a wrong
assembly.
"""

from __future__ import annotations

import casadi
import numpy as np
import pytest

from conftest import ROOT
from symkin import load, pipeline
from symkin.mechanism import closure
from symkin.mechanism.casadi_assembly import CasadiAssembly, independent_rows
from symkin.mechanism.closure import ClosureAssembly
from symkin.model import model_from_text
from symkin.runtime.parallel import closure_velocities, solve_closure
from tolerances import EPS

#: The run-time solver's step tolerance.
TOLERANCE = 1e-12


@pytest.fixture(scope="module")
def falcon(tmp_path_factory):
    """The Falcon's closure with every parameter folded: (numpy model, casadi model, the checked assembly function,
    its home assembly)."""
    text = (ROOT / "models" / "devices" / "novint_falcon.yaml").read_text()
    model = model_from_text(text, file="novint_falcon.yaml")
    request = pipeline.resolve_request(model, "closure,closure_jacobians", "numpy,casadi", fixed="all")
    directory = pipeline.write(pipeline.generate(model, request), tmp_path_factory.mktemp("falcon"))
    numeric = load(directory)
    runtime = ClosureAssembly(numeric)
    symbolic = load(directory, "casadi")
    return numeric, CasadiAssembly(symbolic, independent_rows(runtime)), runtime


def condition(model, q, s, p) -> float:
    """kappa of [Phi_s Phi_p] on its numerical rank (a rod's idle spin left out)."""
    A = np.hstack([model.closure_jacobians(q, s, p)[k] for k in (2, 0)])
    singular = np.linalg.svd(A, compute_uv=False)
    return float(singular[0] / singular[singular > singular[0] * A.shape[0] * EPS][-1])


def test_a_warm_started_path_follows_the_runtime_solver(falcon):
    model, symbolic, runtime = falcon
    assembly = symbolic.function()
    q0 = runtime.home
    s, p = runtime(q0)
    for t in np.linspace(0.0, 2 * np.pi, 12):
        q = q0 + np.radians(5.0) * np.sin(t + np.array([0.0, 2.1, 4.2]))
        result = assembly(q=q, guess=np.concatenate([s, p]))
        reference = solve_closure(model, q, s, p, unknowns=("p", "s"))
        assert closure.closes(reference, p)
        s, p = np.asarray(result["s"]).ravel(), np.asarray(result["p"]).ravel()
        kappa = condition(model, q, s, p)
        np.testing.assert_allclose(p, reference.solution["p"], rtol=0, atol=kappa * TOLERANCE)
        assert float(result["residual"]) <= 64 * EPS * kappa
        assert float(result["jump"]) == 0.0
        J = closure_velocities(model, q, s, p).J
        np.testing.assert_allclose(np.asarray(result["J"]), J, rtol=0, atol=kappa * 64 * EPS * np.abs(J).max())


def test_the_assembly_is_differentiable_through_the_rootfinder(falcon):
    """d p/d q of the rootfinder's solution (CasADi's implicit-function sensitivities) is the function's J, and
    both are central differences of the assembly (step h = 1e-6 rad: truncation h^2 |p'''| / 6 ~ 1e-13 m, rounding
    kappa NEWTON / h ~ 1e-10, below the 1e-8 asked)."""
    model, symbolic, runtime = falcon
    q0 = runtime.home + np.radians([3.0, -2.0, 4.0])
    s, p = runtime(q0)
    q, guess = casadi.MX.sym("q", 3), casadi.MX.sym("guess", symbolic.ns + symbolic.m)
    _, p_of_q = symbolic.assembly(q, guess)
    derivative = casadi.Function("dp_dq", [q, guess], [casadi.jacobian(p_of_q, q)])
    start = np.concatenate([s, p])
    J_ad = np.asarray(derivative(q0, start))
    J = np.asarray(symbolic.function()(q=q0, guess=start)["J"])
    np.testing.assert_allclose(J_ad, J, rtol=0, atol=condition(model, q0, s, p) * 64 * EPS * np.abs(J).max())
    h = 1e-6
    position = casadi.Function("p", [q, guess], [p_of_q])
    columns = [(np.asarray(position(q0 + h * e, start)) - np.asarray(position(q0 - h * e, start))).ravel() / (2 * h)
               for e in np.eye(3)]
    np.testing.assert_allclose(np.column_stack(columns), J, rtol=0, atol=1e-8)


def test_an_unreachable_pose_gives_nan(falcon):
    """One arm turned 120 deg from home: the rootfinder stops short of closing the legs, and s, p and J are NaN
    with the residual saying how far."""
    _, symbolic, runtime = falcon
    s, p = runtime(runtime.home)
    result = symbolic.function()(q=runtime.home + np.radians([120.0, 0.0, 0.0]), guess=np.concatenate([s, p]))
    assert np.isnan(np.asarray(result["p"])).all()
    assert np.isnan(np.asarray(result["s"])).all()
    assert np.isnan(np.asarray(result["J"])).all()
    assert float(result["residual"]) > closure.CLOSED


def test_a_jump_of_assembly_mode_is_flagged(falcon):
    """Every arm turned 170 deg from home: the legs close again, with the arms up (another assembly mode, the
    platform on the base's axis far from the home pose's neighbourhood): flagged, where a 3-deg step is not."""
    _, symbolic, runtime = falcon
    s, p = runtime(runtime.home)
    assembly, guess = symbolic.function(), np.concatenate([s, p])
    far = assembly(q=runtime.home + np.radians(170.0), guess=guess)
    assert float(far["residual"]) <= closure.CLOSED
    assert float(far["jump"]) == 1.0
    near = assembly(q=runtime.home + np.radians([3.0, -2.0, 1.0]), guess=guess)
    assert float(near["jump"]) == 0.0
