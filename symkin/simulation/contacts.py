"""What the joint stops did in a run: contact intervals, time in contact, penetration, energy.

Contact intervals come from the located mode switches of an adaptive run (exact instants,
:class:`~symkin.simulation.stops.ContactModes`), or, for a fixed-step run, from the sampled
penetrations, the crossing instant interpolated linearly between the two samples around it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from symkin.simulation.integrate import Run
from symkin.simulation.stops import JointStops
from symkin.simulation.system import ArmSystem

SIDES = {-1: "lower", 1: "upper"}


@dataclass(frozen=True)
class Contact:
    """Joint ``joint`` (name) was beyond its ``side`` ("lower" or "upper") limit from ``start`` to ``end`` [s]."""

    joint: str
    side: str
    start: float
    end: float


def intervals(stops: JointStops, run: Run) -> list[Contact]:
    """The contacts of ``run`` in time order (a contact still open at the end ends there)."""
    if run.switches:
        return _from_switches(stops, run)
    t = run.t
    penetration = dict(zip((-1, 1), stops.penetration(run.x[:, :stops.dof])))
    found = []
    for j, name in enumerate(stops.names):
        for side, label in SIDES.items():
            d = penetration[side][:, j]
            if not np.isfinite(d).all():
                continue
            inside = d > 0.0
            edges = np.flatnonzero(np.diff(inside.astype(int)))
            # crossing of d = 0 between samples k and k + 1, linearly interpolated
            crossings = [t[k] + (t[k + 1] - t[k]) * d[k] / (d[k] - d[k + 1]) for k in edges]
            marks = ([t[0]] if inside[0] else []) + crossings + ([t[-1]] if inside[-1] else [])
            found += [Contact(name, label, float(a), float(b)) for a, b in zip(marks[::2], marks[1::2])]
    return sorted(found, key=lambda c: c.start)


def _from_switches(stops: JointStops, run: Run) -> list[Contact]:
    q0 = run.x[0, :stops.dof]
    open_ = {(j, int(s)): float(run.t[0]) for j, s in enumerate(stops.contact(q0)) if s}
    found = []
    for switch in run.switches:
        g = switch.guard
        key = (g.joint, g.side)
        if g.entering:
            open_[key] = switch.t
        elif key in open_:
            found.append(Contact(stops.names[g.joint], SIDES[g.side], open_.pop(key), switch.t))
    found += [Contact(stops.names[j], SIDES[s], start, float(run.t[-1])) for (j, s), start in open_.items()]
    return sorted(found, key=lambda c: c.start)


def _stopped(system: ArmSystem) -> JointStops:
    """The system's joint stops: the contact reports are made only for a system that has them."""
    if system.stops is None:
        raise ValueError("the system has no joint stops to report on")
    return system.stops


def _dissipated(dissipated: np.ndarray | None) -> np.ndarray:
    """The stops' dissipated energy of split states (present wherever the system has stops)."""
    if dissipated is None:
        raise ValueError("the states carry no dissipated energy: the system has no joint stops")
    return dissipated


def columns(system: ArmSystem, run: Run, units: tuple[Sequence[str], Sequence[str]]) -> dict[str, np.ndarray]:
    """Per-sample columns: penetration per stop and stop torque per stopped joint, stored and dissipated energy."""
    stops = _stopped(system)
    s = system.split(run.x)
    depth = stops.depth(s.q)
    tau, _ = stops.torque_and_dissipation(s.q, s.qd)
    positions = stops.stop_units(units)[0]
    out = {}
    for j, name in enumerate(stops.names):
        if stops.stiffness[j] > 0.0:
            out[f"penetration {name} [{positions[j]}]"] = depth[:, j]
            if j < stops.dof:
                out[f"tau_stop_{name} [{units[1][j]}]"] = tau[:, j]
    out["stop energy stored [J]"] = stops.stored_energy(s.q)
    out["stop energy dissipated [J]"] = _dissipated(s.dissipated)
    return out


def summary(system: ArmSystem, run: Run, contacts: list[Contact], units: tuple[Sequence[str], Sequence[str]]
            ) -> list[str]:
    """Lines: per stop the number of contacts, time in contact and peak penetration."""
    stops = _stopped(system)
    depth = stops.depth(system.split(run.x).q)
    positions = stops.stop_units(units)[0]
    lines, free = [], []
    for j, name in enumerate(stops.names):
        if stops.stiffness[j] <= 0.0:
            continue
        mine = [c for c in contacts if c.joint == name]
        if not mine:
            free.append(name)
            continue
        parts = [f"{sum(c.side == side for c in mine)} x {side} {sum(c.end - c.start for c in mine if c.side == side):.4g} s"
                 for side in SIDES.values() if any(c.side == side for c in mine)]
        lines.append(f"  {name}: in contact {', '.join(parts)}; max penetration {np.max(depth[:, j]):.3g} "
                     f"{positions[j]} (at the samples)")
    if free:
        lines.append(f"  {', '.join(free)}: no contact with {'its' if len(free) == 1 else 'their'} stops")
    s = system.split(run.x[-1])
    lines.append(f"  stops: {float(stops.stored_energy(s.q)):.3g} J stored at the end, {float(_dissipated(s.dissipated)):.3g} J "
                 "dissipated")
    return lines
