"""Dynamics of parallel mechanisms in the actuated coordinates (Lagrange, loop closure eliminated through J).

=====================  ====================================================================
``mass_matrix``        M(q) = M_a + J^T M_p J
``coriolis_vector``    V = V_a + J^T (M_p b + V_p), b = dJ/dt qd
``gravity_vector``     G = du_a/dq + J^T du_p/dp: the actuator efforts that hold the device still
``friction``           F_f(qd) at the actuators: viscous + Coulomb (sign or tanh)
``inverse_dynamics``   tau = M qdd + V + G + F_f
``forward_dynamics``   qdd = M^-1 (tau - V - G - F_f), by an LDL^T solve
``operational_space``  Mx, Vx, Gx in the task coordinates: F = Mx pdd + Vx + Gx (a hybrid device: at its TCP)
``kinetic_energy``     k = 1/2 qd^T M_a qd + 1/2 pd^T M_p pd
``potential_energy``   u = u_a(q) + u_p(p)
=====================  ====================================================================

Method.  The masses are split into an actuator side (moved by one q_i) and a platform side
(moved by p) (:mod:`symkin.parallel.inertia`), so the Lagrangian of the closed chain is
L = 1/2 qd^T M_a qd + 1/2 pd^T M_p pd - u_a(q) - u_p(p) on the constraint manifold f(q, p) = 0,
whose velocities are pd = J qd (J = J_x^-1 J_q, :mod:`symkin.parallel.quantities`).  The
platform side gives the task-space force F_p = M_p pdd + V_p + G_p (its own Lagrange equations
in p, V_p from the Christoffel symbols of M_p), and by d'Alembert's principle (the constraint
forces do no work on motions pd = J qd) the actuator efforts are

    tau = M_a qdd + V_a + G_a + J^T F_p,   pdd = J qdd + b,   b = -J_x^-1 (zd^T H_i zd)_i,

with H_i the Hessian of f_i in z = (q, p) (differentiate f(q, p) = 0 twice along the motion).
This is the elimination of the loop-closure multipliers through the closed-form Jacobians the
project already has; it keeps the n actuated coordinates, needs no passive variables and no
numerical solve of the closure, and is exact for the lumped rods (the common simplification of
DELTA dynamics: Codourey, Int. J. Robotics Research 17(12), 1998; Pierrot et al. 1991).  A
multiplier formulation over all joint variables would need the passive variables as inputs and
a solve of the closure at every call.

Accuracy.  J_x^-1 enters M (through J^T M_p J) twice and the Coriolis and inverse-dynamics efforts
up to four times (J^T M_p J_x^-1 h(J qd, J qd)), so a relative error d of J^-1 (kappa(J^-1) eps
at best) becomes up to 2 d and 4 d: their ``kappa_degree`` (:class:`~symkin.ir.quantity.QuantityDef`).

Hybrid devices (:mod:`symkin.parallel.hybrid`).  A wrist on the platform moves with the platform
and its own coordinates qw, so its bodies join the platform side in the combined coordinates
c = (p, qw): M_c = M_p(p) + M_w(p, qw), V_c and G_c from M_c and u_p + u_w as above, and the device's
coordinates are (q, qw) with cd = B (qd, qwd), B = diag(J, 1): M = diag(M_a, 0) + B^T M_c B and
tau = (tau_a + J^T F_c,p, F_c,w) with cdd = (J qdd + b, qwdd).  The functions then take qw (and qwd,
qwdd, tauw) after each of their inputs and return the device's n + n_w efforts.

Every function takes the actuated variables q and the platform pose p = fk(q) (or q = ik(p))
as a consistent pair, like the velocity functions.  J_x^-1 is formed once per function by the
adjugate (3 legs) or a Gram-Schmidt QR (6 legs) (:mod:`symkin.dynamics.linsolve`).

Length: every function is built from one set of terms (:class:`ReducedDynamics`: J, b, M_a, M_c, V, G bound
once per program); split, the terms and the functions that combine them would import each other.
"""

from __future__ import annotations

from functools import cached_property
import symengine as se
import sympy

from symkin.dynamics import lagrange
from symkin.dynamics.linsolve import ldl_solve, transpose_solve
from symkin.dynamics.program import Program, dot, mat_vec, se_matrix, se_vector
from symkin.dynamics.joint_forces import joint_friction
from symkin.dynamics.quantities import (EFFORT_UNIT, coordinate_symbols, function_spec, require_gravity,
                                       task_space_dynamics)
