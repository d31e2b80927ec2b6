"""The scenarios of ``symkin simulate``: each returns the time series and a summary.

* :func:`sine` - the seed's simplified haptic scenario (sec. 5.3, Figs. 8.21, 8.22): one
  joint follows a sine, the others are fixed; the joint torques are the inverse dynamics of
  the prescribed motion (eq. 8.34) and the TCP forces F = J^-T tau (eq. 8.35).  The motion
  is then simulated forward under computed-torque control from the same start, which checks
  that the plant reproduces it with these torques.
* :func:`tracking` - trajectory following (Fig. 8.17): a TCP circle, inverse kinematics,
  computed-torque control at the sample rate, zero-order hold.
* :func:`haptic_wall` - the haptic force loop (Fig. 8.18): a mass-spring-damper hand pushes
  the TCP into a virtual wall rendered at the sample rate.
* :func:`gravity_compensation` - a hand moves the handle up and down while the actuators
  cancel the device's weight, tau = G(q), and again with them off: the force felt.
* :func:`free_swing` - no torques: the mechanism swings under gravity; without friction its
  energy k + u stays constant.

Every run records the power balance k + u - w (:meth:`ArmSystem.balance`), whose drift is
the integration error.  With joint stops (``stops=StopSettings(...)``, see
:mod:`symkin.simulation.stops`) the balance is k + u + U + D - w, every run reports its
contacts (:mod:`symkin.simulation.contacts`) and marks them in the figures, and a fixed-step
run checks RK4's stability in contact.

Length: the five scenarios share the run helpers (the system with its stops, the integrator,
the stop report, the energy balance) and differ in their controller and columns only; side by
side they read as one table of experiments.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from symkin.simulation import contacts as contact_report
from symkin.simulation import labels
from symkin.simulation.contacts import Contact
from symkin.simulation.control import ComputedTorque, Wall, WallRenderer
from symkin.simulation.integrate import Run, run_adaptive, run_sampled
from symkin.simulation.limits import declared_limit_lines
from symkin.simulation.plant import Plant
from symkin.simulation.stops import (
    DAMPING_RATIO,
    TIME_CONSTANT,
    ContactModes,
    JointStops,
    Stability,
    rk4_stability,
    stop_configurations,
)
from symkin.simulation.system import ArmSystem
from symkin.simulation.trajectory import JointSine, task_circle
from symkin.simulation.user import MassSpringDamperUser, sine_intent

INTEGRATORS = ("rk4", "dop853")


@dataclass(frozen=True)
class Series:
    """The time series of one run (one design).

    Attributes:
        label: the design, e.g. "l1 = 10 cm, l2 = 10 cm".
        columns: name (with unit) -> (N,) values; the first is the time.
        contacts: the joint-stop contacts of the run (shaded in the figures).
    """

    label: str
    columns: dict[str, np.ndarray]
    contacts: tuple[Contact, ...] = ()


@dataclass(frozen=True)
class FigureSpec:
    """A figure of a scenario: one panel per group of columns, every series in each panel.

    Attributes:
        filename: file name in the output directory.
        title: figure title.
        panels: (y label, column names) per panel, drawn against the time.
    """

    filename: str
    title: str
    panels: tuple[tuple[str, tuple[str, ...]], ...]


@dataclass
class ScenarioResult:
    name: str
    series: list[Series]
    figures: list[FigureSpec]
    summary: list[str] = field(default_factory=list)


class StopStabilityWarning(RuntimeWarning):
    """The fixed RK4 step is unstable in contact with the joint stops (warned before the run)."""


@dataclass(frozen=True)
class StopSettings:
    """Joint stops of a scenario (:class:`~symkin.simulation.stops.JointStops`): contact time
    constant T_c [s], damping ratio zeta, and per-joint stiffness / damping overrides by name."""

    time_constant: float = TIME_CONSTANT
    damping_ratio: float = DAMPING_RATIO
    stiffness: dict[str, float] = field(default_factory=dict)
    damping: dict[str, float] = field(default_factory=dict)

    def build(self, plant: Plant, q: np.ndarray) -> JointStops | None:
        """The stops at the model's declared limits, defaults from M(q) (None: no limits declared)."""
        return JointStops.from_plant(plant, q, time_constant=self.time_constant, damping_ratio=self.damping_ratio,
                                     stiffness=self.stiffness, damping=self.damping)


