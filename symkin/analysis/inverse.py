"""The inverse kinematics an analysis uses for a model (:func:`inverse_kinematics_for`).

Serial arms: the closed forms of :mod:`symkin.ik` whose target is a TCP position (the planar
2R; :class:`ClosedFormInverse`); parallel mechanisms: their closed-form inverse kinematics
(DELTA: one quadratic per leg, 2^3 branches or the chosen working mode;
:func:`symkin.mechanism.reach.generated_inverse`).  Each is an
:class:`~symkin.mechanism.feasibility.InverseKinematics`; joint limits are applied by
:func:`~symkin.mechanism.feasibility.feasible_configurations`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from symkin import mechanism
from symkin.mechanism.feasibility import InverseKinematics
from symkin.mechanism.reach import generated_inverse
from symkin.errors import NotApplicable
from symkin.ik import ClosedFormIK, closed_form_solver
from symkin.runtime.info import GeneratedModel

# --- serial closed forms (symkin.ik) -------------------------------------------------------


@dataclass(frozen=True)
class ClosedFormInverse:
    """A closed-form solver of :mod:`symkin.ik` seen as an :class:`~symkin.mechanism.feasibility.InverseKinematics`.

    The solver recognises the structure from the joint screws (e.g. the planar 2R: two
    parallel revolute axes, both elbow branches from the half-angle law of cosines, seed
    sec. 4.4.1) and checks every branch through the generated ``fk``: a branch is ``valid``
    only where it is a real solution that reproduces the point (residual <= 1e-9 relative,
    :data:`symkin.ik.closed_form.VALID_TOLERANCE`).  A point on the workspace boundary
    (|cos theta2| = 1 up to rounding) is clamped onto it and stays reachable.  The solver's
    own joint limits are not used (its angles are not shifted into them):
    :func:`~symkin.mechanism.feasibility.feasible_configurations` applies the analysis' limits.

    Attributes:
        solver: the :class:`~symkin.ik.closed_form.ClosedFormIK` (task-space targets).
        order: indices that reorder a point (in :func:`~symkin.mechanism.position_axes`
            order) into the solver's target (the model's task-space order).
    """

    solver: ClosedFormIK
    order: tuple[int, ...]
    dimension: int
    branches: int

    def solve(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        solutions = self.solver.solve(np.asarray(points, dtype=np.float64)[..., list(self.order)], shift=False)
        return solutions.q, solutions.valid


def closed_form_inverse(model: GeneratedModel) -> ClosedFormInverse:
    """The closed-form inverse kinematics of a serial model whose task space is positional.

    Raises:
        NotApplicable: :func:`symkin.ik.closed_form.closed_form_solver` recognises no structure
            (as for a mechanism that closes loops, or a view of one), or its solver takes poses (the UR family): the
            Cartesian analyses work on positions, the solver's target must be the model's
            positional task space.
    """
    solver = closed_form_solver(model)  # None for a mechanism that closes loops: its IK is generated code
    if solver is None:
        raise NotApplicable(f"{model.name}: no closed-form inverse kinematics of an open chain recognised (symkin.ik)")
    task = mechanism.task_space(model)
    if solver.kind != "task" or not all(c in mechanism.POSITION_COMPONENTS for c in task):
        raise NotApplicable(f"{model.name}: the closed-form inverse kinematics ({solver.name}) takes "
                         f"{solver.kind} targets, not positions [{', '.join(task)}]: the Cartesian "
                         "workspace analyses need one that takes TCP positions")
    axes = mechanism.position_axes(model)
    order = tuple(axes.index(mechanism.POSITION_COMPONENTS.index(c)) for c in task)
    return ClosedFormInverse(solver, order, len(axes), len(solver.solver.branches))


#: Factories tried in order by :func:`inverse_kinematics_for`; each returns an
#: InverseKinematics for the model or raises NotApplicable: serial closed forms of symkin.ik,
#: then parallel mechanisms' generated ``ik``.
INVERSE_FACTORIES: list = [closed_form_inverse, generated_inverse]


def inverse_kinematics_for(model: GeneratedModel) -> InverseKinematics | None:
    """The first inverse kinematics that applies to ``model``, or None."""
    for factory in INVERSE_FACTORIES:
        try:
            return factory(model)
        except NotApplicable:
            continue
    return None
