"""The dynamics regressor of a serial chain: tau = Y(q, qd, qdd) pi, linear in the standard parameters.

Every term of the inverse dynamics tau = M qdd + V + G + F_f (seed eq. 8.34) is linear in the mass
properties of the links and in the drives' constants (Atkeson, An and Hollerbach, "Estimation of
inertial parameters of manipulator loads and links", IJRR 5(3), 1986; Khalil and Dombre, *Modeling,
Identification and Control of Robots*, 2002, sec. 12.3), so tau = Y pi with

* per link (a joint's moving link, in the joint's Newton-Euler frame F_i of
  :mod:`symkin.dynamics.newton_euler`, about its origin): the ten standard inertial parameters in
  Pinocchio's order (``Inertia::toDynamicParameters``)::

      m, m c_x, m c_y, m c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz

  with I = I_c + m ([c]^T [c]) the rotational inertia about the origin of F_i (parallel axes);
* per joint: the drive's reflected rotor inertia I_a (tau_j += I_a qdd_j), viscous friction f_v
  (f_v qd_j), Coulomb friction f_c (f_c sign(qd_j), or f_c tanh(qd_j / v_s) where the model smooths
  it) and an offset f_o (a constant torque: sensor offsets, the asymmetric part (c+ - c-)/2 of a
  direction-dependent Coulomb level while the joint moves).

Y is derived exactly: tau is linear and homogeneous in pi, so column k of Y is the inverse dynamics with
pi = e_k (the recursive Newton-Euler pass with one link carrying one unit parameter and every other
link massless; Atkeson et al. 1986 build the same columns per link), nothing approximated.  The
links' frames F_i coincide with the link frames of a URDF (whose joint frame is the child link's),
so a URDF model's parameters are Pinocchio's in the same order; a coupled joint's columns reach the
coordinates through A^T (:mod:`symkin.dynamics.coupling`).

The energy regressor (Gautier and Khalil, "On the identification of the inertial parameters of robots",
IEEE CDC 1988): the energy h = k + u is linear in the same pi, h = Y_e(q, qd) pi, and dh/dt = qd . (tau -
F_f) along any motion, so pi can be identified from the power without accelerations.  A link whose joint
frame's origin moves with v and turns with w (both in F_i) has k = 1/2 m |v|^2 + (m c) . (v x w) +
1/2 w^T I w about that origin, and u = -g . (m p + R (m c)) with its pose (R, p) in the base frame: per
link the columns 1/2 |v|^2 - g . p (m), (v x w)_k - (R^T g)_k (m c_k) and 1/2 w_k^2 or w_k w_l (I_kl),
the drive's 1/2 qd_j^2 (I_a) and no friction column (friction does no work on the energy).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
import symengine as se

from symkin.dynamics import newton_euler
from symkin.dynamics.bodies import ZERO3
from symkin.model import joint_kinds
from symkin.dynamics.base_parameters import BaseParameters, base_parameters, require_exact_constants
from symkin.dynamics.coupling import forces_on_coordinates, joint_rates
from symkin.dynamics.parameter_names import DRIVE, INERTIAL
from symkin.dynamics.program import Program, cross, dot, mat_vec
from symkin.dynamics.quantities import gravity_graph, newton_euler_links
from symkin.dynamics.quantities import function_spec
from symkin.ir.quantity import Deriving, quantity
from symkin.ir.spec import FunctionSpec
from symkin.errors import DerivationError
from symkin.model.schema import Friction, Model




def parameter_names(model: Model) -> tuple[str, ...]:
    """The names of the standard parameters pi, in the order of Y's columns: ``<link>.<INERTIAL>`` for
    every moving link in joint order, then ``<joint>.<DRIVE>`` for every joint."""
    return (tuple(f"{j.link}.{p}" for j in model.joints for p in INERTIAL)
            + tuple(f"{j.name}.{p}" for j in model.joints for p in DRIVE))


def _unit_inertias() -> list[newton_euler.SpatialInertia]:
    """The spatial inertia of each standard parameter set to one and the others to zero, in INERTIAL order."""
    zero, one = se.Integer(0), se.Integer(1)

    def unit(row: int, col: int) -> list[list[se.Basic]]:
        return [[one if {r, c} == {row, col} else zero for c in range(3)] for r in range(3)]

    vectors = [[one if k == axis else zero for k in range(3)] for axis in range(3)]
    none = [[zero] * 3 for _ in range(3)]
    return ([newton_euler.SpatialInertia(one, [zero] * 3, none)]
            + [newton_euler.SpatialInertia(zero, v, none) for v in vectors]
            + [newton_euler.SpatialInertia(zero, [zero] * 3, unit(r, c))
               for r, c in ((0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2))])


def _coulomb_shape(friction: Friction | None, v: se.Basic) -> se.Basic:
    """sign(v), or tanh(v / v_s) where the model smooths the Coulomb friction of the joint."""
    if friction is None or friction.smoothing_velocity is None:
        return se.sign(v)
    return se.tanh(v / se.sympify(friction.smoothing_velocity))


def drive_columns(friction: Friction | None, qd: se.Basic, qdd: se.Basic) -> tuple[se.Basic, ...]:
    """A joint's torque per unit of each of its DRIVE parameters: qdd (I_a), qd (f_v), the Coulomb shape (f_c), 1 (f_o)."""
    return (qdd, qd, _coulomb_shape(friction, qd), se.Integer(1))