@dataclass(frozen=True)
class Timing:
    """Duration [s], sample rate [Hz] and integrator of a run."""

    duration: float
    rate: float = 1000.0
    integrator: str = "rk4"
    substeps: int = 1

    @property
    def steps(self) -> int:
        return max(1, int(round(self.duration * self.rate)))


def run_loop(system: ArmSystem, control, x0: np.ndarray, timing: Timing) -> Run:
    """Run the loop with the chosen integrator (see :mod:`symkin.simulation.integrate`); the controller's
    command reaches the actuated joints only (:meth:`Plant.drive`), and the run records what they exert."""
    if system.plant.passive:
        control = _driven(system.plant, control)
    if timing.integrator == "rk4":
        return run_sampled(system.derivative, control, x0, 1.0 / timing.rate, timing.steps, timing.substeps)
    if timing.integrator == "dop853":
        modes = ContactModes(system.stops) if system.stops is not None else None
        return run_adaptive(system.derivative, control, x0, np.arange(timing.steps + 1) / timing.rate, modes=modes)
    raise ValueError(f"unknown integrator {timing.integrator!r}; use one of {', '.join(INTEGRATORS)}")


def _driven(plant: Plant, control):
    """``control`` as the actuators exert it: its command zeroed at the passive joints."""
    return lambda t, x: plant.drive(control(t, x))


def balance_drift(system: ArmSystem, run: Run, energy: np.ndarray | None = None) -> float:
    """max |(k + u - w)(t) - (k + u - w)(0)|, relative to the largest |k + u| met (or 1 J).

    ``energy``: k + u along the run, if the caller has it already.
    """
    s = system.split(run.x)
    energy = system.plant.energy(s.q, s.qd) if energy is None else energy
    b = system.balance(run.x, energy)
    scale = max(1.0, float(np.max(np.abs(energy))))
    return float(np.max(np.abs(b - b[0]))) / scale


def _system(plant: Plant, q: np.ndarray, stops: StopSettings | None, timing: Timing,
            user: MassSpringDamperUser | None = None) -> tuple[ArmSystem, Stability | None]:
    """The system with the stops built at q, and RK4's stability in contact (:func:`_stability`);
    warns (:class:`StopStabilityWarning`) before a fixed-step run that is unstable in contact."""
    system = ArmSystem(plant, user, stops.build(plant, q) if stops is not None else None)
    stability = _stability(system, timing, q)
    if stability is not None and not stability.stable:
        warnings.warn(StopStabilityWarning(
            f"{plant.name}: RK4 at h = {stability.step * 1e3:.4g} ms is unstable in contact with the joint stops "
            f"(omega_max h = {stability.omega_max * stability.step:.3g}, the limit is about 2.83); use --substeps "
            f"{stability.substeps_needed} or more, or a longer --stop-time-constant"), stacklevel=3)
    return system, stability


def _stability(system: ArmSystem, timing: Timing, q: np.ndarray):
    """RK4's stability in contact at q and the corners of the limits where the mechanism assembles (a
    parallel one's corners may not: its mass matrix is NaN there) (None: no stops, or not a fixed-step run)."""
    if system.stops is None or timing.integrator != "rk4":
        return None
    with np.errstate(invalid="ignore", divide="ignore"):
        masses = system.plant.mass_matrix(stop_configurations(system.stops, q))
    masses = masses[np.isfinite(masses).all(axis=(-2, -1))]
    return rk4_stability(system.stops, masses, 1.0 / timing.rate, timing.substeps)


@dataclass(frozen=True)
class StopReport:
    """The joint stops' part of a run: CSV columns, summary lines, contacts (all empty without stops)."""

    columns: dict[str, np.ndarray] = field(default_factory=dict)
    lines: list[str] = field(default_factory=list)
    contacts: tuple[Contact, ...] = ()


def stop_report(system: ArmSystem, run: Run, stability: Stability | None) -> StopReport:
    """Contacts, penetrations and energies of the stops; for RK4, its stability in contact
    (``stability`` from :func:`_system`; None for the event-located DOP853)."""
    stops = system.stops
    if stops is None:
        return StopReport()
    units = labels.joint_units(system.plant)
    found = contact_report.intervals(stops, run)
    lines = ["  " + line for line in stops.describe(units)]
    lines += contact_report.summary(system, run, found, units)
    if stability is not None:
        lines.append("  " + stability.describe())
    else:
        lines.append(f"  {len(run.switches)} stop contacts and releases located by events (DOP853 restarted at each)")
    return StopReport(contact_report.columns(system, run, units), lines, tuple(found))


