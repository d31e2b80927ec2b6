"""The Agile Eye (models/agile_eye.yaml): a spherical 3-RRR platform, the distance form on the unit sphere.

Independent oracles: the Agile Eye's inverse kinematics in closed form from the rotation matrix (each leg's
middle axis perpendicular to its platform axis: theta_1 = atan2(-R23, R33), theta_2 = atan2(-R31, R11),
theta_3 = atan2(-R12, R22); Bonev, Chablat and Wenger 2006), finite differences of it, and rotation matrices
composed here with numpy.
"""

from __future__ import annotations

import os
import subprocess

import numpy as np
import pytest

from symkin import load, load_model
from symkin.analysis import orientations
from symkin.errors import DerivationError
from symkin.derivation import Derivation
from symkin.model.schema import PlatformMotion
from symkin.runtime.parallel import solve_fk
from symkin.structure.mobility import model_mobility
from conftest import MODELS_DIR, SYMKIN_CLI
from tolerances import CLOSED_FORM, KINEMATICS, NEWTON


@pytest.fixture(scope="module")
def eye(generated_dir):
    return load(generated_dir / "agile_eye")


def rotation(p):
    """R = Rz(yaw) Ry(pitch) Rx(roll) of rows p = (roll, pitch, yaw)."""
    roll, pitch, yaw = np.moveaxis(np.asarray(p), -1, 0)
    c, s = np.cos, np.sin
    return np.stack([
        np.stack([c(yaw) * c(pitch), c(yaw) * s(pitch) * s(roll) - s(yaw) * c(roll),
                  c(yaw) * s(pitch) * c(roll) + s(yaw) * s(roll)], axis=-1),
        np.stack([s(yaw) * c(pitch), s(yaw) * s(pitch) * s(roll) + c(yaw) * c(roll),
                  s(yaw) * s(pitch) * c(roll) - c(yaw) * s(roll)], axis=-1),
        np.stack([-s(pitch), c(pitch) * s(roll), c(pitch) * c(roll)], axis=-1)], axis=-2)


def agile_eye_ik(p):
    R = rotation(p)
    return np.stack([np.arctan2(-R[..., 1, 2], R[..., 2, 2]), np.arctan2(-R[..., 2, 0], R[..., 0, 0]),
                     np.arctan2(-R[..., 0, 1], R[..., 1, 1])], axis=-1)


def random_orientations(seed, count, spread=0.5):
    return np.random.default_rng(seed).uniform(-spread, spread, (count, 3))


def test_the_model_is_spherical_with_lambda_three(models):
    parallel = models["agile_eye"].parallel
    assert parallel.motion is PlatformMotion.SPHERICAL
    assert parallel.coordinates == ("roll", "pitch", "yaw")
    report = model_mobility(models["agile_eye"])
    assert (report.lam, report.bodies, report.joints, report.mobility) == (3, 8, 9, 3)


def test_inverse_kinematics_is_the_agile_eyes_closed_form(eye):
    p = random_orientations(1, 500)
    q, margin = eye.ik(p)
    assert np.all(margin > 0)
    assert np.max(np.abs(q - agile_eye_ik(p))) <= 4 * CLOSED_FORM


def test_the_home_orientation_is_isotropic(eye):
    p = np.zeros(3)
    q = eye.ik(p).joints
    assert np.allclose(q, 0.0, atol=CLOSED_FORM)
    assert np.allclose(eye.jacobian(q, p), np.eye(3), atol=CLOSED_FORM)


def test_inverse_jacobian_matches_finite_differences_of_the_closed_form(eye):
    p = random_orientations(2, 40)
    h = 1e-6
    J_fd = np.stack([(agile_eye_ik(p + h * e) - agile_eye_ik(p - h * e)) / (2 * h) for e in np.eye(3)], axis=-1)
    J_inv = eye.inverse_jacobian(agile_eye_ik(p), p)
    # central differences: truncation h^2 |q'''| / 6 ~ 1e-12, rounding eps / h ~ 2e-10
    assert np.allclose(J_inv, J_fd, rtol=0, atol=1e-8)
    assert np.allclose(np.einsum("...ij,...jk->...ik", eye.jacobian(agile_eye_ik(p), p), J_inv), np.eye(3), atol=1e-9)


