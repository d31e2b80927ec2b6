"""Time integration of a closed loop: a plant x' = f(t, x, u) under a controller u = c(t, x).

Two integrators, for two jobs:

* :func:`run_sampled` - the real-time structure of a haptic or robot controller: the control
  is computed at the sample instants t_k = k T (1 kHz by default) and held constant over the
  period (zero-order hold), while the plant moves on with classic fixed-step Runge-Kutta 4.
  Every step costs exactly four evaluations of the dynamics, which is what a hard real-time
  loop needs, and the held torque is what the real actuators apply.  Its error is O(h^4).
* :func:`run_adaptive` - scipy's ``solve_ivp`` with DOP853 (Dormand-Prince 8(5,3)) and a
  continuous control law, for offline reference runs to a tolerance (the energy-balance
  checks run at rtol 1e-10).  A discontinuous (sampled) control would force it to tiny steps
  at every sample, so it is not used for the zero-order-hold loops.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: dx/dt = rhs(t, x, u)
Rhs = Callable[[float, np.ndarray, np.ndarray], np.ndarray]
#: u = control(t, x)
Control = Callable[[float, np.ndarray], np.ndarray]


class SimulationError(RuntimeError):
    """The integration failed (the state left the domain of the dynamics, or the solver gave up)."""


@dataclass(frozen=True)
class Run:
    """A simulated run.

    Attributes:
        t: (N,) sample times [s].
        x: (N, nx) states at ``t``.
        u: (N, nu) controls: ``u[k]`` is applied from ``t[k]`` (sampled runs: held until
            ``t[k + 1]``); the last row is the control at the final state.
        evaluations: right-hand-side evaluations spent.
    """

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    evaluations: int


def rk4_step(rhs: Rhs, t: float, x: np.ndarray, u: np.ndarray, h: float) -> np.ndarray:
    """One classic Runge-Kutta 4 step of x' = rhs(t, x, u) with u held over [t, t + h]."""
    k1 = rhs(t, x, u)
    k2 = rhs(t + 0.5 * h, x + (0.5 * h) * k1, u)
    k3 = rhs(t + 0.5 * h, x + (0.5 * h) * k2, u)
    k4 = rhs(t + h, x + h * k3, u)
    return x + (h / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)


def _check(x: np.ndarray, t: float) -> None:
    if not np.all(np.isfinite(x)):
        raise SimulationError(f"the state is no longer finite at t = {t:.6g} s (a singular mass matrix, or the "
                              "step is too large for the stiffness of the loop: raise --rate or --substeps)")


def run_sampled(rhs: Rhs, control: Control, x0: np.ndarray, period: float, steps: int,
                substeps: int = 1) -> Run:
    """Sampled-data loop: u_k = control(t_k, x_k), held while RK4 advances the plant.

    Args:
        rhs: the plant.
        control: the controller, called once per period.
        x0: initial state.
        period: control period T [s] (1e-3 for a 1 kHz haptic loop).
        steps: number of periods.
        substeps: RK4 steps per period (h = T / substeps).

    Raises:
        SimulationError: the state became non-finite.
    """
    h = period / substeps
    x = np.array(x0, dtype=float)
    xs = np.empty((steps + 1, x.size))
    xs[0] = x
    u = np.asarray(control(0.0, x), dtype=float)
    us = np.empty((steps + 1, u.size))
    for k in range(steps):
        us[k] = u
        t = k * period
        for s in range(substeps):
            x = rk4_step(rhs, t + s * h, x, u, h)
        _check(x, t + period)
        xs[k + 1] = x
        u = np.asarray(control((k + 1) * period, x), dtype=float)
    us[steps] = u
    return Run(np.arange(steps + 1) * period, xs, us, 4 * steps * substeps)


def run_adaptive(rhs: Rhs, control: Control, x0: np.ndarray, t_eval: np.ndarray, *,
                 rtol: float = 1e-10, atol: float = 1e-12) -> Run:
    """Continuous loop x' = rhs(t, x, control(t, x)) with DOP853 to the tolerances.

    Raises:
        SimulationError: the solver failed.
    """
    from scipy.integrate import solve_ivp

    t_eval = np.asarray(t_eval, dtype=float)
    solution = solve_ivp(lambda t, x: rhs(t, x, control(t, x)), (t_eval[0], t_eval[-1]), np.asarray(x0, float),
                         method="DOP853", t_eval=t_eval, rtol=rtol, atol=atol)
    if not solution.success:
        raise SimulationError(f"DOP853 failed at t = {solution.t[-1]:.6g} s: {solution.message}")
    xs = solution.y.T
    _check(xs, t_eval[-1])
    us = np.array([control(t, x) for t, x in zip(t_eval, xs)], dtype=float)
    return Run(t_eval, xs, us, int(solution.nfev))
