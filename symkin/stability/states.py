"""States at which generated code is checked: random, along paths into singularities, scaled.

Singular configurations are found generically, for any serial model: starting from a
random configuration, each joint is swept over a full turn (revolute) or +-1 (prismatic)
and the inverse condition number 1/kappa = sigma_min/sigma_max of the generated task
Jacobian is watched; every local minimum below :data:`CANDIDATE` is refined by golden-section
search to the floating-point floor and kept if 1/kappa falls below :data:`SINGULAR`.  For
the planar arm this finds theta2 = 0 and pi (stretched and folded arm), for the UR10e the
wrist (q5 = 0, pi), the elbow (q3 = 0, pi) and shoulder singularities.  A path then
approaches the singular value q* from one side: q_j = q* + t, t = 1e-1 ... 1e-12, so
kappa grows like 1/t.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from symkin.model import coordinates
from symkin.model.schema import JointType, Model

#: Local minima of 1/kappa below this on the sweep grid are refined.
CANDIDATE = 2e-2
#: A refined minimum below this is a singular configuration.
SINGULAR = 1e-12
SWEEP_POINTS = 721
GOLDEN = (np.sqrt(5.0) - 1.0) / 2.0


def coordinate_range(model: Model) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) per joint for random states: the limits if finite, else +-pi / +-0.5 m."""
    lower, upper = [], []
    defaults = model.parameter_values
    for joint in model.joints:
        span = np.pi if joint.type is JointType.REVOLUTE else 0.5
        if joint.limits is not None:
            lo, hi = (float(b.xreplace(defaults)) for b in joint.limits)
            lower.append(max(lo, -4 * np.pi))
            upper.append(min(hi, 4 * np.pi))
        else:
            lower.append(-span)
            upper.append(span)
    return np.array(lower), np.array(upper)


def random_states(model: Model, count: int, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """``count`` states: q within the joint ranges, qd, qdd, tau uniform in [-1, 1]; (count, n) each."""
    lower, upper = coordinate_range(model)
    states = {"q": rng.uniform(lower, upper, size=(count, model.dof))}
    for group in coordinates.GROUPS:
        if group != "q":
            states[group] = rng.uniform(-1.0, 1.0, size=(count, model.dof))
    return states


def length_parameters(model: Model) -> tuple[str, ...]:
    """Free parameters measured in metres: what a change of scale multiplies."""
    return tuple(p.name for p in model.parameters if p.unit.strip() == "m")


def parameter_values(model: Model, scale: float = 1.0) -> dict[str, float]:
    """Default parameter values as doubles, lengths multiplied by ``scale``."""
    lengths = set(length_parameters(model))
    return {p.name: float(p.value) * (scale if p.name in lengths else 1.0) for p in model.parameters}


@dataclass(frozen=True)
class SingularPath:
    """A path q_j = value + t into a singular configuration of joint j (other joints at ``base``)."""

    joint: int
    name: str
    value: float
    base: np.ndarray
    inverse_kappa: float

    @property
    def label(self) -> str:
        return f"{self.name} -> {self.value:.6g}"

    def states(self, ts: np.ndarray) -> np.ndarray:
        q = np.tile(self.base, (len(ts), 1))
        q[:, self.joint] = self.value + ts
        return q


def _inverse_kappa(jacobian: Callable[[np.ndarray], np.ndarray], q: np.ndarray) -> np.ndarray:
    s = np.linalg.svd(np.asarray(jacobian(q)), compute_uv=False)
    return s[..., -1] / np.where(s[..., 0] > 0, s[..., 0], 1.0)


def _refine(f: Callable[[float], float], a: float, b: float) -> float:
    """Golden-section minimum of f on [a, b], down to the floating-point resolution of the arguments."""
    c, d = b - GOLDEN * (b - a), a + GOLDEN * (b - a)
    fc, fd = f(c), f(d)
    while b - a > 4 * np.finfo(float).eps * max(1.0, abs(a), abs(b)):
        if fc <= fd:
            b, d, fd = d, c, fc
            c = b - GOLDEN * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, d, fd
            d = a + GOLDEN * (b - a)
            fd = f(d)
    return c if fc <= fd else d


def _snap(value: float) -> float:
    """A refined value within 1e-12 of a multiple of pi/2 is that multiple (the singular values
    of the usual mechanisms: stretched, folded, aligned axes)."""
    multiple = round(value / (np.pi / 2))
    return multiple * (np.pi / 2) if abs(value - multiple * (np.pi / 2)) < 1e-12 else value


def singular_paths(model: Model, jacobian: Callable[[np.ndarray], np.ndarray], rng: np.random.Generator,
                   limit: int = 8, per_joint: int = 2) -> list[SingularPath]:
    """Paths into the singular configurations found by sweeping each joint (see module docstring).

    Args:
        model: the model (joint names and types).
        jacobian: the generated task Jacobian, vectorized over (..., n).
        rng: random generator for the base configuration.
        limit: at most this many paths in all.
        per_joint: at most this many paths per joint (those nearest q_j = 0 first).
    """
    lower, upper = coordinate_range(model)
    base = rng.uniform(np.maximum(lower, -np.pi), np.minimum(upper, np.pi))
    found: list[SingularPath] = []
    for j, joint in enumerate(model.joints):
        span = np.pi if joint.type is JointType.REVOLUTE else 1.0
        grid = np.linspace(-span, span, SWEEP_POINTS)
        q = np.tile(base, (SWEEP_POINTS, 1))
        q[:, j] = grid
        r = _inverse_kappa(jacobian, q)

        def at(value: float, j: int = j) -> float:
            point = base.copy()
            point[j] = value
            return float(_inverse_kappa(jacobian, point))

        for i in range(SWEEP_POINTS):
            left, right = r[max(i - 1, 0)], r[min(i + 1, SWEEP_POINTS - 1)]
            if r[i] < CANDIDATE and r[i] <= left and r[i] <= right:
                value = _snap(_refine(at, grid[max(i - 1, 0)], grid[min(i + 1, SWEEP_POINTS - 1)]))
                inverse_kappa = at(value)
                duplicate = any(p.joint == j and abs(np.remainder(p.value - value + np.pi, 2 * np.pi) - np.pi) < 1e-9
                                for p in found)
                if inverse_kappa < SINGULAR and not duplicate:
                    found.append(SingularPath(j, joint.name, value, base, inverse_kappa))
    kept = []
    for j in range(model.dof):
        nearest_zero = sorted((p for p in found if p.joint == j), key=lambda p: abs(p.value))
        kept += sorted(nearest_zero[:per_joint], key=lambda p: p.value)
    return kept[:limit]
