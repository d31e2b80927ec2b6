"""Dynamics of a chain whose joints mimic others, in its coordinates (URDF ``<mimic>``).

A follower moves as q_j = a q_i + b, so the joint values are theta = A q + b with the constant
coupling matrix A (:func:`~symkin.model.coordinates.coupling_matrix`), and theta_d = A qd,
theta_dd = A qdd.  The Lagrangian in q is the chain's at theta(q); by the chain rule its
Euler-Lagrange equations are A^T times the chain's (the principle of virtual work):

    M_q = A^T M(theta) A,   V_q = A^T V(theta, A qd),   G_q = A^T G(theta),
    tau_q = A^T tau(theta, A qd, A qdd),   F_f,q = A^T F_f(A qd)

(Featherstone, *Rigid Body Dynamics Algorithms*, 2008, sec. 8.1, for a constraint theta = gamma(q)
with constant G = A).  Without followers every function returns its input unchanged.
"""

from __future__ import annotations

from collections.abc import Sequence

import symengine as se

from symkin.dynamics.program import se_matrix, se_vector
from symkin.model import coordinates
from symkin.model.schema import Model

Matrix = list[list[se.Basic]]


def joint_rates(model: Model, group: str) -> list[se.Basic]:
    """The joints' values in ``group`` ("q", "qd" or "qdd") as SymEngine expressions of the coordinates."""
    return se_vector(coordinates.joint_values(model, group))


def forces_on_coordinates(model: Model, joint_forces: Sequence[se.Basic]) -> list[se.Basic]:
    """A^T f: the generalized forces on the coordinates of the joint forces (torques) f."""
    A = coordinates.coupling_matrix(model)
    if A is None:
        return list(joint_forces)
    columns = se_matrix(A.T)
    return [sum((a * f for a, f in zip(row, joint_forces) if a != 0), se.Integer(0)) for row in columns]


def matrix_on_coordinates(model: Model, M: Matrix) -> Matrix:
    """A^T M A for a joints x joints matrix M (the mass matrix in the coordinates)."""
    A = coordinates.coupling_matrix(model)
    if A is None:
        return M
    a = se_matrix(A)
    MA = [[sum((M[i][k] * a[k][c] for k in range(len(M)) if a[k][c] != 0), se.Integer(0))
           for c in range(A.shape[1])] for i in range(len(M))]
    return [forces_on_coordinates(model, [MA[i][c] for i in range(len(M))]) for c in range(A.shape[1])]
