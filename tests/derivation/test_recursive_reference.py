"""The recursive reference of the scaling benchmark computes the right thing (issue 12).

``benchmarks/recursive_reference.py`` writes RNEA and CRBA on CasADi symbols only to count
their operations against symkin's generated dynamics; these tests evaluate both numerically
on a generated 7-joint chain and compare them with the tests' own Newton-Euler
(tests/newton_euler.py, base-frame form, no shared code): tau with and without qdd, and
every column of M as the torques of a unit acceleration without velocity or gravity.
"""

from __future__ import annotations

import sys

import numpy as np

from conftest import ROOT
from newton_euler import inverse_dynamics, links_of
from tolerances import DYNAMICS

sys.path.insert(0, str(ROOT / "benchmarks"))
from chain_models import dh_chain  # noqa: E402
from recursive_reference import arithmetic_operations, crba_function, rnea_function  # noqa: E402

N = 7
GRAVITY = np.array([0.0, 0.0, -9.81])


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def test_the_reference_rnea_is_the_newton_euler_of_the_tests():
    rng = np.random.default_rng(12)
    full, bias = rnea_function(dh_chain(N), GRAVITY, True), rnea_function(dh_chain(N), GRAVITY, False)
    for _ in range(5):
        q, qd, qdd = rng.uniform(-np.pi, np.pi, N), rng.uniform(-2, 2, N), rng.uniform(-3, 3, N)
        expected = inverse_dynamics(links_of(dh_chain(N)), GRAVITY, q, qd, qdd)
        assert _relative(np.asarray(full(q, qd, qdd)).ravel(), expected) < DYNAMICS
        expected_bias = inverse_dynamics(links_of(dh_chain(N)), GRAVITY, q, qd, np.zeros(N))
        assert _relative(np.asarray(bias(q, qd)).ravel(), expected_bias) < DYNAMICS


def test_the_reference_crba_is_the_mass_matrix_of_the_tests_newton_euler():
    rng = np.random.default_rng(13)
    crba = crba_function(dh_chain(N))
    for _ in range(5):
        q = rng.uniform(-np.pi, np.pi, N)
        expected = np.array([inverse_dynamics(links_of(dh_chain(N)), np.zeros(3), q, np.zeros(N), column)
                             for column in np.eye(N)]).T
        assert _relative(np.asarray(crba(q)), expected) < DYNAMICS


def test_the_counts_grow_as_the_algorithms_do():
    """RNEA is O(n) and CRBA O(n^2): doubling n doubles, resp. about quadruples, the count."""
    rnea = [arithmetic_operations(rnea_function(dh_chain(n), GRAVITY, False)) for n in (6, 12, 24)]
    crba = [arithmetic_operations(crba_function(dh_chain(n))) for n in (6, 12, 24)]
    assert all(1.7 < b / a < 2.3 for a, b in zip(rnea, rnea[1:]))
    assert all(2.5 < b / a < 4.2 for a, b in zip(crba, crba[1:]))
