"""MuJoCo as the second reference of ``symkin crosscheck`` for a model read from an MJCF file.

Pinocchio checks symkin's reading of the URDF text that symkin writes from the compiled MJCF model
(:mod:`symkin.model.mjcf_source`); this module checks that text itself against MuJoCo on the file as
MuJoCo reads it: at the same states, the joints off the chain at their locked values and at rest,
M against ``mj_fullM`` (armature included) and V + G against ``qfrc_bias - qfrc_spring`` (MuJoCo's Coriolis,
centrifugal and gravity forces, and the joint springs' forces, which symkin's G holds), restricted to the chain's degrees of freedom (and projected on the
coordinates, A^T M A and A^T bias, where joint equalities couple joints: MuJoCo's M is the open tree's).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np


def mujoco_errors(path: Path, model: Any, locked: Mapping[str, float], values: Mapping[str, Any],
                  Q: np.ndarray, QD: np.ndarray, normwise: Any) -> dict[str, float]:
    """{row: largest normwise error over the states} of M and V + G of one backend's ``values``
    (``normwise``: the crosscheck's error measure, with the natural sizes of its dynamics rows)."""
    import mujoco

    from symkin.model.coordinates import coupling_matrix

    # compiled here again (the model reading compiled it confined, in a child: symkin.model.mjcf_compile); its
    # warnings are already the model's notes, and must not land in a MUJOCO_LOG.TXT in the working folder
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda _text: None)
    try:
        reference = mujoco.MjModel.from_xml_path(str(path))
    finally:
        mujoco.set_mju_user_warning(previous)
    data = mujoco.MjData(reference)
    joints = [mujoco.mj_name2id(reference, mujoco.mjtObj.mjOBJ_JOINT, model.source_name("joints", j.name))
              for j in model.joints]
    # joints coupled by MuJoCo's joint equalities: theta = A q + b (MuJoCo's M and bias are the open tree's)
    matrix = coupling_matrix(model)
    A = np.eye(len(joints)) if matrix is None else np.array(matrix.xreplace(model.parameter_values), dtype=float)
    b = np.array([0.0 if j.coupling is None else float(j.coupling.offset.xreplace(model.parameter_values))
                  for j in model.joints])
    dofs = [int(reference.jnt_dofadr[j]) for j in joints]
    positions = [int(reference.jnt_qposadr[j]) for j in joints]
    rest = np.zeros(reference.nq)
    for name, value in locked.items():
        joint = mujoco.mj_name2id(reference, mujoco.mjtObj.mjOBJ_JOINT, name)
        if joint >= 0:
            rest[reference.jnt_qposadr[joint]] = value
    total_mass = float(sum(float(b.mass.xreplace(model.parameter_values)) for b in model.bodies))
    gravity = float(np.linalg.norm(reference.opt.gravity))
    full = np.zeros((reference.nv, reference.nv))
    errors = {"mass_matrix (MuJoCo)": 0.0, "coriolis_vector + gravity_vector (MuJoCo)": 0.0}
    for k in range(len(Q)):
        data.qpos[:], data.qvel[:] = rest, 0.0
        data.qpos[positions], data.qvel[dofs] = A @ Q[k] + b, A @ QD[k]
        mujoco.mj_forward(reference, data)
        mujoco.mj_fullM(reference, data, full)
        M = A.T @ full[np.ix_(dofs, dofs)] @ A
        size = float(np.linalg.norm(M))
        bias = values["coriolis_vector"][k] + (values["gravity_vector"][k] if "gravity_vector" in values else 0.0)
        natural = (size * float(np.linalg.norm(QD[k])) ** 2 + gravity * math.sqrt(size * total_mass)
                   + float(np.linalg.norm(data.qfrc_spring[dofs])))
        for row, got, want, scale in (("mass_matrix (MuJoCo)", values["mass_matrix"][k], M, 0.0),
                                      ("coriolis_vector + gravity_vector (MuJoCo)", bias,
                                       A.T @ (data.qfrc_bias - data.qfrc_spring)[dofs], natural)):
            errors[row] = max(errors[row], normwise(got, want, None, scale))
    return errors