def drive_values(friction: Friction | None, armature: se.Basic) -> list[se.Basic]:
    """A joint's DRIVE parameters in the model: reflected rotor inertia, viscous, Coulomb (the mean of the two
    directions' levels) and offset (half their difference: the torque while the joint moves, whatever its sign)."""
    if friction is None:
        return [se.sympify(armature), se.Integer(0), se.Integer(0), se.Integer(0)]
    negative = friction.coulomb_negative if friction.asymmetric else friction.coulomb
    return [se.sympify(armature), se.sympify(friction.viscous), se.sympify((friction.coulomb + negative) / 2),
            se.sympify((friction.coulomb - negative) / 2)]


def regressor_rows(model: Model, links: Sequence[newton_euler.Link],
                   gravity: Sequence[se.Basic] | None) -> list[list[se.Basic]]:
    """Y (coordinates x parameters) with tau = Y pi, as SymEngine expressions (see the module docstring).

    tau is linear and homogeneous in pi, so column k is tau with pi = e_k: the links' motions once, then per
    column the wrench of one link carrying one unit parameter carried inward, and the drive terms' own factors.
    """
    qd, qdd = joint_rates(model, "qd"), joint_rates(model, "qdd")
    motions = newton_euler.link_motions(links, qd, qdd, gravity)  # the same for every column: once
    zero = [se.Integer(0)] * 3
    columns: list[list[se.Basic]] = []
    for i in range(len(links)):
        for inertia in _unit_inertias():
            wrenches = [(zero, zero)] * len(links)
            wrenches[i] = newton_euler.body_wrench(inertia, motions[i])
            columns.append(newton_euler.joint_torques(links, wrenches, None))
    friction = {f.joint: f for f in model.friction}
    for j, joint in enumerate(model.joints):
        terms = drive_columns(friction.get(joint.name), qd[j], qdd[j])
        columns += [[term if row == j else se.Integer(0) for row in range(len(links))] for term in terms]
    on_coordinates = [forces_on_coordinates(model, column) for column in columns]
    return [list(row) for row in zip(*on_coordinates)]