from symkin.errors import DerivationError
from symkin.ir.quantity import Deriving, quantity
from symkin.ir.spec import FunctionSpec
from symkin.model import coordinates
from symkin.model.schema import Model
from symkin.parallel import hybrid
from symkin.parallel.distal import DistalLinks
from symkin.parallel.inertia import Inertia, split_inertia
from symkin.parallel.inputs import task_input, task_symbols
from symkin.parallel.quantities import (
    PARALLEL,
    constraint_vector,
    reduced_legs,
    parallel_structure,
    square_constraint_jacobians,
)


Matrix = list[list[se.Basic]]

TASK_FORCE_UNIT = "N (position rows), N*m (angle rows)"
WRENCH_UNIT = "N (force rows), N*m (moment rows)"


@quantity("parallel_inertia", "mass distribution split into actuator side and platform side", emitted=False,
          mechanism=PARALLEL)
def _inertia(d: Deriving) -> Inertia:
    structure = d[parallel_structure]
    return split_inertia(d.model, d[reduced_legs], structure.chains, structure.platform)


@quantity("constraint_hessians", "second derivatives of the leg equations in (q, p)", emitted=False,
          mechanism=PARALLEL)
def _constraint_hessians(d: Deriving) -> tuple[tuple[tuple[int, int, sympy.Expr], ...], ...]:
    """Per leg equation f_i, the nonzero (a, b, c) with a <= b such that zd^T H_i zd = sum c zd_a zd_b."""
    z = coordinates.symbols(d.model, "q") + task_symbols(d.model)
    out = []
    for f in d[constraint_vector]:
        present = [k for k, s in enumerate(z) if s in f.free_symbols]
        terms = []
        for i, a in enumerate(present):
            first = sympy.diff(f, z[a])
            for b in present[i:]:
                second = sympy.expand(sympy.diff(first, z[b]))
                if second != 0:
                    terms.append((a, b, second if a == b else 2 * second))
        out.append(tuple(terms))
    return tuple(out)


