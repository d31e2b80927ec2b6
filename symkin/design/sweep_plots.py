"""Figures of a sweep: metric maps over two varied parameters, and the GCI-volume Pareto front.

Drawn with ``matplotlib.figure.Figure`` (no pyplot) and returned as PNG bytes
(:func:`symkin.design.plots.png`), so the command writes them atomically.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from matplotlib.cm import ScalarMappable

from symkin.design.plots import png
from symkin.design.sweeps import OK, SweepDefinition

LABELS = {"gci": "GCI (mean 1/kappa)", "volume": "workspace measure", "kappa_min": "min kappa",
          "kappa_max": "max kappa", "torque_peak": "peak effort per unit force (N m/N)"}


def pareto_front(gci: np.ndarray, volume: np.ndarray) -> np.ndarray:
    """Indices of the designs no other design beats in both GCI and volume (both maximized),
    by decreasing volume: sort by volume, keep each design whose GCI exceeds every GCI before it."""
    order = np.lexsort((-gci, -volume))
    front, best = [], -np.inf
    for i in order:
        if gci[i] > best:
            front.append(i)
            best = gci[i]
    return np.array(front, dtype=int)


def metric_maps(table: Any, definition: SweepDefinition, model_name: str) -> bytes | None:
    """One panel per metric over the first two varied parameters (None: fewer than two are varied)."""
    from matplotlib.figure import Figure

    if len(definition.axes) < 2:
        return None
    data = table.to_pydict()
    ok = np.array([s == OK for s in data["status"]])
    x, y = (np.array(data[a.name]) for a in definition.axes[:2])
    figure = Figure(figsize=(5.0 * len(definition.metrics), 4.4), layout="constrained")
    for k, metric in enumerate(definition.metrics):
        ax = figure.add_subplot(1, len(definition.metrics), k + 1)
        values = np.where(ok, np.array(data[metric], dtype=float), np.nan)
        scale = "log" if metric.startswith("kappa") else "linear"
        if definition.sobol is None and len(definition.axes) == 2:
            shape = (definition.axes[0].count, definition.axes[1].count)
            mesh: ScalarMappable = ax.pcolormesh(x.reshape(shape), y.reshape(shape), values.reshape(shape),
                                                 shading="nearest", norm=scale)
        else:
            mesh = ax.scatter(x, y, c=values, s=12, norm=scale)
        figure.colorbar(mesh, ax=ax, label=LABELS[metric])
        if (~ok).any():
            ax.scatter(x[~ok], y[~ok], marker="x", color="k", s=14, label="no result (status)")
            ax.legend(loc="upper left", bbox_to_anchor=(0.0, -0.15), frameon=False)
        ax.set_xlabel(definition.axes[0].name)
        ax.set_ylabel(definition.axes[1].name)
        ax.set_title(LABELS[metric])
    others = "" if len(definition.axes) == 2 else f" (all {len(definition.axes)} varied parameters projected)"
    figure.suptitle(f"Design sweep of {model_name}: {definition.size} designs{others}")
    return png(figure)


def pareto_figure(table: Any, definition: SweepDefinition, model_name: str,
                  mark: Mapping[str, float] | None = None) -> bytes | None:
    """GCI against workspace measure for every design, the Pareto front highlighted, and ``mark``
    (e.g. the optimum of ``symkin optimize``: {"gci":..., "volume":..., "label":...}) if given.
    None: the sweep lacks gci or volume."""
    from matplotlib.figure import Figure

    if not {"gci", "volume"} <= set(definition.metrics):
        return None
    data = table.to_pydict()
    ok = np.array([s == OK for s in data["status"]])
    gci, volume = np.array(data["gci"], dtype=float)[ok], np.array(data["volume"], dtype=float)[ok]
    figure = Figure(figsize=(7.0, 5.0), layout="constrained")
    ax = figure.add_subplot()
    ax.scatter(volume, gci, s=8, color="0.7", label=f"{int(ok.sum())} designs")
    if len(gci):
        front = pareto_front(gci, volume)
        ax.plot(volume[front], gci[front], "o-", color="C0", ms=4, label=f"Pareto front ({len(front)} designs)")
    if mark is not None:
        ax.plot([mark["volume"]], [mark["gci"]], "*", color="C3", ms=14, label=str(mark.get("label", "marked")))
    ax.set_xlabel("workspace measure (int_W dW)")
    ax.set_ylabel("GCI")
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False)
    ax.set_title(f"{model_name}: GCI against workspace, {definition.size} designs")
    return png(figure)
