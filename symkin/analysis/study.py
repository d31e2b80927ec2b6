"""The workspace study of one design, as ``symkin workspace`` reports it: what is sampled, measured and found.

A serial mechanism (or a parallel one with a closed-form fk) is sampled in its joint space and
mapped through the generated ``fk`` (:func:`symkin.analysis.workspace.sample_workspace`); its
area/volume comes from the joint domain (|det J| dq) and, where an inverse kinematics exists,
from a Cartesian box; its boundary and singular configurations from the occupancy of the
point cloud (seed sec. 4.1, 4.2).  A parallel mechanism also gets a Cartesian grid with
reachability by its closed-form IK and 1/kappa at the cell centres
(:func:`cartesian_index_grid`), which gives its volume, boundary and near-singular cells; a
platform held at a constant orientation (:func:`symkin.mechanism.reach.held_at`) has no fk, and the grid's
boundary cells are its point cloud.  A mechanism without closed forms (sampled by continuation,
:attr:`symkin.mechanism.Sampling.CONTINUATION`) gets the working mode of its home assembly continued over a
Cartesian grid (:func:`continued_study`, :func:`continued_gci_study`): the commands ask the mechanism how it is
sampled and this module for what to report, never its kind.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from symkin.mechanism import feasibility
from symkin.analysis import global_indices, inscribed, inverse, workspace
from symkin.mechanism import reach
from symkin.mechanism.stops import StopInequalities
from symkin import mechanism
from symkin.integration.estimates import Estimate
from symkin.analysis.grids import index_grid
from symkin.mechanism import Limits
from symkin.analysis.workspace import Occupancy, WorkspaceCloud
from symkin.runtime.info import GeneratedModel

#: Cells along the longest side of the Cartesian grid of a parallel mechanism's workspace.
CARTESIAN_CELLS = 64
#: Fraction of the reachable cells, those of lowest 1/kappa, whose place (boundary or not) is reported.
LOWEST_FRACTION = 0.01


def cartesian_index_grid(model: GeneratedModel, box: tuple[np.ndarray, np.ndarray], limits: Limits | None,
                         length: float | None, index=None) -> tuple[Occupancy, np.ndarray]:
    """Reachability grid of a parallel mechanism over ``box`` (:data:`CARTESIAN_CELLS` along its longest
    side) with a local index (1/kappa by default) at its cell centres (:func:`symkin.analysis.grids.index_grid`)."""
    cell = float(max(box[1] - box[0])) / CARTESIAN_CELLS
    return index_grid(model, reach.generated_inverse(model), box, cell, index=index, limits=limits, length=length)


def boundary_cloud(model: GeneratedModel, occupancy: Occupancy, limits: Limits | None) -> WorkspaceCloud:
    """The centres of the boundary cells of a Cartesian grid and their joint coordinates, as a point cloud."""
    points = occupancy.centers()[occupancy.boundary()]
    q, _ = feasibility.feasible_configurations(reach.generated_inverse(model), points,
                                               mechanism.joint_limits(model, limits), mechanism.revolute_mask(model),
                                               StopInequalities.of_model(model))
    return WorkspaceCloud(q, points, ("x", "y", "z"))


@dataclass
class WorkspaceStudy:
    """What :func:`study_workspace` found for one design.

    Attributes:
        cloud: the TCP point cloud (the grid's boundary cells for a platform at a constant orientation).
        sampled: how the cloud was obtained, in words.
        inv_kappa: 1/kappa at the cloud's configurations (None where the Cartesian grid carries it).
        grid: (occupancy, 1/kappa at the cell centres) of a parallel mechanism, else None.
        report: the findings, one line each (extent, area/volume, boundary, singularities).
        outline: the images of the joint-limit edges of a 2-DoF mechanism (for figures).
        grid_axes: the task coordinates along the grid's axes.
        reached_by: how the grid's cells are reached, in words (for figures).
    """

    cloud: WorkspaceCloud
    sampled: str
    inv_kappa: np.ndarray | None
    grid: tuple[Occupancy, np.ndarray] | None
    report: list[str]
    outline: list = field(default_factory=list)
    grid_axes: tuple[str, ...] = ("x", "y", "z")
    reached_by: str = "reachability by ik"


def study_workspace(model: GeneratedModel, *, samples: int, method: str, seed: int, limits: Limits | None,
                    length: float | None, progress: Callable[[str], None] = lambda _stage: None) -> WorkspaceStudy:
    """Sample, measure and report the workspace of one design (see the module docstring).

    Raises:
        ValueError: the model cannot be analysed so (e.g. no reachable cell).
    """
    inv_kappa, box, grid = None, None, None
    if mechanism.sampled_in_task_space(model):  # 1/kappa and the volume come from a Cartesian grid
        box = reach.bounding_box(model, limits=limits)
        progress("Cartesian grid")
        grid = cartesian_index_grid(model, box, limits, length)
    if isinstance(model, reach.ConstantOrientation):  # no fk: the grid's surface is the cloud
        assert grid is not None, "a platform held at a constant orientation is parallel: it has its grid"
        cloud = boundary_cloud(model, grid[0], limits)
        sampled = (f"{int(grid[0].occupied.sum())} reachable cells of a Cartesian grid at roll, pitch, "
                   f"yaw = {reach.orientation_text(model)}")
    else:
        cloud = workspace.sample_workspace(model, samples, method=method, limits=limits, seed=seed)
        if grid is None:
            progress("conditioning")
            inv_kappa = global_indices.local_index(model, cloud.q, length=length, limits=limits)
        sampled = f"{len(cloud.q)} configurations ({method})"
    report = _report(model, cloud, inv_kappa, limits, progress, box)
    report += _cartesian_report(*grid) if grid is not None else []
    joints = mechanism.joint_limits(model, limits).shape[0]
    outline = workspace.limit_curves(model, limits=limits) if joints == 2 else []
    return WorkspaceStudy(cloud, sampled, inv_kappa, grid, report, outline)


#: How the area or volume of a workspace continued over a grid is estimated
#: (:func:`symkin.analysis.continued_workspace.working_mode_measure`).
MEASURE_NOTE = ("95 % confidence: the cells whose neighbours are all reached, and the boundary cells' shares "
                "that random points in them reach")


def held_text(model: GeneratedModel, found) -> str:
    """' at yaw = 20 deg': the angles a workspace continued over a grid holds (``found.pose`` outside its gridded
    ``found.axes``); '' for a platform that only translates."""
    held = ", ".join(f"{name} = {np.degrees(found.pose[i]):g} deg" for i, name in enumerate(mechanism.task_space(model))
                     if name not in found.axes)
    return f" at {held}" if held else ""


def continued_study(model: GeneratedModel, *, cells: int, orientation: dict[str, float], limits: Limits | None,
                    length: float | None, progress: Callable[[str], None] = lambda _stage: None) -> WorkspaceStudy:
    """The workspace of a mechanism sampled by continuation (:attr:`symkin.mechanism.Sampling.CONTINUATION`): the
    working mode of its home assembly at the held angles ``orientation``, continued from the home pose over a
    Cartesian grid of ``cells`` cells along its longest side (:mod:`symkin.analysis.continued_workspace`); the
    cloud is its boundary cells, the grid carries 1/kappa, and the area or volume is the grid's core and the
    boundary cells' reached shares (:func:`symkin.analysis.continued_workspace.working_mode_measure`).

    Raises:
        ValueError: the home pose is out of reach, or the workspace is unbounded within the limits.
    """
    from symkin.analysis import continued_workspace

    progress(f"continuing the loop closure over a grid of {cells} cells a side")
    found = continued_workspace.continued_workspace(model, orientation=orientation, limits=limits, length=length,
                                                    cells=cells)
    assembly = found.home
    assert assembly is not None, "a grid continued without a start solves its home assembly"
    occupancy, values = found.occupancy, found.inv_kappa
    reached = occupancy.occupied
    progress("sampling the boundary cells for the " + ("area" if reached.ndim == 2 else "volume"))
    measure = continued_workspace.working_mode_measure(model, found, limits=limits)
    scaled = f" (characteristic length {found.length:.4g} m)" if found.length is not None else ""
    report = [assembly.describe(model),
              f"{int(reached.sum())} reached cells; {'area' if reached.ndim == 2 else 'volume'}: {measure} "
              f"m^{reached.ndim} ({MEASURE_NOTE})",
              f"1/kappa{scaled}: min {np.min(values[reached]):.4g}, max {np.max(values[reached]):.4g}; "
              f"mean over the workspace (GCI) {found.gci:.4g}"]
    sampled = (f"working mode of the home assembly{held_text(model, found)}, continued from the home pose over a "
               f"Cartesian grid of {occupancy.cell[0]:.3g} m cells (cells joined through a singularity or beyond a "
               "limit are not reached)")
    boundary = occupancy.boundary()
    cloud = WorkspaceCloud(found.q[boundary], occupancy.centers()[boundary], found.axes)
    return WorkspaceStudy(cloud, sampled, None, (occupancy, values), report, grid_axes=found.axes,
                          reached_by="continued from the home pose")


@dataclass(frozen=True)
class ContinuedGCIStudy:
    """The GCI over a workspace continued over a grid (:func:`continued_gci_study`).

    Attributes:
        value: the mean of 1/kappa over the reached cells, its error the change from a grid of half as many cells.
        grid: (occupancy, 1/kappa at the cell centres) of the finer grid.
        axes: the task coordinates along the grid's axes.
        report: what was averaged over, one line each (the measure, the grid, the home assembly).
    """

    value: Estimate
    grid: tuple[Occupancy, np.ndarray]
    axes: tuple[str, ...]
    report: list[str]


def continued_gci_study(model: GeneratedModel, *, cells: int, orientation: dict[str, float], limits: Limits | None,
                        length: float | None) -> ContinuedGCIStudy:
    """The GCI (seed eq. 8.28) over the working mode of the home assembly continued over grids of ``cells`` and half
    as many cells a side (:func:`symkin.analysis.continued_workspace.continued_gci`), with what it was averaged over."""
    from symkin.analysis import continued_workspace

    found = continued_workspace.continued_gci(model, orientation=orientation, limits=limits, length=length, cells=cells)
    space = found.workspace
    d = space.occupancy.occupied.ndim
    scaled = f", position rows over the characteristic length {space.length:.4g} m" if space.length is not None else ""
    report = [f"workspace measure int dW = {found.measure} m^{d} ({MEASURE_NOTE})",
              f"the working mode of the home assembly{held_text(model, space)}, continued from the home pose over a "
              f"grid of {space.occupancy.cell[0]:.3g} m cells; 1/kappa of J = dp/dq{scaled}",
              found.assembly.describe(model)]
    return ContinuedGCIStudy(found.value, (space.occupancy, space.inv_kappa), space.axes, report)


def _cartesian_report(occupancy: Occupancy, values: np.ndarray) -> list[str]:
    """Area or volume, boundary and where the (near-)singular cells lie, from the Cartesian grid."""
    boundary = occupancy.boundary()
    interior = occupancy.interior()
    d = occupancy.occupied.ndim
    lines = [f"{'area' if d == 2 else 'volume'}: {occupancy.measure()} m^{d} (Cartesian grid of "
             f"{occupancy.cell[0]:.3g} m cells, reachability by ik in the working mode: between interior and all "
             "reachable cells, a bracket unless thin parts of the workspace fall between cell centres); "
             f"{int(boundary.sum())} boundary cells"]
    if interior.any():
        lines.append(f"1/kappa at the cell centres: min {np.nanmin(values[boundary]):.4g} on boundary cells, "
                     f"min {np.nanmin(values[interior]):.4g} on interior cells")
    reachable = values[occupancy.occupied]
    worst = occupancy.occupied & (values <= np.quantile(reachable, LOWEST_FRACTION))
    lines.append(f"the {int(worst.sum())} cells of lowest 1/kappa ({LOWEST_FRACTION:.0%}): {int((worst & boundary).sum())} "
                 "on the workspace boundary (seed sec. 4.2: boundary singularities)")
    return lines


def _multiplicity_lines(joint_measure: Estimate | None, occupied: Estimate, kind: str, unit: str, cartesian: bool
                        ) -> list[str]:
    """What the two figures measure, where they prove q -> TCP many-to-one: the joint domain's integral of |det J|
    counts each point of the workspace once per configuration that reaches it, the occupancy each point once, at
    most every occupied cell's volume.  A joint-domain figure beyond that bound (both with their errors) is a
    covering: on average every point is reached at least their ratio of times (the elbow up and down of an arm
    whose joint limits allow both).  ``cartesian``: a figure over a Cartesian box (by inverse kinematics) was
    reported, which measures the set as well."""
    most = occupied.value + occupied.error
    if joint_measure is None or not joint_measure.value - joint_measure.error > most:
        return []
    measured_by = "the Cartesian box's and the occupancy's" if cartesian else "the occupancy's"
    return [f"the {kind}s measure different sets: q -> TCP reaches the workspace more than once (on average at "
            f"least {(joint_measure.value - joint_measure.error) / most:.3g} times: more than every occupied cell's "
            f"{most:.4g} {unit}), which the joint domain's figure counts with multiplicity; the workspace's own "
            f"{kind} is {measured_by}"]


def _inscribed_lines(occupancy: Occupancy) -> list[str]:
    """The largest box (and, in 3-d, upright cylinder) inside the interior cells, as a maker quotes a workspace."""
    interior = occupancy.interior()
    box = inscribed.largest_box(interior, occupancy.lower, occupancy.cell)
    if box is None:
        return ["largest box inside: none (no interior cells: sample more configurations, -n)"]
    size = " x ".join(f"{1e3 * s:.0f}" for s in box.size)
    centre = ", ".join(f"{1e3 * c:.0f}" for c in (box.lower + box.upper) / 2)
    lines = [f"largest box inside (interior cells, axis-aligned): {size} mm, centre ({centre}) mm"]
    if interior.ndim == 3:
        cylinder = inscribed.largest_cylinder(interior, occupancy.lower, occupancy.cell)
        if cylinder is not None:
            lines.append(f"largest upright cylinder inside: diameter {2e3 * cylinder.radius:.0f} mm x height "
                         f"{1e3 * (cylinder.top - cylinder.bottom):.0f} mm, axis at ("
                         f"{', '.join(f'{1e3 * c:.0f}' for c in cylinder.centre)}) mm")
    return lines


def _report(model: GeneratedModel, cloud: WorkspaceCloud, inv_kappa: np.ndarray | None, limits: Limits | None,
            progress: Callable[[str], None], box=None) -> list[str]:
    """Extent, area/volume (joint and Cartesian domains) and, for a serial mechanism, boundary and singularities."""
    lines = []
    joint_measure = None
    lower, upper = cloud.points.min(axis=0), cloud.points.max(axis=0)
    lines.append("extent of the samples: " + ", ".join(f"{a} [{lo:.6g}, {hi:.6g}] m"
                                                       for a, lo, hi in zip(cloud.axes, lower, upper)))
    d = len(cloud.axes)
    unit = f"m^{d}"
    kind = "area" if d == 2 else "volume"
    if mechanism.is_positional(model):
        progress(f"{kind} (joint domain)")
        joint_measure = global_indices.workspace_measure(model, method="qmc", samples=2**16, seed=0, limits=limits)
        lines.append(f"{kind}: {joint_measure} {unit} (qmc, |det J| dq over the joint limits: exact where q -> TCP "
                     "is one-to-one, else with multiplicity)")
    ik = inverse.inverse_kinematics_for(model)
    if ik is not None:
        progress(f"{kind} (Cartesian domain)")
        measure = global_indices.workspace_measure(model, method="qmc", samples=2**16, seed=0, limits=limits,
                                                   domain="cartesian", inverse=ik, box=box)
        lines.append(f"{kind}: {measure} {unit} (qmc over a Cartesian box, reachability by inverse kinematics)")
    if mechanism.sampled_in_task_space(model) or inv_kappa is None:
        return lines  # the Cartesian grid (_cartesian_report) gives the volume, boundary and singularities
    occupancy = workspace.occupancy_from_cloud(cloud)
    boundary = occupancy.boundary()
    occupied = occupancy.measure()
    lines.append(f"{kind}: {occupied} {unit} (occupancy of {occupancy.cell[0]:.3g} m cells: "
                 f"between interior and all occupied cells); {int(boundary.sum())} boundary cells")
    lines += _multiplicity_lines(joint_measure, occupied, kind, unit, ik is not None)
    lines += _inscribed_lines(occupancy)
    singular = np.asarray(inv_kappa <= 0.0)
    on_boundary = int(occupancy.lookup(cloud.points[singular], boundary).sum())
    lines.append(f"1/kappa: min {inv_kappa.min():.4g}, mean {inv_kappa.mean():.4g}, max {inv_kappa.max():.4g}; "
                 f"singular configurations: {int(singular.sum())}, of which {on_boundary} on the workspace "
                 "boundary (seed sec. 4.2: boundary singularities)")
    return lines
