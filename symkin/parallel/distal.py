"""Leg links whose motion follows from their two ends, in the equations of motion (Kane's method).

Two kinds: a spherical leg's distal link, which turns about the centre of rotation carrying two axes, and a
rod of fixed length swinging between its ends C_i(q_i) and B_i(p) with an inertia of its own across it.

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

A rod (:class:`~symkin.parallel.inertia.SwingingRod`) of fixed length L, d = B_i - C_i, adds the kinetic energy
1/2 dI |w|^2 of its angular velocity across it, w = d x dd/dt / L^2 (base frame), to its lumped ends; its
angular momentum dI w changes at N = dI dw/dt = dI d x d''/dt^2 / L^2 (dd/dt x dd/dt = 0), so its share of
the efforts is Q_k = w^(k) . N and of the mass matrix M_kl = dI w^(k) . w^(l), with the same partial rates;
d'' = B_p pdd + pd^T B_pp pd - C' qdd_i - C'' qd_i^2.

Reference: T. R. Kane, D. A. Levinson, Dynamics: Theory and Applications, McGraw-Hill 1985, ch. 6 (generalized
inertia forces); the rotation from two body-fixed axes: W L^-1 maps the link-frame axes (w, v, w x v) to
(C, B, C x B).
"""

from __future__ import annotations

import symengine as se
import sympy

from symkin.dynamics.program import Program, cross, dot, mat_vec, se_matrix, se_vector
from symkin.parallel.inertia import DistalLink, SwingingRod

Vector = list[se.Basic]


class _Ends:
    """A link's two end vectors, C(q_i) (moved by the leg's actuator) and B(p) (by the platform), and their
    derivatives bound into a program."""

    def __init__(self, program: Program, q: sympy.Symbol, C: sympy.Matrix, B: sympy.Matrix, p: list[sympy.Symbol]):
        self.program = program
        C_q = sympy.diff(C, q)
        B_p = [sympy.diff(B, s) for s in p]
        values = program.bind(se_vector(list(C) + list(B) + list(C_q) + list(sympy.diff(C_q, q))
                                        + [e for column in B_p for e in column]))
        self.a, self.b, self.C_q, self.C_qq = values[0:3], values[3:6], values[6:9], values[9:12]
        self.B_p = [values[12 + 3 * k:15 + 3 * k] for k in range(len(p))]
        self._B_pp = [[se_vector(sympy.diff(column, s)) for s in p] for column in B_p]

    def _b_rate(self, pd: Vector) -> Vector:
        return [sum((column[i] * r for column, r in zip(self.B_p, pd)), se.Integer(0)) for i in range(3)]

    def _b_acceleration(self, pd: Vector, pdd: Vector) -> Vector:
        """d^2 B/dt^2 = B_p pdd + pd^T B_pp pd."""
        curvature = [sum((self._B_pp[k][m][i] * pd[k] * pd[m] for k in range(len(pd)) for m in range(len(pd))),
                         se.Integer(0)) for i in range(3)]
        return [r + q for r, q in zip(self._b_rate(pdd), curvature)]

    def _a_acceleration(self, qd: se.Basic, qdd: se.Basic) -> Vector:
        """d^2 C/dt^2 = C'' qd^2 + C' qdd."""
        return [c * qd * qd + c_q * qdd for c, c_q in zip(self.C_qq, self.C_q)]


class _Link(_Ends):
    """One spherical leg's distal link, its axes a = C(q_i) and b = B(p) bound into a program."""

    def __init__(self, program: Program, link: DistalLink, p: list[sympy.Symbol]):
        super().__init__(program, link.q, sympy.Matrix(link.C), sympy.Matrix(link.B), p)
        self.n = [program.let(v) for v in cross(self.a, self.b)]
        self.c = se.sympify(link.cosine)
        self.s2 = se.sympify(sympy.simplify(1 - link.cosine**2))
        self.L_inverse = se_matrix(link.frame_inverse)
        self.inertia = se_matrix(link.inertia)

    def _body(self, projections: Vector) -> Vector:
        """L^-T (v . a, v . b, v . n): a vector's components in the link frame from its projections, bound."""
        L = self.L_inverse
        return [self.program.let(sum((L[k][i] * projections[k] for k in range(3)), se.Integer(0))) for i in range(3)]

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
        dda = self._a_acceleration(qd, qdd)
        ddb = self._b_acceleration(pd, pdd)
        body = self._body([w_a, w_b, w_n])
        dda_n = self.program.let(dot(dda, self.n) - w_a * w_n)
        alpha_a = self.program.let((dot(ddb, self.n) - w_b * w_n - self.c * dda_n) / self.s2)
        alpha_n = dot(dda, self.b) - w_a * w_b + self.c * dot(body, body)
        return body, self._body([alpha_a, self.c * alpha_a - dda_n, alpha_n])

    def moment(self, w: Vector, a: Vector) -> Vector:
        """N = I_o a_b + w_b x I_o w_b, bound."""
        return [self.program.let(v) for v in
                [x + y for x, y in zip(mat_vec(self.inertia, a), cross(w, mat_vec(self.inertia, w)))]]

    def inertia_times(self, w: Vector) -> Vector:
        """I_o w_b."""
        return mat_vec(self.inertia, w)

    def effort_moment(self, qd: se.Basic, qdd: se.Basic, pd: Vector, pdd: Vector) -> Vector:
        """N of the motion, in the frame of :meth:`body_rate` (the link frame)."""
        return self.moment(*self.body_motion(qd, qdd, pd, pdd))


