"""Identification of a device's base parameters from measured motions and torques (issue 33).

The inverse dynamics is linear in the base parameters (:mod:`symkin.dynamics.base_parameters`):
tau = Y_b(q, qd, qdd) pi_b.  Stacking the N samples of a run gives the overdetermined system
W pi_b = y (W: N n x b, y: N n), solved here by

* ordinary least squares (``ols``): pi_b = argmin |y - W pi_b|, with the covariance
  sigma^2 (W^T W)^-1, sigma^2 = |y - W pi_b|^2 / (N n - b) (Gautier, "Numerical calculation of the
  base inertial parameters of robots", J. Robotic Systems 8(4), 1991; Swevers et al. 1997);
* weighted least squares (``wls``): each joint's rows weighted by 1 / sigma_j, the standard deviation
  of that joint's OLS residual (Gautier and Poignet, "Extended Kalman filtering and weighted least
  squares dynamic identification of robot", Control Engineering Practice 9(12), 2001), so that a noisy
  joint does not drown an accurate one.

Both solve through the SVD of W with unit columns (column equilibration; of the triangular factor of its QR
decomposition, which has the same singular values): a run that does not excite
some combination of parameters (a singular value below :data:`RANK_TOLERANCE` times the largest) is
refused, naming the parameters of that combination, instead of printing huge estimates.  The standard
deviation of each estimate comes with it, and the estimate is validated on held-out samples (the last
part of the run): the torque RMS per joint of tau - Y_b pi_b.

The energy balance (``energy``: Gautier, "Dynamic identification of robots with power model", IEEE ICRA
1997) needs no accelerations: the energy h = Y_e(q, qd) pi (:mod:`symkin.dynamics.regressor`) changes over a
window [t_a, t_b] by the work of the efforts less what friction dissipates,

    (Y_e(t_b) - Y_e(t_a)) pi + int qd . Y_d pi dt = int qd . tau dt,

Y_d the friction columns of Y (its ``fv``, ``fc``, ``fo``: their efforts depend on qd alone).  A parameter
change that moves no effort moves no power, so the rows W of this balance are W_b K with the base
parameters' K of Y = Y_b K, and the windows of a run give W_b pi_b = y, one equation per window, solved as
``ols``; the integrals are trapezoidal sums over the samples (error O(h^2) in the sampling step h).

Measurements come from a CSV file (:func:`read_measurements`): a time column ``t`` (s) and per coordinate
``q_<name>``, ``tau_<name>`` and ``qd_<name>``, ``qdd_<name>``; without the rates, they are computed from q
by a zero-phase low-pass filter (Butterworth, 4th order, forward and backward) and central
differences, and tau is filtered alike (parallel filtering, Gautier 1997), at a cutoff the caller states.
"""

from __future__ import annotations

import csv
import difflib
import io
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from symkin.dynamics.parameter_names import DISSIPATIVE
from symkin.model.confined_read import ReadRefused, read_bounded

#: A singular value of the equilibrated observation matrix below this fraction of the largest one means
#: the run does not excite that combination of parameters (sqrt(eps): the estimate would carry no digit).
RANK_TOLERANCE = float(np.sqrt(np.finfo(np.float64).eps))
#: Butterworth order of the filter that differentiates q (4: -80 dB per decade past the cutoff).
FILTER_ORDER = 4
#: Bytes of a run's CSV (an hour at 1 kHz of a 7-joint arm is 0.5 GB); the magnitude beyond which a value is no
#: measurement in SI units (unix time in ms is 2e12; the least squares' products of 1e308 values overflow).
MAX_CSV_BYTES, MAX_MAGNITUDE = 1 << 30, 1e15


class DataError(ValueError):
    """Measurements that cannot be used: the message names the file, the row and the column, and the fix."""


@dataclass(frozen=True)
class Measurements:
    """A run: times (N,), and (N, n) positions, velocities, accelerations and efforts.

    Attributes:
        rates: how qd and qdd were obtained ("measured", or the filter that derived them from q).
    """

    source: str
    time: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray
    rates: str

    def split(self, held_out: float) -> tuple[Measurements, Measurements]:
        """The first part of the run (for the estimate) and its last ``held_out`` fraction (for validation)."""
        cut = len(self.time) - int(round(held_out * len(self.time)))
        parts = []
        for rows in (slice(0, cut), slice(cut, None)):
            parts.append(Measurements(self.source, self.time[rows], self.q[rows], self.qd[rows], self.qdd[rows],
                                      self.tau[rows], self.rates))
        return parts[0], parts[1]


