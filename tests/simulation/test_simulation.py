"""Simulation on the generated code: seed scenario, energy balance, integrator order, haptic
loop, UR10e tracking, CLI.

Oracles: the seed's closed-form 2R dynamics (eqs. 8.52, 8.53) and Jacobian (eq. 8.56),
the power balance d(k + u)/dt = qd . (tau - F_f), DOP853 at tight tolerance as the reference
of RK4's order, and the static equilibrium of springs in series for the virtual wall.
"""

from __future__ import annotations

import numpy as np
import pytest

from symkin import load
from symkin.cli import main
from symkin.errors import GeneratedCodeError
from symkin.simulation import ArmSystem, ComputedTorque, JointSine, Plant, run_adaptive, run_sampled
from symkin.simulation import scenarios
from tests.conftest import GENERATED_DIR, MODELS_DIR
from tolerances import CLOSED_FORM, DYNAMICS
from checks import assert_wall_equilibrium

SEED_CENTER = np.radians([45.0, 45.0])
SEED_DESIGNS = ({"l1": 0.1, "l2": 0.1}, {"l1": 0.2, "l2": 0.2})
G = 9.81


@pytest.fixture(scope="module")
def arm():
    return load(GENERATED_DIR / "planar_2r")


def seed_torques(q, qd, qdd, l1, l2, m1=0.1, m2=0.1):
    """Seed eqs. 8.52 and 8.53, written out."""
    t1, t2 = q[..., 0], q[..., 1]
    d1, d2 = qd[..., 0], qd[..., 1]
    a1, a2 = qdd[..., 0], qdd[..., 1]
    tau1 = ((m1 + m2) * l1 ** 2 * a1 + m2 * l2 ** 2 * (a1 + a2) + m2 * l1 * l2 * np.cos(t2) * (2 * a1 + a2)
            - m2 * l1 * l2 * np.sin(t2) * d2 ** 2 - 2 * m2 * l1 * l2 * np.sin(t2) * d1 * d2
            + m2 * l2 * G * np.cos(t1 + t2) + (m1 + m2) * l1 * G * np.cos(t1))
    tau2 = m2 * l2 * ((a1 + a2) * l2 + l1 * np.cos(t2) * a1 + l1 * np.sin(t2) * d1 ** 2 + G * np.cos(t1 + t2))
    return np.stack([tau1, tau2], axis=-1)


def seed_jacobian(q, l1, l2):
    t1, t12 = q[..., 0], q[..., 0] + q[..., 1]
    return np.stack([np.stack([-l1 * np.sin(t1) - l2 * np.sin(t12), -l2 * np.sin(t12)], -1),
                     np.stack([l1 * np.cos(t1) + l2 * np.cos(t12), l2 * np.cos(t12)], -1)], -2)


@pytest.fixture(scope="module")
def seed_result(arm):
    designs = [(str(d), Plant(arm.bind(**d))) for d in SEED_DESIGNS]
    return scenarios.sine(designs, SEED_CENTER, 1, np.radians(30.0), 1.0, scenarios.Timing(1.0, 200, "dop853"))


