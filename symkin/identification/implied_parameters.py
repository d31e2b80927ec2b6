"""The standard parameters an estimate implies: K from the regressors, which parameters are identifiable, and the
standard parameters nearest a prior that a model file can hold.

Least squares identifies only the base parameters pi_b = K pi.  :func:`nearest_standard` gives the standard
parameters those data imply and that stay closest to the model's own values (Gautier and Khalil's regrouping
keeps the non-identifiable parameters at their a priori values; here "closest" is in the scaled norm of
:func:`symkin.identification.consistent.prior_scale`):

    pi = argmin |D^-1 (pi - pi_prior)|  subject to  K pi = pi_b,   D = diag(prior_scale(pi_prior)).

A parallel model's file holds fewer standard parameters than its regressor has columns (one rotor for all the
actuators' I_a; a spherical model declares no rods): :func:`nearest_held` takes an estimate into what the file
holds, pi = fixed + T z (:class:`~symkin.identification.identified_model.Held`), its base parameters as close to
the estimate's as the file allows (least squares), then the standard parameters nearest the estimate's in the same
scaled norm.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from symkin.identification.consistent import prior_scale
from symkin.identification.identified_model import Held, file_held
from symkin.model.schema import Model

#: A column of K smaller than this fraction of K's largest entry holds no identifiable part of its parameter
#: (K from the regressors by least squares carries rounding of about eps cond(Y_b); sqrt(eps) is far above it).
IDENTIFIABLE_TOLERANCE = float(np.sqrt(np.finfo(np.float64).eps))


#: States of a run that :func:`combinations` solves Y = Y_b K over (evenly spread; all of a shorter run).
COMBINATION_STATES = 512


def combinations(Y: np.ndarray, Y_b: np.ndarray) -> np.ndarray:
    """K with Y = Y_b K: the base parameters' combinations of the standard ones, from both regressors at the
    same states (N, n, P) and (N, n, b); exact up to rounding where Y_b has full column rank.

    The identity holds at every state, so :data:`COMBINATION_STATES` of them spread over the run suffice
    (benchmarks/bench_identification.py times both on 10^5 states of the UR10e); all are taken if those leave
    Y_b rank-deficient.
    """
    count = len(Y_b)
    chosen = np.unique(np.linspace(0, count - 1, min(count, COMBINATION_STATES)).astype(int))
    K, rank = _least_squares(Y[chosen], Y_b[chosen])
    if rank < Y_b.shape[-1] and len(chosen) < count:  # the spread states do not excite every base parameter
        K, _ = _least_squares(Y, Y_b)
    return K


def _least_squares(Y: np.ndarray, Y_b: np.ndarray) -> tuple[np.ndarray, int]:
    """(K, rank of the stacked Y_b) of the least-squares solution of Y = Y_b K over the given states."""
    K, _, rank, _ = np.linalg.lstsq(Y_b.reshape(-1, Y_b.shape[-1]), Y.reshape(-1, Y.shape[-1]), rcond=None)
    return K, int(rank)


def identifiable(K: np.ndarray) -> np.ndarray:
    """Which standard parameters enter some base parameter (a boolean per column of K)."""
    largest = float(np.max(np.abs(K))) if K.size else 0.0
    return np.max(np.abs(K), axis=0) > IDENTIFIABLE_TOLERANCE * largest


def nearest_standard(K: np.ndarray, base_values: np.ndarray, prior: np.ndarray) -> np.ndarray:
    """The standard parameters nearest ``prior`` whose base parameters are ``base_values`` (module docstring)."""
    D = prior_scale(prior)
    correction = np.linalg.lstsq(K * D, base_values - K @ prior, rcond=None)[0]  # the minimum-norm solution
    return prior + D * correction


def nearest_held(K: np.ndarray, base_values: np.ndarray, near: np.ndarray, held: Held) -> np.ndarray:
    """The standard parameters pi = fixed + T z whose base parameters K pi are nearest ``base_values`` (least
    squares) and, among those, nearest ``near`` in the scaled norm |D^-1 (pi - near)|, D = diag(prior_scale(near)):
    z = z_0 + N y with z_0 the least-squares solution of K T z = base_values - K fixed and N the null space of K T."""
    A = K @ held.T
    z0 = np.linalg.lstsq(A, base_values - K @ held.fixed, rcond=None)[0]
    _, singular, Vt = np.linalg.svd(A)
    rank = int(np.sum(singular > max(A.shape) * np.finfo(float).eps * singular.max(initial=0.0)))
    N = Vt[rank:].T
    D = prior_scale(near)
    y = np.linalg.lstsq((held.T @ N) / D[:, None], (near - held.fixed - held.T @ z0) / D, rcond=None)[0]
    return held.fixed + held.T @ (z0 + N @ y)


def file_values(source: Model, names: Sequence[str], K: np.ndarray, prior: np.ndarray, found: Any,
                standard: Any | None,
                consistent_held: Callable[[Held], np.ndarray]) -> tuple[np.ndarray, np.ndarray, str]:
    """What a model file is rewritten with after an identification: (the standard parameters, which of them the run
    identifies, a note on what the file could not hold).

    A file that holds every standard parameter (:func:`symkin.identification.identified_model.file_held`) gets the
    consistent estimate ``standard`` or, from the base parameters ``found.values``, the standard parameters nearest
    the model's ``prior`` (:func:`nearest_standard`).  A file that holds fewer (a parallel model's) gets the
    least-squares estimate taken into what it holds by :func:`nearest_held`, the consistent one refitted over what
    it holds (``consistent_held(held)``: the file's values z), and the note says how far the base parameters it can
    hold lie from the estimate's.

    Args:
        names: the standard parameters, the regressor's columns.
        K: the base parameters' combinations of them (:func:`combinations`).
        found: the least-squares estimate of the base parameters (values, std, names).
        standard: the consistent estimate of the standard parameters (its ``values``), or None.
    """
    identified = identifiable(K)
    held = file_held(source, names, prior)
    if held.every_column:
        return (standard.values if standard is not None else nearest_standard(K, found.values, prior)), identified, ""
    base = found.values if standard is None else K @ standard.values
    estimate = nearest_held(K, base, prior, held) if standard is None else held.fixed + held.T @ consistent_held(held)
    unheld = [name for name, held_here in zip(names, held.columns) if not held_here]
    return estimate, identified & held.columns, _held_note(found, K @ estimate, base, unheld)


def _held_note(found: Any, written: np.ndarray, base: np.ndarray, unheld: list[str]) -> str:
    """How far the base parameters of what a parallel model's file holds lie from the estimate's, in standard
    deviations, and why (one rotor for all actuators: their estimated differences are not in it; ``unheld``: the
    standard parameters the file does not declare, kept at the model's values)."""
    deviation = np.abs(written - base) / np.where(found.std > 0, found.std, np.inf)
    worst = int(np.argmax(deviation))
    kept = f", and not {', '.join(unheld)} (kept at the model's values)" if unheld else ""
    return (f"; its base parameters within {deviation[worst]:.2g} standard deviations of the estimate's (most: "
            f"{found.names[worst]}; the file holds one rotor for all actuators{kept})")