def energy_row(model: Model, links: Sequence[newton_euler.Link], gravity: Sequence[se.Basic] | None
               ) -> list[se.Basic]:
    """Y_e with k + u = Y_e pi (see the module docstring), outward from the base as
    :func:`newton_euler.link_motions`: per frame F_i its w, v and the gravity g_i = R^T g in its own coordinates
    (g_i = E g_p), and g . p of its origin (g . p_p + g_p . r), so no rotation into the base is formed."""
    zero, half = [se.Integer(0)] * 3, se.Rational(1, 2)
    g = list(gravity) if gravity is not None else zero
    qd = joint_rates(model, "qd")
    frames: list[tuple[list[se.Basic], se.Basic, list[se.Basic], list[se.Basic]]] = []
    row: list[se.Basic] = []
    for i, link in enumerate(links):
        g_p, height_p, w_p, v_p = (g, se.Integer(0), zero, zero) if link.parent < 0 else frames[link.parent]
        E, r = link.rotation, link.origin  # F_p -> F_i coordinates; the origin of F_i in F_p
        turning, sliding = joint_kinds.motion_subspace(link.type, link.axis, ZERO3)  # the joint's (w, v) per rate
        w = [a + c * qd[i] for a, c in zip(mat_vec(E, w_p), turning)]
        v = [a + c * qd[i] for a, c in zip(mat_vec(E, [a + b for a, b in zip(v_p, cross(w_p, r))]), sliding)]
        g_i, height = mat_vec(E, g_p), height_p + dot(g_p, r)  # R^T g and g . p
        frames.append((g_i, height, w, v))
        row += [half * dot(v, v) - height] + [m - gl for m, gl in zip(cross(v, w), g_i)]
        row += [half * w[0] * w[0], w[0] * w[1], half * w[1] * w[1], w[0] * w[2], w[1] * w[2], half * w[2] * w[2]]
    for rate in qd:
        row += [half * rate * rate, se.Integer(0), se.Integer(0), se.Integer(0)]
    return row


def standard_parameters(model: Model, links: Sequence[newton_euler.Link]) -> list[se.Basic]:
    """The model's own pi: its links' summed bodies in F_i, its drives' reflected inertia and friction."""
    values: list[se.Basic] = []
    for link in links:
        body = link.inertia
        if body is None:
            values += [se.Integer(0)] * 10
            continue
        J = body.rotational
        values += [body.mass, *body.moment, J[0][0], J[0][1], J[1][1], J[0][2], J[1][2], J[2][2]]
    friction = {f.joint: f for f in model.friction}
    for joint, link in zip(model.joints, links):
        values += drive_values(friction.get(joint.name), link.armature)
    return values


@quantity("regressor_graph", "the regressor Y as SymEngine rows (coordinates x standard parameters)", emitted=False)
def regressor_graph(d: Deriving) -> list[list[se.Basic]]:
    require_no_springs(d.model)
    return regressor_rows(d.model, d[newton_euler_links], d[gravity_graph])


def require_no_springs(model: Model) -> None:
    """Refuse the regressors of a model with joint springs: their forces k (theta - theta_0) are not among the
    standard parameters' columns, so Y pi would not be the model's tau."""
    if model.springs:
        joints = ", ".join(s.joint for s in model.springs)
        raise DerivationError(f"{model.name}: the joints {joints} carry springs ('springs:'), whose forces are not "
                              "in the dynamic parameters' regressors; identify the model without its springs, or "
                              "subtract their torques k (theta - theta_0) from the measured ones first")


@quantity("base_parameters", "the base parameters pi_b = K pi and the columns of Y_b, exact", emitted=False)
def base_parameters_of(d: Deriving) -> BaseParameters:
    links = d[newton_euler_links]
    require_exact_constants(d.model, [e for link in links for row in link.rotation for e in row]
                            + [e for link in links for e in link.origin])
    return base_parameters(d.model, d[regressor_graph], parameter_names(d.model))


@quantity("regressor", "dynamics regressor Y(q, qd, qdd) with tau = Y pi, and the model's standard parameters pi")
def regressor(d: Deriving) -> FunctionSpec:
    """One function giving Y (coordinates x parameters) and the model's pi, whose names are both outputs'
    elements (:func:`parameter_names`)."""
    model = d.model
    program = Program()
    Y = [program.bind(row) for row in d[regressor_graph]]
    names = parameter_names(model)
    return _with_standard_parameters(
        d, "regressor", "Dynamics regressor: tau = Y(q, qd, qdd) pi, linear in the standard parameters.",
        "Column k of Y is the Newton-Euler inverse dynamics with friction (seed eq. 8.34) at pi = e_k, exact; pi "
        "holds per link m, m c_x, m c_y, m c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz (about the joint frame's "
        "origin, Pinocchio's order) and per joint the reflected rotor inertia I_a and the friction f_v, f_c, f_o "
        "(tau += I_a qdd + f_v qd + f_c sign(qd) + f_o); Y pi equals inverse_dynamics (with Coulomb levels that "
        "differ by direction, while the joints move). The names of pi are the outputs' elements in the manifest.",
        ["q", "qd", "qdd"], program,
        ("Y", [e for row in Y for e in row], (model.dof, len(names)),
         "regressor: column k is the torque per unit of parameter k", ""),
        "the model's standard parameters (kg, kg*m, kg*m^2; drives: kg*m^2 or kg, N*m*s/rad or N*s/m, N*m or N)")


