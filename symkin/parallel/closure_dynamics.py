"""Dynamics of legs without the distance form, over all joint variables and the platform pose (issue 31).

Legs of any topology (the dual SCARA of docs/model-format.md) have no closed-form ik or fk, so their dynamics
cannot be reduced symbolically through J = J_x^-1 J_q as the distance form's is (:mod:`symkin.parallel.dynamics`).
Instead, the Lagrangian is written in all the mechanism's variables z = (q, s, p) - the actuated and passive joint
variables of every leg and the platform's task coordinates - where every body's motion is explicit:

* a link moved by leg joint j (``bodies.links``, com c and inertia I in the frame after j's motion, walked from
  the leg's base, :func:`symkin.parallel.legs.walk`) has the velocity Jacobian columns w x (c_w - o) (a rotation
  about the base-frame axis w through o) or w (a translation along w), and the angular columns w (or 0), for
  every elementary motion of its leg up to j; it adds m Jv^T Jv + Jw^T (R I R^T) Jw to M_z in its leg's rows;
* the platform adds M_p(p) (:func:`symkin.parallel.inertia.platform_side`) in the p rows;
* each actuator's rotor adds gear_ratio^2 J_rotor on its q diagonal;
* u(z) = -g . (sum of m c) over the links, plus the platform's u_p(p).

``closure_dynamics`` returns, at (q, s, p) and rates zd = (qd, sd, pd):

    M_z(z),    h_z = V_z + G_z  (V_z = C_z(z, zd) zd from the Christoffel symbols of M_z, G_z = du/dz),   u(z),
    gamma = d/dt (Phi_z) zd = sum_i d(Phi_z zd)/dz_i zd_i,

with Phi_z = [Phi_q Phi_s Phi_p] the closure's Jacobians (:mod:`symkin.parallel.closure`), so that every motion
of the closed mechanism satisfies Phi_z zdd + gamma = 0.  The runtime eliminates the constraint forces with the
velocities the closure allows, zd = W qd (d'Alembert: they do no work on them),
M = W^T M_z W and tau = W^T (M_z zdd + h_z) (:mod:`symkin.runtime.closure_dynamics`): exact at an assembled state,
with W from the closure's Jacobians by a linear solve, as the DELTA's J_x^-1 (no symbolic inverse).
"""

from __future__ import annotations

import dataclasses

import symengine as se
import sympy

from symkin.errors import DerivationError
from symkin.ir.inputs import coordinate_input
from symkin.ir.quantity import Deriving, quantity
from symkin.ir.spec import FunctionSpec, InputSpec, OutputSpec, make_function
from symkin.model import coordinates, joint_kinds
from symkin.model.schema import Model, ParallelBodies
from symkin.dynamics.parameter_names import DRIVE, INERTIAL
from symkin.dynamics.regressor import drive_columns, drive_values
from symkin.geometry import skew
from symkin.parallel.inertia import Triple, about_origin, platform_side, standard_values, unit_triples
from symkin.parallel.inputs import TASK_UNITS, passive_input, passive_symbols, passive_variables, task_input, task_symbols
from symkin.parallel.legs import LegChain
from symkin.parallel.quantities import (PARALLEL, ParallelStructure, actuated_input, closure_jacobian_matrices, jacobian,
                                        parallel_structure, reduced_legs)


#: Per coordinate group of z's rates: the names of the passive and the platform inputs, the unit's time power, a word.
_RATE_GROUPS = {"qd": ("sd", "pd", "/s", "velocities"), "qdd": ("sdd", "pdd", "/s^2", "accelerations")}


def rate_symbols(symbols: tuple[sympy.Symbol, ...], group: str = "qd") -> tuple[sympy.Symbol, ...]:
    """The rate of each coordinate symbol in ``group``, named as the coordinates' (``x`` -> ``x_d``, ``x_dd``)."""
    return tuple(sympy.Symbol(coordinates.symbol_name(group, s.name), real=True) for s in symbols)


