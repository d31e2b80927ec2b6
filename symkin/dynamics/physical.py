"""Which outputs a non-physical inertia blocks (issue 61: validation where it is used).

A serial model's inertia tensor that breaks the triangle inequality (or has a negative principal moment) is kept by
the reader as a located problem (``Model.nonphysical``) instead of refusing the model: its kinematics do not use it.
The quantities that read the bodies' inertias (the body Jacobians and the Newton-Euler links, and so M, C, V, G, tau,
forward dynamics, TCP forces, operational space, energies and regressors) call :func:`require_physical`.
"""

from __future__ import annotations

from symkin.errors import ModelDataError
from symkin.model.schema import Model

#: The serial outputs that use the bodies' inertias, which a non-physical inertia blocks (symkin check refuses a scene
#: asking for one; tests/model/test_model_errors.py derives every emitted quantity to keep this list exact).
INERTIA_OUTPUTS = frozenset({"mass_matrix", "coriolis_matrix", "coriolis_vector", "gravity_vector", "gravity_derivatives",
                             "inverse_dynamics", "inverse_dynamics_derivatives", "forward_dynamics",
                             "forward_dynamics_derivatives", "tcp_force", "operational_space", "kinetic_energy",
                             "potential_energy", "regressor", "energy_regressor", "base_regressor",
                             "inverse_dynamics_sensitivities", "static_torque_derivatives"})


def require_physical(model: Model) -> None:
    """Refuse what uses the bodies' inertias where the model holds a non-physical one (``Model.nonphysical``, with
    its place and the fix, exit 2): the kinematics of the same model derive."""
    if model.nonphysical:
        raise ModelDataError(model.nonphysical)
