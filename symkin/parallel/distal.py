"""The distal links of spherical legs in the equations of motion (Kane's method about the centre of rotation).

A spherical leg's distal link turns about the fixed centre with R_d = W L^-1, W = [a, b, n] for its two unit
axes a = C(q_i) (the middle axis), b = B(p) (the platform's) and n = a x b, which keep the angle of cosine
c = a . b (:class:`~symkin.parallel.inertia.DistalLink`).  Its body angular velocity is w_b = R_d^T w =
L^-T W^T w, and the three projections W^T w follow from da = w x a and db = w x b (s^2 = 1 - c^2):

    w . n = da . b,      w . a = (db . n - c da . n) / s^2,      w . b = c (w . a) - da . n.

The body angular acceleration a_b = L^-T W^T alpha is the same with dda - w x (w x a) for da (and so for b):

    alpha . n = dda . b - (w.a)(w.b) + c |w|^2,
    alpha . a = (ddb . n - (w.b)(w.n) - c (dda . n - (w.a)(w.n))) / s^2,
    alpha . b = c (alpha . a) - (dda . n - (w.a)(w.n)),

with da = C' qd_i, dda = C'' qd_i^2 + C' qdd_i, db = B_p pd and ddb = B_p pdd + pd^T B_pp pd: a few dozen
operations per link, no passive variable and no inverse trigonometry.

A body turning about a fixed point has k = 1/2 w_b^T I_o w_b (I_o: inertia about the point, link frame) and
Euler's equations about it, N = I_o a_b + w_b x I_o w_b.  With the partial angular velocities w_b^(k) (w_b
for the rates of the k-th generalized coordinate: qd = e_k, pd = J e_k for the legs' coordinates; qd = J^-1 e_k,
pd = e_k for the task coordinates) Kane's equations give the link's share of the efforts Q_k = w_b^(k) . N
and of the mass matrix M_kl = w_b^(k) . I_o w_b^(l).  Gravity enters through the potential u_d
(:mod:`symkin.parallel.inertia`).

Reference: T. R. Kane, D. A. Levinson, Dynamics: Theory and Applications, McGraw-Hill 1985, ch. 6 (generalized
inertia forces); the rotation from two body-fixed axes: W L^-1 maps the link-frame axes (w, v, w x v) to
(C, B, C x B).
"""

from __future__ import annotations

import symengine as se
import sympy

from symkin.dynamics.program import Program, cross, dot, mat_vec, se_matrix, se_vector
from symkin.parallel.inertia import DistalLink

Vector = list[se.Basic]


