"""Smooth conditioning of CasADi Jacobians: the objective terms of dimensioning (seed sec. 4.2, Table 8.5).

The condition number kappa = sigma_max / sigma_min (seed eq. 8.25) has a kink where
singular values cross, so gradient-based dimensioning uses the Frobenius-norm condition
number instead (Angeles, Fundamentals of Robotic Mechanical Systems, sec. 4.9):

    kappa_F = (1/n) ||J||_F ||J^-1||_F,      kappa / n <= kappa_F <= kappa,

which equals 1 exactly at isotropy and is smooth elsewhere.  With ||J^-1||_F =
||adj J||_F / |det J|,

    1/kappa_F = n |det J| / (||J||_F ||adj J||_F),

finite (0) at singular configurations instead of a division by zero, and the term
|det J| / kappa_F of a GCI averaged with the Cartesian measure dW = |det J| dq is the
polynomial-over-norms n det(J)^2 / (||J||_F ||adj J||_F), smooth through singularities.
The numpy counterpart is :func:`symkin.numerics.conditioning.inverse_frobenius_condition_number`.
"""

from __future__ import annotations

from collections.abc import Sequence

import casadi


def adjugate(J: casadi.SX) -> casadi.SX:
    """adj J (so that J adj J = det J I) of a square matrix; closed forms up to 3 x 3."""
    n = J.shape[0]
    if n == 1:
        return casadi.SX.ones(1, 1)
    if n == 2:
        return casadi.vertcat(casadi.horzcat(J[1, 1], -J[0, 1]), casadi.horzcat(-J[1, 0], J[0, 0]))
    if n == 3:
        c0, c1, c2 = J[:, 0], J[:, 1], J[:, 2]
        # The rows of adj J are the cross products of the columns: row_i . column_j = det J delta_ij.
        return casadi.horzcat(casadi.cross(c1, c2), casadi.cross(c2, c0), casadi.cross(c0, c1)).T
    return determinant(J) * casadi.inv(J)


def homogenized(J: casadi.SX, length: float | None, position_rows: Sequence[int]) -> casadi.SX:
    """J with its translational rows divided by the characteristic length L (None: unchanged).

    As :func:`symkin.numerics.conditioning.homogenize`.
    """
    if length is None:
        return J
    scale = [1.0 / length if i in position_rows else 1.0 for i in range(J.shape[0])]
    return casadi.diag(casadi.DM(scale)) @ J


def determinant(J: casadi.SX) -> casadi.SX:
    """det J of a square matrix; closed forms up to 3 x 3."""
    n = J.shape[0]
    if J.shape[1] != n:
        raise ValueError(f"the Frobenius condition number needs a square Jacobian, this one is {n} x {J.shape[1]}")
    if n == 1:
        return J[0, 0]
    if n == 2:
        return J[0, 0] * J[1, 1] - J[0, 1] * J[1, 0]
    if n == 3:
        return casadi.dot(J[:, 0], casadi.cross(J[:, 1], J[:, 2]))
    return casadi.det(J)


def _frobenius_product(J: casadi.SX) -> casadi.SX:
    """||J||_F ||adj J||_F = n |det J| kappa_F."""
    return casadi.norm_fro(J) * casadi.norm_fro(adjugate(J))


def inverse_frobenius(J: casadi.SX) -> casadi.SX:
    """1/kappa_F = n |det J| / (||J||_F ||adj J||_F) in [0, 1]; 0 at singular configurations."""
    return J.shape[0] * casadi.fabs(determinant(J)) / _frobenius_product(J)


def measure_weighted_inverse_frobenius(J: casadi.SX, J_h: casadi.SX) -> casadi.SX:
    """|det J| / kappa_F(J_h): the GCI integrand for the Cartesian measure dW = |det J| dq.

    ``J_h`` is J homogenized (J_h = D J with a constant positive diagonal D, or J itself),
    so det J det J_h >= 0 and the term n det J det J_h / (||J_h||_F ||adj J_h||_F) has no
    absolute value: smooth wherever adj J_h != 0.
    """
    return J.shape[0] * determinant(J) * determinant(J_h) / _frobenius_product(J_h)

