"""Dynamic quantities of serial chains, listed in the derivation catalog (seed sec. 4.4).

=====================  ================================================================
``mass_matrix``        M(q), n x n (eqs. 8.31, 8.53)
``coriolis_matrix``    C(q, qd), n x n, Christoffel symbols: V = C qd, dM/dt - 2C skew
``coriolis_vector``    V(q, qd) = C qd, Coriolis and centrifugal terms (eq. 8.31)
``gravity_vector``     G(q) = du/dq (eq. 8.31); not available for models without gravity
``friction``           F_f(qd): viscous + Coulomb (sign or tanh) per joint (eq. 8.34)
``inverse_dynamics``   tau = M qdd + V + G + F_f (eq. 8.34)
``forward_dynamics``   qdd = M^-1 (tau - V - G - F_f), by an LDL^T solve
``tcp_force``          F = J^-T (M qdd + V + G) (eq. 8.37), square task Jacobians
``operational_space``  Mx, Vx, Gx (eqs. 8.61-8.64), square task Jacobians
``kinetic_energy``     k = 1/2 qd^T M qd (eq. 8.32)
``potential_energy``   u = -sum m g . c (eq. 8.32)
=====================  ================================================================

M is built by the composite-rigid-body algorithm and V, G and tau by the recursive
Newton-Euler algorithm (:mod:`symkin.dynamics.newton_euler`, O(n) terms for V, G and tau);
C = Christoffel symbols of that M.  The Lagrangian closed forms
(:mod:`symkin.dynamics.lagrange`: M = sum J^T I J, G = du/dq, V = C qd) are the tests'
reference (tests/lagrangian_reference.py), and the tests check that both routes agree.  The solves are in
:mod:`symkin.dynamics.linsolve`; each emitted function is a straight-line
:class:`~symkin.dynamics.program.Program` converted to sympy definitions.  A model whose
gravity is zero has no gravity terms anywhere (and no ``gravity_vector`` or
``potential_energy`` to emit); bodies without mass and inertia are dropped.
"""

from __future__ import annotations

from collections.abc import Sequence
import symengine as se
import sympy

from symkin.dynamics import lagrange, newton_euler
from symkin.dynamics.coupling import forces_on_coordinates, joint_rates, matrix_on_coordinates
from symkin.dynamics.bodies import BodyJacobians, body_jacobians
from symkin.dynamics.linsolve import ldl_solve, transpose_solve
from symkin.dynamics.program import Program, ProgramMap, se_matrix, se_vector
from symkin.errors import DerivationError
from symkin.dynamics.physical import require_physical
from symkin.dynamics.joint_forces import SPRINGS_IN_G, SPRINGS_IN_U, friction_graph, spring_energy, spring_torques
from symkin.ir.inputs import coordinate_input
from symkin.ir.quantity import Deriving, quantity
from symkin.ir.spec import FunctionSpec, InputSpec, OutputSpec, make_function
from symkin.kinematics.quantities import chain_frames, task_jacobian
from symkin.model import coordinates
from symkin.symengine_bridge import SympyConverter


Matrix = list[list[se.Basic]]

EFFORT_UNIT = "N*m (revolute), N (prismatic)"


def coordinate_symbols(d: Deriving, group: str) -> list[se.Symbol]:
    return se_vector(coordinates.symbols(d.model, group))


def function_spec(d: Deriving, name: str, summary: str, doc: str, groups: Sequence[str | InputSpec],
                  program: Program, outputs: Sequence[tuple[str, Sequence[se.Basic], tuple[int, ...], str, str]],
                  maps: Sequence[ProgramMap] = ()) -> FunctionSpec:
    """The spec of a function whose outputs are SymEngine values of ``program`` (its inputs: the coordinate
    ``groups`` by name, or any input specs), converted to sympy with the model's shared converter.

    Args:
        outputs: (name, row-major entries, shape, doc, unit) per output.
        maps: the column maps over ``program``'s values whose targets the outputs use, in the function's order.
    """
    model = d.model
    values = [e for out in outputs for e in out[1]]
    map_values = [v for m in maps for v in m.values()]
    definitions, flat = program.to_sympy(values + map_values, d[_sympy_converter])
    converted_maps, start = [], len(values)
    for m in maps:
        converted_maps.append(m.to_sympy(flat[start:start + len(m.values())]))
        start += len(m.values())
    specs, start = [], 0
    for out_name, entries, shape, out_doc, unit in outputs:
        size = len(entries)
        rows, cols = (shape + (1, 1))[:2] if len(shape) < 2 else shape
        matrix = sympy.ImmutableMatrix(rows, cols, flat[start:start + size])
        specs.append(OutputSpec(out_name, matrix, out_doc, unit, shape))
        start += size
    inputs = [g if isinstance(g, InputSpec) else coordinate_input(model, g) for g in groups]
    return make_function(model, name, summary, doc, inputs, specs, definitions, converted_maps)


