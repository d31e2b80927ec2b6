"""Figures of a dimensioning run: the objective history and the design before and after.

Drawn with ``matplotlib.figure.Figure`` (no pyplot, no GUI backend) and returned as PNG
bytes, so the command writes them together with its other outputs in one atomic step.
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from typing import Any

import numpy as np

from symkin.analysis import global_indices, workspace
from symkin.design.evaluation import Evaluation, continued_home, inverse_index
from symkin.design.problem import DesignProblem, box_axes, held
from symkin.design.solving import Solution
from symkin.mechanism import Sampling, continuation
from symkin.runtime.info import GeneratedModel

DPI = 150
#: Configurations drawn per serial workspace; points per axis of a parallel slice.
CLOUD_SAMPLES = 20_000
SLICE_POINTS = 121
#: Points per axis of the slice of legs without closed forms (flooded cell by cell from the home assembly).
CONTINUED_SLICE_POINTS = 61
#: A parallel slice shows the required box grown by this fraction of its size on each side.
SLICE_BORDER = 0.5


#: The y label of the objective history, per objective.
HISTORY_LABELS = {"gci": "GCI surrogate (1/kappa_F)", "workspace": "workspace measure",
                  "force": "force bound at the worst box point [N]"}


def png(figure: Any) -> bytes:
    """The figure as PNG bytes."""
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=DPI, bbox_inches="tight")
    return buffer.getvalue()


def history_figure(solution: Solution, problem: DesignProblem, model_name: str) -> Any:
    """The surrogate objective at every iterate of the solver, and the constraint violation where there are constraints."""
    from matplotlib.figure import Figure

    figure = Figure(figsize=(6.0, 4.0), layout="constrained")
    ax = figure.add_subplot()
    ax.plot(np.arange(len(solution.history)), solution.history, marker="o", ms=3)
    ax.set_xlabel(f"{solution.solver} iteration")
    ax.set_ylabel(HISTORY_LABELS[problem.objective])
    ax.set_title(f"{model_name}: maximize {problem.objective} over {', '.join(problem.names)} "
                 f"({solution.iterations} iterations, {solution.status})", fontsize=9)
    ax.grid(alpha=0.3)
    if np.any(solution.infeasibility > 0):
        twin = ax.twinx()
        twin.semilogy(np.arange(len(solution.infeasibility)), np.maximum(solution.infeasibility, 1e-17),
                      color="tab:red", lw=0.8, ls="--")
        measured = "IPOPT inf_pr" if solution.solver == "IPOPT" else "largest g < 0"
        twin.set_ylabel(f"constraint violation ({measured})", color="tab:red")
    return figure


def _quantity(value: float, unit: str) -> str:
    """A parameter value for a title: lengths in mm, angles in deg, other units as declared."""
    if unit == "m":
        return f"{value * 1e3:.4g} mm"
    if unit == "rad":
        return f"{np.degrees(value):.4g} deg"
    return f"{value:.4g} {unit}".rstrip()


def _label(problem: DesignProblem, units: dict[str, str], design: dict[str, float], evaluation: Evaluation,
           which: str) -> str:
    values = ", ".join(f"{n} = {_quantity(design[n], units.get(n, ''))}" for n in problem.names)
    force = "" if evaluation.force is None else f", isotropic force >= {evaluation.force:.4g} N in the box"
    return f"{which}: {values}\nGCI = {evaluation.gci}{force}"


def _box_outline(ax: Any, problem: DesignProblem, axes: Sequence[int], scale: float = 1.0) -> None:
    if problem.box is None:
        return
    (x0, y0), (x1, y1) = scale * problem.box[0][list(axes)], scale * problem.box[1][list(axes)]
    ax.plot([x0, x1, x1, x0, x0], [y0, y0, y1, y1, y0], color="red", lw=1.0, label="required box")
    ax.legend(loc="lower left", fontsize=7)


def _joint_space_panel(ax: Any, problem: DesignProblem, model: GeneratedModel, design: dict[str, float]) -> Any:
    model = model.bind(**design)
    cloud = workspace.sample_workspace(model, CLOUD_SAMPLES, method="sobol", limits=problem.limits, seed=0)
    values = global_indices.local_index(model, cloud.q, length=problem.length, limits=problem.limits)
    mesh = ax.scatter(cloud.points[:, 0], cloud.points[:, 1], c=values, s=2, linewidths=0, rasterized=True,
                      cmap="viridis", vmin=0.0, vmax=1.0)
    ax.set_xlabel(f"{cloud.axes[0]} [m]")
    ax.set_ylabel(f"{cloud.axes[1]} [m]")
    _box_outline(ax, problem, (0, 1))
    return mesh


def _slice(problem: DesignProblem, points: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(U, V, lower, upper): the vertical slice through the box centre (first and last axis, the box grown by
    SLICE_BORDER), as meshgrids of ``points`` a side, and its bounds in every axis (the others at the centre)."""
    lower, upper = problem.required_box
    border = SLICE_BORDER * (upper - lower)
    lo, hi = lower - border, upper + border
    first, last = 0, len(lower) - 1
    U, V = np.meshgrid(np.linspace(lo[first], hi[first], points), np.linspace(lo[last], hi[last], points))
    centre = (lower + upper) / 2
    lo[1:-1], hi[1:-1] = centre[1:-1], centre[1:-1]
    return U, V, lo, hi


