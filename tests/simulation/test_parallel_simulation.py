"""Simulation of a parallel mechanism (issue 14): the DELTA of models/delta.yaml in its actuated
joints, the platform at p = fk(q), with the generated parallel dynamics.

Oracles: exact gravity compensation holds the device still (the residual acceleration is the
rounding of M^-1 (G - G)); the static equilibrium of the springs in series (hand, grip, virtual
wall) with the weight compensated; the numpy and C backends agree; the CLI writes the haptic
scenarios' figures and CSV and reports the felt force.
"""

from __future__ import annotations

import numpy as np
import pytest

from symkin import load
from symkin.cli import main
from symkin.simulation import ArmSystem, Plant, run_sampled
from symkin.simulation import scenarios, user
from checks import assert_wall_equilibrium
from tests.conftest import GENERATED_DIR
from tolerances import EPS

Q0 = np.radians([-15.0, -10.0, -20.0])


@pytest.fixture(scope="module")
def delta():
    return Plant(load(GENERATED_DIR / "delta"))


def test_the_plant_evaluates_the_dynamics_at_the_platform_pose_of_the_joints(delta):
    p = delta.pose(Q0)
    model = delta.model
    tau = np.array([0.01, -0.02, 0.03])
    assert np.array_equal(delta.acceleration(Q0, np.zeros(3), tau), model.forward_dynamics(Q0, p, np.zeros(3), tau))
    assert np.array_equal(delta.point(Q0), p)
    assert np.array_equal(delta.point_jacobian(Q0), model.jacobian(Q0, p))
    assert np.array_equal(delta.gravity(Q0), model.gravity_vector(Q0, p))


def test_gravity_compensation_holds_the_delta_still(delta):
    """Under tau = G(q) from rest, qdd = M^-1 (G - G) is rounding: each evaluation errs by <= ~64 kappa(M) eps
    |M^-1 G| (a backward-stable LDL^T solve of the generated terms), so in t seconds q moves by less than that
    times t^2 (twice the t^2/2 of a constant acceleration).  With the actuators off the DELTA falls."""
    system = ArmSystem(delta)
    steps, h = 300, 1e-3
    held = run_sampled(system.derivative, lambda t, x: delta.gravity(x[:3]), system.initial(Q0), h, steps)
    fallen = run_sampled(system.derivative, lambda t, x: np.zeros(3), system.initial(Q0), h, 50)  # before the legs stretch
    M, G = delta.mass_matrix(Q0), delta.gravity(Q0)
    free_fall = np.linalg.solve(M, G)
    bound = 64 * np.linalg.cond(M) * EPS * np.abs(free_fall).max() * (steps * h) ** 2
    assert np.abs(held.x[:, :3] - Q0).max() <= bound, (np.abs(held.x[:, :3] - Q0).max(), bound)
    assert np.abs(fallen.x[-1, :3] - Q0).max() > 1e6 * bound


def test_the_delta_renders_a_wall_at_the_series_spring_equilibrium(delta):
    assert_wall_equilibrium(delta, Q0, 2000)


def test_numpy_and_c_backends_simulate_the_same_delta_haptic_loop():
    runs = [scenarios.haptic_wall("", Plant(load(GENERATED_DIR / "delta", backend)), Q0, 0.005, 0.02,
                                  scenarios.Timing(0.3, 1000, "rk4")).series[0].columns for backend in ("numpy", "c")]
    assert np.max(runs[0]["penetration [m]"]) > 1e-3
    for name in ("tau_theta1 [N m]", "tau_theta3 [N m]", "F_felt_x [N]", "TCP x [m]"):
        np.testing.assert_allclose(runs[1][name], runs[0][name], rtol=1e-9, atol=1e-11)


@pytest.mark.parametrize("scenario, figure", [("haptic-wall", "haptic-wall.png"),
                                              ("gravity-compensation", "gravity-compensation.png")])