def _peak(values: np.ndarray) -> float:
    return float(np.max(np.abs(values)))


def require_actuated(plant: Plant, scenario: str) -> None:
    """Refuse a scenario that prescribes every joint's motion on a plant with passive joints.

    Raises:
        ValueError: the plant has passive joints; the message names them and the scenarios that apply.
    """
    if plant.passive:
        raise ValueError(f"{plant.name}: the {scenario} scenario prescribes the motion of every joint, but "
                         f"{', '.join(plant.passive)} {'is' if len(plant.passive) == 1 else 'are'} passive (active: "
                         "false: no actuator holds it); simulate haptic-wall, gravity-compensation or free-swing")


def tcp_forces(J: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """F = J^-T tau (seed eq. 8.35) per sample (N, m); NaN where J is singular (kappa > 1e12).

    Raises:
        ValueError: the task Jacobian is not square (tau does not determine F).
    """
    if J.shape[-1] != J.shape[-2]:
        raise ValueError(f"TCP forces F = J^-T tau need a square task Jacobian, got {J.shape[-2]} x {J.shape[-1]}")
    force = np.full(tau.shape[:-1] + (J.shape[-2],), np.nan)
    regular = np.linalg.cond(J) < 1e12
    force[regular] = np.linalg.solve(np.swapaxes(J[regular], -1, -2), tau[regular][..., None])[..., 0]
    return force


def sine(designs: Sequence[tuple[str, Plant]], center: np.ndarray, joint: int, amplitude: float, frequency: float,
         timing: Timing, stops: StopSettings | None = None) -> ScenarioResult:
    """The seed's simplified haptic scenario for each design (Figs. 8.21, 8.22)."""
    series, summary = [], []
    plant0 = designs[0][1]
    require_actuated(plant0, "sine")
    names = plant0.coordinates
    positions, efforts = labels.joint_units(plant0)
    reference = JointSine(np.asarray(center, float), joint, amplitude, frequency)
    t = np.arange(timing.steps + 1) / timing.rate
    q, qd, qdd = reference(t)
    for label, plant in designs:
        tau = plant.torque(q, qd, qdd)
        force = tcp_forces(plant.task_jacobian(q), tau)
        system, stability = _system(plant, center, stops, timing)
        run = run_loop(system, ComputedTorque(system, reference), system.initial(q[0], qd[0]), timing)
        report = stop_report(system, run, stability)
        simulated = system.split(run.x)
        error = _peak(simulated.q - q)
        columns = {"t [s]": t}
        columns |= labels.named("", names, positions, q)
        columns |= labels.named("tau_", names, efforts, tau)
        columns |= {f"F_{c} [{unit}]": force[:, i] for i, (c, unit) in enumerate(labels.force_units(plant))}
        columns |= labels.named("simulated ", names, positions, simulated.q)
        columns |= labels.named("simulated tau_", names, efforts, run.u)
        series.append(Series(label, columns | report.columns, report.contacts))
        summary.append(f"{label}: peak torques {labels.peaks('tau_', names, efforts, tau)}; peak TCP forces "
                       + ", ".join(f"|F_{c}| <= {np.nanmax(np.abs(force[:, i])):.4g} {unit}"
                                   for i, (c, unit) in enumerate(labels.force_units(plant))))
        singular = int(np.sum(np.isnan(force[:, 0])))
        if singular:
            summary.append(f"  {singular} samples at a singular configuration: TCP forces undefined (NaN)")
        if labels.seed(plant, "8.21"):  # the seed's observation on its 2R arm
            above = bool(np.all(tau[:, 0] > tau[:, 1]))
            larger = _peak(tau[:, 0]) > _peak(tau[:, 1])
            summary.append(f"  tau_{names[0]} > tau_{names[1]} at every sample: {'yes' if above else 'no'}; peak "
                           f"|tau_{names[0]}| > peak |tau_{names[1]}|: {'yes' if larger else 'no'} (seed: the first "
                           "actuator carries the following links)")
        summary.append(f"  forward simulation under computed torque ({timing.integrator}): max joint error "
                       f"{error:.3g} {labels.label(positions)}, energy balance drift {balance_drift(system, run):.3g}")
        summary += declared_limit_lines(plant, tau, qd)
        summary += report.lines
    figures = [
        FigureSpec("fig-8-21-torques.png", f"Torques on the joints: {plant0.name}{labels.seed(plant0, '8.21')}",
                   tuple((f"tau_{n} [{u}]", (f"tau_{n} [{u}]",)) for n, u in zip(names, efforts))),
        FigureSpec("fig-8-22-tcp-forces.png",
                   f"Forces on the TCP (F = J^-T tau): {plant0.name}{labels.seed(plant0, '8.22')}",
                   tuple((f"F_{c} [{unit}]", (f"F_{c} [{unit}]",)) for c, unit in labels.force_units(plant0))),
        FigureSpec("sine-motion.png", "Prescribed and simulated joint motion",
                   tuple((f"{n} [{u}]", (f"{n} [{u}]", f"simulated {n} [{u}]")) for n, u in zip(names, positions))),
    ]
    return ScenarioResult("sine", series, figures, summary)


def tracking(label: str, plant: Plant, q_start: np.ndarray, radius: float, timing: Timing,
             bandwidth: float = 50.0, stops: StopSettings | None = None) -> ScenarioResult:
    """A TCP circle followed by computed-torque control (seed Fig. 8.17)."""
    require_actuated(plant, "tracking")
    reference = task_circle(plant, q_start, radius, timing.duration)
    system, stability = _system(plant, q_start, stops, timing)
    run = run_loop(system, ComputedTorque(system, reference, bandwidth), system.initial(q_start), timing)
    report = stop_report(system, run, stability)
    q_r = reference(run.t)[0]
    s = system.split(run.x)
    p_r, p = plant.point(q_r), plant.point(s.q)
    names = plant.coordinates
    positions, efforts = labels.joint_units(plant)
    columns = {"t [s]": run.t}
    columns |= labels.named("reference ", names, positions, q_r)
    columns |= labels.named("", names, positions, s.q)
    columns |= labels.named("tau_", names, efforts, run.u)
    columns |= labels.named("reference TCP ", plant.point_axes, "m", p_r)
    columns |= labels.named("TCP ", plant.point_axes, "m", p)
    columns["TCP error [m]"] = np.linalg.norm(p - p_r, axis=-1)
    summary = [f"{label}: TCP circle of radius {radius:g} m in {timing.duration:g} s, computed torque "
               f"(omega = {bandwidth:g} rad/s) at {timing.rate:g} Hz ({timing.integrator})",
               f"  max joint error {_peak(s.q - q_r):.3g} {labels.label(positions)}, max TCP error "
               f"{_peak(columns['TCP error [m]']):.3g} m",
               f"  peak torques {labels.peaks('tau_', names, efforts, run.u)}; energy balance drift "
               f"{balance_drift(system, run):.3g}"]
    summary += declared_limit_lines(plant, run.u, s.qd) + report.lines
    figures = [FigureSpec("tracking.png", f"Trajectory following (seed Fig. 8.17): {plant.name}", (
        ("TCP [m]", tuple(f"{prefix}TCP {c} [m]" for c in plant.point_axes for prefix in ("reference ", "")))
        , ("TCP error [m]", ("TCP error [m]",)),
        (f"torque [{labels.label(efforts)}]", tuple(f"tau_{n} [{u}]" for n, u in zip(names, efforts)))))]
    return ScenarioResult("tracking", [Series(label, columns | report.columns, report.contacts)], figures, summary)


def haptic_wall(label: str, plant: Plant, q_start: np.ndarray, wall_offset: float, push: float, timing: Timing, *,
                frequency: float = 1.0, stiffness: float = 1000.0, damping: float = 2.0, force_gain: float = 0.0,
                hand: dict[str, float] | None = None, stops: StopSettings | None = None) -> ScenarioResult:
    """A hand pushes the TCP into a virtual wall rendered in the loop (seed Fig. 8.18).

    The wall's normal is the first translational task axis; its surface lies ``wall_offset``
    beyond the start TCP position, and the hand intends to move ``push`` along the normal
    and back, sinusoidally at ``frequency``.  ``hand`` overrides parameters of
    :class:`~symkin.simulation.user.MassSpringDamperUser` (mass, arm_stiffness, ...).
    """
    q_start = np.asarray(q_start, dtype=float)
    p0 = plant.point(q_start)
    normal = np.zeros(len(p0))
    normal[0] = 1.0
    user = MassSpringDamperUser(sine_intent(p0, normal, push, frequency), **(hand or {}))
    wall = Wall(normal, float(p0 @ normal) + wall_offset, stiffness, damping)
    system, stability = _system(plant, q_start, stops, timing, user)
    renderer = WallRenderer(system, wall, force_gain)
    run = run_loop(system, renderer, system.initial(q_start), timing)
    report = stop_report(system, run, stability)
    s = system.split(run.x)
    p = plant.point(s.q)
    desired, sensed = renderer.desired_and_sensed(run.t, run.x)
    names, axes = plant.coordinates, plant.point_axes
    _, efforts = labels.joint_units(plant)
    m, N = plant.point_unit, plant.force_unit
    columns = {"t [s]": run.t}
    columns |= labels.named("TCP ", axes, m, p)
    columns |= labels.named("hand ", axes, m, s.held()[0])
    columns[f"penetration [{m}]"] = np.maximum(0.0, wall.penetration(p))
    columns |= labels.named("F_desired_", axes, N, desired)
    columns |= labels.named("F_felt_", axes, N, sensed)
    columns |= labels.named("tau_", names, efforts, run.u)
    summary = [f"{label}: wall at {axes[0]} = {wall.offset:.4g} {m} (k_w = {wall.stiffness:g} {N}/{m}, b_w = "
               f"{wall.damping:g} {N} s/{m}), hand pushing {push:g} {m} at {frequency:g} Hz, loop at {timing.rate:g} Hz "
               f"({timing.integrator}), force feedback K_f = {force_gain:g}",
               f"  peak penetration {_peak(columns[f'penetration [{m}]']):.3g} {m}, peak felt force "
               f"{_peak(sensed[:, 0]):.3g} {N} (desired {_peak(desired[:, 0]):.3g} {N}), max |F_desired - F_felt| "
               f"{_peak(desired - sensed):.3g} {N}",
               f"  peak torques {labels.peaks('tau_', names, efforts, run.u)}; energy balance drift "
               f"{balance_drift(system, run):.3g}"]
    summary += declared_limit_lines(plant, run.u, s.qd) + report.lines
    figures = [FigureSpec("haptic-wall.png", f"Haptic loop with a virtual wall (seed Fig. 8.18): {plant.name}", (
        (f"position [{m}]", (f"TCP {axes[0]} [{m}]", f"hand {axes[0]} [{m}]")),
        (f"penetration [{m}]", (f"penetration [{m}]",)),
        (f"force on the hand [{N}]", (f"F_desired_{axes[0]} [{N}]", f"F_felt_{axes[0]} [{N}]")),
        (f"torque [{labels.label(efforts)}]", tuple(f"tau_{n} [{u}]" for n, u in zip(names, efforts)))))]
    return ScenarioResult("haptic-wall", [Series(label, columns | report.columns, report.contacts)], figures,
                          summary)


def gravity_compensation(label: str, plant: Plant, q_start: np.ndarray, travel: float, timing: Timing, *,
                         frequency: float = 1.0, hand: dict[str, float] | None = None,
                         stops: StopSettings | None = None) -> ScenarioResult:
    """What a user feels of the device's weight: the hand moves the handle ``travel`` up and down
    along the last translational task axis (z, or y of a planar arm) at ``frequency``, once with the
    actuators holding tau = G(q) (gravity compensation, the generated ``gravity_vector``) and once
    with them off (tau = 0).  The force the hand exerts on the handle, F_h, is what the user feels:
    with compensation only the device's inertia, Coriolis and friction forces remain (its
    transparency); without, also its weight, J^-T G(q) at the TCP (seed eq. 8.35).
    """
    q_start = np.asarray(q_start, dtype=float)
    if not np.any(plant.gravity(q_start)):
        raise ValueError(f"{plant.name}: the model has no gravity (or no 'gravity_vector'): nothing to compensate")
    p0 = plant.point(q_start)
    axes = plant.point_axes
    vertical = np.zeros(len(p0))
    vertical[-1] = 1.0
    user = MassSpringDamperUser(sine_intent(p0, vertical, travel, frequency), **(hand or {}))
    zero = np.zeros(plant.dof)
    runs = (("gravity compensated (tau = G)", lambda t, x: plant.gravity(x[:plant.dof])),  # x = [q, qd, ...]
            ("actuators off (tau = 0)", lambda t, x: zero))
    series, lines, felt_peaks = [], [], []
    names = plant.coordinates
    _, efforts = labels.joint_units(plant)
    m, N = plant.point_unit, plant.force_unit
    for run_label, control in runs:
        system, stability = _system(plant, q_start, stops, timing, user)
        run = run_loop(system, control, system.initial(q_start), timing)
        report = stop_report(system, run, stability)
        s = system.split(run.x)
        p, _, v = system.tcp_motion(s.q, s.qd)
        hand_position, hand_velocity = s.held()
        felt = user.force_on_tcp(p, v, hand_position, hand_velocity)
        columns = {"t [s]": run.t}
        columns |= labels.named("TCP ", axes, m, p)
        columns |= labels.named("hand ", axes, m, hand_position)
        columns |= labels.named("F_hand_", axes, N, felt)
        columns |= labels.named("tau_", names, efforts, run.u)
        series.append(Series(run_label, columns | report.columns, report.contacts))
        felt_peaks.append(_peak(felt))
        lines += [f"  {run_label}: the hand pushes with up to {_peak(felt):.3g} {N} (mean "
                  f"{float(np.mean(felt[:, -1])):.3g} {N} along {axes[-1]}, rms "
                  f"{float(np.sqrt(np.mean(np.sum(felt ** 2, axis=-1)))):.3g} {N}); peak torques "
                  f"{labels.peaks('tau_', names, efforts, run.u)}; energy balance drift "
                  f"{balance_drift(system, run):.3g}"] + declared_limit_lines(plant, run.u, s.qd) + report.lines
    summary = [f"{label}: the hand moves the handle {travel:g} {m} along {axes[-1]} at {frequency:g} Hz, loop at "
               f"{timing.rate:g} Hz ({timing.integrator}); compensation cuts the peak force felt from "
               f"{felt_peaks[1]:.3g} {N} to {felt_peaks[0]:.3g} {N}"]
    J0 = plant.task_jacobian(q_start)
    if J0.shape[0] == J0.shape[1]:
        weight = tcp_forces(J0[None], plant.gravity(q_start)[None])[0][plant.point_rows]
        summary.append(f"  the device's weight at the handle at the start: J^-T G = ("
                       + ", ".join(f"{v:.4g}" for v in weight) + f") {N} along ({', '.join(axes)})")
    summary += lines
    figures = [FigureSpec("gravity-compensation.png", f"Gravity compensation, felt by a user's hand: {plant.name}", (
        (f"TCP {axes[-1]} [{m}]", (f"TCP {axes[-1]} [{m}]", f"hand {axes[-1]} [{m}]")),
        (f"force of the hand [{N}]", tuple(f"F_hand_{c} [{N}]" for c in axes)),
        (f"torque [{labels.label(efforts)}]", tuple(f"tau_{n} [{u}]" for n, u in zip(names, efforts)))))]
    return ScenarioResult("gravity-compensation", series, figures, summary)


def free_swing(label: str, plant: Plant, q_start: np.ndarray, timing: Timing,
               stops: StopSettings | None = None) -> ScenarioResult:
    """No torques, released at rest: the energy k + u is conserved without friction and stops
    (with stops: k + u + U + D, U stored in and D dissipated by them)."""
    system, stability = _system(plant, q_start, stops, timing)
    zero = np.zeros(plant.dof)
    run = run_loop(system, lambda t, x: zero, system.initial(q_start), timing)
    report = stop_report(system, run, stability)
    s = system.split(run.x)
    energy = plant.energy(s.q, s.qd)
    names = plant.coordinates
    positions, _ = labels.joint_units(plant)
    columns = {"t [s]": run.t}
    columns |= labels.named("", names, positions, s.q)
    columns["energy k + u [J]"] = energy
    columns["work of friction [J]"] = s.work
    balance = system.balance(run.x, energy)
    columns |= report.columns
    columns["balance drift [J]"] = balance - balance[0]
    summary = [f"{label}: free swing for {timing.duration:g} s ({timing.integrator}, {run.evaluations} evaluations)",
               f"  energy change {float(energy[-1] - energy[0]):.3g} J (friction work {float(s.work[-1]):.3g} J), "
               f"energy balance drift {balance_drift(system, run, energy):.3g}"] + report.lines
    stopped = tuple(c for c in report.columns if c.startswith("penetration "))
    panels: tuple[tuple[str, tuple[str, ...]], ...] = ((f"joint [{labels.label(positions)}]", tuple(f"{n} [{u}]" for n, u in zip(names, positions))),
              ("energy [J]", ("energy k + u [J]", "stop energy stored [J]", "stop energy dissipated [J]")))
    panels += ((f"penetration [{labels.label(positions)}]", stopped),) if stopped else ()
    figures = [FigureSpec("free-swing.png", f"Free swing: {plant.name}",
                          panels + (("balance drift [J]", ("balance drift [J]",)),))]
    return ScenarioResult("free-swing", [Series(label, columns, report.contacts)], figures, summary)
