"""Derivatives of the inverse dynamics (issue 65): ``inverse_dynamics_derivatives`` gives d tau/dq, d tau/dqd and
d tau/dqdd = M, derived on the recursive Newton-Euler program.

References: Pinocchio's analytical RNEA derivatives (``computeRNEADerivatives``, Carpentier and Mansard 2018) on a
6-DoF arm (models/ur10e.urdf), a 7-DoF arm as shipped (example-robot-data's Panda, its hand locked) and a tree (a
torso carrying two arms and a head, through the URDF symkin exports; its drive's armature set in Pinocchio, its
viscous friction added by hand); central finite differences of the generated tau on the PHANToM Premium (couplings,
rotor inertia, Coulomb and viscous friction).  Both sides of the Pinocchio comparisons are exact methods, so they
differ by rounding: DYNAMICS (tests/tolerances.py) relative to the entries' scale.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from conftest import MODELS_DIR, random_q, reference_function
from sample_models import ROBOTS_DIR, TORSO
from symkin.derivation import Derivation
from symkin.model import load_model, model_from_text
from symkin.model.urdf_export import export_urdf
from tolerances import DYNAMICS, EPS

def _agree(got: np.ndarray, want: np.ndarray, state) -> None:
    scale = max(1.0, float(np.abs(want).max()))
    error = float(np.abs(got - want).max())
    assert error <= DYNAMICS * scale, f"error {error:.3g} > {DYNAMICS * scale:.3g} at {state}"


def _compare_with_pinocchio(model, reference, names: list[str], seed: int) -> None:
    """At five random states: symkin's derivatives (plain lambdify of the derivation) against Pinocchio's on the
    joints ``names`` of ``reference`` (the model's joints in its order; the others at their neutral values, at rest),
    with the model's viscous friction, which Pinocchio's RNEA leaves out (a URDF's joint damping), added to
    d tau/dqd."""
    joints = [reference.joints[reference.getJointId(name)] for name in names]
    columns = [joint.idx_v for joint in joints]
    viscous = {f.joint: float(f.viscous.xreplace(model.parameter_values)) for f in model.friction}
    friction = np.array([viscous.get(j.name, 0.0) for j in model.joints])
    derivatives = reference_function(model, Derivation(model)["inverse_dynamics_derivatives"])
    data = reference.createData()
    rng = np.random.default_rng(seed)
    for _ in range(5):
        q, qd, qdd = random_q(model, rng), rng.uniform(-2, 2, model.dof), rng.uniform(-5, 5, model.dof)
        Q, V, A = pin.neutral(reference), np.zeros(reference.nv), np.zeros(reference.nv)
        for joint, angle in zip(joints, q):  # a continuous joint (no limits) holds cos and sin
            Q[joint.idx_q:joint.idx_q + joint.nq] = [np.cos(angle), np.sin(angle)] if joint.nq == 2 else angle
        V[columns], A[columns] = qd, qdd
        dq, dv, da = (np.asarray(m)[np.ix_(columns, columns)] for m in pin.computeRNEADerivatives(reference, data, Q, V, A))
        da = np.triu(da) + np.triu(da, 1).T
        dtau_dq, dtau_dqd, dtau_dqdd = derivatives(q, qd, qdd)
        _agree(dtau_dq, dq, (q, qd, qdd))
        _agree(dtau_dqd, dv + np.diag(friction), (q, qd, qdd))
        _agree(dtau_dqdd, da, (q, qd, qdd))


def test_a_6_dof_arm_agrees_with_pinocchio():
    path = MODELS_DIR / "ur10e.urdf"
    reference = pin.buildModelFromUrdf(str(path))
    model = load_model(path)
    _compare_with_pinocchio(model, reference, [model.source_name("joints", j.name) for j in model.joints], 65)


def test_a_stock_7_dof_arm_agrees_with_pinocchio():
    """The Panda as shipped: its fingers locked at 0 and lumped into the chain by symkin, free (at rest) in
    Pinocchio's whole model."""
    path = ROBOTS_DIR / "panda_description/urdf/panda.urdf"
    model = load_model(path, tip="panda_link8", chain=True)
    reference = pin.buildModelFromUrdf(str(path))
    _compare_with_pinocchio(model, reference, [model.source_name("joints", j.name) for j in model.joints], 66)


def test_a_tree_agrees_with_pinocchio():
    model = model_from_text(TORSO, file="torso.yaml")
    reference = pin.buildModelFromXML(export_urdf(model))
    for actuator in model.actuators:  # the drive's reflected rotor inertia: Pinocchio's armature
        index = reference.joints[reference.getJointId(actuator.joint)].idx_v
        reference.armature[index] = float(actuator.reflected_inertia.xreplace(model.parameter_values))
    _compare_with_pinocchio(model, reference, [j.name for j in model.joints], 67)


def test_finite_differences_of_tau_on_a_coupled_geared_arm_with_friction():
    """PHANToM Premium (models/phantom_premium.yaml): couplings, rotor inertia, Coulomb + viscous friction.  Central
    differences with h = EPS^(1/3) |x| (truncation h^2 |tau'''| / 6 and rounding EPS |tau| / h, both ~EPS^(2/3)
    ~ 4e-11 of tau's scale); 1e-8 of the scale leaves a factor of 100.  The states keep |qd| > h, so no Coulomb
    sign flips between the two sides."""
    model = load_model(MODELS_DIR / "phantom_premium.yaml")
    d = Derivation(model)
    tau = reference_function(model, d["inverse_dynamics"])
    derivatives = reference_function(model, d["inverse_dynamics_derivatives"])
    rng = np.random.default_rng(65)
    for _ in range(3):
        state = [random_q(model, rng), rng.uniform(0.2, 2, model.dof) * rng.choice([-1, 1], model.dof),
                 rng.uniform(-5, 5, model.dof)]
        scale = max(1.0, float(np.abs(tau(*state)[0]).max()))
        for which, analytic in enumerate(derivatives(*state)):
            columns = []
            for j in range(model.dof):
                h = EPS ** (1 / 3) * max(1.0, abs(state[which][j]))
                plus, minus = [s.copy() for s in state], [s.copy() for s in state]
                plus[which][j] += h
                minus[which][j] -= h
                columns.append((tau(*plus)[0] - tau(*minus)[0]) / (2 * h))
            np.testing.assert_allclose(analytic, np.column_stack(columns), rtol=0, atol=1e-8 * scale)


@pytest.mark.parametrize("name", ["ur10e", "phantom_premium", "planar_2r"])
def test_d_tau_d_qdd_is_the_mass_matrix(name, models, derivations):
    """The derivative by the accelerations is the composite-rigid-body M (two routes, rounding apart)."""
    model, d = models[name], derivations[name]
    derivatives = reference_function(model, d["inverse_dynamics_derivatives"])
    M = reference_function(model, d["mass_matrix"])
    rng = np.random.default_rng(68)
    q = random_q(model, rng)
    _agree(derivatives(q, rng.uniform(-1, 1, model.dof), rng.uniform(-1, 1, model.dof))[2], M(q)[0], q)


def test_the_linearization_of_the_plant_is_the_forward_dynamics_slope(generated_dir):
    """docs/generated-code.md's MPC linearization from generated/ur10e: d qdd/dq = -M^-1 dtau/dq and
    d qdd/dqd = -M^-1 dtau/dqd at qdd = the forward dynamics' (the implicit-function theorem on M qdd + h = tau),
    against central differences of the generated forward dynamics (h = EPS^(1/3): error ~EPS^(2/3) kappa(M) of the
    slopes' scale; 1e-6 leaves a wide margin at kappa(M) ~ 1e3)."""
    from symkin import load

    arm = load(generated_dir / "ur10e")
    q, qd, tau = np.radians([10.0, -80.0, 70.0, -30.0, 60.0, 5.0]), np.full(6, 0.2), np.full(6, 1.5)
    d = arm.inverse_dynamics_derivatives(q, qd, arm.forward_dynamics(q, qd, tau))
    M_inv = np.linalg.inv(d.dtau_dqdd)
    h = EPS ** (1 / 3)
    for which, analytic in ((0, -M_inv @ d.dtau_dq), (1, -M_inv @ d.dtau_dqd)):
        columns = []
        for e in np.eye(6):
            plus, minus = [q, qd], [q, qd]
            plus[which], minus[which] = plus[which] + h * e, minus[which] - h * e
            columns.append((arm.forward_dynamics(*plus, tau) - arm.forward_dynamics(*minus, tau)) / (2 * h))
        slope = np.column_stack(columns)
        np.testing.assert_allclose(analytic, slope, rtol=0, atol=1e-6 * max(1.0, float(np.abs(slope).max())))
