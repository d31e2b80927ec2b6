"""Joints of parallel legs, shared by the leg-by-leg form (:mod:`symkin.model.parallel_build`)
and the DELTA shorthand (:mod:`symkin.model.delta`): their variable names and position limits, and the start
values a model declares for them at its home pose (``parallel.home_assembly``)."""

from __future__ import annotations

import difflib
from typing import Any

import sympy

from symkin.errors import name_list
from symkin.model import joint_kinds
from symkin.model.reader import Reader, describe, position_limits
from symkin.model.schema import Leg, LegJointType
from symkin.model.units import ANGLE, LENGTH
from symkin.model.yaml_source import KeyPath


def variable_names(name: str, jtype: LegJointType) -> tuple[str, ...]:
    """Coordinate names of a leg joint's motions: ``name`` (R, P), ``name_1``... (U, S), ``name_t``, ``name_r`` (C)."""
    return joint_kinds.kind(jtype).variables(name)


def leg_joint_limits(r: Reader, path: KeyPath, value: Any,
                     jtype: LegJointType) -> tuple[tuple[sympy.Expr, sympy.Expr] | None, ...] | None:
    """Position limits of a leg joint: ``[lower, upper]`` (R, P) or one pair per motion (U, S, C).

    A motion of a multi-DoF joint may be left free with ``null``; None when invalid.
    """
    rotations = joint_kinds.kind(jtype).rotations
    if jtype.dof == 1:
        bounds = position_limits(r, path, value, rotations[0])
        return None if bounds is None else (bounds,)
    items = r.sequence(path, value, jtype.dof, f"limits, one [lower, upper] (or null) per motion of the "
                                               f"{jtype.value} joint")
    if items is None:
        return None
    limits = tuple(None if item is None else position_limits(r, path + (k,), item, rotations[k])
                   for k, item in enumerate(items))
    return None if any(b is None and item is not None for b, item in zip(limits, items)) else limits


def read_home_assembly(r: Reader, path: KeyPath, section: dict[str, Any], legs: tuple[Leg, ...]
                       ) -> tuple[tuple[str, sympy.Expr], ...] | None:
    """``home_assembly: {variable: value}``: where Gauss-Newton starts the legs' joint variables (active or passive,
    named as in the closure's q and s) to close them at ``home``; the assembly it reaches is the home assembly of
    the analyses that continue the closure.  Unnamed variables start at 0."""
    apath = path + ("home_assembly",)
    if "home_assembly" not in section:
        return None
    if "home" not in section:
        r.fail(apath, "a home assembly needs the home pose it closes at", "add parallel.home: [...] (task coordinates)")
    value = section["home_assembly"]
    if not isinstance(value, dict):
        r.fail(apath, f"expected a mapping of leg joint variables to values, got {describe(value)}",
               "write e.g. home_assembly: {knee1: deg(-60), knee2: deg(-60)}")
        return None
    kinds = {variable: rotation for leg in legs for joint in leg.joints for variable, _, rotation in joint.motions}
    out = []
    for name, item in value.items():
        if name not in kinds:
            close = difflib.get_close_matches(str(name), list(kinds), n=1)
            hint = f"did you mean '{close[0]}'? " if close else ""
            r.fail(apath + (name,), f"no leg joint variable named {describe(name)}",
                   f"{hint}name the legs' joint variables (a U joint's are <name>_1, <name>_2): "
                   f"{name_list(list(kinds))}")
            continue
        expr = r.expr(apath + (name,), item, dimension=ANGLE if kinds[name] else LENGTH)
        if expr is not None:
            out.append((str(name), expr))
    return tuple(out)
