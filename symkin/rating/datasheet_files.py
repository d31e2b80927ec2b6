"""A datasheet's files: one CSV row per rated pose and one figure with a map per measure (``symkin rate``)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from symkin.rating.datasheet import Datasheet, axis_scale


def csv_text(sheet: Datasheet, coordinates: Sequence[str]) -> str:
    """One row per rated pose: q, the TCP and every measure (the home pose last)."""
    unit = axis_scale(sheet.axes)[2]
    header = [*coordinates, *(f"{a} [{unit}]" for a in sheet.axes),
              *(f"{m.name} [{m.unit}]" if m.unit else m.name for m in sheet.measures)]
    columns = np.column_stack([sheet.q, sheet.points, *(m.values for m in sheet.measures)])
    rows = [",".join(f"{v:.9g}" for v in row) for row in columns]
    return "\n".join([f"# symkin rate: {sheet.model}, {len(rows)} poses (the last is the home pose)",
                      ",".join(header), *rows]) + "\n"


#: Percentiles the colour scale spans (a few extreme poses near the usable workspace's edge would wash out the map);
#: a scale that clips says so with extend arrows and the true range in its label.
COLOUR_PERCENTILES = (1.0, 99.0)
#: Cells along the longer side of a spatial device's map (its poses binned over x and y), at most; fewer for
#: fewer poses (about a few poses a cell).
MAP_CELLS = 40


def colour_range(shown: np.ndarray, values: np.ndarray) -> tuple[float, float, str, str]:
    """(low, high, extend, note) of a measure's colour scale: the :data:`COLOUR_PERCENTILES` of the finite values
    ``shown`` (the poses, or a map's cells), ``extend`` ('neither', 'min', 'max', 'both': where the measure's
    ``values`` lie beyond the scale) and the note for its label ('' or 'colours clipped; values 0.05 .. 69')."""
    finite, every = shown[np.isfinite(shown)], values[np.isfinite(values)]
    if not len(finite):
        return 0.0, 1.0, "neither", ""
    low, high = (float(v) for v in np.percentile(finite, COLOUR_PERCENTILES))
    high = max(high, low + 1e-300)
    below, above = bool(np.min(every) < low), bool(np.max(every) > high)
    extend = {(False, False): "neither", (True, False): "min", (False, True): "max", (True, True): "both"}[
        (below, above)]
    note = "" if extend == "neither" else f"colours clipped; values {np.min(every):.3g} .. {np.max(every):.3g}"
    return low, high, extend, note


def worst_map(points: np.ndarray, values: np.ndarray, worst_is_min: bool, cells: int | None = None
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x edges, y edges, map) of a spatial device's measure seen from above: in each x-y cell the worst value over
    the heights sampled there (NaN where none), what a designer reads off a datasheet."""
    from scipy.stats import binned_statistic_2d

    finite = np.isfinite(values)
    x, y = points[finite, 0], points[finite, 1]
    cells = int(np.clip(np.sqrt(finite.sum() / 3), 8, MAP_CELLS)) if cells is None else cells
    span = max(float(np.ptp(x)), float(np.ptp(y)), 1e-12)
    bins = [max(2, int(np.ceil(cells * max(float(np.ptp(c)), 1e-12) / span))) for c in (x, y)]
    result = binned_statistic_2d(x, y, values[finite], statistic="min" if worst_is_min else "max", bins=bins)
    return result.x_edge, result.y_edge, result.statistic.T


def drawn_measures(sheet: Datasheet) -> list:
    """The measures the datasheet figure maps: those over every direction (those along one axis are in the table
    only); none where the model declares nothing they need (the figure is then not drawn)."""
    return [measure for measure in sheet.measures if measure.axis is None]


def figure_png(sheet: Datasheet, title: str) -> bytes:
    """The datasheet figure (:func:`datasheet_figure`) as PNG bytes."""
    import io

    buffer = io.BytesIO()
    datasheet_figure(sheet, title).savefig(buffer, format="png", dpi=110)
    return buffer.getvalue()


def datasheet_figure(sheet: Datasheet, title: str) -> Any:
    """The datasheet figure: one map per measure over every direction (those along one axis are in the table only)
    over the rated poses, the home pose starred.  A planar device's poses are coloured by their value; a spatial
    device's are seen from above, each x-y cell showing the worst value over the heights sampled there (:func:`worst_map`).  A colour scale that clips (:func:`colour_range`) has extend
    arrows and the true range in its label."""
    from matplotlib.figure import Figure

    drawn = drawn_measures(sheet)
    count = len(drawn)
    columns = min(3, count)
    rows = -(-count // columns)
    spatial = sheet.points.shape[1] == 3
    figure = Figure(figsize=(4.6 * columns, 3.9 * rows + 0.6), layout="constrained")
    scale, unit, _ = axis_scale(sheet.axes)
    points = scale * sheet.points
    home = points[sheet.home]
    for k, measure in enumerate(drawn):
        ax: Any = figure.add_subplot(rows, columns, k + 1)
        if spatial:
            x_edges, y_edges, grid = worst_map(points, measure.values, measure.worst_is_min)
            low, high, extend, note = colour_range(grid, measure.values)
            mesh = ax.pcolormesh(x_edges, y_edges, grid, cmap="viridis", vmin=low, vmax=high, rasterized=True)
            ax.set_title(f"worst over {sheet.axes[2]}", fontsize=9)
        else:
            low, high, extend, note = colour_range(measure.values, measure.values)
            mesh = ax.scatter(*points.T, c=measure.values, cmap="viridis", vmin=low, vmax=high, s=2, linewidths=0,
                              rasterized=True)
        ax.scatter(home[0], home[1], marker="*", s=90, c="red", edgecolors="white", linewidths=0.5, label="home")
        label = f"{measure.name} [{measure.unit or '-'}]" + (f"\n({note})" if note else "")
        figure.colorbar(mesh, ax=ax, shrink=0.85, extend=extend, label=label)
        ax.set_xlabel(f"{sheet.axes[0]} [{unit}]")
        ax.set_ylabel(f"{sheet.axes[1]} [{unit}]")
        ax.set_aspect("equal")
    figure.suptitle(title + " (home pose: red star)")
    return figure
