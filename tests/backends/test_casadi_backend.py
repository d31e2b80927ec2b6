"""The CasADi backend: named functions that keep the IR's common subexpressions, deterministic
files, and CasADi's own C generation of them."""

from __future__ import annotations

import os
import shutil
import subprocess

import casadi
import numpy as np
import pytest

from conftest import random_q
from symkin.backends.casadi.emit import build_function, serialize
from symkin.ir.spec import OptimizedFunction
from symkin.optimize import optimize
from tolerances import KINEMATICS, UR10E_SCALE


def test_functions_have_named_inputs_outputs_and_defaults(loaded):
    ur = loaded("ur10e", "casadi")
    fk = ur.fk.casadi
    assert fk.name() == "fk"
    assert fk.name_in() == ["q", "d1", "a2", "a3", "d4", "d5", "d6"]
    assert fk.name_out() == ["base_T_tcp"]
    assert fk.size_in(0) == (6, 1)
    assert fk.size_out(0) == (4, 4)
    assert fk.nnz_out(0) == 16  # dense, as the other backends
    # Called by name: omitted parameters take the model defaults, an omitted q is NaN.
    q = np.linspace(-1, 1, 6)
    np.testing.assert_allclose(fk(q=q)["base_T_tcp"].full(), ur.fk(q), atol=KINEMATICS * UR10E_SCALE)
    assert np.all(np.isnan(fk(d1=0.2)["base_T_tcp"].full()[:3, :]))
    combined = ur.combined.casadi
    assert combined.name_out() == ["base_T_tcp", "J", "M", "V", "G"]
    assert combined.name_in()[:2] == ["q", "qd"]
    # The raw function names the wrong input itself (the wrappers raise the numpy backend's errors).
    with pytest.raises(RuntimeError, match=r"Input 0 \(q\) has mismatching shape"):
        fk(q=np.zeros(5))


def test_graph_keeps_the_common_subexpressions(models, derivations):
    """The SX graph built from the optimized IR is far smaller than one built from the raw outputs."""
    spec = derivations["ur10e"]["frames"]
    optimized = optimize(spec)
    raw = OptimizedFunction(spec, (), tuple(tuple(o.entries) for o in spec.outputs), {})
    shared, unshared = build_function(optimized), build_function(raw)
    assert shared.n_nodes() < unshared.n_nodes() / 2
    q = np.random.default_rng(0).uniform(-3, 3, 6)
    params = [float(i.default) for i in spec.parameter_inputs]
    for a, b in zip(shared(q, *params), unshared(q, *params)):
        np.testing.assert_allclose(a.full(), b.full(), atol=KINEMATICS * UR10E_SCALE)


def test_serialization_is_deterministic_within_a_process(derivations):
    """Same IR, same bytes, whatever was built before (the golden test covers fresh processes)."""
    first = serialize(build_function(optimize(derivations["planar_2r"]["jacobian"])))
    build_function(optimize(derivations["ur10e"]["fk"]))
    assert serialize(build_function(optimize(derivations["planar_2r"]["jacobian"]))) == first


def test_functions_differentiate_like_the_generated_jacobian(loaded, models):
    """CasADi's AD of the fk graph gives the geometric Jacobian's linear rows (an independent check)."""
    ur = loaded("ur10e", "casadi")
    q = casadi.SX.sym("q", 6)
    position = ur.fk.casadi(q, *[ur.parameters[p] for p in ("d1", "a2", "a3", "d4", "d5", "d6")])[0:3, 3]
    dp_dq = casadi.Function("dp_dq", [q], [casadi.jacobian(position, q)])
    for point in random_q(models["ur10e"], np.random.default_rng(1), 5):
        # AD propagates the FK's rounding through one more product per node: twice KINEMATICS
        np.testing.assert_allclose(dp_dq(point).full(), ur.jacobian_geometric(point)[:3], atol=2 * KINEMATICS * UR10E_SCALE)


@pytest.mark.skipif(shutil.which(os.environ.get("CC", "cc")) is None, reason="no C compiler")
def test_casadi_generates_c_that_compiles_and_agrees(loaded, models, tmp_path):
    ur = loaded("ur10e", "casadi")
    generator = casadi.CodeGenerator("ur10e_casadi.c", {"with_header": True})
    for name in ("fk", "jacobian", "combined"):
        generator.add(getattr(ur, name).casadi)
    generator.generate(str(tmp_path) + os.sep)
    library = tmp_path / "libur10e_casadi.so"
    subprocess.run([os.environ.get("CC", "cc"), "-std=c99", "-O1", "-fPIC", "-shared", "-Wall",
                    str(tmp_path / "ur10e_casadi.c"), "-o", str(library), "-lm"], check=True, capture_output=True)
    q = random_q(models["ur10e"], np.random.default_rng(3), 20)
    params = [ur.parameters[p] for p in ("d1", "a2", "a3", "d4", "d5", "d6")]
    external = casadi.external("fk", str(library))
    jacobian = casadi.external("jacobian", str(library))
    for point in q:
        np.testing.assert_allclose(external(point, *params).full(), ur.fk(point), atol=KINEMATICS * UR10E_SCALE)
        np.testing.assert_allclose(jacobian(point, *params[1:]).full(), ur.jacobian(point), atol=KINEMATICS * UR10E_SCALE)
