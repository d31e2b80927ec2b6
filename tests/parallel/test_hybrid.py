"""Hybrid devices (models/delta_wrist.yaml): a DELTA whose platform carries a 3R wrist.

Independent oracles: Pinocchio's kinematics of the same device built here joint by joint (the platform's
translation as three prismatic joints, then the wrist), the wrist written out as rotation matrices, finite
differences through the DELTA's closed-form fk, and the located errors of wrist sections that cannot work.
"""

from __future__ import annotations

import dataclasses
import json
import subprocess

import numpy as np
import pinocchio as pin
import pytest

from conftest import MODELS_DIR, SYMKIN_CLI
from symkin import load, load_model
from symkin.derivation import Derivation
from symkin.errors import DerivationError, ModelError
from symkin.analysis import global_indices
from symkin.rating import formulas
from symkin.mechanism.device import WholeDevice
from symkin.mechanism import reach
from symkin.cli import main
from symkin.simulation import Plant, scenarios
from checks import assert_wall_equilibrium
from tolerances import CLOSED_FORM, DELTA_SCALE, DYNAMICS, EPS, KINEMATICS

W, H = 0.05, 0.03  # wrist centre below the platform, grip point along the handle (models/delta_wrist.yaml)


@pytest.fixture(scope="module")
def device(generated_dir):
    return load(generated_dir / "delta_wrist")


def rot(axis: str, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return {"x": np.array([[1, 0, 0], [0, c, -s], [0, s, c]]), "y": np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
            "z": np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])}[axis]


