"""The dynamics regressor of a parallel mechanism: tau = Y(q, p, qd, qdd) pi, linear in its bodies' parameters.

The reduced dynamics of :mod:`symkin.parallel.dynamics` (tau = M_a qdd + V_a + G_a + J^T (M_p pdd + V_p + G_p)
+ F_f) is linear in the mass distribution :class:`~symkin.parallel.inertia.Inertia`, and that is linear in the
bodies' standard parameters once each body is described about a frame origin by its mass m, first moment
h = m c and inertia I_o = I_c + m (|c|^2 E - c c^T) (Atkeson, An and Hollerbach 1986; Khalil and Dombre 2002,
sec. 14.4 for parallel robots: the legs' and platform's regressors combined through the Jacobian):

* the platform body (10: m, h, I_o about the platform origin in platform axes, Pinocchio's order
  ``m, mx, my, mz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz``): k_p = 1/2 m |v_o|^2 + v_o . R (w_b x h) + 1/2 w_b^T I_o w_b;
* the actuated link of every leg (10, the same body on every leg, about the frame right after the actuated
  joint): M_a,ii = m |v_o|^2 + 2 v_o . (w x R h) + w^T R I_o R^T w, u = -g . (m o + R h), with o, R the frame's
  origin and axes and w the joint's axis (its origin stays on the axis: v_o = 0 for a revolute actuator);
* the rods (``rod.mB``: the mass at the platform joints B_i, ``rod.mC``: at the proximal joints C_i, and where
  every rod keeps one length L, ``rod.dI`` = I_c - m f (1 - f) L^2: its inertia across it beyond its ends');
* per actuated joint, as a serial chain's drive: reflected rotor inertia I_a and friction f_v, f_c, f_o.

Column k of Y is the reduced inverse dynamics of the mass distribution with pi = e_k (friction: its own factor),
exact; the kinematic terms (J, the bias b, pd and pdd) are bound once and shared by every column.  The energy
regressor (Gautier and Khalil 1988) has the same columns: k + u = Y_e(q, p, qd) pi, the kinetic and potential
energy of each unit mass distribution (a drive's reflected inertia 1/2 qd_j^2, friction none), for the
identification from the power the drives deliver.
"""

from __future__ import annotations

import dataclasses
from functools import cached_property

import symengine as se
import sympy

from symkin.dynamics.program import Program
from symkin.dynamics.quantities import coordinate_symbols, function_spec
from symkin.dynamics.parameter_names import DRIVE, INERTIAL
from symkin.dynamics.regressor import drive_columns, drive_values
from symkin.errors import DerivationError
from symkin.ir.quantity import Deriving, quantity
from symkin.ir.spec import FunctionSpec
from symkin.model.schema import Model, PlatformMotion
from symkin.parallel.distance import DistanceLeg
from symkin.parallel.dynamics import device_inputs, ReducedDynamics
from symkin.parallel.inertia import (
    Inertia,
    SwingingRod,
    about_origin,
    actuated_frame,
    elbow_mass_terms,
    platform_side,
    point_mass,
)
from symkin.parallel.legs import LegChain
from symkin.parallel.quantities import PARALLEL, parallel_structure, reduced_legs

Triple = tuple[sympy.Expr, sympy.Matrix, sympy.Matrix]


def _unit_triples() -> list[Triple]:
    """(m, h, I_o) with one standard parameter 1 and the others 0, in INERTIAL order."""
    out: list[Triple] = [(sympy.Integer(1), sympy.zeros(3, 1), sympy.zeros(3, 3))]
    out += [(sympy.Integer(0), sympy.Matrix([int(k == axis) for k in range(3)]), sympy.zeros(3, 3))
            for axis in range(3)]
    for r, c in ((0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2)):
        inertia = sympy.zeros(3, 3)
        inertia[r, c] = inertia[c, r] = 1
        out.append((sympy.Integer(0), sympy.zeros(3, 1), inertia))
    return out


def _flat(triple: Triple) -> list[sympy.Expr]:
    """(m, h, I_o) as the ten standard parameters."""
    m, h, I = triple
    return [m, h[0], h[1], h[2], I[0, 0], I[0, 1], I[1, 1], I[0, 2], I[1, 2], I[2, 2]]


@dataclasses.dataclass(frozen=True)
class _Legs:
    """What the regressor needs of the legs: their distance forms and chains, and which bodies they have."""

    model: Model
    legs: tuple[DistanceLeg, ...]
    chains: tuple[LegChain, ...]

    @cached_property
    def has_actuated_links(self) -> bool:
        """Every leg's actuator is its first moving joint, so a link moves with it alone."""
        try:
            for leg, chain in zip(self.legs, self.chains):
                actuated_frame(self.model, False, leg, chain)
        except DerivationError:
            return False
        return True

    @cached_property
    def rod_length_squared(self) -> sympy.Expr | None:
        """L^2 when every rod keeps one and the same length (the actuators before the rods), else None."""
        if any(leg.actuator != "before" for leg in self.legs):
            return None
        first = self.legs[0].L2
        return first if all(sympy.simplify(leg.L2 - first) == 0 for leg in self.legs) else None


