"""Conditioning of the Jacobian (seed sec. 4.2, Table 8.5): isotropy, singularities, criteria, length.

Oracles: the symbolic Jacobian of the derivation (exact isotropy), numpy's SVD-based
``numpy.linalg.cond``, and mpmath's SVD at 50 digits near singular configurations.
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
import sympy

import symkin
from symkin.numerics import conditioning as C
from symkin.analysis import global_indices
from symkin import mechanism
from symkin.model import coordinates

from conftest import GENERATED_DIR
from tolerances import svd

ARM = symkin.load(GENERATED_DIR / "planar_2r")
UR10E = symkin.load(GENERATED_DIR / "ur10e")


# --- isotropy of the 2R arm ------------------------------------------------------------------


def _gram(models, derivations):
    model = models["planar_2r"]
    th1, th2 = coordinates.symbols(model, "q")
    l1, l2 = model.parameter("l1").symbol, model.parameter("l2").symbol
    J = sympy.Matrix(derivations["planar_2r"]["jacobian"].outputs[0].expr)
    return sympy.simplify(J.T * J), th1, th2, l1, l2


def test_isotropic_configuration_is_derived_from_the_symbolic_jacobian(models, derivations):
    """J^T J = lambda I  <=>  l1 = sqrt(2) l2 and cos(theta2) = -1/sqrt(2) (theta2 = +-135 deg)."""
    G, th1, th2, l1, l2 = _gram(models, derivations)
    c2 = sympy.Symbol("c2", real=True)
    # J^T J depends on theta2 only through cos(theta2) (and not at all on theta1).
    assert not G.has(th1)
    G_c = G.subs(sympy.cos(th2), c2)
    assert not G_c.has(th2)
    positive = sympy.Symbol("L1", positive=True), sympy.Symbol("L2", positive=True)
    G_c = G_c.subs({l1: positive[0], l2: positive[1]})
    solutions = sympy.solve([G_c[0, 1], G_c[0, 0] - G_c[1, 1]], [c2, positive[0]], dict=True)
    assert solutions == [{c2: -sympy.sqrt(2) / 2, positive[0]: sympy.sqrt(2) * positive[1]}]


@pytest.mark.parametrize("theta2", [3 * sympy.pi / 4, -3 * sympy.pi / 4])
def test_jtj_is_exactly_proportional_to_identity_at_isotropy(models, derivations, theta2):
    G, th1, th2, l1, l2 = _gram(models, derivations)
    isotropic = sympy.simplify(G.subs({l1: sympy.sqrt(2) * l2, th2: theta2}))
    assert sympy.simplify(isotropic - l2**2 * sympy.eye(2)) == sympy.zeros(2, 2)


@pytest.mark.parametrize("theta2", [3 * np.pi / 4, -3 * np.pi / 4])
def test_kappa_is_one_at_isotropy_numerically(theta2):
    arm = ARM.bind(l1=np.sqrt(2) * 0.1, l2=0.1)
    q = np.column_stack([np.linspace(-np.pi, np.pi, 9), np.full(9, theta2)])
    J = arm.jacobian(q)
    # a 2x2 SVD (svd(2): two backward-stable ones compared, relative to sigma_max)
    assert np.allclose(C.condition_number(J), 1.0, rtol=0, atol=svd(2))
    assert np.allclose(C.inverse_condition_number(J), 1.0, rtol=0, atol=svd(2))
    assert np.allclose(C.frobenius_condition_number(J), 1.0, rtol=0, atol=svd(2))
    assert np.allclose(C.singular_values(J), 0.1, rtol=svd(2))
    # Away from it the arm is not isotropic.
    assert np.all(C.inverse_condition_number(arm.jacobian(q + [0.0, 0.1])) < 0.999)


# --- singular configurations -----------------------------------------------------------------


def test_stretched_and_folded_arm_give_inverse_kappa_zero_never_nan():
    q = np.array([[t1, t2] for t1 in np.linspace(-3, 3, 13) for t2 in (0.0, np.pi, -np.pi)])
    J = ARM.jacobian(q)
    for arm_J in (J, ARM.bind(l1=0.3, l2=0.1).jacobian(q)):
        inverse = C.inverse_condition_number(arm_J)
        assert np.all(inverse == 0.0)
        assert np.all(C.condition_number(arm_J) == np.inf)
        assert np.all(C.inverse_frobenius_condition_number(arm_J) == 0.0)
        assert np.all(C.transmission_indices(arm_J).speed == np.inf)
    assert C.inverse_condition_number(np.zeros((2, 2))) == 0.0
    assert C.inverse_condition_number(np.zeros((6, 6))) == 0.0


@pytest.mark.parametrize("shape", [(3, 3), (6, 6), (6, 2), (2, 6), (4, 3)])
def test_rank_deficient_matrices_give_exactly_zero(shape):
    rng = np.random.default_rng(1)
    m, n = shape
    k = min(m, n)
    J = rng.normal(size=(200, m, k - 1)) @ rng.normal(size=(200, k - 1, n))  # rank k-1
    assert np.all(C.inverse_condition_number(J) == 0.0)
    assert np.all(C.inverse_frobenius_condition_number(J) == 0.0)
    assert not np.isnan(C.condition_number(J)).any()


def test_2x2_closed_form_is_as_accurate_as_an_svd_near_singularity():
    """1/kappa at theta2 = 1e-12 ... 1e-2 against a 50-digit SVD of the same matrix.

    An SVD is backward stable (absolute error of a few eps on 1/kappa); the naive closed
    form sigma_min^2 = (t - sqrt(t^2 - 4 det^2)) / 2 would be off by ~sqrt(eps) = 1e-8.
    """
    q = np.array([[0.3, t] for t in np.logspace(-12, -2, 11)])
    J = ARM.bind(l1=0.25, l2=0.1).jacobian(q)
    ours = C.inverse_condition_number(J)
    with mpmath.workdps(50):
        for Jk, value in zip(J, ours):
            s = mpmath.svd_r(mpmath.matrix(Jk.tolist()), compute_uv=False)
            exact = min(s) / max(s)
            assert abs(value - float(exact)) <= 4 * np.finfo(float).eps


# --- against numpy and the definitions --------------------------------------------------------


@pytest.mark.parametrize("shape", [(2, 2), (3, 3), (6, 6), (6, 2), (2, 6)])
def test_indices_match_numpy_svd(shape):
    rng = np.random.default_rng(2)
    J = rng.normal(size=(64,) + shape)
    cond = np.linalg.cond(J, 2)
    assert np.allclose(C.condition_number(J), cond, rtol=1e-12)
    assert np.allclose(C.inverse_condition_number(J), 1 / cond, rtol=1e-12)
    s = np.linalg.svd(J, compute_uv=False)
    assert np.allclose(C.singular_values(J), s, rtol=0, atol=svd(max(shape)) * s[..., :1])
    k = min(shape)
    frobenius = np.sqrt((s**2).sum(-1) * (s**-2).sum(-1)) / k
    assert np.allclose(C.frobenius_condition_number(J), frobenius, rtol=1e-12)
    if shape[0] == shape[1]:
        assert np.allclose(C.frobenius_condition_number(J), np.linalg.cond(J, "fro") / k, rtol=1e-10)
    # kappa / k <= kappa_F <= kappa
    kF = C.frobenius_condition_number(J)
    assert np.all(kF <= cond * (1 + 1e-12))
    assert np.all(kF >= cond / k * (1 - 1e-12))
    assert np.allclose(C.manipulability(J), np.sqrt(np.linalg.det(J @ np.swapaxes(J, -1, -2)))
                       if shape[0] <= shape[1] else np.prod(s, axis=-1), rtol=1e-10)


def test_table_8_5_criteria_are_singular_values_of_the_inverse_jacobian():
    rng = np.random.default_rng(3)
    J = rng.normal(size=(50, 3, 3))
    s_inverse = np.linalg.svd(np.linalg.inv(J), compute_uv=False)
    indices = C.transmission_indices(J)
    assert np.allclose(indices.force, s_inverse[:, -1], rtol=1e-12)  # sigma_min(J^-1) -> max
    assert np.allclose(indices.speed, s_inverse[:, 0], rtol=1e-12)  # sigma_max(J^-1) -> min
    assert np.allclose(indices.manipulability, np.abs(np.linalg.det(J)), rtol=1e-12)
    assert np.allclose(indices.inverse_condition, s_inverse[:, -1] / s_inverse[:, 0], rtol=1e-12)


def test_indices_from_an_inverse_jacobian():
    rng = np.random.default_rng(4)
    J = rng.normal(size=(20, 3, 3))
    J_inverse = np.linalg.inv(J)
    assert np.allclose(C.from_inverse(J_inverse), J, rtol=1e-10, atol=1e-12)
    assert np.allclose(C.inverse_condition_number(J_inverse), C.inverse_condition_number(J), rtol=1e-12)
    singular = np.outer([1.0, 2.0, 3.0], [1.0, 0.0, 1.0])
    assert np.all(C.from_inverse(singular) == 0.0)
    assert C.inverse_condition_number(C.from_inverse(singular)) == 0.0


def test_absolute_determinant_closed_forms_match_lapack():
    rng = np.random.default_rng(5)
    for n in (2, 3, 4):
        J = rng.normal(size=(30, n, n))
        assert np.allclose(C.absolute_determinant(J), np.abs(np.linalg.det(J)), rtol=1e-12)


# --- characteristic length (UR10e: translations and rotations mixed) -------------------------


def test_homogenize_scales_only_the_translational_rows():
    J = UR10E.jacobian(np.full(6, 0.3))
    rows = mechanism.position_rows(UR10E)
    assert rows == (0, 1, 2)
    H = C.homogenize(J, 0.5, rows)
    assert np.allclose(H[:3], J[:3] / 0.5)
    assert np.array_equal(H[3:], J[3:])
    with pytest.raises(ValueError):
        C.homogenize(J, 0.0, rows)


def test_characteristic_length_minimizes_the_mean_frobenius_conditioning():
    q = np.random.default_rng(6).uniform(-np.pi, np.pi, (512, 6))
    J = UR10E.jacobian(q)
    rows = mechanism.position_rows(UR10E)
    L = C.characteristic_length(J, rows)

    def cost(length):
        return np.mean(1 / C.inverse_frobenius_condition_number(C.homogenize(J, length, rows))[
            C.inverse_condition_number(J) > 0] ** 2)

    assert 0.05 < L < 1.5  # metres, for an arm of 1.3 m reach
    assert cost(L) < cost(1.05 * L)
    assert cost(L) < cost(L / 1.05)


def test_characteristic_length_scales_with_the_mechanism():
    """Scaling every length of the UR10e by s scales its characteristic length by s."""
    lengths = {name: UR10E.parameters[name] for name in ("d1", "a2", "a3", "d4", "d5", "d6")}
    q = np.random.default_rng(7).uniform(-np.pi, np.pi, (256, 6))
    rows = mechanism.position_rows(UR10E)
    L = C.characteristic_length(UR10E.jacobian(q), rows)
    scaled = UR10E.bind(**{k: 2.5 * v for k, v in lengths.items()})
    assert C.characteristic_length(scaled.jacobian(q), rows) == pytest.approx(2.5 * L, rel=1e-6)


def test_mixed_task_space_needs_a_length():
    with pytest.raises(ValueError, match="characteristic length"):
        global_indices.local_index(UR10E, np.zeros((1, 6)))
    auto = global_indices.local_index(UR10E, np.full((1, 6), 0.4), length="auto")
    assert 0 < auto[0] <= 1