def read_measurements(path: str | Path, coordinates: Sequence[str], cutoff: float | None = None) -> Measurements:
    """The run in the CSV file ``path`` for a model with these coordinates (see the module docstring).

    Args:
        cutoff: the low-pass cutoff (Hz) that derives qd and qdd from q when the file has no rate columns.

    Raises:
        DataError: a missing or unknown column, a value that is not a finite number, time that does not
            increase (or is not uniform where q must be differentiated), or rates without a cutoff.
    """
    source = str(path)
    try:
        rows = list(csv.reader(io.StringIO(read_bounded(path, MAX_CSV_BYTES).decode("utf-8-sig"), newline="")))
    except ReadRefused as err:
        raise DataError(f"{source}: {err.message}; {err.fix}") from None
    except (csv.Error, UnicodeDecodeError) as err:
        raise DataError(f"{source}: not a CSV file ({err})") from None
    if not rows:
        raise DataError(f"{source}: empty; write a header row (t, q_<joint>..., tau_<joint>...) and one row per sample")
    header = [name.strip() for name in rows[0]]
    required = ["t", *(f"q_{c}" for c in coordinates), *(f"tau_{c}" for c in coordinates)]
    rates = [f"{g}_{c}" for g in ("qd", "qdd") for c in coordinates]
    known = set(required) | set(rates)
    for column, name in enumerate(header, start=1):
        if name not in known:
            near = difflib.get_close_matches(name, sorted(known), n=1)
            hint = f"did you mean '{near[0]}'?" if near else f"the columns are {', '.join(required + rates)}"
            raise DataError(f"{source}, row 1, column {column}: unknown column '{name}'; {hint}")
    for column, name in enumerate(header, start=1):
        if header.index(name) + 1 != column:
            raise DataError(f"{source}, row 1, column {column}: the column '{name}' repeats column "
                            f"{header.index(name) + 1}; keep one of them")
    missing = [name for name in required if name not in header]
    if missing:
        raise DataError(f"{source}, row 1: missing column{'s' if len(missing) > 1 else ''} {', '.join(missing)} "
                        f"(the model's coordinates are {', '.join(coordinates)})")
    given = [name for name in rates if name in header]
    if given and len(given) != len(rates):
        absent = [name for name in rates if name not in header]
        raise DataError(f"{source}, row 1: rate columns {', '.join(absent)} missing: give qd_ and qdd_ of every "
                        "coordinate, or none of them (then --cutoff derives them from q)")
    data = np.empty((len(rows) - 1, len(header)))
    for r, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise DataError(f"{source}, row {r}: {len(row)} values for {len(header)} columns")
        for c, text in enumerate(row):
            try:
                value = float(text)
            except ValueError:
                value = math.nan
            if not math.isfinite(value):
                raise DataError(f"{source}, row {r}, column {c + 1} ({header[c]}): '{text.strip()[:40]}' is not a "
                                "finite number; drop the sample or fill the gap")
            if abs(value) > MAX_MAGNITUDE:
                raise DataError(f"{source}, row {r}, column {c + 1} ({header[c]}): {value:g} is beyond "
                                f"{MAX_MAGNITUDE:g}, no measurement in SI units (its square would overflow the "
                                "least squares); check the units and the sample")
            data[r - 2, c] = value
    columns = {name: data[:, k] for k, name in enumerate(header)}
    time = columns["t"]
    steps = np.diff(time)
    if np.any(steps <= 0):
        r = int(np.argmax(steps <= 0)) + 3
        raise DataError(f"{source}, row {r}, column {header.index('t') + 1} (t): the time does not increase "
                        f"({time[r - 3]:g} s, then {time[r - 2]:g} s); sort the samples by time")

    def block(group: str) -> np.ndarray:
        return np.stack([columns[f"{group}_{c}"] for c in coordinates], axis=-1)

    q, tau = block("q"), block("tau")
    if given:
        return Measurements(source, time, q, block("qd"), block("qdd"), tau, "measured")
    return _differentiated(source, time, q, tau, cutoff)


