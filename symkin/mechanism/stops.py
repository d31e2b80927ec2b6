"""Stops on combinations of the joint coordinates (``joint_stops:`` of the model file): lower <= a . q + b <= upper.

A box of per-coordinate limits cannot hold the stop of a parallelogram, whose links meet at a bound on q3 - q2
whatever q2 and q3 are separately (the PHANToM's -65 deg <= q3 - q2 <= 55 deg).  The run-time mechanism counts a
configuration as reachable only within every stop (:func:`symkin.mechanism.working_mode.assemble`, the inverse
kinematics' :func:`symkin.mechanism.feasibility.feasible_configurations`), so the workspace, the GCI and the rating
sample the same set.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin.mechanism.limits import LIMIT_TOLERANCE
from symkin.runtime.info import GeneratedModel


@dataclass(frozen=True)
class StopInequalities:
    """The stops of a model as arrays over its coordinates q (n,).

    Attributes:
        rows: (k, n) the multipliers a of each stop.
        offsets: (k,) b.
        lower, upper: (k,) the bounds.
        expressions: the combinations as the model file writes them.
    """

    rows: np.ndarray
    offsets: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    expressions: tuple[str, ...]

    @classmethod
    def of_model(cls, model: GeneratedModel) -> StopInequalities:
        """The stops the manifest records over ``model``'s coordinates (none: k = 0).

        Raises:
            ValueError: a stop names a coordinate the model does not have (a manifest written by hand).
        """
        names = model.info.coordinate_names
        stops = model.info.joint_stops
        rows = np.zeros((len(stops), len(names)))
        for k, stop in enumerate(stops):
            for name, a in stop.coefficients.items():
                if name not in names:
                    raise ValueError(f"{model.name}: the joint stop '{stop.expression}' names '{name}', not a "
                                     f"coordinate of the model ({', '.join(names)}); derive the model again")
                rows[k, names.index(name)] = a
        return cls(rows, np.array([s.offset for s in stops], dtype=float),
                   np.array([s.limits[0] for s in stops], dtype=float),
                   np.array([s.limits[1] for s in stops], dtype=float), tuple(s.expression for s in stops))

    def __len__(self) -> int:
        return len(self.expressions)

    def over(self, n: int) -> StopInequalities:
        """The same stops over n >= the model's coordinates (a hybrid device's wrist joints after them, which no
        stop names)."""
        rows = np.zeros((len(self), n))
        rows[:, :self.rows.shape[1]] = self.rows
        return dataclasses.replace(self, rows=rows)

    def values(self, q: np.ndarray) -> np.ndarray:
        """a . q + b of every stop (..., k) at configurations q (..., n)."""
        return np.asarray(q, dtype=float) @ self.rows.T + self.offsets

    def respected(self, q: np.ndarray, tolerance: float = LIMIT_TOLERANCE) -> np.ndarray:
        """Whether configurations q (..., n) lie within every stop (...)."""
        return within_stops(np.asarray(q, dtype=float), self.rows, self.offsets, self.lower, self.upper, tolerance)


def within_stops(q: Any, rows: Any, offsets: Any, lower: Any, upper: Any, tolerance: float = LIMIT_TOLERANCE,
                 xp: Any = np) -> Any:
    """Whether configurations q (..., n) lie within every stop lower <= rows . q + offsets <= upper (...), in the
    array module ``xp`` (numpy, or jax.numpy on a JAX device, the arrays passed as traced arguments); True without
    stops."""
    values = q @ rows.T + offsets
    return xp.all((values >= lower - tolerance) & (values <= upper + tolerance), axis=-1)


def respected(model: GeneratedModel, q: np.ndarray) -> np.ndarray:
    """Whether configurations q (..., n) of ``model`` lie within its declared stops (...): all True without any."""
    stops = StopInequalities.of_model(model)
    q = np.asarray(q, dtype=float)
    return stops.respected(q) if len(stops) else np.ones(q.shape[:-1], dtype=bool)