def _box_panel(ax: Any, problem: DesignProblem, model: GeneratedModel, design: dict[str, float]) -> Any:
    """1/kappa on the vertical slice through the box centre (first and last axis): by the closed-form ik, or for
    legs without closed forms on the working mode's cells of the slice flooded from the design's home assembly."""
    points_per_axis = CONTINUED_SLICE_POINTS if problem.sampling is Sampling.CONTINUATION else SLICE_POINTS
    U, V, lo, hi = _slice(problem, points_per_axis)
    first, last = 0, len(lo) - 1
    if problem.sampling is Sampling.CONTINUATION:
        bound = model.bind(**design)
        counts = [points_per_axis if axis in (first, last) else 1 for axis in range(len(lo))]
        flood = continuation.flood_box(bound, lo, hi, counts, start=continued_home(problem, model, design),
                                       vertices=True, limits=problem.limits)
        reached = flood.reached
        cells = np.zeros(len(reached))
        cells[reached] = continuation.conditioning_at(bound, flood.q[reached], flood.s[reached],
                                                      flood.poses[reached], problem.length).inv_kappa
        values: np.ndarray = cells.reshape(points_per_axis, points_per_axis).T  # the grid's (u, v) -> the meshgrid's (v, u)
    else:
        points = np.tile(lo, (U.size, 1))
        points[:, first], points[:, last] = U.ravel(), V.ravel()
        values = inverse_index(held(problem, model.bind(**design)), points, problem.limits,
                               problem.length)[0].reshape(U.shape)
    scale, unit = (np.degrees(1.0), "deg") if problem.sampling is Sampling.ORIENTATIONS else (1.0, "m")
    mesh = ax.pcolormesh(scale * U, scale * V, np.ma.masked_equal(values, 0.0), shading="auto", cmap="viridis",
                         vmin=0.0, vmax=1.0, rasterized=True)
    axes = box_axes(model)
    ax.set_xlabel(f"{axes[first]} [{unit}]")
    ax.set_ylabel(f"{axes[last]} [{unit}] (slice through the box centre)")
    _box_outline(ax, problem, (first, last), scale)
    return mesh


def design_figure(problem: DesignProblem, model: GeneratedModel, solution: Solution,
                  evaluations: tuple[Evaluation, Evaluation]) -> Any:
    """1/kappa over the workspace (serial) or a slice of the box region (parallel), before and after."""
    from matplotlib.figure import Figure

    figure = Figure(figsize=(11.0, 4.8), layout="constrained")
    panel = _box_panel if problem.sampling is not Sampling.JOINTS else _joint_space_panel
    mesh = None
    first = None
    for k, (design, evaluation, which) in enumerate(zip((solution.start, solution.optimum), evaluations,
                                                        ("before", "after"))):
        ax = figure.add_subplot(1, 2, k + 1, sharex=first, sharey=first)
        first = first or ax
        mesh = panel(ax, problem, model, design)
        ax.set_aspect("equal")
        ax.set_title(_label(problem, model.info.units, design, evaluation, which), fontsize=8)
    if mesh is not None:  # the two panels drew
        figure.colorbar(mesh, ax=figure.axes, label="1/kappa")
    return figure
