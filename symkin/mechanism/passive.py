"""Passive joint variables of a parallel mechanism at assembled poses, and their declared limits.

At an assembled pair (q, p) the passive joint variables s solve the generated loop closure
phi(q, s, p) = 0 (6 rows per leg: the position of the leg end and the 2 tan(angle/2) axis of
its orientation error against the platform attachment; see docs/model-format.md).  With
q and p given the system is overdetermined but consistent, so s is found by damped
Gauss-Newton on ``closure`` and ``closure_jacobians`` (Phi_s), s <- s - Phi_s^+ phi
(:func:`symkin.runtime.parallel.solve_closure`), vectorized over the batch.

**Branch.**  A U or S joint reaches the same leg pose with other values of its angles (a U
joint with perpendicular axes: (u1 + pi, pi - u2), its cross turned over); a real joint
cannot pass between them.  The branch analysed is the one of the *home assembly*: s_home is
found at the home pose (q_home = ik(p_home)) starting from s = 0, the legs as drawn in the
model file; every pose then starts from s_home, and the steps are capped at
:data:`MAX_STEP` (rad or m) so the iteration stays on that branch instead of jumping to one
a half turn away (for the DELTA this is the closed-form branch |elbow_2| < pi/2, tested).
Angles are reported wrapped to their declared limit interval (the first representative at
or above the lower limit; :func:`symkin.mechanism.limits.within_limits`).

**Unresolved poses.**  Where the iteration does not converge (step above :data:`STEP_TOLERANCE`
after :data:`MAX_ITERATIONS`, or closure residual above :data:`CLOSURE_TOLERANCE`) the passive
variables are unknown: the pose counts as unreachable and a :class:`PassiveJointWarning`
says how many poses that was, never silently accepted.
"""

from __future__ import annotations

import warnings
import weakref
from dataclasses import dataclass

import numpy as np

from symkin import mechanism
from symkin.mechanism.limits import within_limits
from symkin.manifest_schema import VectorInput
from symkin.runtime.info import GeneratedModel
from symkin.runtime.parallel import solve_closure

#: Damping of the Gauss-Newton iteration: the largest step (max-norm, rad or m).
MAX_STEP = 0.3
#: Converged when the last step is at most this (max-norm).
STEP_TOLERANCE = 1e-12
#: ... and the closure residual (max-norm, m and dimensionless) at most this.
CLOSURE_TOLERANCE = 1e-10
MAX_ITERATIONS = 40


class PassiveJointWarning(UserWarning):
    """Passive joint variables could not be found at some poses (they count as unreachable)."""


@dataclass(frozen=True)
class PassiveLimits:
    """The declared limits of a parallel model's passive joint variables.

    Attributes:
        names: every passive variable, in the order of ``s``.
        revolute: (k,) which of them are angles.
        columns: (m,) indices into ``s`` of the limited ones.
        bounds: (m, 2) their [lower, upper].
    """

    names: tuple[str, ...]
    revolute: np.ndarray
    columns: np.ndarray
    bounds: np.ndarray


@dataclass(frozen=True)
class AssemblyLimits:
    """The limits an assembly (q, s) of a parallel mechanism keeps: the actuators' and the declared passive joints'.

    Attributes:
        joints: (n, 2) the actuators' [lower, upper]; an actuator whose bounds are not finite is free.
        revolute: (n,) which actuators are angles.
        passive: the declared passive-joint limits, None where none are declared.
    """

    joints: np.ndarray
    revolute: np.ndarray
    passive: PassiveLimits | None

    def hold(self, q: np.ndarray, s: np.ndarray) -> np.ndarray:
        """Boolean (K,): the actuators q (K, n) and the passive joints s (K, ns) within their limits (angles taken
        modulo 2 pi, :func:`~symkin.mechanism.limits.within_limits`)."""
        limited = np.all(np.isfinite(self.joints), axis=1)
        inside = within_limits(q[:, limited], self.joints[limited], self.revolute[limited])[1]
        if self.passive is not None:
            columns = self.passive.columns
            inside &= within_limits(s[:, columns], self.passive.bounds, self.passive.revolute[columns])[1]
        return inside


def _passive_input(model: GeneratedModel) -> VectorInput:
    if "closure" in model.info.functions:
        return model.info.functions["closure"].vectors["s"]
    raise ValueError(f"{model.name}: passive-joint limits are declared; enforcing them needs the generated "
                     "'closure' and 'closure_jacobians' (add them to the scene outputs and derive again)")


