"""Force transmission of parallel mechanisms: the actuator efforts that render a task-space force.

By virtual work, tau . qdot = F . pdot for every motion, and pdot = J qdot with J = J_x^-1 J_q
(:mod:`symkin.parallel.quantities`), so

* ``tcp_force_map``          tau = J^T F = J_q^T J_x^-T F: the actuator torques (forces) with which
  the platform exerts the task-space force F on what it touches (to hold an external force,
  render its opposite; seed sec. 4, "Jacobian Matrix": the statics of the haptic device, what
  its control loop sends every millisecond);
* ``tcp_force_map_inverse``  F = J^-T tau = J_x^T J_q^-T tau: the force the platform exerts for
  given actuator efforts (J_q is diagonal, so no solve).

F is conjugate to the task coordinates p: a force along x, y, z (N) for a translational platform;
for a platform that also rotates, the components conjugate to roll, pitch and yaw are the
generalized moments of those angles (N m per rad of angle rate), not the moment vector.
Gravity and the device's inertia are not included (they are the dynamics quantities).
"""

from __future__ import annotations

import sympy

from symkin.ir.inputs import coordinate_input
from symkin.ir.quantity import Deriving, quantity
from symkin.ir.spec import FunctionSpec, InputSpec, OutputSpec, make_function
from symkin.parallel import determinant
from symkin.parallel.inputs import TASK_UNITS, task_input
from symkin.parallel.quantities import PARALLEL, square_constraint_jacobians


#: unit of the force component conjugate to each task coordinate
FORCE_UNITS = {"m": "N", "rad": "N*m"}


def force_input(d: Deriving) -> InputSpec:
    """The input ``F``: the task-space force conjugate to p (one component per task coordinate)."""
    names = tuple(f"F_{c}" for c in d.model.task_space)
    return InputSpec("F", "vector", tuple(sympy.Symbol(n, real=True) for n in names), names,
                     tuple(FORCE_UNITS[TASK_UNITS[c]] for c in d.model.task_space),
                     "task-space force on the platform, conjugate to p")


def _efforts_unit(d: Deriving) -> str:
    return "N*m (revolute actuators), N (prismatic)"


@quantity("tcp_force_map", "actuator efforts tau = J^T F with which the platform exerts the force F",
          mechanism=PARALLEL)
def _tcp_force_map(d: Deriving) -> FunctionSpec:
    J_x, J_q = square_constraint_jacobians(d, "the force map")
    F = sympy.Matrix(force_input(d).symbols)
    # J^T F = J_q^T J_x^-T F with J_x^-T = adj(J_x)^T / det(J_x)
    tau = J_q.T * (determinant.adjugate(J_x).T * F) / determinant.determinant(J_x)
    return make_function(
        d.model, "tcp_force_map", "Actuator efforts that render a task-space force.",
        "tau = J^T F = J_q^T J_x^-T F (virtual work: tau . qdot = F . pdot with pdot = J qdot; seed sec. 4): "
        "the efforts with which the platform exerts the force F on what it touches. Infinite at interior "
        "singularities (det J_x = 0). Gravity and inertia are not included.",
        [coordinate_input(d.model, "q"), task_input(d.model), force_input(d)],
        [OutputSpec("tau", sympy.ImmutableMatrix(tau), "actuator efforts", _efforts_unit(d), shape=(d.model.dof,))],
    )


@quantity("tcp_force_map_inverse", "task-space force F = J^-T tau of the actuator efforts tau", mechanism=PARALLEL)
def _tcp_force_map_inverse(d: Deriving) -> FunctionSpec:
    J_x, J_q = square_constraint_jacobians(d, "the force map")
    tau = coordinate_input(d.model, "tau")
    scaled = sympy.Matrix([s / J_q[i, i] for i, s in enumerate(tau.symbols)])  # J_q^-T tau (J_q diagonal)
    F = J_x.T * scaled
    return make_function(
        d.model, "tcp_force_map_inverse", "Task-space force of given actuator efforts.",
        "F = J^-T tau = J_x^T J_q^-T tau (J_q diagonal): the force the platform exerts when the actuators "
        "apply tau (seed sec. 4). Infinite at boundary singularities (a J_q,ii = 0).",
        [coordinate_input(d.model, "q"), task_input(d.model), tau],
        [OutputSpec("F", sympy.ImmutableMatrix(F), "task-space force conjugate to p",
                    ", ".join(sorted({FORCE_UNITS[TASK_UNITS[c]] for c in d.model.task_space})),
                    shape=(len(d.model.task_space),))],
    )