def rate_inputs(model: Model, group: str = "qd") -> tuple[InputSpec, InputSpec, InputSpec]:
    """The inputs qd, sd, pd (``group`` "qd") or qdd, sdd, pdd ("qdd")."""
    passive_name, platform_name, per_time, word = _RATE_GROUPS[group]
    passive = passive_variables(model)
    s = InputSpec(passive_name, "vector", rate_symbols(passive_symbols(model), group),
                  tuple(name for name, _ in passive),
                  tuple(("rad" if rotation else "m") + per_time for _, rotation in passive), f"passive joint {word}")
    p = InputSpec(platform_name, "vector", rate_symbols(task_symbols(model), group), model.task_space,
                  tuple(f"{TASK_UNITS[c]}{per_time}" for c in model.task_space), f"task {word} of the platform (TCP)")
    return coordinate_input(model, group), s, p


def _link_mass_matrix(body: Triple, chain: LegChain, joint: int, index: dict[sympy.Symbol, int], size: int
                      ) -> tuple[sympy.Matrix, sympy.Matrix]:
    """(M contribution over z, m o + R h) of the link moved by the leg's joint ``joint``, its body given about that
    link's frame (origin o, axes R) as (m, h, I_o): k = 1/2 m |v_o|^2 + v_o . (w x R h) + 1/2 w^T R I_o R^T w, so
    M = m Jv^T Jv + A + A^T + Jw^T R I_o R^T Jw with A = Jv^T [R h]x^T Jw (Jv, Jw: the origin's velocity and the
    link's angular velocity per unit rate of each variable of z)."""
    mass, first_moment, inertia = body
    frame = chain.links[joint]
    R = sympy.Matrix(frame.R)
    origin = sympy.Matrix(frame.p)
    moved = sum(len(j.variables) for j in chain.leg.joints[:joint + 1])
    Jv, Jw = sympy.zeros(3, size), sympy.zeros(3, size)
    for motion in chain.motions[:moved]:
        linear, angular = joint_kinds.twist_column(motion.rotation, motion.direction, motion.point, origin)
        Jv[:, index[motion.variable]], Jw[:, index[motion.variable]] = linear, angular
    r = R * first_moment
    A = Jv.T * skew(r).T * Jw
    return mass * Jv.T * Jv + A + A.T + Jw.T * (R * inertia * R.T) * Jw, mass * origin + r


def _variables(model: Model) -> tuple[sympy.Symbol, ...]:
    """z = (q, s, p)."""
    return coordinates.symbols(model, "q") + passive_symbols(model) + task_symbols(model)


def _setting(d: Deriving) -> tuple[ParallelBodies, ParallelStructure, tuple[sympy.Symbol, ...], dict[sympy.Symbol, int]]:
    """The model's bodies, its legs' structure, z = (q, s, p) and each variable's index in z."""
    assert d.model.parallel is not None and d.model.parallel.bodies is not None
    z = _variables(d.model)
    return d.model.parallel.bodies, d[parallel_structure], z, {symbol: k for k, symbol in enumerate(z)}


def _mass_and_potential(d: Deriving) -> tuple[sympy.Matrix, sympy.Expr]:
    """M_z and u over z (see the module docstring)."""
    model = d.model
    bodies, structure, z, index = _setting(d)
    M = sympy.zeros(len(z), len(z))
    moment = sympy.zeros(3, 1)
    by_joint = {body.link: body for body in bodies.links}
    for chain in structure.chains:
        for k, joint in enumerate(chain.leg.joints):
            if joint.name in by_joint:
                term, first_moment = _link_mass_matrix(about_origin(by_joint[joint.name]), chain, k, index, len(z))
                M += term
                moment += first_moment
    parts = [about_origin(bodies.platform)] if bodies.platform is not None else []
    M_p, u_p = platform_side(model, parts, structure.platform)
    n, m = len(model.coordinates), len(model.task_space)
    M[len(z) - m:, len(z) - m:] += M_p
    rotor = bodies.gear_ratio**2 * bodies.rotor_inertia
    for k in range(n):
        M[k, k] += rotor
    return M, -sympy.Matrix(model.gravity).dot(moment) + u_p