def _flat(matrix: Matrix) -> list[se.Basic]:
    return [v for row in matrix for v in row]


# --------------------------------------------------------------------------- internal quantities

@quantity("sympy_converter", "SymEngine -> sympy conversion shared by the functions of one model", emitted=False,
          mechanism="any")
def _sympy_converter(d: Deriving) -> SympyConverter:
    """One memo for every function: programs that start alike (M, then dM/dq) convert their
    common assignments once."""
    symbols = [s for g in coordinates.GROUPS for s in coordinates.symbols(d.model, g)]
    symbols += [p.symbol for p in d.model.parameters]
    return SympyConverter({s.name: s for s in symbols})


@quantity("body_jacobians", "velocity Jacobians of the bodies at their centres of mass", emitted=False)
def body_jacobians_of(d: Deriving) -> tuple[BodyJacobians, ...]:
    require_physical(d.model)
    return body_jacobians(d.model, d[chain_frames])


@quantity("newton_euler_links", "links in their joint frames with spatial inertias (Newton-Euler)", emitted=False)
def newton_euler_links(d: Deriving) -> tuple[newton_euler.Link, ...]:
    require_physical(d.model)
    return newton_euler.chain_links(d.model)


@quantity("mass_matrix_graph", "M(q) by the composite-rigid-body algorithm, as a SymEngine graph", emitted=False)
def mass_matrix_graph(d: Deriving) -> Matrix:
    return matrix_on_coordinates(d.model, newton_euler.mass_matrix(d[newton_euler_links]))


@quantity("mass_matrix_partials", "dM/dq_k as SymEngine graphs", emitted=False)
def _mass_matrix_partials(d: Deriving) -> list[Matrix]:
    return lagrange.mass_matrix_partials(d[mass_matrix_graph], coordinate_symbols(d, "q"))


@quantity("gravity_graph", "gravity vector in the base frame, or None if zero", emitted=False)
def gravity_graph(d: Deriving) -> list[se.Basic] | None:
    if all(c == 0 for c in d.model.gravity):
        return None
    return se_vector(d.model.gravity)


@quantity("task_jacobian_graph", "task Jacobian J (square) as SymEngine expressions", emitted=False)
def _task_jacobian_graph(d: Deriving) -> Matrix:
    J = d[task_jacobian].outputs[0].expr
    if J.shape[0] != J.shape[1]:
        raise DerivationError(
            f"{d.model.name}: the task Jacobian is {J.shape[0]} x {J.shape[1]}; TCP forces and operational-space "
            f"dynamics need a square one (as many task coordinates as joints, {d.model.dof}); "
            "change 'task_space' of the model")
    return se_matrix(J)


def require_gravity(d: Deriving, name: str) -> None:
    """Refuse ``name`` (gravity's and the springs' term) for a model without both, where it is identically zero."""
    if all(c == 0 for c in d.model.gravity) and not d.model.springs:
        raise DerivationError(f"{d.model.name}: the model has no gravity, so {name} is identically zero and is "
                              f"not emitted; declare 'gravity:' in the model or remove '{name}' from the outputs")


