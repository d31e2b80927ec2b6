"""The largest box and upright cylinder inside a workspace's interior cells (issue 64: a workspace as a maker quotes
it).  Oracles written here: every axis-aligned box of small random masks tried by brute force; a cylinder whose
cells are known, and the containment of every point of the cylinder found in occupied cells."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from symkin.analysis import inscribed
from tolerances import CLOSED_FORM


def brute_force_box(mask: np.ndarray) -> int:
    """The most cells of an all-True axis-aligned box of a 3-d mask, every box tried."""
    best = 0
    ranges = [[(a, b) for a in range(n) for b in range(a + 1, n + 1)] for n in mask.shape]
    for (x0, x1), (y0, y1), (z0, z1) in itertools.product(*ranges):
        if mask[x0:x1, y0:y1, z0:z1].all():
            best = max(best, (x1 - x0) * (y1 - y0) * (z1 - z0))
    return best


@pytest.mark.parametrize("seed", range(6))
def test_the_largest_box_is_the_brute_forces(seed):
    rng = np.random.default_rng(seed)
    mask = rng.random((5, 6, 4)) < 0.8
    cell = np.array([0.01, 0.02, 0.03])
    box = inscribed.largest_box(mask, np.zeros(3), cell)
    cells = np.round(box.size / cell).astype(int)
    assert int(np.prod(cells)) == brute_force_box(mask)
    first = np.round(box.lower / cell).astype(int)
    assert mask[tuple(slice(f, f + c) for f, c in zip(first, cells))].all()
    assert box.volume == pytest.approx(np.prod(cells) * np.prod(cell), rel=1e-12)


def test_a_flat_mask_gives_its_largest_rectangle_and_an_empty_one_none():
    mask = np.zeros((6, 5), dtype=bool)
    mask[1:4, 1:5] = True
    mask[5, 0] = True
    box = inscribed.largest_box(mask, np.array([-0.3, 0.1]), np.array([0.1, 0.1]))
    np.testing.assert_allclose(box.lower, [-0.2, 0.2], rtol=0, atol=CLOSED_FORM)
    np.testing.assert_allclose(box.upper, [0.1, 0.6], rtol=0, atol=CLOSED_FORM)
    assert inscribed.largest_box(np.zeros((3, 3, 3), dtype=bool), np.zeros(3), np.ones(3)) is None


def test_the_cylinder_found_lies_in_the_cells_of_a_known_cylinder_and_nearly_fills_it():
    """Cells whose centres lie within a cylinder of radius 0.1 m over 0.2 m of height (cells of 1 cm): the cylinder
    found has every sampled point in a True cell, its height is the cells', and its radius is within a cell and
    a half-diagonal of 0.1 m."""
    cell = np.array([0.01, 0.01, 0.01])
    lower = np.array([-0.15, -0.15, 0.0])
    centres = lower + cell * (np.stack(np.meshgrid(*(np.arange(n) for n in (30, 30, 30)), indexing="ij"), -1) + 0.5)
    mask = (np.hypot(centres[..., 0] - 0.01, centres[..., 1]) <= 0.1) & (centres[..., 2] >= 0.05) & (
        centres[..., 2] <= 0.25)
    found = inscribed.largest_cylinder(mask, lower, cell)
    assert found.top - found.bottom == pytest.approx(0.2, abs=1e-12)
    assert 0.1 - 1.5 * cell[0] - np.hypot(*cell[:2]) / 2 <= found.radius <= 0.1
    rng = np.random.default_rng(2)
    angle, reach = rng.uniform(0, 2 * np.pi, 20000), found.radius * np.sqrt(rng.uniform(0, 1, 20000))
    points = np.column_stack([found.centre[0] + reach * np.cos(angle), found.centre[1] + reach * np.sin(angle),
                              rng.uniform(found.bottom, found.top, 20000)])
    index = np.floor((points - lower) / cell).astype(int)
    assert mask[tuple(index.T)].all()


@pytest.mark.parametrize("seed", range(4))
def test_a_box_of_given_sizes_fits_where_a_brute_force_finds_a_full_window(seed):
    rng = np.random.default_rng(seed)
    mask = rng.random((7, 6, 5)) < 0.85
    cell = np.array([0.01, 0.02, 0.03])
    for cells in itertools.product(range(1, 4), repeat=3):
        size = np.array(cells) * cell * 0.9                      # rounded up to whole cells
        placements = [start for start in itertools.product(*(range(n - k + 1) for n, k in zip(mask.shape, cells)))
                      if mask[tuple(slice(s, s + k) for s, k in zip(start, cells))].all()]
        found = inscribed.placed_box(mask, np.zeros(3), cell, size)
        assert (found is None) == (not placements)
        if found is not None:
            start = tuple(np.round(found.lower / cell).astype(int))
            assert start in placements
            np.testing.assert_allclose(found.size, np.array(cells) * cell, rtol=CLOSED_FORM)
