"""symkin.newton.newton_iterate's stall rule: a sample whose residual stagnates stops early, not converged, and the
samples that converge are untouched by it."""

from __future__ import annotations

import numpy as np

from symkin.newton import newton_iterate

ITERATIONS = 30


def squares(shift: np.ndarray):
    """equations(x, rows) of x^2 + shift = 0, one scalar equation per sample."""
    def equations(x: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return x**2 + shift[rows, None], 2 * x[:, :, None]
    return equations


def test_a_stagnating_residual_stops_a_sample_without_touching_the_converging_ones():
    shift = np.array([-2.0, 1.0, -9.0])  # x^2 = 2 and x^2 = 9 have roots; x^2 = -1 has none: Newton wanders
    start = np.array([[1.0], [0.5], [2.0]])
    plain = newton_iterate(start, squares(shift), 1e-12, ITERATIONS)
    stalled = newton_iterate(start, squares(shift), 1e-12, ITERATIONS, stall=4)
    assert stalled.converged.tolist() == plain.converged.tolist() == [True, False, True]
    np.testing.assert_array_equal(stalled.solution[[0, 2]], plain.solution[[0, 2]])
    np.testing.assert_array_equal(stalled.iterations[[0, 2]], plain.iterations[[0, 2]])
    assert plain.iterations[1] == ITERATIONS
    assert stalled.iterations[1] < ITERATIONS / 2
    assert np.isnan(stalled.solution[1, 0])
    assert stalled.residual[1] >= 1.0  # x^2 + 1 never falls below 1
