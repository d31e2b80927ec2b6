"""The workspace in chunks on Dask (issue 15: ``symkin workspace --samples 1e9``).

Oracles: the in-memory study of the same grid sample (extent, 1/kappa extremes and singular
counts equal to the bit; the mean to the rounding of a sum), the occupancy computed from every
point at once on the same cells (equal cell by cell), the planar arm's area l1 l2 pi / 2 within
its error bar (times 3), and the scheduling itself: serial and a 2-worker LocalCluster give the
same result to the bit.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import GENERATED_DIR

from symkin import load
from symkin.analysis import chunked_workspace, global_indices, workspace
from symkin.analysis.chunked_workspace import CloudSpec
from symkin.cli import main
from symkin.runtime.payload import ModelPayload

pytestmark = pytest.mark.xdist_group("dask")

AREA = 0.1 * 0.1 * math.pi / 2          # l1 l2 pi / 2 at the planar arm's defaults
EPS = np.finfo(float).eps


@pytest.fixture(scope="module")
def payload():
    return ModelPayload.from_directory(GENERATED_DIR / "planar_2r")


@pytest.fixture(scope="module")
def grid_result(payload):
    spec = CloudSpec((), (), None, "grid", 70**2, 0)
    return chunked_workspace.chunked_workspace(payload, spec, chunk=700, keep=300, scheduler="serial")


def test_a_chunked_grid_is_the_in_memory_study(grid_result):
    model = load(GENERATED_DIR / "planar_2r")
    cloud = workspace.sample_workspace(model, 70**2, method="grid")
    inv_kappa = global_indices.local_index(model, cloud.q)
    assert grid_result.configurations == len(cloud.q) == 4900
    np.testing.assert_array_equal(grid_result.lower, cloud.points.min(axis=0))
    np.testing.assert_array_equal(grid_result.upper, cloud.points.max(axis=0))
    assert (grid_result.inv_kappa_min, grid_result.inv_kappa_max) == (inv_kappa.min(), inv_kappa.max())
    # a sum of 4900 terms in 1 in [0, 1], in another order: n eps relative at worst
    assert abs(grid_result.inv_kappa_mean - inv_kappa.mean()) <= len(inv_kappa) * EPS * inv_kappa.mean()
    occupancy = grid_result.occupancy
    index = np.clip(np.floor((cloud.points - occupancy.lower) / occupancy.cell).astype(int), 0,
                    np.array(occupancy.occupied.shape) - 1)
    every_point = np.zeros_like(occupancy.occupied)
    every_point[tuple(index.T)] = True
    np.testing.assert_array_equal(occupancy.occupied, every_point)
    singular = inv_kappa <= 0.0
    assert grid_result.singular_count == singular.sum() == 70  # theta2 = 0, the grid's first column
    assert grid_result.singular_on_boundary == occupancy.lookup(cloud.points[singular], occupancy.boundary()).sum()
    assert abs(grid_result.measure.value - AREA) <= 3 * grid_result.measure.error
    assert len(grid_result.cloud.q) <= 7 * math.ceil(300 / 7)
    assert len(grid_result.inv_kappa) == len(grid_result.cloud.q)


def test_every_task_holds_at_most_a_chunk_and_returns_summaries_bounded_by_the_grid(payload, monkeypatch):
    seen = []
    original = chunked_workspace._summary_chunk

    def spy(*args):
        result = original(*args)
        seen.append((args[3] - args[2], result))
        return result

    monkeypatch.setattr(chunked_workspace, "_summary_chunk", spy)
    spec = CloudSpec((), (), None, "random", 5000, 1)
    found = chunked_workspace.chunked_workspace(payload, spec, chunk=1200, keep=100, scheduler="serial")
    assert [count for count, _ in seen] == [1200, 1200, 1200, 1200, 200]
    for _, summary in seen:
        assert len(summary.occupied) <= found.occupancy.occupied.size
        assert len(summary.kept_q) <= 100 // 5 + 1


def test_serial_and_a_local_cluster_agree_to_the_bit(payload, grid_result):
    spec = CloudSpec((), (), None, "grid", 70**2, 0)
    local = chunked_workspace.chunked_workspace(payload, spec, chunk=700, keep=300, scheduler="local", workers=2)
    np.testing.assert_array_equal(local.occupancy.occupied, grid_result.occupancy.occupied)
    np.testing.assert_array_equal(local.cloud.points, grid_result.cloud.points)
    assert (local.inv_kappa_mean, local.measure.value, local.measure.error) == \
        (grid_result.inv_kappa_mean, grid_result.measure.value, grid_result.measure.error)


def test_cli_workspace_in_chunks(tmp_path, capsys):
    figure = tmp_path / "cloud.png"
    assert main(["workspace", str(GENERATED_DIR / "planar_2r"), "-n", "1e5", "--scheduler", "serial", "--chunk",
                 "20000", "-o", str(figure), "--map", str(tmp_path / "map.png")]) == 0
    out = capsys.readouterr().out
    assert "99856 configurations (grid, in chunks of 20000)" in out
    assert "in 5 chunks in this process" in out
    area = out.split("area: ")[1].split()
    assert abs(float(area[0]) - AREA) <= 3 * float(area[2])
    assert figure.stat().st_size > 0
    assert (tmp_path / "map.png").stat().st_size > 0


@pytest.mark.parametrize("model, arguments, message", [
    ("delta", ["--scheduler", "serial"], "a parallel mechanism's workspace is measured on a Cartesian grid"),
    ("planar_2r", ["--scheduler", "elsewhere"], "--scheduler 'elsewhere'"),
    ("planar_2r", ["--scheduler", "serial", "--chunk", "0"], "at least one configuration"),
])
def test_cli_workspace_chunked_bad_input_exits_with_code_2(capsys, model, arguments, message):
    with pytest.raises(SystemExit) as exit_info:
        main(["workspace", str(GENERATED_DIR / model), "--no-figure", *arguments])
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err
