"""A device's usable workspace as a maker quotes it: the largest box and upright cylinder inside it (issue 64).

The usable workspace is the datasheet's (:mod:`symkin.rating.datasheet`): the configurations within the joint limits
and stops whose handle Jacobian has 1/kappa at least the rating's ``conditioning``.  Its handle positions, sampled
on a joint grid far denser than the rating's poses, fill the cells of an occupancy
(:func:`symkin.analysis.workspace.occupancy_from_cloud`: cells twice the grid's spacing); the box and the cylinder
are the largest among its interior cells (:mod:`symkin.analysis.inscribed`), so they lie inside the usable set up to
the sampling, and the summary states the cell size they are quantized by.  A platform with a closed-form inverse
kinematics is gridded in Cartesian space directly; legs without closed forms (any topology) take the cells of the
home assembly's working mode continued over a Cartesian grid at the rating's orientation
(:func:`symkin.mechanism.continuation.continued_grid`), as their rating does.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from symkin import mechanism
from symkin.analysis import inscribed, workspace
from symkin.mechanism import Sampling, continuation, feasibility, reach
from symkin.mechanism.stops import StopInequalities
from symkin.mechanism.working_mode import assemble
from symkin.numerics import sampling
from symkin.numerics.conditioning import inverse_condition_number
from symkin.runtime.info import GeneratedModel

#: Samples of the shapes' grid: joint configurations of a serial arm (a joint grid: its cells map to cells of
#: the handle's space far apart at full reach), cells of a platform's Cartesian grid; about 1/15 of the box's
#: size each, both under a second for the example devices.
JOINT_SAMPLES, CARTESIAN_SAMPLES = 2 ** 18, 2 ** 15


@dataclass(frozen=True)
class WorkspaceShapes:
    """The largest box and upright cylinder inside the usable workspace (None: none fits a cell), the cell size
    they are quantized by (m) and the configurations sampled; ``not_rated``: why there are none (else "")."""

    box: inscribed.Box | None
    cylinder: inscribed.Cylinder | None
    cell: float
    samples: int
    not_rated: str = ""
    #: the interior cells the shapes were found among (their grid's corner and cell sizes), for :meth:`place`
    interior: np.ndarray | None = field(default=None, compare=False, repr=False)
    corner: np.ndarray | None = field(default=None, compare=False, repr=False)
    cells: np.ndarray | None = field(default=None, compare=False, repr=False)

    def place(self, size: np.ndarray) -> inscribed.Box | None:
        """Where a box of ``size`` (x, y, z in m: a maker's) fits inside the usable workspace, None where nowhere
        (:func:`symkin.analysis.inscribed.placed_box` on the same interior cells)."""
        if self.interior is None or self.corner is None or self.cells is None:
            return None
        return inscribed.placed_box(self.interior, self.corner, self.cells, size)

    def lines(self) -> list[str]:
        """summary.txt's lines, each with its definition."""
        if self.not_rated:
            return [f"workspace box and cylinder: not rated ({self.not_rated})"]
        where = (f"inside the usable workspace (interior cells of {1e3 * self.cell:.3g} mm, from {self.samples} "
                 "samples)")
        if self.box is None:
            return [f"workspace box: none fits {where}"]
        lines = [f"workspace box: {' x '.join(f'{1e3 * s:.0f}' for s in self.box.size)} mm (x, y, z), "
                 f"{self.box.volume:.4g} m^3, the largest axis-aligned box {where}"]
        if self.cylinder is not None:
            lines.append(f"workspace cylinder: diameter {2e3 * self.cylinder.radius:.0f} mm x height "
                         f"{1e3 * (self.cylinder.top - self.cylinder.bottom):.0f} mm, {self.cylinder.volume:.4g} m^3, "
                         f"the largest upright cylinder (axis along z) {where}")
        return lines

    def to_json(self) -> dict[str, Any]:
        if self.not_rated:
            return {"not_rated": self.not_rated}
        record: dict[str, Any] = {"cell_m": self.cell, "samples": self.samples,
                                  "definition": "largest axis-aligned box and upright cylinder among the interior "
                                                "cells of the usable workspace's occupancy"}
        if self.box is not None:
            record["box"] = {"lower_m": self.box.lower.tolist(), "upper_m": self.box.upper.tolist(),
                             "size_m": self.box.size.tolist(), "volume_m3": self.box.volume}
        if self.cylinder is not None:
            c = self.cylinder
            record["cylinder"] = {"axis_xy_m": c.centre.tolist(), "radius_m": c.radius, "bottom_m": c.bottom,
                                  "top_m": c.top, "volume_m3": c.volume}
        return record


def usable_shapes(model: GeneratedModel, conditioning: float, limits: mechanism.Limits | None = None,
                  samples: int | None = None, orientation: Sequence[float] | None = None) -> WorkspaceShapes:
    """The largest box and cylinder inside the usable workspace of a device whose handle translates in x, y and z
    (a serial arm on a joint grid, a translational platform on a Cartesian grid - legs without closed forms at the
    ``orientation`` (roll, pitch, yaw in rad; default the home pose's) where their platform also turns: ``samples`` of it, default :data:`JOINT_SAMPLES` or
    :data:`CARTESIAN_SAMPLES`); otherwise why not."""
    sampled = mechanism.sampling(model)
    rows = list(mechanism.position_rows(model))
    if sampled is Sampling.ORIENTATIONS or mechanism.handle_on_further_joints(model) or (
            sampled is Sampling.INVERSE and not mechanism.is_positional(model)):
        return WorkspaceShapes(None, None, 0.0, 0, "the box and cylinder are found for a handle that translates, of "
                                                    "a serial arm or a platform that translates (held at an "
                                                    "orientation where it also turns, legs without closed forms)")
    if len(rows) != 3:
        return WorkspaceShapes(None, None, 0.0, 0, f"the handle moves in {len(rows)} directions, not in x, y and z")
    if sampled is Sampling.INVERSE:
        return _cartesian_shapes(model, conditioning, limits, samples or CARTESIAN_SAMPLES)
    if sampled is Sampling.CONTINUATION:
        return _continued_shapes(model, conditioning, limits, samples or CARTESIAN_SAMPLES,
                                 reach.held_orientation(model, orientation), rows)
    samples = samples or JOINT_SAMPLES
    box = mechanism.joint_limits(model, limits)
    per_axis = max(2, int(round(samples ** (1.0 / len(box)))))
    q = sampling.grid(box[:, 0], box[:, 1], per_axis, midpoints=False)
    points, inside = assemble(model, q)
    J = mechanism.jacobian(model, q, points if mechanism.sampled_in_task_space(model) else None)[..., rows, :]
    with np.errstate(invalid="ignore", divide="ignore"):
        usable = inside & (inverse_condition_number(J) >= conditioning)
    if not usable.any():
        return WorkspaceShapes(None, None, 0.0, len(q), "no sampled configuration is usable")
    kept = workspace.WorkspaceCloud(q[usable], points[usable], ("x", "y", "z"), None)
    grid = workspace.WorkspaceCloud(q, points, ("x", "y", "z"), (per_axis,) * len(box))
    occupancy = workspace.occupancy_from_cloud(kept, 2.0 * workspace.cloud_spacing(grid, inside))
    return _shapes_of(occupancy, len(q))


def _cartesian_shapes(model: GeneratedModel, conditioning: float, limits: mechanism.Limits | None, samples: int
                      ) -> WorkspaceShapes:
    """A translational platform's shapes on a Cartesian grid of about ``samples`` cells over its bounding box: a cell
    is usable where its centre is reached in the working mode (the generated ik, the joint limits and stops) with
    1/kappa of J >= ``conditioning``."""
    lower, upper = reach.bounding_box(model, limits=limits)
    cell = float(np.max(upper - lower)) / round(samples ** (1.0 / 3.0))
    start, size, counts, centres = workspace.grid_cells((lower, upper), cell)
    q, usable = feasibility.feasible_configurations(reach.generated_inverse(model), centres,
                                                    mechanism.joint_limits(model, limits),
                                                    mechanism.revolute_mask(model), StopInequalities.of_model(model))
    with np.errstate(invalid="ignore", divide="ignore"):
        usable[usable] = inverse_condition_number(model.jacobian(q[usable], centres[usable])) >= conditioning
    return _shapes_of(workspace.Occupancy(start, size, usable.reshape(counts)), len(centres))


def _continued_shapes(model: GeneratedModel, conditioning: float, limits: mechanism.Limits | None, samples: int,
                      orientation: dict[str, float] | None, rows: list[int]) -> WorkspaceShapes:
    """Legs without closed forms: the cells of the home assembly's working mode, continued over a Cartesian grid of
    about ``samples`` cells (its longest side ``samples^(1/3)`` cells) at the held ``orientation``, where 1/kappa of
    J's position rows is at least ``conditioning``."""
    grid = continuation.continued_grid(model, orientation=orientation, limits=limits,
                                       cells=max(2, round(samples ** (1.0 / 3.0))))
    usable = grid.reached.copy()
    with np.errstate(invalid="ignore", divide="ignore"):
        usable[usable] = inverse_condition_number(grid.J[usable][:, rows, :]) >= conditioning
    return _shapes_of(workspace.Occupancy(grid.lower, grid.cell, usable), int(grid.reached.size))


def _shapes_of(occupancy: workspace.Occupancy, samples: int) -> WorkspaceShapes:
    """The largest box and cylinder among the occupancy's interior cells, which it keeps for :meth:`place`."""
    interior = occupancy.interior()
    return WorkspaceShapes(inscribed.largest_box(interior, occupancy.lower, occupancy.cell),
                           inscribed.largest_cylinder(interior, occupancy.lower, occupancy.cell),
                           float(occupancy.cell[0]), samples, "", interior, occupancy.lower, occupancy.cell)
