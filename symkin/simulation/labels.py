"""Names and units of what the scenarios write: CSV column names, axis labels, summary peaks.

Each joint carries its own units (rad and N m for a revolute joint, m and N for a prismatic
one), each task coordinate the unit of its generalized force (N along a translation, N m about
a rotation), so no line or column mixes them; an axis that shows several joints lists their
units once each.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from symkin import mechanism
from symkin.simulation.plant import Plant


def named(prefix: str, names: Sequence[str], unit: str | Sequence[str], values: np.ndarray) -> dict[str, np.ndarray]:
    """Columns ``<prefix><name> [<unit>]``: one unit for all, or one per name."""
    units = [unit] * len(names) if isinstance(unit, str) else list(unit)
    return {f"{prefix}{name} [{u}]": values[:, i] for i, (name, u) in enumerate(zip(names, units))}


def label(units: Sequence[str]) -> str:
    """The unit of an axis that shows several joints: their units, each once (``rad|m``)."""
    return "|".join(dict.fromkeys(units))


def peaks(prefix: str, names: Sequence[str], units: Sequence[str], values: np.ndarray) -> str:
    """``|<prefix><name>| <= peak unit`` per joint, each with its own unit."""
    return ", ".join(f"|{prefix}{n}| <= {float(np.max(np.abs(values[:, i]))):.4g} {u}"
                     for i, (n, u) in enumerate(zip(names, units)))


def seed(plant: Plant, figure: str) -> str:
    """" (seed Fig. <figure>)" for the seed chapter's arm (a planar 2R arm, task space x, y), else ""."""
    planar_2r = plant.dof == 2 and bool(np.all(plant.revolute)) and tuple(plant.task_space) == ("x", "y")
    return f" (seed Fig. {figure})" if planar_2r else ""


def force_units(plant: Plant) -> list[tuple[str, str]]:
    """(task coordinate, unit of its generalized force): N along a translation, N m about a rotation."""
    return [(c, "N" if c in mechanism.POSITION_COMPONENTS else "N m") for c in plant.task_space]


def joint_units(plant: Plant) -> tuple[list[str], list[str]]:
    """(position units, effort units), one per joint: rad and N m for a revolute joint, m and N for a
    prismatic one."""
    return (["rad" if r else "m" for r in plant.revolute], ["N m" if r else "N" for r in plant.revolute])
