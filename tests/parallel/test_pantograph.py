"""The five-bar pantograph (models/pantograph.yaml): a planar platform point on two RRR legs.

Independent oracles: the pantograph's geometry written out here (the elbows on circles about the
motor axes, the handle where the distal links meet, by the law of cosines), finite differences of
that closed form, and the mobility of a planar mechanism (eq. 8.2 with lambda = 3).
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import MODELS_DIR as MODELS
from symkin import analysis, load, load_model, pipeline
from symkin.errors import ModelError
from symkin.model.schema import PlatformMotion
from symkin.structure.mobility import model_mobility
from mujoco_reference import MUJOCO_AGREEMENT, TINY_INERTIA, TINY_MASS, reduced_dynamics
from tolerances import KINEMATICS, PANTOGRAPH_SCALE

D, L_PROX, L_DIST = 0.038, 0.07, 0.09
MOTORS = np.array([[-D / 2, 0.0], [D / 2, 0.0]])


@pytest.fixture(scope="module")
def pantograph(generated_dir):
    return load(generated_dir / "pantograph")


def elbows(q):
    """C_i = A_i + l (cos q_i, sin q_i)."""
    q = np.asarray(q)
    return MOTORS + L_PROX * np.stack([np.cos(q), np.sin(q)], axis=-1)


def handle(q, side=1):
    """The handle by the law of cosines: from C_1, at the angle acos(|C1C2| / 2L) off the line C_1 -> C_2,
    on its left (side = +1, a positive turn about z) or right (-1)."""
    C = elbows(q)
    u = C[..., 1, :] - C[..., 0, :]
    distance = np.linalg.norm(u, axis=-1)
    angle = np.arctan2(u[..., 1], u[..., 0]) + side * np.arccos(distance / (2 * L_DIST))
    return C[..., 0, :] + L_DIST * np.stack([np.cos(angle), np.sin(angle)], axis=-1)


def sample_joint_angles(rng, count):
    """Elbows-out configurations around the home pose with the handle on the +y side."""
    q = np.stack([rng.uniform(np.deg2rad(70), np.deg2rad(170), count),
                  rng.uniform(np.deg2rad(10), np.deg2rad(110), count)], axis=-1)
    C = elbows(q)
    spread = np.linalg.norm(C[:, 1] - C[:, 0], axis=-1)
    q = q[(spread > 0.02) & (spread < 1.8 * L_DIST)]
    return q[elbows_out(q, handle(q))]


def elbows_out(q, p):
    """The model's IK branches: the handle at a negative turn about z from elbow 1 (seen from motor 1), at a
    positive one from elbow 2 (seen from motor 2)."""
    C = elbows(q)
    arm, reach = C - MOTORS, p[:, None, :] - MOTORS
    turn = [arm[:, i, 0] * reach[:, i, 1] - arm[:, i, 1] * reach[:, i, 0] for i in range(2)]
    return (turn[0] < 0) & (turn[1] > 0)


def test_the_model_is_planar_with_two_coordinates(models):
    parallel = models["pantograph"].parallel
    assert parallel.coordinates == ("x", "y")
    assert parallel.motion is PlatformMotion.PLANAR
    assert parallel.task_dof == 2


def test_mobility_is_two_with_lambda_three_and_the_handle_spin_idle(models):
    report = model_mobility(models["pantograph"])
    # 5 bodies of the five-bar and the handle point (a platform body), 6 revolute joints: 3 (6 - 6 - 1) + 6 = 3,
    # less the handle's spin about its joint (an identical condition): 2
    assert (report.lam, report.bodies, report.joints, report.identical) == (3, 6, 6, 1)
    assert report.mobility == report.intended == 2


def test_forward_kinematics_is_the_circle_intersection(pantograph):
    rng = np.random.default_rng(1)
    q = sample_joint_angles(rng, 400)
    p, margin = pantograph.fk(q)
    assert np.all(margin > 0)
    expected = handle(q)
    J = pantograph.jacobian(q, expected)
    kappa = np.linalg.cond(J)
    error = np.linalg.norm(p - expected, axis=-1)
    assert np.all(error <= KINEMATICS * PANTOGRAPH_SCALE * kappa)


def test_inverse_kinematics_inverts_the_forward_kinematics(pantograph):
    rng = np.random.default_rng(2)
    q = sample_joint_angles(rng, 400)
    p = handle(q)
    q_back, margin = pantograph.ik(p)
    assert np.all(margin > 0)
    J_inv = pantograph.inverse_jacobian(q, p)
    kappa = np.linalg.cond(J_inv)
    assert np.max(np.abs(q_back - q) / kappa[:, None]) <= KINEMATICS


def test_jacobian_matches_finite_differences_of_the_closed_form(pantograph):
    rng = np.random.default_rng(3)
    q = sample_joint_angles(rng, 50)
    h = 1e-6
    columns = [(handle(q + h * e) - handle(q - h * e)) / (2 * h) for e in np.eye(2)]
    J_fd = np.stack(columns, axis=-1)
    J = pantograph.jacobian(q, handle(q))
    # central differences: truncation h^2 |f'''| / 6 <= 1e-12 * L, rounding eps L / h ~ 2e-11 m
    assert np.allclose(J, J_fd, rtol=0, atol=1e-9)
    assert np.allclose(np.einsum("...ij,...jk->...ik", pantograph.inverse_jacobian(q, handle(q)), J),
                       np.eye(2), atol=1e-9)


def test_the_closure_vanishes_at_an_assembly(pantograph):
    q = np.array([2.2, 0.9])
    p = handle(q)
    points = pantograph.leg_points(q, p)
    C = points[[1, 4], :2]
    assert np.allclose(C, elbows(q), atol=KINEMATICS * PANTOGRAPH_SCALE)
    # passive joints: elbow angle and handle angle of each leg (the platform does not turn)
    s = []
    for i in range(2):
        distal = np.arctan2(*(p - C[i])[::-1])
        s += [distal - q[i], -distal]
    phi = pantograph.closure(q, np.array(s), p)
    assert np.max(np.abs(phi)) <= KINEMATICS * PANTOGRAPH_SCALE


def test_both_assembly_modes(tmp_path):
    text = (MODELS / "pantograph.yaml").read_text().replace("fk_branch: positive", "fk_branch: negative")
    (tmp_path / "pantograph.yaml").write_text(text)
    model = load_model(tmp_path / "pantograph.yaml")
    pipeline.write(pipeline.generate(model, pipeline.resolve_request(model, "fk,jacobian", "numpy")), tmp_path / "out")
    mirrored = load(tmp_path / "out" / "pantograph", backend="numpy")
    q = np.array([2.0, 1.0])
    p, _ = mirrored.fk(q)
    expected = handle(q, side=-1)
    assert np.linalg.norm(expected - handle(q)) > 0.05  # the other assembly mode, far from the first
    kappa = np.linalg.cond(mirrored.jacobian(q, expected))
    assert np.linalg.norm(p - expected) <= KINEMATICS * PANTOGRAPH_SCALE * kappa


@pytest.mark.parametrize("motion, message", [
    ("[y, x]", "out of order"),
    ("[x, x]", "repeated or out of order"),
    ("[x, up]", "not a list of platform coordinates"),
    ("rotation", "unknown platform motion"),
])
def test_bad_motions_are_refused_with_a_fix(tmp_path, motion, message):
    text = (MODELS / "pantograph.yaml").read_text().replace("motion: [x, y]", f"motion: {motion}")
    (tmp_path / "bad.yaml").write_text(text)
    with pytest.raises(ModelError) as caught:
        load_model(tmp_path / "bad.yaml")
    assert "parallel.motion" in str(caught.value)
    assert message in str(caught.value)


def test_legs_that_do_not_match_the_declared_motion_count_actuators(tmp_path):
    text = (MODELS / "pantograph.yaml").read_text().replace("motion: [x, y]", "motion: translation")
    (tmp_path / "bad.yaml").write_text(text)
    with pytest.raises(ModelError, match=r"3 degrees of freedom \(x, y, z\) but the legs have 2 active joints"):
        load_model(tmp_path / "bad.yaml")



def independent_ik(p):
    """Actuator angles of handle points p (N, 2) by circle intersection, elbows out, NaN where a leg cannot reach:
    elbow i on the circle of radius l about motor i and of radius L about p, on the side the branch names."""
    q = np.full(p.shape, np.nan)
    for i, side in ((0, 1.0), (1, -1.0)):  # elbow 1 to the left of motor 1 -> p, elbow 2 to the right of motor 2 -> p
        u = p - MOTORS[i]
        distance = np.linalg.norm(u, axis=-1)
        with np.errstate(invalid="ignore"):
            spread = np.arccos((L_PROX**2 + distance**2 - L_DIST**2) / (2 * L_PROX * distance))
        q[:, i] = np.arctan2(u[:, 1], u[:, 0]) + side * spread
    return q


def test_workspace_area_matches_a_monte_carlo_estimate_of_the_reachable_set(pantograph):
    rng = np.random.default_rng(4)
    lower, upper = np.array([-0.16, -0.16]), np.array([0.16, 0.18])
    points = rng.uniform(lower, upper, (400_000, 2))
    q = independent_ik(points)
    wrapped = np.angle(np.exp(1j * q))
    within = np.all((wrapped >= 0) & (wrapped <= np.pi), axis=-1)
    assembles = within & np.isfinite(q).all(axis=-1)
    # the working mode's assembly: the handle to the left of elbow 1 -> elbow 2 (fk_branch positive)
    C = elbows(np.where(assembles[:, None], q, 0.0))
    u, v = C[:, 1] - C[:, 0], points - C[:, 0]
    reachable = assembles & (u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0] > 0)
    box = float(np.prod(upper - lower))
    fraction = reachable.mean()
    monte_carlo = fraction * box
    sigma = box * np.sqrt(fraction * (1 - fraction) / len(points))
    measured = analysis.workspace_measure(pantograph, samples=2**16, seed=0)
    assert abs(measured.value - monte_carlo) <= 4 * sigma + measured.error


# --------------------------------------------------------------------------- dynamics against MuJoCo

def mujoco_five_bar(v):
    """The five-bar with the model's bodies as MuJoCo sees them: each proximal and distal link a uniform bar
    (the model's distal `rod` with its inertia across it, m L^2 / 12), the handle a point mass on distal link 1,
    the loop closed by a point constraint (connect) at the handle; the massless inertias TINY
    (:mod:`mujoco_reference`)."""
    import mujoco

    d, l, L = v["d"], v["l"], v["L"]
    bar, distal_bar = v["m_proximal"] * l**2 / 12, v["m_distal"] * L**2 / 12
    point = f'diaginertia="{TINY_INERTIA} {TINY_INERTIA} {TINY_INERTIA}"'
    legs = []
    for i, x in ((1, -d / 2), (2, d / 2)):
        handle = (f'<body name="handle" pos="{L} 0 0"><inertial pos="0 0 0" mass="{v["m_handle"]}" '
                  f'{point}/><site name="handle1"/></body>' if i == 1 else f'<site name="handle2" pos="{L} 0 0"/>')
        legs.append(
            f'<body name="proximal{i}" pos="{x} 0 0">'
            f'<joint name="theta{i}" type="hinge" axis="0 0 1" armature="{v["J_rotor"]}"/>'
            f'<inertial pos="{l / 2} 0 0" mass="{v["m_proximal"]}" diaginertia="{TINY_INERTIA} {bar} {bar}"/>'
            f'<body name="distal{i}" pos="{l} 0 0"><joint name="elbow{i}" type="hinge" axis="0 0 1"/>'
            f'<inertial pos="{L / 2} 0 0" mass="{v["m_distal"]}" diaginertia="{TINY_INERTIA} {distal_bar} '
            f'{distal_bar}"/>{handle}</body></body>')
    xml = (f'<mujoco><option gravity="0 0 -9.81"/><worldbody>{"".join(legs)}</worldbody>'
           '<equality><connect site1="handle2" site2="handle1"/></equality></mujoco>')
    model = mujoco.MjModel.from_xml_string(xml)
    return model, mujoco.MjData(model)


def reduced_mujoco_dynamics(reference, data, q, qd, qdd):
    """(M, tau, p) of the five-bar in its actuated coordinates (:func:`mujoco_reference.reduced_dynamics`), the
    tree's passive angles from the closed-form handle."""
    C = elbows(q)
    p = handle(q)
    distal = [np.arctan2(*(p - C[i])[::-1]) for i in range(2)]
    position = np.array([q[0], distal[0] - q[0], q[1], distal[1] - q[1]])
    M, tau = reduced_dynamics(reference, data, position, [0, 2], [1, 3], qd, qdd)
    return M, tau, p


def test_dynamics_match_mujoco_with_the_loop_closed_by_an_equality(models, pantograph):
    values = {p.name: float(p.value) for p in models["pantograph"].parameters}
    reference, data = mujoco_five_bar(values)
    rng = np.random.default_rng(6)
    for q in sample_joint_angles(rng, 12):
        qd, qdd = rng.uniform(-2, 2, 2), rng.uniform(-20, 20, 2)
        M_ref, tau_ref, p = reduced_mujoco_dynamics(reference, data, q, qd, qdd)
        M = pantograph.mass_matrix(q, p)
        assert np.max(np.abs(M - M_ref)) <= MUJOCO_AGREEMENT * np.max(np.abs(M_ref))
        tau = pantograph.inverse_dynamics(q, p, qd, qdd)
        assert np.max(np.abs(tau - tau_ref)) <= MUJOCO_AGREEMENT * np.max(np.abs(tau_ref))


def test_a_free_frictionless_motion_keeps_its_energy(pantograph):
    """The forward dynamics in q (p = fk(q)) integrated for 0.2 s without actuator efforts: k + u stays constant to
    the integrator's tolerance (a wrong V would feed or drain energy)."""
    from scipy.integrate import solve_ivp

    rtol = 1e-11

    def state(y):
        q, qd = y[:2], y[2:]
        return q, pantograph.fk(q).position, qd

    def rate(_t, y):
        q, p, qd = state(y)
        return np.concatenate([qd, pantograph.forward_dynamics(q, p, qd, np.zeros(2))])

    y0 = np.concatenate([pantograph.ik(np.array([0.0, 0.1])).joints, [3.0, -2.0]])
    solution = solve_ivp(rate, (0.0, 0.2), y0, method="DOP853", rtol=rtol, atol=rtol * 1e-2)
    assert solution.success
    energies = np.array([pantograph.kinetic_energy(*state(y)) + pantograph.potential_energy(*state(y)[:2])
                         for y in solution.y.T])
    # the local errors of ~len(t) steps, each <= rtol relative to the state, times the energy's scale
    bound = 10 * len(solution.t) * rtol * np.max(np.abs(energies))
    assert np.ptp(energies) <= bound
    assert np.ptp(solution.y[0]) > 0.1  # it moved
