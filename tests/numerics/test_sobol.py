"""Sobol' points drawn without scipy.stats (symkin.numerics.sobol): scipy.stats.qmc.Sobol is the reference, bit for
bit, so that every quantity estimated from them (GCI, workspace measures, the quoted figures of the docs) is what
it was when scipy drew them, and the command line stops importing scipy.stats for its sample points."""

from __future__ import annotations

import subprocess
import warnings

import numpy as np
import pytest

from conftest import SYMKIN_CLI
from symkin.numerics import sampling
from symkin.numerics.sobol import MAX_DIMENSION, Sobol

qmc = pytest.importorskip("scipy.stats").qmc


def _scipy(dimension: int, start: int, stop: int, rng: np.random.Generator | None) -> np.ndarray:
    engine = qmc.Sobol(dimension, scramble=rng is not None, bits=30, rng=rng)
    if start:
        engine.fast_forward(start)
    with warnings.catch_warnings():  # a range that is not a power of 2
        warnings.simplefilter("ignore", UserWarning)
        return engine.random(stop - start)


@pytest.mark.parametrize("dimension", [1, 2, 3, 6, 31, MAX_DIMENSION])
@pytest.mark.parametrize("start, stop", [(0, 1), (0, 1024), (37, 1000), (4096, 8192), (5, 70001)])
def test_the_points_are_scipys_bit_for_bit(dimension, start, stop):
    """Plain and scrambled (scipy spawns a child of the generator it is given: the scramble draws from that child),
    any range of the sequence (scipy's fast-forward), up to the table's last dimension."""
    plain = Sobol(dimension).points(start, stop)
    assert np.array_equal(plain, _scipy(dimension, start, stop, None))
    key = [dimension, start]
    scrambled = Sobol(dimension, np.random.default_rng(key).spawn(1)[0]).points(start, stop)
    assert np.array_equal(scrambled, _scipy(dimension, start, stop, np.random.default_rng(key)))


def test_the_box_sampler_draws_what_it_drew_with_scipy():
    """sampling.sobol as it was written on scipy: replicate scrambles from one generator, then the digits below 2^-30
    from that generator (its stream untouched by the scrambles)."""
    lower, upper = np.array([-1.0, 0.0, 2.0]), np.array([1.0, 0.5, 3.0])
    rng = np.random.default_rng(2026)
    sets = np.stack([qmc.Sobol(d=3, scramble=True, bits=30, rng=rng).random_base2(6) for _ in range(4)])
    expected = lower + (sets + rng.random(sets.shape) * 2.0**-30) * (upper - lower)
    assert np.array_equal(sampling.sobol(lower, upper, 6, np.random.default_rng(2026), replicates=4), expected)


def test_more_dimensions_than_the_table_are_refused():
    with pytest.raises(ValueError, match=f"between 1 and {MAX_DIMENSION}"):
        Sobol(MAX_DIMENSION + 1)


def test_a_qmc_estimate_imports_no_scipy_stats():
    script = ("import sys\n"
              "import numpy as np\n"
              "from symkin.numerics import sampling\n"
              "from symkin.integration.integrators import quasi_monte_carlo_estimate\n"
              "sampling.sobol(np.zeros(2), np.ones(2), 4, np.random.default_rng(0), replicates=4)\n"
              "quasi_monte_carlo_estimate(np.ones((4, 1)), 64)\n"
              "print('scipy.stats' in sys.modules)\n")
    result = subprocess.run([SYMKIN_CLI[0], "-c", script], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "False"
