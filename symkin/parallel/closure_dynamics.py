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

import sympy

from symkin.errors import DerivationError
from symkin.ir.inputs import coordinate_input
from symkin.ir.quantity import Deriving, quantity
from symkin.ir.spec import FunctionSpec, InputSpec, OutputSpec, make_function
from symkin.model import coordinates
from symkin.model.schema import Body, Model
from symkin.parallel.inertia import about_origin, platform_side
from symkin.parallel.inputs import TASK_UNITS, passive_input, passive_symbols, passive_variables, task_input, task_symbols
from symkin.parallel.legs import LegChain
from symkin.parallel.quantities import (PARALLEL, ParallelStructure, actuated_input, closure_jacobian_matrices, jacobian,
                                        parallel_structure, reduced_legs)


def rate_symbols(symbols: tuple[sympy.Symbol, ...]) -> tuple[sympy.Symbol, ...]:
    """The rate of each coordinate symbol, named as the coordinates' velocities (``x`` -> ``x_d``)."""
    return tuple(sympy.Symbol(coordinates.symbol_name("qd", s.name), real=True) for s in symbols)


def _rate_inputs(model: Model) -> tuple[InputSpec, InputSpec, InputSpec]:
    """The inputs qd, sd, pd."""
    passive = passive_variables(model)
    sd = InputSpec("sd", "vector", rate_symbols(passive_symbols(model)), tuple(name for name, _ in passive),
                   tuple("rad/s" if rotation else "m/s" for _, rotation in passive), "passive joint velocities")
    pd = InputSpec("pd", "vector", rate_symbols(task_symbols(model)), model.task_space,
                   tuple(f"{TASK_UNITS[c]}/s" for c in model.task_space), "task velocities of the platform (TCP)")
    return coordinate_input(model, "qd"), sd, pd


def _link_mass_matrix(body: Body, chain: LegChain, joint: int, index: dict[sympy.Symbol, int], size: int
                      ) -> tuple[sympy.Matrix, sympy.Matrix]:
    """(M contribution over z, m c_w) of the link moved by the leg's joint ``joint``."""
    frame = chain.links[joint]
    R = sympy.Matrix(frame.R)
    c = sympy.Matrix(frame.p) + R * sympy.Matrix(body.com)
    inertia = R * sympy.Matrix(body.inertia) * R.T
    moved = sum(len(j.variables) for j in chain.leg.joints[:joint + 1])
    Jv, Jw = sympy.zeros(3, size), sympy.zeros(3, size)
    for motion in chain.motions[:moved]:
        w = sympy.Matrix(motion.direction)
        column = index[motion.variable]
        if motion.rotation:
            Jv[:, column] = w.cross(c - sympy.Matrix(motion.point))
            Jw[:, column] = w
        else:
            Jv[:, column] = w
    return body.mass * Jv.T * Jv + Jw.T * inertia * Jw, body.mass * c


def _variables(model: Model) -> tuple[sympy.Symbol, ...]:
    """z = (q, s, p)."""
    return coordinates.symbols(model, "q") + passive_symbols(model) + task_symbols(model)


def _mass_and_potential(d: Deriving) -> tuple[sympy.Matrix, sympy.Expr]:
    """M_z and u over z (see the module docstring)."""
    model = d.model
    assert model.parallel is not None and model.parallel.bodies is not None
    bodies = model.parallel.bodies
    structure: ParallelStructure = d[parallel_structure]
    z = _variables(model)
    index = {symbol: k for k, symbol in enumerate(z)}
    M = sympy.zeros(len(z), len(z))
    moment = sympy.zeros(3, 1)
    by_joint = {body.link: body for body in bodies.links}
    for chain in structure.chains:
        for k, joint in enumerate(chain.leg.joints):
            if joint.name in by_joint:
                term, first_moment = _link_mass_matrix(by_joint[joint.name], chain, k, index, len(z))
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


@quantity("closure_dynamics", "M_z, h_z = V_z + G_z and the closure's acceleration term gamma over z = (q, s, p), for "
          "legs without the distance form", mechanism=PARALLEL)
def _closure_dynamics(d: Deriving) -> FunctionSpec:
    _check_bodies(d)
    model = d.model
    z = _variables(model)
    qd, sd, pd = _rate_inputs(model)
    zd = sympy.Matrix(qd.symbols + sd.symbols + pd.symbols)
    M, u = _mass_and_potential(d)
    partials = [M.diff(symbol) for symbol in z]
    # V_k = sum_ij (dM_kj/dz_i - 1/2 dM_ij/dz_k) zd_i zd_j: dM/dt zd - 1/2 d(zd^T M zd)/dz
    M_dot = sum((partials[i] * zd[i] for i in range(len(z))), sympy.zeros(len(z), len(z)))
    V = M_dot * zd - sympy.Matrix([(zd.T * partials[k] * zd)[0] for k in range(len(z))]) / 2
    G = sympy.Matrix([sympy.diff(u, symbol) for symbol in z])
    Phi_p, Phi_q, Phi_s = closure_jacobian_matrices(d)
    Phi = sympy.Matrix.hstack(Phi_q, Phi_s, Phi_p)
    gamma = jacobian(Phi * zd, z) * zd
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
