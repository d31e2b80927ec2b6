"""Steps per second of the 1 kHz haptic loop, numpy against C, planar arm, UR10e and DELTA.

Run with `make bench` or `python benchmarks/bench_simulate.py [--seconds S]`.  One step is
one control period: the wall renderer (fk, task Jacobian, gravity vector) and one RK4 step
of the arm coupled to the mass-spring-damper hand (four forward-dynamics evaluations, each
with fk and the Jacobian for the hand's force).  A loop is real-time capable at 1 kHz when
it runs faster than 1000 steps/s.  Also: the torque-only computed-torque loop (one
inverse-dynamics call per step) and DOP853 evaluations/s for reference, and the same free
swing with the joint stops (DOP853 restarted at every located contact) and the cost of the stops
in the haptic loop (planar_2r only: the UR10e's +-2 pi limits are not met in 1 s).  The DELTA
runs in its actuated joints with the platform at fk(q) (symkin.simulation.plant); its free swing
is left out (without stops it falls until a leg stretches out).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import symkin  # noqa: E402
from symkin.text_table import format_table  # noqa: E402
from symkin.simulation import (ArmSystem, ComputedTorque, JointSine, MassSpringDamperUser, Plant, Wall,  # noqa: E402
                               WallRenderer, run_adaptive, run_sampled, sine_intent)
from symkin.simulation.scenarios import balance_drift  # noqa: E402
from symkin.simulation.stops import ContactModes, JointStops  # noqa: E402

STARTS = {"planar_2r": np.radians([45.0, 45.0]), "ur10e": np.array([0.3, -1.2, 1.4, -1.6, -1.5, 0.2]),
          "delta": np.radians([-15.0, -10.0, -20.0])}


def _loops(plant, q0: np.ndarray, stops: JointStops | None) -> dict[str, tuple]:
    """(system, controller, initial state) of the timed loops (with stops: the haptic loop again)."""
    p0 = plant.point(q0)
    normal = np.zeros(len(p0))
    normal[0] = 1.0
    user = MassSpringDamperUser(sine_intent(p0, normal, 0.02, 1.0))
    held = ArmSystem(plant, user)
    wall = WallRenderer(held, Wall(normal, float(p0[0]) + 0.005))
    free = ArmSystem(plant)
    tracking = ComputedTorque(free, JointSine(q0, plant.dof - 1, 0.3, 1.0))
    loops = {"haptic wall + hand, RK4 + ZOH": (held, wall, held.initial(q0)),
             "computed torque, RK4 + ZOH": (free, tracking, free.initial(q0, tracking.reference(0.0)[1]))}
    if stops is not None:
        stopped = ArmSystem(plant, user, stops)
        loops["haptic wall + hand + joint stops"] = (stopped, WallRenderer(stopped, wall.wall), stopped.initial(q0))
    return loops


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=1.0, help="simulated time per run (default: 1)")
    args = parser.parse_args(argv)
    steps = int(round(args.seconds * 1000))
    rows = []
    for name, q0 in STARTS.items():
        for backend in ("numpy", "c"):
            plant = Plant(symkin.load(ROOT / "generated" / name, backend))
            stops = JointStops.from_plant(plant, q0) if name == "planar_2r" else None
            for label, (system, control, x0) in _loops(plant, q0, stops).items():
                start = time.perf_counter()
                run = run_sampled(system.derivative, control, x0, 1e-3, steps)
                rate = steps / (time.perf_counter() - start)
                drift = balance_drift(system, run)
                rows.append([name, backend, label, f"{rate:,.0f}", f"{rate / 1000:.1f}x", f"{drift:.1e}"])
            if plant.parallel:
                continue
            system = ArmSystem(plant)
            zero = np.zeros(plant.dof)
            start = time.perf_counter()
            run = run_adaptive(system.derivative, lambda t, x: zero, system.initial(q0), np.linspace(0, args.seconds, 11))
            elapsed = time.perf_counter() - start
            rows.append([name, backend, "free swing, DOP853 rtol 1e-10", f"{run.evaluations / elapsed:,.0f} f/s",
                         f"{args.seconds / elapsed:.1f}x", f"{balance_drift(system, run):.1e}"])
            if stops is not None:
                system = ArmSystem(plant, stops=stops)
                start = time.perf_counter()
                run = run_adaptive(system.derivative, lambda t, x: zero, system.initial(q0),
                                   np.linspace(0, args.seconds, 11), modes=ContactModes(stops))
                elapsed = time.perf_counter() - start
                rows.append([name, backend, f"free swing onto the stops, DOP853 ({len(run.switches)} events)",
                             f"{run.evaluations / elapsed:,.0f} f/s", f"{args.seconds / elapsed:.1f}x",
                             f"{balance_drift(system, run):.1e}"])
    print(f"Loops at 1 kHz over {args.seconds:g} s of simulated time: control periods per second of wall time "
          "(real time = steps/s / 1000; DOP853: right-hand-side evaluations per second)")
    print(format_table(["model", "backend", "loop", "steps/s", "real time", "energy balance drift"], rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
