"""Issue 33, step 4: excitation trajectories (symkin excite) - a finite Fourier series per joint that makes the
stacked base regressor well conditioned, within the joint limits and the velocity and acceleration bounds.

References: the condition number of the optimum against the start's, both computed by numpy's SVD; the bounds
on a grid 50 times as dense as the criterion's samples; rest at t = 0 and periodicity; a run simulated along
the optimum (the model's inverse dynamics with noise) identified by symkin identify within its standard
deviations.
"""

from __future__ import annotations

import subprocess

import numpy as np
import pytest

from conftest import GENERATED_DIR, MODELS_DIR, SYMKIN_CLI
from symkin import pipeline
from symkin.identification import estimation
from symkin.identification import excitation
from symkin.model import model_from_text
from symkin.runtime.loader import load
from sample_models import DRIVEN
from tolerances import CLOSED_FORM

PERIOD, HARMONICS, SPEED, ACCELERATION = 4.0, 4, 2.0, 10.0


@pytest.fixture(scope="module")
def arm(tmp_path_factory):
    model = model_from_text(DRIVEN, "driven")
    request = pipeline.resolve_request(model, ("base_regressor", "inverse_dynamics"), "numpy,casadi", None, False,
                                       "none")
    directory = pipeline.write(pipeline.generate(model, request), tmp_path_factory.mktemp("excite"))
    return load(directory, "numpy"), load(directory, "casadi")


@pytest.fixture(scope="module")
def optimum(arm):
    return excitation.optimize_excitation(arm[1], period=PERIOD, harmonics=HARMONICS, max_velocity=SPEED,
                               max_acceleration=ACCELERATION, max_iterations=80)


def test_the_optimum_is_far_better_conditioned_than_the_start(arm, optimum):
    assert optimum.condition < optimum.condition_start / 10
    numpy_arm = arm[0]
    t = np.arange(optimum.samples) * PERIOD / optimum.samples
    W = numpy_arm.base_regressor(*optimum.states(t))[0].reshape(-1, 13)
    scaled = W / np.linalg.norm(W, axis=0)
    singular = np.linalg.svd(scaled, compute_uv=False)
    assert singular[0] / singular[-1] < 1e3                    # well conditioned, whatever the column scaling


def test_the_optimum_keeps_its_bounds_starts_at_rest_and_repeats(arm, optimum):
    t = np.linspace(0.0, PERIOD, 50 * optimum.samples * 4 + 1)
    q, qd, qdd = optimum.states(t)
    lower, upper = np.array([c.limits for c in arm[0].info.coordinates]).T
    assert np.all(q >= lower)
    assert np.all(q <= upper)
    assert np.max(np.abs(qd)) <= SPEED
    assert np.max(np.abs(qdd)) <= ACCELERATION
    np.testing.assert_allclose(qd[0], 0.0, atol=CLOSED_FORM * SPEED * HARMONICS)
    np.testing.assert_allclose(qdd[0], 0.0, atol=CLOSED_FORM * ACCELERATION * HARMONICS)
    np.testing.assert_allclose(q[-1], q[0], atol=CLOSED_FORM * HARMONICS * float(np.max(upper - lower)))


def test_a_run_along_the_optimum_identifies_the_arm(arm, optimum):
    numpy_arm = arm[0]
    t = np.arange(0.0, 3 * PERIOD, 0.005)
    q, qd, qdd = optimum.states(t)
    noise = 1e-3
    tau = numpy_arm.inverse_dynamics(q, qd, qdd) + np.random.default_rng(5).normal(0.0, noise, q.shape)
    Y_b, pi_b = numpy_arm.base_regressor(q, qd, qdd)
    names = numpy_arm.info.functions["base_regressor"].outputs["pi_b"]
    found = estimation.least_squares(Y_b, tau, names, "wls")
    assert np.all(np.abs(found.values - pi_b[0]) < 5 * found.std)


