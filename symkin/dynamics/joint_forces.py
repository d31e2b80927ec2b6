"""Forces that act at the joints, not through the bodies: friction (``friction:``, seed eq. 8.34) and springs.

Joint springs (``springs:``, :class:`~symkin.model.schema.Spring`): the potential 1/2 k (theta - theta_0)^2 of
each sprung joint and its generalized force k (theta - theta_0), which :mod:`symkin.dynamics.quantities` adds to G
(so to tau, forward dynamics and Gx) and to the potential energy; on the coordinates through A^T where joints
are coupled."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import symengine as se

from symkin.dynamics.coupling import forces_on_coordinates, joint_rates
from symkin.ir.quantity import Deriving, quantity
from symkin.model.schema import Friction, Spring

#: what the documentation of G and of the potential energy add for a model with joint springs
SPRINGS_IN_G = (" The joint springs' forces k (theta - theta_0) are part of G: u includes their potential "
                "1/2 k (theta - theta_0)^2.")
SPRINGS_IN_U = " The joint springs add 1/2 k (theta - theta_0)^2 each."


@quantity("spring_torques", "joint springs' forces K (theta - theta_0) on the coordinates, or None", emitted=False)
def spring_torques(d: Deriving) -> list[se.Basic] | None:
    """A^T (k_j (theta_j - theta_0,j)) per joint: the generalized force of the springs' potential."""
    if not d.model.springs:
        return None
    return _on_coordinates(d, "q", d.model.springs,
                           lambda s, theta: se.sympify(s.stiffness) * (theta - se.sympify(s.reference)))


def _on_coordinates(d: Deriving, group: str, entries: Sequence[Friction | Spring],
                    force: Callable[[Any, se.Basic], se.Basic]) -> list[se.Basic]:
    """A^T f of the joints' forces f_j = force(entry, value of joint j in ``group``) of ``entries`` (one per joint,
    by ``entry.joint``; 0 at the other joints)."""
    values = dict(zip((j.name for j in d.model.joints), joint_rates(d.model, group)))
    forces = {name: se.Integer(0) for name in values}
    for entry in entries:
        forces[entry.joint] = force(entry, values[entry.joint])
    return forces_on_coordinates(d.model, list(forces.values()))


def spring_energy(d: Deriving) -> se.Basic:
    """sum 1/2 k_j (theta_j - theta_0,j)^2 over the model's springs (0 without)."""
    theta = dict(zip((j.name for j in d.model.joints), joint_rates(d.model, "q")))
    return sum((se.sympify(s.stiffness) * (theta[s.joint] - se.sympify(s.reference)) ** 2 / 2
                for s in d.model.springs), se.Integer(0))


@quantity("friction_graph", "F_f(qd) as SymEngine expressions, or None without friction", emitted=False)
def friction_graph(d: Deriving) -> list[se.Basic] | None:
    """F_f,j = viscous_j qd_j + coulomb_j sign(qd_j), or coulomb_j tanh(qd_j / v_s,j) when smoothed."""
    if not d.model.friction:
        return None
    return _on_coordinates(d, "qd", d.model.friction, joint_friction)


def joint_friction(f: Friction, v: se.Basic) -> se.Basic:
    """viscous v + coulomb sign(v), or coulomb tanh(v / v_s) with a smoothing velocity v_s (seed eq. 8.34).

    Levels c+ (positive motion) and c- (negative motion) give (c+ + c-)/2 s + (c+ - c-)/2 s^2 with
    s = sign(v) or tanh(v / v_s): c+ for v > 0, -c- for v < 0, 0 at rest.
    """
    s = se.sign(v) if f.smoothing_velocity is None else se.tanh(v / se.sympify(f.smoothing_velocity))
    viscous = se.sympify(f.viscous) * v
    if not f.asymmetric:
        return viscous + se.sympify(f.coulomb) * s
    positive, negative = se.sympify(f.coulomb), se.sympify(f.coulomb_negative)
    return viscous + (positive + negative) / 2 * s + (positive - negative) / 2 * s ** 2