def test_seed_scenario_torques_and_forces_match_the_seed_closed_forms(seed_result):
    for design, series in zip(SEED_DESIGNS, seed_result.series):
        c = series.columns
        t = c["t [s]"]
        q = np.stack([c["theta1 [rad]"], c["theta2 [rad]"]], -1)
        assert np.all(q[:, 0] == SEED_CENTER[0])
        # one sine of angles <= 2 pi, scaled and shifted: CLOSED_FORM of the angles (<= pi)
        np.testing.assert_allclose(q[:, 1], SEED_CENTER[1] + np.radians(30) * np.sin(2 * np.pi * t), rtol=0,
                                   atol=CLOSED_FORM * np.pi)
        w = 2 * np.pi
        qd = np.stack([0 * t, np.radians(30) * w * np.cos(w * t)], -1)
        qdd = np.stack([0 * t, -np.radians(30) * w * w * np.sin(w * t)], -1)
        tau = np.stack([c["tau_theta1 [N m]"], c["tau_theta2 [N m]"]], -1)
        np.testing.assert_allclose(tau, seed_torques(q, qd, qdd, **design), rtol=0, atol=DYNAMICS * np.abs(tau).max())
        force = np.stack([c["F_x [N]"], c["F_y [N]"]], -1)
        J = seed_jacobian(q, **design)
        # F = J^-T tau is solved: backward stable, J^T F reproduces tau to eps x kappa(J) of its terms
        kappa = float(np.max(np.linalg.cond(J)))
        np.testing.assert_allclose(np.einsum("...ji,...j->...i", J, force), tau, rtol=0,  # seed eq. 8.35
                                   atol=DYNAMICS * kappa * np.abs(tau).max())
        # the seed's observation: tau1 > tau2, and the larger peak, in both designs
        assert np.all(tau[:, 0] > tau[:, 1])
        assert np.max(np.abs(tau[:, 0])) > np.max(np.abs(tau[:, 1]))
        # the forward simulation reproduces the prescribed motion with these torques
        simulated = np.stack([c["simulated theta1 [rad]"], c["simulated theta2 [rad]"]], -1)
        assert np.max(np.abs(simulated - q)) < 1e-8
        np.testing.assert_allclose(np.stack([c["simulated tau_theta1 [N m]"], c["simulated tau_theta2 [N m]"]], -1),
                                   tau, atol=1e-7)
    peaks = [np.max(np.abs(s.columns["tau_theta1 [N m]"])) for s in seed_result.series]
    assert peaks[1] > 2 * peaks[0]  # longer, heavier-loaded links need more than twice the torque


def test_tcp_force_is_the_generated_tcp_force(arm, seed_result):
    c = seed_result.series[0].columns
    t = c["t [s]"]
    q_r, qd_r, qdd_r = JointSine(SEED_CENTER, 1, np.radians(30), 1.0)(t)
    np.testing.assert_allclose(arm.tcp_force(q_r, qd_r, qdd_r), np.stack([c["F_x [N]"], c["F_y [N]"]], -1),
                               rtol=1e-10, atol=1e-12)


def test_tcp_forces_are_flagged_at_singular_configurations(arm):
    q = np.array([[0.3, 0.0], [0.3, 0.5]])
    tau = np.array([[0.1, 0.2], [0.1, 0.2]])
    force = scenarios.tcp_forces(arm.jacobian(q), tau)
    assert np.all(np.isnan(force[0]))
    np.testing.assert_allclose(seed_jacobian(q[1], 0.1, 0.1).T @ force[1], tau[1], rtol=1e-12)
    with pytest.raises(ValueError, match="square"):
        scenarios.tcp_forces(np.zeros((2, 3, 6)), np.zeros((2, 6)))


def test_free_swing_conserves_energy_to_the_tolerance(arm):
    result = scenarios.free_swing("", Plant(arm), SEED_CENTER, scenarios.Timing(1.0, 100, "dop853"))
    energy = result.series[0].columns["energy k + u [J]"]
    swing = result.series[0].columns["theta1 [rad]"]
    assert np.ptp(swing) > 1.0                                   # it really swings
    assert np.max(np.abs(energy - energy[0])) < 1e-8 * np.max(np.abs(energy))


FRICTION = """
friction:
  theta1: {viscous: 0.002, coulomb: 0.003, smoothing_velocity: 0.05}
  theta2: {viscous: 0.001}
"""


@pytest.fixture(scope="module")
def friction_dirs(tmp_path_factory):
    """planar_2r with friction, derived with and without the 'friction' function."""
    from symkin import pipeline
    from symkin.model import load_model

    root = tmp_path_factory.mktemp("friction")
    source = root / "planar_2r.yaml"
    source.write_text((MODELS_DIR / "planar_2r.yaml").read_text().replace("\nscene:", FRICTION + "\nscene:"))
    model = load_model(source)
    outputs = ["fk", "jacobian", "forward_dynamics", "inverse_dynamics", "mass_matrix", "kinetic_energy", "potential_energy",
               "gravity_vector", "coriolis_vector"]
    dirs = {}
    for name, extra in (("with", ["friction"]), ("without", [])):
        request = pipeline.resolve_request(model, outputs + extra, "numpy", None)
        dirs[name] = pipeline.write(pipeline.generate(model, request), root / name)
    return dirs


