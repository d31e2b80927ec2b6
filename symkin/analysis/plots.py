"""Figures of the analyses, written to files (PNG, PDF, SVG... by the file extension).

matplotlib is used through ``matplotlib.figure.Figure`` only (no pyplot, no GUI backend,
no global state), so figures can be drawn from any thread or a headless CI machine.
Every function writes the file atomically (a temporary sibling, then a rename) and
returns its path.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from symkin.analysis.workspace import Occupancy, WorkspaceCloud
from symkin.atomic import file_mode

DPI = 150


def _save(figure, path: str | Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent)
    os.close(handle)
    try:
        figure.savefig(temporary, dpi=DPI, bbox_inches="tight")
        os.chmod(temporary, file_mode())  # mkstemp makes it private; the figure is not
        os.replace(temporary, path)
    finally:
        if os.path.exists(temporary):
            os.unlink(temporary)
    return path


def _figure(size: tuple[float, float] = (6.4, 5.2)):
    from matplotlib.figure import Figure

    return Figure(figsize=size, layout="constrained")


@dataclass(frozen=True)
class WorkspaceLayer:
    """One workspace drawn by :func:`plot_workspaces`.

    Attributes:
        label: legend text, e.g. "l1 = l2 = 10 cm".
        cloud: the TCP point cloud.
        outline: curves (each (count, d)) drawn as lines, e.g. the limit curves.
    """

    label: str
    cloud: WorkspaceCloud
    outline: Sequence[np.ndarray] = ()


def plot_workspaces(layers: Sequence[WorkspaceLayer], path: str | Path, *, title: str = "Workspace",
                    scale: float = 1.0, unit: str = "m") -> Path:
    """TCP point clouds (and outlines) of one or more designs in one planar or 3-D plot.

    Args:
        layers: the workspaces to overlay.
        path: output file.
        title: figure title.
        scale: factor applied to the coordinates (100 to draw metres in cm).
        unit: unit label of the scaled coordinates.
    """
    if not layers:
        raise ValueError("nothing to plot")
    d = layers[0].cloud.points.shape[1]
    figure = _figure()
    colors = ["tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple"]
    if d == 2:
        ax = figure.add_subplot()
        for k, layer in enumerate(layers):
            color = colors[k % len(colors)]
            p = layer.cloud.points * scale
            ax.scatter(p[:, 0], p[:, 1], s=1.5, color=color, alpha=0.35, linewidths=0, rasterized=True)
            for i, curve in enumerate(layer.outline):
                ax.plot(curve[:, 0] * scale, curve[:, 1] * scale, color=color, lw=1.5,
                        label=layer.label if i == 0 else None)
            if not layer.outline:
                ax.plot([], [], "o", color=color, label=layer.label)
        ax.set_aspect("equal")
        ax.grid(True, lw=0.3)
    elif d == 3:
        ax = figure.add_subplot(projection="3d")
        for k, layer in enumerate(layers):
            p = layer.cloud.points * scale
            ax.scatter(p[:, 0], p[:, 1], p[:, 2], s=0.5, color=colors[k % len(colors)], alpha=0.3,
                       label=layer.label, rasterized=True)
        ax.set_zlabel(f"{layers[0].cloud.axes[2]} [{unit}]")
    else:
        raise ValueError(f"cannot draw a {d}-D workspace")
    ax.set_xlabel(f"{layers[0].cloud.axes[0]} [{unit}]")
    ax.set_ylabel(f"{layers[0].cloud.axes[1]} [{unit}]")
    figure.suptitle(title)
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)  # beside the clouds, never on them
    return _save(figure, path)


def plot_index_map(cloud: WorkspaceCloud, values: np.ndarray, path: str | Path, *,
                   title: str = "1/kappa over the workspace", label: str = "1/kappa",
                   outline: Sequence[np.ndarray] = (), scale: float = 1.0, unit: str = "m") -> Path:
    """A local index (1/kappa by default) over the workspace, as colours.

    A 2-DoF grid cloud is drawn as a curvilinear mesh (the image of the joint grid,
    smoothly shaded); scattered or 3-D clouds as coloured points.
    """
    values = np.asarray(values, dtype=np.float64).ravel()
    points = cloud.points * scale
    d = points.shape[1]
    figure = _figure()
    options = {"cmap": "viridis", "vmin": 0.0, "vmax": max(1e-12, float(np.max(values)))}
    if d == 2:
        ax = figure.add_subplot()
        if cloud.grid_shape is not None and len(cloud.grid_shape) == 2:
            shape = cloud.grid_shape
            mesh = ax.pcolormesh(points[:, 0].reshape(shape), points[:, 1].reshape(shape), values.reshape(shape),
                                 shading="gouraud", rasterized=True, **options)
        else:
            mesh = ax.scatter(points[:, 0], points[:, 1], c=values, s=3, linewidths=0, rasterized=True, **options)
        for curve in outline:
            ax.plot(curve[:, 0] * scale, curve[:, 1] * scale, color="black", lw=0.8)
        ax.set_aspect("equal")
    elif d == 3:
        ax = figure.add_subplot(projection="3d")
        mesh = ax.scatter(points[:, 0], points[:, 1], points[:, 2], c=values, s=1, rasterized=True, **options)
        ax.set_zlabel(f"{cloud.axes[2]} [{unit}]")
    else:
        raise ValueError(f"cannot draw a {d}-D workspace")
    figure.colorbar(mesh, ax=ax, label=label)
    ax.set_xlabel(f"{cloud.axes[0]} [{unit}]")
    ax.set_ylabel(f"{cloud.axes[1]} [{unit}]")
    figure.suptitle(title)  # over the axes and the colour bar: an axes title ran under the bar
    return _save(figure, path)


def plot_time_against_error(panels: dict[str, dict[str, tuple[Sequence[float], Sequence[float], Sequence[float]]]],
                            path: str | Path, *, title: str = "Run time against error") -> Path:
    """Log-log plots of wall time against error, one panel per domain, one colour per integrator.

    Args:
        panels: panel title -> integrator name -> (times in s, achieved absolute errors,
            estimated errors); achieved errors are drawn solid, estimates dashed.
    """
    figure = _figure((5.0 * len(panels) + 1.5, 4.6))
    axes = figure.subplots(1, len(panels), sharey=True, squeeze=False)[0]
    floor = 1e-17
    names = list(dict.fromkeys(name for series in panels.values() for name in series))
    for ax, (panel, series) in zip(axes, panels.items()):
        for name, (times, achieved, estimated) in series.items():
            color = f"C{names.index(name)}"
            milliseconds = np.asarray(times) * 1e3
            ax.loglog(milliseconds, np.maximum(achieved, floor), "o-", color=color, label=f"{name}: achieved")
            ax.loglog(milliseconds, np.maximum(estimated, floor), "x--", color=color, alpha=0.6,
                      label=f"{name}: estimated")
        ax.set_xlabel("wall time [ms]")
        ax.set_title(panel, fontsize="medium")
        ax.grid(True, which="both", lw=0.3)
    axes[0].set_ylabel("absolute error of the GCI")
    handles, labels = axes[0].get_legend_handles_labels()
    figure.legend(handles, labels, loc="outside right center", fontsize="small")
    figure.suptitle(title)
    return _save(figure, path)


def plot_index_slices(occupancy: Occupancy, values: np.ndarray, path: str | Path, *, count: int = 6,
                      title: str = "1/kappa over the workspace", label: str = "1/kappa",
                      axes: Sequence[str] = ("x", "y", "z"), scale: float = 1.0, unit: str = "m") -> Path:
    """A local index over a 3-D workspace as horizontal slices (the last axis, z, held fixed); over a
    2-D (planar) workspace as one map.

    Args:
        occupancy: the Cartesian grid (:func:`symkin.analysis.grids.index_grid`).
        values: the index at the cell centres, the grid's shape, NaN outside the workspace
            (drawn blank).
        count: number of slices, evenly spread over the layers that hold workspace cells
            (between 10 % and 90 % of their height).
    """
    values = np.asarray(values, dtype=np.float64)
    planar = values.ndim == 2
    if planar:
        values = values[:, :, None]
    if values.ndim != 3:
        raise ValueError(f"slices need a 2-D or 3-D grid, got shape {values.shape}")
    layers = np.nonzero(np.isfinite(values).any(axis=(0, 1)))[0]
    if layers.size == 0:
        raise ValueError("the workspace is empty: nothing to draw")
    # evenly between 10 % and 90 % of the height: the extreme layers hold a few cells only
    spread = np.linspace(0.1, 0.9, count) if layers.size > count else np.linspace(0.0, 1.0, layers.size)
    chosen = layers[np.unique(np.round(spread * (layers.size - 1)).astype(int))]
    columns = min(3, len(chosen))
    rows = int(np.ceil(len(chosen) / columns))
    figure = _figure((3.4 * columns + 1.2, 3.2 * rows + 0.6))
    grid = figure.subplots(rows, columns, squeeze=False, sharex=True, sharey=True)
    lower, cell = occupancy.lower * scale, occupancy.cell * scale
    shape = values.shape
    edges = [lower[i] + np.arange(shape[i] + 1) * cell[i] for i in range(2)]
    vmax = max(1e-12, float(np.nanmax(values)))
    mesh = None
    for ax, layer in zip(grid.ravel(), chosen):
        mesh = ax.pcolormesh(edges[0], edges[1], values[:, :, layer].T, cmap="viridis", vmin=0.0, vmax=vmax,
                             rasterized=True)
        if not planar:
            ax.set_title(f"{axes[2]} = {lower[2] + (layer + 0.5) * cell[2]:.4g} {unit}", fontsize="medium")
        ax.set_aspect("equal")
        ax.grid(True, lw=0.3)
    for ax in grid.ravel()[len(chosen):]:
        ax.set_visible(False)
    for ax in grid[-1]:
        ax.set_xlabel(f"{axes[0]} [{unit}]")
    for ax in grid[:, 0]:
        ax.set_ylabel(f"{axes[1]} [{unit}]")
    figure.colorbar(mesh, ax=grid.ravel().tolist(), label=label)
    figure.suptitle(title)
    return _save(figure, path)


def plot_index_sections(occupancy: Occupancy, values: np.ndarray, path: str | Path,
                        through: Sequence[float] | np.ndarray, *,
                        title: str = "1/kappa over the workspace", label: str = "1/kappa",
                        axes: Sequence[str] = ("x", "y", "z"), scale: float = 1.0, unit: str = "m") -> Path:
    """A local index over a 3-D workspace on the three grid sections through a point (e.g. the home pose).

    Panels: the plane of the first two axes (z held at the point's), of the first and
    third (y held) and of the second and third (x held), each through the grid layer that
    holds the point; NaN cells (outside the workspace) are blank.

    Raises:
        ValueError: the grid is not 3-D or the point lies outside it.
    """
    values = np.asarray(values, dtype=np.float64)
    if values.ndim != 3:
        raise ValueError(f"sections need a 3-D grid, got shape {values.shape}")
    layer = np.floor((np.asarray(through, dtype=np.float64) - occupancy.lower) / occupancy.cell).astype(int)
    if np.any(layer < 0) or np.any(layer >= np.array(values.shape)):
        raise ValueError(f"the point {list(through)} lies outside the grid")
    vmax = max(1e-12, float(np.nanmax(values)))
    figure = _figure((13.0, 4.2))
    panels = figure.subplots(1, 3, squeeze=True)
    lower, cell = occupancy.lower * scale, occupancy.cell * scale
    mesh = None
    for ax, held in zip(panels, (2, 1, 0)):
        shown = [i for i in range(3) if i != held]
        section = np.take(values, layer[held], axis=held)
        edges = [lower[i] + np.arange(values.shape[i] + 1) * cell[i] for i in shown]
        mesh = ax.pcolormesh(edges[0], edges[1], section.T, cmap="viridis", vmin=0.0, vmax=vmax, rasterized=True)
        ax.set_title(f"{axes[held]} = {lower[held] + (layer[held] + 0.5) * cell[held]:.4g} {unit}", fontsize="medium")
        ax.set_xlabel(f"{axes[shown[0]]} [{unit}]")
        ax.set_ylabel(f"{axes[shown[1]]} [{unit}]")
        ax.set_aspect("equal")
        ax.grid(True, lw=0.3)
    figure.colorbar(mesh, ax=list(panels), label=label)
    figure.suptitle(title)
    return _save(figure, path)
