"""The workspace of a parallel mechanism of any leg topology, by continuation of its loop closure (issue 31): its
area or volume and its GCI.

The working mode of the home assembly, continued over a grid of the handle's positions at a constant orientation,
with 1/kappa of J = dp/dq at its cells, comes from the run-time mechanism
(:func:`symkin.mechanism.continuation.continued_grid`); here it becomes an occupancy (:func:`continued_workspace`),
its area or volume is measured without the bias of counting cells (:func:`working_mode_measure`: the grid's core
and a stratified Monte Carlo over its boundary cells), and its GCI is the mean of 1/kappa over the reached cells
(the midpoint rule) with the change from a grid of half as many cells as its error (:func:`continued_gci`).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, fields

import numpy as np

from symkin import mechanism
from symkin.integration.estimates import CONFIDENCE, Estimate
from symkin.analysis.workspace import Occupancy
from symkin.mechanism import Limits, continuation
from symkin.runtime.info import GeneratedModel

#: Uniform random points per boundary cell of the working mode's area or volume (:func:`working_mode_measure`).
BAND_SAMPLES = 4


@dataclass(frozen=True)
class ContinuedWorkspace(continuation.ContinuedGrid):
    """The working mode of the home assembly at a constant orientation, on a grid (:func:`continued_workspace`):
    the grid of :class:`symkin.mechanism.continuation.ContinuedGrid` as an occupancy, with its GCI."""

    @property
    def occupancy(self) -> Occupancy:
        """The reached cells (their centres' positions in the axes ``axes``)."""
        return Occupancy(self.lower, self.cell, self.reached)

    @property
    def gci(self) -> float:
        """The mean of 1/kappa over the reached cells (the global conditioning index)."""
        return float(np.mean(self.inv_kappa[self.reached]))


def continued_workspace(model: GeneratedModel, *, orientation: dict[str, float] | None = None,
                        limits: Limits | None = None, length: float | None = None, cells: int = continuation.CELLS,
                        start: tuple[np.ndarray, np.ndarray] | None = None,
                        box: tuple[np.ndarray, np.ndarray] | None = None) -> ContinuedWorkspace:
    """The working mode of the home assembly at a constant orientation, on a grid
    (:func:`symkin.mechanism.continuation.continued_grid`, whose arguments these are), as an occupancy.

    Raises:
        ValueError: the model has no closure to continue, an orientation names no angle of its task space, the
            home pose is out of reach, or the workspace is unbounded.
    """
    grid = continuation.continued_grid(model, orientation=orientation, limits=limits, length=length, cells=cells,
                                       start=start, box=box)
    return ContinuedWorkspace(**{field.name: getattr(grid, field.name) for field in fields(grid)})


def _band(reached: np.ndarray) -> np.ndarray:
    """Cells (of the grid's shape) that differ from one of their 3^d - 1 neighbours (diagonal ones too, so that a
    cell the boundary crosses at a corner is in): the reached cells along the working mode's boundary and the
    unreached cells beside them."""
    padded = np.pad(reached, 1, mode="edge")
    band = np.zeros_like(reached)
    for offset in itertools.product((0, 1, 2), repeat=reached.ndim):
        band |= padded[tuple(slice(o, o + n) for o, n in zip(offset, reached.shape))] != reached
    return band


def working_mode_measure(model: GeneratedModel, found: ContinuedWorkspace, *, limits: Limits | None = None,
                         samples: int = BAND_SAMPLES, seed: int = 0) -> Estimate:
    """The area or volume of the working mode on ``found``'s grid, without the bias of counting cells.

    Counting the cells whose centres are reached, or bracketing between the interior and all reached cells (whose
    midpoint was 30 % low on a DELTA at 16 cells a side), leaves the cells the boundary cuts to chance.  Here the
    grid's cells split into the *core* (reached, with all 3^d - 1 neighbours reached: counted whole) and the *band*
    (cells that differ from a neighbour, on both sides of the boundary: :func:`_band`).  In each band cell
    ``samples`` uniform random points are continued from the cell's own solution, or from the nearest reached
    neighbour's, as the flood continues its cells (:func:`symkin.mechanism.continuation.continue_from`: steps of at most a cell, the legs close, within the
    limits, no singularity crossed), and the cell counts with the share f_c that is reached:

        V = h^d (core + sum_c f_c),   var V = h^2d sum_c s_c^2 / k,

    a stratified Monte Carlo over the band (k points per cell, s_c^2 = f_c (1 - f_c) k / (k - 1) the sample
    variance).  The error is the half-width of the 95 % confidence interval of that sum; what it leaves out is a
    part of the workspace thinner than a cell inside the core or beyond the band (the grid's resolution, as for
    the flood itself).
    """
    from scipy.special import ndtri

    if samples < 2:
        raise ValueError(f"samples: at least 2 points per boundary cell, got {samples}")
    occupancy = found.occupancy
    reached = occupancy.occupied
    band = _band(reached)
    cells = np.flatnonzero(band)
    shape, d = reached.shape, reached.ndim
    flat_q, flat_s = found.q.reshape(-1, found.q.shape[-1]), found.s.reshape(-1, found.s.shape[-1])
    index = np.array(np.unravel_index(cells, shape)).T
    source = np.where(reached.ravel()[cells], cells, -1)
    for offset in sorted(itertools.product((-1, 0, 1), repeat=d), key=lambda o: sum(map(abs, o)))[1:]:
        neighbour = index + offset  # an unreached band cell starts from its nearest reached neighbour
        inside = np.all((neighbour >= 0) & (neighbour < shape), axis=1)
        flat = np.full(len(cells), -1)
        flat[inside] = np.ravel_multi_index(tuple(neighbour[inside].T), shape)
        take = (source < 0) & (flat >= 0)
        take[take] &= reached.ravel()[flat[take]]
        source[take] = flat[take]
    assert np.all(source >= 0), "every band cell is reached or beside a reached cell"
    task = mechanism.task_space(model)
    positions = np.array([c in mechanism.POSITION_COMPONENTS for c in task])
    centres = occupancy.centers().reshape(-1, d)
    rng = np.random.default_rng(seed)
    targets = np.repeat(found.pose[None], len(cells) * samples, axis=0)
    corners = np.repeat(occupancy.lower + index * occupancy.cell, samples, axis=0)
    targets[:, positions] = corners + rng.random((len(corners), d)) * occupancy.cell
    starts = np.repeat(source, samples)
    p = np.repeat(found.pose[None], len(starts), axis=0)
    p[:, positions] = centres[starts]
    taken = np.zeros(len(starts), dtype=bool)
    for group in (starts == np.repeat(cells, samples), starts != np.repeat(cells, samples)):  # own, neighbour's
        if group.any():  # marched apart: the points within their own cell take one step, not the neighbours' two
            taken[group] = continuation.continue_from(model, (flat_q[starts[group]], flat_s[starts[group]], p[group]),
                                                      targets[group], step=float(occupancy.cell.min()),
                                                      limits=limits)[2]
    shares = taken.reshape(len(cells), samples).mean(axis=1)
    volume = occupancy.cell_volume
    core = int(np.count_nonzero(reached & ~band))
    variance = volume**2 * np.sum(shares * (1 - shares)) / (samples - 1)
    quantile = float(ndtri(0.5 + CONFIDENCE / 2))
    return Estimate(volume * (core + float(np.sum(shares))), quantile * float(np.sqrt(variance)),
                    int(reached.size + len(starts)), "grid core + stratified Monte Carlo on the boundary cells", True)


@dataclass(frozen=True)
class ContinuedIndex:
    """The GCI over the working mode of a model reached by continuation (:func:`continued_gci`).

    Attributes:
        value: the mean of 1/kappa over the reached cells, its error the change from a grid of half as many
            cells a side.
        measure: the area or volume (m^d), its error the 95 % confidence half-width (:func:`working_mode_measure`).
        workspace: the grid it was averaged over.
        assembly: the home assembly the grids were continued from.
    """

    value: Estimate
    measure: Estimate
    workspace: ContinuedWorkspace
    assembly: continuation.HomeAssembly


def continued_gci(model: GeneratedModel, *, orientation: dict[str, float] | None = None, limits: Limits | None = None,
                  length: float | None = None, cells: int = continuation.CELLS) -> ContinuedIndex:
    """The GCI (seed eq. 8.28, midpoint rule over the reached cells) of the working mode at a constant orientation.

    The error estimate is the change of the mean from a grid of half as many cells a side (with the fine grid's
    characteristic length): the mean's error comes mostly from the cells along the workspace's boundary, whose
    share halves with the cell size, so the change bounds the fine grid's error where the grids resolve the
    workspace.  The coarse grid is laid over the fine grid's box.  Arguments as :func:`continued_workspace`.
    """
    fine = continued_workspace(model, orientation=orientation, limits=limits, length=length, cells=cells)
    assembly = fine.home
    assert assembly is not None, "a grid continued without a start solves its home assembly"
    coarse = continued_workspace(model, orientation=orientation, limits=limits, length=fine.length,
                                 cells=max(cells // 2, 2), start=(assembly.q, assembly.s), box=fine.box)
    evaluations = int(fine.occupancy.occupied.size + coarse.occupancy.occupied.size)
    value = Estimate(fine.gci, abs(fine.gci - coarse.gci), evaluations, "grid", False)
    return ContinuedIndex(value, working_mode_measure(model, fine, limits=limits), fine, assembly)