def test_the_closed_form_fk_inverts_the_ik_over_the_workspace(eye):
    """FK(IK(R)) = R to rounding (kappa(J^-1) times a few eps) at every sampled orientation whose actuators lie
    within their limits; a configuration outside the home pose's working mode is not claimed (ik(fk(q)) = q
    is the working-mode test of symkin.mechanism.reach)."""
    p = random_orientations(7, 4000, spread=1.2)
    q = eye.ik(p).joints
    inside = np.all(np.abs(q) <= np.deg2rad(60), axis=-1)
    assert inside.sum() > 1000
    p, q = p[inside], q[inside]
    solution = eye.fk(q)
    assert np.all(solution.margin >= 0)
    kappa = np.linalg.cond(eye.inverse_jacobian(q, p))
    error = np.max(np.abs(rotation(solution.orientation) - rotation(p)), axis=(-2, -1))
    assert np.all(error <= KINEMATICS * kappa)


def test_the_closed_form_fk_returns_the_home_pose(eye, models):
    home = np.array([float(e) for e in models["agile_eye"].parallel.home])
    assert np.max(np.abs(eye.fk(eye.ik(home).joints).orientation - home)) <= CLOSED_FORM


def test_forward_kinematics_by_newton_returns_the_orientation(eye):
    p = random_orientations(3, 200)
    q = eye.ik(p).joints
    report = solve_fk(eye, q, np.zeros(3))
    assert report.all_converged
    kappa = np.linalg.cond(eye.inverse_jacobian(q, p))
    error = np.max(np.abs(rotation(report.solution) - rotation(p)), axis=(-2, -1))
    assert np.all(error <= NEWTON * kappa)


def passive_joints(q, p):
    """Each leg's middle and top angles by hand: leg k's axes are x, y, z permuted cyclically (P_k maps x to its
    actuator axis), so P_k^T R P_k = Rx(theta) Ry(s1) Rz(s2) and Rx(theta)^T P_k^T R P_k = Ry(s1) Rz(s2) =
    [[c1 c2, -c1 s2, s1], [s2, c2, 0], [-s1 c2, s1 s2, c1]]."""
    R = rotation(p)
    e = np.eye(3)
    s = []
    for k, theta in enumerate(q):
        P = np.stack([e[k], e[(k + 1) % 3], e[(k + 2) % 3]], axis=-1)
        M = rotation(np.array([theta, 0.0, 0.0])).T @ P.T @ R @ P
        s += [np.arctan2(M[0, 2], M[2, 2]), np.arctan2(M[1, 0], M[1, 1])]
    return np.array(s)


def test_the_closure_vanishes_at_the_assembly(eye):
    """At q = ik(p) and the passive joints found by hand, every leg's end frame is the platform's."""
    p = np.array([0.2, -0.1, 0.3])
    q = eye.ik(p).joints
    phi = eye.closure(q, passive_joints(q, p), p)
    assert np.max(np.abs(phi)) <= KINEMATICS
    # and a passive joint off by 1e-3 rad shows in the residual
    moved = passive_joints(q, p) + np.eye(6)[3] * 1e-3
    assert np.max(np.abs(eye.closure(q, moved, p))) > 1e-4


def test_a_leg_whose_axis_misses_the_centre_has_no_distance_form(tmp_path):
    text = (MODELS_DIR / "agile_eye.yaml").read_text().replace(
        "{name: mid, type: R, axis: [0, 1, 0]}", "{name: mid, type: R, axis: [0, 1, 0], origin: {xyz: [0.01, 0, 0]}}", 1)
    (tmp_path / "bent.yaml").write_text(text)
    with pytest.raises(DerivationError, match="does not pass through the centre"):
        Derivation(load_model(tmp_path / "bent.yaml"))["ik"]


def test_orientation_workspace_measure_matches_uniformly_random_rotations(eye):
    """Rotations drawn uniformly from SO(3) (scipy's Haar sampler), reachable where every leg's closed-form angle
    lies within its +-60 deg limits: the fraction times 8 pi^2 against the |cos pitch| integral over the chart."""
    from scipy.spatial.transform import Rotation

    yaw_pitch_roll = Rotation.random(200_000, random_state=5).as_euler("ZYX")
    q = agile_eye_ik(yaw_pitch_roll[:, ::-1])
    reachable = np.all(np.abs(q) <= np.deg2rad(60.0), axis=-1)
    fraction = reachable.mean()
    monte_carlo = fraction * orientations.SO3_MEASURE
    sigma = orientations.SO3_MEASURE * np.sqrt(fraction * (1 - fraction) / len(q))
    result = orientations.orientation_gci(eye, samples=2**16, seed=0)
    assert abs(result.measure.value - monte_carlo) <= 4 * sigma + result.measure.error
    assert 0 < result.value.value < 1


