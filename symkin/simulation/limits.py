"""A run against the limits its model declares: peak joint torques and speeds over the velocity
and effort limits of the manifest (URDF ``<limit effort velocity>``, YAML ``effort_limit`` and
``velocity_limit``), as summary lines."""

from __future__ import annotations

import numpy as np

from symkin.simulation.plant import Plant


def declared_limit_lines(plant: Plant, tau: np.ndarray, qd: np.ndarray) -> list[str]:
    """Summary lines that set the peak joint torques and speeds of a run against the limits the
    model declares (URDF ``<limit effort velocity>``, YAML ``effort_limit``/``velocity_limit``):
    the largest ratio peak/limit and its joint, and every joint whose limit is exceeded."""
    lines = []
    for what, values, limits in (("effort", tau, plant.effort_limits), ("velocity", qd, plant.velocity_limits)):
        declared = ~np.isnan(limits)
        if not declared.any():
            continue
        ratios = np.where(declared, np.max(np.abs(values), axis=0) / np.where(declared, limits, 1.0), 0.0)
        worst = int(np.argmax(ratios))
        exceeded = [plant.coordinates[j] for j in np.flatnonzero(ratios > 1.0)]
        verdict = f"exceeded at {', '.join(exceeded)}" if exceeded else "within the limits"
        lines.append(f"  {what} limits of the model: peak/limit up to {ratios[worst]:.3g} "
                     f"({plant.coordinates[worst]}): {verdict}")
    return lines
