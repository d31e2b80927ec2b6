"""Generalized-coordinate symbols of a model and the input groups of generated functions.

The coordinates are a serial chain's joints or a parallel mechanism's actuated joint
variables (:attr:`symkin.model.schema.Model.coordinates`).  Every coordinate ``j`` owns four symbols: its coordinate ``j`` (in ``q``), velocity ``j_d``
(in ``qd``), acceleration ``j_dd`` (in ``qdd``) and actuator effort ``tau_j`` (in
``tau``).  Symbols are created on demand: sympy symbols with equal name and assumptions
are equal, so every module sees the same symbols without sharing state.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import sympy

from symkin.errors import ModelError
from symkin.model import joint_kinds
from symkin.model.schema import Coordinate, Joint, Model


@dataclass(frozen=True)
class GroupDef:
    """How one coordinate group names its symbols and what units they have."""

    name: str
    doc: str
    prefix: str
    suffix: str
    revolute_unit: str
    prismatic_unit: str


GROUPS: dict[str, GroupDef] = {
    "q": GroupDef("q", "joint coordinates", "", "", "rad", "m"),
    "qd": GroupDef("qd", "joint velocities", "", "_d", "rad/s", "m/s"),
    "qdd": GroupDef("qdd", "joint accelerations", "", "_dd", "rad/s^2", "m/s^2"),
    "tau": GroupDef("tau", "joint torques (revolute) or forces (prismatic)", "tau_", "", "N*m", "N"),
}


def symbol_name(group: str, joint_name: str) -> str:
    """Name of the symbol of ``joint_name`` in ``group`` (e.g. ``theta1_d``)."""
    g = GROUPS[group]
    return f"{g.prefix}{joint_name}{g.suffix}"


def symbols(model: Model, group: str) -> tuple[sympy.Symbol, ...]:
    """The symbols of one coordinate group, in joint order."""
    return symbols_of(model.coordinates, group)


def symbols_of(joints: Sequence[Joint | Coordinate], group: str) -> tuple[sympy.Symbol, ...]:
    """The symbols of one coordinate group of ``joints`` (a model's coordinates, a hybrid device's wrist's)."""
    return tuple(sympy.Symbol(symbol_name(group, j.name), real=True) for j in joints)


def units(model: Model, group: str) -> tuple[str, ...]:
    """Per-joint units of one coordinate group."""
    return units_of(model.coordinates, group)


def units_of(joints: Sequence[Joint | Coordinate], group: str) -> tuple[str, ...]:
    """Per-joint units of one coordinate group of ``joints``."""
    g = GROUPS[group]
    return tuple(joint_kinds.per_coordinate(j.type, g.revolute_unit, g.prismatic_unit) for j in joints)


def joint_values(model: Model, group: str) -> tuple[sympy.Expr, ...]:
    """The value of every joint of a serial chain in ``group`` ("q", "qd" or "qdd"), in joint order.

    A joint that moves by its own coordinate is its symbol; a coupled joint
    (:class:`~symkin.model.schema.Coupling`) is ``sum_k a_k q_k (+ b for q)``, so that everything
    built on these values is a function of the coordinates alone.
    """
    own = dict(zip((c.name for c in model.coordinates), symbols(model, group)))
    values = []
    for joint in model.joints:
        if joint.coupling is None:
            values.append(own[joint.name])
        else:
            value = sympy.Add(*(a * own[name] for name, a in joint.coupling.terms))
            values.append(value + joint.coupling.offset if group == "q" else value)
    return tuple(values)


def coupling_matrix(model: Model) -> sympy.ImmutableMatrix | None:
    """A = d(joint values)/d(coordinates), joints x coordinates, or None when every joint is a coordinate.

    Joint rates are A qd; the coordinates' Jacobian columns are J A, their mass matrix A^T M A and
    their generalized forces A^T tau (virtual work, the coupling being linear).
    """
    if all(j.coupling is None for j in model.joints):
        return None
    index = {c.name: k for k, c in enumerate(model.coordinates)}
    A = sympy.zeros(len(model.joints), len(index))
    for row, joint in enumerate(model.joints):
        if joint.coupling is None:
            A[row, index[joint.name]] = 1
        else:
            for name, a in joint.coupling.terms:
                A[row, index[name]] = a
    return sympy.ImmutableMatrix(A)


def all_symbol_names(joint_name: str) -> tuple[str, ...]:
    """Every symbol name a joint claims (used to detect clashes with parameter names)."""
    return tuple(symbol_name(g, joint_name) for g in GROUPS)


def coordinate_range(model: Model) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) per joint for random states (the stability harness, the feasibility check of
    the mass matrix, the crosscheck): the limits at the default parameters, clamped to +-4 pi, else
    +-pi rad / +-0.5 m."""
    lower, upper = [], []
    defaults = model.parameter_values
    for joint in model.coordinates:
        span = joint_kinds.per_coordinate(joint.type, np.pi, 0.5)
        if joint.limits is not None:
            lo, hi = (float(b.xreplace(defaults)) for b in joint.limits)
            lower.append(max(lo, -4 * np.pi))
            upper.append(min(hi, 4 * np.pi))
        else:
            lower.append(-span)
            upper.append(span)
    for follower in model.joints:
        coupling, limits = follower.coupling, follower.limits
        if coupling is None or coupling.leader is None or not follower.follower or limits is None:
            continue  # a box of coordinates bounds a one-term follower only
        # the follower's limits bound its leader: lo <= a q + b <= hi
        k = [c.name for c in model.coordinates].index(coupling.leader)
        a, b = (float(sympy.sympify(v).xreplace(defaults)) for v in (coupling.multiplier, coupling.offset))
        ends = sorted((float(limit.xreplace(defaults)) - b) / a for limit in limits)
        if max(lower[k], ends[0]) > min(upper[k], ends[1]):
            raise ModelError([model.problem(("serial",), f"the limits of '{follower.name}' and of its leader "
                                                        f"'{coupling.leader}' leave no common value "
                                                        f"(q = {a:g} {coupling.leader} + {b:g})",
                                            "widen the limits, or fix the coupling's multiplier and offset "
                                            "(an MJCF range is in degrees unless <compiler angle=\"radian\">)")])
        lower[k], upper[k] = max(lower[k], ends[0]), min(upper[k], ends[1])
    return np.array(lower), np.array(upper)
