"""The Lagrangian dynamics of a serial chain in closed form (seed sec. 4.4, eqs. 8.31-8.34).

With L = k - u (eq. 8.32) and the velocity Jacobians of :mod:`symkin.dynamics.bodies`,

* kinetic energy    k = 1/2 qd^T M(q) qd,
  M = sum_b m_b Jv_b^T Jv_b + Jw_b^T I_b Jw_b   (inertia and angular columns in link axes);
* potential energy  u = -sum_b m_b g . c_b      (g the gravity vector in the base frame);
* gravity vector    G = du/dq, G_j = -sum_b m_b g . Jv_b,j   (dc_b/dq_j = Jv_b,j), summed
  through the first moment of the bodies each joint moves;
* Coriolis matrix   C_ij = sum_k c_ijk qd_k with the Christoffel symbols of the first kind
  c_ijk = 1/2 (dM_ij/dq_k + dM_ik/dq_j - dM_jk/dq_i), so that V = C qd and dM/dt - 2C is
  skew-symmetric (Craig, *Introduction to Robotics*, sec. 6.8; Spong et al., *Robot
  Modeling and Control*, sec. 7.3);
* and eq. 8.33, d/dt dL/dqd - dL/dq = M qdd + V + G.

Nothing is differentiated with respect to time and nothing is simplified: M is summed from
the Jacobians, G is read off them, and only the partial derivatives dM/dq_k (of a shared
graph, in SymEngine) are taken.  All functions take and return SymEngine expressions.
"""

from __future__ import annotations

from collections.abc import Sequence

import symengine as se

from symkin.dynamics.bodies import ZERO3, BodyJacobians
from symkin.dynamics.program import cross, dot, mat_vec, se_vector
from symkin.kinematics.chain import JointAxis
from symkin.model import joint_kinds

Matrix = list[list[se.Basic]]


def mass_matrix(bodies: Sequence[BodyJacobians], n: int) -> Matrix:
    """M(q), n x n, symmetric (eq. 8.31)."""
    M: Matrix = [[se.Integer(0)] * n for _ in range(n)]
    for b in bodies:
        for r in range(b.joints):
            for s in range(r, b.joints):
                term = se.Integer(0)
                if b.mass != 0:
                    term += b.mass * dot(b.linear[r], b.linear[s])
                if b.inertia is not None:
                    term += dot(b.angular[r], mat_vec(b.inertia, b.angular[s]))
                M[r][s] += term
    for r in range(n):
        for s in range(r):
            M[r][s] = M[s][r]
    return M


def potential_energy(bodies: Sequence[BodyJacobians], gravity: Sequence[se.Basic]) -> se.Basic:
    """u(q) = -sum_b m_b g . c_b (zero at the base origin)."""
    return -sum((b.mass * dot(gravity, b.com) for b in bodies if b.mass != 0), se.Integer(0))


def gravity_vector(bodies: Sequence[BodyJacobians], axes: Sequence[JointAxis], gravity: Sequence[se.Basic]
                   ) -> list[se.Basic]:
    """G(q) = du/dq, G_j = -sum_b m_b g . Jv_b,j, summed per joint through the bodies' first moment.

    For a revolute joint j with axis z_j through a_j, sum_b m_b Jv_b,j = z_j x (S_j - m_j a_j)
    with S_j = sum_b m_b c_b and m_j = sum_b m_b over the bodies that j moves; for a
    prismatic joint it is m_j z_j.  One cross product per joint instead of one per body.
    """
    G = []
    for j, axis in enumerate(axes):
        moved = [b for b in bodies if b.joints > j and b.mass != 0]
        mass = sum((b.mass for b in moved), se.Integer(0))
        # sum_b m_b (v + w x (c_b - a)) = m v + w x (S - m a) for the joint's twist (w, v) per unit rate
        w, v = joint_kinds.motion_subspace(axis.type, se_vector(axis.direction), ZERO3)
        moment = [sum((b.mass * b.com[r] for b in moved), se.Integer(0)) for r in range(3)]
        point = se_vector(axis.point)
        column = [mass * a + b for a, b in zip(v, cross(w, [moment[r] - mass * point[r] for r in range(3)]))]
        G.append(-dot(gravity, column))
    return G


def mass_matrix_partials(M: Matrix, q: Sequence[se.Symbol]) -> list[Matrix]:
    """dM/dq_k for every k, as ``partials[k][i][j]`` (symmetric in i, j)."""
    n = len(q)
    partials = []
    for qk in q:
        dM: Matrix = [[se.Integer(0)] * n for _ in range(n)]
        for i in range(n):
            for j in range(i, n):
                dM[i][j] = dM[j][i] = se.diff(M[i][j], qk)
        partials.append(dM)
    return partials


def christoffel(partials: Sequence[Matrix], i: int, j: int, k: int) -> se.Basic:
    """c_ijk = 1/2 (dM_ij/dq_k + dM_ik/dq_j - dM_jk/dq_i)."""
    return (partials[k][i][j] + partials[j][i][k] - partials[i][j][k]) / 2


def coriolis_matrix(partials: Sequence[Matrix], qd: Sequence[se.Symbol]) -> Matrix:
    """C(q, qd) with C_ij = sum_k c_ijk qd_k."""
    n = len(qd)
    return [[sum((christoffel(partials, i, j, k) * qd[k] for k in range(n)), se.Integer(0)) for j in range(n)]
            for i in range(n)]


def coriolis_vector(partials: Sequence[Matrix], qd: Sequence[se.Symbol]) -> list[se.Basic]:
    """V(q, qd) = C qd = dM/dt qd - 1/2 d(qd^T M qd)/dq, with dM/dt = sum_k dM/dq_k qd_k."""
    n = len(qd)
    Mdot = [[sum((partials[k][i][j] * qd[k] for k in range(n)), se.Integer(0)) for j in range(n)] for i in range(n)]
    return [dot(Mdot[i], qd) - dot(qd, mat_vec(partials[i], qd)) / 2 for i in range(n)]


def kinetic_energy(M: Matrix, qd: Sequence[se.Symbol]) -> se.Basic:
    """k = 1/2 qd^T M qd."""
    return dot(qd, mat_vec(M, qd)) / 2
