"""Backends are generic: any vector inputs (q, qd, ...), parameters, and scalar, vector or
matrix outputs need no backend change (as the dynamics quantities will have)."""

from __future__ import annotations

import numpy as np
import pytest
import sympy

from conftest import BACKENDS
from symkin import load, manifest
from symkin.atomic import replace_directory
from symkin.backends import get_backend
from symkin.ir.inputs import coordinate_input
from symkin.ir.bundle import ModelCode, ParameterInfo
from symkin.ir.spec import OutputSpec, combine_functions, make_function
from symkin.optimize import optimize
from tolerances import CLOSED_FORM, DYNAMICS, KINEMATICS


@pytest.fixture(scope="module")
def dynamics_like(models, tmp_path_factory):
    """A planar_2r 'energy' function of q and qd: scalar, vector and matrix outputs, parameters."""
    model = models["planar_2r"]
    q, qd = coordinate_input(model, "q"), coordinate_input(model, "qd")
    (t1, t2), (w1, w2) = q.symbols, qd.symbols
    l1, l2, m1, m2, g = (p.symbol for p in model.parameters)
    M = sympy.ImmutableMatrix([[(m1 + m2) * l1**2 + m2 * l2**2 + 2 * m2 * l1 * l2 * sympy.cos(t2),
                                m2 * l2**2 + m2 * l1 * l2 * sympy.cos(t2)],
                               [m2 * l2**2 + m2 * l1 * l2 * sympy.cos(t2), m2 * l2**2]])
    w = sympy.Matrix([w1, w2])
    kinetic = (w.T * M * w)[0] / 2
    gravity = sympy.ImmutableMatrix([g * ((m1 + m2) * l1 * sympy.cos(t1) + m2 * l2 * sympy.cos(t1 + t2)),
                                     g * m2 * l2 * sympy.cos(t1 + t2)])
    friction = sympy.ImmutableMatrix([sympy.Rational(1, 10) * w1 + sympy.Rational(1, 2) * sympy.sign(w1),
                                      sympy.Max(w2, 0) - sympy.Min(w1, w2, 0) + sympy.Abs(w1) ** 3])
    energy = make_function(model, "energy", "Energy terms.", "test function",
                           [q, qd], [OutputSpec("k", sympy.ImmutableMatrix([kinetic]), "kinetic energy", "J"),
                                     OutputSpec("G", gravity, "gravity torques", "N*m", shape=(2,)),
                                     OutputSpec("M", M, "mass matrix", "kg*m^2"),
                                     OutputSpec("F", friction, "friction-like terms", shape=(2,))])
    mass = make_function(model, "mass", "Mass matrix.", "test function", [q],
                         [OutputSpec("M", M, "mass matrix", "kg*m^2")])
    specs = [energy, mass, combine_functions(model, "combined", [energy, mass])]
    code = ModelCode(model.name, model.hash, model.description, "test", tuple(j.name for j in model.joints),
                     tuple(ParameterInfo(p.name, float(p.value), p.unit, p.doc, p.name == "g")
                           for p in model.parameters),
                     tuple(optimize(s, ["g"]) for s in specs), float32=True)
    files, backend_files = {}, {}
    for name in BACKENDS:
        emitted = get_backend(name).emit(code)
        files.update(emitted)
        backend_files[name] = sorted(emitted)
    files[manifest.MANIFEST_NAME] = manifest.dumps(manifest.build_manifest(model, code, [], backend_files))
    target = tmp_path_factory.mktemp("generic") / model.name
    replace_directory(target, files)
    values = model.parameter_values
    reference = sympy.lambdify([q.symbols, qd.symbols], [kinetic.xreplace(values), gravity.xreplace(values),
                                                         M.xreplace(values), friction], modules="numpy")
    return target, reference


