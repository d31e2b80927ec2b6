"""Derivatives of the dynamics (issue 65): ``inverse_dynamics_derivatives`` gives d tau/dq, d tau/dqd and
d tau/dqdd = M, derived on the recursive Newton-Euler program; ``forward_dynamics_derivatives`` d qdd/dq, d qdd/dqd
and d qdd/dtau = M^-1.

References: Pinocchio's analytical RNEA, ABA and static-torque derivatives (``computeRNEADerivatives``,
``computeABADerivatives``, ``computeStaticTorqueDerivatives``; Carpentier and Mansard 2018) on a 6-DoF arm (models/ur10e.urdf), a 7-DoF arm as shipped (example-robot-data's Panda,
its hand locked) and a tree (a torso carrying two arms and a head, through the URDF symkin exports; its drive's
armature set in Pinocchio, its friction added by hand); central finite differences of the generated tau on the PHANToM Premium (couplings,
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

def _agree(got: np.ndarray, want: np.ndarray, state, kappa: float = 1.0) -> None:
    scale = max(1.0, float(np.abs(want).max()))
    error = float(np.abs(got - want).max())
    assert error <= DYNAMICS * kappa * scale, f"error {error:.3g} > {DYNAMICS * kappa * scale:.3g} at {state}"


def _friction(model, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(F_f(qd), d F_f/dqd diagonal) of the model's friction, viscous + Coulomb sign(qd), which Pinocchio's RNEA and
    ABA leave out (a URDF's joint damping and friction)."""
    values = model.parameter_values
    viscous, coulomb = np.zeros(model.dof), np.zeros(model.dof)
    names = [j.name for j in model.joints]
    for f in model.friction:
        assert f.smoothing_velocity is None, "the test's friction is viscous + sign(qd)"
        assert not f.asymmetric, "the test's friction is viscous + sign(qd)"
        viscous[names.index(f.joint)] = float(f.viscous.xreplace(values))
        coulomb[names.index(f.joint)] = float(f.coulomb.xreplace(values))
    return viscous * qd + coulomb * np.sign(qd), viscous


def _compare_with_pinocchio(model, reference, seed: int) -> None:
    """At five random states: symkin's derivatives of the inverse and the forward dynamics (plain lambdify of the
    derivation) against Pinocchio's analytical RNEA and ABA derivatives of ``reference``, a model of the same
    joints (by the model's names), with the model's friction added to Pinocchio's torques and to d tau/dqd.  The
    forward dynamics' derivatives pass through M^-1: DYNAMICS kappa(M)."""
    joints = [reference.joints[reference.getJointId(model.source_name("joints", j.name))] for j in model.joints]
    assert reference.nv == model.dof
    columns = [joint.idx_v for joint in joints]
    d = Derivation(model)
    inverse = reference_function(model, d["inverse_dynamics_derivatives"])
    forward = reference_function(model, d["forward_dynamics_derivatives"])
    data = reference.createData()
    rng = np.random.default_rng(seed)
    for _ in range(5):
        q, qd, qdd = random_q(model, rng), rng.uniform(-2, 2, model.dof), rng.uniform(-5, 5, model.dof)
        Q, V, A = pin.neutral(reference), np.zeros(reference.nv), np.zeros(reference.nv)
        for joint, angle in zip(joints, q):  # a continuous joint (no limits) holds cos and sin
            Q[joint.idx_q:joint.idx_q + joint.nq] = [np.cos(angle), np.sin(angle)] if joint.nq == 2 else angle
        V[columns], A[columns] = qd, qdd
        order = np.ix_(columns, columns)
        dq, dv, da = (np.asarray(m)[order] for m in pin.computeRNEADerivatives(reference, data, Q, V, A))
        da = np.triu(da) + np.triu(da, 1).T
        friction, slope = _friction(model, qd)
        dtau_dq, dtau_dqd, dtau_dqdd = inverse(q, qd, qdd)
        _agree(dtau_dq, dq, (q, qd, qdd))
        _agree(dtau_dqd, dv + np.diag(slope), (q, qd, qdd))
        _agree(dtau_dqdd, da, (q, qd, qdd))
        tau = np.asarray(pin.rnea(reference, data, Q, V, A))[columns] + friction   # symkin's torques for qdd
        T = np.zeros(reference.nv)
        T[columns] = tau - friction
        pin.computeABADerivatives(reference, data, Q, V, T)
        M_inv = np.triu(data.Minv) + np.triu(data.Minv, 1).T
        kappa = float(np.linalg.cond(da))
        dqdd_dq, dqdd_dqd, dqdd_dtau = forward(q, qd, tau)
        _agree(dqdd_dq, np.asarray(data.ddq_dq)[order], (q, qd, tau), kappa)
        _agree(dqdd_dqd, np.asarray(data.ddq_dv)[order] - M_inv[order] @ np.diag(slope), (q, qd, tau), kappa)
        _agree(dqdd_dtau, M_inv[order], (q, qd, tau), kappa)


