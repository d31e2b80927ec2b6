"""Operation counts of the recursive algorithms Pinocchio runs, for the chains of ``chain_models.py``.

Issue 12 asks that the generated dynamics stay within 1.5x of the algorithmic flop counts
of the recursive algorithms (RNEA ~ O(n), CRBA ~ O(n^2)).  Pinocchio's compiled C++ does not
report operations, so this module writes the two algorithms once, in the body-fixed link
frames Pinocchio uses, on CasADi SX symbols, and counts the arithmetic instructions of the
resulting CasADi function (common subexpressions merged, constants folded, exact zeros and
ones of the +-90 deg twists exploited as a hand-written implementation would):

* **RNEA** (Luh, Walker and Paul 1980; Featherstone, *Rigid Body Dynamics Algorithms*,
  2008, Table 5.1, in 3-D vector form): outward pass of angular velocity w, angular
  acceleration dw and origin acceleration a (gravity as an upward base acceleration),
  F = m a_c, N = I_c dw + w x I_c w; inward pass f_i = R f_{i+1} + F_i,
  n_i = R n_{i+1} + N_i + r_i x f_i + c_i x F_i (moments about the joint axis point),
  tau_i = z_i . n_i.  With qdd = 0 it computes V + G, the quantity symkin's
  coriolis_vector + gravity_vector emit.
* **CRBA** (Featherstone 2008, Table 6.2, in 3-D vector form): composite mass, first moment
  and inertia about each link origin, accumulated tip to base; the column of joint i is the
  momentum rate of composite i under a unit acceleration of joint i, carried to every
  joint j < i by rotation and a moment shift: M_ji = z_j . n_j.

Both are checked against the tests' independent numeric Newton-Euler (tests/derivation/test_recursive_reference.py),
so the counts belong to algorithms that compute the right thing.

Frame conventions (classic DH, ^{i-1}T_i = Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)), in frame i:
the joint axis z_i = R_i^T e_z = (0, sin alpha_i, cos alpha_i) and the offset of o_i from
o_{i-1}, r_i = R_i^T p_i = (a_i, sin alpha_i d_i, cos alpha_i d_i), are constants.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import casadi as ca

from chain_models import ChainLink

#: CasADi operations that are not arithmetic: reading inputs, writing outputs, literals.
NON_ARITHMETIC = frozenset({ca.OP_INPUT, ca.OP_OUTPUT, ca.OP_CONST, ca.OP_PARAMETER, ca.OP_ASSIGN})


def _exact_cos_sin(angle: float) -> tuple[float, float]:
    """cos and sin with the exact 0 and +-1 of multiples of pi/2 (as symkin's deg(90) has)."""
    quarter = angle / (math.pi / 2)
    if abs(quarter - round(quarter)) < 1e-12:
        return ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0))[round(quarter) % 4]
    return math.cos(angle), math.sin(angle)


def _rotation(q: ca.SX, alpha: float) -> ca.SX:
    """^{i-1}R_i = Rz(q) Rx(alpha)."""
    c, s = ca.cos(q), ca.sin(q)
    cos_a, sin_a = _exact_cos_sin(alpha)
    return ca.vertcat(ca.horzcat(c, -s * cos_a, s * sin_a),
                      ca.horzcat(s, c * cos_a, -c * sin_a),
                      ca.horzcat(0, sin_a, cos_a))


def _link_constants(link: ChainLink) -> tuple[ca.DM, ca.DM]:
    """The joint axis z_i and the offset r_i = o_i - o_{i-1}, both in frame i."""
    cos_a, sin_a = _exact_cos_sin(link.alpha)
    return ca.DM([0.0, sin_a, cos_a]), ca.DM([link.a, sin_a * link.d, cos_a * link.d])