def _differentiated(source: str, time: np.ndarray, q: np.ndarray, tau: np.ndarray,
                    cutoff: float | None) -> Measurements:
    """qd, qdd from q by filtfilt and central differences; tau filtered alike (the same delay: none)."""
    from scipy.signal import butter, filtfilt

    if cutoff is None:
        raise DataError(f"{source}: no qd_/qdd_ columns: give --cutoff HZ, the low-pass cutoff with which symkin "
                        "derives them from q (a few times the bandwidth of the motion)")
    if len(time) < 3:
        raise DataError(f"{source}: {len(time)} samples; differentiating q needs many more")
    step = float(np.mean(np.diff(time)))
    if np.max(np.abs(np.diff(time) - step)) > 1e-6 * step:
        r = int(np.argmax(np.abs(np.diff(time) - step))) + 3
        raise DataError(f"{source}, row {r}, column t: the sampling is not uniform (step {time[r - 2] - time[r - 3]:g}"
                        f" s against {step:g} s), which differentiating q needs; resample the run")
    nyquist = 0.5 / step
    if not 0 < cutoff < nyquist:
        raise DataError(f"{source}: --cutoff {cutoff:g} Hz must lie between 0 and the Nyquist frequency "
                        f"{nyquist:g} Hz of the sampling")
    b, a = butter(FILTER_ORDER, cutoff / nyquist)
    filtered = filtfilt(b, a, q, axis=0)
    qd = np.gradient(filtered, step, axis=0)
    qdd = np.gradient(qd, step, axis=0)
    rates = (f"derived from q: Butterworth low-pass of order {FILTER_ORDER} at {cutoff:g} Hz, forward and "
             "backward (zero phase), central differences; tau filtered alike")
    return Measurements(source, time, filtered, qd, qdd, filtfilt(b, a, tau, axis=0), rates)