class _Link:
    """One distal link's vectors bound into a program."""

    def __init__(self, program: Program, link: DistalLink, p: list[sympy.Symbol]):
        self.program = program
        C, B = sympy.Matrix(link.C), sympy.Matrix(link.B)
        C_q = sympy.diff(C, link.q)
        B_p = [sympy.diff(B, s) for s in p]
        values = program.bind(se_vector(list(C) + list(B) + list(C_q) + list(sympy.diff(C_q, link.q))
                                        + [e for column in B_p for e in column]))
        self.a, self.b, self.C_q, self.C_qq = values[0:3], values[3:6], values[6:9], values[9:12]
        self.n = [program.let(v) for v in cross(self.a, self.b)]
        self.B_p = [values[12 + 3 * k:15 + 3 * k] for k in range(len(p))]
        self._B_pp = [[se_vector(sympy.diff(column, s)) for s in p] for column in B_p]
        self.c = se.sympify(link.cosine)
        self.s2 = se.sympify(sympy.simplify(1 - link.cosine**2))
        self.L_inverse = se_matrix(link.frame_inverse)
        self.inertia = se_matrix(link.inertia)

    def _body(self, projections: Vector) -> Vector:
        """L^-T (v . a, v . b, v . n): a vector's components in the link frame from its projections, bound."""
        L = self.L_inverse
        return [self.program.let(sum((L[k][i] * projections[k] for k in range(3)), se.Integer(0))) for i in range(3)]

    def _b_rate(self, pd: Vector) -> Vector:
        return [sum((column[i] * r for column, r in zip(self.B_p, pd)), se.Integer(0)) for i in range(3)]

    def _projections(self, qd: se.Basic, pd: Vector) -> Vector:
        """(w . a, w . b, w . n), bound."""
        da, db = [c * qd for c in self.C_q], self._b_rate(pd)
        da_n = self.program.let(dot(da, self.n))
        w_a = self.program.let((dot(db, self.n) - self.c * da_n) / self.s2)
        return [w_a, self.program.let(self.c * w_a - da_n), self.program.let(dot(da, self.b))]

    def body_rate(self, qd: se.Basic, pd: Vector) -> Vector:
        """w_b for the leg's actuated rate qd and the platform rates pd."""
        return self._body(self._projections(qd, pd))

    def body_motion(self, qd: se.Basic, qdd: se.Basic, pd: Vector, pdd: Vector) -> tuple[Vector, Vector]:
        """(w_b, a_b) for the rates (qd, pd) and accelerations (qdd, pdd)."""
        w_a, w_b, w_n = self._projections(qd, pd)
        dda = [c * qd * qd + c_q * qdd for c, c_q in zip(self.C_qq, self.C_q)]
        curvature = [sum((self._B_pp[k][m][i] * pd[k] * pd[m] for k in range(len(pd)) for m in range(len(pd))),
                         se.Integer(0)) for i in range(3)]
        ddb = [r + q for r, q in zip(self._b_rate(pdd), curvature)]
        body = self._body([w_a, w_b, w_n])
        dda_n = self.program.let(dot(dda, self.n) - w_a * w_n)
        alpha_a = self.program.let((dot(ddb, self.n) - w_b * w_n - self.c * dda_n) / self.s2)
        alpha_n = dot(dda, self.b) - w_a * w_b + self.c * dot(body, body)
        return body, self._body([alpha_a, self.c * alpha_a - dda_n, alpha_n])

    def moment(self, w: Vector, a: Vector) -> Vector:
        """N = I_o a_b + w_b x I_o w_b, bound."""
        return [self.program.let(v) for v in
                [x + y for x, y in zip(mat_vec(self.inertia, a), cross(w, mat_vec(self.inertia, w)))]]


class DistalLinks:
    """The distal links of a spherical mechanism in one program: their share of M, of the efforts and of k.

    A generalized coordinate is given by its rates: ``columns`` lists, per coordinate, (qd, pd) with qd the
    legs' actuated rates (n) and pd the platform's (n)."""

    def __init__(self, program: Program, links: tuple[DistalLink, ...], q: list[se.Basic], p: list[sympy.Symbol]):
        self.program = program
        self.links = [_Link(program, link, p) for link in links]
        self.leg_of = [q.index(se.sympify(link.q)) for link in links]

    def partial_rates(self, columns: list[tuple[Vector, Vector]]) -> list[list[Vector]]:
        """w_b^(k) per link, per coordinate."""
        return [[link.body_rate(qd[i], pd) for qd, pd in columns] for link, i in zip(self.links, self.leg_of)]

    def mass_matrix(self, columns: list[tuple[Vector, Vector]]) -> list[list[se.Basic]]:
        """sum over the links of w_b^(k) . I_o w_b^(l)."""
        size = len(columns)
        M = [[se.Integer(0)] * size for _ in range(size)]
        for link, partials in zip(self.links, self.partial_rates(columns)):
            moments = [[self.program.let(v) for v in mat_vec(link.inertia, w)] for w in partials]
            for k in range(size):
                for m in range(k, size):
                    M[k][m] = M[m][k] = M[k][m] + dot(partials[k], moments[m])
        return M

    def efforts(self, columns: list[tuple[Vector, Vector]], qd: Vector, pd: Vector, qdd: Vector, pdd: Vector
                ) -> Vector:
        """Q_k = sum over the links of w_b^(k) . N for the motion (qd, pd, qdd, pdd)."""
        Q = [se.Integer(0)] * len(columns)
        for link, i, partials in zip(self.links, self.leg_of, self.partial_rates(columns)):
            N = link.moment(*link.body_motion(qd[i], qdd[i], pd, pdd))
            Q = [total + dot(w, N) for total, w in zip(Q, partials)]
        return Q

    def kinetic_energy(self, qd: Vector, pd: Vector) -> se.Basic:
        """sum over the links of 1/2 w_b . I_o w_b."""
        total = se.Integer(0)
        for link, i in zip(self.links, self.leg_of):
            w = link.body_rate(qd[i], pd)
            total += dot(w, mat_vec(link.inertia, w)) / 2
        return total