def _inertia_about_com(link: ChainLink) -> ca.DM:
    xx, yy, zz, xy, xz, yz = link.inertia
    return ca.DM([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def rnea_function(links: Sequence[ChainLink], gravity: Sequence[float], with_acceleration: bool) -> ca.Function:
    """tau(q, qd[, qdd]) by the recursive Newton-Euler algorithm; without qdd it is V + G."""
    n = len(links)
    q, qd = ca.SX.sym("q", n), ca.SX.sym("qd", n)
    qdd = ca.SX.sym("qdd", n) if with_acceleration else ca.SX.zeros(n)
    rotations = [_rotation(q[i], link.alpha) for i, link in enumerate(links)]
    w, dw, a = ca.SX.zeros(3), ca.SX.zeros(3), -ca.DM(gravity)
    forces, moments = [], []
    for i, link in enumerate(links):
        z, r = _link_constants(link)
        c = ca.DM(link.com)
        Rt = rotations[i].T
        w_parent = Rt @ w
        w = w_parent + z * qd[i]
        dw = Rt @ dw + z * qdd[i] + ca.cross(w_parent, z * qd[i])
        a = Rt @ a + ca.cross(dw, r) + ca.cross(w, ca.cross(w, r))
        a_com = a + ca.cross(dw, c) + ca.cross(w, ca.cross(w, c))
        inertia = _inertia_about_com(link)
        forces.append(link.mass * a_com)
        moments.append(inertia @ dw + ca.cross(w, inertia @ w))
    tau = [None] * n
    f_child, n_child = ca.SX.zeros(3), ca.SX.zeros(3)
    for i in reversed(range(n)):
        z, r = _link_constants(links[i])
        if i + 1 < n:
            f_child, n_child = rotations[i + 1] @ f_child, rotations[i + 1] @ n_child
        f = f_child + forces[i]
        moment = n_child + moments[i] + ca.cross(r, f) + ca.cross(ca.DM(links[i].com), forces[i])
        tau[i] = ca.dot(z, moment)
        f_child, n_child = f, moment
    inputs = [q, qd] + ([qdd] if with_acceleration else [])
    return ca.Function("rnea", inputs, [ca.vertcat(*tau)], {"cse": True})


def _shifted_inertia(inertia: ca.SX, first_moment: ca.SX, mass: float, p: ca.SX) -> ca.SX:
    """Inertia about A from the inertia about B, where B = A + p (parallel-axis theorem, first moment h about B):
    I_A = I_B + (2 h.p + m p.p) 1 - (p h^T + h p^T) - m p p^T."""
    scalar = 2 * ca.dot(first_moment, p) + mass * ca.dot(p, p)
    return (inertia + scalar * ca.SX.eye(3) - (p @ first_moment.T + first_moment @ p.T) - mass * (p @ p.T))


def crba_function(links: Sequence[ChainLink]) -> ca.Function:
    """M(q) by the composite-rigid-body algorithm."""
    n = len(links)
    q = ca.SX.sym("q", n)
    rotations = [_rotation(q[i], link.alpha) for i, link in enumerate(links)]
    M = ca.SX.zeros(n, n)
    mass, first_moment, inertia = 0.0, ca.SX.zeros(3), ca.SX.zeros(3, 3)  # composite i+1..n about o_{i+1}
    for i in reversed(range(n)):
        link = links[i]
        c = ca.DM(link.com)
        own_inertia = _inertia_about_com(link) + link.mass * (ca.dot(c, c) * ca.DM.eye(3) - c @ c.T)
        if i + 1 < n:
            R = rotations[i + 1]
            next_link = links[i + 1]
            _, r_next = _link_constants(next_link)
            p = R @ r_next  # o_{i+1} - o_i in frame i
            moved_moment = R @ first_moment
            inertia = _shifted_inertia(R @ inertia @ R.T, moved_moment, mass, p)
            first_moment = moved_moment + mass * p
        mass = mass + link.mass
        first_moment = first_moment + link.mass * c
        inertia = inertia + own_inertia
        z, r = _link_constants(link)
        v = ca.cross(z, r)  # velocity of o_i for a unit rate of joint i
        f = mass * v + ca.cross(z, first_moment)
        moment = inertia @ z + ca.cross(first_moment, v) + ca.cross(r, f)  # about o_{i-1}
        M[i, i] = ca.dot(z, moment)
        for j in reversed(range(i)):
            R = rotations[j + 1]
            f, moment = R @ f, R @ moment
            z_j, r_j = _link_constants(links[j])
            moment = moment + ca.cross(r_j, f)
            M[j, i] = M[i, j] = ca.dot(z_j, moment)
    return ca.Function("crba", [q], [M], {"cse": True})


def arithmetic_operations(function: ca.Function) -> int:
    """Instructions of a CasADi SX function that compute (sin, cos and sqrt count one, as in symkin's counts)."""
    return sum(1 for k in range(function.n_instructions()) if function.instruction_id(k) not in NON_ARITHMETIC)
