"""What the dynamics derive and what they leave out: zero gravity, massless links, errors, determinism."""

from __future__ import annotations

import numpy as np
import pytest
import sympy

from conftest import MODELS_DIR, reference_function
from symkin.derivation import Derivation
from symkin.errors import DerivationError, ModelError
from symkin.model import model_from_text
from symkin.optimize import optimize
from tolerances import CLOSED_FORM, DYNAMICS

ARM = (MODELS_DIR / "planar_2r.yaml").read_text()


def _variant(old: str, new: str) -> str:
    assert old in ARM
    return ARM.replace(old, new)


def test_zero_gravity_emits_no_gravity_terms():
    model = model_from_text(_variant("gravity: [0, -g, 0]", "gravity: [0, 0, 0]"), "arm")
    d = Derivation(model)
    for name in ("gravity_vector", "potential_energy"):
        with pytest.raises(DerivationError, match="no gravity"):
            d[name]
    tau = d["inverse_dynamics"]
    assert "g" not in {i.name for i in tau.inputs}
    assert [o.name for o in d["operational_space"].outputs] == ["Mx", "Vx"]
    # tau = M qdd + V exactly.
    rng = np.random.default_rng(30)
    M, V = reference_function(model, d["mass_matrix"]), reference_function(model, d["coriolis_vector"])
    f = reference_function(model, tau)
    for _ in range(5):
        q, qd, qdd = rng.uniform(-3, 3, (3, 2))
        tau = f(q, qd, qdd)[0]
        np.testing.assert_allclose(tau, M(q)[0] @ qdd + V(q, qd)[0], rtol=0, atol=DYNAMICS * np.abs(tau).max())


def test_massless_links_contribute_nothing_and_cost_nothing():
    """A third link with zero mass and no inertia changes neither M nor its program."""
    base = model_from_text(ARM, "arm")
    with_massless = model_from_text(_variant("  - {link: link2, mass: m2}",
                                             "  - {link: link2, mass: m2}\n  - {link: link1, mass: 0, com: [0.05, 0, 0]}"),
                                    "arm")
    assert len(with_massless.bodies) == len(base.bodies) + 1
    for name in ("mass_matrix", "coriolis_matrix", "gravity_vector", "inverse_dynamics"):
        a, b = Derivation(base)[name], Derivation(with_massless)[name]
        assert a.definitions == b.definitions, name
        assert a.outputs == b.outputs, name
        assert optimize(a).op_counts == optimize(b).op_counts


def test_point_masses_and_rigid_bodies_both_count():
    """An inertia tensor on a link adds I_zz to the planar mass matrix (rotation about z)."""
    rigid = model_from_text(_variant("  - {link: link2, mass: m2}",
                                     "  - {link: link2, mass: m2, inertia: {xx: 0.001, yy: 0.002, zz: 0.003}}"), "arm")
    base = model_from_text(ARM, "arm")
    M_rigid = sympy.Matrix(Derivation(rigid)["mass_matrix"].expanded_outputs()[0])
    M_point = sympy.Matrix(Derivation(base)["mass_matrix"].expanded_outputs()[0])
    difference = (M_rigid - M_point).applyfunc(sympy.simplify)
    assert difference == sympy.Matrix([[sympy.Rational(3, 1000)] * 2] * 2)


def test_tcp_force_needs_a_square_task_jacobian():
    model = model_from_text(_variant("task_space: [x, y]", "task_space: [x, y, z]"), "arm")
    with pytest.raises(DerivationError, match="square"):
        Derivation(model)["tcp_force"]


def test_friction_needs_a_friction_section_and_positive_smoothing():
    with pytest.raises(DerivationError, match="no friction"):
        Derivation(model_from_text(ARM, "arm"))["friction"]
    bad = ARM + "friction:\n  theta1: {coulomb: 0.1, smoothing_velocity: -0.01}\n"
    with pytest.raises(ModelError, match="smoothing velocity must be positive"):
        model_from_text(bad, "arm")