def test_the_gci_command_states_the_measure_of_orientations(generated_dir):
    run = subprocess.run([*SYMKIN_CLI, "gci", str(generated_dir / "agile_eye"), "--samples", "4096"],
                         capture_output=True, text=True, env=dict(os.environ, SYMKIN_QUIET="1"))
    assert run.returncode == 0, run.stderr
    assert "rad^3" in run.stdout
    assert "invariant measure of SO(3)" in run.stdout
    refused = subprocess.run([*SYMKIN_CLI, "gci", str(generated_dir / "agile_eye"), "--map", "map.png"],
                             capture_output=True, text=True)
    assert refused.returncode == 2
    assert "spherical platform" in refused.stderr


def test_the_orientation_cloud_holds_the_reachable_orientations_with_their_conditioning(eye):
    p, values = orientations.orientation_cloud(eye, 4096, seed=1)
    q, margin = eye.ik(p)
    assert np.all(np.isfinite(q))
    assert np.all(np.abs(q) <= np.deg2rad(60) * (1 + CLOSED_FORM))  # the actuators' limits of models/agile_eye.yaml
    # the cloud's values are (|cos pitch| 1/kappa) / |cos pitch| of the integrand: one rounding
    np.testing.assert_allclose(values, orientations.inverse_condition(eye, q, p), rtol=CLOSED_FORM, atol=0)
    # 8.9 % of SO(3) in the Haar measure; the chart's uniform density puts more of the samples near pitch = 0
    assert 0.05 < len(p) / 4096 < 0.2


def test_the_workspace_command_draws_the_orientations_and_states_their_measure(eye, generated_dir, tmp_path):
    figure = tmp_path / "eye.png"
    run = subprocess.run([*SYMKIN_CLI, "workspace", str(generated_dir / "agile_eye"), "-n", "4096", "-o", str(figure)],
                         capture_output=True, text=True, env=dict(os.environ, SYMKIN_QUIET="1"))
    assert run.returncode == 0, run.stderr
    measure = orientations.orientation_gci(eye, samples=4096, seed=0).measure
    assert f"orientation workspace {measure.value:.4g} +- {measure.error:.2g} rad^3" in run.stdout
    assert figure.stat().st_size > 0
    refused = subprocess.run([*SYMKIN_CLI, "workspace", str(generated_dir / "agile_eye"),
                              "--map", str(tmp_path / "m.png"), "-o", str(tmp_path / "w.png")],
                             capture_output=True, text=True)
    assert refused.returncode == 2
    assert "spherical platform" in refused.stderr
    assert not (tmp_path / "m.png").exists()
    assert not (tmp_path / "w.png").exists()


# --------------------------------------------------------------------------- dynamics against MuJoCo

#: each leg's frame P_k: leg 1 the base frame, leg 2 turned by x -> y -> z -> x, leg 3 twice (the model's bases)
LEG_FRAMES = [np.roll(np.eye(3), k, axis=0) for k in range(3)]


def arc_inertial(mass, radius, plane):
    """A MuJoCo <inertial> of a thin quarter arc of ``radius`` from the first to the second axis of ``plane``
    (indices into x, y, z), integrated here: centre (2r/pi)(e_i + e_j), I = m r^2 [(1/2, 1/2, 1) on (i, j, k),
    -1/pi on (i, j)] about the centre of rotation, moved to the centre of mass."""
    i, j = plane
    com = np.zeros(3)
    com[[i, j]] = 2 * radius / np.pi
    about_centre = np.zeros((3, 3))
    k = 3 - i - j
    about_centre[i, i] = about_centre[j, j] = mass * radius**2 / 2
    about_centre[k, k] = mass * radius**2
    about_centre[i, j] = about_centre[j, i] = -mass * radius**2 / np.pi
    I = about_centre - mass * (com @ com * np.eye(3) - np.outer(com, com))
    full = " ".join(f"{v:.17g}" for v in (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]))
    return f'<inertial pos="{com[0]:.17g} {com[1]:.17g} {com[2]:.17g}" mass="{mass:.17g}" fullinertia="{full}"/>'