def written_out(p: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """base_T_tcp: the platform at p (no rotation), down w to the wrist centre, Rz(psi1) Rx(psi2) Ry(psi3),
    the grip point h along the handle's y axis."""
    R = rot("z", psi[0]) @ rot("x", psi[1]) @ rot("y", psi[2])
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = p + np.array([0, 0, -W]) + R @ np.array([0, H, 0])
    return T


def pinocchio_device() -> tuple[pin.Model, int]:
    """The device as Pinocchio's serial chain in (x, y, z, psi1, psi2, psi3), and its TCP frame."""
    model = pin.Model()
    parent = 0
    for name, joint in (("x", pin.JointModelPX()), ("y", pin.JointModelPY()), ("z", pin.JointModelPZ())):
        parent = model.addJoint(parent, joint, pin.SE3.Identity(), name)
    wrist_centre = pin.SE3(np.eye(3), np.array([0, 0, -W]))
    parent = model.addJoint(parent, pin.JointModelRZ(), wrist_centre, "psi1")
    parent = model.addJoint(parent, pin.JointModelRX(), pin.SE3.Identity(), "psi2")
    parent = model.addJoint(parent, pin.JointModelRY(), pin.SE3.Identity(), "psi3")
    tool = model.addFrame(pin.Frame("tcp", parent, 0, pin.SE3(np.eye(3), np.array([0, H, 0])), pin.FrameType.OP_FRAME))
    return model, tool


def random_device_states(device, count: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q, p, psi): assembled DELTA poses around the home pose (q = ik(p)) and wrist angles within the limits."""
    rng = np.random.default_rng(seed)
    p = np.array([0, 0, -0.15]) + rng.uniform(-0.04, 0.04, (count, 3))
    q, margin = device.ik(p)
    keep = np.all(margin > 0, axis=-1)
    psi = rng.uniform(np.deg2rad([-120, -70, -160]), np.deg2rad([120, 70, 160]), (count, 3))
    return q[keep], p[keep], psi[keep]


def test_the_device_moves_by_its_platform_and_its_wrist(models):
    model = models["delta_wrist"]
    wrist = model.parallel.wrist
    assert [j.name for j in wrist.coordinates] == ["psi1", "psi2", "psi3"]
    assert model.task_space == ("x", "y", "z")
    assert model.dof == 3  # the legs' actuators; the wrist's joints on top


def test_the_manifest_records_the_wrist_coordinates_with_their_limits(device):
    wrist = device.info.wrist
    assert [c.name for c in wrist] == ["psi1", "psi2", "psi3"]
    assert all(c.revolute for c in wrist)
    assert np.allclose([c.limits for c in wrist], np.deg2rad([[-120, 120], [-70, 70], [-160, 160]]), rtol=0,
                       atol=CLOSED_FORM * np.pi)
    assert [c.name for c in device.info.coordinates] == ["theta1", "theta2", "theta3"]


def test_device_fk_and_jacobian_agree_with_pinocchio_and_the_written_out_wrist(device):
    q, p, psi = random_device_states(device, 60, seed=1)
    model, tool = pinocchio_device()
    data = model.createData()
    T = device.device_fk(p, psi)
    J_c = device.device_jacobian(p, psi)
    for k in range(len(p)):
        c = np.concatenate([p[k], psi[k]])
        pin.forwardKinematics(model, data, c)
        pin.updateFramePlacements(model, data)
        assert np.allclose(T[k], data.oMf[tool].homogeneous, rtol=0, atol=KINEMATICS * DELTA_SCALE)
        assert np.allclose(T[k], written_out(p[k], psi[k]), rtol=0, atol=KINEMATICS * DELTA_SCALE)
        J_pin = pin.computeFrameJacobian(model, data, c, tool, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        assert np.allclose(J_c[k], J_pin, rtol=0, atol=KINEMATICS * DELTA_SCALE)


def test_the_actuator_jacobian_is_the_chain_rule_through_the_platform(device):
    q, p, psi = random_device_states(device, 40, seed=2)
    J_a = device.device_actuator_jacobian(q, p, psi)
    J_c = device.device_jacobian(p, psi)
    J = device.jacobian(q, p)
    kappa = np.linalg.cond(J)
    chain_rule = np.concatenate([J_c[..., :3] @ J, J_c[..., 3:]], axis=-1)
    assert np.all(np.max(np.abs(J_a - chain_rule), axis=(-2, -1)) <= KINEMATICS * DELTA_SCALE * kappa)
    # finite differences of the TCP position through the DELTA's closed-form fk: p = fk(q), then the wrist
    h = 1e-6
    columns = []
    for e in np.eye(6):
        up, _ = device.fk(q + h * e[:3])
        down, _ = device.fk(q - h * e[:3])
        columns.append((device.device_fk(up, psi + h * e[3:])[..., :3, 3]
                        - device.device_fk(down, psi - h * e[3:])[..., :3, 3]) / (2 * h))
    # central differences: truncation h^2 |f'''| / 6 and rounding eps L / h, both below 1e-9 m per rad here
    assert np.allclose(J_a[..., :3, :], np.stack(columns, axis=-1), rtol=0, atol=1e-8)


def test_a_delta_without_wrist_has_no_device_quantities(models):
    with pytest.raises(DerivationError, match="carries no wrist"):
        Derivation(models["delta"])["device_fk"]


@pytest.mark.parametrize("edit, message", [
    (("- {name: psi1,", "- {name: theta1,"), "clashes with the variable 'theta1'"),
    (("link: fork2,", "link: platform,"), "the wrist link 'platform' is a name the platform's motion takes"),
    (("  chain:\n    - {name: psi1", "  chain:\n    - {name: psi1, parent: nowhere"), "hangs on 'nowhere'"),
    (("      inertia: {yy: m_handle", "      inertia: {yy: -m_handle"), "wrist.bodies[2].inertia"),
])
def test_a_wrist_that_cannot_work_is_a_located_error(tmp_path, edit, message):
    text = (MODELS_DIR / "delta_wrist.yaml").read_text()
    assert edit[0] in text
    path = tmp_path / "device.yaml"
    path.write_text(text.replace(edit[0], edit[1], 1))
    with pytest.raises(ModelError, match=message.replace("[", r"\[").replace("(", r"\(")):
        load_model(path)


def test_a_wrist_on_a_serial_chain_is_refused_on_the_command_line(tmp_path):
    path = tmp_path / "arm.yaml"
    path.write_text((MODELS_DIR / "planar_2r.yaml").read_text() + "\nwrist:\n  chain:\n    - {name: w1}\n")
    run = subprocess.run([*SYMKIN_CLI, "check", str(path)], capture_output=True, text=True)
    assert run.returncode == 2
    assert "a wrist is carried by a parallel platform" in run.stderr
    assert "arm.yaml" in run.stderr


# --------------------------------------------------------------------------- the dynamics of the whole device

M_PLATFORM = 0.021  # the DELTA's platform plate without the handle (models/delta_wrist.yaml)
STEP = 1e-5


def pinocchio_device_with_bodies() -> tuple[pin.Model, int]:
    """:func:`pinocchio_device` with the wrist's bodies (models/delta_wrist.yaml; the platform joints massless)."""
    model, tool = pinocchio_device()
    bar = 0.04 ** 2 / 12  # slender forks of 40 mm
    r, length = 0.01, 0.08  # the handle, a cylinder along its y axis
    bodies = {"psi1": pin.Inertia(0.012, np.zeros(3), np.diag([0.012 * bar, 0.012 * bar, 0])),
              "psi2": pin.Inertia(0.009, np.zeros(3), np.diag([0, 0.009 * bar, 0.009 * bar])),
              "psi3": pin.Inertia(0.03, np.array([0, H, 0]), 0.03 * np.diag([(3 * r * r + length ** 2) / 12, r * r / 2,
                                                                              (3 * r * r + length ** 2) / 12]))}
    for name, inertia in bodies.items():
        model.appendBodyToJoint(model.getJointId(name), inertia, pin.SE3.Identity())
    return model, tool


@pytest.fixture(scope="module")
def delta(generated_dir):
    """The DELTA alone (models/delta.yaml: the same legs, arms, rods and rotors; its platform carries the handle)."""
    return load(generated_dir / "delta")


def test_the_device_dynamics_are_the_deltas_and_pinocchios_wrist_through_the_platform_jacobian(device, delta):
    """M = diag(M_delta, 0) + B^T M_w B and G = (G_delta, 0) + B^T G_w, B = diag(J, 1): the DELTA's dynamics with
    the plate alone on its platform, and the wrist's in (p, qw) by Pinocchio's CRBA and gravity."""
    q, p, psi = random_device_states(device, 30, seed=3)
    model, _ = pinocchio_device_with_bodies()
    data = model.createData()
    M, G = device.mass_matrix(q, p, psi), device.gravity_vector(q, p, psi)
    M_delta, G_delta = delta.mass_matrix(q, p, m_platform=M_PLATFORM), delta.gravity_vector(q, p, m_platform=M_PLATFORM)
    J = delta.jacobian(q, p)
    for k in range(len(p)):
        c = np.concatenate([p[k], psi[k]])
        B = np.block([[J[k], np.zeros((3, 3))], [np.zeros((3, 3)), np.eye(3)]])
        M_w = pin.crba(model, data, c)
        M_w = np.triu(M_w) + np.triu(M_w, 1).T
        expected_M = B.T @ M_w @ B
        expected_M[:3, :3] += M_delta[k]
        expected_G = B.T @ pin.computeGeneralizedGravity(model, data, c)
        expected_G[:3] += G_delta[k]
        # J enters twice (kappa_degree 2): the DYNAMICS budget times kappa(J)^2 of the entries' scale
        kappa = np.linalg.cond(J[k])
        assert np.max(np.abs(M[k] - expected_M)) <= DYNAMICS * kappa ** 2 * np.abs(expected_M).max()
        assert np.max(np.abs(G[k] - expected_G)) <= DYNAMICS * kappa * np.abs(expected_G).max()


def test_the_device_coriolis_vector_follows_from_its_mass_matrix(device):
    """Lagrange in u = (q, qw): V = dM/dt ud - 1/2 d(ud^T M ud)/du with M(u) = mass_matrix(q, fk(q), qw)."""
    rng = np.random.default_rng(4)

    def M(u):
        return device.mass_matrix(u[:3], device.fk(u[:3])[0], u[3:])

    q, p, psi = random_device_states(device, 4, seed=4)
    for k in range(len(p)):
        u, ud = np.concatenate([q[k], psi[k]]), rng.uniform(-2, 2, 6)
        Mdot = (M(u + STEP * ud) - M(u - STEP * ud)) / (2 * STEP)
        dT = np.array([ud @ (M(u + STEP * e) - M(u - STEP * e)) @ ud / (2 * STEP) for e in np.eye(6)])
        V = device.coriolis_vector(q[k], p[k], psi[k], ud[:3], ud[3:])
        assert np.allclose(V, Mdot @ ud - dT / 2, rtol=0, atol=1e-7 * np.abs(M(u)).max() * ud @ ud)


def test_the_inverse_dynamics_is_m_v_g_the_forward_dynamics_inverts_it_and_power_balances(device):
    rng = np.random.default_rng(5)
    q, p, psi = random_device_states(device, 4, seed=5)
    for k in range(len(p)):
        ud, udd = rng.uniform(-2, 2, 6), rng.uniform(-5, 5, 6)
        args = (q[k], p[k], psi[k])
        tau = device.inverse_dynamics(*args, ud[:3], ud[3:], udd[:3], udd[3:])
        M, V, G = device.mass_matrix(*args), device.coriolis_vector(*args, ud[:3], ud[3:]), device.gravity_vector(*args)
        scale = np.abs(M) @ np.abs(udd) + np.abs(V) + np.abs(G)
        assert np.all(np.abs(tau - (M @ udd + V + G)) <= DYNAMICS * scale.max())
        back = device.forward_dynamics(*args, ud[:3], ud[3:], tau[:3], tau[3:])
        assert np.allclose(back, udd, rtol=0, atol=DYNAMICS * np.linalg.cond(M) * np.abs(udd).max())

        def energy(t):
            u = np.concatenate([q[k], psi[k]]) + t * ud + t * t / 2 * udd
            at = (u[:3], device.fk(u[:3])[0], u[3:])
            rates = ud + t * udd
            return device.kinetic_energy(*at, rates[:3], rates[3:]) + device.potential_energy(*at)
        h = 1e-4
        power = (energy(h) - energy(-h)) / (2 * h)
        assert abs(tau @ ud - power) <= 1e-5 * (np.abs(tau) @ np.abs(ud))


def test_a_free_motion_keeps_its_energy(device):
    """No effort, no friction: k + u stays constant along the forward dynamics, integrated in u = (q, qw)
    with p = fk(q) at every step, to the integrator's tolerance."""
    from scipy.integrate import solve_ivp

    q, p, psi = random_device_states(device, 1, seed=6)
    zero = np.zeros(3)

    def rates(_t, x):
        q, qw, qd, qwd = x[:3], x[3:6], x[6:9], x[9:]
        udd = device.forward_dynamics(q, device.fk(q)[0], qw, qd, qwd, zero, zero)
        return np.concatenate([qd, qwd, udd])

    def energy(x):
        q, qw, qd, qwd = x[:3], x[3:6], x[6:9], x[9:]
        at = (q, device.fk(q)[0], qw)
        return device.kinetic_energy(*at, qd, qwd) + device.potential_energy(*at)

    start = np.concatenate([q[0], psi[0], [0.5, -0.3, 0.2], [2.0, -1.0, 3.0]])
    run = solve_ivp(rates, (0, 0.1), start, method="DOP853", rtol=1e-11, atol=1e-12, dense_output=False)
    assert run.success
    energies = np.array([energy(x) for x in run.y.T])
    swing = np.abs(energies[0]) + device.kinetic_energy(q[0], p[0], psi[0], start[6:9], start[9:])
    assert np.max(np.abs(energies - energies[0])) <= 1e-8 * swing


Z0 = np.radians([-15.0, -10.0, -20.0, 20.0, -30.0, 40.0])  # the legs' theta, then the wrist's psi


@pytest.fixture(scope="module")
def plant(device):
    return Plant(device)


@pytest.fixture(scope="module")
def motorized(tmp_path_factory):
    """The device with motors on its wrist: models/delta_wrist.yaml without its wrist's ``active: false``."""
    out = tmp_path_factory.mktemp("motorized")
    text = (MODELS_DIR / "delta_wrist.yaml").read_text()
    assert text.count(", active: false}") == 3
    (out / "delta_wrist.yaml").write_text(text.replace(", active: false}", "}"))
    assert main(["derive", str(out / "delta_wrist.yaml"), "-o", str(out), "--backend", "numpy", "-q"]) == 0
    return Plant(load(out / "delta_wrist"))


def test_the_plant_of_a_hybrid_device_is_its_legs_and_wrist_with_the_wrists_tcp(plant, device):
    assert plant.coordinates == ("theta1", "theta2", "theta3", "psi1", "psi2", "psi3")
    assert plant.joint_limits[4].tolist() == pytest.approx(np.radians([-70.0, 70.0]).tolist(), rel=CLOSED_FORM)
    q, psi = Z0[:3], Z0[3:]
    p = device.fk(q).position
    np.testing.assert_allclose(plant.point(Z0), written_out(p, psi)[:3, 3], rtol=0, atol=KINEMATICS * DELTA_SCALE)
    assert np.array_equal(plant.point_jacobian(Z0), device.device_actuator_jacobian(q, p, psi)[:3])
    qd, tau = np.array([0.3, -0.2, 0.1, 1.0, -2.0, 0.5]), np.array([0.01, -0.02, 0.03, 0.004, -0.002, 0.001])
    assert np.array_equal(plant.acceleration(Z0, qd, tau), device.forward_dynamics(q, p, psi, qd[:3], qd[3:],
                                                                                    tau[:3], tau[3:]))
    assert np.array_equal(plant.energy(Z0, qd), device.kinetic_energy(q, p, psi, qd[:3], qd[3:])
                          + device.potential_energy(q, p, psi))
    assert plant.passive == ("psi1", "psi2", "psi3")               # models/delta_wrist.yaml: active: false
    assert plant.drive(tau).tolist() == [0.01, -0.02, 0.03, 0.0, 0.0, 0.0]


def test_a_passive_wrist_gets_no_actuator_effort_and_keeps_the_power_balance(plant):
    """The renderer's command reaches the DELTA's motors only; the wrist moves under the hand, its weight
    and its stops, and k + u + U + D - w stays constant (the work w counts the efforts actually exerted)."""
    result = scenarios.haptic_wall("", plant, Z0, 0.01, 0.02, scenarios.Timing(0.3, 1000, "dop853"),
                                   stops=scenarios.StopSettings())
    c = result.series[0].columns
    for name in ("psi1", "psi2", "psi3"):
        assert not np.any(c[f"tau_{name} [N m]"])
    assert np.max(np.abs(c["tau_theta1 [N m]"])) > 0.01
    assert np.max(c["penetration psi1 [rad]"]) > 0.01        # the wrist swings (here into psi1's stop)
    drift = float(next(line for line in result.summary if "energy balance drift" in line)
                  .split("energy balance drift ")[1].split()[0])
    assert drift < 1e-6


@pytest.mark.parametrize("scenario", ["sine", "tracking"])
def test_prescribing_a_passive_wrists_motion_is_refused_with_exit_2(scenario, generated_dir, tmp_path, capsys):
    with pytest.raises(SystemExit) as exit:
        main(["simulate", str(generated_dir / "delta_wrist"), "--scenario", scenario, "-o", str(tmp_path / "out")])
    assert exit.value.code == 2
    assert "psi1, psi2, psi3 are passive" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_motorized_wrist_renders_a_wall_at_the_series_spring_equilibrium(motorized):
    """The hand's force reaches every actuator through J_a^T, the wrist's included: at rest the renderer's
    wrist torques balance the hand's moment about the wrist, and the hand feels the wall."""
    assert not motorized.passive
    assert_wall_equilibrium(motorized, Z0, 2000)


def test_a_motorized_wrist_is_held_while_the_handle_follows_a_tcp_circle(motorized):
    result = scenarios.tracking("", motorized, Z0, 0.02, scenarios.Timing(0.6, 1000, "rk4"), bandwidth=80.0)
    c = result.series[0].columns
    psi = np.stack([c[f"psi{i} [rad]"] for i in (1, 2, 3)], -1)
    assert np.max(np.abs(psi - Z0[3:])) < 1e-4                  # the wrist holds its angles...
    assert np.max(c["TCP error [m]"]) < 1e-4                      # ...while the handle draws the circle
    assert np.ptp(c["reference TCP x [m]"]) > 0.039


def test_cli_simulates_a_hybrid_device(generated_dir, tmp_path):
    run = subprocess.run([*SYMKIN_CLI, "simulate", str(generated_dir / "delta_wrist"), "--scenario", "haptic-wall",
                          "--duration", "0.3", "--backend", "c", "-o", str(tmp_path / "out")],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert "|tau_psi2| <= 0 N m" in run.stdout
    assert "peak felt force" in run.stdout
    assert (tmp_path / "out" / "haptic-wall.png").read_bytes()[:4] == b"\x89PNG"


def test_the_whole_device_is_its_legs_and_wrist_with_the_grip_as_tcp(device, generated_dir):
    view = WholeDevice(device)
    assert view.info.coordinate_names == ("theta1", "theta2", "theta3", "psi1", "psi2", "psi3")
    assert view.info.task_space == ("x", "y", "z", "wx", "wy", "wz")
    T = view.fk(Z0)
    np.testing.assert_allclose(T, written_out(device.fk(Z0[:3]).position, Z0[3:]), rtol=0,
                               atol=KINEMATICS * DELTA_SCALE)
    out_of_reach = np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0])       # the arms up: the legs do not assemble
    assert np.all(np.isnan(view.fk(out_of_reach)))
    assert not np.any(view.jacobian(out_of_reach))
    with pytest.raises(ValueError, match="no wrist"):
        WholeDevice(load(generated_dir / "delta"))


