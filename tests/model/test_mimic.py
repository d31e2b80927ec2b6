"""Joints that mimic others on the chain (issue 13): q_j = a q_i + b, one coordinate for both.

The reference is the same arm with every joint free (the tests' ODD_ARM, which hits every branch
of the kinematics and Newton-Euler code): at theta = A q + b, theta_d = A qd, theta_dd = A qdd the
coupled model must give fk(theta), J(theta) A, A^T M(theta) A, A^T V(theta, A qd), A^T G(theta),
A^T tau(theta, A qd, A qdd) and A^T F_f(A qd) (virtual work; Featherstone 2008, sec. 8.1), and its
Coriolis matrix must satisfy V = C qd with dM/dt - 2C skew, from the Christoffel symbols of A^T M A.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import reference_function
from symkin.derivation import Derivation
from symkin.errors import ModelError
from symkin.model import coordinates, model_from_text
from sample_models import ODD_ARM
from tolerances import DYNAMICS, KINEMATICS

#: j3 follows j1 (and carries the arm's friction), j4 follows the prismatic j2.
FOLLOWERS = {"j3": "{joint: j1, multiplier: -0.5, offset: 0.2}", "j4": "{joint: j2, multiplier: 3, offset: -0.1}"}
A_NUMERIC = np.array([[1, 0], [0, 1], [-0.5, 0], [0, 3]])
B_NUMERIC = np.array([0, 0, 0.2, -0.1])


def _coupled(arm: str, followers: dict[str, str], key: str = "mimic") -> str:
    for name, mimic in followers.items():
        start = arm.index(f"{{name: {name},")
        end = arm.index("}\n", arm.index("origin", start)) if "origin" in arm[start:arm.index("\n", start)] else \
            arm.index("}\n", start)
        arm = arm[:end] + f", {key}: {mimic}" + arm[end:]
    return arm


@pytest.fixture(scope="module")
def arms():
    free, coupled = model_from_text(ODD_ARM), model_from_text(_coupled(ODD_ARM, FOLLOWERS))
    return (free, Derivation(free)), (coupled, Derivation(coupled))


def test_followers_have_no_coordinate_and_a_constant_coupling(arms):
    _, (coupled, _) = arms
    assert [c.name for c in coupled.coordinates] == ["j1", "j2"]
    assert coupled.dof == 2
    assert np.array_equal(np.array(coordinates.coupling_matrix(coupled), dtype=float), A_NUMERIC)


def test_the_coupled_arm_is_the_free_arm_on_the_coupling(arms):
    (free, fd), (coupled, cd) = arms
    _agrees_on_the_coupling(free, fd, coupled, cd, A_NUMERIC, B_NUMERIC)


#: Issue 30: j3 keeps its coordinate but moves relative to j1 (a parallelogram's distal joint, whose
#: coordinate is the link's absolute angle), j4 follows two coordinates (a differential).
COUPLINGS = {"j3": '"j3 - j1 + 0.2"', "j4": '"j1 + 2*j2 - l1/3"'}
A_GENERAL = np.array([[1, 0, 0], [0, 1, 0], [-1, 0, 1], [1, 2, 0]])
B_GENERAL = np.array([0, 0, 0.2, -0.1])


def test_affine_couplings_of_several_coordinates_are_the_free_arm_on_the_coupling(arms):
    (free, fd), _ = arms
    coupled = model_from_text(_coupled(ODD_ARM, COUPLINGS, "coupling"))
    assert [c.name for c in coupled.coordinates] == ["j1", "j2", "j3"]
    assert coupled.dof == 3
    assert np.array_equal(np.array(coordinates.coupling_matrix(coupled), dtype=float), A_GENERAL)
    _agrees_on_the_coupling(free, fd, coupled, Derivation(coupled), A_GENERAL, B_GENERAL)


def _agrees_on_the_coupling(free, fd, coupled, cd, A, b):
    """fk(theta), J(theta) A, A^T M A, A^T V, A^T G, A^T F_f, A^T tau and the energies at theta = A q + b."""
    functions = ("fk", "jacobian_geometric", "mass_matrix", "coriolis_vector", "gravity_vector", "friction",
                 "inverse_dynamics", "potential_energy", "kinetic_energy")
    f = {name: reference_function(free, fd[name]) for name in functions}
    c = {name: reference_function(coupled, cd[name]) for name in functions}
    n = A.shape[1]
    rng = np.random.default_rng(13)
    for _ in range(5):
        q, qd, qdd = rng.uniform(-2, 2, n), rng.uniform(-2, 2, n), rng.uniform(-3, 3, n)
        theta, theta_d, theta_dd = A @ q + b, A @ qd, A @ qdd
        np.testing.assert_allclose(c["fk"](q)[0], f["fk"](theta)[0], rtol=0, atol=KINEMATICS)
        np.testing.assert_allclose(c["jacobian_geometric"](q)[0], f["jacobian_geometric"](theta)[0] @ A,
                                   rtol=0, atol=KINEMATICS)
        want = {"mass_matrix": A.T @ f["mass_matrix"](theta)[0] @ A,
                "coriolis_vector": A.T @ f["coriolis_vector"](theta, theta_d)[0],
                "gravity_vector": A.T @ f["gravity_vector"](theta)[0],
                "friction": A.T @ f["friction"](theta_d)[0],
                "inverse_dynamics": A.T @ f["inverse_dynamics"](theta, theta_d, theta_dd)[0],
                "potential_energy": f["potential_energy"](theta)[0],
                "kinetic_energy": f["kinetic_energy"](theta, theta_d)[0]}
        for name, value in want.items():
            arity = {"mass_matrix": 1, "gravity_vector": 1, "potential_energy": 1, "friction": 0,
                     "inverse_dynamics": 3}.get(name, 2)
            args = (qd,) if arity == 0 else (q, qd, qdd)[:arity]
            got = c[name](*args)[0]
            # the same chain arithmetic, summed through A: a few roundings of the largest term
            assert np.max(np.abs(got - value)) <= DYNAMICS * max(1.0, np.max(np.abs(value))), (name, got, value)


def test_the_coupled_coriolis_matrix_is_the_christoffel_form_of_the_reduced_mass_matrix(arms):
    _, (coupled, cd) = arms
    M, C, V = (reference_function(coupled, cd[n]) for n in ("mass_matrix", "coriolis_matrix", "coriolis_vector"))
    rng = np.random.default_rng(14)
    q, qd = rng.uniform(-2, 2, 2), rng.uniform(-2, 2, 2)
    step = 1e-6
    # dM/dt by central differences along qd: truncation O(step^2), rounding eps |M| / step
    Mdot = (M(q + step * qd)[0] - M(q - step * qd)[0]) / (2 * step)
    Cq = C(q, qd)[0]
    np.testing.assert_allclose(Cq @ qd, V(q, qd)[0], rtol=0, atol=DYNAMICS * max(1.0, np.abs(Cq).max()))
    skew = Mdot - 2 * Cq
    assert np.max(np.abs(skew + skew.T)) <= 1e-8 * max(1.0, np.abs(Mdot).max()), skew


@pytest.mark.parametrize(("mimic", "message"), [
    ("{joint: j9}", "mimics 'j9', no joint of the chain"),
    ("{joint: j3}", "mimics 'j3', the joint itself"),
    ("{joint: j1, multiplier: 0}", "multiplier of 0"),
])
def test_a_bad_mimic_is_a_located_error(mimic, message):
    with pytest.raises(ModelError, match=message) as error:
        model_from_text(_coupled(ODD_ARM, {"j3": mimic}))
    assert "mimic" in str(error.value)


def test_a_follower_of_a_follower_is_refused():
    with pytest.raises(ModelError, match="mimics 'j3', a joint that mimics another"):
        model_from_text(_coupled(ODD_ARM, {"j3": "{joint: j1}", "j4": "{joint: j3}"}))


def test_pinocchio_with_native_mimic_joints_agrees(arms):
    """An independent reference: Pinocchio's own mimic joints (JointModelMimic, buildModelFromXML(mimic=True))
    on the URDF that symkin exports, which carries the <mimic> elements.  Pinocchio's mimic needs bounded
    revolute joints (a continuous one has two configuration entries), so the joints get limits here."""
    import pinocchio as pin  # a test dependency: missing, this test fails

    from symkin.model.urdf_export import export_urdf

    arm = ODD_ARM
    for name in ("j1", "j3", "j4"):
        arm = arm.replace(f"{{name: {name},", f"{{name: {name}, limits: [-3, 3],")
    model = model_from_text(_coupled(arm, FOLLOWERS))
    derivation = Derivation(model)
    reference = pin.buildModelFromXML(export_urdf(model), mimic=True)
    assert reference.nq == reference.nv == model.dof == 2
    gravity = np.array([float(g.xreplace(model.parameter_values)) for g in model.gravity])
    reference.gravity = pin.Motion(np.concatenate([gravity, np.zeros(3)]))
    data = reference.createData()
    fk, M, V, G = (reference_function(model, derivation[n])
                   for n in ("fk", "mass_matrix", "coriolis_vector", "gravity_vector"))
    tcp = reference.getFrameId("tcp")
    rng = np.random.default_rng(15)
    for _ in range(4):
        q, qd, qdd = rng.uniform(-1.5, 1.5, 2), rng.uniform(-2, 2, 2), rng.uniform(-3, 3, 2)
        pin.framesForwardKinematics(reference, data, q)
        np.testing.assert_allclose(fk(q)[0], data.oMf[tcp].homogeneous, rtol=0, atol=KINEMATICS)
        mass = pin.crba(reference, data, q)
        mass = np.triu(mass) + np.triu(mass, 1).T
        np.testing.assert_allclose(M(q)[0], mass, rtol=0, atol=DYNAMICS * np.abs(mass).max())
        tau = pin.rnea(reference, data, q, qd, qdd)  # without friction: Pinocchio's RNEA has none
        ours = M(q)[0] @ qdd + V(q, qd)[0] + G(q)[0]
        np.testing.assert_allclose(ours, tau, rtol=0, atol=DYNAMICS * max(1.0, np.abs(tau).max()))


@pytest.mark.parametrize(("couplings", "message"), [
    ({"j3": '"j1 * j2"'}, "is not affine in the coordinates"),
    ({"j3": '"sin(j1)"'}, "is not affine in the coordinates"),
    ({"j3": '"j9 + 1"'}, "j9"),
    ({"j3": '"0.3"'}, "names no coordinate: the joint would be fixed"),
    ({"j3": '"j4"', "j4": '"j3"'}, "joint 'j3' moves with 'j4', a joint that mimics another"),
    ({"j3": '"2 * j1"', "j4": '"j3 + j2"'}, "joint 'j4' moves with 'j3', a joint that mimics another"),
])
def test_a_bad_coupling_is_a_located_error(couplings, message):
    with pytest.raises(ModelError, match=message) as error:
        model_from_text(_coupled(ODD_ARM, couplings, "coupling"), file="arm.yaml")
    assert "arm.yaml:" in str(error.value)
    assert "coupling" in str(error.value)