@pytest.mark.parametrize("backend", BACKENDS)
def test_two_vector_inputs_and_scalar_vector_matrix_outputs(dynamics_like, backend):
    target, reference = dynamics_like
    generated = load(target, backend=backend)
    rng = np.random.default_rng(0)
    q, qd = rng.uniform(-3, 3, (7, 2)), rng.uniform(-2, 2, (7, 2))
    qd[3] = 0.0  # sign(0) = 0 in every backend
    result = generated.energy(q, qd)
    assert type(result).__name__ == "EnergyResult"
    assert result.k.shape == (7,)
    assert result.G.shape == (7, 2)
    assert result.M.shape == (7, 2, 2)
    for i in range(7):
        k, G, M, F = reference(q[i], qd[i])
        # dynamics of a two-body cart-pendulum, relative to each output's largest entry
        for got, want in ((result.F[i], np.ravel(F)), (result.k[i], k), (result.G[i], np.ravel(G)), (result.M[i], M)):
            np.testing.assert_allclose(got, want, rtol=0, atol=DYNAMICS * max(np.abs(want).max(), 1.0))
    single = generated.energy(q[0], qd[0])
    assert single.k.shape == ()
    assert single.G.shape == (2,)
    # one configuration through the batch code or the single-call path: the same operations (the C
    # batch loop may vectorize sin/cos, which differ in the last bit): CLOSED_FORM
    np.testing.assert_allclose(single.k, result.k[0], rtol=CLOSED_FORM)
    # parameters broadcast; the folded g is no argument; qd broadcasts against q
    np.testing.assert_allclose(generated.energy(q, qd[0], m2=np.full(7, 0.1)).k, generated.energy(q, qd[0]).k,
                               rtol=CLOSED_FORM)
    with pytest.raises(TypeError):
        generated.energy(q, qd, g=9.81)
    with pytest.raises(ValueError, match=r"energy\(\): 'qd' must have shape \(\.\.\., 2\), got \(7, 3\)"):
        generated.energy(q, np.zeros((7, 3)))
    combined = generated.combined(q, qd)
    assert combined._fields == ("k", "G", "energy_M", "F", "mass_M")
    np.testing.assert_allclose(combined.mass_M, result.M, rtol=0, atol=DYNAMICS * np.abs(result.M).max())
    assert generated.mass(q).shape == (7, 2, 2)


def test_generic_c_compiles_without_warnings(dynamics_like, tmp_path):
    import subprocess

    from checks import CC, STRICT_FLAGS

    if CC is None:
        pytest.skip("no C compiler")
    target, _ = dynamics_like
    result = subprocess.run([CC, *STRICT_FLAGS, "-c", str(target / "planar_2r.c"), "-o", str(tmp_path / "g.o")],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert not result.stderr, result.stderr


def test_constant_outputs_and_prismatic_joints(tmp_path):
    """A Cartesian robot: the Jacobian is constant (no statements at all), fk has no trigonometry."""
    import subprocess

    from symkin import pipeline
    from symkin.model import load_model
    from checks import CC, STRICT_FLAGS

    path = tmp_path / "cart.yaml"
    path.write_text("name: cart\nparameters:\n  h: 0.5\nserial:\n  dh:\n    convention: classic\n    rows:\n"
                    "      - [x1, P, 0, 0, 0, 0]\n      - [x2, P, pi/2, h, 0, pi/2]\ntask_space: [x, y, z]\n"
                    "scene:\n  outputs: [fk, jacobian]\n  backends: [numpy, c, casadi]\n  float32: true\n")
    model = load_model(path)
    target = pipeline.write(pipeline.generate(model, pipeline.resolve_request(model)), tmp_path / "out")
    if CC is not None:
        result = subprocess.run([CC, *STRICT_FLAGS, "-c", str(target / "cart.c"), "-o", str(tmp_path / "cart.o")],
                                capture_output=True, text=True)
        assert result.returncode == 0, result.stderr
        assert not result.stderr, result.stderr
    q = np.random.default_rng(1).uniform(-1, 1, (5, 2))
    reference = load(target)
    for backend in ("c", "casadi"):
        generated = load(target, backend=backend)
        np.testing.assert_allclose(generated.fk(q, h=0.7), reference.fk(q, h=0.7), rtol=0, atol=KINEMATICS)
        np.testing.assert_allclose(generated.jacobian(q), reference.jacobian(q), rtol=0, atol=KINEMATICS)
        assert not np.any(np.isnan(generated.jacobian(q)))
