"""``joint_stops:``: stops on affine combinations of the joint coordinates (:class:`~symkin.model.schema.JointStop`).

Written as a list, each stop an affine expression in the coordinates (and parameters) with its bounds::

    joint_stops:
      - {expression: "q3 - q2", limits: [deg(-65), deg(55)], doc: "the parallelogram's links meet"}

The expression is read as a coupling is (never evaluated as code); its coordinates are of one kind (angles or
lengths, the unit of the limits), lower < upper at the parameters' defaults, and a declared home configuration lies
within every stop.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import sympy

from symkin.errors import name_list
from symkin.model import joint_kinds
from symkin.model.reader import Reader, describe, position_limits
from symkin.model.schema import Coordinate, Joint, JointStop
from symkin.model.serial_build import read_affine
from symkin.model.yaml_source import KeyPath

#: The keys of one stop.
STOP_KEYS = ("expression", "limits", "doc")


def read_joint_stops(r: Reader, value: Any, coordinates: Sequence[Joint | Coordinate], home: Sequence[sympy.Expr] | None,
                     path: KeyPath = ("joint_stops",)) -> tuple[JointStop, ...]:
    """The stops at ``path`` over the model's ``coordinates`` (each with a ``name`` and a ``type``), checked against
    the ``home`` configuration where one is declared."""
    items = r.sequence(path, value, what="stops, each {expression: ..., limits: [lower, upper]}")
    if items is None:
        return ()
    symbols = {c.name: sympy.Dummy(c.name) for c in coordinates}
    turns = {c.name: joint_kinds.kind(c.type).rotations[0] for c in coordinates}     # an angle, not a length
    stops = []
    for i, item in enumerate(items):
        spath = path + (i,)
        spec = r.mapping(spath, item, required=("expression", "limits"), optional=("doc",))
        if spec is None or "expression" not in spec or "limits" not in spec:
            continue
        if not isinstance(spec["expression"], str):
            r.fail(spath + ("expression",), f"a stop's expression is text, got {describe(spec['expression'])}",
                   "write the combination in quotes, e.g. expression: \"q3 - q2\"")
            continue
        combination = read_affine(r, spath + ("expression",), spec["expression"], symbols,
                                  "a stop bounds a constant combination of coordinates, e.g. 'q3 - q2'",
                                  "it would bound nothing",
                                  f"name coordinates of the model: {name_list(list(symbols)) or '(none)'}")
        if combination is None:
            continue
        terms, offset = combination
        kinds = {turns[name] for name, _ in terms}
        if len(kinds) > 1:
            r.fail(spath + ("expression",), f"'{spec['expression']}' adds angles and lengths",
                   "bound revolute coordinates and prismatic ones in separate stops")
            continue
        bounds = position_limits(r, spath + ("limits",), spec["limits"], revolute=kinds == {True})
        if bounds is None:
            continue
        # the text as messages and the manifest show it: the parser took only names, numbers and operators,
        # and its whitespace is one space each (no line breaks into a summary)
        stop = JointStop(terms, offset, bounds[0], bounds[1], " ".join(spec["expression"].split()))
        if home is not None:
            _check_home(r, spath, stop, dict(zip(symbols, home)))
        stops.append(stop)
    return tuple(stops)


def _check_home(r: Reader, path: KeyPath, stop: JointStop, home: dict[str, sympy.Expr]) -> None:
    """The home configuration lies within the stop (at the parameters' defaults)."""
    value = r.default_value(sum((a * home[name] for name, a in stop.terms), stop.offset))
    low, high = r.default_value(stop.lower), r.default_value(stop.upper)
    if value is None or low is None or high is None:
        return
    if not low <= value <= high:
        r.fail(path, f"at the home configuration {stop.expression} = {value:g}, outside the stop [{low:g}, {high:g}]",
               "widen the stop or move the home configuration (serial.home) within it")