def _lagrange_terms(M: sympy.Matrix, u: sympy.Expr, z: tuple[sympy.Symbol, ...], zd: sympy.Matrix
                    ) -> tuple[sympy.Matrix, sympy.Matrix]:
    """(V_z, G_z) of the Lagrangian 1/2 zd^T M zd - u: V_k = sum_ij (dM_kj/dz_i - 1/2 dM_ij/dz_k) zd_i zd_j
    (dM/dt zd - 1/2 d(zd^T M zd)/dz), G = du/dz."""
    partials = [M.diff(symbol) for symbol in z]
    M_dot = sum((partials[i] * zd[i] for i in range(len(z))), sympy.zeros(len(z), len(z)))
    V = M_dot * zd - sympy.Matrix([(zd.T * partials[k] * zd)[0] for k in range(len(z))]) / 2
    return V, sympy.Matrix([sympy.diff(u, symbol) for symbol in z])


def _check_bodies(d: Deriving) -> None:
    """Refuse a model whose legs have the distance form (their dynamics is mass_matrix & co.) or declare no bodies."""
    model = d.model
    assert model.parallel is not None
    try:
        d[reduced_legs]
    except DerivationError:
        pass
    else:
        raise DerivationError(f"model '{model.name}': its legs have the distance form, whose dynamics are "
                              "mass_matrix, coriolis_vector and gravity_vector in the actuated coordinates; "
                              "closure_dynamics is for legs without it")
    if model.parallel.bodies is None:
        raise DerivationError(f"model '{model.name}': closure_dynamics needs the mass properties: declare "
                              "'bodies:' with 'links:' (the link each leg joint moves) and the 'platform'")


def closure_terms(d: Deriving) -> tuple[sympy.Matrix, sympy.Matrix]:
    """(Phi_z, gamma): the closure's Jacobian over z = (q, s, p), [Phi_q Phi_s Phi_p], and gamma = d(Phi_z)/dt zd
    at the rates zd = (qd, sd, pd) (:func:`rate_inputs`), so that Phi_z zd = 0 and Phi_z zdd + gamma = 0 along
    every assembled motion."""
    z = _variables(d.model)
    zd = sympy.Matrix([s for spec in rate_inputs(d.model) for s in spec.symbols])
    Phi_p, Phi_q, Phi_s = closure_jacobian_matrices(d)
    Phi = sympy.Matrix.hstack(Phi_q, Phi_s, Phi_p)
    return Phi, jacobian(Phi * zd, z) * zd


@quantity("closure_dynamics", "M_z, h_z = V_z + G_z and the closure's acceleration term gamma over z = (q, s, p), for "
          "legs without the distance form", mechanism=PARALLEL)
def _closure_dynamics(d: Deriving) -> FunctionSpec:
    _check_bodies(d)
    model = d.model
    z = _variables(model)
    qd, sd, pd = rate_inputs(model)
    zd = sympy.Matrix(qd.symbols + sd.symbols + pd.symbols)
    M, u = _mass_and_potential(d)
    V, G = _lagrange_terms(M, u, z, zd)
    Phi_z, gamma = closure_terms(d)
    inputs = [actuated_input(d), passive_input(model), task_input(model), qd, sd, pd]
    rows = ", ".join(f"{leg.name}: x, y, z, rx, ry, rz" for leg in model.parallel.legs)  # type: ignore[union-attr]
    return make_function(
        model, "closure_dynamics", "Dynamics of legs without the distance form, over z = (q, s, p).",
        "The Lagrangian of every leg link (bodies.links), the platform and the rotors in all the mechanism's "
        "variables z = (q, s, p): M_z(z) (k = 1/2 zd^T M_z zd), h_z = V_z + G_z (Christoffel symbols of M_z; "
        "G_z = du/dz), the potential energy u, and gamma = d(Phi_z)/dt zd, so that an assembled motion has Phi_z zdd + gamma = 0 "
        "(Phi_z = [Phi_q Phi_s Phi_p], closure_jacobians). With zd = W qd the velocities the closure allows, "
        "M = W^T M_z W and tau = W^T (M_z zdd + h_z) (symkin.runtime.closure_dynamics).",
        inputs,
        [OutputSpec("M_z", sympy.ImmutableMatrix(M), "mass matrix over z = (q, s, p)"),
         OutputSpec("h_z", sympy.ImmutableMatrix(V + G), "Coriolis, centrifugal and gravity terms over z",
                    shape=(len(z),)),
         OutputSpec("gamma", sympy.ImmutableMatrix(gamma), f"d(Phi_z)/dt zd, rows as in closure() ({rows})",
                    shape=(gamma.shape[0],)),
         OutputSpec("u", sympy.ImmutableMatrix([u]), "potential energy (zero at the base origin)", "J", shape=())],
    )