def mujoco_agile_eye(v):
    """The Agile Eye as MuJoCo sees it: three hinge chains (actuator x, middle y, platform z in each leg's frame),
    the arcs integrated by :func:`arc_inertial`, the camera on leg 1's last body, legs 2 and 3 welded to it."""
    import mujoco

    from mujoco_reference import TINY_INERTIA, TINY_MASS

    tiny = f'<inertial pos="0 0 0" mass="{TINY_MASS}" diaginertia="{TINY_INERTIA} {TINY_INERTIA} {TINY_INERTIA}"/>'
    camera = (f'<inertial pos="0 0 0" mass="{v["m_camera"]}" diaginertia="{v["I_camera"]} {v["I_camera"]} '
              f'{v["I_camera"]}"/>')
    legs = []
    for i, frame in enumerate(LEG_FRAMES, start=1):
        axes = " ".join(f"{c:.17g}" for c in np.concatenate([frame[:, 0], frame[:, 1]]))
        legs.append(
            f'<body name="proximal{i}" xyaxes="{axes}"><joint name="theta{i}" axis="1 0 0" armature="{v["J_rotor"]}"/>'
            f'{arc_inertial(v["m_p"], v["r_p"], (0, 1))}'
            f'<body name="distal{i}"><joint name="mid{i}" axis="0 1 0"/>{arc_inertial(v["m_d"], v["r_d"], (1, 2))}'
            f'<body name="top{i}"><joint name="top{i}" axis="0 0 1"/>{camera if i == 1 else tiny}</body></body></body>')
    xml = (f'<mujoco><option gravity="0 0 -9.81"/><worldbody>{"".join(legs)}</worldbody>'
           '<equality><weld body1="top2" body2="top1"/><weld body1="top3" body2="top1"/></equality></mujoco>')
    model = mujoco.MjModel.from_xml_string(xml)
    return model, mujoco.MjData(model)


def tree_angles(q, p):
    """Every joint angle of the three chains at the assembly (q, p): theta, then :func:`passive_joints`' middle and
    top angles, per leg."""
    passive = passive_joints(q, p).reshape(3, 2)
    return np.concatenate([[theta, *angles] for theta, angles in zip(q, passive)])


def test_dynamics_with_the_distal_arcs_match_mujoco_with_the_legs_welded(models, eye):
    """M and tau (gravity, rotors, proximal and distal arcs with their full inertia, the camera) against MuJoCo's
    tree of the three chains closed by two welds, reduced to the actuated joints."""
    pytest.importorskip("mujoco")
    from mujoco_reference import MUJOCO_AGREEMENT, reduced_dynamics

    values = {p.name: float(p.value) for p in models["agile_eye"].parameters}
    reference, data = mujoco_agile_eye(values)
    rng = np.random.default_rng(3)
    for p in random_orientations(4, 8):
        q = eye.ik(p).joints
        qd, qdd = rng.uniform(-3, 3, 3), rng.uniform(-30, 30, 3)
        M_ref, tau_ref = reduced_dynamics(reference, data, tree_angles(q, p), [0, 3, 6], [1, 2, 4, 5, 7, 8], qd, qdd)
        M = eye.mass_matrix(q, p)
        assert np.max(np.abs(M - M_ref)) <= MUJOCO_AGREEMENT * np.max(np.abs(M_ref))
        tau = eye.inverse_dynamics(q, p, qd, qdd)
        assert np.max(np.abs(tau - tau_ref)) <= MUJOCO_AGREEMENT * np.max(np.abs(tau_ref))