def test_a_6_dof_arm_agrees_with_pinocchio():
    path = MODELS_DIR / "ur10e.urdf"
    _compare_with_pinocchio(load_model(path), pin.buildModelFromUrdf(str(path)), 65)


def test_a_stock_7_dof_arm_agrees_with_pinocchio():
    """The Panda as shipped: its fingers locked at 0 and lumped into the chain by symkin, locked at 0 in
    Pinocchio's reduced model of the whole file."""
    path = ROBOTS_DIR / "panda_description/urdf/panda.urdf"
    model = load_model(path, tip="panda_link8", chain=True)
    whole = pin.buildModelFromUrdf(str(path))
    chain = {model.source_name("joints", j.name) for j in model.joints}
    locked = [whole.getJointId(name) for name in whole.names[1:] if name not in chain]
    _compare_with_pinocchio(model, pin.buildReducedModel(whole, locked, pin.neutral(whole)), 66)


def test_a_tree_agrees_with_pinocchio():
    model = model_from_text(TORSO, file="torso.yaml")
    reference = pin.buildModelFromXML(export_urdf(model))
    for actuator in model.actuators:  # the drive's reflected rotor inertia: Pinocchio's armature
        index = reference.joints[reference.getJointId(actuator.joint)].idx_v
        reference.armature[index] = float(actuator.reflected_inertia.xreplace(model.parameter_values))
    _compare_with_pinocchio(model, reference, 67)


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


def test_the_generated_linearization_of_the_plant_is_the_forward_dynamics_slope(generated_dir):
    """generated/ur10e's forward_dynamics_derivatives (docs/generated-code.md's MPC linearization) against central
    differences of its generated forward dynamics (h = EPS^(1/3): error ~EPS^(2/3) kappa(M) of the slopes' scale;
    1e-6 leaves a wide margin at kappa(M) ~ 1e3), and against -M^-1 times the inverse dynamics' derivatives at the
    same motion; M^-1 exactly symmetric."""
    from symkin import load

    arm = load(generated_dir / "ur10e")
    q, qd, tau = np.radians([10.0, -80.0, 70.0, -30.0, 60.0, 5.0]), np.full(6, 0.2), np.full(6, 1.5)
    d = arm.forward_dynamics_derivatives(q, qd, tau)
    inverse = arm.inverse_dynamics_derivatives(q, qd, arm.forward_dynamics(q, qd, tau))
    kappa = float(np.linalg.cond(inverse.dtau_dqdd))
    _agree(d.dqdd_dtau, np.linalg.inv(inverse.dtau_dqdd), q, kappa)
    assert np.array_equal(d.dqdd_dtau, d.dqdd_dtau.T), "M^-1 is its lower triangle, mirrored"
    h = EPS ** (1 / 3)
    for which, analytic in ((0, d.dqdd_dq), (1, d.dqdd_dqd)):
        _agree(analytic, -d.dqdd_dtau @ (inverse.dtau_dq, inverse.dtau_dqd)[which], q, kappa)
        columns = []
        for e in np.eye(6):
            plus, minus = [q, qd], [q, qd]
            plus[which], minus[which] = plus[which] + h * e, minus[which] - h * e
            columns.append((arm.forward_dynamics(*plus, tau) - arm.forward_dynamics(*minus, tau)) / (2 * h))
        slope = np.column_stack(columns)
        np.testing.assert_allclose(analytic, slope, rtol=0, atol=1e-6 * max(1.0, float(np.abs(slope).max())))


