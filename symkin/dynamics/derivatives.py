"""Derivatives of the dynamics of serial chains (issue 65), for model-predictive control, trajectory optimization
and the linearization of a plant at a state.

=================================  ==================================================================================
``inverse_dynamics_derivatives``   d tau/dq, d tau/dqd and d tau/dqdd = M of tau = M qdd + V + G + F_f (n x n each)
=================================  ==================================================================================

They are derived on the recursive program, not on expanded closed forms: the torques are the straight-line program
of the recursive Newton-Euler pass (:func:`symkin.dynamics.newton_euler.inverse_dynamics`, bound by
:meth:`symkin.dynamics.program.Program.bind`: every link's motion and wrench an assignment shared by all that
follow), and the program is differentiated forward (:meth:`symkin.dynamics.program.Program.jacobian`): each
assignment's gradient is formed once from its operands' gradients and named - the derivative program of the
recursion, O(n) times its O(n) length, as the analytical derivatives of the RNEA (Carpentier and Mansard,
"Analytical Derivatives of Rigid Body Dynamics Algorithms", RSS 2018) cost O(n^2) for the n^2 entries.
Couplings come in through the
joints' values as functions of the coordinates (the derivatives are with respect to the coordinates), springs
through their torques in G, rotor inertia through the armature in M, and friction through F_f(qd): viscous terms
and smoothed Coulomb terms (tanh) differentiate as they are; a sign(qd) Coulomb term has the derivative 0 wherever
it is defined (qd != 0), as every linearization of a Coulomb model takes it.
"""

from __future__ import annotations

import symengine as se

from symkin.dynamics import newton_euler
from symkin.dynamics.coupling import forces_on_coordinates, joint_rates
from symkin.dynamics.joint_forces import friction_graph, spring_torques
from symkin.dynamics.program import Program
from symkin.dynamics.quantities import coordinate_symbols, function_spec, gravity_graph, newton_euler_links
from symkin.ir.quantity import Deriving, quantity
from symkin.ir.spec import FunctionSpec


def torque_graph(d: Deriving) -> tuple[list[se.Basic], list[se.Basic] | None]:
    """tau(q, qd, qdd) = M qdd + V + G + F_f on the coordinates as unbound SymEngine graphs: (the Newton-Euler
    torques, gravity and the springs' included; the friction's F_f(qd), None without friction) (seed eq. 8.34)."""
    model = d.model
    tau = forces_on_coordinates(model, newton_euler.inverse_dynamics(
        d[newton_euler_links], joint_rates(model, "qd"), joint_rates(model, "qdd"), d[gravity_graph]))
    if model.springs:
        tau = [a + b for a, b in zip(tau, d[spring_torques])]
    return tau, d[friction_graph]


def _without_sign_derivatives(value: se.Basic) -> se.Basic:
    """``value`` with the derivatives of sign(.) set to 0 (their value wherever sign is differentiable); for the
    small friction terms only (a walk over every node of a tree)."""
    derivatives = [a for a in value.atoms(se.Derivative) if isinstance(a.args[0], se.sign)]
    return value.subs({a: se.Integer(0) for a in derivatives}) if derivatives else value


def torque_jacobian(d: Deriving, program: Program, variables: list[se.Symbol]) -> list[se.Basic]:
    """The row-major entries d tau_i / d variables_j, named in ``program``: the Newton-Euler program bound and
    differentiated forward (:meth:`~symkin.dynamics.program.Program.jacobian`), plus the friction's derivative."""
    rigid, friction = torque_graph(d)
    entries = program.jacobian(program.bind(rigid), variables)
    if friction is None:
        return entries
    slopes = [_without_sign_derivatives(se.diff(f, x)) for f in friction for x in variables]
    return [entry + slope for entry, slope in zip(entries, slopes)]


@quantity("inverse_dynamics_derivatives", "d tau/dq, d tau/dqd, d tau/dqdd = M of the inverse dynamics (n x n each)")
def _inverse_dynamics_derivatives(d: Deriving) -> FunctionSpec:
    n = d.model.dof
    program = Program()
    variables = [x for group in ("q", "qd", "qdd") for x in coordinate_symbols(d, group)]
    entries = program.bind(torque_jacobian(d, program, variables))
    dq, dqd, dqdd = ([entries[i * 3 * n + k * n + j] for i in range(n) for j in range(n)] for k in range(3))
    return function_spec(
        d, "inverse_dynamics_derivatives", "Derivatives of the inverse dynamics: the linearization of tau at a motion.",
        "tau(q + dq, qd + dqd, qdd + dqdd) = tau + dtau_dq dq + dtau_dqd dqd + dtau_dqdd dqdd to first order, "
        "tau = M qdd + V + G + F_f (seed eq. 8.34); dtau_dqdd = M.  Forward-mode derivative of the recursive "
        "Newton-Euler program (Carpentier and Mansard, RSS 2018); a sign(qd) Coulomb term counts with derivative 0.",
        ["q", "qd", "qdd"], program,
        [("dtau_dq", dq, (n, n), "d tau / dq: row i, column j is d tau_i / d q_j", ""),
         ("dtau_dqd", dqd, (n, n), "d tau / dqd: the damping of the motion (Coriolis and friction)", ""),
         ("dtau_dqdd", dqdd, (n, n), "d tau / dqdd = M(q), the mass matrix", "")])