@dataclasses.dataclass(frozen=True)
class UnitBodies:
    """What both closure regressors are formed from: per inertial column (each leg link's body, then the
    platform's, ten standard parameters each), M_z and u of the unit body pi = e_k; the names and the model's
    values of every column (the inertial ones, then per actuator the drive's I_a, f_v, f_c, f_o)."""

    inertial: tuple[tuple[sympy.Matrix, sympy.Expr], ...]
    names: tuple[str, ...]
    values: tuple[sympy.Expr, ...]


@quantity("closure_unit_bodies", "M_z and u of each unit body of the closure regressors, their names and pi",
          emitted=False, mechanism=PARALLEL)
def unit_bodies(d: Deriving) -> UnitBodies:
    _check_bodies(d)
    model = d.model
    bodies, structure, z, index = _setting(d)
    g = sympy.Matrix(model.gravity)
    inertial: list[tuple[sympy.Matrix, sympy.Expr]] = []
    names: list[str] = []
    values: list[sympy.Expr] = []
    for body in bodies.links:
        places = [(chain, k) for chain in structure.chains for k, joint in enumerate(chain.leg.joints)
                  if joint.name == body.link]
        for triple in unit_triples():
            M, moment = sympy.zeros(len(z), len(z)), sympy.zeros(3, 1)
            for chain, k in places:
                term, first_moment = _link_mass_matrix(triple, chain, k, index, len(z))
                M, moment = M + term, moment + first_moment
            inertial.append((M, -g.dot(moment)))
        names += [f"{body.link}.{p}" for p in INERTIAL]
        values += standard_values(about_origin(body))
    m = len(model.task_space)
    for triple in unit_triples():
        M_p, u_p = platform_side(model, [triple], structure.platform)
        M = sympy.zeros(len(z), len(z))
        M[len(z) - m:, len(z) - m:] = M_p
        inertial.append((M, u_p))
    names += [f"platform.{p}" for p in INERTIAL]
    values += (standard_values(about_origin(bodies.platform)) if bodies.platform is not None
               else [sympy.Integer(0)] * len(INERTIAL))
    friction = {f.joint: f for f in model.friction}
    armature = bodies.gear_ratio ** 2 * bodies.rotor_inertia
    for coordinate in model.coordinates:
        names += [f"{coordinate.name}.{p}" for p in DRIVE]
        values += [sympy.sympify(v) for v in drive_values(friction.get(coordinate.name), se.sympify(armature))]
    return UnitBodies(tuple(inertial), tuple(names), tuple(values))


def _standard_outputs(first: OutputSpec, units: UnitBodies) -> list[OutputSpec]:
    """``first`` (a regressor, its last axis the columns) and pi, both named by the columns."""
    return [dataclasses.replace(first, elements=units.names),
            OutputSpec("pi", sympy.ImmutableMatrix(units.values), "the model's standard parameters",
                       shape=(len(units.values),), elements=units.names)]


@quantity("closure_regressor", "regressor Y_z(z, zd, zdd) over z = (q, s, p) with M_z zdd + h_z + F_f = Y_z pi, and the "
          "model's standard parameters pi, for legs without the distance form", mechanism=PARALLEL)
