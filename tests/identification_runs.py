"""Simulated runs of the driven 2R arm for the identification tests (tests/identification/test_identification.py and
tests/identification/test_identified_model.py): the model's own generated inverse dynamics along a periodic excitation (a finite
Fourier series, Swevers et al. 1997) with Gaussian noise on the efforts."""

from __future__ import annotations

import numpy as np
import pytest

from sample_models import DRIVEN
from symkin import pipeline
from symkin.model import model_from_text
from symkin.runtime.loader import load

#: Noise on the efforts (N m): large against rounding, small against the 2R arm's torques (~0.1 N m).
NOISE = 1e-3
#: A run's duration and sampling (s): five periods of the excitation at 200 Hz.
DURATION, RATE = 10.0, 200.0


@pytest.fixture(scope="module")
def arm(tmp_path_factory):
    """The driven 2R arm (sample_models.DRIVEN) derived with its regressors and inverse dynamics (numpy)."""
    model = model_from_text(DRIVEN, "driven")
    request = pipeline.resolve_request(model, ("regressor", "base_regressor", "inverse_dynamics", "energy_regressor"),
                                       "numpy", None, False, "none")
    return load(pipeline.write(pipeline.generate(model, request), tmp_path_factory.mktemp("identify")), "numpy")


def excitation(n: int, seed: int = 0, harmonics: int = 4, period: float = 2.0, rate: float = RATE):
    """t, q, qd, qdd of a finite Fourier series per joint (Swevers et al. 1997), exact derivatives."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, DURATION, 1.0 / rate)
    omega = 2 * np.pi / period * np.arange(1, harmonics + 1)
    a, b = rng.uniform(-0.4, 0.4, (2, n, harmonics)) / np.arange(1, harmonics + 1)
    phase = np.outer(t, omega)                                  # (N, harmonics)
    q = np.sin(phase) @ a.T + np.cos(phase) @ b.T + 0.7
    qd = (np.cos(phase) * omega) @ a.T - (np.sin(phase) * omega) @ b.T
    qdd = -(np.sin(phase) * omega ** 2) @ a.T - (np.cos(phase) * omega ** 2) @ b.T
    return t, q, qd, qdd


def write_run(path, names, t, q, tau, qd=None, qdd=None):
    """The run as a CSV file of `symkin identify` (t, q_*, optionally qd_* and qdd_*, tau_*)."""
    columns = {"t": t[:, None], **{f"q_{n}": q[:, [k]] for k, n in enumerate(names)}}
    if qd is not None:
        columns.update({f"qd_{n}": qd[:, [k]] for k, n in enumerate(names)})
        columns.update({f"qdd_{n}": qdd[:, [k]] for k, n in enumerate(names)})
    columns.update({f"tau_{n}": tau[:, [k]] for k, n in enumerate(names)})
    np.savetxt(path, np.hstack(list(columns.values())), delimiter=",", header=",".join(columns), comments="")
    return path


def simulated_run(arm, seed=1):
    """t, q, qd, qdd and the efforts with noise of an excitation run of the arm."""
    t, q, qd, qdd = excitation(len(arm.info.coordinates), seed)
    tau = arm.inverse_dynamics(q, qd, qdd) + np.random.default_rng(seed).normal(0, NOISE, q.shape)
    return t, q, qd, qdd, tau