class ReducedDynamics:
    """The pieces of the equations of motion bound into one program, each formed once when first used."""

    def __init__(self, d: Deriving, program: Program, parts: Inertia | None = None, wrist_bodies: bool = True):
        """``parts``: the mass distribution (the model's by default); ``wrist_bodies``: whether a hybrid device's
        wrist bodies are in it (the regressor's columns of the legs' and platform's parameters leave them out)."""
        self.d, self.program = d, program
        self.wrist_bodies = wrist_bodies
        self.n = d.model.dof
        self.parts: Inertia = d[_inertia] if parts is None else parts
        self.q = coordinate_symbols(d, "q")
        self.p = se_vector(task_symbols(d.model))
        # a hybrid device's wrist coordinates: the platform side moves in c = (p, qw)
        self.qw = se_vector(hybrid.wrist_symbols(d.model, "q"))
        self.c = self.p + self.qw

    def with_parts(self, parts: Inertia, wrist_bodies: bool = True) -> ReducedDynamics:
        """The terms of another mass distribution on the same mechanism and program, sharing the kinematic terms
        (J_x, J_q, J_x^-1, J) already bound; ``wrist_bodies`` as :class:`ReducedDynamics`'."""
        other = ReducedDynamics(self.d, self.program, parts, wrist_bodies)
        other.__dict__.update({k: v for k, v in self.__dict__.items() if k in ("jacobians", "J_x_inverse", "J")})
        return other

    def platform_motion(self, qd: list[se.Basic], qdd: list[se.Basic] | None) -> tuple[list[se.Basic], list[se.Basic]]:
        """(pd, pdd) = (J qd, J qdd + b), bound (qdd None: zero)."""
        pd = self.task_rates(qd)
        pdd = self.bias(qd, pd)
        if qdd is not None:
            pdd = [a + b for a, b in zip(mat_vec(self.J, qdd), pdd)]
        return pd, pdd

    @cached_property
    def jacobians(self) -> tuple[Matrix, list[se.Basic]]:
        """(J_x, diagonal of J_q), bound."""
        J_x, J_q = square_constraint_jacobians(self.d, "the dynamics")
        n = self.n
        values = self.program.bind([v for row in se_matrix(J_x) for v in row] + se_vector(J_q.diagonal()))
        return [values[i * n:(i + 1) * n] for i in range(n)], values[n * n:]

    @cached_property
    def J_x_inverse(self) -> Matrix:
        """J_x^-1 from one solve, J_x X = E (written as (J_x^T)^T X = E)."""
        J_x, _ = self.jacobians
        identity = [[se.Integer(int(i == j)) for j in range(self.n)] for i in range(self.n)]
        return transpose_solve(self.program, [list(col) for col in zip(*J_x)], identity)

    @cached_property
    def J(self) -> Matrix:
        """J = J_x^-1 J_q (J_q diagonal)."""
        _, J_q = self.jacobians
        return [[self.program.let(self.J_x_inverse[i][j] * J_q[j]) for j in range(self.n)] for i in range(self.n)]

    def J_transpose(self, v: list[se.Basic]) -> list[se.Basic]:
        """J^T v."""
        J = self.J
        return [sum((J[k][i] * v[k] for k in range(self.n)), se.Integer(0)) for i in range(self.n)]

    def B_transpose(self, F: list[se.Basic]) -> list[se.Basic]:
        """B^T F with B = diag(J, 1): the legs' efforts J^T F_p of a platform-side force F in c, then a wrist's
        rows of F as they are."""
        return self.J_transpose(F[:self.n]) + F[self.n:]

    def task_rates(self, qd: list[se.Basic]) -> list[se.Basic]:
        """pd = J qd, bound."""
        return [self.program.let(v) for v in mat_vec(self.J, qd)]

    def curvature(self, qd: list[se.Basic], pd: list[se.Basic]) -> list[se.Basic]:
        """h = (zd^T H_i zd)_i, bound: the second derivative of the leg equations along the motion at
        zero accelerations, so that J_x pdd - J_q qdd + h = 0."""
        zd = list(qd) + list(pd)
        return [self.program.let(sum((se.sympify(c) * zd[a] * zd[b] for a, b, c in terms), se.Integer(0)))
                for terms in self.d[_constraint_hessians]]

    def bias(self, qd: list[se.Basic], pd: list[se.Basic]) -> list[se.Basic]:
        """b = dJ/dt qd = -J_x^-1 h, so that pdd = J qdd + b."""
        h = self.curvature(qd, pd)
        return [self.program.let(-dot(row, h)) for row in self.J_x_inverse]

    def task_side(self, qd: list[se.Basic]) -> tuple[Matrix, list[se.Basic], list[se.Basic] | None, list[se.Basic]]:
        """(M_c, V_c, G_c, cd): the equations F_c = M_c cdd + V_c + G_c of the force conjugate to c = (p, qw) (p alone
        without a wrist: the platform's operational space), and the rates cd = (J qd, qwd).

        The legs' actuator side is carried into c by J^-1 = J_q^-1 J_x (J_q diagonal: no solve):
        M_c = M_p + diag(J^-T M_a J^-1, 0), V_c = V_p + (J^-T (V_a - M_a J^-1 b), 0) with J^-1 b = -J_q^-1 h,
        G_c = G_p + (J^-T G_a, 0) (None without gravity).
        """
        program, n, size = self.program, self.n, len(self.c)
        J_x, J_q = self.jacobians
        J_inverse = [[program.let(J_x[i][k] / J_q[i]) for k in range(n)] for i in range(n)]

        def carried(v: list[se.Basic]) -> list[se.Basic]:  # (J^-T v, 0): a leg-side effort as a force in c
            return [sum((J_inverse[i][k] * v[i] for i in range(n)), se.Integer(0)) for k in range(n)] + \
                [se.Integer(0)] * (size - n)

        pd = self.task_rates(qd)
        J_inverse_b = [program.let(-h / J_q[i]) for i, h in enumerate(self.curvature(qd, pd))]
        M: Matrix = [[se.Integer(0)] * size for _ in range(size)]
        M_p = self.M_p  # bound before M_a
        for k in range(size):
            for m in range(k, size):
                leg_side = sum((J_inverse[i][k] * self.M_a[i] * J_inverse[i][m] for i in range(n)), se.Integer(0)) \
                    if m < n else se.Integer(0)
                M[k][m] = M[m][k] = program.let(M_p[k][m] + leg_side)
        cd = pd + self.wrist("qd")
        # the actuator side seen in c, minus its share of the bias; then the platform side's own
        V = [a + c for a, c in zip(carried([v - m * x for v, m, x in zip(self.V_a(qd), self.M_a, J_inverse_b)]),
                                   self.V_p(cd))]
        if self.distal is not None:  # distal links, rods: the rates of p_m are (qd, pd) = (J^-1 e_m, e_m); qdd = -J^-1 b
            one = [[se.Integer(int(i == j)) for i in range(n)] for j in range(n)]
            columns = [([row[m] for row in J_inverse], one[m]) for m in range(n)]
            force = self.distal.efforts(columns, list(qd), pd, [-x for x in J_inverse_b], [se.Integer(0)] * n)
            V = [v + f for v, f in zip(V, force + [se.Integer(0)] * (size - n))]
            distal = self.distal.mass_matrix(columns)
            for k in range(n):
                for m in range(k, n):
                    M[k][m] = M[m][k] = program.let(M[k][m] + distal[k][m])
        if self.gravity_parts is None:
            return M, V, None, cd
        G_a, G_p = self.gravity_parts
        return M, V, [a + c for a, c in zip(carried(G_a), G_p)], cd

    @cached_property
    def distal(self) -> DistalLinks | None:
        """The spherical legs' distal links and the rods with an inertia of their own in this program
        (:mod:`symkin.parallel.distal`), None without them."""
        if not self.parts.distal_links and not self.parts.rods:
            return None
        return DistalLinks(self.program, self.parts.distal_links, self.parts.rods, self.q,
                           list(task_symbols(self.d.model)))

    def leg_columns(self) -> list[tuple[list[se.Basic], list[se.Basic]]]:
        """The rates (qd, pd) = (e_j, J e_j) of each actuated coordinate q_j."""
        one = [[se.Integer(int(i == j)) for i in range(self.n)] for j in range(self.n)]
        return [(one[j], [row[j] for row in self.J]) for j in range(self.n)]

    @cached_property
    def M_a(self) -> list[se.Basic]:
        return self.program.bind(se_vector(self.parts.actuator_diagonal))

    @cached_property
    def side_matrix(self) -> Matrix:
        """M_c, the platform side's mass matrix in c: M_p(p), plus a hybrid device's wrist M_w(p, qw)."""
        M = se_matrix(self.parts.platform_matrix)
        if not self.qw:
            return M
        m, size = len(self.p), len(self.c)
        wrist = self.d[hybrid.wrist_inertia].matrix if self.wrist_bodies else [[se.Integer(0)] * size] * size
        return [[(M[i][j] if i < m and j < m else se.Integer(0)) + wrist[i][j] for j in range(size)]
                for i in range(size)]

    @cached_property
    def M_p(self) -> Matrix:
        """M_c, bound."""
        n = len(self.c)
        values = self.program.bind([v for row in self.side_matrix for v in row])
        return [values[i * n:(i + 1) * n] for i in range(n)]

    def wrist(self, group: str) -> list[se.Basic]:
        """A hybrid device's wrist symbols of a coordinate group (qwd for "qd"), [] without a wrist."""
        return se_vector(hybrid.wrist_symbols(self.d.model, group))

    def V_a(self, qd: list[se.Basic]) -> list[se.Basic]:
        """1/2 dM_a,ii/dq_i qd_i^2 (M_a diagonal, M_a,ii a function of q_i only)."""
        return [se.diff(m, q) * v * v / 2 for m, q, v in zip(se_vector(self.parts.actuator_diagonal), self.q, qd)]

    def V_p(self, pd: list[se.Basic]) -> list[se.Basic]:
        """The platform side's Coriolis and centrifugal force in c (pd: its rates): Christoffel symbols of M_c."""
        M_p = self.side_matrix
        if all(se.diff(v, s) == 0 for row in M_p for v in row for s in self.c):
            return [se.Integer(0)] * len(self.c)
        return self.program.bind(lagrange.coriolis_vector(lagrange.mass_matrix_partials(M_p, self.c), pd))

    @cached_property
    def potential(self) -> tuple[se.Basic, se.Basic]:
        """(u_a(q), u_c(c)): the actuator side's and the platform side's (with a wrist's) potential energy."""
        u_c = se.sympify(self.parts.platform_potential)
        if self.qw and self.wrist_bodies:
            u_c += self.d[hybrid.wrist_inertia].potential
        return se.sympify(self.parts.actuator_potential), u_c

    @cached_property
    def gravity_parts(self) -> tuple[list[se.Basic], list[se.Basic]] | None:
        """(G_a = du_a/dq, G_p = du_c/dc), bound; None without gravity."""
        if all(c == 0 for c in self.d.model.gravity):
            return None
        u_a, u_p = self.potential
        if self.parts.distal_links:  # the distal links' potential u_d(q, p) on both sides
            u_d = se.sympify(self.parts.distal_potential)
            u_a, u_p = u_a + u_d, u_p + u_d
        values = self.program.bind([se.diff(u_a, q) for q in self.q] + [se.diff(u_p, p) for p in self.c])
        return values[:self.n], values[self.n:]

    def torques(self, qd: list[se.Basic], qdd: list[se.Basic] | None, with_gravity: bool = True,
                with_friction: bool = True, wrist: tuple[list[se.Basic], list[se.Basic] | None] = ([], None),
                motion: tuple[list[se.Basic], list[se.Basic]] | None = None) -> list[se.Basic]:
        """M_a qdd + V_a + G_a + F_f + J^T (M_p pdd + V_p + G_p), pdd = J qdd + b (qdd None: zero).

        On a hybrid device ``wrist`` = (qwd, qwdd) (qwdd None: zero) and the platform side is in c = (p, qw):
        F_c = M_c cdd + V_c + G_c with cdd = (J qdd + b, qwdd); the legs take J^T of its p rows, the wrist its qw
        rows (plus the wrist's friction), after the legs' efforts.  ``motion``: (pd, pdd) of
        :meth:`platform_motion`, when several mass distributions share them (the regressor's columns).
        """
        pd, pdd = self.platform_motion(qd, qdd) if motion is None else motion
        qwd, qwdd = wrist
        pd, pdd = pd + list(qwd), pdd + (list(qwdd) if qwdd is not None else [se.Integer(0)] * len(qwd))
        F_p = [a + b for a, b in zip(mat_vec(self.M_p, pdd), self.V_p(pd))]
        tau = [a for a in self.V_a(qd)]
        if qdd is not None:
            tau = [t + m * a for t, m, a in zip(tau, self.M_a, qdd)]
        gravity = self.gravity_parts if with_gravity else None
        if gravity is not None:
            F_p = [f + g for f, g in zip(F_p, gravity[1])]
            tau = [t + g for t, g in zip(tau, gravity[0])]
        if self.distal is not None:
            accelerations = list(qdd) if qdd is not None else [se.Integer(0)] * self.n
            tau = [t + e for t, e in zip(tau, self.distal.efforts(self.leg_columns(), list(qd), pd[:self.n],
                                                                  accelerations, pdd[:self.n]))]
        tau += [se.Integer(0)] * len(qwd)  # a wrist's joints: their rows of B^T F_c and their friction
        friction = actuator_friction(self.d.model, qd + list(qwd)) if with_friction else None
        if friction is not None:
            tau = [t + f for t, f in zip(tau, friction)]
        return [t + f for t, f in zip(tau, self.B_transpose(F_p))]

    def kinetic_energy(self, qd: list[se.Basic], cd: list[se.Basic]) -> se.Basic:
        """k = 1/2 qd^T M_a qd + 1/2 cd^T M_c cd with the platform side's rates cd = (pd, qwd), plus the spherical legs'
        distal links (1/2 w_b^T I_o w_b each) and the rods' own inertia (1/2 dI |w|^2)."""
        k = (sum((m * v * v for m, v in zip(self.M_a, qd)), se.Integer(0)) + dot(cd, mat_vec(self.M_p, cd))) / 2
        if self.distal is not None:
            k += self.distal.kinetic_energy(list(qd), cd[:self.n])
        return k

    def mass_matrix(self) -> Matrix:
        """M_a + B^T M_c B with B = diag(J, 1) (J^T M_p J without a wrist; symmetric by construction)."""
        n, J, size = self.n, self.J, len(self.c)
        columns = [[J[k][j] for k in range(n)] + [se.Integer(0)] * (size - n) for j in range(n)]
        MJ = [[self.program.let(v) for v in mat_vec(self.M_p, column)] for column in columns]
        distal = self.distal.mass_matrix(self.leg_columns()) if self.distal is not None else None
        M: Matrix = [[se.Integer(0)] * size for _ in range(size)]
        for i in range(n):
            for j in range(i, n):
                M[i][j] = M[j][i] = self.program.let(
                    (self.M_a[i] if i == j else 0) + sum((J[k][i] * MJ[j][k] for k in range(n)), se.Integer(0))
                    + (distal[i][j] if distal is not None else 0))
        for w in range(n, size):  # a wrist's rows: (J^T M_c,pw) and M_c,ww
            for i in range(n):
                M[i][w] = M[w][i] = self.program.let(sum((J[k][i] * self.M_p[k][w] for k in range(n)), se.Integer(0)))
            for v in range(w, size):
                M[w][v] = M[v][w] = self.M_p[w][v]
        return M



