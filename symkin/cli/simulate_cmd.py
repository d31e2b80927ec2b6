"""``symkin simulate``: forward dynamics of a serial model or a parallel mechanism with a closed-form fk in a scenario (seed sec. 5)."""

from __future__ import annotations

import argparse
import math
import sys
import time
import warnings
from pathlib import Path

from symkin.analysis.needs import NEEDS
from symkin.cli import analysis_args
from symkin.analysis import model_files
from symkin.cli.progress import Progress

#: What a model file is also derived with where the model has it (NEEDS["simulate"] always): gravity, friction,
#: a hybrid device's TCP (device_fk, device_actuator_jacobian) where it has a wrist, the closure's dynamics.
OPTIONAL_OUTPUTS = ("gravity_vector", "potential_energy", "friction", "device_fk", "device_actuator_jacobian",
                    "closure_dynamics")
SCENARIOS = ("sine", "tracking", "haptic-wall", "gravity-compensation", "free-swing")
#: the integrator each scenario uses unless --integrator says otherwise
DEFAULT_INTEGRATOR = {"sine": "dop853", "tracking": "rk4", "haptic-wall": "rk4", "gravity-compensation": "rk4",
                      "free-swing": "dop853"}


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "simulate", help="simulate the dynamics: seed haptic scenario, trajectory following, virtual wall",
        description="Integrate the forward dynamics of a serial model, or of a parallel mechanism with a closed-form "
                    "fk (a DELTA, a pantograph, the Agile Eye: in its actuated joints, the platform at fk(q); a DELTA carrying a "
                    "wrist: in the legs' and the "
                    "wrist's joints, the TCP the wrist's; legs without closed forms with bodies: in the actuated "
                    "joints, the dynamics reduced through the loop closure, the assembly solved step by step from the "
                    "home assembly), with its generated functions. Scenarios: "
                    "'sine' (seed sec. 5.3, Figs. 8.21, 8.22: one joint follows a sine, the others are fixed; joint "
                    "torques and TCP forces F = J^-T tau, checked by a forward simulation), 'tracking' (Fig. 8.17: a "
                    "TCP circle through inverse kinematics and computed-torque control), 'haptic-wall' (Fig. 8.18: a "
                    "mass-spring-damper hand pushes into a virtual wall rendered in a 1 kHz loop), 'gravity-compensation' (the "
                    "hand moves the handle up and down, --push along the last task axis, with the actuators holding "
                    "tau = G(q) and with them off: the force the user feels), 'free-swing' (no "
                    "torques; energy conserved without friction). Joints stop at their declared limits (a stiff "
                    "spring-damper, --joint-stops); contacts are reported and shaded in the figures. Writes CSV per run, summary.txt and figures into "
                    "the output directory (replaced as a whole).",
        epilog="Seed Figs. 8.21/8.22: symkin simulate generated/planar_2r --scenario sine --design l1=0.1,l2=0.1 "
               "--design l1=0.2,l2=0.2 -o out/figures/seed-haptic-scenario")
    p.add_argument("model", metavar="MODEL",
                   help="generated model directory (from 'symkin derive', e.g. generated/planar_2r) or a model file "
                        "(YAML; the dynamics are derived on the fly)")
    p.add_argument("--scenario", choices=SCENARIOS, default="sine", help="what to simulate (default: %(default)s)")
    p.add_argument("--backend", default="numpy", metavar="NAME", help="generated code to evaluate: numpy, c, casadi "
                                                                      "(default: %(default)s)")
    p.add_argument("--set", dest="assignments", action="append", default=[], metavar="NAME=VALUE[,...]",
                   help="parameter values instead of the defaults, e.g. --set m2=0.2 (repeatable)")
    p.add_argument("--design", action="append", default=[], metavar="NAME=VALUE[,...]",
                   help="a design (parameter values on top of --set); 'sine' compares several, the other scenarios "
                        "use the first; repeatable")
    p.add_argument("--q0", nargs="+", metavar="Q", default=None,
                   help="start (sine: centre) configuration, rad or m; append 'deg' for degrees, e.g. 45deg "
                        "(default: the middle of the joint limits, 0 for unlimited joints, if the task "
                        "Jacobian is well conditioned there, else the best-conditioned of 256 poses within the "
                        "limits; the output says which)")
    p.add_argument("--duration", type=float, default=2.0, metavar="S", help="simulated time [s] (default: 2)")
    p.add_argument("--rate", type=float, default=1000.0, metavar="HZ",
                   help="control and sample rate [Hz] (default: 1000, the haptic loop)")
    p.add_argument("--integrator", choices=("rk4", "dop853"),
                   help="rk4: fixed step under a sampled (zero-order hold) controller; dop853: adaptive, "
                        "continuous control (default: dop853 for sine and free-swing, rk4 otherwise)")
    p.add_argument("--substeps", type=int, default=1, metavar="K", help="rk4 steps per sample (default: 1)")
    p.add_argument("--joint", metavar="NAME", help="sine: the moving joint (default: the last)")
    p.add_argument("--amplitude", default="30deg", metavar="A",
                   help="sine: amplitude, rad or m, or with 'deg' (default: %(default)s)")
    p.add_argument("--frequency", type=float, default=1.0, metavar="HZ",
                   help="sine: frequency; haptic-wall, gravity-compensation: frequency of the hand's motion "
                        "(default: 1)")
    p.add_argument("--radius", type=float, default=0.02, metavar="M", help="tracking: circle radius (default: 0.02)")
    p.add_argument("--bandwidth", type=float, default=50.0, metavar="RAD_S",
                   help="computed torque: omega of the error dynamics (default: 50)")
    p.add_argument("--wall", type=float, metavar="M",
                   help="haptic-wall: distance of the wall from the start TCP along the first task axis "
                        "(default: 0.01 m; a handle that only turns: 0.1 rad along its first angle)")
    p.add_argument("--push", type=float, metavar="M",
                   help="haptic-wall: how far the hand intends to move towards the wall; gravity-compensation: its "
                        "travel up and down (default: 0.02 m; a turning handle: 0.2 rad)")
    p.add_argument("--wall-stiffness", type=float, metavar="N_M",
                   help="k_w (default: 1000 N/m; a turning handle: 2 N m/rad)")
    p.add_argument("--wall-damping", type=float, metavar="NS_M",
                   help="b_w (default: 2 N s/m; a turning handle: 0.01 N m s/rad)")
    p.add_argument("--force-gain", type=float, default=0.0, metavar="K",
                   help="haptic-wall: force feedback gain K_f (default: 0, open-loop impedance rendering)")
    p.add_argument("--hand", action="append", default=[], metavar="NAME=VALUE[,...]",
                   help="haptic-wall, gravity-compensation: user model, of mass, arm_stiffness, arm_damping, "
                        "grip_stiffness, grip_damping (default: 0.2 kg, 200 N/m, 5 N s/m, 2000 N/m, 10 N s/m; a "
                        "handle that only turns, held by its angles: 1e-3 kg m^2, 1.5 N m/rad, 0.03 N m s/rad, "
                        "15 N m/rad, 0.1 N m s/rad)")
    p.add_argument("--joint-stops", choices=("on", "off"),
                   help="mechanical stops at the declared joint limits: a linear spring-damper beyond each limit "
                        "(default: on when the model declares limits)")
    p.add_argument("--stop-time-constant", type=float, metavar="S",
                   help="stops: contact time constant T_c = 1/omega_n; k_i = m_i / T_c^2 with m_i = 1/(M^-1)_ii at the "
                        "start configuration (default: 0.003)")
    p.add_argument("--stop-damping-ratio", type=float, metavar="ZETA",
                   help="stops: damping ratio, c_i = 2 zeta m_i / T_c; restitution exp(-zeta pi / sqrt(1 - "
                        "zeta^2)) (default: 0.5)")
    p.add_argument("--stop-stiffness", action="append", default=[], metavar="JOINT=K[,...]",
                   help="stops: stiffness of a joint's stops [N m/rad or N/m] instead of the default, or of a "
                        "stop on a combination of joints by its expression (\"q3 - q2=K\") (repeatable)")
    p.add_argument("--stop-damping", action="append", default=[], metavar="JOINT=C[,...]",
                   help="stops: damping of a joint's stops [N m s/rad or N s/m] instead of the default (repeatable)")
    p.add_argument("-o", "--out", metavar="DIR", help="output directory (default: out/simulation/MODEL-SCENARIO)")
    p.add_argument("--no-figure", action="store_true", help="write CSV and summary only")
    p.set_defaults(run=run, parser=p)


