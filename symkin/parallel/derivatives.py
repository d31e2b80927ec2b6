"""Derivatives of the reduced dynamics of parallel mechanisms (issue 65): the linearization of a device's plant in its
actuated coordinates, for model-predictive control of a haptic device or a DELTA robot.

================================  ===================================================================================
``inverse_dynamics_derivatives``  d tau/dq, d tau/dqd and d tau/dqdd = M of tau = M qdd + V + G + F_f (n x n each)
``forward_dynamics_derivatives``  d qdd/dq, d qdd/dqd and d qdd/dtau = M^-1 of the forward dynamics (n x n each)
``gravity_derivatives``           d G/dq of the gravity compensation efforts (n x n)
================================  ===================================================================================

The reduced dynamics (:mod:`symkin.parallel.dynamics`) take the actuated variables q with the platform pose p as a
consistent pair (p = fk(q)), so a change of q moves p along the closure: dp = J dq, J = J_x^-1 J_q the task
Jacobian the program already holds.  Every derivative by q is therefore the total one,

    d tau/dq = (partial tau/partial q) + (partial tau/partial p) J,

the partial derivatives by automatic differentiation of the reduced dynamics' straight-line program
(:meth:`symkin.dynamics.program.Program.jacobian`: reverse mode, one adjoint sweep per effort) and J's entries
shared with the efforts.  The forward dynamics' derivatives follow by the implicit-function theorem as for serial
chains (:mod:`symkin.dynamics.derivatives`): d qdd/dq = -M^-1 d tau/dq and d qdd/dqd = -M^-1 d tau/dqd at
qdd = FD(q, qd, tau), d qdd/dtau = M^-1, by LDL^T solves.  Friction enters through F_f(qd) (a sign(qd) Coulomb term
with derivative 0 wherever it is defined).  A hybrid device (a wrist on the platform) has the coordinates (q, qw):
the wrist's joints are coordinates of their own (p does not move with them), so its columns are the partial
derivatives by qw, qwd (and qwdd: M's), after the legs' - the efforts (tau, tauw) by (q, qw), (qd, qwd), (qdd, qwdd),
(n + n_w) x (n + n_w) each.
"""

from __future__ import annotations

import symengine as se

from symkin.dynamics.derivatives import forward_dynamics_slopes, without_sign_derivatives
from symkin.dynamics.program import Program
from symkin.dynamics.quantities import coordinate_symbols, function_spec, require_gravity
from symkin.ir.quantity import Deriving, quantity
from symkin.ir.spec import FunctionSpec
from symkin.parallel.dynamics import ReducedDynamics, actuator_friction, device_inputs, device_size
from symkin.parallel.quantities import PARALLEL

_PAIR = "Evaluate at a consistent pair q, p (p = fk(q) or q = ik(p)); the derivatives by q move p with it (dp = J dq)."


def _total_by_q(terms: ReducedDynamics, outputs: list[se.Basic], extra: list[se.Symbol]) -> list[list[se.Basic]]:
    """[d outputs/dq (total: p = fk(q) moves with q), d outputs/d extra] as row-major lists: the program's partial
    derivatives by (q, p, extra), the p columns carried to q by J."""
    n, k = terms.n, len(extra)
    width = 2 * n + k
    partial = terms.program.jacobian(outputs, terms.q + terms.p + extra)
    J = terms.J
    by_q = [partial[i * width + j] + sum((partial[i * width + n + m] * J[m][j] for m in range(n)), se.Integer(0))
            for i in range(len(outputs)) for j in range(n)]
    by_extra = [partial[i * width + 2 * n + j] for i in range(len(outputs)) for j in range(k)]
    return [by_q, by_extra]


def _by_coordinates(terms: ReducedDynamics, outputs: list[se.Basic], rates: list[se.Basic]
                    ) -> tuple[list[se.Basic], list[se.Basic]]:
    """(d outputs/d(q, qw), d outputs/d rates) row-major: by the legs' q the total derivative, by a hybrid device's
    wrist joints qw (none without a wrist) the partial one."""
    n, w, k = terms.n, len(terms.qw), len(terms.qw) + len(rates)
    by_q, by_extra = _total_by_q(terms, outputs, terms.qw + rates)
    by_coordinates = [v for i in range(len(outputs)) for v in by_q[i * n:(i + 1) * n] + by_extra[i * k:i * k + w]]
    by_rates = [v for i in range(len(outputs)) for v in by_extra[i * k + w:(i + 1) * k]]
    return by_coordinates, by_rates


def _torque_slopes(d: Deriving, terms: ReducedDynamics) -> tuple[list[se.Basic], list[se.Basic]]:
    """(d tau/d(q, qw), d tau/d(qd, qwd)) row-major of tau = M qdd + V + G + F_f at symbolic accelerations: the rigid
    efforts' program differentiated, plus the friction's derivative."""
    qd, qdd = coordinate_symbols(d, "qd"), coordinate_symbols(d, "qdd")
    rigid = terms.torques(qd, qdd, with_friction=False, wrist=(terms.wrist("qd"), terms.wrist("qdd")))
    rates = qd + terms.wrist("qd")
    dq, dqd = _by_coordinates(terms, rigid, rates)
    friction = actuator_friction(d.model, rates)
    if friction is not None:
        size = len(rates)
        dqd = [dqd[i * size + j] + without_sign_derivatives(se.diff(friction[i], rates[j]))
               for i in range(size) for j in range(size)]
    return dq, dqd


