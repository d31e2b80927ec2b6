"""Derivatives of the dynamics of serial chains (issue 65; parallel mechanisms: :mod:`symkin.parallel.derivatives`),
for model-predictive control, trajectory optimization and the linearization of a plant at a state.

=================================  ==================================================================================
``inverse_dynamics_derivatives``   d tau/dq, d tau/dqd and d tau/dqdd = M of tau = M qdd + V + G + F_f (n x n each)
``forward_dynamics_derivatives``   d qdd/dq, d qdd/dqd and d qdd/dtau = M^-1 of the forward dynamics (n x n each)
``gravity_derivatives``            d G/dq of the gravity vector (springs included; n x n): the static stiffness
``static_torque_derivatives``      d tau_s/dq of the static torques tau_s = G(q) - J(q)^T F that hold the arm still
                                   under gravity and a wrench F on the TCP (n x n): gravity's stiffness and the
                                   force's (Pinocchio's computeStaticTorqueDerivatives)
``fk_sensitivities``               d base_T_tcp / d p of the free parameters p (lengths, offsets; 16 x P)
``jacobian_sensitivities``         d J / d p (m n x P): for kinematic calibration and design gradients
``inverse_dynamics_sensitivities`` d tau / d p (n x P): of lengths, masses, inertias, friction, gear ratios
=================================  ==================================================================================

They are derived on the recursive program, not on expanded closed forms: the torques are the straight-line program
of the recursive Newton-Euler pass (:func:`symkin.dynamics.newton_euler.inverse_dynamics`, bound by
:meth:`symkin.dynamics.program.Program.bind`: every link's motion and wrench an assignment shared by all that
follow), and the program is differentiated by automatic differentiation of the straight-line program
(:meth:`symkin.dynamics.program.Program.jacobian`): in reverse mode for the n torques by their 2n states (one
adjoint sweep per torque, each assignment's adjoint formed once and named; 19 % fewer operations than forward mode
for the UR10e), in forward mode where the variables are fewer - the derivative program of the recursion, O(n) times
its O(n) length, as the analytical derivatives of the RNEA (Carpentier and Mansard, "Analytical Derivatives of Rigid
Body Dynamics Algorithms", RSS 2018) cost O(n^2) for the n^2 entries.  Couplings come in through the
joints' values as functions of the coordinates (the derivatives are with respect to the coordinates), springs
through their torques in G, rotor inertia through the armature in M, and friction through F_f(qd): viscous terms
and smoothed Coulomb terms (tanh) differentiate as they are; a sign(qd) Coulomb term has the derivative 0 wherever
it is defined (qd != 0), as every linearization of a Coulomb model takes it.

The forward dynamics' derivatives follow from the inverse's by the implicit-function theorem on
tau = ID(q, qd, qdd) at qdd = FD(q, qd, tau) (Carpentier and Mansard's route to the ABA derivatives):

    d qdd/dq = -M^-1 d tau/dq,   d qdd/dqd = -M^-1 d tau/dqd,   d qdd/dtau = M^-1,

the inverse dynamics' derivative program evaluated at the accelerations the LDL^T solve of the forward dynamics
gives, then the same factors' substitutions for the n + n right-hand sides [-d tau/dq | -d tau/dqd] and the n
columns of the identity, as one column map (:func:`~symkin.dynamics.linsolve.ldl_substitution_map`: the C backend
prints its body once, as a loop over the 3n columns, so the function's code fits the instruction cache), and M^-1
as the lower triangle of the last n columns, mirrored (exactly symmetric, as d tau/dqdd = M is).
"""

from __future__ import annotations

from collections.abc import Callable

import symengine as se
import sympy

from symkin.dynamics.linsolve import ldl_factor, ldl_substitute, ldl_substitution_map
from symkin.dynamics.program import Program, ProgramMap
from symkin.dynamics.quantities import (BoundTerms, coordinate_symbols, function_spec, inverse_dynamics_spec,
                                        require_gravity)
from symkin.errors import DerivationError
from symkin.ir.quantity import Deriving, quantity
from symkin.ir.spec import FunctionSpec, InputSpec
from symkin.kinematics.quantities import forward_kinematics, task_jacobian
from symkin.symengine_bridge import to_symengine


def without_sign_derivatives(value: se.Basic) -> se.Basic:
    """``value`` with the derivatives of sign(.) set to 0 (their value wherever sign is differentiable); for the
    small friction terms only (a walk over every node of a tree)."""
    derivatives = [a for a in value.atoms(se.Derivative) if isinstance(a.args[0], se.sign)]
    return value.subs({a: se.Integer(0) for a in derivatives}) if derivatives else value