def device_inputs(d: Deriving, *groups: str) -> list:
    """q, then p, then the other coordinate groups; a hybrid device's wrist vector after each (qw after p)."""
    if d.model.parallel is None or d.model.parallel.wrist is None:
        return ["q", task_input(d.model), *groups]
    return ["q", task_input(d.model), hybrid.wrist_input(d.model)] + \
        [spec for group in groups for spec in (group, hybrid.wrist_input(d.model, group))]


def actuator_friction(model: Model, qd: list[se.Basic]) -> list[se.Basic] | None:
    """F_f of every coordinate (qd: the legs' then a wrist's rates), None without friction.  It needs no leg
    geometry: legs of any topology (with or without the distance form) have it."""
    if not model.friction:
        return None
    names = [c.name for c in model.coordinates]
    if hybrid.wrist_symbols(model, "q"):
        names += [j.name for j in hybrid.wrist_of(model).coordinates]
    rates = dict(zip(names, qd))
    forces = {name: se.Integer(0) for name in rates}
    for f in model.friction:
        forces[f.joint] = joint_friction(f, rates[f.joint])
    return list(forces.values())


def device_size(d: Deriving) -> int:
    """The device's coordinates: the legs' actuated joints, then a hybrid device's wrist joints."""
    return d.model.dof + len(hybrid.wrist_symbols(d.model, "q"))


