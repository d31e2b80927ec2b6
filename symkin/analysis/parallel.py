"""Parallel mechanisms in the analyses: working mode, reachability by closed-form IK, Jacobians at (q, p).

A parallel mechanism's generated functions differ from a serial arm's (see README):
``fk(q)`` returns ``position`` and ``margin`` (NaN where the legs cannot be assembled),
``ik(p)`` returns ``joints`` and per-leg ``margin`` (NaN where p is out of reach) and the
velocity functions take both ``q`` and ``p``: ``jacobian(q, p)`` is J = J_x^-1 J_q
(seed eq. 8.29).

**Working mode.**  Both closed forms choose one of two roots: ``ik`` the branch of each
leg (the DELTA's knee outwards), ``fk`` the assembly (the DELTA's TCP below its elbows).
The workspace analysed here is the set of TCP positions reachable *in the model's
declared working mode* (``ik_branch`` and ``fk_branch`` of the model file): p with
q = ik(p) within the joint limits and fk(q) = p; in joint space, q within the limits with
ik(fk(q)) = q.  On that set q <-> p is one-to-one, so the joint domain (dW = |det J| dq)
and the Cartesian domain (dW = 1_W(p) dp) of :mod:`symkin.analysis.global_indices`
integrate over the same workspace and give the same GCI (tested).  Configurations of
another working mode (e.g. a DELTA leg with its knee inwards, reached from the box of
actuator angles through a leg singularity det J_q = 0) are outside; at that boundary
|det J| = |det J_q| / |det J_x| vanishes, so the joint-domain integrand stays continuous.

**Passive-joint limits** (``limits`` on leg joints, recorded in the manifest) are part of
the working mode: a configuration or point counts only if its passive joint variables,
found from the generated loop closure on the home assembly's branch, are within them
(:mod:`symkin.analysis.passive`; unresolved poses count as unreachable, with a warning).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin.analysis import mechanism, passive
from symkin.ik.rotations import wrap_angle

#: Largest |ik(fk(q)) - q| (rad or m) of a configuration in the working mode.  The two
#: roots of a leg differ by far more except next to the leg singularity where they
#: meet, and there the integrand vanishes.
JOINT_ROUND_TRIP_TOLERANCE = 1e-6
#: Largest |fk(ik(p)) - p| relative to the size of the mechanism (metres).
POSITION_ROUND_TRIP_TOLERANCE = 1e-6


def _require(model: Any, names: tuple[str, ...]) -> None:
    for name in names:
        mechanism.parallel_function(model, name)


def working_mode(model: Any, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """TCP positions of configurations q (..., n) and whether each is in the working mode.

    Returns:
        (p, inside): p = fk(q) (..., 3), NaN where the legs cannot be assembled; inside:
        boolean (...), fk assembles, ik(fk(q)) = q and the declared passive-joint limits hold
        (the actuators' joint limits are not checked here).
    """
    _require(model, ("fk", "ik"))
    q = np.asarray(q, dtype=np.float64)
    with np.errstate(invalid="ignore"):  # the closed forms take sqrt of negative margins: NaN, as documented
        p = model.fk(q).position
        back = model.ik(np.where(np.isfinite(p), p, 0.0)).joints
        error = np.abs(np.where(mechanism.revolute_mask(model), wrap_angle(back - q), back - q))
        inside = np.isfinite(p).all(axis=-1) & np.all(error <= JOINT_ROUND_TRIP_TOLERANCE, axis=-1)
    limits = passive.declared_limits(model)
    if limits is not None:
        batch = inside.shape
        inside = passive.admissible(model, limits, q.reshape(-1, q.shape[-1]), p.reshape(-1, p.shape[-1]),
                                    inside.reshape(-1)).reshape(batch)
    return p, inside


def jacobian_in_working_mode(model: Any, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """J(q, fk(q)) (..., 3, n) and the working-mode mask (...) of configurations q (see :func:`working_mode`)."""
    p, inside = working_mode(model, q)
    return model.jacobian(q, np.where(np.isfinite(p), p, 0.0)), inside


@dataclass(frozen=True)
class ParallelInverse:
    """The generated closed-form ``ik`` as an :class:`~symkin.analysis.inverse.InverseKinematics`.

    One branch (the model's working mode): a point is valid where every leg reaches it
    (margin >= 0), the forward kinematics of the solution returns to it and the passive
    joint variables are within their declared limits.

    Attributes:
        model: the loaded parallel model (with ``ik`` and ``fk``).
        size: a length of the mechanism (m) that scales the round-trip tolerance.
        passive_limits: the declared passive-joint limits, None if there are none.
    """

    model: Any
    size: float
    passive_limits: passive.PassiveLimits | None = None
    dimension: int = 3
    branches: int = 1

    def solve(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        points = np.asarray(points, dtype=np.float64)
        with np.errstate(invalid="ignore"):  # NaN where out of reach, as documented
            q = self.model.ik(points).joints
            finite = np.isfinite(q).all(axis=-1)
            p = self.model.fk(np.where(finite[:, None], q, 0.0)).position
            returns = np.all(np.abs(p - points) <= POSITION_ROUND_TRIP_TOLERANCE * self.size, axis=-1)
        valid = finite & returns
        if self.passive_limits is not None:
            valid = passive.admissible(self.model, self.passive_limits, q, points, valid)
        return q[:, None, :], valid[:, None]


def parallel_inverse(model: Any) -> ParallelInverse:
    """The closed-form inverse kinematics of a parallel mechanism with a translational platform.

    Raises:
        ValueError: the model is not parallel, its platform also rotates (pose task space),
            it lacks the generated ``ik`` or ``fk``, or its passive-joint limits are malformed
            or cannot be evaluated (no generated ``closure``).
    """
    if not mechanism.is_parallel(model):
        raise ValueError(f"{model.name}: not a parallel mechanism")
    if tuple(mechanism.task_space(model)) != mechanism.POSITION_COMPONENTS:
        raise ValueError(f"{model.name}: the Cartesian workspace of a platform that also rotates "
                         f"(task space {list(mechanism.task_space(model))}) is not analysed yet")
    _require(model, ("ik", "fk", "jacobian"))
    home = model.manifest["model"]["parallel"].get("home")
    if home is None:
        raise ValueError(f"{model.name}: declare a home pose (parallel.home) to scale the workspace analyses")
    size = max(float(np.linalg.norm(home)), 1e-3)
    return ParallelInverse(model, size, passive.declared_limits(model))

