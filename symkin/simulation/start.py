"""The default start pose of a simulation: a well-conditioned configuration within the limits.

A serial device's declared rest configuration (``serial.home``) is the start where the model has one.  Else the middle of the joint limits (0 for an unlimited joint) is the start unless the task
Jacobian is worse conditioned there than :data:`WELL_CONDITIONED`: symmetric limits put many
arms at a singularity (a SCARA or a UR arm stretched out), where TCP forces are undefined and
a task-space reference leaves the workspace.  Then the start is the best-conditioned pose of a
deterministic Sobol set, 10 % inside the limits so that a motion about it has room.
"""

from __future__ import annotations

import numpy as np

from symkin.numerics.sobol import Sobol
from symkin.simulation.plant import Plant

#: 1/kappa of the task Jacobian above which the middle of the limits is kept.
WELL_CONDITIONED = 0.05
#: Candidate poses searched otherwise.
START_CANDIDATES = 256


def start_pose(plant: Plant) -> tuple[np.ndarray, str]:
    """(q0, how it was chosen, for the output)."""
    declared = plant.mechanism.home_configuration
    if declared is not None:
        return declared, f"the model's home configuration (1/kappa = {float(plant.dexterity(declared)):.3g})"
    limits = plant.joint_limits
    finite = np.isfinite(limits).all(axis=1)
    middle = plant.middle_of_limits()
    conditioning = float(plant.dexterity(middle))
    if conditioning >= WELL_CONDITIONED:
        return middle, f"the middle of the joint limits (1/kappa = {conditioning:.3g})"
    span = np.where(finite[:, None], limits, np.where(plant.revolute, np.pi, 0.5)[:, None] * [-1.0, 1.0])
    low, high = span[:, 0] + 0.1 * np.ptp(span, axis=1), span[:, 1] - 0.1 * np.ptp(span, axis=1)
    candidates = low + Sobol(plant.dof).points(0, START_CANDIDATES) * (high - low)
    measures = np.nan_to_num(plant.dexterity(candidates), nan=0.0)
    best = int(np.argmax(measures))
    return candidates[best], (f"the best-conditioned of {START_CANDIDATES} poses within the limits (1/kappa = "
                              f"{float(measures[best]):.3g}); the middle of the limits has 1/kappa = {conditioning:.3g}")