def torque_jacobian(terms: BoundTerms, variables: list[se.Symbol]) -> list[se.Basic]:
    """The row-major entries d tau_i / d variables_j of tau = M qdd + V + G + F_f (seed eq. 8.34), named in the
    terms' program: its Newton-Euler torques (gravity and the springs' included, :meth:`BoundTerms.newton_euler`)
    differentiated (:meth:`~symkin.dynamics.program.Program.jacobian`), plus the friction's derivative."""
    rigid = terms.newton_euler(velocity=True, acceleration=True, gravity=True)
    entries = terms.program.jacobian(rigid, variables)
    friction = terms.friction()
    if friction is None:
        return entries
    slopes = [without_sign_derivatives(se.diff(f, x)) for f in friction for x in variables]
    return [entry + slope for entry, slope in zip(entries, slopes)]


def forward_dynamics_slopes(program: Program, M: list[list[se.Basic]], rest: list[se.Basic], tau: list[se.Basic],
                            qdd: list[se.Basic], slope_rows: Callable[[], list[list[se.Basic]]]
                            ) -> tuple[list[se.Basic], list[se.Basic], list[se.Basic], ProgramMap]:
    """(d qdd/dq, d qdd/dqd, d qdd/dtau) row-major by the implicit-function theorem on tau = M qdd + rest, and the
    column map they read: the accelerations qdd = M^-1 (tau - rest) by an LDL^T solve bound into ``program``, then
    ``slope_rows()`` - row i the 2n derivatives d tau_i/dq, d tau_i/dqd of the inverse dynamics at the symbols
    ``qdd``, bound after the solve - at those accelerations, and M^-1 [-dtau/dq | -dtau/dqd | I] by the same
    factors' substitutions as one column map (:func:`~symkin.dynamics.linsolve.ldl_substitution_map`, the
    function's map 0), M^-1 its last n columns' lower triangle, mirrored (exactly symmetric)."""
    n = len(tau)
    factors = ldl_factor(program, M)
    accelerations = [row[0] for row in ldl_substitute(program, *factors, [[t - r] for t, r in zip(tau, rest)])]
    start = len(program.assignments)
    rows = slope_rows()
    at_motion = dict(zip(qdd, accelerations))  # the derivative program at qdd = FD(q, qd, tau)
    program.substitute(start, at_motion)
    columns = [[-rows[i][j].xreplace(at_motion) for i in range(n)] for j in range(2 * n)]
    columns += [[se.Integer(int(i == c)) for i in range(n)] for c in range(n)]
    solve = ldl_substitution_map(program, *factors, columns)
    X = solve.targets
    by_q, by_qd = ([X[k * n + j][i] for i in range(n) for j in range(n)] for k in range(2))
    return by_q, by_qd, [X[2 * n + min(i, j)][max(i, j)] for i in range(n) for j in range(n)], solve


@quantity("inverse_dynamics_derivatives", "d tau/dq, d tau/dqd, d tau/dqdd = M of the inverse dynamics (n x n each)")
def _inverse_dynamics_derivatives(d: Deriving) -> FunctionSpec:
    n = d.model.dof
    program = Program()
    terms = BoundTerms(d, program)
    variables = [x for group in ("q", "qd", "qdd") for x in coordinate_symbols(d, group)]
    entries = program.bind(torque_jacobian(terms, variables))
    dq, dqd, slopes = ([entries[i * 3 * n + k * n + j] for i in range(n) for j in range(n)] for k in range(3))
    dqdd = [slopes[max(i, j) * n + min(i, j)] for i in range(n) for j in range(n)]  # M: its lower triangle, mirrored
    return function_spec(
        d, "inverse_dynamics_derivatives", "Derivatives of the inverse dynamics: the linearization of tau at a motion.",
        "tau(q + dq, qd + dqd, qdd + dqdd) = tau + dtau_dq dq + dtau_dqd dqd + dtau_dqdd dqdd to first order, "
        "tau = M qdd + V + G + F_f (seed eq. 8.34); dtau_dqdd = M.  Reverse-mode derivative of the recursive "
        "Newton-Euler program (Carpentier and Mansard, RSS 2018), dtau_dqdd = M from the same adjoint sweeps (its "
        "lower triangle, mirrored: exactly symmetric); a sign(qd) Coulomb term counts with derivative 0.",
        ["q", "qd", "qdd"], program,
        [("dtau_dq", dq, (n, n), "d tau / dq: row i, column j is d tau_i / d q_j", ""),
         ("dtau_dqd", dqd, (n, n), "d tau / dqd: the damping of the motion (Coriolis and friction)", ""),
         ("dtau_dqdd", dqdd, (n, n), "d tau / dqdd = M(q), the mass matrix", "")])