def test_the_whole_devices_gci_is_a_monte_carlo_of_its_homogenized_actuator_jacobian(device):
    """GCI = int g |det J_a| dz / int |det J_a| dz over the legs' and the wrist's joint box, g = 1/kappa of J_a
    with its translational rows divided by L, against a plain Monte-Carlo written here with the raw generated
    functions (the working mode checked as ik(fk(q)) = q); both are estimates, compared within four standard
    errors of their difference."""
    view = WholeDevice(device)
    limits = np.array(view.joint_limits)
    length = reach.characteristic_length_of(view, limits)
    ours = global_indices.global_index(view, method="qmc", samples=2**14, seed=0, length=length)
    rng = np.random.default_rng(31)
    z = rng.uniform(limits[:, 0], limits[:, 1], (2**15, 6))
    q, psi = z[:, :3], z[:, 3:]
    with np.errstate(invalid="ignore"):
        p = device.fk(q).position
        inside = np.isfinite(p).all(axis=1)
        inside[inside] = np.all(np.abs(device.ik(p[inside]).joints - q[inside]) < 1e-9, axis=1)
    J = device.device_actuator_jacobian(q[inside], p[inside], psi[inside])
    weight = np.abs(np.linalg.det(J))
    scaled = J.copy()
    scaled[:, :3] /= length
    sigma = np.linalg.svd(scaled, compute_uv=False)
    g = sigma[:, -1] / sigma[:, 0]
    numerator, denominator = np.zeros(len(z)), np.zeros(len(z))
    numerator[inside], denominator[inside] = weight * g, weight
    reference = numerator.mean() / denominator.mean()
    residual = (numerator - reference * denominator) / denominator.mean()   # the ratio estimator's error
    error = residual.std() / np.sqrt(len(z))
    standard_error = ours.value.error / ours.integral.quantile           # its half-width over its quantile
    assert abs(ours.value.value - reference) < 4 * np.hypot(error, standard_error)