@quantity("energy_regressor", "energy regressor Y_e(q, qd) with k + u = Y_e pi, and the model's standard parameters pi")
def energy_regressor(d: Deriving) -> FunctionSpec:
    """Y_e and the model's pi, named as :func:`regressor`'s (the module docstring has the columns)."""
    program = Program()
    require_no_springs(d.model)
    Y_e = program.bind(energy_row(d.model, d[newton_euler_links], d[gravity_graph]))
    return _with_standard_parameters(
        d, "energy_regressor", "Energy regressor: k + u = Y_e(q, qd) pi, linear in the standard parameters.",
        "The kinetic and potential energy of every link about its joint frame's origin (Gautier and Khalil 1988) "
        "and of every drive's reflected rotor inertia, per unit of each standard parameter (the columns of "
        "regressor; the friction columns are 0); Y_e pi equals kinetic_energy + potential_energy, and "
        "d(Y_e pi)/dt = qd . (tau - F_f) along a motion: identification from the power, without accelerations.",
        ["q", "qd"], program, ("Y_e", Y_e, (len(Y_e),), "energy per unit of each standard parameter", ""),
        "the model's standard parameters (as regressor's)")


def _with_standard_parameters(d: Deriving, name: str, summary: str, doc: str, inputs: list[str], program: Program,
                              first: tuple[str, Sequence[se.Basic], tuple[int, ...], str, str],
                              pi_doc: str) -> FunctionSpec:
    """The function of outputs ``first`` (a function_spec output tuple) and the model's standard parameters pi, the
    elements of both named by :func:`parameter_names` (the manifest's names of Y's columns and of pi)."""
    names = parameter_names(d.model)
    pi = program.bind(standard_parameters(d.model, d[newton_euler_links]))
    spec = function_spec(d, name, summary, doc, inputs, program, [first, ("pi", pi, (len(names),), pi_doc, "")])
    outputs = tuple(dataclasses.replace(o, elements=names) for o in spec.outputs)
    return dataclasses.replace(spec, outputs=outputs)


@quantity("base_regressor", "base regressor Y_b (full column rank) with tau = Y_b pi_b, and the model's pi_b = K pi")
def base_regressor(d: Deriving) -> FunctionSpec:
    """Y_b and the model's pi_b, named by the outputs' elements (the base parameters' names).  K, constant, is not an
    output (a batch would repeat it per state): its rows are the equations in the function's doc, and
    ``Derivation["base_parameters"].combinations``."""
    model = d.model
    found = d[base_parameters_of]
    Y = d[regressor_graph]
    program = Program()
    Y_b = [program.bind([row[b] for b in found.base]) for row in Y]
    pi = standard_parameters(model, d[newton_euler_links])
    pi_b = program.bind([se.Add(*(se.sympify(k) * p for k, p in zip(row, pi) if k != 0))
                         for row in found.combinations])
    rank = len(found.base)
    spec = function_spec(
        d, "base_regressor", "Base regressor: tau = Y_b(q, qd, qdd) pi_b, Y_b of full column rank.",
        "The linearly independent columns of the regressor (Gautier and Khalil 1990), found exactly by a rational "
        "echelon form over random rational states (symkin.dynamics.base_parameters); Y = Y_b K and pi_b = K pi "
        "with K exact for every value of the model's parameters: " + "; ".join(found.equations()) + ".",
        ["q", "qd", "qdd"], program,
        [("Y_b", [e for row in Y_b for e in row], (model.dof, rank), "base regressor: full column rank", ""),
         ("pi_b", pi_b, (rank,), "the model's base parameters (the identifiable combinations)", "")])
    outputs = tuple(dataclasses.replace(o, elements=found.base_names) for o in spec.outputs)
    return dataclasses.replace(spec, outputs=outputs)