@dataclass(frozen=True)
class LeastSquaresEstimate:
    """Base parameters estimated from a run.

    Attributes:
        names: the base parameters' names.
        values: the estimates.
        std: their standard deviations (from the residual and (W^T W)^-1).
        method: "ols", "wls" or "energy".
        joint_std: the standard deviation of each joint's residual (the weights of WLS are its inverse).
        condition: the condition number of the column-equilibrated observation matrix.
        samples: the samples used.
    """

    names: tuple[str, ...]
    values: np.ndarray
    std: np.ndarray
    method: str
    joint_std: np.ndarray
    condition: float
    samples: int

    @property
    def relative_std(self) -> np.ndarray:
        """std / |value| (inf for a value of zero): above ~0.1 a parameter is poorly identified by the run."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.values != 0, self.std / np.abs(self.values), np.inf)


def _solve(W: np.ndarray, y: np.ndarray, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray, float]:
    """pi, (W^T W)^-1 and the condition number, through the SVD of W with unit columns: of its triangular factor
    R ([W y] = Q [R z; 0 r], Householder; W and R have the same singular values, and Q^T y = z), so that the
    tall W is factored once, without forming its U (10^5 samples of a 6-DoF arm: 600 000 rows).

    Raises:
        DataError: a combination of parameters the rows do not excite, named.
    """
    scale = np.linalg.norm(W, axis=0)
    silent = [names[int(k)] for k in np.flatnonzero(scale == 0)]
    if silent:
        raise DataError(f"the run does not excite {', '.join(silent)} (their regressor columns are zero): move "
                        "the joints that act on them")
    count = W.shape[1]
    triangle = np.asarray(np.linalg.qr(np.column_stack([W / scale, y]), mode="r"))
    U, S, Vt = np.linalg.svd(triangle[:count, :count])
    y = triangle[:count, count]
    weak = np.flatnonzero(S < RANK_TOLERANCE * S[0])
    if weak.size:
        direction = np.abs(Vt[weak[0]])
        involved = [names[int(k)] for k in np.argsort(direction)[::-1] if direction[k] > 0.1][:6]
        raise DataError(f"the run does not identify the combination of {', '.join(involved)} (singular value "
                        f"{S[weak[0]] / S[0]:.1e} of the largest, condition {S[0] / S[-1]:.1e}): excite the joints "
                        "more richly (symkin excite), or fix these parameters")
    pi = (Vt.T @ ((U.T @ y) / S)) / scale
    inverse = (Vt.T / S ** 2) @ Vt / np.outer(scale, scale)
    return pi, inverse, float(S[0] / S[-1])


def least_squares(Y_b: np.ndarray, tau: np.ndarray, names: Sequence[str], method: str = "ols") -> LeastSquaresEstimate:
    """Least-squares base parameters from the base regressor ``Y_b`` (N, n, b) and the efforts ``tau`` (N, n).

    Raises:
        DataError: fewer equations than parameters, or a combination the run does not excite.
        ValueError: an unknown method.
    """
    if method not in ("ols", "wls"):
        raise ValueError(f"unknown method '{method}': ols or wls")
    samples, joints, count = Y_b.shape
    dof = samples * joints - count
    if dof <= 0:
        raise DataError(f"{samples} samples give {samples * joints} equations for {count} base parameters: record "
                        f"at least {count // joints + 1} samples (many more, for a useful estimate)")
    pi, inverse, condition = _solve(Y_b.reshape(-1, count), tau.reshape(-1), names)
    residual = tau - Y_b @ pi
    joint_std = np.sqrt(np.sum(residual ** 2, axis=0) / (samples - count / joints))
    if method == "wls":
        weights = 1.0 / np.where(joint_std > 0, joint_std, 1.0)
        pi, inverse, condition = _solve((Y_b * weights[None, :, None]).reshape(-1, count),
                                        (tau * weights).reshape(-1), names)
        residual = (tau - Y_b @ pi) * weights
    variance = float(np.sum(residual ** 2) / dof)
    return LeastSquaresEstimate(tuple(names), pi, np.sqrt(variance * np.diag(inverse)), method, joint_std, condition, samples)


@dataclass(frozen=True)
class Validation:
    """The estimate on held-out samples: per joint, the RMS of tau - Y_b pi_b and of tau itself."""

    rms: np.ndarray
    tau_rms: np.ndarray
    samples: int

    @property
    def relative(self) -> np.ndarray:
        return self.rms / np.where(self.tau_rms > 0, self.tau_rms, 1.0)


def validate(Y_b: np.ndarray, tau: np.ndarray, values: np.ndarray) -> Validation:
    """The torque error of ``values`` on held-out samples (Y_b (N, n, b), tau (N, n))."""
    return validation_of(Y_b @ values, tau)


def validation_of(predicted: np.ndarray, tau: np.ndarray) -> Validation:
    """The error of ``predicted`` efforts against the held-out ones (both (N, n))."""
    error = tau - predicted
    return Validation(np.sqrt(np.mean(error ** 2, axis=0)), np.sqrt(np.mean(tau ** 2, axis=0)), len(tau))


def validation_figure_png(time: np.ndarray, tau: np.ndarray, predicted: np.ndarray, coordinates: Sequence[str],
                          units: Sequence[str], title: str) -> bytes:
    """Measured and predicted efforts over the held-out samples, one panel per joint."""
    import io

    from matplotlib.figure import Figure

    count = len(coordinates)
    figure = Figure(figsize=(8.0, 1.9 * count + 0.8), layout="constrained")
    axes = figure.subplots(count, 1, sharex=True, squeeze=False)[:, 0]
    for k, ax in enumerate(axes):
        ax.plot(time, tau[:, k], color="0.6", linewidth=1.5, label="measured")
        ax.plot(time, predicted[:, k], color="tab:blue", linewidth=0.9, label="Y_b pi_b")
        ax.set_ylabel(f"{coordinates[k]} [{units[k]}]")
    axes[0].legend(loc="upper right", fontsize="small")
    axes[-1].set_xlabel("t [s]")
    figure.suptitle(title)
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=110)
    return buffer.getvalue()


def weighted_triangle(Y: np.ndarray, tau: np.ndarray, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """R and z of [W y] = Q [R z; 0 r] (Householder QR) for a regressor Y (N, n, P) and efforts (N, n) with each
    joint's rows weighted: |W pi - y|^2 = |R pi - z|^2 + r^2, the data of an estimate in P numbers (for the
    consistent estimate, :mod:`symkin.identification.consistent`)."""
    count = Y.shape[-1]
    rows = (Y * weights[None, :, None]).reshape(-1, count)
    triangle = np.asarray(np.linalg.qr(np.column_stack([rows, (tau * weights).reshape(-1)]), mode="r"))
    return triangle[:count, :count], triangle[:count, count]


def energy_windows(time: np.ndarray, window: float) -> np.ndarray:
    """The sample indices that bound consecutive windows of ``window`` seconds or the next sample after (the
    last window ends at the last sample whole; the run's remainder shorter than a window is left out)."""
    bounds = [0]
    for k in range(1, len(time)):
        if time[k] - time[bounds[-1]] >= window * (1.0 - 1e-9):
            bounds.append(k)
    return np.asarray(bounds)


def energy_balance(time: np.ndarray, qd: np.ndarray, tau: np.ndarray, Y_e: np.ndarray, Y_d: np.ndarray,
                   window: float) -> tuple[np.ndarray, np.ndarray]:
    """W (windows, P) and y (windows,) of the energy balance over consecutive windows (module docstring).

    Args:
        time, qd, tau: the run (N,), (N, n), (N, n).
        Y_e: the energy regressor at its samples (N, P).
        Y_d: the regressor's dissipative columns at its samples, the others zero (N, n, P).
        window: the windows' length (s).
    """
    steps = np.diff(time)[:, None]

    def integral(rate: np.ndarray) -> np.ndarray:           # trapezoidal, from the first sample to each one
        return np.concatenate([np.zeros((1,) + rate.shape[1:]), np.cumsum(0.5 * steps * (rate[1:] + rate[:-1]),
                                                                            axis=0)])

    bounds = energy_windows(time, window)
    stored = Y_e[bounds[1:]] - Y_e[bounds[:-1]]
    dissipated = np.diff(integral(np.einsum("ni,nip->np", qd, Y_d))[bounds], axis=0)
    work = np.diff(integral(np.einsum("ni,ni->n", qd, tau)[:, None])[bounds, 0])
    return stored + dissipated, work


def energy_least_squares(run: Measurements, Y: np.ndarray, Y_e: np.ndarray, Y_b: np.ndarray, K: np.ndarray,
                         standard: Sequence[str], names: Sequence[str], window: float) -> LeastSquaresEstimate:
    """Base parameters from the energy balance over windows of ``run`` (module docstring), with their standard
    deviations; ``joint_std`` is the torque residual per joint of the estimate over the run, as for the other
    methods.

    Args:
        Y, Y_e, Y_b: the regressor (N, n, P), the energy regressor (N, P) and the base regressor (N, n, b) at the
            run's samples.
        K: the base parameters' combinations (b, P), Y = Y_b K (:func:`symkin.identification.implied_parameters.combinations`).
        standard, names: the standard (P) and the base (b) parameters' names.
        window: the windows' length (s).

    Raises:
        DataError: fewer windows than parameters, or a combination the run does not excite.
    """
    dissipative = np.array([name.rsplit(".", 1)[-1] in DISSIPATIVE for name in standard])
    W, work = energy_balance(run.time, run.qd, run.tau, Y_e, np.where(dissipative, Y, 0.0), window)
    W_b = W @ np.linalg.pinv(K)            # W = W_b K, K of full row rank: W_b = W K^+
    tau = run.tau
    windows, count = W_b.shape
    if windows <= count:
        raise DataError(f"{windows} windows of the run give {windows} energy equations for {count} base parameters: "
                        "shorten --window or record a longer run (many more windows than parameters, for a useful "
                        "estimate)")
    pi, inverse, condition = _solve(W_b, work, names)
    variance = float(np.sum((work - W_b @ pi) ** 2) / (windows - count))
    samples, joints = tau.shape
    joint_std = np.sqrt(np.sum((tau - Y_b @ pi) ** 2, axis=0) / max(samples - count / joints, 1.0))
    return LeastSquaresEstimate(tuple(names), pi, np.sqrt(variance * np.diag(inverse)), "energy", joint_std,
                                condition, samples)