class BoundTerms:
    """The terms of eq. 8.34 bound into one program, always in the same order (M, dM/dq, V, G, F_f),
    so that the programs of different functions start alike and share their conversion.

    M comes from the composite-rigid-body algorithm, everything without M from one Newton-Euler
    pass (:func:`~symkin.dynamics.newton_euler.inverse_dynamics`).
    """

    def __init__(self, d: Deriving, program: Program):
        self.d, self.program = d, program
        self.n = d.model.dof

    def mass_matrix(self) -> Matrix:
        values = self.program.bind(_flat(self.d[mass_matrix_graph]))
        return [values[i * self.n:(i + 1) * self.n] for i in range(self.n)]

    def partials(self) -> list[Matrix]:
        """dM/dq_k as partials[k][i][j]."""
        n = self.n
        values = self.program.bind([v for dM in self.d[_mass_matrix_partials] for v in _flat(dM)])
        return [[values[k * n * n + i * n:k * n * n + (i + 1) * n] for i in range(n)] for k in range(n)]

    def newton_euler(self, velocity: bool, acceleration: bool, gravity: bool) -> list[se.Basic]:
        """The Newton-Euler torques of the chosen terms (M qdd, V, G: gravity and the springs), bound."""
        d = self.d
        qd, qdd = (joint_rates(d.model, g) if use else None for g, use in (("qd", velocity), ("qdd", acceleration)))
        torques = forces_on_coordinates(d.model, newton_euler.inverse_dynamics(
            d[newton_euler_links], qd, qdd, d[gravity_graph] if gravity else None))
        return self._plus_springs(torques) if gravity else self.program.bind(torques)

    def coriolis_vector(self) -> list[se.Basic]:
        return self.newton_euler(velocity=True, acceleration=False, gravity=False)

    def gravity_vector(self) -> list[se.Basic] | None:
        """G(q): gravity's torques plus the springs', None where both are absent."""
        if (weight := self.d[gravity_graph]) is None and not self.d.model.springs:
            return None
        return self._plus_springs([se.Integer(0)] * self.n if weight is None else forces_on_coordinates(
            self.d.model, newton_euler.gravity_torques(self.d[newton_euler_links], weight)))

    def _plus_springs(self, torques: list[se.Basic]) -> list[se.Basic]:
        """``torques`` + the springs' forces, bound (derived only where there are springs: the manifest lists them)."""
        springs = self.d[spring_torques] if self.d.model.springs else None
        return self.program.bind(torques if springs is None else [t + s for t, s in zip(torques, springs)])

    def friction(self) -> list[se.Basic] | None:
        return self.d[friction_graph]

    def torques(self, acceleration: bool, with_friction: bool) -> list[se.Basic]:
        """M qdd (if ``acceleration``) + V + G (+ F_f): eq. 8.34, in one Newton-Euler pass."""
        terms = self.newton_euler(velocity=True, acceleration=acceleration, gravity=True)
        friction = self.friction() if with_friction else None
        return terms if friction is None else [a + b for a, b in zip(terms, friction)]


# --------------------------------------------------------------------------- emitted functions

@quantity("mass_matrix", "mass matrix M(q) (n x n, symmetric positive definite)")
def _mass_matrix(d: Deriving) -> FunctionSpec:
    program = Program()
    M = _flat(BoundTerms(d, program).mass_matrix())
    return function_spec(
        d, "mass_matrix", "Joint-space mass matrix.",
        "M(q) = sum over bodies of m Jv^T Jv + Jw^T I Jw with the velocity Jacobians at the centres of mass "
        "(seed eqs. 8.31-8.33; 2-DoF example eq. 8.53), evaluated by the composite-rigid-body algorithm "
        "(Featherstone 2008, table 6.2).",
        ["q"], program, [("M", M, (d.model.dof, d.model.dof), "symmetric positive definite mass matrix", "")])


@quantity("coriolis_matrix", "Coriolis matrix C(q, qd) from Christoffel symbols (n x n)")
def _coriolis_matrix(d: Deriving) -> FunctionSpec:
    n = d.model.dof
    program = Program()
    C = lagrange.coriolis_matrix(BoundTerms(d, program).partials(), coordinate_symbols(d, "qd"))
    return function_spec(
        d, "coriolis_matrix", "Coriolis matrix from the Christoffel symbols of M.",
        "C_ij = sum_k c_ijk qd_k, c_ijk = 1/2 (dM_ij/dq_k + dM_ik/dq_j - dM_jk/dq_i); V = C qd and "
        "dM/dt - 2C is skew-symmetric.",
        ["q", "qd"], program, [("C", _flat(C), (n, n), "Coriolis matrix", "")])


@quantity("coriolis_vector", "Coriolis and centrifugal vector V(q, qd) = C qd (n)")
def _coriolis_vector(d: Deriving) -> FunctionSpec:
    program = Program()
    V = BoundTerms(d, program).coriolis_vector()
    return function_spec(
        d, "coriolis_vector", "Coriolis and centrifugal torques.",
        "V(q, qd) = C(q, qd) qd = dM/dt qd - 1/2 d(qd^T M qd)/dq (seed eq. 8.31; 2-DoF example eq. 8.54), "
        "evaluated by a recursive Newton-Euler pass without gravity and acceleration (seed sec. 4.4).",
        ["q", "qd"], program, [("V", V, (d.model.dof,), "Coriolis and centrifugal joint torques", EFFORT_UNIT)])