def declared_limits(model: GeneratedModel) -> PassiveLimits | None:
    """The passive-joint limits recorded in the manifest (``model.parallel.legs[i].passive_limits``), or None.

    Raises:
        ValueError: a limit is not a pair of finite numbers [lower < upper], names an unknown
            passive variable, or the closure functions needed to evaluate s were not generated.
    """
    legs = model.info.passive_limits
    if not any(legs):
        return None
    s = _passive_input(model)
    if "closure_jacobians" not in model.functions:
        raise ValueError(f"{model.name}: passive-joint limits are declared; enforcing them needs the generated "
                         "'closure_jacobians' (add it to the scene outputs and derive again)")
    names = s.elements
    columns, bounds = [], []
    for i, leg in enumerate(legs):
        for name, value in leg.items():
            where = f"{model.name}: manifest.json model.parallel.legs[{i}].passive_limits.{name}"
            if name not in names:
                raise ValueError(f"{where}: no passive joint variable of that name (passive variables: "
                                 f"{', '.join(names)}); fix the model file's limits and derive again")
            pair = np.array(value, dtype=np.float64) if isinstance(value, (list, tuple)) else np.array([])
            if pair.shape != (2,) or not np.all(np.isfinite(pair)) or not pair[0] < pair[1]:
                raise ValueError(f"{where}: expected [lower, upper] with finite lower < upper, got {value!r}; "
                                 "fix the model file's limits and derive again")
            columns.append(names.index(name))
            bounds.append(pair)
    revolute = np.array([unit == "rad" for unit in s.units])
    return PassiveLimits(names, revolute, np.array(columns, dtype=int), np.array(bounds))


def _solve(model: GeneratedModel, q: np.ndarray, p: np.ndarray, start: np.ndarray):
    return solve_closure(model, q, start, p, unknowns=("s",), tol=STEP_TOLERANCE, max_iterations=MAX_ITERATIONS,
                         max_step=MAX_STEP)


#: s_home of every loaded model analysed so far (a model's parameters do not change; ``bind``
#: makes a new one).
_HOME_ASSEMBLIES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def home_assembly(model: GeneratedModel) -> np.ndarray:
    """s_home: the passive variables at the home pose, from s = 0 (the branch every pose is solved on).

    Computed once per loaded model (read-only array).

    Raises:
        ValueError: the home pose is out of reach or its passive variables do not converge.
    """
    if model not in _HOME_ASSEMBLIES:
        _HOME_ASSEMBLIES[model] = _home_assembly(model)
    return _HOME_ASSEMBLIES[model]


def _home_assembly(model: GeneratedModel) -> np.ndarray:
    home = mechanism.home_pose(model)
    size = len(_passive_input(model).elements)
    with np.errstate(invalid="ignore"):
        q = model.ik(home).joints
    report = _solve(model, q, home, np.zeros(size))
    if not (report.converged and report.residual <= CLOSURE_TOLERANCE):
        raise ValueError(f"{model.name}: the passive joint variables at the home pose {home.tolist()} do not "
                         f"converge (closure residual {float(report.residual):.3g}); check parallel.home")
    s = report.solution["s"]
    s.setflags(write=False)
    return s


@dataclass(frozen=True)
class PassiveSolution:
    """Passive joint variables of a batch of poses.

    Attributes:
        s: (N, k), angles wrapped to their limit intervals; NaN where unresolved.
        resolved: (N,) the iteration converged and the closure residual is within tolerance.
        within: (N,) resolved and every declared limit holds.
        residual: (N,) closure residual (max-norm) at s.
    """

    s: np.ndarray
    resolved: np.ndarray
    within: np.ndarray
    residual: np.ndarray


def solve_passive(model: GeneratedModel, limits: PassiveLimits, q: np.ndarray, p: np.ndarray) -> PassiveSolution:
    """The passive joint variables at assembled poses (q (N, n), p (N, 3)) and whether they are within limits."""
    report = _solve(model, np.asarray(q, dtype=np.float64), np.asarray(p, dtype=np.float64), home_assembly(model))
    resolved = report.converged & (report.residual <= CLOSURE_TOLERANCE)
    s = np.where(resolved[:, None], report.solution["s"], np.nan)
    limited, inside = within_limits(s[:, limits.columns], limits.bounds, limits.revolute[limits.columns])
    s[:, limits.columns] = limited
    return PassiveSolution(s, resolved, resolved & inside, report.residual)


def admissible(model: GeneratedModel, limits: PassiveLimits, q: np.ndarray, p: np.ndarray, candidates: np.ndarray) -> np.ndarray:
    """Boolean (N,): candidate poses whose passive variables are found and within their limits.

    Only the candidates (assembled poses) are solved; a candidate whose passive variables
    are not found is excluded and counted in a :class:`PassiveJointWarning`.
    """
    result = np.zeros(candidates.shape, dtype=bool)
    if not candidates.any():
        return result
    solution = solve_passive(model, limits, q[candidates], p[candidates])
    result[candidates] = solution.within
    unresolved = int(np.count_nonzero(~solution.resolved))
    if unresolved:
        warnings.warn(PassiveJointWarning(
            f"{model.name}: the passive joint variables of {unresolved} of {len(solution.resolved)} assembled poses "
            f"did not converge to a closure residual <= {CLOSURE_TOLERANCE:g}; they count as unreachable"),
            stacklevel=2)
    return result