_PAIR = "Evaluate at a consistent pair q, p (p = fk(q) or q = ik(p))."


@quantity("mass_matrix", "mass matrix M(q) = M_a + J^T M_p J in the actuated coordinates (n x n)", mechanism=PARALLEL,
          kappa_degree=2)
def _mass_matrix(d: Deriving) -> FunctionSpec:
    program = Program()
    M = ReducedDynamics(d, program).mass_matrix()
    n = device_size(d)
    return function_spec(
        d, "mass_matrix", "Mass matrix in the actuated coordinates.",
        "M = M_a + J^T M_p J: the actuator side (arms, rod shares at the elbows, rotors times the gear ratio "
        "squared; diagonal) plus the platform side (platform and rod shares at the platform joints) carried "
        f"to the actuators by the task Jacobian J (k = 1/2 qd^T M qd). {_PAIR}",
        device_inputs(d), program, [("M", [v for row in M for v in row], (n, n), "symmetric positive definite mass matrix",
                               "")])


@quantity("coriolis_vector", "Coriolis and centrifugal efforts V = V_a + J^T (M_p b + V_p) (n)", mechanism=PARALLEL,
          kappa_degree=4)
def _coriolis_vector(d: Deriving) -> FunctionSpec:
    program = Program()
    terms = ReducedDynamics(d, program)
    V = terms.torques(coordinate_symbols(d, "qd"), None, with_gravity=False, with_friction=False,
                      wrist=(terms.wrist("qd"), None))
    return function_spec(
        d, "coriolis_vector", "Coriolis and centrifugal efforts at the actuators.",
        "V = V_a + J^T (M_p b + V_p(p, pd)) with pd = J qd and b = dJ/dt qd = -J_x^-1 (zd^T H_i zd)_i (the "
        "second derivative of the leg equations along the motion); V_a and V_p from the Christoffel symbols of "
        f"M_a(q) and M_p(p). {_PAIR}",
        device_inputs(d, "qd"), program, [("V", V, (device_size(d),), "Coriolis and centrifugal efforts", EFFORT_UNIT)])