def test_cli_analyses_the_whole_device_and_refuses_a_model_without_wrist(generated_dir, tmp_path, capsys):
    assert main(["gci", str(generated_dir / "delta_wrist"), "--device", "-n", "4096", "--seed", "0"]) == 0
    text = capsys.readouterr().out
    assert "characteristic length L" in text
    assert "m^3 rad^3" in text
    assert main(["workspace", str(generated_dir / "delta_wrist"), "--device", "-n", "4096",
                 "-o", str(tmp_path / "device.png")]) == 0
    assert (tmp_path / "device.png").read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(SystemExit) as exit:
        main(["gci", str(generated_dir / "delta"), "--device"])
    assert exit.value.code == 2
    assert "has no wrist" in capsys.readouterr().err


def test_the_grip_feels_the_mass_the_forward_dynamics_accelerates_with_a_push(device, plant):
    """Lambda = (J_p M^-1 J_p^T)^-1 of the whole device at its grip point (J_p the translational rows of J_a, M
    the device's mass matrix in z): a unit force at the grip, mapped to the joints by J_p^T and fed to the
    generated forward dynamics from rest (the wrist free: no motor holds it), accelerates the grip by the
    mobility J_p M^-1 J_p^T (the weight's acceleration subtracted)."""
    view = WholeDevice(device)
    J = view.jacobian(Z0)[:3]
    still = np.zeros(6)
    falling = J @ plant.acceleration(Z0, still, still)
    mobility = np.array([J @ plant.acceleration(Z0, still, J.T @ force) - falling for force in np.eye(3)]).T
    Lambda = formulas.apparent_mass(view.mass_matrix(Z0), J)
    np.testing.assert_allclose(Lambda @ mobility, np.eye(3), rtol=0, atol=1e-9)


