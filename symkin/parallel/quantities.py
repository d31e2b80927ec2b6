"""Quantities of parallel mechanisms, registered in the derivation graph (``mechanism="parallel"``).

=========================  ===================================================================
``parallel_structure``     (internal) every leg walked once, and the platform frame
``closure``                loop-closure residual Phi(q, s, p), 6 rows per leg (seed sec. 3.2 steps 1-2)
``closure_jacobians``      implicit Jacobians Phi_p, Phi_q, Phi_s of the closure
``leg_joints``             every joint centre of every leg and its end at (q, s) (drawing legs without a distance form)
``distance_legs``          (internal) legs reduced to f_i(q_i, p) = (|B_i - C_i|^2 - L_i^2)/2
``constraints``            f(q, p), one equation per leg
``constraint_jacobians``   J_x = df/dp, J_q = -df/dq: J_x pdot = J_q qdot
``leg_points``             joint centres A_i, C_i(q), B_i(p) of every leg (drawing)
``ik``                     closed-form inverse kinematics q(p) with per-leg margins
``fk``                     closed-form forward kinematics p(q) by trilateration (3 legs, translation)
``jacobian``               task Jacobian J = J_x^-1 J_q: pdot = J qdot (seed eq. 8.29)
``inverse_jacobian``       J^-1 = J_q^-1 J_x: qdot = J^-1 pdot (seed eq. 8.30)
``singularities``          det J_q (workspace boundary) and det J_x (interior) (seed sec. 4.2)
=========================  ===================================================================

Coordinates (``docs/model-format.md``, "Coordinates of parallel mechanisms"): q are the
actuated joint variables, p the task coordinates of the platform, s the passive joint
variables.  Velocity functions take both q and p: evaluate them at a consistent pair,
p = fk(q) or q = ik(p).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import sympy

from symkin.errors import DerivationError
from symkin.ir.inputs import coordinate_input
from symkin.ir.quantity import Deriving, quantity
from symkin.ir.spec import FunctionSpec, OutputSpec, make_function
from symkin.kinematics.chain import Frame
from symkin.model import coordinates
from symkin.model.schema import PlatformMotion
from symkin.parallel import closed_form, closure, determinant, distance
from symkin.parallel.inputs import (
    passive_input,
    passive_symbols,
    task_input,
    task_symbols,
)
from symkin.parallel.legs import LegChain, platform_frame, walk


PARALLEL = "parallel"


@dataclass(frozen=True)
class ParallelStructure:
    """The platform frame base_T_platform(p) and every walked leg."""

    platform: Frame
    chains: tuple[LegChain, ...]


def actuated_input(d: Deriving):
    return coordinate_input(d.model, "q")


def jacobian(rows: sympy.Matrix, symbols: tuple[sympy.Symbol, ...]) -> sympy.ImmutableMatrix:
    """d rows / d symbols, differentiating each row only by the symbols it contains (legs are sparse)."""
    out = sympy.zeros(len(rows), len(symbols))
    for i, row in enumerate(rows):
        present = row.free_symbols
        for j, s in enumerate(symbols):
            if s in present:
                out[i, j] = sympy.diff(row, s)
    return sympy.ImmutableMatrix(out)


def _branch_text(sigma: int) -> str:
    return "positive" if sigma > 0 else "negative"


@quantity("parallel_structure", "legs walked from the base and the platform frame", emitted=False, mechanism=PARALLEL)
def parallel_structure(d: Deriving) -> ParallelStructure:
    assert d.model.parallel is not None
    return ParallelStructure(platform_frame(d.model), tuple(walk(leg) for leg in d.model.parallel.legs))


# --------------------------------------------------------------------------- generic loop closure

@quantity("leg_closures", "closure equations of every leg", emitted=False, mechanism=PARALLEL)
def _leg_closures(d: Deriving) -> tuple[closure.LegClosure, ...]:
    structure: ParallelStructure = d[parallel_structure]
    return tuple(closure.LegClosure(structure.platform, chain) for chain in structure.chains)


@quantity("closure_residual", "loop-closure equations Phi(q, s, p) (sympy)", emitted=False, mechanism=PARALLEL)
def _closure_residual(d: Deriving) -> sympy.ImmutableMatrix:
    return sympy.ImmutableMatrix([e for leg in d[_leg_closures] for e in leg.residual()])


def _closure_rows(d: Deriving) -> str:
    return ", ".join(f"{leg.name}: x, y, z, rx, ry, rz" for leg in d.model.parallel.legs)  # type: ignore[union-attr]


@quantity("closure", "loop-closure residual Phi(q, s, p), 6 rows per leg (zero when the legs close)",
          mechanism=PARALLEL, residual=True)
def closure_spec(d: Deriving) -> FunctionSpec:
    phi = d[_closure_residual]
    return make_function(
        d.model, "closure", "Loop-closure residual of every leg.",
        "Seed sec. 3.2, inverse kinematics steps 1-2: the closed vector chain of each leg, split into "
        "Cartesian components: the end of the leg's joint chain minus the platform attachment "
        "(position rows) and 2 vee(E - E^T) / (1 + trace E) = 2 tan(angle/2) axis of the residual rotation "
        "E = R_attachment^T R_end (orientation rows). "
        "Zero exactly when the mechanism is assembled at (q, s, p).",
        [actuated_input(d), passive_input(d.model), task_input(d.model)],
        [OutputSpec("phi", phi, f"residual rows ({_closure_rows(d)})", shape=(len(phi),))],
    )


def closure_jacobian_matrices(d: Deriving) -> tuple[sympy.ImmutableMatrix, ...]:
    """(Phi_p, Phi_q, Phi_s) = d phi / d (p, q, s), from the joint screws (:class:`symkin.parallel.closure.LegClosure`;
    a plain function, not a node of the graph: the derived quantities a manifest lists stay those of before)."""
    task = task_symbols(d.model)
    columns = [{**leg.joint_derivatives(), **leg.task_derivatives(task)} for leg in d[_leg_closures]]
    return tuple(sympy.ImmutableMatrix([[leg.get(s, [0] * 6)[k] for s in symbols] for leg in columns for k in range(6)])
                 for symbols in (task, coordinates.symbols(d.model, "q"), passive_symbols(d.model)))


@quantity("closure_jacobians", "implicit Jacobians Phi_p, Phi_q, Phi_s of the loop closure", mechanism=PARALLEL)
def _closure_jacobians(d: Deriving) -> FunctionSpec:
    outputs = [OutputSpec(name, matrix, f"d phi / d {wrt}, rows as in closure(), one column per element of {wrt}")
               for matrix, (name, wrt) in zip(closure_jacobian_matrices(d), (("Phi_p", "p"), ("Phi_q", "q"),
                                                                              ("Phi_s", "s")))]
    return make_function(
        d.model, "closure_jacobians", "Implicit Jacobians of the loop closure.",
        "Differentiating Phi(q, s, p) = 0 gives Phi_p pdot + Phi_q qdot + Phi_s sdot = 0, the velocity "
        "relation of any leg topology; Newton steps on these matrices solve the closure numerically "
        "(symkin.runtime.parallel.solve_closure). Formed from the joint screws: a rotation about the axis w "
        "through o moves the leg end by w x (p_end - o) and turns it by w.",
        [actuated_input(d), passive_input(d.model), task_input(d.model)], outputs,
    )


@quantity("leg_joints", "every joint centre of every leg and its end, at (q, s), for legs without the distance form "
          "(drawing)", mechanism=PARALLEL)
def _leg_joints(d: Deriving) -> FunctionSpec:
    try:
        d[reduced_legs]
    except DerivationError:
        pass
    else:
        raise DerivationError(f"model '{d.model.name}': its legs have the distance form, drawn by leg_points from the "
                              "closed-form ik; leg_joints draws legs without it (from the closure's q and s)")
    outputs = [OutputSpec(c.leg.name, sympy.ImmutableMatrix([list(point) for point in (*c.centres, c.end.p)]),
                          f"leg {c.leg.name}: its joints' centres, base to platform, then its end (columns x, y, z)", "m")
               for c in d[parallel_structure].chains]
    return make_function(
        d.model, "leg_joints", "Joint centres of every leg and its end, for drawing legs of any topology.",
        "Per leg (an output named by the leg), in the base frame, walking its joints from the base: the centre of "
        "each joint (its frame's origin after the joint's origin operations, moved by the joints before it) and the "
        "end of the leg's chain, the platform attachment point where the legs close (closure() = 0). Evaluate at "
        "an assembled (q, s) (symkin.runtime.parallel.solve_closure).", [actuated_input(d), passive_input(d.model)],
        outputs)


# --------------------------------------------------------------------------- distance form

@quantity("distance_legs", "legs reduced to one distance equation each", emitted=False, mechanism=PARALLEL)
def reduced_legs(d: Deriving) -> tuple[distance.DistanceLeg, ...]:
    structure: ParallelStructure = d[parallel_structure]
    motion = d.model.parallel.motion  # type: ignore[union-attr]
    surface = {PlatformMotion.PLANAR: "plane", PlatformMotion.SPHERICAL: "sphere"}.get(motion, "space")
    legs = distance.distance_legs(structure.chains, structure.platform, surface)
    if isinstance(legs, str):
        raise DerivationError(f"model '{d.model.name}': {legs}; use the generic outputs closure and closure_jacobians "
                              "with symkin.runtime.parallel (solve_closure for its ik and fk, closure_velocities for its "
                              "Jacobian and singularities), closure_dynamics and closure_regressor for its dynamics, "
                              "closure_base_regressor for its base parameters (docs/model-format.md, 'Legs of any "
                              "topology')")
    return legs


@quantity("constraint_vector", "f(q, p) (sympy)", emitted=False, mechanism=PARALLEL)
def constraint_vector(d: Deriving) -> sympy.ImmutableMatrix:
    return sympy.ImmutableMatrix([leg.constraint for leg in d[reduced_legs]])


@quantity("constraints", "leg equations f(q, p) = (|B_i - C_i|^2 - L_i^2)/2, zero when assembled",
          mechanism=PARALLEL, residual=True)
def _constraints(d: Deriving) -> FunctionSpec:
    f = d[constraint_vector]
    return make_function(
        d.model, "constraints", "Leg equations in distance form.",
        "f_i = (|B_i(p) - C_i(q)|^2 - L_i(q)^2) / 2 for every leg: the rod between the point joints C_i and "
        "B_i has length L_i (seed sec. 3.2.1, the sphere equation about C'_i). Zero when assembled.",
        [actuated_input(d), task_input(d.model)],
        [OutputSpec("f", f, "one equation per leg", "m^2", shape=(len(f),))],
    )


@quantity("constraint_jacobian_matrices", "J_x and J_q (sympy)", emitted=False, mechanism=PARALLEL)
def _constraint_jacobian_matrices(d: Deriving) -> tuple[sympy.ImmutableMatrix, sympy.ImmutableMatrix]:
    f = sympy.Matrix(d[constraint_vector])
    J_x = jacobian(f, task_symbols(d.model))
    J_q = -jacobian(f, coordinates.symbols(d.model, "q"))
    return J_x, sympy.ImmutableMatrix(J_q)


@quantity("constraint_jacobians", "J_x = df/dp and J_q = -df/dq, so that J_x pdot = J_q qdot", mechanism=PARALLEL)
def _constraint_jacobians(d: Deriving) -> FunctionSpec:
    J_x, J_q = d[_constraint_jacobian_matrices]
    return make_function(
        d.model, "constraint_jacobians", "Jacobians of the leg equations.",
        "Differentiating f(q, p) = 0 gives the velocity relation J_x pdot = J_q qdot with J_x = df/dp "
        "(rows (B_i - C_i)^T dB_i/dp) and J_q = -df/dq (diagonal: one actuator per leg).",
        [actuated_input(d), task_input(d.model)],
        [OutputSpec("J_x", J_x, "df/dp: one row per leg, one column per task coordinate"),
         OutputSpec("J_q", J_q, "-df/dq: one row per leg, one column per actuated joint (diagonal)")],
    )


@quantity("leg_points", "joint centres of every leg: first joint A_i, proximal point joint C_i(q), platform joint "
          "B_i(p)", mechanism=PARALLEL)
def _leg_points(d: Deriving) -> FunctionSpec:
    structure: ParallelStructure = d[parallel_structure]
    legs = d[reduced_legs]
    points = [list(point) for chain, leg in zip(structure.chains, legs) for point in (chain.centres[0], leg.C, leg.B)]
    return make_function(
        d.model, "leg_points", "Joint centres of every leg, for drawing the mechanism.",
        "Per leg, in the base frame: the centre A_i of its first joint (fixed), the proximal point joint C_i(q) "
        "that the rod starts from (the DELTA's elbow; A_i itself when the rod starts at the base) and the "
        "platform joint B_i(p) = P + R(p) b_i (seed sec. 3.2.1). Evaluate at a consistent pair q = ik(p).",
        [actuated_input(d), task_input(d.model)],
        [OutputSpec("points", sympy.ImmutableMatrix(points), "rows A_1, C_1, B_1, A_2, ...: three points per leg "
                    "(columns x, y, z)", "m")],
    )


@quantity("ik", "closed-form inverse kinematics q(p) per leg, with reachability margins", mechanism=PARALLEL)
def _ik(d: Deriving) -> FunctionSpec:
    legs = d[reduced_legs]
    solutions = [closed_form.solve_leg(leg) for leg in legs]
    branches = "; ".join(f"{leg.leg.name}: {leg.q} on the {_branch_text(leg.leg.ik_branch)} branch"
                         for leg in legs)
    return make_function(
        d.model, "ik", "Inverse kinematics: actuated joint variables from the task coordinates.",
        "Per leg (seed sec. 3.2, step 3), the equation |B_i(p) - C_i(q_i)| = L_i(q_i) solved in closed form: "
        "q = atan2(gamma, beta) + sigma atan2(sqrt(beta^2 + gamma^2 - alpha^2), -alpha), in (-pi, pi] as one atan2 "
        "of its sine and cosine, for a revolute "
        "actuator (a robust form of seed eqs. 8.18-8.20), the root of a quadratic for a prismatic one. "
        f"Branches: {branches} (positive: the platform joint B_i lies at a positive rotation about the actuator "
        "axis from the elbow C_i, or the larger root of a prismatic actuator; negative: the other solution). "
        "Where a leg's margin is negative p is out of its reach and its q is NaN.",
        [task_input(d.model)],
        [OutputSpec("joints", sympy.ImmutableMatrix([s.value for s in solutions]), "actuated joint variables q",
                    shape=(len(solutions),)),
         OutputSpec("margin", sympy.ImmutableMatrix([s.margin for s in solutions]),
                    "per leg: >= 0 iff the leg reaches p (the radicand of its solution)", shape=(len(solutions),))],
    )


@quantity("fk", "closed-form forward kinematics p(q): trilateration (3 legs, translational platform) or "
          "circle intersection (2 legs, planar point)", mechanism=PARALLEL)
def _fk(d: Deriving) -> FunctionSpec:
    parallel = d.model.parallel
    assert parallel is not None
    side = _branch_text(parallel.fk_branch)
    if parallel.motion is PlatformMotion.TRANSLATION and len(parallel.legs) == 3:
        position, margin = closed_form.trilaterate(d[reduced_legs], parallel.fk_branch)
        text = ("Trilateration (seed sec. 3.2.1): P lies on the spheres of radius L_i about S_i = C_i(q) - b_i; "
                "P = S1 + w + t n with n = (S2 - S1) x (S3 - S1), w in the plane of the centres and "
                f"t = sigma sqrt(margin / |n|^2). The root on the {side} side of n is returned. Where the margin "
                "is negative the spheres do not meet and the position is NaN.")
        names, what = "x, y, z", "spheres"
    elif parallel.coordinates == ("x", "y") and len(parallel.legs) == 2:
        position, margin = closed_form.intersect_circles(d[reduced_legs], parallel.fk_branch)
        text = ("Circle intersection (the planar case of seed sec. 3.2.1): P lies on the circles in z = 0 about "
                "S_i = C_i(q) - b_i; P = S1 + w + t n with n = z x (S2 - S1), w on the line of the centres and "
                f"t = sigma sqrt(margin / |S2 - S1|^2). The assembly mode on the {side} side of S1 -> S2 is "
                "returned (positive: left, a positive turn about z). Where the margin is negative the circles do "
                "not meet and the position is NaN.")
        names, what = "x, y", "circles"
    elif parallel.motion is PlatformMotion.SPHERICAL and parallel.coordinates == ("roll", "pitch", "yaw"):
        R, margin = closed_form.orthogonal_spherical(d[reduced_legs], _home_signs(d))
        text = ("Orthogonal spherical platform (the Agile Eye; Bonev, Chablat and Wenger 2006): the platform axes "
                "f_i = R b_i are an orthonormal frame with f_i . C_i = 0; f_1 = cos phi u + sin phi v about the first "
                "middle axis, f_3 ~ C_3 x f_1, and f_2 . C_2 = 0 gives X cos 2 phi + Y sin 2 phi = Z in closed form "
                "(symkin.parallel.closed_form). Of its eight solutions the one with the home pose's root and the legs' "
                "ik branches is returned; where the margin is negative the legs cannot be assembled and the "
                "orientation is NaN.")
        return make_function(
            d.model, "fk", "Forward kinematics: platform orientation from the actuated joint variables.", text,
            [actuated_input(d)],
            [OutputSpec("orientation", sympy.ImmutableMatrix(closed_form.rpy_of(R)),
                        "platform orientation roll, pitch, yaw (R = Rz(yaw) Ry(pitch) Rx(roll))", "rad", shape=(3,)),
             OutputSpec("margin", sympy.ImmutableMatrix([margin]), ">= 0 iff the legs assemble (a real solution)",
                        "", shape=())])
    else:
        raise DerivationError(
            f"model '{d.model.name}': closed-form forward kinematics needs a translational platform on three "
            "legs (trilateration), a planar point [x, y] on two (circle intersection) or an orthogonal spherical "
            "platform (the Agile Eye); solve it numerically with symkin.runtime.parallel.solve_fk (Newton on the "
            "generated ik and inverse_jacobian)")
    return make_function(
        d.model, "fk", "Forward kinematics: TCP position from the actuated joint variables.", text,
        [actuated_input(d)],
        [OutputSpec("position", sympy.ImmutableMatrix(position), f"TCP position {names}", "m",
                    shape=(len(position),)),
         OutputSpec("margin", sympy.ImmutableMatrix([margin]), f">= 0 iff the {what} meet (a real solution)",
                    "m^2", shape=())],
    )


def _home_signs(d: Deriving) -> tuple[int, int, int]:
    """The signs (sigma, s_1, s_3) of :func:`closed_form.orthogonal_spherical` whose solution is the home pose
    (at the parameters' default values).

    Raises:
        DerivationError: none is (the home pose is not an assembly of the legs' ik).
    """
    legs, model = d[reduced_legs], d.model
    closed_form.require_orthogonal(legs)
    if model.parallel is None or model.parallel.home is None:
        raise DerivationError(f"model '{model.name}': the fk of a spherical platform returns the home pose's "
                              "assembly mode; declare parallel.home")
    values = model.parameter_values
    home = {s: sympy.sympify(e).xreplace(values) for s, e in zip(task_symbols(model), model.parallel.home)}
    q = {leg.q: closed_form.solve_leg(leg).value.xreplace(values).xreplace(home).evalf() for leg in legs}

    def at_home(vector: sympy.Matrix) -> sympy.Matrix:
        return sympy.Matrix(vector).xreplace(values).xreplace(q).evalf()
    C = [at_home(leg.C) for leg in legs]
    rates = [at_home(sympy.diff(sympy.Matrix(leg.C), leg.q)) for leg in legs]
    b = [at_home(leg.b) for leg in legs]
    target = sympy.Matrix(platform_frame(model).R).xreplace(values).xreplace(home).evalf()
    for signs in itertools.product((1, -1), repeat=3):
        R, _ = closed_form.orthogonal_frame(C, rates, sympy.sqrt(rates[0].dot(rates[0])), b,
                                            signs)  # type: ignore[arg-type]
        deviation = (R - target).norm()
        if deviation.is_number and deviation.is_finite and deviation < 1e-9:  # NaN: a degenerate sign
            return signs  # type: ignore[return-value]
    raise DerivationError(f"model '{model.name}': the home pose is not an assembly of the legs' ik, so no fk "
                          "branch can be chosen; check parallel.home and the legs' ik_branch")


def square_constraint_jacobians(d: Deriving, name: str) -> tuple[sympy.Matrix, sympy.Matrix]:
    """(J_x, J_q) of a model with as many legs as task coordinates (``name``: what needs them, for the error)."""
    J_x, J_q = d[_constraint_jacobian_matrices]
    if J_x.shape[0] != J_x.shape[1]:
        raise DerivationError(f"model '{d.model.name}': {name} needs as many legs as task coordinates")
    return sympy.Matrix(J_x), sympy.Matrix(J_q)


def platform_jacobian(d: Deriving, name: str) -> sympy.Matrix:
    """J = J_x^-1 J_q = adj(J_x) J_q / det(J_x), pdot = J qdot (``name``: what needs it, for the error)."""
    J_x, J_q = square_constraint_jacobians(d, name)
    return determinant.adjugate(J_x) * J_q / determinant.determinant(J_x)


@quantity("jacobian", "task Jacobian J = J_x^-1 J_q of the platform: pdot = J qdot", mechanism=PARALLEL)
def _jacobian(d: Deriving) -> FunctionSpec:
    J = platform_jacobian(d, "the task Jacobian")
    return make_function(
        d.model, "jacobian", "Task Jacobian of the platform.",
        "J = J_x^-1 J_q from J_x pdot = J_q qdot, so that dp = J dq (seed eq. 8.29); J_x^-1 = adj(J_x) / "
        "det(J_x). Infinite at interior singularities (det J_x = 0).",
        [actuated_input(d), task_input(d.model)],
        [OutputSpec("J", sympy.ImmutableMatrix(J), "rows: task coordinates; columns: actuated joints")],
    )


@quantity("inverse_jacobian", "inverse Jacobian J^-1 = J_q^-1 J_x: qdot = J^-1 pdot", mechanism=PARALLEL)
def _inverse_jacobian(d: Deriving) -> FunctionSpec:
    J_x, J_q = square_constraint_jacobians(d, "the inverse Jacobian")
    J_inv = sympy.Matrix([[J_x[i, j] / J_q[i, i] for j in range(J_x.shape[1])] for i in range(J_x.shape[0])])
    return make_function(
        d.model, "inverse_jacobian", "Inverse Jacobian of the platform.",
        "J^-1 = J_q^-1 J_x (J_q is diagonal), so that dq = J^-1 dp (seed eq. 8.30): row i is the derivative of "
        "leg i's actuated variable with respect to the task coordinates. Its determinant vanishes at "
        "interior singularities.",
        [actuated_input(d), task_input(d.model)],
        [OutputSpec("J_inv", sympy.ImmutableMatrix(J_inv), "rows: actuated joints; columns: task coordinates")],
    )


@quantity("singularities", "det J_q (zero at workspace-boundary singularities) and det J_x (interior)",
          mechanism=PARALLEL)
def _singularities(d: Deriving) -> FunctionSpec:
    J_x, J_q = square_constraint_jacobians(d, "the singularity measures")
    det_q = sympy.Mul(*[J_q[i, i] for i in range(J_q.shape[0])])
    return make_function(
        d.model, "singularities", "Singularity measures of both types.",
        "Seed sec. 4.2: det J_q = 0 where a leg is stretched or folded (workspace-boundary singularity: J "
        "loses rank, the TCP cannot move in some direction); det J_x = 0 where the legs' constraint "
        "directions become dependent (workspace-interior singularity: J^-1 loses rank, the platform gains "
        "a degree of freedom). det J_x is expanded by minors, a polynomial in its entries.",
        [actuated_input(d), task_input(d.model)],
        [OutputSpec("det_Jq", sympy.ImmutableMatrix([det_q]), "det J_q (boundary singularities where zero)",
                    shape=()),
         OutputSpec("det_Jx", sympy.ImmutableMatrix([determinant.determinant(J_x)]),
                    "det J_x (interior singularities where zero)", shape=())],
    )
