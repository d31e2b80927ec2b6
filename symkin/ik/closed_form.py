"""Closed-form inverse kinematics: every solution branch of the mechanisms whose structure allows it.

A solver is chosen by recognising the structure of the joint axes at q = 0
(:mod:`symkin.ik.screws`), not by the model's name or DH convention:

* :mod:`symkin.ik.planar` - two parallel revolute axes with a position target in their
  plane (the seed's planar arm): two elbow branches;
* :mod:`symkin.ik.ur` - six revolute axes with axes 2, 3, 4 parallel, axis 5 normal to
  them, axis 6 normal to 5 and intersecting it (the Universal Robots family): eight
  branches (shoulder, wrist, elbow).

Every candidate is checked by evaluating the generated ``fk`` at it: a branch is ``valid``
only if it reproduces the target (never an approximation), ``within_limits`` after its
revolute angles are shifted by multiples of 2 pi into the joint limits (nearest to a
reference configuration).  Singular configurations are flagged per branch (see
:class:`BranchFlag`); an unreachable target has no valid branch and says why.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from symkin.errors import GeneratedCodeError
from symkin.ik.problem import ModelKinematics, Residual, as_target, residual_for
from symkin.mechanism.limits import wrap_angle
from symkin.ik.screws import HomeScrews, home_screws
from symkin.runtime.info import GeneratedModel

#: Branches whose separating quantity (relative to the mechanism's scale, or an angle in
#: rad) is below this are flagged singular: the branches coincide there, and the joints the
#: singularity couples are determined only in combination.
SINGULARITY_EPSILON = 1e-9
#: Largest residual (relative to max(1, |target position|), rad for angles) for which a
#: candidate counts as a solution; the solvers reach about 1e-15.
VALID_TOLERANCE = 1e-9
#: Tolerance of the structure tests on unit axis directions and (relative) distances.
STRUCTURE_TOLERANCE = 1e-9


class BranchFlag(enum.IntFlag):
    """What happened on the way to one branch (combine with ``|``; 0 = a regular solution)."""

    SHOULDER = 1
    """Shoulder singularity: the branches of the first joint coincide (or it is undetermined)."""
    ELBOW = 2
    """Elbow singularity: the arm is stretched or folded, the two elbow branches coincide."""
    WRIST = 4
    """Wrist singularity (UR: q5 = 0 or pi): only a combination of the coupled joints is determined."""
    CLAMPED = 8
    """A rounding-size negative factor was clamped to zero: the target is on the workspace boundary."""
    UNREACHABLE_SHOULDER = 16
    """No first-joint angle exists: the wrist point lies too close to the first axis."""
    UNREACHABLE_ELBOW = 32
    """No elbow angle exists: the target is beyond the reach of the arm (or too close to its base)."""

    @classmethod
    def describe(cls, value: int) -> str:
        names = [(flag.name or "").lower().replace("_", " ") for flag in cls if value & flag]
        return ", ".join(names) if names else "regular"


UNREACHABLE = BranchFlag.UNREACHABLE_SHOULDER | BranchFlag.UNREACHABLE_ELBOW


class Solver(Protocol):
    """A structure-specific closed-form solver (see :mod:`symkin.ik.planar`, :mod:`symkin.ik.ur`)."""

    name: str
    kind: str
    branches: tuple[str, ...]

    def candidates(self, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(q (..., k, n), flags (..., k)) for targets of shape (..., *target_shape)."""
        ...


#: Recognisers, tried in order: recogniser(kinematics, screws) -> Solver or None (the
#: modules of the solvers register themselves; symkin.ik imports them all).
RECOGNISERS: list[Callable[[ModelKinematics, HomeScrews], Solver | None]] = []


@dataclass(frozen=True)
class ClosedFormSolutions:
    """All branches for a batch of targets (batch shape ``...``, k branches, n joints).

    Attributes:
        q: (..., k, n) joint coordinates per branch (NaN where the branch does not exist).
        valid: (..., k) the branch reproduces the target through the generated fk.
        within_limits: (..., k) the branch lies within the joint limits.
        flags: (..., k) :class:`BranchFlag` values.
        position_error, orientation_error: (..., k) residual of fk(q) against the target.
        branches: the names of the k branches.
        solver: the name of the solver.
    """

    q: np.ndarray
    valid: np.ndarray
    within_limits: np.ndarray
    flags: np.ndarray
    position_error: np.ndarray
    orientation_error: np.ndarray
    branches: tuple[str, ...]
    solver: str

    @property
    def usable(self) -> np.ndarray:
        """(..., k) valid and within the joint limits."""
        return self.valid & self.within_limits

    @property
    def reachable(self) -> np.ndarray:
        """(...,) at least one usable branch."""
        return np.any(self.usable, axis=-1)

    def describe(self, index: tuple[int, ...] = ()) -> list[str]:
        """Lines describing every branch of the target at ``index`` of the batch."""
        lines = []
        for k, branch in enumerate(self.branches):
            at = index + (k,)
            flags = BranchFlag.describe(int(self.flags[at]))
            if not self.valid[at]:
                lines.append(f"{branch}: no solution ({flags})")
                continue
            limits = "" if self.within_limits[at] else ", outside the joint limits"
            lines.append(f"{branch}: q = [{', '.join(f'{v:.12g}' for v in self.q[at])}] ({flags}{limits}; "
                         f"residual {self.position_error[at]:.2g}, {self.orientation_error[at]:.2g} rad)")
        return lines