def test_the_operational_space_at_the_tcp_gives_the_device_efforts_and_the_grips_apparent_mass(device):
    """F = Mx xdd + Vx + Gx at the wrist's TCP, xdd = J_a udd + dJ_a/dt ud (J_a = device_actuator_jacobian, u = (q, qw)):
    J_a^T F is the device's M udd + V + G.  At rest (Vx = 0) exactly, so Mx and Gx are checked to rounding; in motion
    at udd = 0 with dJ_a/dt ud by central differences along the motion (q + t qd, fk, qw + t qwd).  The translational
    block of Mx^-1 = J_a M^-1 J_a^T is the inverse of the apparent mass symkin rate --device quotes at the grip."""
    q, p, psi = random_device_states(device, 6, seed=8)
    rng = np.random.default_rng(9)
    step = 1e-6
    finite_difference = 100 * EPS / step  # rounding of J_a over 2 step; the truncation (step^2 times J's third
    still = np.zeros(3)                    # derivative) is far below it
    for k in range(len(p)):
        args = (q[k], p[k], psi[k])
        J_a, M = device.device_actuator_jacobian(*args), device.mass_matrix(*args)
        udd, ud = rng.uniform(-5, 5, 6), rng.uniform(-2, 2, 6)
        Mx, Vx, Gx = device.operational_space(*args, still, still)
        expected = M @ udd + device.gravity_vector(*args)
        kappa = np.linalg.cond(J_a)
        assert np.abs(Vx).max() == 0.0  # no motion, no velocity terms
        # J_a^-1 enters Mx and Gx twice and once, J_a^T maps them back: the budget times kappa(J_a)^2
        assert np.abs(J_a.T @ (Mx @ J_a @ udd + Gx) - expected).max() <= DYNAMICS * kappa ** 2 * np.abs(expected).max()

        def J(t):
            moved = q[k] + t * ud[:3]
            return device.device_actuator_jacobian(moved, device.fk(moved)[0], psi[k] + t * ud[3:])

        Jdot_ud = (J(step) - J(-step)) / (2 * step) @ ud
        Mx, Vx, _ = device.operational_space(*args, ud[:3], ud[3:])
        V = device.coriolis_vector(*args, ud[:3], ud[3:])
        assert np.abs(J_a.T @ (Mx @ Jdot_ud + Vx) - V).max() <= finite_difference * kappa ** 2 * np.abs(V).max()
        Lambda = formulas.apparent_mass(M, J_a[:3])
        grip = np.linalg.inv(np.linalg.inv(Mx)[:3, :3])
        assert np.abs(Lambda - grip).max() <= DYNAMICS * np.linalg.cond(M) * kappa ** 2 * np.abs(Lambda).max()