@quantity("forward_dynamics_derivatives", "d qdd/dq, d qdd/dqd, d qdd/dtau = M^-1 of the forward dynamics (n x n each)",
          solves_with="mass_matrix")
def _forward_dynamics_derivatives(d: Deriving) -> FunctionSpec:
    n = d.model.dof
    program = Program()
    terms = BoundTerms(d, program)
    variables = [x for group in ("q", "qd") for x in coordinate_symbols(d, group)]

    def slope_rows() -> list[list[se.Basic]]:
        slopes = torque_jacobian(terms, variables)
        return [slopes[i * 2 * n:(i + 1) * 2 * n] for i in range(n)]

    dq, dqd, dtau, solve = forward_dynamics_slopes(
        program, terms.mass_matrix(), terms.torques(acceleration=False, with_friction=True),
        coordinate_symbols(d, "tau"), coordinate_symbols(d, "qdd"), slope_rows)
    return function_spec(
        d, "forward_dynamics_derivatives", "Derivatives of the forward dynamics: the linearization of the plant.",
        "qdd(q + dq, qd + dqd, tau + dtau) = qdd + dqdd_dq dq + dqdd_dqd dqd + dqdd_dtau dtau to first order, "
        "qdd = M^-1 (tau - V - G - F_f) (seed eq. 8.34); by the implicit-function theorem dqdd_dq = -M^-1 dtau_dq, "
        "dqdd_dqd = -M^-1 dtau_dqd at qdd and dqdd_dtau = M^-1, by LDL^T solves (Carpentier and Mansard, RSS 2018), "
        "M^-1 from its lower triangle, mirrored (exactly symmetric), the solves' substitutions one loop over columns; "
        "a state-space model x = (q, qd) has A = [[0, I], [dqdd_dq, dqdd_dqd]] and B = [[0], [dqdd_dtau]].",
        ["q", "qd", "tau"], program,
        [("dqdd_dq", dq, (n, n), "d qdd / dq: row i, column j is d qdd_i / d q_j", ""),
         ("dqdd_dqd", dqd, (n, n), "d qdd / dqd", ""),
         ("dqdd_dtau", dtau, (n, n), "d qdd / dtau = M(q)^-1, exactly symmetric", "")], maps=[solve])


@quantity("gravity_derivatives", "d G/dq of the gravity vector (n x n)")
def _gravity_derivatives(d: Deriving) -> FunctionSpec:
    require_gravity(d, "gravity_derivatives")
    n = d.model.dof
    program = Program()
    G = BoundTerms(d, program).gravity_vector()
    assert G is not None, "require_gravity refuses a model without gravity"
    dG = program.bind(program.jacobian(G, coordinate_symbols(d, "q")))
    return function_spec(
        d, "gravity_derivatives", "Derivative of the gravity vector: the stiffness gravity (and the springs) add.",
        "G(q + dq) = G(q) + dG_dq dq to first order (seed eq. 8.31's G = du/dq, so dG_dq = d^2u/dq^2 is symmetric "
        "for gravity and springs alike); derivative of the Newton-Euler program at rest (automatic differentiation).",
        ["q"], program, [("dG_dq", dG, (n, n), "d G / dq: row i, column j is d G_i / d q_j", "")])


