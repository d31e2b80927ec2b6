"""Do the legs constrain the platform to the motion the model declares?  A check at the home pose (issue 31).

``parallel.motion`` names the platform's coordinates and holds the others at 0 in every derived function; the
legs must do the same physically.  At the home pose, with the legs assembled (q and s solved from the generated
closure by Gauss-Newton), each leg i lets the platform move with the twists of its joints' span S_i (base frame,
twists (w, v) with v the velocity of the body point at the base origin: r x a for a turn about the axis a through
r, (0, a) for a slide along a).  The platform's possible twists are the intersection of the legs' spans (Hunt;
Kong and Gosselin, *Type Synthesis of Parallel Mechanisms*, 2007, ch. 2): with the actuators free they must be the
declared coordinates' twists exactly, with the actuators locked there must be none.  A platform that is a point
(no angle among its coordinates and every leg attached there, the pantograph's handle) is judged by the velocity
of that point: its spin in the joint is idle.

Subspaces are compared by their singular values: a direction counts when its singular value exceeds
:data:`RANK_TOLERANCE` of the largest (a generic pose is far from both a rank drop and rounding), so the check
is numerical and made at one pose; a home pose at a singularity is reported as such.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sympy

from symkin.derivation import Derivation
from symkin.errors import ModelError
from symkin.model import coordinates, joint_kinds
from symkin.model.schema import Model
from symkin.parallel.assembly import STARTS, assembler
from symkin.parallel.inputs import passive_symbols, task_symbols
from symkin.parallel.quantities import ParallelStructure, parallel_structure

#: A singular value below this fraction of the largest is a direction the subspace does not have.
RANK_TOLERANCE = 1e-8
AXES = ("x", "y", "z")
#: How to mend a parallel.motion the legs contradict (the problems say how they differ).
MOTION_FIX = ("declare the coordinates the legs let the platform move in (symkin mobility MODEL prints them), or change "
              "the legs")


@dataclass(frozen=True)
class MotionCheck:
    """What the legs allow at the home pose.

    Attributes:
        problems: why the legs and ``parallel.motion`` disagree (empty: they agree).
        free: the dimension of the platform's motion with the actuators free.
        locked: the dimension with the actuators locked.
        note: why the check could not be made (then ``problems`` is empty), else "".
    """

    problems: tuple[str, ...]
    free: int = 0
    locked: int = 0
    note: str = ""


def _null_space(A: np.ndarray) -> np.ndarray:
    """An orthonormal basis (columns) of the null space of A."""
    if A.shape[0] == 0:
        return np.eye(A.shape[1])
    _, S, Vt = np.linalg.svd(A)
    rank = int(np.sum(S > RANK_TOLERANCE * (S[0] if len(S) else 0.0)))
    return Vt[rank:].T


def intersection(spans: list[np.ndarray]) -> np.ndarray:
    """A basis (6 x k) of the twists in every span (each 6 x n_i): T = S_i a_i for all i."""
    sizes = [S.shape[1] for S in spans]
    rows = []
    for i, S in enumerate(spans):
        row = [np.eye(6)] + [np.zeros((6, n)) for n in sizes]
        row[1 + i] = -S
        rows.append(np.hstack(row))
    null = _null_space(np.vstack(rows))
    twists = null[:6]
    if twists.size == 0:
        return np.zeros((6, 0))
    U, S, _ = np.linalg.svd(twists, full_matrices=False)
    return U[:, S > RANK_TOLERANCE * max(S.max(initial=0.0), 1.0)]


def _joint_twists(structure: ParallelStructure, values: dict[sympy.Symbol, float]) -> list[list[tuple[np.ndarray, bool]]]:
    """Per leg, per elementary joint motion: its twist (w, v) at the assembled pose and whether it is actuated."""
    out = []
    for chain in structure.chains:
        actuated = {sympy.Symbol(j.variables[j.active], real=True) for j in chain.leg.joints if j.active is not None}
        twists = []
        for motion in chain.motions:
            a = np.array(sympy.Matrix(motion.direction).xreplace(values).evalf(), dtype=float).ravel()
            r = np.array(sympy.Matrix(motion.point).xreplace(values).evalf(), dtype=float).ravel()
            linear, angular = joint_kinds.twist_column(motion.rotation, a, r, np.zeros(3))  # at the base origin
            twist = np.concatenate([angular, linear])
            twists.append((twist, motion.variable in actuated))
        out.append(twists)
    return out


def _declared_twists(model: Model, structure: ParallelStructure, home: dict[sympy.Symbol, float]) -> np.ndarray:
    """The twists of the declared coordinates at home (6 x m): w from dR/dp R^T, v = dP/dp - w x P."""
    R, P = sympy.Matrix(structure.platform.R), sympy.Matrix(structure.platform.p)
    at_home = np.array(P.xreplace(home).evalf(), dtype=float).ravel()
    columns = []
    for s in task_symbols(model):
        W = np.array((R.diff(s) * R.T).xreplace(home).evalf(), dtype=float)
        w = np.array([W[2, 1], W[0, 2], W[1, 0]])
        v = np.array(P.diff(s).xreplace(home).evalf(), dtype=float).ravel() - np.cross(w, at_home)
        columns.append(np.concatenate([w, v]))
    return np.array(columns).T


def _direction(vector: np.ndarray) -> str:
    """A unit direction as text, rounding noise of the SVD shown as 0, its largest component positive (a subspace's
    basis vector has either sign: which one the SVD returns depends on rounding)."""
    unit = vector / np.linalg.norm(vector)
    unit = unit if unit[int(np.argmax(np.abs(unit)))] > 0 else -unit
    unit = np.where(np.abs(unit) < 1e-9, 0.0, unit) + 0.0
    return f"({unit[0]:.3g}, {unit[1]:.3g}, {unit[2]:.3g})"


def _describe(twist: np.ndarray) -> str:
    """A twist in words: its turn, or its slide, and the coordinate it is where it is along a base axis."""
    w, v = twist[:3], twist[3:]
    turns = np.linalg.norm(w) > RANK_TOLERANCE * max(float(np.linalg.norm(twist)), 1.0)
    vector = w if turns else v
    unit = np.abs(vector) / np.linalg.norm(vector)
    axis = int(np.argmax(unit))
    coordinate = (("roll", "pitch", "yaw") if turns else AXES)[axis] if unit[axis] > 1 - 1e-9 else None
    text = f"turn about {_direction(w)}" if turns else f"slide along {_direction(v)}"
    return text if coordinate is None else f"{text} (its coordinate {coordinate})"


def _point_velocities(twists: np.ndarray, point: np.ndarray) -> np.ndarray:
    """The velocities v + w x point of the body point at ``point`` under each twist (columns)."""
    return twists[3:] + np.cross(twists[:3].T, point).T


def check_platform_motion(model: Model) -> MotionCheck:
    """Compare the platform motion the legs allow at the home pose with ``parallel.motion`` (module docstring)."""
    parallel = model.parallel
    assert parallel is not None
    if parallel.home is None:
        return MotionCheck((), note="no parallel.home: the motion is checked at the home pose")
    derivation = Derivation(model)
    structure = derivation[parallel_structure]
    values = model.parameter_values
    home_values = [float(sympy.sympify(e).xreplace(values)) for e in parallel.home]
    assembled = assembler(derivation)(np.array(home_values))
    if assembled is None:
        return MotionCheck((), note=f"the legs did not close at the home pose from {STARTS + 1} starts "
                                    "(Gauss-Newton on the closure): the motion was not checked")
    q, s = assembled
    joints = dict(zip(coordinates.symbols(model, "q") + passive_symbols(model), [*q, *s]))
    joints.update(dict(zip(task_symbols(model), home_values)))
    joints.update({k: float(v) for k, v in values.items()})
    legs = _joint_twists(structure, joints)
    free = intersection([np.array([t for t, _ in leg]).T for leg in legs])
    locked = intersection([np.array([t for t, active in leg if not active] or [np.zeros(6)]).T for leg in legs])
    declared = _declared_twists(model, structure, joints)
    attachments = {tuple(np.round(np.array(sympy.Matrix(c.attachment.p).xreplace(joints).evalf(), dtype=float).ravel(),
                                  12)) for c in structure.chains}
    point_platform = not set(model.task_space) & {"roll", "pitch", "yaw"} and len(attachments) == 1
    if point_platform:
        point = np.array(sympy.Matrix(structure.platform.p).xreplace(joints).evalf(), dtype=float).ravel()
        free, locked, declared = (_point_velocities(t, point) for t in (free, locked, declared))
    problems = []
    names = ", ".join(model.task_space)
    if locked.size and np.linalg.svd(locked, compute_uv=False).max(initial=0.0) > RANK_TOLERANCE:
        problems.append(f"with the actuators locked the legs still let the platform {_describe_any(locked, point_platform)}: "
                        "the actuators do not hold it at the home pose (a singular home pose, or a leg without an "
                        "actuator's constraint)")
    outside = free - declared @ np.linalg.lstsq(declared, free, rcond=None)[0]
    if outside.size and np.linalg.norm(outside, axis=0).max(initial=0.0) > RANK_TOLERANCE:
        column = outside[:, int(np.argmax(np.linalg.norm(outside, axis=0)))]
        problems.append(f"the legs let the platform {_describe_any(column[:, None], point_platform)}, which "
                        f"parallel.motion [{names}] holds at 0: declare that coordinate or add legs that constrain it")
    missing = declared - free @ np.linalg.lstsq(free, declared, rcond=None)[0] if free.size else declared
    for k, name in enumerate(model.task_space):
        if np.linalg.norm(missing[:, k]) > RANK_TOLERANCE * max(float(np.linalg.norm(declared[:, k])), 1.0):
            problems.append(f"the legs do not let the platform move in its coordinate {name} at the home pose")
    rank = (lambda M: int(np.sum(np.linalg.svd(M, compute_uv=False) > RANK_TOLERANCE)) if M.size else 0)
    return MotionCheck(tuple(problems), rank(free), rank(locked))


def require_declared_motion(model: Model) -> MotionCheck:
    """The check of a parallel model (:func:`check_platform_motion`), refused where the legs contradict
    ``parallel.motion``.

    Raises:
        ModelError: the problems, each located at the model file's ``parallel.motion``, with the fix.
    """
    motion = check_platform_motion(model)
    if motion.problems:
        raise ModelError([model.problem(("parallel", "motion"), problem, MOTION_FIX) for problem in motion.problems])
    return motion


def _describe_any(twists: np.ndarray, point_platform: bool) -> str:
    """The first twist (column) in words; a point platform's columns are its point's velocities."""
    column = twists[:, 0]
    return f"move along {_direction(column)}" if point_platform else _describe(column)