@quantity("gravity_vector", "actuator efforts G = du_a/dq + J^T du_p/dp that hold the device against gravity",
          mechanism=PARALLEL)
def _gravity_vector(d: Deriving) -> FunctionSpec:
    require_gravity(d, "gravity_vector")
    program = Program()
    terms = ReducedDynamics(d, program)
    G_a, G_p = terms.gravity_parts  # type: ignore[misc]
    G = [a + b for a, b in zip(G_a + [se.Integer(0)] * (device_size(d) - d.model.dof), terms.B_transpose(G_p))]
    return function_spec(
        d, "gravity_vector", "Gravity compensation efforts.",
        "G = du_a/dq + J^T du_p/dp with u = -g . (sum of mass times centre of mass): the actuator efforts that "
        f"hold the device still at the pose (gravity compensation of a haptic device). {_PAIR}",
        device_inputs(d), program, [("G", G, (device_size(d),), "actuator efforts that hold the device against gravity",
                               EFFORT_UNIT)])


@quantity("friction", "actuator friction F_f(qd): viscous + Coulomb (n)", mechanism=PARALLEL)
def _friction(d: Deriving) -> FunctionSpec:
    program = Program()
    wrist_rates = se_vector(hybrid.wrist_symbols(d.model, "qd"))
    F = actuator_friction(d.model, coordinate_symbols(d, "qd") + wrist_rates)
    if F is None:
        raise DerivationError(f"{d.model.name}: the model declares no friction; add a 'friction:' section "
                              "or remove 'friction' from the outputs")
    return function_spec(
        d, "friction", "Actuator friction efforts.",
        "F_f = viscous qd + coulomb sign(qd) per actuator (seed eq. 8.34), or coulomb tanh(qd / v_s) where the "
        "model gives a smoothing velocity v_s.",
        ["qd"] + ([hybrid.wrist_input(d.model, "qd")] if wrist_rates else []), program,
        [("F_f", F, (device_size(d),), "friction efforts opposing the motion", EFFORT_UNIT)])