def test_energy_balance_with_friction_holds_to_the_tolerance(friction_dirs):
    plant = Plant(load(friction_dirs["with"]))
    system = ArmSystem(plant)
    reference = JointSine(SEED_CENTER, 1, np.radians(30), 1.0)
    q0, qd0, _ = reference(0.0)
    run = run_adaptive(system.derivative, ComputedTorque(system, reference), system.initial(q0, qd0),
                       np.linspace(0.0, 1.0, 401), rtol=1e-11, atol=1e-13)
    s = system.split(run.x)
    energy = plant.energy(s.q, s.qd)
    # d(k + u)/dt = qd . (tau - F_f): the accumulated work matches the energy change
    np.testing.assert_allclose(energy - energy[0], s.work, atol=1e-9 * np.max(np.abs(energy)))
    # independently: the trapezoidal integral of the power from the recorded states and torques
    power = np.einsum("ij,ij->i", s.qd, run.u - plant.friction(s.qd))
    trapezoid = np.concatenate([[0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(run.t))])
    np.testing.assert_allclose(trapezoid, s.work, atol=5e-4 * np.max(np.abs(s.work)))  # O(h^2)
    # friction dissipates: released from rest, the free swing loses energy
    free = scenarios.free_swing("", plant, SEED_CENTER, scenarios.Timing(1.0, 100, "dop853"))
    c = free.series[0].columns
    assert c["work of friction [J]"][-1] < -1e-4
    np.testing.assert_allclose(c["energy k + u [J]"] - c["energy k + u [J]"][0], c["work of friction [J]"],
                               atol=1e-9)


def test_a_plant_refuses_generated_code_without_friction_for_a_model_with_friction(friction_dirs, arm, tmp_path):
    with pytest.raises(GeneratedCodeError, match="friction"):
        Plant(load(friction_dirs["without"]))
    with pytest.raises(GeneratedCodeError, match="forward_dynamics"):
        from symkin import pipeline
        from symkin.model import load_model
        model = load_model(MODELS_DIR / "planar_2r.yaml")
        Plant(load(pipeline.write(pipeline.generate(model, pipeline.resolve_request(model, "fk", "numpy", None)),
                                  tmp_path)))


def test_rk4_converges_with_fourth_order(arm):
    system = ArmSystem(Plant(arm))
    x0 = system.initial(SEED_CENTER)
    zero = np.zeros(2)
    reference = run_adaptive(system.derivative, lambda t, x: zero, x0, np.array([0.0, 0.4]), rtol=1e-12,
                             atol=1e-14).x[-1]
    errors = [np.max(np.abs(run_sampled(system.derivative, lambda t, x: zero, x0, 0.4 / steps, steps).x[-1]
                            - reference)) for steps in (200, 400)]
    assert 11.0 < errors[0] / errors[1] < 32.0, errors   # 2^4 = 16 asymptotically; 3rd order: 8




def test_virtual_wall_settles_at_the_series_spring_equilibrium(arm):
    assert_wall_equilibrium(Plant(arm), SEED_CENTER, 1500)


