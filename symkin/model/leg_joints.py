"""Joints of parallel legs, shared by the leg-by-leg form (:mod:`symkin.model.parallel_build`)
and the DELTA shorthand (:mod:`symkin.model.delta`): their variable names and position limits."""

from __future__ import annotations

from typing import Any

import sympy

from symkin.model import joint_kinds
from symkin.model.reader import Reader, position_limits
from symkin.model.schema import LegJointType
from symkin.model.yaml_source import KeyPath


def variable_names(name: str, jtype: LegJointType) -> tuple[str, ...]:
    """Coordinate names of a leg joint's motions: ``name`` (R, P), ``name_1``... (U, S), ``name_t``, ``name_r`` (C)."""
    return joint_kinds.kind(jtype).variables(name)


def leg_joint_limits(r: Reader, path: KeyPath, value: Any,
                     jtype: LegJointType) -> tuple[tuple[sympy.Expr, sympy.Expr] | None, ...] | None:
    """Position limits of a leg joint: ``[lower, upper]`` (R, P) or one pair per motion (U, S, C).

    A motion of a multi-DoF joint may be left free with ``null``; None when invalid.
    """
    if jtype.dof == 1:
        bounds = position_limits(r, path, value)
        return None if bounds is None else (bounds,)
    items = r.sequence(path, value, jtype.dof, f"limits, one [lower, upper] (or null) per motion of the "
                                               f"{jtype.value} joint")
    if items is None:
        return None
    limits = tuple(None if item is None else position_limits(r, path + (k,), item) for k, item in enumerate(items))
    return None if any(b is None and item is not None for b, item in zip(limits, items)) else limits