class _Rod(_Ends):
    """One rod's inertia across it beyond its lumped ends (see the module docstring): a = C(q_i), b = B(p)."""

    def __init__(self, program: Program, rod: SwingingRod, p: list[sympy.Symbol]):
        super().__init__(program, rod.q, sympy.Matrix(rod.C), sympy.Matrix(rod.B), p)
        self.d = [program.let(b - a) for a, b in zip(self.a, self.b)]
        self.inertia = se.sympify(rod.inertia)
        self.length_squared = se.sympify(rod.length_squared)

    def _across(self, rate: Vector) -> Vector:
        """d x rate / L^2, bound."""
        return [self.program.let(v / self.length_squared) for v in cross(self.d, rate)]

    def body_rate(self, qd: se.Basic, pd: Vector) -> Vector:
        """w = d x dd/dt / L^2 (base frame) for the leg's actuated rate qd and the platform rates pd."""
        return self._across([b - c * qd for b, c in zip(self._b_rate(pd), self.C_q)])

    def inertia_times(self, w: Vector) -> Vector:
        """dI w."""
        return [self.inertia * v for v in w]

    def effort_moment(self, qd: se.Basic, qdd: se.Basic, pd: Vector, pdd: Vector) -> Vector:
        """N = dI d x d''/dt^2 / L^2, bound."""
        acceleration = [b - a for a, b in zip(self._a_acceleration(qd, qdd), self._b_acceleration(pd, pdd))]
        return [self.program.let(self.inertia * v) for v in self._across(acceleration)]


class DistalLinks:
    """The links of a mechanism's legs that move with their ends (spherical legs' distal links, rods with an
    inertia of their own) in one program: their share of M, of the efforts and of k.

    A generalized coordinate is given by its rates: ``columns`` lists, per coordinate, (qd, pd) with qd the
    legs' actuated rates (n) and pd the platform's (n)."""

    def __init__(self, program: Program, links: tuple[DistalLink, ...], rods: tuple[SwingingRod, ...],
                 q: list[se.Basic], p: list[sympy.Symbol]):
        self.program = program
        self.links: list[_Link | _Rod] = [_Link(program, link, p) for link in links]
        self.links += [_Rod(program, rod, p) for rod in rods]
        self.leg_of = [q.index(se.sympify(link.q)) for link in links] + [q.index(se.sympify(rod.q)) for rod in rods]

    def partial_rates(self, columns: list[tuple[Vector, Vector]]) -> list[list[Vector]]:
        """w_b^(k) per link, per coordinate."""
        return [[link.body_rate(qd[i], pd) for qd, pd in columns] for link, i in zip(self.links, self.leg_of)]

    def mass_matrix(self, columns: list[tuple[Vector, Vector]]) -> list[list[se.Basic]]:
        """sum over the links of w_b^(k) . I_o w_b^(l)."""
        size = len(columns)
        M = [[se.Integer(0)] * size for _ in range(size)]
        for link, partials in zip(self.links, self.partial_rates(columns)):
            moments = [[self.program.let(v) for v in link.inertia_times(w)] for w in partials]
            for k in range(size):
                for m in range(k, size):
                    M[k][m] = M[m][k] = M[k][m] + dot(partials[k], moments[m])
        return M

    def efforts(self, columns: list[tuple[Vector, Vector]], qd: Vector, pd: Vector, qdd: Vector, pdd: Vector
                ) -> Vector:
        """Q_k = sum over the links of w_b^(k) . N for the motion (qd, pd, qdd, pdd)."""
        Q = [se.Integer(0)] * len(columns)
        for link, i, partials in zip(self.links, self.leg_of, self.partial_rates(columns)):
            N = link.effort_moment(qd[i], qdd[i], pd, pdd)
            Q = [total + dot(w, N) for total, w in zip(Q, partials)]
        return Q

    def kinetic_energy(self, qd: Vector, pd: Vector) -> se.Basic:
        """sum over the links of 1/2 w_b . I_o w_b (a rod's 1/2 dI |w|^2)."""
        total = se.Integer(0)
        for link, i in zip(self.links, self.leg_of):
            w = link.body_rate(qd[i], pd)
            total += dot(w, link.inertia_times(w)) / 2
        return total
