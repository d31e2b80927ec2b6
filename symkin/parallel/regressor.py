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
* a spherical platform's distal link (10, the same body on every leg, about its frame's origin on the middle
  axis): taken about the centre of rotation (the parallel-axis theorem with the first moment) into the distal
  links' Euler equations (:mod:`symkin.parallel.distal`) and potential;
* the rods (``rod.mB``: the mass at the platform joints B_i, ``rod.mC``: at the proximal joints C_i, and where
  every rod keeps one length L, ``rod.dI`` = I_c - m f (1 - f) L^2: its inertia across it beyond its ends');
* per actuated joint, as a serial chain's drive: reflected rotor inertia I_a and friction f_v, f_c, f_o;
* a hybrid device's wrist (:mod:`symkin.parallel.hybrid`): its links' 10 and joints' 4 each, the columns of the
  serial regressor of the device chain (platform joints, then the wrist) at the platform's motion, the platform's
  rows carried to the legs by J^T (:class:`WristColumns`).

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
from symkin.dynamics.parameter_names import DRIVE, INERTIAL, ROD
from symkin.dynamics.quantities import gravity_graph, newton_euler_links
from symkin.dynamics.regressor import (
    drive_columns,
    drive_values,
    energy_row,
    parameter_names,
    regressor_graph,
    standard_parameters,
)
from symkin.errors import DerivationError
from symkin.ir.quantity import Deriving, quantity
from symkin.ir.spec import FunctionSpec
from symkin.model import coordinates
from symkin.model.schema import Body, Model
from symkin.parallel import hybrid
from symkin.parallel.distance import DistanceLeg
from symkin.parallel.dynamics import device_inputs, ReducedDynamics
from symkin.parallel.inertia import (
    Inertia,
    SwingingRod,
    about_origin,
    actuated_frame,
    Triple,
    distal_link,
    elbow_mass_terms,
    platform_side,
    point_mass,
    standard_values,
    unit_triples,
)
from symkin.parallel.legs import LegChain
from symkin.parallel.quantities import PARALLEL, parallel_structure, reduced_legs

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

    @property
    def distal_body(self) -> Body | None:
        """The spherical legs' distal link (``bodies: distal_link:``), the same body on every leg, or None."""
        bodies = self.model.parallel.bodies  # type: ignore[union-attr]
        return None if bodies is None else bodies.distal_link

    @cached_property
    def rod_length_squared(self) -> sympy.Expr | None:
        """L^2 when every rod keeps one and the same length (the actuators before the rods), else None."""
        if any(leg.actuator != "before" for leg in self.legs):
            return None
        first = self.legs[0].L2
        return first if all(sympy.simplify(leg.L2 - first) == 0 for leg in self.legs) else None


def body_parameter_names(legs: _Legs) -> tuple[str, ...]:
    """pi's names: the platform's, the actuated links', the distal links' and the rods' parameters, then each
    actuator's DRIVE."""
    names = [f"platform.{p}" for p in INERTIAL]
    if legs.has_actuated_links:
        names += [f"actuated_link.{p}" for p in INERTIAL]
    if legs.distal_body is not None:
        names += [f"distal_link.{p}" for p in INERTIAL]
    names += [f"rod.{p}" for p in ROD[:3 if legs.rod_length_squared is not None else 2]]
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

    out = [on_platform([triple]) for triple in unit_triples()]
    g = sympy.Matrix(model.gravity)
    if legs.has_actuated_links:
        frames = [actuated_frame(model, False, leg, chain) for leg, chain in zip(legs.legs, legs.chains)]
        for m, h, I in unit_triples():
            diagonal, potential = [], sympy.Integer(0)
            for leg, (R, o, w) in zip(legs.legs, frames):
                v = sympy.diff(o, leg.q)
                diagonal.append(sympy.trigsimp(m * v.dot(v) + 2 * v.dot(w.cross(R * h)) + (w.T * R * I * R.T * w)[0, 0]))
                potential += -g.dot(m * o + R * h)
            out.append(dataclasses.replace(empty, actuator_diagonal=tuple(diagonal), actuator_potential=potential))
    if legs.distal_body is not None:
        out += _distal_unit_inertias(legs, empty)
    out.append(on_platform([point_mass(sympy.Integer(1), leg.b) for leg in legs.legs]))
    elbows = [elbow_mass_terms(model, leg) for leg in legs.legs]
    out.append(dataclasses.replace(empty, actuator_diagonal=tuple(e[0] for e in elbows),
                                   actuator_potential=-sum((e[1] for e in elbows), sympy.Integer(0))))
    L2 = legs.rod_length_squared
    if L2 is not None:
        out.append(dataclasses.replace(empty, rods=tuple(SwingingRod(leg.q, leg.C, leg.B, leg.L2, sympy.Integer(1))
                                                         for leg in legs.legs)))
    return out


def _distal_unit_inertias(legs: _Legs, empty: Inertia) -> list[Inertia]:
    """The distal links' columns: each unit (m, h, I_o) about the link frame's origin, which lies at s = d w from
    the centre of rotation on the middle axis (link frame), taken about the centre as the distal links' dynamics
    need it: h_c = h + m s, I_c = I_o + 2 (h . s) E - h s^T - s h^T + m (|s|^2 E - s s^T) (the parallel-axis theorem
    for a body whose centre of mass is not at the origin), the potential -g . R_d h_c on every leg."""
    model, body = legs.model, legs.distal_body
    assert body is not None
    massless = dataclasses.replace(body, mass=sympy.Integer(0), com=(0, 0, 0), inertia=sympy.ImmutableMatrix.zeros(3))
    frames = [distal_link(model, massless, leg, chain) for leg, chain in zip(legs.legs, legs.chains)]
    g, E = sympy.Matrix(model.gravity), sympy.eye(3)
    out = []
    for m, h, I in unit_triples():
        links, potential = [], sympy.Integer(0)
        for frame in frames:
            s = sympy.Matrix(frame.com)  # the massless link's "centre of mass": its frame's origin, d w
            about_centre = I + 2 * h.dot(s) * E - h * s.T - s * h.T + m * (s.dot(s) * E - s * s.T)
            links.append(dataclasses.replace(frame, inertia=sympy.ImmutableMatrix(about_centre)))
            potential += -g.dot(frame.rotation * (h + m * s))
        out.append(dataclasses.replace(empty, distal_links=tuple(links), distal_potential=potential))
    return out


def body_parameters(legs: _Legs) -> list[sympy.Expr]:
    """The model's own pi, in the order of :func:`body_parameter_names`."""
    model = legs.model
    bodies = model.parallel.bodies  # type: ignore[union-attr]
    assert bodies is not None
    zero: Triple = (sympy.Integer(0), sympy.zeros(3, 1), sympy.zeros(3, 3))
    values = standard_values(about_origin(bodies.platform) if bodies.platform is not None else zero)
    if legs.has_actuated_links:
        values += standard_values(about_origin(bodies.actuated_link) if bodies.actuated_link is not None else zero)
    if legs.distal_body is not None:
        values += standard_values(about_origin(legs.distal_body))
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
def reduced_regressor(d: Deriving) -> FunctionSpec:
    """Y (device coordinates x parameters) and the model's pi, both named by :attr:`RegressorColumns.names` in the
    manifest."""
    model = d.model
    shared = d[regressor_columns]
    program = Program()
    terms = ReducedDynamics(d, program)
    qd, qdd = coordinate_symbols(d, "qd"), coordinate_symbols(d, "qdd")
    motion = terms.platform_motion(qd, qdd)
    wrist = (terms.wrist("qd"), terms.wrist("qdd"))
    columns = [terms.with_parts(parts, wrist_bodies=False).torques(qd, qdd, with_friction=False, motion=motion,
                                                                   wrist=wrist)
               for parts in shared.unit_inertias]
    friction = {f.joint: f for f in model.friction}
    n = model.dof + len(wrist[0])
    for j, coordinate in enumerate(model.coordinates):
        for term in drive_columns(friction.get(coordinate.name), qd[j], qdd[j]):
            columns.append([term if row == j else se.Integer(0) for row in range(n)])
    if shared.wrist is not None:
        columns += [terms.B_transpose(F_c) for F_c in shared.wrist.forces(d, motion)]
    Y = program.bind([column[row] for row in range(n) for column in columns])
    return _with_body_parameters(
        d, shared, "regressor", "Dynamics regressor: tau = Y(q, p, qd, qdd) pi, linear in the standard parameters.",
        "Column k of Y is the reduced inverse dynamics tau = M_a qdd + V_a + G_a + J^T (M_p pdd + V_p + G_p) + F_f "
        "with pi = e_k, exact (symkin.parallel.regressor): the platform's m, m c, I_o (about its origin, Pinocchio's "
        "order), the actuated links' (about the frame after the actuated joint, the same body on every leg), a "
        "spherical platform's distal links' (about their frame's origin, the same body on every leg), the "
        "rods' masses at the platform joints (mB) and the proximal joints (mC) and their inertia beyond their ends "
        "(dI), and per actuator I_a, f_v, f_c, f_o; a hybrid device's wrist adds its links' and joints' columns "
        "(its serial regressor on the platform, the platform's rows carried to the legs by J^T); Y pi equals "
        "inverse_dynamics. Evaluate at a consistent pair q, p (p = fk(q) or q = ik(p)).",
        device_inputs(d, "qd", "qdd"), program,
        ("Y", Y, (n, len(shared.names)), "regressor: column k is the effort per unit of parameter k", ""))


@quantity("energy_regressor", "energy regressor Y_e(q, p, qd) with k + u = Y_e pi, and the model's standard "
          "parameters pi", mechanism=PARALLEL, kappa_degree=2)
def _energy_regressor(d: Deriving) -> FunctionSpec:
    """Y_e and the model's pi, named as the regressor's: the energy of each unit mass distribution."""
    shared = d[regressor_columns]
    program = Program()
    terms = ReducedDynamics(d, program)
    qd = coordinate_symbols(d, "qd")
    pd = terms.task_rates(qd)
    cd = pd + terms.wrist("qd")
    row = [terms.with_parts(parts, wrist_bodies=False).kinetic_energy(qd, cd)
           + se.sympify(parts.actuator_potential + parts.platform_potential + parts.distal_potential)
           for parts in shared.unit_inertias]
    half = se.Rational(1, 2)
    row += [e for rate in qd for e in (half * rate * rate, se.Integer(0), se.Integer(0), se.Integer(0))]
    if shared.wrist is not None:
        row += shared.wrist.energies(d, pd)
    Y_e = program.bind(row)
    return _with_body_parameters(
        d, shared, "energy_regressor", "Energy regressor: k + u = Y_e(q, p, qd) pi, linear in the standard parameters.",
        "The kinetic and potential energy of each mass distribution with pi = e_k (the columns of regressor; a "
        "drive's reflected inertia 1/2 qd_j^2, friction 0; a hybrid device's wrist: its serial energy regressor "
        "on the platform); Y_e pi equals kinetic_energy + potential_energy, and "
        "d(Y_e pi)/dt = qd . (tau - F_f) along a motion. Evaluate at a consistent pair q, p.",
        device_inputs(d, "qd"), program, ("Y_e", Y_e, (len(Y_e),), "energy per unit of each standard parameter", ""))


@dataclasses.dataclass(frozen=True)
class RegressorColumns:
    """What both parallel regressors are formed from: the legs and the unit mass distributions of their
    inertial columns (:func:`unit_inertias`), built once per derivation (:func:`regressor_columns`)."""

    legs: _Legs
    unit_inertias: tuple[Inertia, ...]
    wrist: WristColumns | None = None

    @property
    def names(self) -> tuple[str, ...]:
        """pi's names: the legs' and platform's (:func:`body_parameter_names`), then a hybrid device's wrist's."""
        return body_parameter_names(self.legs) + (self.wrist.names if self.wrist is not None else ())


@dataclasses.dataclass(frozen=True)
class WristColumns:
    """A hybrid device's wrist in the regressors: the columns of its links' and joints' standard parameters in
    the serial regressor of the device chain (:func:`symkin.parallel.hybrid.device_chain`: the platform joints,
    massless, then the wrist), whose rows are the forces conjugate to c = (p, qw).  The platform joints' rates
    are the platform's (pd, pdd = J qdd + b), so a column is the wrist's share of F_c, carried to the device's
    coordinates by B^T = diag(J^T, 1) as the platform side's efforts are.

    Attributes:
        names: the kept columns' names (``<link>.<INERTIAL>``, ``<joint>.<DRIVE>``, the chain's).
        indices: the kept columns of the chain's regressor.
        platform_joints: how many platform joints the chain starts with.
    """

    names: tuple[str, ...]
    indices: tuple[int, ...]
    platform_joints: int

    @staticmethod
    def of(d: Deriving) -> WristColumns:
        """The wrist's columns of the device chain's regressor (its links' INERTIAL, its joints' DRIVE)."""
        chain = d[hybrid.device_derivation].model
        joints, m = len(chain.joints), len(hybrid.platform_joints(d.model))
        inertial = [len(INERTIAL) * j + k for j in range(m, joints) for k in range(len(INERTIAL))]
        drives = [len(INERTIAL) * joints + len(DRIVE) * j + k for j in range(m, joints) for k in range(len(DRIVE))]
        names = parameter_names(chain)
        return WristColumns(tuple(names[k] for k in inertial + drives), tuple(inertial + drives), m)

    def _platform_rates(self, d: Deriving, *groups: tuple[str, list[se.Basic]]) -> dict[se.Basic, se.Basic]:
        """The chain's rate symbols of its platform joints -> the platform's rates (in the order of p)."""
        chain = d[hybrid.device_derivation].model
        order = hybrid.combined_order(d.model, len(chain.joints))
        out = {}
        for group, values in groups:
            symbols = [se.sympify(s) for s in coordinates.symbols(chain, group)]
            out.update({symbols[order[position]]: values[position] for position in range(self.platform_joints)})
        return out

    def forces(self, d: Deriving, motion: tuple[list[se.Basic], list[se.Basic]]) -> list[list[se.Basic]]:
        """Per kept column, F_c (in the order of c) at the platform's motion (pd, pdd)."""
        chain = d[hybrid.device_derivation]
        order = hybrid.combined_order(d.model, len(chain.model.joints))
        rates = self._platform_rates(d, ("qd", motion[0]), ("qdd", motion[1]))
        Y = chain[regressor_graph]
        return [[Y[order[position]][k].xreplace(rates) for position in range(len(order))] for k in self.indices]

    def energies(self, d: Deriving, pd: list[se.Basic]) -> list[se.Basic]:
        """Per kept column, the wrist's k + u per unit parameter at the platform's rates pd."""
        chain = d[hybrid.device_derivation]
        row = energy_row(chain.model, chain[newton_euler_links], chain[gravity_graph])
        rates = self._platform_rates(d, ("qd", pd))
        return [row[k].xreplace(rates) for k in self.indices]

    def parameters(self, d: Deriving) -> list[se.Basic]:
        """The model's values of the kept columns' parameters."""
        chain = d[hybrid.device_derivation]
        values = standard_parameters(chain.model, chain[newton_euler_links])
        return [values[k] for k in self.indices]


@quantity("parallel_regressor_columns", "the legs and unit mass distributions of the parallel regressors",
          emitted=False, mechanism=PARALLEL)
def regressor_columns(d: Deriving) -> RegressorColumns:
    """The legs the regressors are formed from (after checking that the model has them) and their unit inertias."""
    model = d.model
    if model.parallel.bodies is None:  # type: ignore[union-attr]
        raise DerivationError(f"model '{model.name}' declares no bodies, so it has no regressor; add a 'bodies:' "
                              "section (see docs/model-format.md)")
    structure = d[parallel_structure]
    legs = _Legs(model, d[reduced_legs], structure.chains)
    wrist = WristColumns.of(d) if model.parallel.wrist is not None else None  # type: ignore[union-attr]
    return RegressorColumns(legs, tuple(unit_inertias(legs, structure.platform)), wrist)


def _with_body_parameters(d: Deriving, shared: RegressorColumns, name: str, summary: str, doc: str, inputs: list,
                          program: Program, first: tuple[str, list[se.Basic], tuple[int, ...], str, str]
                          ) -> FunctionSpec:
    """The function of the output ``first`` and the model's pi, both named by :attr:`RegressorColumns.names`."""
    names = shared.names
    wrist = shared.wrist.parameters(d) if shared.wrist is not None else []
    pi = program.bind([se.sympify(v) for v in body_parameters(shared.legs)] + wrist)
    spec = function_spec(d, name, summary, doc, inputs, program,
                         [first, ("pi", pi, (len(names),), "the model's standard parameters (kg, kg*m, kg*m^2; "
                                  "drives as a serial model's)", "")])
    return dataclasses.replace(spec, outputs=tuple(dataclasses.replace(o, elements=names) for o in spec.outputs))

