"""Cartesian grids of a workspace, evaluated through the GCI's Cartesian integrand.

:func:`reachability_grid` marks the cells whose centre an inverse kinematics reaches within
the joint limits (the workspace of a parallel mechanism, seen the inverse way);
:func:`index_grid` adds a local index (1/kappa by default, seed Table 8.5) at those centres.
Both evaluate :func:`symkin.analysis.global_indices.cartesian_integrand` (on JAX's device where the GCI runs there:
:func:`~symkin.analysis.global_indices.cartesian_integrand_for`), so a map and the GCI integrate the same function.
"""

from __future__ import annotations

import numpy as np

from symkin.numerics import conditioning
from symkin.analysis import global_indices
from symkin.mechanism.feasibility import InverseKinematics
from symkin.mechanism import Limits
from symkin.analysis.workspace import Occupancy, grid_cells
from symkin.runtime.info import GeneratedModel


def reachability_grid(model: GeneratedModel, inverse: InverseKinematics, box: tuple[np.ndarray, np.ndarray],
                      cell: float, *, limits: Limits | None = None) -> Occupancy:
    """Cells whose centre the inverse kinematics reaches within the joint limits.

    This is the Cartesian grid with IK feasibility of parallel mechanisms; any
    :class:`~symkin.mechanism.feasibility.InverseKinematics` plugs in.  The cells are evaluated
    with the Cartesian integrand of the GCI (:func:`~symkin.analysis.global_indices.cartesian_integrand`).
    """
    start, size, counts, centers = grid_cells(box, cell)
    indicator = global_indices.cartesian_integrand_for(model, inverse, box, index=None, limits=limits).function(centers)
    return Occupancy(start, size, (indicator[:, 0] > 0).reshape(counts))


def index_grid(model: GeneratedModel, inverse: InverseKinematics, box: tuple[np.ndarray, np.ndarray], cell: float, *,
               index=None, limits: Limits | None = None, length: float | None = None) -> tuple[Occupancy, np.ndarray]:
    """A local index (1/kappa by default) at the reachable cell centres of a Cartesian grid.

    Returns:
        (occupancy, values): the reachability grid (:func:`reachability_grid`) and the index
        at every cell centre, an array of the grid's shape, NaN at unreachable cells.
    """
    index = conditioning.inverse_condition_number if index is None else index
    start, size, counts, centers = grid_cells(box, cell)
    scored = global_indices.cartesian_integrand_for(model, inverse, box, index=index, limits=limits,
                                                    length=length).function(centers)
    inside = scored[:, 1] > 0
    values = np.where(inside, scored[:, 0], np.nan)
    return Occupancy(start, size, inside.reshape(counts)), values.reshape(counts)
