"""A model's structure in one line, as ``symkin check`` prints it: joints (a parallel model's legs, actuators
and wrist), parameters, bodies and task space.

The model layer knows what kind of mechanism it built; the commands above it print this text instead of telling
kinds apart themselves (issue 62).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from symkin.model.schema import Model


def structure_summary(model: Model) -> str:
    """'N joints (a:R, b:P), ... parameters, ... bodies, task space [...]': the structure of ``model``."""
    return (f"{_joints(model)}, {len(model.parameters)} parameters, {_bodies(model)}, "
            f"task space [{', '.join(model.task_space)}]")


def _typed(joints: Iterable[Any]) -> str:
    """'a:R, b:P': joints (or coordinates) by name and type."""
    return ", ".join(f"{joint.name}:{joint.type.value}" for joint in joints)


def _joints(model: Model) -> str:
    """A serial model's joints (and its coordinates when couplings make them fewer); a parallel model's legs,
    actuated coordinates and the wrist on its platform."""
    if model.parallel is None:
        text = f"{len(model.joints)} joints ({_typed(model.joints)})"
        text = text if model.dof == len(model.joints) else f"{text}, {model.dof} coordinates"
        return text + _stops(model)
    legs = ", ".join(f"{leg.name}:{''.join(j.type.value for j in leg.joints)}" for leg in model.parallel.legs)
    text = (f"parallel, {len(model.parallel.legs)} legs ({legs}), {model.dof} actuated "
            f"({_typed(model.coordinates)})")
    wrist = model.parallel.wrist
    if wrist is None:
        return text + _stops(model)
    return f"{text}, a wrist of {len(wrist.joints)} joints on the platform ({_typed(wrist.joints)})" + _stops(model)


def _stops(model: Model) -> str:
    """', stops on q3 - q2': the combinations of coordinates the model stops (nothing without)."""
    if not model.joint_stops:
        return ""
    return f", stops on {', '.join(stop.expression for stop in model.joint_stops)}"


def _bodies(model: Model) -> str:
    """The bodies a model declares: a serial model's count; a parallel model's kinds (and its wrist's count)."""
    if model.parallel is None:
        return f"{len(model.bodies)} bodies"
    declared = model.parallel.bodies
    kinds = [] if declared is None else [name for name, present in (
        ("platform", declared.platform is not None), ("actuated links", declared.actuated_link is not None),
        ("rods", declared.rod_mass != 0), ("rotors", declared.rotor_inertia != 0)) if present]
    text = f"bodies: {', '.join(kinds)}" if kinds else "no bodies"
    wrist = model.parallel.wrist
    return text if wrist is None else f"{text} (+ {len(wrist.bodies)} on the wrist)"