@quantity("gravity_vector", "gravity vector G(q) = du/dq (n)")
def _gravity_vector(d: Deriving) -> FunctionSpec:
    require_gravity(d, "gravity_vector")
    program = Program()
    G = BoundTerms(d, program).gravity_vector()
    assert G is not None, "require_gravity refuses a model without gravity"
    return function_spec(
        d, "gravity_vector", "Gravity torques.",
        "G(q) = du/dq with u = -sum m g . c over the bodies (seed eq. 8.31; 2-DoF example eq. 8.54), "
        "evaluated by a recursive Newton-Euler pass at rest (seed sec. 4.4)." + SPRINGS_IN_G * bool(d.model.springs),
        ["q"], program, [("G", G, (d.model.dof,), "joint torques that hold the arm against gravity", EFFORT_UNIT)])


@quantity("friction", "joint friction F_f(qd): viscous + Coulomb (n)")
def _friction(d: Deriving) -> FunctionSpec:
    F = d[friction_graph]
    if F is None:
        raise DerivationError(f"{d.model.name}: the model declares no friction; add a 'friction:' section "
                              "or remove 'friction' from the outputs")
    program = Program()
    return function_spec(
        d, "friction", "Joint friction torques.",
        "F_f = viscous qd + coulomb sign(qd) per joint (seed eq. 8.34), or coulomb tanh(qd / v_s) where the "
        "model gives a smoothing velocity v_s; with levels c+ and c- for the two directions, "
        "(c+ + c-)/2 s + (c+ - c-)/2 s^2.",
        ["qd"], program, [("F_f", F, (d.model.dof,), "friction torques opposing the motion", EFFORT_UNIT)])


@quantity("inverse_dynamics", "inverse dynamics tau = M qdd + V + G + F_f (n)")
def inverse_dynamics_spec(d: Deriving) -> FunctionSpec:
    n = d.model.dof
    program = Program()
    tau = BoundTerms(d, program).torques(acceleration=True, with_friction=True)
    return function_spec(
        d, "inverse_dynamics", "Inverse dynamics: joint torques for a motion.",
        "tau = M(q) qdd + V(q, qd) + G(q) + F_f(qd) (seed eq. 8.34), by the recursive Newton-Euler algorithm "
        "(seed sec. 4.4, Luh-Walker-Paul; O(n) operations).",
        ["q", "qd", "qdd"], program, [("tau", tau, (n,), "joint torques (revolute) or forces (prismatic)",
                                       EFFORT_UNIT)])


@quantity("forward_dynamics", "forward dynamics qdd = M^-1 (tau - V - G - F_f) (n)", solves_with="mass_matrix")
def _forward_dynamics(d: Deriving) -> FunctionSpec:
    n = d.model.dof
    program = Program()
    terms = BoundTerms(d, program)
    M = terms.mass_matrix()
    rhs = [[t - b] for t, b in zip(coordinate_symbols(d, "tau"), terms.torques(acceleration=False, with_friction=True))]
    qdd = [row[0] for row in ldl_solve(program, M, rhs)]
    return function_spec(
        d, "forward_dynamics", "Forward dynamics: joint accelerations under given torques.",
        "qdd = M(q)^-1 (tau - V(q, qd) - G(q) - F_f(qd)) (seed eq. 8.34 solved for qdd), by a straight-line "
        "LDL^T factorization of the symmetric positive definite M.",
        ["q", "qd", "tau"], program, [("qdd", qdd, (n,), "joint accelerations", "rad/s^2 (revolute), m/s^2 "
                                                                                 "(prismatic)")])


@quantity("tcp_force", "TCP force F = J^-T (M qdd + V + G) (m, square task Jacobian)", solves_with="jacobian")
def _tcp_force(d: Deriving) -> FunctionSpec:
    n = d.model.dof
    J = d[_task_jacobian_graph]
    program = Program()
    rhs = [[b] for b in BoundTerms(d, program).torques(acceleration=True, with_friction=False)]
    values = program.bind(_flat(J))
    J = [values[i * n:(i + 1) * n] for i in range(n)]
    F = [row[0] for row in transpose_solve(program, J, rhs)]
    components = ", ".join(d.model.task_space)
    return function_spec(
        d, "tcp_force", "Force (wrench) at the TCP that produces a joint motion.",
        f"F = J^-T (M qdd + V + G) (seed eqs. 8.36-8.37, 2-DoF example eqs. 8.59-8.60), task components "
        f"[{components}]; J^-T by the adjugate for up to 3 task coordinates, else by a Gram-Schmidt QR "
        "(no pivoting needed).",
        ["q", "qd", "qdd"], program, [("F", F, (n,), f"TCP force components [{components}]", "N, N*m")])


