"""Physics of the derived dynamics, for every example model at random states.

M symmetric positive definite; dM/dt - 2C skew-symmetric; V = C qd; G = du/dq; the power
balance d(k + u)/dt = qd . (tau - F_f); forward dynamics inverts inverse dynamics; TCP
forces and operational-space dynamics satisfy their defining equations (seed sec. 4.4).
Derivatives are central finite differences at 40 digits (mpmath), where the check needs
more than double precision.
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
import yaml

from conftest import EXAMPLE_MODELS, MODELS_DIR, random_q, reference_function
from symkin.derivation import Derivation
from symkin.model import model_from_text
from tolerances import CLOSED_FORM
from sample_models import FRICTION_ARM

STATES = 4



def _dynamic_models(models):
    out = {name: models[name] for name in EXAMPLE_MODELS if models[name].bodies}
    out["friction_arm"] = model_from_text(FRICTION_ARM)
    return out


@pytest.fixture(scope="module")
def cases(models, derivations):
    """(model, derivation) of every example model with bodies, plus the friction arm."""
    out = {}
    for name, model in _dynamic_models(models).items():
        out[name] = (model, derivations[name] if name in derivations else Derivation(model))
    return out


def _declares_bodies(name: str) -> bool:
    data = yaml.safe_load((MODELS_DIR / f"{name}.yaml").read_text())
    return "bodies" in data and "parallel" not in data


#: The serial example models with bodies, chosen at collection, plus the friction arm (the parallel
#: models' dynamics, in actuated coordinates on a constraint manifold, are tests/parallel/test_parallel_dynamics.py's).
CASE_NAMES = [name for name in EXAMPLE_MODELS if _declares_bodies(name)] + ["friction_arm"]


def _f(case, name, modules="numpy"):
    model, d = case
    fn = reference_function(model, d[name], modules)
    return lambda *args: fn(*args)[0] if len(d[name].outputs) == 1 else fn(*args)


def _states(model, seed):
    rng = np.random.default_rng(seed)
    for _ in range(STATES):
        yield random_q(model, rng), rng.uniform(-2, 2, model.dof), rng.uniform(-3, 3, model.dof)


def _mp(x):
    return [mpmath.mpf(float(v)) for v in x]


def _mp_array(values) -> np.ndarray:
    return np.array([[float(v) for v in row] for row in np.atleast_2d(values)], dtype=float).squeeze()


@pytest.mark.parametrize("name", CASE_NAMES)
def test_mass_matrix_is_symmetric_positive_definite(name, cases):
    model, _ = cases[name]
    M = _f(cases[name], "mass_matrix")
    for q, _, _ in _states(model, 10):
        Mq = M(q)
        # M_ij and M_ji are emitted once (symmetric outputs share their expression): equal to the bit
        # unless a backend computes them apart; CLOSED_FORM of the largest entry allows one reordering
        np.testing.assert_allclose(Mq, Mq.T, rtol=0, atol=CLOSED_FORM * np.abs(Mq).max())
        assert np.linalg.eigvalsh(Mq).min() > 0


@pytest.mark.parametrize("name", CASE_NAMES)
def test_coriolis_matrix_gives_V_and_makes_Mdot_minus_2C_skew(name, cases):
    model, _ = cases[name]
    M = _f(cases[name], "mass_matrix", "mpmath")
    C, V = _f(cases[name], "coriolis_matrix"), _f(cases[name], "coriolis_vector")
    h = mpmath.mpf("1e-15")
    with mpmath.workdps(40):
        for q, qd, _ in _states(model, 11):
            Cq = C(q, qd)
            np.testing.assert_allclose(Cq @ qd, V(q, qd), rtol=1e-12, atol=1e-12 * np.abs(Cq).max())
            q0, v = _mp(q), _mp(qd)
            Mdot = (M([a + h * b for a, b in zip(q0, v)]) - M([a - h * b for a, b in zip(q0, v)])) / (2 * h)
            N = _mp_array(Mdot) - 2 * Cq
            np.testing.assert_allclose(N, -N.T, rtol=0, atol=1e-12 * max(1.0, np.abs(Cq).max()))


@pytest.mark.parametrize("name", CASE_NAMES)
def test_gravity_vector_is_the_gradient_of_the_potential(name, cases):
    model, _ = cases[name]
    G, u = _f(cases[name], "gravity_vector"), _f(cases[name], "potential_energy", "mpmath")
    h = mpmath.mpf("1e-15")
    with mpmath.workdps(40):
        for q, _, _ in _states(model, 12):
            q0 = _mp(q)
            grad = []
            for i in range(model.dof):
                plus, minus = list(q0), list(q0)
                plus[i] += h
                minus[i] -= h
                grad.append(float((u(plus)[()] - u(minus)[()]) / (2 * h)))
            np.testing.assert_allclose(G(q), grad, rtol=1e-12, atol=1e-12 * np.abs(grad).max())


@pytest.mark.parametrize("name", CASE_NAMES)
def test_power_balance(name, cases):
    """d(k + u)/dt = qd . (tau - F_f) along q(t) = q + t qd + t^2/2 qdd (central difference in t)."""
    model, d = cases[name]
    k, u = _f(cases[name], "kinetic_energy", "mpmath"), _f(cases[name], "potential_energy", "mpmath")
    tau = _f(cases[name], "inverse_dynamics")
    friction = _f(cases[name], "friction") if model.friction else (lambda qd: np.zeros(model.dof))
    h = mpmath.mpf("1e-15")
    with mpmath.workdps(40):
        for q, qd, qdd in _states(model, 13):
            q0, v, a = _mp(q), _mp(qd), _mp(qdd)

            def energy(t):
                qt = [x + t * y + t * t / 2 * z for x, y, z in zip(q0, v, a)]
                vt = [y + t * z for y, z in zip(v, a)]
                return k(qt, vt)[()] + u(qt)[()]

            power = float((energy(h) - energy(-h)) / (2 * h))
            expected = qd @ (tau(q, qd, qdd) - friction(qd))
            assert power == pytest.approx(expected, rel=1e-10, abs=1e-10)


@pytest.mark.parametrize("name", CASE_NAMES)
def test_forward_dynamics_inverts_inverse_dynamics(name, cases):
    model, _ = cases[name]
    tau, qdd_of = _f(cases[name], "inverse_dynamics"), _f(cases[name], "forward_dynamics")
    M, V, G = _f(cases[name], "mass_matrix"), _f(cases[name], "coriolis_vector"), _f(cases[name], "gravity_vector")
    friction = _f(cases[name], "friction") if model.friction else (lambda qd: np.zeros(model.dof))
    for q, qd, qdd in _states(model, 14):
        t = tau(q, qd, qdd)
        np.testing.assert_allclose(t, M(q) @ qdd + V(q, qd) + G(q) + friction(qd), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(qdd_of(q, qd, t), qdd, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("name", CASE_NAMES)
def test_tcp_force_and_operational_space_satisfy_their_definitions(name, cases):
    """J^T F = M qdd + V + G (eq. 8.35/8.37); Mx = J^-T M J^-1, Vx = J^-T (V - M J^-1 Jdot qd), Gx = J^-T G."""
    model, d = cases[name]
    assert len(model.task_space) == model.dof, "every dynamic case has a square task Jacobian"
    J, F = _f(cases[name], "jacobian"), _f(cases[name], "tcp_force")
    M, V, G = _f(cases[name], "mass_matrix"), _f(cases[name], "coriolis_vector"), _f(cases[name], "gravity_vector")
    Jmp = _f(cases[name], "jacobian", "mpmath")
    ops = _f(cases[name], "operational_space")
    h = mpmath.mpf("1e-15")
    checked = 0
    for q, qd, qdd in _states(model, 15):
        Jq = J(q)
        if abs(np.linalg.det(Jq)) < 1e-3 * np.abs(Jq).max() ** model.dof:
            continue  # too close to a singularity for a meaningful comparison
        checked += 1
        rhs = M(q) @ qdd + V(q, qd) + G(q)
        np.testing.assert_allclose(Jq.T @ F(q, qd, qdd), rhs, rtol=1e-9, atol=1e-9 * np.abs(rhs).max())
        with mpmath.workdps(40):
            q0, v = _mp(q), _mp(qd)
            Jdot = _mp_array((Jmp([a + h * b for a, b in zip(q0, v)]) - Jmp([a - h * b for a, b in zip(q0, v)]))
                             / (2 * h))
        Jinv = np.linalg.inv(Jq)
        Mx, Vx, Gx = ops(q, qd)
        np.testing.assert_allclose(Mx, Jinv.T @ M(q) @ Jinv, rtol=1e-8, atol=1e-8 * np.abs(Mx).max())
        Vx_ref = Jinv.T @ (V(q, qd) - M(q) @ Jinv @ Jdot @ qd)
        np.testing.assert_allclose(Vx, Vx_ref, rtol=1e-8, atol=1e-8 * np.abs(Vx_ref).max())
        np.testing.assert_allclose(Gx, Jinv.T @ G(q), rtol=1e-8, atol=1e-8 * np.abs(Gx).max())
    assert checked >= STATES // 2, f"only {checked} of {STATES} random states were away from singularities"


@pytest.mark.parametrize("name", CASE_NAMES)
def test_coriolis_matrix_is_made_of_christoffel_symbols(name, cases):
    """C_ij = sum_k 1/2 (dM_ij/dq_k + dM_ik/dq_j - dM_jk/dq_i) qd_k with dM/dq by differences of M."""
    model, _ = cases[name]
    M = _f(cases[name], "mass_matrix", "mpmath")
    C = _f(cases[name], "coriolis_matrix")
    n = model.dof
    h = mpmath.mpf("1e-15")
    with mpmath.workdps(40):
        for q, qd, _ in _states(model, 16):
            q0 = _mp(q)
            dM = []
            for k in range(n):
                plus, minus = list(q0), list(q0)
                plus[k] += h
                minus[k] -= h
                dM.append(_mp_array((M(plus) - M(minus)) / (2 * h)).reshape(n, n))
            want = np.array([[sum((dM[k][i, j] + dM[j][i, k] - dM[i][j, k]) / 2 * qd[k] for k in range(n))
                              for j in range(n)] for i in range(n)])
            np.testing.assert_allclose(C(q, qd), want, rtol=0, atol=1e-12 * max(1.0, np.abs(want).max()))