@pytest.mark.parametrize("path", [MODELS_DIR / "ur10e.urdf", ROBOTS_DIR / "panda_description/urdf/panda.urdf"],
                         ids=["ur10e", "panda"])
def test_the_gravity_derivative_agrees_with_pinocchio_and_is_symmetric(path):
    """computeGeneralizedGravityDerivatives; dG/dq = d^2u/dq^2 is a Hessian, symmetric to rounding."""
    model = load_model(path, tip="panda_link8", chain=True) if "panda" in path.name else load_model(path)
    whole = pin.buildModelFromUrdf(str(path))
    chain = {model.source_name("joints", j.name) for j in model.joints}
    reference = pin.buildReducedModel(whole, [whole.getJointId(n) for n in whole.names[1:] if n not in chain],
                                      pin.neutral(whole))
    dG = reference_function(model, Derivation(model)["gravity_derivatives"])
    data = reference.createData()
    rng = np.random.default_rng(69)
    for _ in range(5):
        q = random_q(model, rng)
        want = np.asarray(pin.computeGeneralizedGravityDerivatives(reference, data, q))
        (got,) = dG(q)
        _agree(got, want, q)
        _agree(got, got.T, q)


@pytest.fixture(scope="module")
def ur10e_sensitivities(tmp_path_factory):
    """models/ur10e.yaml's fk, J and tau with their parameter sensitivities, numpy, every parameter free, and the
    parameters each base function takes (the sensitivities' columns)."""
    from symkin import load, pipeline

    model = load_model(MODELS_DIR / "ur10e.yaml")
    names = "fk,jacobian,inverse_dynamics,fk_sensitivities,jacobian_sensitivities,inverse_dynamics_sensitivities"
    request = pipeline.resolve_request(model, names, "numpy", None, False, "none")
    directory = pipeline.write(pipeline.generate(model, request), tmp_path_factory.mktemp("sensitivities"))
    d = Derivation(model)
    columns = {base: [i.name for i in d[base].inputs if i.kind == "parameter"]
               for base in ("fk", "jacobian", "inverse_dynamics")}
    return load(directory), columns, model.parameter_values, {p.name: p.symbol for p in model.parameters}


@pytest.mark.parametrize("base", ["fk", "jacobian", "inverse_dynamics"])
def test_parameter_sensitivities_are_central_differences_of_the_function(ur10e_sensitivities, base):
    """d f/d p of each free parameter (lengths, masses, g) against central differences of the generated f with that
    parameter moved by h = EPS^(1/3) max(1, |p|) (error ~EPS^(2/3) of f's scale: 1e-8 leaves a factor 100)."""
    arm, columns, values, symbols = ur10e_sensitivities
    rng = np.random.default_rng(70)
    state = [rng.uniform(-3, 3, 6) for _ in range(3 if base == "inverse_dynamics" else 1)]
    slopes = np.asarray(getattr(arm, f"{base}_sensitivities")(*state))  # one output: the array itself
    function = getattr(arm, base)
    scale = max(1.0, float(np.abs(function(*state)).max()))
    for j, name in enumerate(columns[base]):
        value = float(values[symbols[name]])
        h = EPS ** (1 / 3) * max(1.0, abs(value))
        difference = (np.asarray(function(*state, **{name: value + h})) -
                      np.asarray(function(*state, **{name: value - h}))) / (2 * h)
        np.testing.assert_allclose(slopes[:, j], difference.ravel(), rtol=0, atol=1e-8 * scale, err_msg=name)


