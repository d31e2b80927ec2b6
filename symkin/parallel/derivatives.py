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
with derivative 0 wherever it is defined).  Hybrid devices (a wrist on the platform) are not covered yet.
"""

from __future__ import annotations

import symengine as se

from symkin.dynamics.derivatives import forward_dynamics_slopes, without_sign_derivatives
from symkin.dynamics.program import Program
from symkin.dynamics.quantities import coordinate_symbols, function_spec, require_gravity
from symkin.errors import DerivationError
from symkin.ir.quantity import Deriving, quantity
from symkin.ir.spec import FunctionSpec
from symkin.parallel.dynamics import ReducedDynamics, actuator_friction, device_inputs
from symkin.parallel.quantities import PARALLEL

_PAIR = "Evaluate at a consistent pair q, p (p = fk(q) or q = ik(p)); the derivatives by q move p with it (dp = J dq)."


def _terms(d: Deriving, name: str, program: Program) -> ReducedDynamics:
    if d.model.parallel is not None and d.model.parallel.wrist is not None:
        raise DerivationError(f"{d.model.name}: {name} is not derived for hybrid devices (a wrist on the platform) "
                              f"yet; remove {name} from the outputs")
    return ReducedDynamics(d, program)


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


def _torque_slopes(d: Deriving, terms: ReducedDynamics) -> tuple[list[se.Basic], list[se.Basic]]:
    """(d tau/dq, d tau/dqd) row-major of tau = M qdd + V + G + F_f at symbolic qdd: the rigid efforts' program
    differentiated, plus the friction's derivative."""
    qd, qdd = coordinate_symbols(d, "qd"), coordinate_symbols(d, "qdd")
    rigid = terms.torques(qd, qdd, with_friction=False)
    dq, dqd = _total_by_q(terms, rigid, qd)
    friction = actuator_friction(d.model, qd)
    if friction is not None:
        n = terms.n
        dqd = [dqd[i * n + j] + without_sign_derivatives(se.diff(friction[i], qd[j]))
               for i in range(n) for j in range(n)]
    return dq, dqd


@quantity("inverse_dynamics_derivatives", "d tau/dq, d tau/dqd, d tau/dqdd = M at the actuators (n x n each)",
          mechanism=PARALLEL, kappa_degree=5)
def _inverse_dynamics_derivatives(d: Deriving) -> FunctionSpec:
    n = d.model.dof
    program = Program()
    terms = _terms(d, "inverse_dynamics_derivatives", program)
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
    n = d.model.dof
    program = Program()
    terms = _terms(d, "forward_dynamics_derivatives", program)

    def slope_rows() -> list[list[se.Basic]]:
        dq, dqd = _torque_slopes(d, terms)
        return [dq[i * n:(i + 1) * n] + dqd[i * n:(i + 1) * n] for i in range(n)]

    by_q, by_qd, by_tau = forward_dynamics_slopes(
        program, terms.mass_matrix(), terms.torques(coordinate_symbols(d, "qd"), None), coordinate_symbols(d, "tau"),
        coordinate_symbols(d, "qdd"), slope_rows)
    return function_spec(
        d, "forward_dynamics_derivatives", "Derivatives of the forward dynamics at the actuators: the linearization "
        "of the device's plant.",
        "qdd(q + dq, qd + dqd, tau + dtau) = qdd + dqdd_dq dq + dqdd_dqd dqd + dqdd_dtau dtau to first order, "
        "qdd = M^-1 (tau - V - G - F_f) the reduced dynamics; by the implicit-function theorem dqdd_dq = "
        "-M^-1 dtau_dq, dqdd_dqd = -M^-1 dtau_dqd at qdd and dqdd_dtau = M^-1, by LDL^T solves. " + _PAIR,
        device_inputs(d, "qd", "tau"), program,
        [("dqdd_dq", by_q, (n, n), "d qdd / dq: row i, column j is d qdd_i / d q_j", ""),
         ("dqdd_dqd", by_qd, (n, n), "d qdd / dqd", ""),
         ("dqdd_dtau", by_tau, (n, n), "d qdd / dtau = M(q)^-1", "")])


@quantity("gravity_derivatives", "d G/dq of the gravity compensation efforts at the actuators (n x n)",
          mechanism=PARALLEL, kappa_degree=3)
def _gravity_derivatives(d: Deriving) -> FunctionSpec:
    require_gravity(d, "gravity_derivatives")
    n = d.model.dof
    program = Program()
    terms = _terms(d, "gravity_derivatives", program)
    gravity = terms.gravity_parts
    assert gravity is not None, "require_gravity refuses a model without gravity"
    G = [a + b for a, b in zip(gravity[0], terms.B_transpose(gravity[1]))]
    dG = program.bind(_total_by_q(terms, G, [])[0])
    return function_spec(
        d, "gravity_derivatives", "Derivative of the gravity compensation efforts: the stiffness gravity adds at "
        "the actuators.",
        "G(q + dq) = G(q) + dG_dq dq to first order, G = du_a/dq + J^T du_p/dp (the efforts that hold the device "
        "still); the total derivative by q (partial by q plus partial by p times J) of the program. " + _PAIR,
        device_inputs(d), program, [("dG_dq", dG, (n, n), "d G / dq: row i, column j is d G_i / d q_j", "")])
