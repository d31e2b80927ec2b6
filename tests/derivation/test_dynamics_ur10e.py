"""UR10e inverse dynamics against an independent numeric recursive Newton-Euler (tests/newton_euler.py).

The Newton-Euler side uses Universal Robots' classic DH table and mass properties exactly
as published (docs/ur10e-parameters.md: CoM and inertia in the classic frame of each link);
symkin derives models/ur10e.yaml (modified DH, converted frames) and
models/ur10e_classic.yaml.  Agreement to 1e-10 relative checks the dynamics and the frame
conversion at once.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import random_q, reference_function
from newton_euler import Link, inverse_dynamics
from tolerances import DYNAMICS


def _inertia(xx, yy, zz, xy, xz, yz):
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


UR10E = [  # d, a, alpha, mass, com (classic frame i), inertia about the CoM (classic frame i axes)
    Link(0.1807, 0, np.pi / 2, 7.369, (0.021, 0, 0.027), _inertia(0.03408, 0.03529, 0.02156, 0.00002, -0.00425, 0.00008)),
    Link(0, -0.6127, 0, 13.051, (0.38, 0, 0.158), _inertia(0.02814, 0.77068, 0.76943, 0.00005, -0.01561, 0.00002)),
    Link(0, -0.57155, 0, 3.989, (0.24, 0, 0.068), _inertia(0.01014, 0.30928, 0.30646, 0.00008, 0.00916, 0)),
    Link(0.17415, 0, np.pi / 2, 2.1, (0, 0.007, 0.018), _inertia(0.00296, 0.00222, 0.00258, -0.00001, 0, -0.00024)),
    Link(0.11985, 0, -np.pi / 2, 1.98, (0, 0.007, 0.018), _inertia(0.00296, 0.00222, 0.00258, -0.00001, 0, -0.00024)),
    Link(0.11655, 0, 0, 0.615, (0, 0, -0.026), _inertia(0.00040, 0.00041, 0.00034, 0, 0, 0)),
]
GRAVITY = np.array([0, 0, -9.81])


@pytest.mark.parametrize("name", ["ur10e", "ur10e_classic"])
def test_inverse_dynamics_equals_numeric_newton_euler(name, models, derivations):
    model = models[name]
    tau = reference_function(model, derivations[name]["inverse_dynamics"])
    rng = np.random.default_rng(20)
    for _ in range(20):
        q, qd, qdd = random_q(model, rng), rng.uniform(-2, 2, 6), rng.uniform(-5, 5, 6)
        want = inverse_dynamics(UR10E, GRAVITY, q, qd, qdd)
        got = tau(q, qd, qdd)[0]
        # symbolic against numeric Newton-Euler: rounding only (DYNAMICS of the largest torque)
        assert np.max(np.abs(got - want)) <= DYNAMICS * np.max(np.abs(want)), (q, qd, qdd)


def test_newton_euler_is_not_vacuous():
    """The oracle itself: a static arm holds gravity only; moving it changes the torques."""
    q = np.array([0.1, -1.2, 0.8, 0.3, 1.1, -0.4])
    static = inverse_dynamics(UR10E, GRAVITY, q, np.zeros(6), np.zeros(6))
    assert static[0] == pytest.approx(0, abs=1e-12)  # the first axis is vertical
    assert abs(static[1]) > 10  # the shoulder carries the arm
    assert np.all(inverse_dynamics(UR10E, np.zeros(3), q, np.zeros(6), np.zeros(6)) == 0)
    moving = inverse_dynamics(UR10E, GRAVITY, q, np.ones(6), np.zeros(6))
    assert np.max(np.abs(moving - static)) > 1