def test_the_static_torques_derivative_is_their_central_difference_and_gravitys_at_no_wrench():
    """static_torque_derivatives of the UR10e (models/ur10e.yaml: its task space x, y, z, wx, wy, wz, so F is a force
    and a moment at the TCP in the base frame) against central differences of G(q) - J(q)^T F from the generated
    gravity vector and Jacobian (h = EPS^(1/3): error ~EPS^(2/3) of the scale; 1e-8 leaves a factor of 100), and at
    F = 0 against gravity_derivatives (the same program: DYNAMICS).  The force's own stiffness is not idle here."""
    model = load_model(MODELS_DIR / "ur10e.yaml")
    d = Derivation(model)
    derivative = reference_function(model, d["static_torque_derivatives"])
    gravity, jacobian = reference_function(model, d["gravity_vector"]), reference_function(model, d["jacobian"])
    dG = reference_function(model, d["gravity_derivatives"])
    rng = np.random.default_rng(65)

    def static(q, F):
        return gravity(q)[0] - jacobian(q)[0].T @ F

    for _ in range(3):
        q, F = random_q(model, rng), np.concatenate([rng.uniform(-50, 50, 3), rng.uniform(-5, 5, 3)])
        (analytic,) = derivative(q, F)
        h = EPS ** (1 / 3)
        slope = np.column_stack([(static(q + h * e, F) - static(q - h * e, F)) / (2 * h) for e in np.eye(model.dof)])
        scale = max(1.0, float(np.abs(slope).max()))
        np.testing.assert_allclose(analytic, slope, rtol=0, atol=1e-8 * scale)
        (at_rest,) = derivative(q, np.zeros(6))
        _agree(at_rest, dG(q)[0], q)
        assert np.abs(analytic - at_rest).max() > 1e-3 * scale     # the wrench's stiffness is there


def test_the_static_torques_derivative_is_pinocchios_with_the_wrench_held_in_the_base_frame():
    """computeStaticTorqueDerivatives on models/ur10e.urdf: Pinocchio holds each external force fixed in its joint's
    frame, symkin's static_torque_derivatives the wrench F = (f, m) at the TCP fixed in the base frame.  Carried by the
    last link, F turns with it: dF/dq_k = (w_k x f, w_k x m) with w_k the joint's axis (the angular rows of the
    TCP's geometric Jacobian J), so symkin's derivative is Pinocchio's plus J^T (w_k x f, w_k x m) in column k - an
    exact identity, rounding apart (DYNAMICS of the scale); the static torques themselves, G - J^T F, are Pinocchio's
    computeStaticTorque with the wrench moved to the last joint's origin and frame."""
    path = MODELS_DIR / "ur10e.urdf"
    model, reference = load_model(path), pin.buildModelFromUrdf(str(path))
    last = reference.getJointId(model.source_name("joints", model.joints[-1].name))
    assert [reference.getJointId(model.source_name("joints", j.name)) for j in model.joints] == list(range(1, 7))
    d = Derivation(model)
    derivative, jacobian, fk = (reference_function(model, d[name])
                                for name in ("static_torque_derivatives", "jacobian", "fk"))
    data = reference.createData()
    rng = np.random.default_rng(70)
    for _ in range(3):
        q, F = random_q(model, rng), np.concatenate([rng.uniform(-50, 50, 3), rng.uniform(-5, 5, 3)])
        (J,), (tcp,) = jacobian(q), fk(q)
        pin.forwardKinematics(reference, data, q)
        R, t = data.oMi[last].rotation, data.oMi[last].translation
        f, m = F[:3], F[3:]
        forces = [pin.Force.Zero() for _ in range(reference.njoints)]
        forces[last] = pin.Force(R.T @ f, R.T @ (m + np.cross(tcp[:3, 3] - t, f)))
        static = np.asarray(pin.computeStaticTorque(reference, data, q, forces))
        _agree(static, np.asarray(pin.computeGeneralizedGravity(reference, data, q)) - J.T @ F, q)
        carried = np.asarray(pin.computeStaticTorqueDerivatives(reference, data, q, forces))
        turning = np.column_stack([J.T @ np.concatenate([np.cross(J[3:, k], f), np.cross(J[3:, k], m)])
                                   for k in range(model.dof)])
        (got,) = derivative(q, F)
        _agree(got, carried + turning, q)
        assert np.abs(turning).max() > 1e-2 * np.abs(got).max()  # the frames' difference is not idle
