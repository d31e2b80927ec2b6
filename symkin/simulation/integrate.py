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
  at every sample, so it is not used for the zero-order-hold loops.  A right-hand side that
  switches (joint stops engaging and releasing) is integrated mode by mode: the solver stops
  at the switching instant located by an event function (``solve_ivp`` events, root found to
  machine precision on the dense output) and restarts in the new mode, so no step straddles
  the discontinuity and the error control is not smeared over it.  After a switch the guard
  that fired, and its counterpart in the new mode, are zero at the restart: each guard is
  re-armed there (:class:`ArmedGuard`), so that only a crossing after the restart ends the new
  mode.  Without that, a joint that leaves its stop and is pushed back within one solver step
  (a bounce shorter than the step, or a joint settling onto its stop) had its new contact
  located at the restart instant itself, and the run switched back and forth there forever.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from symkin import reporting

#: dx/dt = rhs(t, x, u)
Rhs = Callable[[float, np.ndarray, np.ndarray], np.ndarray]
#: u = control(t, x)
Control = Callable[[float, np.ndarray], np.ndarray]


#: a switching run gives up after this many mode switches (chattering)
MAX_SWITCHES = 10_000
#: a sampled run reports its count every this many control periods
REPORT_PERIODS = 64


class Modes(Protocol):
    """The discrete modes of a switching right-hand side (e.g. :class:`~symkin.simulation.stops.ContactModes`).

    ``rhs(t, x, u, argument(mode))`` is smooth within a mode; each guard g(t, x) (with the
    ``solve_ivp`` event attributes ``direction`` and ``terminal``) ends the mode at its zero.
    """

    def initial(self, x: np.ndarray) -> Any: ...

    def argument(self, mode: Any) -> Any: ...

    def guards(self, mode: Any) -> Sequence[Callable[[float, np.ndarray], float]]: ...

    def switch(self, mode: Any, guard: Any) -> Any: ...


@dataclass(frozen=True)
class Switch:
    """A mode switch of a run: at time ``t`` (state ``x``) the ``guard`` reached zero."""

    t: float
    x: np.ndarray
    guard: Any


class ArmedGuard:
    """A guard g of a mode that starts at a switch (t0, x0), where g may be exactly zero.

    ``solve_ivp`` looks for a sign change of an event between the ends of each step and then
    for a root in that step with Brent's method.  At a switch the guard just crossed (and its
    counterpart, the same function watching the other direction) is zero at t0: the first step
    whose end lies past its next crossing brackets two roots, and Brent's method returns the
    one at t0, so the new mode ends where it began.  The armed guard takes, at t0 itself, the
    sign it has before it triggers (-direction), and g elsewhere: every root after t0 is kept,
    the one at t0 is not.  A guard already past its trigger at t0 (two joints reaching their
    stops within the root tolerance, only one located) then fires at once, as it should.
    """

    def __init__(self, guard: Callable[[float, np.ndarray], float], t0: float):
        self.guard = guard
        self.t0 = t0
        self.direction = getattr(guard, "direction", 0.0)
        self.terminal = getattr(guard, "terminal", False)

    def __call__(self, t: float, x: np.ndarray) -> float:
        if t == self.t0 and self.direction:
            return -self.direction
        return self.guard(t, x)


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
        switches: the mode switches located by events (adaptive runs with modes), in order.
    """

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    evaluations: int
    switches: tuple[Switch, ...] = ()


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


class _SimulatedTime:
    """Reports how far an adaptive run has come, in milliseconds of simulated time (at most once a millisecond)."""

    def __init__(self, end: float):
        self.total = int(np.ceil(end * 1e3))
        self.shown = -1

    def wrap(self, derivative: Callable[[float, np.ndarray], np.ndarray]) -> Callable[[float, np.ndarray], np.ndarray]:
        """``derivative``, reporting the time it is evaluated at."""
        def reported(t: float, x: np.ndarray) -> np.ndarray:
            done = int(t * 1e3)
            if done > self.shown:
                self.shown = done
                reporting.report_progress("simulating (ms of simulated time)", done=done, total=self.total)
            return derivative(t, x)
        return reported


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
        if k % REPORT_PERIODS == 0:
            reporting.report_progress("simulating (control periods)", done=k, total=steps)
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
                 rtol: float = 1e-10, atol: float = 1e-12, modes: Modes | None = None) -> Run:
    """Continuous loop x' = rhs(t, x, control(t, x)) with DOP853 to the tolerances.

    With ``modes``, the right-hand side in a mode m is ``rhs(t, x, u, modes.argument(m))``;
    the run is integrated segment by segment between the zeros of the mode's guards.

    Raises:
        SimulationError: the solver failed, or the modes switched more than
            :data:`MAX_SWITCHES` times.
    """
    from scipy.integrate import solve_ivp

    t_eval = np.asarray(t_eval, dtype=float)
    t0, x, end = t_eval[0], np.asarray(x0, float), t_eval[-1]
    mode = modes.initial(x) if modes is not None else None
    parts: list[np.ndarray] = []
    switches: list[Switch] = []
    evaluations = 0
    clock = _SimulatedTime(end)
    while True:
        argument = () if modes is None else (modes.argument(mode),)
        guards = list(modes.guards(mode)) if modes is not None else []
        events: list[Any] = [ArmedGuard(g, t0) for g in guards] if guards and switches else list(guards)
        times = t_eval[(t_eval >= t0) if not parts else (t_eval > t0)]
        solution = solve_ivp(clock.wrap(lambda t, y: rhs(t, y, control(t, y), *argument)), (t0, end), x,
                             method="DOP853", t_eval=times, rtol=rtol, atol=atol, events=events or None)
        evaluations += int(solution.nfev)
        if not solution.success:
            raise SimulationError(f"DOP853 failed at t = {solution.t[-1] if solution.t.size else t0:.6g} s: "
                                  f"{solution.message}")
        parts.append(np.reshape(solution.y, (x.size, -1)).T)
        if solution.status != 1:  # reached the end
            break
        assert modes is not None, "only a guard ends a segment before the end"
        fired = next(i for i, hits in enumerate(solution.t_events) if hits.size)
        t0, x = float(solution.t_events[fired][0]), solution.y_events[fired][0]
        switches.append(Switch(t0, x, guards[fired]))
        if len(switches) > MAX_SWITCHES:
            raise SimulationError(f"more than {MAX_SWITCHES} mode switches by t = {t0:.6g} s (chattering)")
        mode = modes.switch(mode, guards[fired])
        if t0 >= end:  # the switch is the last instant: its state is the last sample, if not yet recorded
            if sum(len(p) for p in parts) < len(t_eval):
                parts.append(x[None])
            break
    xs = np.concatenate(parts)
    _check(xs, end)
    us = np.array([control(t, x) for t, x in zip(t_eval, xs)], dtype=float)
    return Run(t_eval, xs, us, evaluations, tuple(switches))