def task_space_dynamics(program: Program, J_graph: Matrix, coordinates: Sequence[se.Basic], rates: Sequence[se.Basic],
                        M: Matrix, V: list[se.Basic], G: list[se.Basic] | None
                        ) -> tuple[Matrix, list[se.Basic], list[se.Basic] | None]:
    """(Mx, Vx, Gx) of the equations M qdd + V + G = J^T F seen at x, xd = J qd (seed eqs. 8.61-8.64; Craig sec.
    6.11): Mx = J^-T M J^-1, Vx = J^-T V - Mx dJ/dt qd, Gx = J^-T G (None without G).

    ``J_graph`` is the square Jacobian in ``coordinates`` (unbound), ``rates`` their rates, M, V, G bound in
    ``program``; dJ/dt qd = sum_k dJ/dq_k qd_k qd, and J^-T [M | V | G] comes from one
    :func:`~symkin.dynamics.linsolve.transpose_solve`, Mx = J^-T (J^-T M)^T (M symmetric).
    """
    n = len(J_graph)
    Jdot_rates = [sum((se.diff(J_graph[i][j], coordinates[k]) * rates[k] * rates[j] for j in range(n)
                       for k in range(n)), se.Integer(0)) for i in range(n)]
    values = program.bind(_flat(J_graph) + Jdot_rates)
    J = [values[i * n:(i + 1) * n] for i in range(n)]
    jdot = values[n * n:]
    first = transpose_solve(program, J, [M[i] + [V[i]] + ([G[i]] if G is not None else []) for i in range(n)])
    Mx = transpose_solve(program, J, [[first[j][i] for j in range(n)] for i in range(n)])
    Mx = [[Mx[i][j] if i >= j else Mx[j][i] for j in range(n)] for i in range(n)]  # exactly symmetric
    Vx = [first[i][n] - sum((Mx[i][k] * jdot[k] for k in range(n)), se.Integer(0)) for i in range(n)]
    return Mx, Vx, None if G is None else [first[i][n + 1] for i in range(n)]


@quantity("operational_space", "operational-space dynamics Mx, Vx, Gx (square task Jacobian)",
          solves_with="jacobian")
def _operational_space(d: Deriving) -> FunctionSpec:
    n = d.model.dof
    J_graph = d[_task_jacobian_graph]  # refuses a task Jacobian that is not square before any dynamics
    program = Program()
    terms = BoundTerms(d, program)
    M = terms.mass_matrix()
    V = terms.coriolis_vector()
    G = terms.gravity_vector()
    Mx, Vx, Gx = task_space_dynamics(program, J_graph, coordinate_symbols(d, "q"), coordinate_symbols(d, "qd"),
                                     M, V, G)
    outputs = [("Mx", _flat(Mx), (n, n), "operational-space mass matrix J^-T M J^-1", ""),
               ("Vx", Vx, (n,), "operational-space Coriolis and centrifugal force J^-T (V - M J^-1 dJ/dt qd)", "")]
    if Gx is not None:
        outputs.append(("Gx", Gx, (n,), "operational-space gravity force J^-T G", ""))
    components = ", ".join(d.model.task_space)
    return function_spec(
        d, "operational_space", "Operational-space dynamics F = Mx xdd + Vx + Gx.",
        f"Mx = J^-T M J^-1, Vx = J^-T (V - M J^-1 dJ/dt qd), Gx = J^-T G (seed eqs. 8.61-8.64; Craig sec. "
        f"6.11) for the task components [{components}].  Gx is omitted for a model without gravity.",
        ["q", "qd"], program, outputs)


@quantity("kinetic_energy", "kinetic energy k(q, qd) = 1/2 qd^T M qd (scalar)")
def _kinetic_energy(d: Deriving) -> FunctionSpec:
    program = Program()
    (k,) = program.bind([lagrange.kinetic_energy(BoundTerms(d, program).mass_matrix(), coordinate_symbols(d, "qd"))])
    return function_spec(
        d, "kinetic_energy", "Kinetic energy.", "k = 1/2 qd^T M(q) qd (seed eq. 8.32).",
        ["q", "qd"], program, [("k", [k], (), "kinetic energy of all bodies", "J")])


@quantity("potential_energy", "potential energy u(q) = -sum m g . c (scalar)")
def _potential_energy(d: Deriving) -> FunctionSpec:
    require_gravity(d, "potential_energy")
    program = Program()
    weight = d[gravity_graph]
    (u,) = program.bind([(lagrange.potential_energy(d[body_jacobians_of], weight) if weight is not None
                          else se.Integer(0)) + spring_energy(d)])
    return function_spec(
        d, "potential_energy", "Gravitational potential energy.",
        "u = -sum m g . c over the bodies, zero with every centre of mass at the base origin (seed eq. 8.32)."
        + SPRINGS_IN_U * bool(d.model.springs),
        ["q"], program, [("u", [u], (), "potential energy", "J")])