def _number(option: str, text: str) -> float:
    try:
        return analysis_args.parse_value(text)
    except ValueError:
        raise ValueError(f"{option}: '{text}' is not a number (rad or m, or degrees with 'deg')") from None


def _start(args: argparse.Namespace, plant) -> tuple[list[float], str]:
    """(q0, how it was chosen): --q0, else :func:`symkin.simulation.start.start_pose`."""
    if args.q0 is not None:
        values = [_number("--q0", v) for v in args.q0]
        if len(values) != plant.dof:
            raise ValueError(f"--q0: {plant.name} has {plant.dof} joints ({' '.join(plant.coordinates)}), "
                             f"got {len(values)} values")
        return values, "--q0"
    from symkin.simulation.start import start_pose

    q0, reason = start_pose(plant)
    return q0.tolist(), reason


def _stops(args: argparse.Namespace, plant, q0):
    """The StopSettings of the arguments (None: stops off), checked by building them at q0.

    Raises:
        ValueError: stops asked for on a model without limits, stop parameters with the stops
            off, or a bad parameter.
    """
    from symkin.simulation.scenarios import StopSettings

    limited = any(math.isfinite(v) for bounds in plant.joint_limits for v in bounds)
    tuning = [name for name, given in (("--stop-time-constant", args.stop_time_constant is not None),
                                       ("--stop-damping-ratio", args.stop_damping_ratio is not None),
                                       ("--stop-stiffness", bool(args.stop_stiffness)),
                                       ("--stop-damping", bool(args.stop_damping))) if given]
    if args.joint_stops == "on" and not limited:
        raise ValueError(f"--joint-stops on: {plant.name} declares no joint limits (declare them in the model file)")
    if args.joint_stops == "off" or not limited:
        if tuning:
            raise ValueError(f"{', '.join(tuning)}: the joint stops are off"
                             + ("" if limited else f" ({plant.name} declares no joint limits)"))
        return None
    settings = StopSettings(**{k: v for k, v in (("time_constant", args.stop_time_constant),
                                                  ("damping_ratio", args.stop_damping_ratio)) if v is not None},
                            stiffness=analysis_args.parse_assignments(args.stop_stiffness),
                            damping=analysis_args.parse_assignments(args.stop_damping))
    settings.build(plant, q0)
    return settings


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from symkin.atomic import replace_directory
    from symkin.simulation import Plant, SimulationError, scenarios, user
    from symkin.simulation.output import scenario_files

    try:
        base = model_files.generated_model(args.model, args.backend, NEEDS["simulate"], OPTIONAL_OUTPUTS,
                                           display=Progress)
        if args.backend == "jax":  # the same figures, but no batch for JAX to fuse: each step's calls are dispatches
            print(f"{base.name}: --backend jax: a simulation evaluates one state per call, and each call of the JAX code "
                  "costs a dispatch; --backend c or numpy run it faster", flush=True)
        values = analysis_args.parse_assignments(args.assignments)
        if values:
            base = base.bind(**values)
        designs = [analysis_args.parse_assignments([text]) for text in args.design] or [{}]
        plants = [(analysis_args.design_label(base, d, "cm"), Plant(base.bind(**d) if d else base)) for d in designs]
        plant = plants[0][1]
        start_pose, start_reason = _start(args, plant)
        q0 = np.array(start_pose)
        haptic = user.TURNING if plant.turning else user.TRANSLATING
        hand = {**haptic.hand, **analysis_args.parse_assignments(args.hand)}
        unknown = set(hand) - {"mass", "arm_stiffness", "arm_damping", "grip_stiffness", "grip_damping"}
        if unknown:
            raise ValueError(f"--hand: unknown user parameters {sorted(unknown)}; use mass, arm_stiffness, "
                             "arm_damping, grip_stiffness, grip_damping")
        if not (args.rate > 0 and args.duration > 0 and args.substeps >= 1):
            raise ValueError("--rate and --duration must be positive and --substeps at least 1")
        joint = plant.dof - 1 if args.joint is None else plant.coordinates.index(args.joint) \
            if args.joint in plant.coordinates else None
        if joint is None:
            raise ValueError(f"--joint: {plant.name} has no joint '{args.joint}'; use one of "
                             f"{', '.join(plant.coordinates)}")
        amplitude = _number("--amplitude", args.amplitude)
        stops = _stops(args, plant, q0)
    except (ValueError, KeyError) as err:
        analysis_args.fail_on_bad_input(args, err)
    timing = scenarios.Timing(args.duration, args.rate, args.integrator or DEFAULT_INTEGRATOR[args.scenario],
                              args.substeps)
    label, _ = plants[0]
    start = time.perf_counter()
    with Progress(base.name) as progress, warnings.catch_warnings():
        warnings.simplefilter("always", scenarios.StopStabilityWarning)
        shown = warnings.showwarning
        warnings.showwarning = lambda message, category, *rest: (
            print(f"symkin simulate: warning: {message}", file=sys.stderr)
            if issubclass(category, scenarios.StopStabilityWarning) else shown(message, category, *rest))
        progress(f"simulating {args.scenario}")
        try:
            if args.scenario == "sine":
                result = scenarios.sine(plants, q0, joint, amplitude, args.frequency, timing, stops)
            elif args.scenario == "tracking":
                result = scenarios.tracking(label, plant, q0, args.radius, timing, args.bandwidth, stops)
            elif args.scenario == "haptic-wall":
                result = scenarios.haptic_wall(label, plant, q0, _or(args.wall, haptic.wall),
                                               _or(args.push, haptic.push), timing, frequency=args.frequency,
                                               stiffness=_or(args.wall_stiffness, haptic.wall_stiffness),
                                               damping=_or(args.wall_damping, haptic.wall_damping),
                                               force_gain=args.force_gain, hand=hand,
                                               stops=stops)
            elif args.scenario == "gravity-compensation":
                result = scenarios.gravity_compensation(label, plant, q0, _or(args.push, haptic.push), timing,
                                                        frequency=args.frequency, hand=hand, stops=stops)
            else:
                result = scenarios.free_swing(label, plant, q0, timing, stops)
        except SimulationError as err:
            print(f"symkin simulate: {err}")
            return 1
        except ValueError as err:  # the scenario does not apply to the model
            analysis_args.fail_on_bad_input(args, err)
        progress("writing")
        out = args.out or f"out/simulation/{base.name}-{args.scenario}"
        files = scenario_files(base.name, result, figures=not args.no_figure)
        replace_directory(Path(out), files)
    print(f"{base.name} ({args.backend}): {args.scenario}, {timing.duration:g} s at {timing.rate:g} Hz")
    print(f"  start: q0 = [{', '.join(f'{v:.4g}' for v in q0)}], {start_reason}")
    for line in result.summary:
        print(f"  {line}")
    print(f"wrote {len(files)} files to {out}/ ({', '.join(sorted(files))}) in {time.perf_counter() - start:.2f} s")
    return 0


def _or(value: float | None, default: float) -> float:
    """An option's value, or the default of the handle's kind where it was not given."""
    return default if value is None else value
