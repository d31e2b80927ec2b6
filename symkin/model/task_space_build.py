"""The ``task_space:`` of a serial chain: the TCP coordinates its Jacobian and IK work in."""

from __future__ import annotations

from typing import Any

from symkin.model.reader import Reader, describe
from symkin.model.yaml_source import KeyPath

TASK_COMPONENTS = ("x", "y", "z", "roll", "pitch", "yaw", "wx", "wy", "wz")
TASK_SHORTHANDS = {"pose": ("x", "y", "z", "wx", "wy", "wz"), "position": ("x", "y", "z")}


def read_task_space(r: Reader, value: Any) -> tuple[str, ...]:
    path: KeyPath = ("task_space",)
    if isinstance(value, str):
        if value in TASK_SHORTHANDS:
            return TASK_SHORTHANDS[value]
        r.fail(path, f"unknown task space '{value}'",
               f"use 'pose', 'position' or a list of components from {', '.join(TASK_COMPONENTS)}")
        return ()
    items = r.sequence(path, value, what="task-space components")
    if items is None:
        return ()
    out: list[str] = []
    for i, item in enumerate(items):
        if item not in TASK_COMPONENTS:
            r.fail(path + (i,), f"unknown task-space component {describe(item)}",
                   f"use components from {', '.join(TASK_COMPONENTS)}")
        elif item in out:
            r.fail(path + (i,), f"task-space component '{item}' appears twice", "list each component once")
        else:
            out.append(item)
    if not items:
        r.fail(path, "the task space is empty", "list at least one component, e.g. [x, y]")
    return tuple(out)
