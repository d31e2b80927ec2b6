"""Closed-loop dynamics from MuJoCo's tree with the loops closed by equality constraints (a test-only reference).

MuJoCo simulates a closed mechanism as a kinematic tree (every joint a coordinate) plus equality constraints
(``connect``, ``weld``).  Reduced to the actuated coordinates: the tree's velocities are T qd with the passive rows
from the constraint Jacobian (J_c T = 0), its accelerations T qdd + c with J_c c = -dJ_c/dt qd_tree (dJ_c/dt qd by
central differences), and then M = T^T M_tree T and tau = T^T (M_tree qdd_tree + bias_tree): d'Alembert's principle,
as symkin's parallel dynamics, but from MuJoCo's own recursive algorithms and constraint Jacobians.

Bodies that symkin treats as massless need a positive mass and inertia in MuJoCo: they get TINY_MASS and
TINY_INERTIA, whose share of M (~1e-14 kg m^2 of >= 1e-5) is below MUJOCO_AGREEMENT.
"""

from __future__ import annotations

import numpy as np

TINY_MASS, TINY_INERTIA = 1e-12, 1e-14
#: the TINY bodies (above) and central differences of the constraint Jacobian (step 1e-5 rad: truncation ~1e-10,
#: rounding eps / h ~ 2e-11), relative to the largest entry
MUJOCO_AGREEMENT = 1e-9


def reduced_dynamics(reference, data, position, active, passive, qd, qdd):
    """(M, tau) of the closed loop in the actuated coordinates (tree indices ``active``) at the tree configuration
    ``position`` (the loops closed), for actuated rates qd and accelerations qdd."""
    import mujoco

    def constraint_jacobian(at):
        data.qpos[:] = at
        mujoco.mj_forward(reference, data)
        return data.efc_J.reshape(data.nefc, reference.nv).copy()

    J = constraint_jacobian(position)
    T = np.zeros((reference.nv, len(active)))
    T[active] = np.eye(len(active))
    T[passive] = np.linalg.lstsq(J[:, passive], -J[:, active], rcond=None)[0]
    velocity = T @ qd
    h = 1e-5
    J_dot_qd = (constraint_jacobian(position + h * velocity)
                - constraint_jacobian(position - h * velocity)) @ velocity / (2 * h)
    offset = np.zeros(reference.nv)
    offset[passive] = np.linalg.lstsq(J[:, passive], -J_dot_qd, rcond=None)[0]
    data.qpos[:], data.qvel[:] = position, velocity
    mujoco.mj_forward(reference, data)
    M = np.zeros((reference.nv, reference.nv))
    mujoco.mj_fullM(reference, data, M)
    tau = T.T @ (M @ (T @ qdd + offset) + data.qfrc_bias)
    return T.T @ M @ T, tau
