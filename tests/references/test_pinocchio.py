"""symkin against Pinocchio (test-only dependency) on the same robot file, models/ur10e.urdf.

Pinocchio reads the URDF itself; symkin derives the URDF and models/ur10e.yaml.  Mass
matrix (CRBA), nonlinear effects V + G (RNEA with qdd = 0), gravity, the TCP pose and the
TCP frame Jacobian in base axes agree to DYNAMICS (512 eps, tests/tolerances.py) relative to the
largest entry: two exact methods (Lagrange closed forms, CRBA/RNEA) differ only in rounding.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin  # a test dependency (pyproject's test extra): missing, the suite fails instead of skipping
import pytest

from conftest import MODELS_DIR, random_q, reference_function
from symkin.derivation import Derivation
from symkin.model import load_model
from tolerances import DYNAMICS


URDF = MODELS_DIR / "ur10e.urdf"
TOLERANCE = DYNAMICS


@pytest.fixture(scope="module")
def pinocchio_model():
    model = pin.buildModelFromUrdf(str(URDF))
    return model, model.createData(), model.getFrameId("tool0")


@pytest.fixture(scope="module", params=["urdf", "yaml"])
def symkin_side(request, models, derivations):
    if request.param == "yaml":
        return models["ur10e"], derivations["ur10e"]
    model = load_model(URDF)
    return model, Derivation(model)


def _close(got, want, *state):
    scale = max(1.0, float(np.max(np.abs(want))))
    error = float(np.max(np.abs(np.asarray(got) - want)))
    assert error <= TOLERANCE * scale, f"error {error:.3g} > bound {TOLERANCE * scale:.3g} at state {state}"


def test_dynamics_agree_with_pinocchio(pinocchio_model, symkin_side):
    model, d = symkin_side
    pmodel, pdata, _ = pinocchio_model
    assert pmodel.nq == model.dof == 6
    M = reference_function(model, d["mass_matrix"])
    V = reference_function(model, d["coriolis_vector"])
    G = reference_function(model, d["gravity_vector"])
    tau = reference_function(model, d["inverse_dynamics"])
    rng = np.random.default_rng(40)
    for _ in range(10):
        q, qd, qdd = random_q(model, rng), rng.uniform(-2, 2, 6), rng.uniform(-5, 5, 6)
        M_pin = pin.crba(pmodel, pdata, q).copy()
        M_pin = np.triu(M_pin) + np.triu(M_pin, 1).T
        _close(M(q)[0], M_pin, q, qd, qdd)
        _close(V(q, qd)[0] + G(q)[0], pin.nonLinearEffects(pmodel, pdata, q, qd), q, qd, qdd)
        _close(G(q)[0], pin.computeGeneralizedGravity(pmodel, pdata, q), q, qd, qdd)
        _close(tau(q, qd, qdd)[0], pin.rnea(pmodel, pdata, q, qd, qdd), q, qd, qdd)


def test_kinematics_agree_with_pinocchio(pinocchio_model, symkin_side):
    model, d = symkin_side
    pmodel, pdata, tool = pinocchio_model
    fk = reference_function(model, d["fk"])
    J = reference_function(model, d["jacobian_geometric"])
    rng = np.random.default_rng(41)
    for _ in range(10):
        q = random_q(model, rng)
        pin.forwardKinematics(pmodel, pdata, q)
        pin.updateFramePlacements(pmodel, pdata)
        _close(fk(q)[0], pdata.oMf[tool].homogeneous, q)
        J_pin = pin.computeFrameJacobian(pmodel, pdata, q, tool, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        _close(J(q)[0], J_pin, q)