@quantity("inverse_dynamics", "inverse dynamics tau = M qdd + V + G + F_f at the actuators (n)", mechanism=PARALLEL,
          kappa_degree=4)
def _inverse_dynamics(d: Deriving) -> FunctionSpec:
    program = Program()
    terms = ReducedDynamics(d, program)
    tau = terms.torques(coordinate_symbols(d, "qd"), coordinate_symbols(d, "qdd"),
                        wrist=(terms.wrist("qd"), terms.wrist("qdd")))
    return function_spec(
        d, "inverse_dynamics", "Inverse dynamics: actuator efforts for a motion.",
        "tau = M_a qdd + V_a + G_a + F_f + J^T (M_p pdd + V_p + G_p) with pdd = J qdd + b (d'Alembert: the loop "
        "constraint forces do no work on motions pd = J qd), equal to M qdd + V + G + F_f without forming M. "
        f"{_PAIR}",
        device_inputs(d, "qd", "qdd"), program, [("tau", tau, (device_size(d),), "actuator efforts", EFFORT_UNIT)])


@quantity("forward_dynamics", "forward dynamics qdd = M^-1 (tau - V - G - F_f) (n)", solves_with="mass_matrix",
          mechanism=PARALLEL, kappa_degree=4)
def _forward_dynamics(d: Deriving) -> FunctionSpec:
    program = Program()
    terms = ReducedDynamics(d, program)
    rest = terms.torques(coordinate_symbols(d, "qd"), None, wrist=(terms.wrist("qd"), None))
    M = terms.mass_matrix()
    efforts = coordinate_symbols(d, "tau") + terms.wrist("tau")
    qdd = [row[0] for row in ldl_solve(program, M, [[t - r] for t, r in zip(efforts, rest)])]
    return function_spec(
        d, "forward_dynamics", "Forward dynamics: actuator accelerations under given efforts.",
        "qdd = M^-1 (tau - V - G - F_f) by a straight-line LDL^T factorization of the symmetric positive "
        f"definite M = M_a + J^T M_p J; the platform then accelerates with pdd = J qdd + b. {_PAIR}",
        device_inputs(d, "qd", "tau"), program,
        [("qdd", qdd, (device_size(d),), "actuator accelerations", "rad/s^2 (revolute), m/s^2 (prismatic)")])


@quantity("operational_space", "task-space dynamics F = Mx pdd + Vx + Gx of the platform", mechanism=PARALLEL,
          kappa_degree=3)
def _operational_space(d: Deriving) -> FunctionSpec:
    if d.model.parallel is not None and d.model.parallel.wrist is not None:
        return _device_operational_space(d)
    program = Program()
    n = d.model.dof
    Mx, Vx, Gx, _ = ReducedDynamics(d, program).task_side(coordinate_symbols(d, "qd"))
    outputs = [("Mx", [v for row in Mx for v in row], (n, n), "task-space mass matrix J^-T M J^-1", ""),
               ("Vx", Vx, (n,), "task-space Coriolis and centrifugal force", TASK_FORCE_UNIT)]
    if Gx is not None:
        outputs.append(("Gx", Gx, (n,), "task-space gravity force J^-T G", TASK_FORCE_UNIT))
    return function_spec(
        d, "operational_space", "Task-space dynamics of the platform.",
        "F = Mx pdd + Vx + Gx is the force on the platform (conjugate to p) that produces the motion, tau = J^T F: "
        "Mx = J^-T M_a J^-1 + M_p, Vx = J^-T (V_a - M_a J^-1 b) + V_p, Gx = J^-T G_a + G_p with J^-1 = J_q^-1 J_x "
        "and J^-1 b = -J_q^-1 h (h: the leg equations' second derivative along the motion; no solve but pd = J qd: "
        f"J_q is diagonal; seed eqs. 8.61-8.64). Gx is omitted for a model without gravity. {_PAIR}",
        device_inputs(d, "qd"), program, outputs)


