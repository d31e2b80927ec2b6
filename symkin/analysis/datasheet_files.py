"""A datasheet's files: one CSV row per rated pose and one figure with a map per measure (``symkin rate``)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from symkin.analysis.datasheet import Datasheet, axis_scale


def csv_text(sheet: Datasheet, coordinates: Sequence[str]) -> str:
    """One row per rated pose: q, the TCP and every measure (the home pose last)."""
    unit = axis_scale(sheet.axes)[2]
    header = [*coordinates, *(f"{a} [{unit}]" for a in sheet.axes),
              *(f"{m.name} [{m.unit}]" if m.unit else m.name for m in sheet.measures)]
    columns = np.column_stack([sheet.q, sheet.points, *(m.values for m in sheet.measures)])
    rows = [",".join(f"{v:.9g}" for v in row) for row in columns]
    return "\n".join([f"# symkin rate: {sheet.model}, {len(rows)} poses (the last is the home pose)",
                      ",".join(header), *rows]) + "\n"


def figure_png(sheet: Datasheet, title: str) -> bytes:
    """The datasheet figure: one map per measure over the rated poses (x-y, or 3-D for a spatial device),
    coloured by its value, the home pose marked."""
    import io

    from matplotlib.figure import Figure

    count = len(sheet.measures)
    columns = min(3, count)
    rows = -(-count // columns)
    spatial = sheet.points.shape[1] == 3
    figure = Figure(figsize=(4.2 * columns, 3.6 * rows + 0.6), layout="constrained")
    scale, unit, _ = axis_scale(sheet.axes)
    points = scale * sheet.points
    for k, measure in enumerate(sheet.measures):
        ax: Any = figure.add_subplot(rows, columns, k + 1, **({"projection": "3d"} if spatial else {}))
        values = measure.values
        finite = np.isfinite(values)
        low, high = np.percentile(values[finite], [1, 99]) if finite.any() else (0.0, 1.0)
        mesh = ax.scatter(*points.T, c=values, cmap="viridis", vmin=low, vmax=max(high, low + 1e-300), s=2,
                          linewidths=0, rasterized=True)
        ax.scatter(*points[sheet.home][:, None], marker="*", s=80, c="red", label="home")
        figure.colorbar(mesh, ax=ax, shrink=0.8, label=f"{measure.name} [{measure.unit or '-'}]")
        ax.set_xlabel(f"{sheet.axes[0]} [{unit}]")
        ax.set_ylabel(f"{sheet.axes[1]} [{unit}]")
        if spatial:
            ax.set_zlabel(f"{sheet.axes[2]} [{unit}]")
        else:
            ax.set_aspect("equal")
    figure.suptitle(title)
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=110)
    return buffer.getvalue()
