"""Units of model parameters: read, checked and converted exactly to SI (issue 60).

A parameter may state its unit (``{value: 60, unit: mm}``).  The unit is not decoration: a known unit's value is
converted to SI by an exact factor (a rational, or pi/180 for degrees), so the derivation stays exact and a model
written in mm, g and deg derives the same expressions as its SI twin; the parameter then carries the SI unit.
An unknown unit is refused with the file, the line and the closest known one.  SI units keep the text as written
(``kg*m^2`` or ``kg m^2``), so SI model files derive byte for byte as before.

Units are written with ``*`` or a space between factors, ``^`` or ``**`` for powers, ``/`` for one division:
``kg*m^2``, ``g cm^2``, ``N*m/A``, ``mN m/A``, ``rad/s``, ``N*m*s/rad``.
"""

from __future__ import annotations

import difflib
import re
from dataclasses import dataclass

import sympy

#: Dimensions, named as docs/model-format.md names them.
LENGTH, ANGLE, MASS, INERTIA, FORCE, TORQUE = "length", "angle", "mass", "inertia", "force", "torque"
TORQUE_CONSTANT, CURRENT, ANGULAR_SPEED, SPEED = "torque constant", "current", "angular speed", "speed"
ACCELERATION, ANGULAR_DAMPING, LINEAR_DAMPING, RATIO = "acceleration", "angular damping", "linear damping", "ratio"
STIFFNESS, ANGULAR_STIFFNESS, TIME = "stiffness", "angular stiffness", "time"


@dataclass(frozen=True)
class Unit:
    """A known unit: its SI counterpart, the exact factor to it (value_SI = value * factor) and its dimension."""

    si: str
    factor: sympy.Expr
    dimension: str


def _table() -> dict[str, Unit]:
    r = sympy.Rational
    rows = [
        # (units, SI unit, factors, dimension)
        ({"m": 1, "cm": r(1, 100), "mm": r(1, 1000), "um": r(1, 10**6), "in": r(254, 10**4)}, "m", LENGTH),
        ({"rad": 1, "deg": sympy.pi / 180}, "rad", ANGLE),
        ({"kg": 1, "g": r(1, 1000)}, "kg", MASS),
        ({"kg*m^2": 1, "g*cm^2": r(1, 10**7), "g*mm^2": r(1, 10**9), "kg*mm^2": r(1, 10**6), "kg*cm^2": r(1, 10**4)},
         "kg*m^2", INERTIA),
        ({"N": 1, "mN": r(1, 1000)}, "N", FORCE),
        ({"N*m": 1, "mN*m": r(1, 1000), "N*mm": r(1, 1000)}, "N*m", TORQUE),
        ({"N*m/A": 1, "mN*m/A": r(1, 1000)}, "N*m/A", TORQUE_CONSTANT),
        ({"A": 1, "mA": r(1, 1000)}, "A", CURRENT),
        ({"rad/s": 1, "deg/s": sympy.pi / 180, "rpm": sympy.pi / 30}, "rad/s", ANGULAR_SPEED),
        ({"m/s": 1, "mm/s": r(1, 1000)}, "m/s", SPEED),
        ({"m/s^2": 1, "mm/s^2": r(1, 1000)}, "m/s^2", ACCELERATION),
        ({"N*m*s/rad": 1, "N*m*s": 1, "mN*m*s/rad": r(1, 1000)}, "N*m*s/rad", ANGULAR_DAMPING),
        ({"N*s/m": 1, "N*s/mm": 1000}, "N*s/m", LINEAR_DAMPING),
        ({"N/m": 1, "N/mm": 1000}, "N/m", STIFFNESS),
        ({"N*m/rad": 1}, "N*m/rad", ANGULAR_STIFFNESS),
        ({"s": 1, "ms": r(1, 1000)}, "s", TIME),
        ({"1": 1}, "1", RATIO),
    ]
    return {name: Unit(si, sympy.sympify(factor), dimension) for units, si, dimension in rows
            for name, factor in units.items()}


UNITS: dict[str, Unit] = _table()
_SEPARATORS = re.compile(r"\s*[*·.]\s*|\s+")


def normalized(text: str) -> str:
    """A unit's text in the table's spelling: factors joined by ``*``, powers by ``^``, ``µm`` as ``um``."""
    text = text.strip().replace("**", "^").replace("²", "^2").replace("µ", "u").replace("μ", "u")
    parts = text.split("/")
    return "/".join(_SEPARATORS.sub("*", part.strip()) for part in parts)


def unit_of(text: str) -> Unit | None:
    """The known unit written ``text`` (None if unknown)."""
    return UNITS.get(normalized(text))


#: Words for units, for the suggestion only (a unit is written as a symbol).
_WORDS = {"meter": "m", "metre": "m", "millimeter": "mm", "millimetre": "mm", "centimeter": "cm", "centimetre": "cm",
          "inch": "in", "degree": "deg", "radian": "rad", "gram": "g", "kilogram": "kg", "newton": "N",
          "ampere": "A", "amp": "A", "second": "s"}


def suggestion(text: str) -> str:
    """A fix for the unknown unit ``text``: the closest known units, and the list by dimension."""
    word = normalized(text).lower().rstrip("s") if len(text) > 2 else ""
    words = difflib.get_close_matches(word, list(_WORDS), n=1, cutoff=0.75) if word else []
    near = [_WORDS[words[0]]] if words else difflib.get_close_matches(normalized(text), list(UNITS), n=2, cutoff=0.5)
    hint = f"did you mean {' or '.join(repr(n) for n in near)}? " if near else ""
    return (f"{hint}known units: " + "; ".join(
        f"{dimension}: {', '.join(n for n, u in UNITS.items() if u.dimension == dimension)}"
        for dimension in dict.fromkeys(u.dimension for u in UNITS.values())))