class ClosedFormIK:
    """A recognised closed-form solver bound to a model's generated functions.

    Use :func:`closed_form_solver` to get one.
    """

    def __init__(self, kinematics: ModelKinematics, solver: Solver):
        self.kinematics = kinematics
        self.solver = solver
        self.residual: Residual = residual_for(kinematics, solver.kind)

    @property
    def name(self) -> str:
        return self.solver.name

    @property
    def kind(self) -> str:
        return self.solver.kind

    def solve(self, target: np.ndarray | Sequence, reference: np.ndarray | Sequence | None = None, *,
              shift: bool = True) -> ClosedFormSolutions:
        """Every branch for targets (..., *target shape).

        Args:
            target: pose (..., 4, 4) or task-space targets (..., m), per :attr:`kind`.
            reference: configuration (n,) or (..., n): each revolute angle is shifted by a
                multiple of 2 pi into the joint limits, as close to the reference as possible
                (default: zero).
            shift: False keeps the solver's own angles (no 2 pi shifts, ``reference`` unused;
                ``within_limits`` then says whether they happen to lie inside), for callers
                that apply joint limits of their own (the workspace analyses).
        """
        target = as_target(self.residual, target)
        tshape = self.residual.target_shape()
        batch = target.shape[:target.ndim - len(tshape)]
        q, flags = self.solver.candidates(target)
        kin = self.kinematics
        if shift:
            ref = np.zeros(kin.dof) if reference is None else np.asarray(reference, dtype=float)
            q, within = _into_limits(kin, q, ref[..., None, :])
        else:
            within = kin.within_limits(q)  # False where q is NaN (no such branch)
        branches = len(self.solver.branches)
        q_eval = np.where(np.isfinite(q), q, 0.0)
        expanded = np.broadcast_to(target[..., None, :, :] if self.kind == "pose" else target[..., None, :],
                                   batch + (branches,) + tshape)
        e = self.residual.error(q_eval, expanded)
        lengths, angles = self.residual.split_norms(e)
        scale = self.residual.length_scale(expanded)
        exists = np.all(np.isfinite(q), axis=-1) & ((flags & UNREACHABLE) == 0)
        valid = exists & (lengths <= VALID_TOLERANCE * scale) & (angles <= VALID_TOLERANCE)
        lengths = np.where(exists, lengths, np.nan)
        angles = np.where(exists, angles, np.nan)
        return ClosedFormSolutions(q, valid, within & valid, flags.astype(int), lengths, angles,
                                   self.solver.branches, self.solver.name)


def _into_limits(kin: ModelKinematics, q: np.ndarray, reference: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Shift revolute angles by 2 pi k into [lower, upper], nearest to ``reference`` (an angle that
    no shift brings inside is left nearest to the reference)."""
    two_pi = 2.0 * np.pi
    nearest = reference + wrap_angle(q - reference)
    lower, upper = kin.lower, kin.upper
    # the representative nearest the reference, then moved into the limits if it is outside
    up = np.ceil((lower - nearest) / two_pi)
    down = np.floor((upper - nearest) / two_pi)
    shift = np.where(nearest < lower, up, np.where(nearest > upper, down, 0.0))
    moved = nearest + two_pi * np.where(np.isfinite(shift), shift, 0.0)
    inside = (moved >= lower) & (moved <= upper)
    shifted = np.where(kin.revolute, np.where(inside, moved, nearest), q)
    finite = np.all(np.isfinite(shifted), axis=-1)
    within = finite & np.all((shifted >= lower) & (shifted <= upper), axis=-1)
    return shifted, within


def closed_form_solver(model: GeneratedModel | ModelKinematics,
                       limits: Sequence[tuple[float, float]] | None = None) -> ClosedFormIK | None:
    """The closed-form solver of ``model``'s structure, or None if no known structure matches
    (or it is no serial chain: a parallel mechanism, whose IK is generated code of its own, or a view of a
    hybrid device as a whole, symkin.mechanism.device)."""
    if not isinstance(model, ModelKinematics) and model.info.mechanism != "serial":
        return None
    kin = model if isinstance(model, ModelKinematics) else ModelKinematics(model, limits)
    try:
        screws = home_screws(kin)
        for recognise in RECOGNISERS:
            solver = recognise(kin, screws)
            if solver is not None:
                return ClosedFormIK(kin, solver)
    except GeneratedCodeError:  # not a plain serial chain, or its residual lacks a generated function
        return None
    return None


def register(recogniser: Callable[[ModelKinematics, HomeScrews], Solver | None]):
    """Decorator adding a recogniser to :data:`RECOGNISERS`."""
    RECOGNISERS.append(recogniser)
    return recogniser