def test_the_command_writes_a_trajectory_symkin_identify_reads(tmp_path):
    """symkin excite on the 2R arm's model file; the arm's generated inverse dynamics "measures" tau along the
    trajectory; the file with tau appended is what symkin identify reads, and the run identifies the arm."""
    result = subprocess.run(SYMKIN_CLI + ["excite", str(MODELS_DIR / "planar_2r.yaml"), "--max-velocity", "2",
                                          "--max-acceleration", "10", "--period", "4", "--harmonics", "3",
                                          "--periods", "3", "--max-iterations", "40", "-o", str(tmp_path / "out")],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert "cond(W)" in result.stdout
    assert (tmp_path / "out" / "excitation.png").stat().st_size > 10_000
    text = (tmp_path / "out" / "excitation.csv").read_text()
    assert text.splitlines()[0] == "t,q_theta1,q_theta2,qd_theta1,qd_theta2,qdd_theta1,qdd_theta2"
    table = np.loadtxt(tmp_path / "out" / "excitation.csv", delimiter=",", skiprows=1)
    arm = load(GENERATED_DIR / "planar_2r")
    tau = arm.inverse_dynamics(table[:, 1:3], table[:, 3:5], table[:, 5:7])
    data = tmp_path / "run.csv"
    np.savetxt(data, np.column_stack([table, tau]), delimiter=",", comments="",
               header=text.splitlines()[0] + ",tau_theta1,tau_theta2")
    run = estimation.read_measurements(data, ["theta1", "theta2"])
    assert run.rates == "measured"
    np.testing.assert_array_equal(run.tau, tau)


def test_a_missing_bound_is_refused(arm):
    with pytest.raises(ValueError, match="--max-velocity"):
        excitation.optimize_excitation(arm[1], max_acceleration=ACCELERATION)


def test_limits_given_for_the_run_replace_the_models(arm):
    """--limit narrows the motion (here theta1 to [0.2, 0.8] rad), and the bounds hold for all t."""
    found = excitation.optimize_excitation(arm[1], period=PERIOD, harmonics=2, max_velocity=SPEED,
                                max_acceleration=ACCELERATION, max_iterations=20, limits={"theta1": (0.2, 0.8)})
    q = found.states(np.linspace(0.0, PERIOD, 20001))[0]
    assert np.min(q[:, 0]) >= 0.2
    assert np.max(q[:, 0]) <= 0.8


def test_a_last_iterate_that_excites_less_than_the_start_is_not_returned(arm, monkeypatch):
    """IPOPT stopped at its iteration limit may sit where the motion excites less than the start (restoring
    feasibility first, as 3 iterations on the Stewart platform do).  Here its last iterate is the start's offsets
    at rest (no column of velocity or acceleration excited: cond(W S) infinite): the start is kept, and the status
    says so; the start needs no shrinking (it moves every joint by a tenth of its range)."""
    class StoppedAtRest:
        """IPOPT's stand-in: called as the solver, it returns the start's offsets with no motion."""

        def __call__(self, x0, lbg, ubg):
            x = np.zeros_like(x0)
            x[:2] = x0[:2]                                       # the offsets of the two joints
            return {"x": x}

        def stats(self):
            return {"return_status": "Maximum_Iterations_Exceeded"}

    monkeypatch.setattr(excitation.casadi, "nlpsol", lambda *args, **kwargs: StoppedAtRest())
    found = excitation.optimize_excitation(arm[1], period=PERIOD, harmonics=HARMONICS, max_velocity=SPEED,
                                           max_acceleration=ACCELERATION, max_iterations=1)
    assert found.status == "Maximum_Iterations_Exceeded; its last iterate excited less than the start, which is kept"
    assert found.condition == found.condition_start
    assert np.abs(found.a).max() > 0


def _stopped_arm(tmp_path_factory, stop: str, home: str = ""):
    """The driven arm with a stop on a combination of its joints (and a home configuration), derived for CasADi."""
    text = DRIVEN.replace("      - [theta2, R, 0, 0, l2, 0, [0, deg(90)]]",
                          "      - [theta2, R, 0, 0, l2, 0, [0, deg(90)]]" + (f"\n  home: {home}" if home else ""))
    model = model_from_text(text + f"joint_stops:\n  - {stop}\n", "stopped")
    request = pipeline.resolve_request(model, ("base_regressor",), "casadi", None, False, "none")
    return load(pipeline.write(pipeline.generate(model, request), tmp_path_factory.mktemp("stopped")), "casadi")


def test_the_motion_keeps_the_stops_on_combinations_of_joints(tmp_path_factory):
    """Issue 64: a stop 60 deg <= theta1 + theta2 <= 110 deg (inside the box 0..90 deg each) holds along the whole
    period, on a grid 200 times as dense as the criterion's samples, and the motion reaches towards it."""
    arm = _stopped_arm(tmp_path_factory, '{expression: "theta1 + theta2", limits: [deg(60), deg(110)]}')
    found = excitation.optimize_excitation(arm, period=PERIOD, harmonics=2, max_velocity=SPEED,
                                           max_acceleration=ACCELERATION, max_iterations=20)
    total = found.states(np.linspace(0.0, PERIOD, 200 * found.samples + 1))[0].sum(axis=1)
    assert np.min(total) >= np.radians(60)
    assert np.max(total) <= np.radians(110)
    assert np.ptp(total) > np.radians(10)


def test_a_start_that_breaks_a_stop_moves_to_the_home_configuration_or_is_refused(tmp_path_factory):
    """The middle of the limits (45, 45 deg) breaks theta1 + theta2 <= 60 deg: the motion starts about the declared
    home configuration; without one the excitation says what to declare."""
    stop = '{expression: "theta1 + theta2", limits: [0, deg(60)]}'
    arm = _stopped_arm(tmp_path_factory, stop, home="[0.2, 0.3]")
    found = excitation.optimize_excitation(arm, period=PERIOD, harmonics=2, max_velocity=SPEED,
                                           max_acceleration=ACCELERATION, max_iterations=20)
    assert np.max(found.states(np.linspace(0.0, PERIOD, 20001))[0].sum(axis=1)) <= np.radians(60)
    with pytest.raises(ValueError, match="breaks the stop on theta1 \\+ theta2: declare serial.home within the stops"):
        excitation.optimize_excitation(_stopped_arm(tmp_path_factory, stop), period=PERIOD, harmonics=2,
                                       max_velocity=SPEED, max_acceleration=ACCELERATION, max_iterations=5)