def closure_regressor_spec(d: Deriving) -> FunctionSpec:
    """Column k of Y_z is the Lagrangian's M_z zdd + V_z + G_z (and friction) with pi = e_k: each leg link's body
    (bodies.links) and the platform's as ten standard parameters about their frames' origins, and per actuator
    the drive's I_a, f_v, f_c, f_o (as the serial regressor's, symkin.dynamics.regressor)."""
    model = d.model
    units = d[unit_bodies]
    z = _variables(model)
    rates, accelerations = rate_inputs(model), rate_inputs(model, "qdd")
    zd = sympy.Matrix([s for spec in rates for s in spec.symbols])
    zdd = sympy.Matrix([s for spec in accelerations for s in spec.symbols])
    columns: list[sympy.Matrix] = []
    for M, u in units.inertial:
        V, G = _lagrange_terms(M, u, z, zd)
        columns.append(M * zdd + V + G)
    friction = {f.joint: f for f in model.friction}
    qd, qdd = rates[0].symbols, accelerations[0].symbols
    real = {sympy.Symbol(symbol.name): symbol for symbol in qd + qdd}  # SymEngine's symbols come back plain
    for j, coordinate in enumerate(model.coordinates):
        for term in drive_columns(friction.get(coordinate.name), se.sympify(qd[j]), se.sympify(qdd[j])):
            entry = sympy.sympify(term).xreplace(real)
            columns.append(sympy.Matrix([entry if row == j else 0 for row in range(len(z))]))
    Y = sympy.Matrix.hstack(*columns)
    inputs = [actuated_input(d), passive_input(model), task_input(model), *rates, *accelerations]
    return make_function(
        model, "closure_regressor", "Regressor of legs without the distance form over z = (q, s, p), and pi.",
        "Y_z(z, zd, zdd) with M_z zdd + h_z + F_f = Y_z pi (closure_dynamics' Lagrange equations, friction on the "
        "actuators), linear in the standard parameters pi: per leg link body (bodies.links) and the platform m, "
        "m c, I_o about their frames' origins (Pinocchio's order), per actuator I_a, f_v, f_c, f_o. With zd = W qd "
        "and zdd = W qdd + c the motion the closure allows, tau = W^T Y_z pi (symkin.runtime.closure_dynamics."
        "closure_regressor). The names of pi are the outputs' elements in the manifest.",
        inputs, _standard_outputs(OutputSpec("Y_z", sympy.ImmutableMatrix(Y), "regressor over z: column k is the "
                                             "effort per unit of parameter k"), units))


@quantity("closure_energy_regressor", "energy regressor Y_e(z, zd) with k + u = Y_e pi, and the model's standard "
          "parameters pi, for legs without the distance form", mechanism=PARALLEL)
def _closure_energy_regressor(d: Deriving) -> FunctionSpec:
    """Column k of Y_e is the energy 1/2 zd^T M_z zd + u of the unit body pi = e_k; a drive's reflected inertia
    1/2 qd_j^2, its friction 0 (as the serial energy regressor's, symkin.dynamics.regressor)."""
    model = d.model
    units = d[unit_bodies]
    rates = rate_inputs(model)
    zd = sympy.Matrix([s for spec in rates for s in spec.symbols])
    row = [(zd.T * M * zd)[0] / 2 + u for M, u in units.inertial]
    for rate in rates[0].symbols:
        row += [rate ** 2 / 2, sympy.Integer(0), sympy.Integer(0), sympy.Integer(0)]
    inputs = [actuated_input(d), passive_input(model), task_input(model), *rates]
    return make_function(
        model, "closure_energy_regressor", "Energy regressor of legs without the distance form: k + u = Y_e pi.",
        "The kinetic and potential energy 1/2 zd^T M_z zd + u of each unit body over z = (q, s, p) (the columns of "
        "closure_regressor; a drive's reflected inertia 1/2 qd_j^2, friction 0). At the velocities the closure "
        "allows, zd = W qd, Y_e pi is the mechanism's energy and d(Y_e pi)/dt = qd . (tau - F_f) along a motion "
        "(symkin.runtime.closure_dynamics.closure_energy_regressor).",
        inputs, _standard_outputs(OutputSpec("Y_e", sympy.ImmutableMatrix(row), "energy per unit of each standard "
                                             "parameter", shape=(len(row),)), units))