def _device_operational_space(d: Deriving) -> FunctionSpec:
    """Mx, Vx, Gx of a hybrid device at its wrist's TCP, in the device's coordinates (q, qw): the forces conjugate
    to c = (p, qw) (:meth:`ReducedDynamics.task_side`) seen at the TCP, whose twist is x = J_c cd (J_c = ``device_jacobian``,
    square), by :func:`~symkin.dynamics.quantities.task_space_dynamics`."""
    J_graph = se_matrix(hybrid.combined_jacobian(d))
    size = len(J_graph[0])
    if size != len(J_graph):
        raise DerivationError(
            f"model '{d.model.name}': the operational-space dynamics at the wrist's TCP need as many device "
            f"coordinates as the TCP's twist has components ({len(J_graph)}); the platform moves in "
            f"{len(d.model.task_space)} and the wrist in {size - len(d.model.task_space)}: remove "
            "'operational_space' (symkin rate --device gives the apparent mass at the grip)")
    program = Program()
    terms = ReducedDynamics(d, program)
    M_c, V_c, G_c, cd = terms.task_side(coordinate_symbols(d, "qd"))
    Mx, Vx, Gx = task_space_dynamics(program, J_graph, terms.c, cd, M_c, V_c, G_c)
    outputs = [("Mx", [v for row in Mx for v in row], (size, size), "mass matrix at the TCP J_c^-T M_c J_c^-1", ""),
               ("Vx", Vx, (size,), "Coriolis and centrifugal wrench at the TCP", WRENCH_UNIT)]
    if Gx is not None:
        outputs.append(("Gx", Gx, (size,), "gravity wrench at the TCP", WRENCH_UNIT))
    return function_spec(
        d, "operational_space", "Operational-space dynamics of the hybrid device at the wrist's TCP.",
        "F = Mx xdd + Vx + Gx is the wrench [f; m] at the TCP (base axes) that produces the motion whose twist is "
        "x = [v; w] = J_c [pd; qwd] (device_jacobian), tau = J_a^T F: the legs' actuator side carried into "
        "c = (p, qw) by J^-1 = J_q^-1 J_x, M_c = M_c,p + diag(J^-T M_a J^-1, 0), V_c = V_c,p + (J^-T (V_a - M_a "
        "J^-1 b), 0), G_c = G_c,p + (J^-T G_a, 0), then Mx = J_c^-T M_c J_c^-1, Vx = J_c^-T V_c - Mx dJ_c/dt cd, "
        f"Gx = J_c^-T G_c (J_c^-T by a Gram-Schmidt QR). Gx is omitted without gravity. {_PAIR}",
        device_inputs(d, "qd"), program, outputs)


@quantity("kinetic_energy", "kinetic energy k = 1/2 qd^T M_a qd + 1/2 pd^T M_p pd (scalar)", mechanism=PARALLEL,
          kappa_degree=2)
def _kinetic_energy(d: Deriving) -> FunctionSpec:
    program = Program()
    terms = ReducedDynamics(d, program)
    qd = coordinate_symbols(d, "qd")
    k = terms.kinetic_energy(qd, terms.task_rates(qd) + terms.wrist("qd"))  # c-rates (pd, qwd) on a hybrid device
    return function_spec(
        d, "kinetic_energy", "Kinetic energy.",
        f"k = 1/2 qd^T M_a qd + 1/2 pd^T M_p pd with pd = J qd (= 1/2 qd^T M qd). {_PAIR}",
        device_inputs(d, "qd"), program, [("k", [k], (), "kinetic energy of all bodies", "J")])


@quantity("potential_energy", "potential energy u = u_a(q) + u_p(p) (scalar)", mechanism=PARALLEL)
def _potential_energy(d: Deriving) -> FunctionSpec:
    require_gravity(d, "potential_energy")
    program = Program()
    parts = d[_inertia]
    if d.model.parallel is not None and d.model.parallel.wrist is not None:
        (u,) = program.bind([sum(ReducedDynamics(d, program).potential, se.Integer(0))])
    else:
        (u,) = program.bind([se.sympify(parts.actuator_potential + parts.platform_potential + parts.distal_potential)])
    return function_spec(
        d, "potential_energy", "Gravitational potential energy.",
        f"u = -g . (sum of mass times centre of mass), zero with every mass at the base origin. {_PAIR}",
        device_inputs(d), program, [("u", [u], (), "potential energy", "J")])