def test_cli_runs_the_haptic_scenarios_on_the_delta(scenario, figure, tmp_path, capsys):
    out = tmp_path / scenario
    assert main(["simulate", str(GENERATED_DIR / "delta"), "--scenario", scenario, "--duration", "0.5",
                 "-o", str(out)]) == 0
    names = {p.name for p in out.iterdir()}
    assert figure in names
    assert "summary.txt" in names
    assert any(n.endswith(".csv") for n in names)
    assert (out / figure).read_bytes()[:4] == b"\x89PNG"
    text = capsys.readouterr().out
    if scenario == "haptic-wall":
        assert "peak felt force" in text
        assert "desired" in text
    else:
        cut = text.split("cuts the peak force felt from ")[1].split(" N")
        without, with_compensation = float(cut[0]), float(cut[1].split("to ")[1])
        assert with_compensation < 0.5 * without
        csv = sorted(n for n in names if n.endswith(".csv"))
        assert csv == ["gravity-compensation-1-gravitycompensated_tau=G.csv",
                       "gravity-compensation-2-actuatorsoff_tau=0.csv"]


def test_a_parallel_model_without_closed_form_fk_is_refused_with_exit_code_2(tmp_path, capsys):
    assert main(["simulate", str(GENERATED_DIR / "stewart"), "--scenario", "free-swing", "-o", str(tmp_path / "out")]) == 2
    assert "closed-form fk" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_the_agile_eyes_turning_handle_rests_on_a_virtual_wall_at_the_series_spring_equilibrium():
    """A handle that only turns is held by its angles: a hand pulled 0.2 rad in roll beyond a wall 0.1 rad away
    (2 N m/rad) settles where the torsional springs in series balance, feeling the wall's moment, the weight
    compensated (:func:`test_simulation.assert_wall_equilibrium`)."""
    hand = {**user.TURNING.hand, "arm_damping": 0.2}  # overdamped: settled (1e-6) within the 1.5 s
    assert_wall_equilibrium(Plant(load(GENERATED_DIR / "agile_eye")), np.zeros(3), 1500, offset=0.1, stiffness=2.0,
                            damping=0.05, hand=hand)


def test_the_agile_eye_swings_with_its_energy_balanced_and_refuses_a_tcp_circle(tmp_path, capsys):
    """A spherical platform is a plant too (p = fk(q), its orientation): a free swing against its joint stops keeps
    k + u + the stops' work to the integrator's tolerance; a TCP circle has no TCP point to follow; a hand turns
    its handle into a virtual wall in the 1 kHz loop (its units N m/rad), its energy balanced."""
    out = tmp_path / "swing"
    assert main(["simulate", str(GENERATED_DIR / "agile_eye"), "--scenario", "free-swing", "--duration", "0.5",
                 "-o", str(out)]) == 0
    summary = (out / "summary.txt").read_text()
    drift = float(summary.split("energy balance drift ")[1].split()[0].rstrip(","))
    assert drift <= 1e-8, summary
    capsys.readouterr()
    with pytest.raises(SystemExit) as exit_info:
        main(["simulate", str(GENERATED_DIR / "agile_eye"), "--scenario", "tracking", "-o", str(tmp_path / "circle")])
    assert exit_info.value.code == 2
    assert "tracking follows a TCP circle, and this device's handle only turns (roll, pitch, yaw)" \
        in capsys.readouterr().err
    assert not (tmp_path / "circle").exists()
    out = tmp_path / "wall"
    assert main(["simulate", str(GENERATED_DIR / "agile_eye"), "--scenario", "haptic-wall", "--duration", "0.3",
                 "-o", str(out)]) == 0
    summary = (out / "summary.txt").read_text()
    assert "wall at roll = 0.1 rad (k_w = 2 N m/rad, b_w = 0.01 N m s/rad)" in summary
    assert float(summary.split("energy balance drift ")[1].split()[0].rstrip(",")) <= 1e-8, summary
    assert "F_felt_roll [N m]" in (out / "haptic-wall-1-asdeclared.csv").read_text()
