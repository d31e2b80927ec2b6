"""Figures are drawn and checked for layout (issue 16): legends cover no data, titles are not cut.

Before, the legends of the simulation figures sat inside the panels at loc="best" (covering
curves in fig-8-21's top panel, sine-motion's lower panel and free-swing), the workspace legend
on the clouds, and the 1/kappa map's axes title ran under the colour bar.  The figures are
rendered (Agg) and every legend's box must lie outside every axes box, and every title inside the
figure and clear of every axes box.
"""

from __future__ import annotations

import numpy as np

from checks import check_figure_layout as _check_layout
from conftest import GENERATED_DIR
from symkin import analysis, load
from symkin.analysis import plots
from symkin.simulation import Plant, scenarios
from symkin.simulation.output import figure_of


def test_simulation_figures_keep_legends_off_the_curves():
    arm = Plant(load(GENERATED_DIR / "planar_2r"))
    for result in (scenarios.sine([("a", arm), ("b", Plant(load(GENERATED_DIR / "planar_2r").bind(l1=0.2)))],
                                  np.radians([45, 45]), 1, np.radians(30), 1.0, scenarios.Timing(0.1, 200, "rk4")),
                   scenarios.free_swing("a", arm, np.radians([45, 45]), scenarios.Timing(0.1, 200, "rk4"))):
        for spec in result.figures:
            _check_layout(figure_of(spec, result.series))


def test_workspace_and_index_map_figures_keep_titles_and_legends_clear(tmp_path, monkeypatch):
    drawn = []
    monkeypatch.setattr(plots, "_save", lambda figure, path: drawn.append(figure) or path)
    arm = load(GENERATED_DIR / "planar_2r")
    cloud = analysis.sample_workspace(arm, 2000)
    plots.plot_workspaces([plots.WorkspaceLayer(label="l1 = l2 = 10 cm", cloud=cloud)], tmp_path / "w.png",
                          title="Workspace of the planar 2R arm (seed Fig. 8.19), two designs compared")
    values = np.linspace(0.0, 1.0, len(cloud.points))
    plots.plot_index_map(cloud, values, tmp_path / "m.png", label="1/kappa",
                         title="Inverse condition number 1/kappa of the planar 2R arm over its workspace")
    assert len(drawn) == 2
    for figure in drawn:
        _check_layout(figure)


def test_the_slice_and_section_maps_of_a_3d_workspace_keep_titles_clear(tmp_path, monkeypatch):
    """The DELTA's maps: six z slices, and three sections through a point, each with one colour bar."""
    from symkin.analysis.workspace import Occupancy

    drawn = []
    monkeypatch.setattr(plots, "_save", lambda figure, path: drawn.append(figure) or path)
    occupied = np.ones((12, 12, 8), dtype=bool)
    occupancy = Occupancy(np.array([-0.06, -0.06, -0.2]), np.array([0.01, 0.01, 0.01]), occupied)
    values = np.random.default_rng(1).uniform(0.2, 0.9, occupied.shape)
    title = "Inverse condition number 1/kappa of the DELTA over its reachable workspace"
    plots.plot_index_slices(occupancy, values, tmp_path / "s.png", title=title)
    plots.plot_index_sections(occupancy, values, tmp_path / "c.png", [0.0, 0.0, -0.16], title=title)
    assert len(drawn) == 2
    for figure in drawn:
        _check_layout(figure)