def _require_regressor(model: Model) -> None:
    parallel = model.parallel
    assert parallel is not None
    bodies = parallel.bodies
    reason = None
    if parallel.wrist is not None:
        reason = "a hybrid device's wrist"
    elif parallel.motion is PlatformMotion.SPHERICAL or (bodies is not None and bodies.distal_link is not None):
        reason = "a spherical platform's distal links"
    if reason is not None:
        raise DerivationError(f"model '{model.name}': the regressor of a parallel model does not cover {reason} yet; "
                              "identify the serial part with a serial model of it")


def body_parameter_names(legs: _Legs) -> tuple[str, ...]:
    """pi's names: the platform's, the actuated links' and the rods' parameters, then each actuator's DRIVE."""
    names = [f"platform.{p}" for p in INERTIAL]
    if legs.has_actuated_links:
        names += [f"actuated_link.{p}" for p in INERTIAL]
    names += ["rod.mB", "rod.mC"] + (["rod.dI"] if legs.rod_length_squared is not None else [])
    return tuple(names) + tuple(f"{c.name}.{p}" for c in legs.model.coordinates for p in DRIVE)


def unit_inertias(legs: _Legs, platform) -> list[Inertia]:
    """The mass distribution of each inertial standard parameter set to 1 (the others 0), in the order of
    :func:`body_parameter_names` (the drives' columns are not mass distributions)."""
    model, n = legs.model, len(legs.legs)
    task = len(model.task_space)
    none = sympy.ImmutableMatrix(sympy.zeros(task, task))
    empty = Inertia((sympy.Integer(0),) * n, sympy.Integer(0), none, sympy.Integer(0))

    def on_platform(parts: list[Triple]) -> Inertia:
        M_p, u_p = platform_side(model, parts, platform)
        return dataclasses.replace(empty, platform_matrix=M_p, platform_potential=u_p)

    out = [on_platform([triple]) for triple in _unit_triples()]
    g = sympy.Matrix(model.gravity)
    if legs.has_actuated_links:
        frames = [actuated_frame(model, False, leg, chain) for leg, chain in zip(legs.legs, legs.chains)]
        for m, h, I in _unit_triples():
            diagonal, potential = [], sympy.Integer(0)
            for leg, (R, o, w) in zip(legs.legs, frames):
                v = sympy.diff(o, leg.q)
                diagonal.append(sympy.trigsimp(m * v.dot(v) + 2 * v.dot(w.cross(R * h)) + (w.T * R * I * R.T * w)[0, 0]))
                potential += -g.dot(m * o + R * h)
            out.append(dataclasses.replace(empty, actuator_diagonal=tuple(diagonal), actuator_potential=potential))
    out.append(on_platform([point_mass(sympy.Integer(1), leg.b) for leg in legs.legs]))
    elbows = [elbow_mass_terms(model, leg) for leg in legs.legs]
    out.append(dataclasses.replace(empty, actuator_diagonal=tuple(e[0] for e in elbows),
                                   actuator_potential=-sum((e[1] for e in elbows), sympy.Integer(0))))
    L2 = legs.rod_length_squared
    if L2 is not None:
        out.append(dataclasses.replace(empty, rods=tuple(SwingingRod(leg.q, leg.C, leg.B, leg.L2, sympy.Integer(1))
                                                         for leg in legs.legs)))
    return out


def body_parameters(legs: _Legs) -> list[sympy.Expr]:
    """The model's own pi, in the order of :func:`body_parameter_names`."""
    model = legs.model
    bodies = model.parallel.bodies  # type: ignore[union-attr]
    assert bodies is not None
    zero: Triple = (sympy.Integer(0), sympy.zeros(3, 1), sympy.zeros(3, 3))
    values = _flat(about_origin(bodies.platform) if bodies.platform is not None else zero)
    if legs.has_actuated_links:
        values += _flat(about_origin(bodies.actuated_link) if bodies.actuated_link is not None else zero)
    f, m = bodies.rod_platform_fraction, bodies.rod_mass
    values += [m * f, m * (1 - f)]
    L2 = legs.rod_length_squared
    if L2 is not None:
        values.append(bodies.rod_inertia - m * f * (1 - f) * L2 if bodies.rod_inertia is not None else sympy.Integer(0))
    friction = {fr.joint: fr for fr in model.friction}
    armature = se.sympify(bodies.gear_ratio ** 2 * bodies.rotor_inertia)
    return values + [v for c in model.coordinates for v in drive_values(friction.get(c.name), armature)]


@quantity("regressor", "dynamics regressor Y(q, p, qd, qdd) with tau = Y pi, and the model's standard parameters pi",
          mechanism=PARALLEL, kappa_degree=4)
