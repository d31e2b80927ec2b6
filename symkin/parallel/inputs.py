"""The vector inputs of parallel-mechanism functions besides ``q``.

Coordinates of a parallel mechanism (see ``docs/model-format.md``, "Coordinates"):

* ``q`` - the actuated joint variables, leg by leg (the generalized coordinates);
* ``p`` - the task coordinates of the platform (TCP): ``x, y, z`` for a translational
  platform, plus ``roll, pitch, yaw`` (R = Rz(yaw) Ry(pitch) Rx(roll)) for a full pose;
* ``s`` - the passive joint variables, leg by leg (only the loop-closure functions take them).
"""

from __future__ import annotations

import sympy

from symkin.ir.spec import InputSpec
from symkin.model.schema import Model

TASK_UNITS = {"x": "m", "y": "m", "z": "m", "roll": "rad", "pitch": "rad", "yaw": "rad"}


def task_symbols(model: Model) -> tuple[sympy.Symbol, ...]:
    """The symbols of the task coordinates p (named as the task-space components)."""
    return tuple(sympy.Symbol(name, real=True) for name in model.task_space)


def task_input(model: Model) -> InputSpec:
    """The input ``p``: the platform's task coordinates."""
    return InputSpec("p", "vector", task_symbols(model), model.task_space,
                     tuple(TASK_UNITS[c] for c in model.task_space), "task coordinates of the platform (TCP)")


def passive_variables(model: Model) -> tuple[tuple[str, bool], ...]:
    """(name, is_rotation) of every passive joint variable, leg by leg, joint by joint."""
    assert model.parallel is not None
    return tuple((variable, rotation) for leg in model.parallel.legs for joint in leg.joints
                 for k, (variable, _, rotation) in enumerate(joint.motions) if k != joint.active)


def passive_symbols(model: Model) -> tuple[sympy.Symbol, ...]:
    return tuple(sympy.Symbol(name, real=True) for name, _ in passive_variables(model))


def passive_input(model: Model) -> InputSpec:
    """The input ``s``: the passive joint variables."""
    variables = passive_variables(model)
    return InputSpec("s", "vector", passive_symbols(model), tuple(name for name, _ in variables),
                     tuple("rad" if rotation else "m" for _, rotation in variables), "passive joint variables")