@quantity("inverse_dynamics_derivatives", "d tau/dq, d tau/dqd, d tau/dqdd = M at the actuators (n x n each)",
          mechanism=PARALLEL, kappa_degree=5)
def _inverse_dynamics_derivatives(d: Deriving) -> FunctionSpec:
    program = Program()
    terms = ReducedDynamics(d, program)
    n = device_size(d)
    M = terms.mass_matrix()
    dq, dqd = (program.bind(v) for v in _torque_slopes(d, terms))
    return function_spec(
        d, "inverse_dynamics_derivatives", "Derivatives of the inverse dynamics at the actuators: the linearization "
        "of tau at a motion.",
        "tau(q + dq, qd + dqd, qdd + dqdd) = tau + dtau_dq dq + dtau_dqd dqd + dtau_dqdd dqdd to first order with "
        "tau = M qdd + V + G + F_f the reduced dynamics; dtau_dq is the total derivative (partial by q plus partial "
        "by p times J), dtau_dqdd = M; reverse-mode derivative of the reduced dynamics' program. " + _PAIR,
        device_inputs(d, "qd", "qdd"), program,
        [("dtau_dq", dq, (n, n), "d tau / dq: row i, column j is d tau_i / d q_j", ""),
         ("dtau_dqd", dqd, (n, n), "d tau / dqd: the damping of the motion (Coriolis and friction)", ""),
         ("dtau_dqdd", [M[i][j] for i in range(n) for j in range(n)], (n, n), "d tau / dqdd = M(q)", "")])


@quantity("forward_dynamics_derivatives", "d qdd/dq, d qdd/dqd, d qdd/dtau = M^-1 at the actuators (n x n each)",
          solves_with="mass_matrix", mechanism=PARALLEL, kappa_degree=5)
def _forward_dynamics_derivatives(d: Deriving) -> FunctionSpec:
    program = Program()
    terms = ReducedDynamics(d, program)
    n = device_size(d)

    def slope_rows() -> list[list[se.Basic]]:
        dq, dqd = _torque_slopes(d, terms)
        return [dq[i * n:(i + 1) * n] + dqd[i * n:(i + 1) * n] for i in range(n)]

    rest = terms.torques(coordinate_symbols(d, "qd"), None, wrist=(terms.wrist("qd"), None))
    by_q, by_qd, by_tau, solve = forward_dynamics_slopes(
        program, terms.mass_matrix(), rest, coordinate_symbols(d, "tau") + terms.wrist("tau"),
        coordinate_symbols(d, "qdd") + terms.wrist("qdd"), slope_rows)
    return function_spec(
        d, "forward_dynamics_derivatives", "Derivatives of the forward dynamics at the actuators: the linearization "
        "of the device's plant.",
        "qdd(q + dq, qd + dqd, tau + dtau) = qdd + dqdd_dq dq + dqdd_dqd dqd + dqdd_dtau dtau to first order, "
        "qdd = M^-1 (tau - V - G - F_f) the reduced dynamics; by the implicit-function theorem dqdd_dq = "
        "-M^-1 dtau_dq, dqdd_dqd = -M^-1 dtau_dqd at qdd and dqdd_dtau = M^-1, by LDL^T solves. " + _PAIR,
        device_inputs(d, "qd", "tau"), program,
        [("dqdd_dq", by_q, (n, n), "d qdd / dq: row i, column j is d qdd_i / d q_j", ""),
         ("dqdd_dqd", by_qd, (n, n), "d qdd / dqd", ""),
         ("dqdd_dtau", by_tau, (n, n), "d qdd / dtau = M(q)^-1, exactly symmetric", "")], maps=[solve])


@quantity("gravity_derivatives", "d G/dq of the gravity compensation efforts at the actuators (n x n)",
          mechanism=PARALLEL, kappa_degree=3)
def _gravity_derivatives(d: Deriving) -> FunctionSpec:
    require_gravity(d, "gravity_derivatives")
    program = Program()
    terms = ReducedDynamics(d, program)
    n = device_size(d)
    gravity = terms.gravity_parts
    assert gravity is not None, "require_gravity refuses a model without gravity"
    G = [a + b for a, b in zip(gravity[0] + [se.Integer(0)] * len(terms.qw), terms.B_transpose(gravity[1]))]
    dG = program.bind(_by_coordinates(terms, G, [])[0])
    return function_spec(
        d, "gravity_derivatives", "Derivative of the gravity compensation efforts: the stiffness gravity adds at "
        "the actuators.",
        "G(q + dq) = G(q) + dG_dq dq to first order, G = du_a/dq + J^T du_p/dp (the efforts that hold the device "
        "still); the total derivative by q (partial by q plus partial by p times J) of the program. " + _PAIR,
        device_inputs(d), program, [("dG_dq", dG, (n, n), "d G / dq: row i, column j is d G_i / d q_j", "")])