def _regressor(d: Deriving) -> FunctionSpec:
    """Y (actuators x parameters) and the model's pi, both named by :func:`body_parameter_names` in the manifest."""
    model = d.model
    shared = d[regressor_columns]
    legs = shared.legs
    program = Program()
    terms = ReducedDynamics(d, program)
    qd, qdd = coordinate_symbols(d, "qd"), coordinate_symbols(d, "qdd")
    motion = terms.platform_motion(qd, qdd)
    columns = [terms.with_parts(parts).torques(qd, qdd, with_friction=False, motion=motion)
               for parts in shared.unit_inertias]
    friction = {f.joint: f for f in model.friction}
    n = model.dof
    for j, coordinate in enumerate(model.coordinates):
        for term in drive_columns(friction.get(coordinate.name), qd[j], qdd[j]):
            columns.append([term if row == j else se.Integer(0) for row in range(n)])
    Y = program.bind([column[row] for row in range(n) for column in columns])
    return _with_body_parameters(
        d, legs, "regressor", "Dynamics regressor: tau = Y(q, p, qd, qdd) pi, linear in the standard parameters.",
        "Column k of Y is the reduced inverse dynamics tau = M_a qdd + V_a + G_a + J^T (M_p pdd + V_p + G_p) + F_f "
        "with pi = e_k, exact (symkin.parallel.regressor): the platform's m, m c, I_o (about its origin, Pinocchio's "
        "order), the actuated links' (about the frame after the actuated joint, the same body on every leg), the "
        "rods' masses at the platform joints (mB) and the proximal joints (mC) and their inertia beyond their ends "
        "(dI), and per actuator I_a, f_v, f_c, f_o; Y pi equals inverse_dynamics. Evaluate at a consistent pair "
        "q, p (p = fk(q) or q = ik(p)).",
        device_inputs(d, "qd", "qdd"), program,
        ("Y", Y, (n, len(body_parameter_names(legs))), "regressor: column k is the effort per unit of parameter k", ""))


@quantity("energy_regressor", "energy regressor Y_e(q, p, qd) with k + u = Y_e pi, and the model's standard "
          "parameters pi", mechanism=PARALLEL, kappa_degree=2)
def _energy_regressor(d: Deriving) -> FunctionSpec:
    """Y_e and the model's pi, named as the regressor's: the energy of each unit mass distribution."""
    shared = d[regressor_columns]
    legs = shared.legs
    program = Program()
    terms = ReducedDynamics(d, program)
    qd = coordinate_symbols(d, "qd")
    pd = terms.task_rates(qd)
    row = [terms.with_parts(parts).kinetic_energy(qd, pd)
           + se.sympify(parts.actuator_potential + parts.platform_potential + parts.distal_potential)
           for parts in shared.unit_inertias]
    half = se.Rational(1, 2)
    row += [e for rate in qd for e in (half * rate * rate, se.Integer(0), se.Integer(0), se.Integer(0))]
    Y_e = program.bind(row)
    return _with_body_parameters(
        d, legs, "energy_regressor", "Energy regressor: k + u = Y_e(q, p, qd) pi, linear in the standard parameters.",
        "The kinetic and potential energy of each mass distribution with pi = e_k (the columns of regressor; a "
        "drive's reflected inertia 1/2 qd_j^2, friction 0); Y_e pi equals kinetic_energy + potential_energy, and "
        "d(Y_e pi)/dt = qd . (tau - F_f) along a motion. Evaluate at a consistent pair q, p.",
        device_inputs(d, "qd"), program, ("Y_e", Y_e, (len(Y_e),), "energy per unit of each standard parameter", ""))


@dataclasses.dataclass(frozen=True)
class RegressorColumns:
    """What both parallel regressors are formed from: the legs and the unit mass distributions of their
    inertial columns (:func:`unit_inertias`), built once per derivation (:func:`regressor_columns`)."""

    legs: _Legs
    unit_inertias: tuple[Inertia, ...]


@quantity("parallel_regressor_columns", "the legs and unit mass distributions of the parallel regressors",
          emitted=False, mechanism=PARALLEL)
def regressor_columns(d: Deriving) -> RegressorColumns:
    """The legs the regressors are formed from (after checking that the model has them) and their unit inertias."""
    model = d.model
    _require_regressor(model)
    if model.parallel.bodies is None:  # type: ignore[union-attr]
        raise DerivationError(f"model '{model.name}' declares no bodies, so it has no regressor; add a 'bodies:' "
                              "section (see docs/model-format.md)")
    structure = d[parallel_structure]
    legs = _Legs(model, d[reduced_legs], structure.chains)
    return RegressorColumns(legs, tuple(unit_inertias(legs, structure.platform)))


def _with_body_parameters(d: Deriving, legs: _Legs, name: str, summary: str, doc: str, inputs: list, program: Program,
                          first: tuple[str, list[se.Basic], tuple[int, ...], str, str]) -> FunctionSpec:
    """The function of the output ``first`` and the model's pi, both named by :func:`body_parameter_names`."""
    names = body_parameter_names(legs)
    pi = program.bind([se.sympify(v) for v in body_parameters(legs)])
    spec = function_spec(d, name, summary, doc, inputs, program,
                         [first, ("pi", pi, (len(names),), "the model's standard parameters (kg, kg*m, kg*m^2; "
                                  "drives as a serial model's)", "")])
    return dataclasses.replace(spec, outputs=tuple(dataclasses.replace(o, elements=names) for o in spec.outputs))