def test_a_device_whose_coordinates_do_not_span_the_tcps_twist_has_no_operational_space():
    """The DELTA with a 2R wrist (5 coordinates) cannot give its TCP every twist (Mx would not exist): refused."""
    model = load_model(MODELS_DIR / "delta_wrist.yaml")
    wrist = model.parallel.wrist
    joints = wrist.joints[:-1]
    links = {j.link for j in joints}
    shorter = dataclasses.replace(wrist, joints=joints, tip=joints[-1].link,
                                  bodies=tuple(b for b in wrist.bodies if b.link in links))
    two_r = dataclasses.replace(model, parallel=dataclasses.replace(model.parallel, wrist=shorter))
    with pytest.raises(DerivationError, match="as many device coordinates as the TCP's twist"):
        Derivation(two_r)["operational_space"]


def test_cli_rates_the_whole_device_at_its_grip(generated_dir, tmp_path):
    out = tmp_path / "rate"
    assert main(["rate", str(generated_dir / "delta_wrist"), "--device", "-n", "1000", "--no-figure",
                 "-o", str(out)]) == 0
    sheet = json.loads((out / "datasheet.json").read_text())
    view = WholeDevice(load(generated_dir / "delta_wrist"))
    home = np.array(sheet["home"]["q"])
    masses = formulas.principal_masses(view.mass_matrix(home), view.jacobian(home)[:3])
    assert sheet["measures"]["apparent_mass_min"]["home"] == pytest.approx(masses[0], rel=1e-9)
    assert sheet["measures"]["apparent_mass_max"]["home"] == pytest.approx(masses[-1], rel=1e-9)
    with pytest.raises(SystemExit) as exit:
        main(["rate", str(generated_dir / "delta_wrist"), "-o", str(tmp_path / "refused")])
    assert exit.value.code == 2