def test_the_task_space_form_and_the_power_balance_of_the_dynamics(eye):
    """Along platform paths p + t pd + t^2/2 pdd (q = ik(p), rates by differences, h = 1e-4: second differences
    ~ eps / h^2 ~ 2e-8 relative): tau = J^T (Mx pdd + Vx + Gx) (the operational space, with the distal arcs
    carried into p) and tau . qd = d(k + u)/dt."""
    rng = np.random.default_rng(17)
    h = 1e-4

    def motion(p, pd, pdd, step):
        q = lambda t: eye.ik(p + t * pd + t * t / 2 * pdd).joints  # noqa: E731
        q0, plus, minus = q(0.0), q(step), q(-step)
        return q0, (plus - minus) / (2 * step), (plus - 2 * q0 + minus) / step**2

    for p in random_orientations(5, 5):
        pd, pdd = rng.uniform(-2, 2, 3), rng.uniform(-20, 20, 3)
        q, qd, qdd = motion(p, pd, pdd, h)
        tau = eye.inverse_dynamics(q, p, qd, qdd)
        Mx, Vx, Gx = eye.operational_space(q, p, qd)
        F = Mx @ pdd + Vx + Gx
        scale = np.abs(eye.jacobian(q, p).T) @ (np.abs(Mx) @ np.abs(pdd) + np.abs(Vx) + np.abs(Gx))
        assert np.max(np.abs(eye.jacobian(q, p).T @ F - tau)) <= 1e-5 * scale.max()

        def energy(t):
            pt = p + t * pd + t * t / 2 * pdd
            qt, qdt, _ = motion(pt, pd + t * pdd, pdd, 1e-5)
            return eye.kinetic_energy(qt, pt, qdt) + eye.potential_energy(qt, pt)
        power = (energy(h) - energy(-h)) / (2 * h)
        assert abs(tau @ qd - power) <= 1e-5 * (np.abs(tau) @ np.abs(qd))


def test_a_free_frictionless_motion_keeps_its_energy(eye):
    """The operational-space dynamics in p (q = ik(p), qd = J^-1 pd) integrated for 0.2 s without efforts: k + u
    stays constant to the integrator's tolerance (a wrong Vx would feed or drain energy)."""
    from scipy.integrate import solve_ivp

    rtol = 1e-11

    def state(y):
        p, pd = y[:3], y[3:]
        q = eye.ik(p).joints
        return q, p, eye.inverse_jacobian(q, p) @ pd

    def rate(_t, y):
        Mx, Vx, Gx = eye.operational_space(*state(y))
        return np.concatenate([y[3:], np.linalg.solve(Mx, -Vx - Gx)])

    solution = solve_ivp(rate, (0.0, 0.2), [0.1, -0.2, 0.15, 2.0, -1.0, 1.5], method="DOP853", rtol=rtol,
                         atol=rtol * 1e-2)
    assert solution.success
    kinetic = np.array([eye.kinetic_energy(*state(y)) for y in solution.y.T])
    potential = np.array([eye.potential_energy(*state(y)[:2]) for y in solution.y.T])
    bound = 10 * len(solution.t) * rtol * (kinetic.max() + np.abs(potential).max())
    assert np.ptp(kinetic + potential) <= bound
    assert np.ptp(solution.y[0]) > 0.1  # it moved


@pytest.mark.parametrize("model,old,new,key,message", [
    ("agile_eye.yaml", "  rotor: {inertia: J_rotor", "  rod: {mass: m_d}\n  rotor: {inertia: J_rotor", "bodies.rod",
     "a spherical leg has no rod between point joints"),
    ("agile_eye.yaml", "  rotor: {inertia: J_rotor", "  rod: {inertia: 1e-6}\n  rotor: {inertia: J_rotor", "bodies.rod",
     "a spherical leg has no rod between point joints"),
    ("pantograph.yaml", "  rod: {mass: m_distal, platform_fraction: 1/2, inertia: m_distal*L^2/12}",
     "  distal_link: {mass: m_distal}",
     "bodies.distal_link", "a distal link's own inertia is derived for spherical legs only"),
])
def test_the_link_between_the_last_two_joints_is_declared_as_the_legs_kind_needs(tmp_path, model, old, new, key,
                                                                                 message):
    from symkin.errors import ModelError

    text = (MODELS_DIR / model).read_text()
    assert old in text
    path = tmp_path / model
    path.write_text(text.replace(old, new))
    with pytest.raises(ModelError) as error:
        load_model(path)
    assert key in str(error.value)
    assert message in str(error.value)
    assert "fix:" in str(error.value)


def test_a_spherical_platform_whose_links_are_not_at_90_degrees_has_no_closed_form_fk(tmp_path):
    text = (MODELS_DIR / "agile_eye.yaml").read_text()
    old = "{name: top, type: R, axis: [0, 0, 1]}"
    assert old in text
    (tmp_path / "tilted.yaml").write_text(text.replace(old, "{name: top, type: R, axis: [0, 1, 1]}"))
    derivation = Derivation(load_model(tmp_path / "tilted.yaml"))
    assert derivation["ik"] is not None  # the legs keep their distance form and closed-form ik
    with pytest.raises(DerivationError, match="middle and platform axes stay at 90 deg"):
        derivation["fk"]