def test_smooth_coulomb_friction_is_a_tanh_of_the_velocity():
    model = model_from_text(ARM.replace("  g: {", "  v_s: 0.02\n  g: {")
                            + "friction:\n  theta2: {viscous: 0.1, coulomb: 0.5, smoothing_velocity: v_s}\n", "arm")
    F = Derivation(model)["friction"].expanded_outputs()[0]
    v = sympy.Symbol("theta2_d", real=True)
    v_s = model.parameter("v_s").symbol
    assert F[0] == 0
    assert sympy.simplify(F[1] - (v / 10 + sympy.tanh(v / v_s) / 2)) == 0


def test_programs_are_deterministic():
    """Two fresh derivations give identical definitions (symengine's CSE does not depend on hash seeds)."""
    model = model_from_text(ARM, "arm")
    a, b = Derivation(model)["forward_dynamics"], Derivation(model)["forward_dynamics"]
    assert a == b
    assert a.definitions


def test_generated_friction_and_dynamics_match_the_expressions(tmp_path):
    """sign and tanh friction through the numpy backend (the example models have no friction)."""
    from symkin import load, pipeline
    from sample_models import FRICTION_ARM

    model = model_from_text(FRICTION_ARM)
    request = pipeline.resolve_request(model, only="friction,inverse_dynamics,forward_dynamics")
    arm = load(pipeline.write(pipeline.generate(model, request), tmp_path))
    d = Derivation(model)
    rng = np.random.default_rng(31)
    q, qd, x = rng.uniform(-2, 2, (3, 50, 3))
    qd[0] = [0.0, -0.01, 0.2]
    for name, args in (("friction", (qd,)), ("inverse_dynamics", (q, qd, x)), ("forward_dynamics", (q, qd, x))):
        reference = reference_function(model, d[name])
        got = getattr(arm, name)(*args)
        for k in range(0, 50, 7):
            np.testing.assert_allclose(got[k], reference(*(a[k] for a in args))[0], rtol=1e-12, atol=1e-12)
    # j1 at rest: no friction; j2: viscous + sign Coulomb; j3: smooth Coulomb only.
    np.testing.assert_allclose(arm.friction(qd[0]), [0, 0.05 * -0.01 - 0.1, 0.2 * np.tanh(0.2 / 0.05)],
                               rtol=CLOSED_FORM, atol=0)  # one tanh, a product and a sum


def test_tcp_force_where_elimination_without_pivoting_fails(models, derivations):
    """UR10e with J_11 = 0 (the TCP in the base's x-z plane) but J regular: J^T F = b still holds."""
    model = models["ur10e"]
    J = reference_function(model, derivations["ur10e"]["jacobian"])
    F = reference_function(model, derivations["ur10e"]["tcp_force"])
    M = reference_function(model, derivations["ur10e"]["mass_matrix"])
    V = reference_function(model, derivations["ur10e"]["coriolis_vector"])
    G = reference_function(model, derivations["ur10e"]["gravity_vector"])
    fk = reference_function(model, derivations["ur10e"]["fk"])
    q = np.array([0.0, -1.1, 1.3, -0.7, 1.2, 0.4])
    x, y = fk(q)[0][:2, 3]
    q[0] = -np.arctan2(y, x)  # turn the base until the TCP lies in the x-z plane: J_11 = -y = 0
    Jq = J(q)[0]
    assert abs(Jq[0, 0]) < 1e-12
    assert abs(np.linalg.det(Jq)) > 1e-3
    qd, qdd = np.linspace(-1, 1, 6), np.linspace(2, -2, 6)
    rhs = M(q)[0] @ qdd + V(q, qd)[0] + G(q)[0]
    np.testing.assert_allclose(Jq.T @ F(q, qd, qdd)[0], rhs, rtol=1e-10, atol=1e-10 * np.abs(rhs).max())
