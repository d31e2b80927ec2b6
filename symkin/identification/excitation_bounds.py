"""The bounds of an excitation trajectory (:mod:`symkin.identification.excitation`): its Fourier series, how far it
may stray between the constraint points, and the factor that shrinks a solved motion about its offsets until it
keeps the joint limits, the stops on combinations of joints, the velocity and acceleration bounds (and a platform's
assembly) on a grid denser than the constraints'.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import casadi
import numpy as np

from symkin.mechanism.stops import StopInequalities
from symkin.runtime.info import GeneratedModel


def series(lib: Any, offsets: Any, a: Any, b: Any, period: float, t: np.ndarray) -> tuple[Any, Any, Any]:
    """q, qd, qdd of the Fourier series at the times t, with numpy or CasADi (``lib``) coefficients."""
    harmonics = a.shape[1]
    omega = 2 * np.pi / period * np.arange(1, harmonics + 1)       # (L,)
    sine, cosine = np.sin(np.outer(t, omega)), np.cos(np.outer(t, omega))  # (K, L)
    q = lib.repmat(offsets.T, len(t), 1) if lib is casadi else np.tile(offsets, (len(t), 1))
    q = q + (sine / omega) @ a.T - (cosine / omega) @ b.T
    qd = cosine @ a.T + sine @ b.T
    qdd = -(sine * omega) @ a.T + (cosine * omega) @ b.T
    return q, qd, qdd


def between_points(a: np.ndarray, b: np.ndarray, omega: np.ndarray, spacing: float) -> tuple[np.ndarray, ...]:
    """Per joint, how far q, qd and qdd can stray between two grid points ``spacing`` apart beyond the larger of
    their values there: h^2 / 8 max |f''| for each (the error of linear interpolation), with max |q''| <=
    sum_l (|a| + |b|) l w and each further derivative one more factor l w."""
    size = np.abs(a) + np.abs(b)
    return tuple(spacing ** 2 / 8 * size @ omega ** k for k in (1, 2, 3))


def fitting_factor(states: tuple[np.ndarray, np.ndarray, np.ndarray], offsets: np.ndarray,
                    margins: tuple[np.ndarray, ...], bounds: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
                    stops: StopInequalities | None = None) -> float:
    """The largest s <= 1 with q0 + s (q - q0), s qd and s qdd within the bounds (and a . q + b within the
    ``stops``) at every time, not only at the checked ones (``margins``: what each may add between them,
    proportional to the motion as s is; a stop's, sum_i |a_i| times its joints').

    Raises:
        ValueError: the offsets themselves outside the limits or the stops (IPOPT did not find a feasible motion).
    """
    q, qd, qdd = states
    lower, upper, speeds, accelerations = bounds
    if np.any(offsets < lower) or np.any(offsets > upper):
        raise ValueError("IPOPT found no motion within the joint limits; check the limits and bounds")
    motion = q - offsets
    with np.errstate(divide="ignore", invalid="ignore"):  # a joint at rest bounds nothing: inf (or 0/0 at a limit)
        ratios = [(upper - offsets) / (np.max(motion, axis=0) + margins[0]),
                  (offsets - lower) / (np.max(-motion, axis=0) + margins[0]),
                  speeds / (np.max(np.abs(qd), axis=0) + margins[1]),
                  accelerations / (np.max(np.abs(qdd), axis=0) + margins[2])]
        if stops is not None:
            start, moved, between = stops.values(offsets), motion @ stops.rows.T, np.abs(stops.rows) @ margins[0]
            if not np.all(stops.respected(offsets)):
                raise ValueError("IPOPT found no motion within the joint stops; check the limits and the stops")
            ratios += [(stops.upper - start) / (np.max(moved, axis=0) + between),
                       (start - stops.lower) / (np.max(-moved, axis=0) + between)]
    return float(min(1.0, *(float(np.fmin.reduce(r)) for r in ratios)))  # fmin: NaN (0/0) bounds nothing either


def stops_of_series(model: GeneratedModel, n: int) -> StopInequalities | None:
    """The model's stops on combinations of joints over the n joints a series moves (a hybrid device's wrist
    joints after the model's coordinates), or None without any."""
    stops = StopInequalities.of_model(model)
    return stops.over(n) if len(stops) else None


def start_within_stops(model: GeneratedModel, middle: np.ndarray, stops: StopInequalities | None) -> np.ndarray:
    """Where the start's motion is centred: the middle of the joint limits, or where that breaks a stop on a
    combination of joints (the PHANToM's q3 - q2), the declared home configuration (the model file keeps it within
    the limits and the stops).

    Raises:
        ValueError: the middle breaks a stop and the model declares no home configuration.
    """
    if stops is None or stops.respected(middle):
        return middle
    home = model.info.home_configuration
    if home is None:
        broken = [text for text, value, low, high in zip(stops.expressions, stops.values(middle), stops.lower,
                                                          stops.upper) if not low <= value <= high]
        raise ValueError(f"{model.name}: the middle of the joint limits breaks the stop on {', '.join(broken)}: "
                         "declare serial.home within the stops (the excitation moves about it)")
    return np.concatenate([np.asarray(home, dtype=float), middle[len(home):]])


#: Bisection steps of the shrink factor of a task-space series (its joints' motion is not linear in it).
SHRINK_STEPS = 20


def task_fitting_factor(joints: Callable[..., Any], offsets: np.ndarray, a: np.ndarray, b: np.ndarray,
                         period: float, t: np.ndarray, bounds: tuple[np.ndarray, ...]) -> float:
    """The largest s <= 1 (to 2^-SHRINK_STEPS) with the joints of the series p0 + s (p - p0) within the bounds and
    the legs assembled at the times ``t`` (a grid ten times as dense as the constraints').

    Raises:
        ValueError: not even the series' offsets, the platform at rest, within them (IPOPT found no motion).
    """
    lower, upper, speeds, accelerations = bounds

    def fits(s: float) -> bool:
        q, qd, qdd, margin = joints(*series(np, offsets, s * a, s * b, period, t))
        return bool(np.all(q >= lower) and np.all(q <= upper) and np.all(np.abs(qd) <= speeds)
                    and np.all(np.abs(qdd) <= accelerations) and np.all(np.asarray(margin) >= 0))

    if fits(1.0):
        return 1.0
    if not fits(0.0):
        raise ValueError("IPOPT found no motion within the joint limits; check the limits and bounds")
    low, high = 0.0, 1.0
    for _ in range(SHRINK_STEPS):
        low, high = ((low + high) / 2, high) if fits((low + high) / 2) else (low, (low + high) / 2)
    return low
