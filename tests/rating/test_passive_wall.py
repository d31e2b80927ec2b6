"""The stiffest passive wall along a task axis (issue 64): Abbott and Okamura's bound (IEEE T-RO 21(5), 2005) on one
prismatic joint, checked against the energy a sampled, quantized virtual wall puts into the device over closed
cycles; and its inputs at a handle (the least damping, the least Coulomb force and the widest quantization error along
an axis) against scans of the motions the hand can make on the seed's 2R arm.

The energy oracle is written here from the wall's definition, not from the formula: a joint (viscous b, Coulomb f_c)
moves through the sampled positions x_0, ..., x_N = x_0 (a closed cycle inside the wall); the wall holds
F_k = -K q(x_k) over each period T (q: the encoder's reading, floor(x / Delta) Delta), so it does the work
-sum_k K q(x_k) (x_{k+1} - x_k), while moving at constant speed between samples (the least dissipating way through
them) the joint dissipates sum_k b (x_{k+1} - x_k)^2 / T + f_c |x_{k+1} - x_k|.  The wall with the device is passive
iff no cycle makes the first exceed the second.
"""

from __future__ import annotations

import numpy as np
import pytest

from symkin.rating import formulas
from tolerances import EPS

PERIOD = 1e-3
STEP = 2e-5                                   # m per encoder count
#: (viscous N s/m, Coulomb N) of a linear haptic axis: the sampled term 2 b / T binds (40 against 5000 N/m), then a
#: damped one where the quantization term 2 f_c / Delta binds (10000 against 5000 N/m).
JOINTS = [(0.02, 0.05), (5.0, 0.05)]


def surplus(K: float, x: np.ndarray, viscous: float, coulomb: float) -> float:
    """The energy the wall puts in beyond what the joint dissipates over the closed cycle x (J)."""
    x = np.append(x, x[0])
    moved = np.diff(x)
    read = STEP * np.floor(x[:-1] / STEP)
    work = -np.sum(K * read * moved)
    return float(work - np.sum(viscous * moved ** 2 / PERIOD + coulomb * np.abs(moved)))


def one_joint_bound(viscous: float, coulomb: float) -> float:
    J = np.array([[1.0]])                      # a prismatic joint moving the handle along its axis
    sampled = formulas.renderable_stiffness(formulas.axis_damping(J, [viscous]), PERIOD)
    quantized = formulas.quantization_stiffness(formulas.axis_slip_friction(J, [coulomb]),
                                                formulas.axis_quantization(J, [STEP]))
    return float(np.minimum(sampled, quantized)[0])


@pytest.mark.parametrize("viscous, coulomb", JOINTS)
def test_the_one_joint_bound_is_abbott_and_okamuras(viscous, coulomb):
    assert one_joint_bound(viscous, coulomb) == min(2 * viscous / PERIOD, 2 * coulomb / STEP)


@pytest.mark.parametrize("viscous, coulomb", JOINTS)
def test_no_cycle_gains_energy_below_the_bound_and_one_does_above_it(viscous, coulomb):
    """Below the bound random cycles of every size (a tenth of a count to a thousand counts per period) all lose
    energy; 2 % above it a cycle gains: two samples far apart (the growing oscillation, where 2 b / T binds) or two
    samples straddling one count's edge (the one-count limit cycle, where 2 f_c / Delta binds)."""
    bound = one_joint_bound(viscous, coulomb)
    rng = np.random.default_rng(64)
    inside = 500 * STEP                                      # m into the wall, on a count's edge
    for scale in STEP * np.logspace(-1, 3, 41):
        for _ in range(25):
            cycle = inside + scale * rng.uniform(-1.0, 1.0, size=rng.integers(2, 12))
            # the sums' rounding (terms up to K x |dx|) is far below the margins the bound leaves
            assert surplus(0.98 * bound, cycle, viscous, coulomb) <= 64 * EPS * bound * inside * scale * cycle.size
    if bound == 2 * viscous / PERIOD:
        # K far^2 against 2 b far^2 / T + 2 f_c far: 2 % above the bound gains once far > 50 f_c T / b
        far = 100 * coulomb * PERIOD / viscous
        worst = np.array([inside, inside + far])
    else:
        # K Delta s against 2 f_c s + 2 b s^2 / T: 2 % above the bound gains once s < 0.02 f_c T / b
        s = 0.002 * coulomb * PERIOD / viscous
        worst = np.array([inside - s / 2, inside + s / 2])
    assert surplus(1.02 * bound, worst, viscous, coulomb) > 0.0
    assert surplus(0.98 * bound, worst, viscous, coulomb) < 0.0