@quantity("static_torque_derivatives", "d tau_s/dq of the static torques tau_s = G - J^T F (n x n)")
def _static_torque_derivatives(d: Deriving) -> FunctionSpec:
    n, task = d.model.dof, d.model.task_space
    program = Program()
    G = BoundTerms(d, program).gravity_vector() or [se.Integer(0)] * n
    J = program.bind([to_symengine(v) for v in d[task_jacobian].outputs[0].expr])   # row-major, task x joints
    names = tuple(f"F_{c}" for c in task)
    wrench = InputSpec("F", "vector", tuple(sympy.Symbol(name, real=True) for name in names), names,
                       tuple("N" if c in ("x", "y", "z") else "N*m" for c in task),
                       "wrench the environment exerts on the TCP, one component per task coordinate")
    F = [to_symengine(f) for f in wrench.symbols]
    static = [G[i] - sum((J[k * n + i] * F[k] for k in range(len(task))), se.Integer(0)) for i in range(n)]
    dtau = program.bind(program.jacobian(static, coordinate_symbols(d, "q")))
    return function_spec(
        d, "static_torque_derivatives", "Derivative of the static torques: the stiffness gravity and a TCP wrench add.",
        "tau_s(q + dq, F) = tau_s(q, F) + dtau_dq dq to first order, tau_s = G(q) - J(q)^T F the joint torques that "
        "hold the arm still under gravity and a wrench F the environment exerts on the TCP (seed eqs. 8.31, 8.36; "
        "Pinocchio's computeStaticTorqueDerivatives); -d(J^T F)/dq is the stiffness a constant force adds (the "
        "conservative congruence transformation of Chen and Kao, 2000); derivative of the program (automatic "
        "differentiation).",
        ["q", wrench], program, [("dtau_dq", dtau, (n, n), "d tau_s / dq: row i, column j is d tau_s_i / d q_j", "")])


def parameter_sensitivities(d: Deriving, spec: FunctionSpec, name: str, summary: str) -> FunctionSpec:
    """d outputs / d p of a derived function ``spec`` for the free parameters p it takes (its parameter inputs, in
    its order): its straight-line program (definitions and outputs) moved into a :class:`Program` and differentiated
    (:meth:`Program.jacobian`) with respect to the parameters; one output ``d<output>_dp`` per output, (size, P)
    with the output's entries in row-major order, row k column j = d output.flat[k] / d p_j.  The inputs are the
    spec's.

    Raises:
        DerivationError: ``spec`` takes no free parameter (every one folded or none used): nothing to differentiate.
    """
    parameters = [i for i in spec.inputs if i.kind == "parameter"]
    if not parameters:
        raise DerivationError(f"{d.model.name}: {spec.name} uses no free parameter, so {name} has nothing to "
                              "differentiate; declare the lengths, masses or other values as parameters")
    program = Program()
    memo: dict = {}
    renamed: dict[se.Basic, se.Basic] = {}
    for symbol, expr in spec.straight_line_definitions():  # the spec's names replaced by the program's
        renamed[to_symengine(symbol)] = program.let(to_symengine(expr, memo).xreplace(renamed))
    outputs = [[to_symengine(e, memo).xreplace(renamed) for e in out.expr] for out in spec.outputs]
    symbols = [to_symengine(p.symbols[0]) for p in parameters]
    entries = program.bind(program.jacobian([e for out in outputs for e in out], symbols))
    results, start = [], 0
    for out, values in zip(spec.outputs, outputs):
        size = len(values) * len(symbols)
        results.append((f"d{out.name}_dp", entries[start:start + size], (len(values), len(symbols)),
                        f"d {out.name} / d ({', '.join(p.name for p in parameters)}): row k is entry k of {out.name} "
                        "(row-major)", ""))
        start += size
    return function_spec(d, name, summary,
                         f"Automatic derivative of {spec.name}'s program with respect to its free parameters "
                         f"({', '.join(p.name for p in parameters)}): {spec.summary}",
                         list(spec.vector_inputs), program, results)


@quantity("fk_sensitivities", "d base_T_tcp / d p of the free parameters (16 x P, row-major pose entries)")
def _fk_sensitivities(d: Deriving) -> FunctionSpec:
    return parameter_sensitivities(d, d[forward_kinematics], "fk_sensitivities",
                                   "Sensitivity of the TCP pose to the model's free parameters (kinematic calibration).")


@quantity("jacobian_sensitivities", "d J / d p of the free parameters (m n x P, row-major Jacobian entries)")
def _jacobian_sensitivities(d: Deriving) -> FunctionSpec:
    return parameter_sensitivities(d, d[task_jacobian], "jacobian_sensitivities",
                                   "Sensitivity of the task Jacobian to the model's free parameters (design gradients).")


@quantity("inverse_dynamics_sensitivities", "d tau / d p of the free parameters (n x P)")
def _inverse_dynamics_sensitivities(d: Deriving) -> FunctionSpec:
    return parameter_sensitivities(d, d[inverse_dynamics_spec], "inverse_dynamics_sensitivities",
                                   "Sensitivity of the inverse dynamics to the model's free parameters (identification, "
                                   "design gradients).")