def test_ur10e_follows_a_tcp_circle():
    plant = Plant(load(GENERATED_DIR / "ur10e"))
    q0 = np.array([0.3, -1.2, 1.4, -1.6, -1.5, 0.2])
    result = scenarios.tracking("", plant, q0, 0.05, scenarios.Timing(0.6, 1000, "rk4"), bandwidth=80.0)
    c = result.series[0].columns
    reference = np.stack([c[f"reference TCP {a} [m]"] for a in "xy"], -1)
    assert np.ptp(reference[:, 0]) > 0.099
    assert np.ptp(reference[:, 1]) > 0.099     # the circle is really drawn
    assert np.max(c["TCP error [m]"]) < 1e-4                    # with the torque held for 1 ms (ZOH)
    assert c["TCP error [m]"][-1] < 2e-5
    q = np.stack([c[f"q{i} [rad]"] for i in range(1, 7)], -1)
    tau = np.stack([c[f"tau_q{i} [N m]"] for i in range(1, 7)], -1)
    assert np.all(np.abs(tau) < plant.effort_limits)             # within the UR10e's declared torque limits
    assert plant.effort_limits.tolist() == [330, 330, 150, 56, 56, 56]  # models/ur10e.yaml, via the manifest
    assert any("effort limits of the model" in line and "within the limits" in line for line in result.summary)
    assert np.max(np.abs(q - q0)) < 0.5


def test_numpy_and_c_backends_simulate_the_same_haptic_loop(arm):
    runs = [scenarios.haptic_wall("", Plant(load(GENERATED_DIR / "planar_2r", backend)), SEED_CENTER, 0.005, 0.02,
                                  scenarios.Timing(0.3, 1000, "rk4")).series[0].columns for backend in ("numpy", "c")]
    assert np.max(runs[0]["penetration [m]"]) > 1e-3
    for name in ("tau_theta1 [N m]", "tau_theta2 [N m]", "F_felt_x [N]", "TCP x [m]"):
        np.testing.assert_allclose(runs[1][name], runs[0][name], rtol=1e-9, atol=1e-11)


def test_cli_writes_the_seed_figures_and_csv(tmp_path, capsys):
    out = tmp_path / "seed"
    assert main(["simulate", str(GENERATED_DIR / "planar_2r"), "--scenario", "sine", "--design", "l1=0.1,l2=0.1",
                 "--design", "l1=0.2,l2=0.2", "--duration", "1", "--rate", "100", "-o", str(out)]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert {"fig-8-21-torques.png", "fig-8-22-tcp-forces.png", "summary.txt"} <= set(names)
    assert sum(n.endswith(".csv") for n in names) == 2
    assert (out / "fig-8-21-torques.png").read_bytes()[:4] == b"\x89PNG"
    lines = (out / "sine-1-l1=10cm_l2=10cm.csv").read_text().splitlines()
    assert lines[1].startswith("t [s],theta1 [rad],theta2 [rad],tau_theta1 [N m]")
    assert len(lines) == 2 + 101
    assert "tau_theta1 > tau_theta2 at every sample: yes" in capsys.readouterr().out


def test_cli_derives_a_model_file_on_the_fly(tmp_path, capsys):
    out = tmp_path / "swing"
    assert main(["simulate", str(MODELS_DIR / "planar_2r.yaml"), "--scenario", "free-swing", "--duration", "0.2",
                 "--rate", "100", "--no-figure", "-o", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["free-swing-1-asdeclared.csv", "summary.txt"]


@pytest.mark.parametrize("arguments, message", [
    (["--q0", "1", "2", "3"], "has 2 joints"),
    (["--joint", "theta9"], "no joint 'theta9'"),
    (["--hand", "mass=1,stiffnes=3"], "unknown user parameters"),
    (["--set", "l9=1"], "l9"),
    (["--rate", "0"], "must be positive"),
    (["--joint-stops", "off", "--stop-time-constant", "0.01"], "the joint stops are off"),
    (["--stop-time-constant", "0"], "time constant must be positive"),
    (["--stop-damping-ratio", "-0.1"], "must not be negative"),
    (["--stop-stiffness", "theta9=100"], "no joint or stop 'theta9'"),
    (["--stop-stiffness", "theta1=-1"], "must be positive"),
    (["--stop-damping", "theta1"], "is not NAME=VALUE"),
    (["--joint-stops", "maybe"], "invalid choice"),
])
def test_bad_arguments_exit_with_code_2_and_write_nothing(arguments, message, tmp_path, capsys):
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as exit_info:
        main(["simulate", str(GENERATED_DIR / "planar_2r"), "-o", str(out)] + arguments)
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err
    assert not out.exists()
