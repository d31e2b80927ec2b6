"""Issue 33, step 3: `symkin identify` - base parameters from a measured run, by least squares.

Reference: runs simulated with the model's own generated inverse dynamics along a periodic excitation (a finite
Fourier series, Swevers et al. 1997) with Gaussian noise on the efforts: the estimates recover the model's base
parameters pi_b within their reported standard deviations; bad data are refused with file, row and column (exit 2,
nothing written).
"""

from __future__ import annotations

import json
import os
import subprocess

import numpy as np
import pytest

from conftest import ROOT, SYMKIN_CLI
from symkin.identification import consistent, estimation
from symkin.dynamics.parameter_names import DISSIPATIVE
from symkin.model import model_from_text
from identification_runs import NOISE, RATE, arm, excitation, simulated_run, write_run  # noqa: F401 (the fixture arm)
from sample_models import DRIVEN
from tolerances import EPS

@pytest.mark.parametrize("method", ["ols", "wls"])
def test_a_simulated_run_gives_back_the_models_base_parameters(arm, method):
    t, q, qd, qdd, tau = simulated_run(arm)
    Y_b, pi_b = arm.base_regressor(q, qd, qdd)
    names = arm.info.functions["base_regressor"].outputs["pi_b"]
    found = estimation.least_squares(Y_b, tau, names, method)
    error = np.abs(found.values - pi_b[0]) / found.std
    assert np.all(error < 5), dict(zip(names, error))           # 5 standard deviations: 1 in 1.7 million
    assert np.median(error) < 1.5                                 # and distributed as standard deviations are
    assert np.allclose(found.joint_std, NOISE, rtol=0.1)          # the noise, seen in the residual of each joint


def test_rates_derived_from_q_by_the_stated_filter(arm, tmp_path):
    """Without qd and qdd columns, a zero-phase low-pass at --cutoff and central differences: at 200 Hz and a 5 Hz
    cutoff the derived accelerations of the 2 s excitation (4 harmonics, up to 2 Hz) are close to the exact ones."""
    t, q, qd, qdd, tau = simulated_run(arm)
    run = estimation.read_measurements(write_run(tmp_path / "run.csv", ["theta1", "theta2"], t, q, tau),
                                           ["theta1", "theta2"], cutoff=5.0)
    inner = slice(100, -100)                                      # away from the filter's edge transients
    assert np.max(np.abs(run.qdd[inner] - qdd[inner])) < 0.02 * np.max(np.abs(qdd))
    assert "Butterworth low-pass of order 4 at 5 Hz" in run.rates


def test_the_command_writes_the_estimate_and_its_validation(arm, tmp_path):
    t, q, qd, qdd, tau = simulated_run(arm)
    data = write_run(tmp_path / "run.csv", ["theta1", "theta2"], t, q, tau, qd, qdd)
    result = subprocess.run(SYMKIN_CLI + ["identify", str(arm.directory), str(data), "-o", str(tmp_path / "out")],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    record = json.loads((tmp_path / "out" / "estimate.json").read_text())
    assert record["method"] == "wls"
    assert len(record["parameters"]) == 13
    assert all(r < 3 * NOISE for r in record["validation"]["rms"].values())
    assert (tmp_path / "out" / "validation.png").stat().st_size > 10_000
    assert "link1.mxR" in result.stdout


def test_the_library_identifies_as_the_command_does(arm, tmp_path):
    """symkin.identification.workflow.identify is the command's workflow (issue 62: the CLI parses and writes): the
    same run gives the same estimate, and without a figure no validation.png."""
    from symkin.identification.workflow import IdentifyRequest, identify

    t, q, qd, qdd, tau = simulated_run(arm)
    data = write_run(tmp_path / "run.csv", ["theta1", "theta2"], t, q, tau, qd, qdd)
    found = identify(IdentifyRequest(str(arm.directory), str(data), method="ols", figure=False))
    assert sorted(found.files) == ["estimate.csv", "estimate.json", "summary.txt"]
    record = json.loads(found.files["estimate.json"])
    fit, _ = estimation.read_measurements(data, ["theta1", "theta2"]).split(0.25)  # the default holdout
    Y_b, _ = arm.base_regressor(fit.q, fit.qd, fit.qdd)
    direct = estimation.least_squares(Y_b, fit.tau, arm.info.functions["base_regressor"].outputs["pi_b"], "ols")
    assert [p["value"] for p in record["parameters"]] == direct.values.tolist()  # the same arithmetic
    assert record["method"] == "ols"


@pytest.mark.parametrize("change, message", [
    (lambda text: text.replace("tau_theta2", "tau_theta3", 1), "row 1, column 5: unknown column 'tau_theta3'; did "
                                                                 "you mean 'tau_theta2'"),
    (lambda text: text.replace(",tau_theta2", ",tau_x", 1), "unknown column 'tau_x'"),
    (lambda text: "\n".join(line.rsplit(",", 1)[0] if k else line.replace(",tau_theta2", "")
                            for k, line in enumerate(text.splitlines())), "missing column tau_theta2"),
    (lambda text: text.replace(text.splitlines()[5].split(",")[2], "nan", 1), "row 6, column 3 (q_theta2): 'nan'"),
    (lambda text: "\n".join(text.splitlines()[:3] + [text.splitlines()[2]] + text.splitlines()[3:]),
     "row 4, column 1 (t): the time does not increase"),
])
def test_bad_data_are_refused_with_file_row_and_column_and_nothing_is_written(arm, tmp_path, change, message):
    t, q, qd, qdd, tau = simulated_run(arm)
    data = write_run(tmp_path / "run.csv", ["theta1", "theta2"], t, q, tau)
    data.write_text(change(data.read_text()))
    result = subprocess.run(SYMKIN_CLI + ["identify", str(arm.directory), str(data), "--cutoff", "5",
                                          "-o", str(tmp_path / "out")], capture_output=True, text=True)
    assert result.returncode == 2
    assert f"{data}, " in result.stderr
    assert message in result.stderr.replace("\n", " ")
    assert not (tmp_path / "out").exists()


def test_hostile_csv_files_are_refused_or_read_right(arm, tmp_path):
    """Issue 59: a repeated column is refused (it silently won), a UTF-8 byte-order mark (Excel's) is read, a
    value whose square overflows is refused at its row and column, a FIFO is refused without blocking."""
    t, q, qd, qdd, tau = simulated_run(arm)
    data = write_run(tmp_path / "run.csv", ["theta1", "theta2"], t, q, tau, qd, qdd)
    text = data.read_text()
    coordinates = ["theta1", "theta2"]
    bom = tmp_path / "bom.csv"
    bom.write_bytes(b"\xef\xbb\xbf" + text.encode())
    assert np.array_equal(estimation.read_measurements(bom, coordinates).tau,
                          estimation.read_measurements(data, coordinates).tau)
    header = text.splitlines()[0]
    repeated = tmp_path / "repeated.csv"
    repeated.write_text("\n".join(line + "," + line.split(",")[1] for line in text.splitlines()) + "\n")
    with pytest.raises(estimation.DataError, match=rf"row 1, column {header.count(',') + 2}: the column "
                                                       "'q_theta1' repeats column 2"):
        estimation.read_measurements(repeated, coordinates)
    huge = tmp_path / "huge.csv"
    lines = text.splitlines()
    lines[4] = ",".join(lines[4].split(",")[:2] + ["1e308"] + lines[4].split(",")[3:])
    huge.write_text("\n".join(lines) + "\n")
    with pytest.raises(estimation.DataError, match=r"row 5, column 3 \(q_theta2\): 1e\+308 is beyond 1e\+15"):
        estimation.read_measurements(huge, coordinates)
    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    with pytest.raises(estimation.DataError, match="is not a regular file"):
        estimation.read_measurements(fifo, coordinates)


def test_a_run_that_does_not_excite_a_parameter_or_a_combination_names_them(arm):
    """Joint 2 held still: its rotor and friction columns vanish. Joint 1 held still: gravity acts on link 1's
    first moments through a constant angle, so m c_x and m c_y of link 1 are not told apart (their columns are
    parallel; with the columns that vanish left out, the SVD finds the combination). Named, not estimated."""
    t, q, qd, qdd, tau = simulated_run(arm)
    names = arm.info.functions["base_regressor"].outputs["pi_b"]
    still = q.copy(), qd.copy(), qdd.copy()
    still[0][:, 1], still[1][:, 1], still[2][:, 1] = 0.3, 0.0, 0.0
    with pytest.raises(estimation.DataError, match="does not excite theta2.Ia, theta2.fv, theta2.fc"):
        estimation.least_squares(arm.base_regressor(*still)[0], arm.inverse_dynamics(*still), names)
    still = q.copy(), qd.copy(), qdd.copy()
    still[0][:, 0], still[1][:, 0], still[2][:, 0] = 0.3, 0.0, 0.0
    inertial = [k for k, name in enumerate(names) if name.startswith("link") and name != "link1.IzzR"]
    with pytest.raises(estimation.DataError, match="does not identify the combination of link1.m"):
        estimation.least_squares(arm.base_regressor(*still)[0][..., inertial], arm.inverse_dynamics(*still),
                                [names[k] for k in inertial])


def test_too_few_samples_for_the_base_parameters_are_refused(arm):
    t, q, qd, qdd, tau = simulated_run(arm)
    Y_b, _ = arm.base_regressor(q[:5], qd[:5], qdd[:5])
    with pytest.raises(estimation.DataError, match="5 samples give 10 equations for 13 base parameters"):
        estimation.least_squares(Y_b, tau[:5], arm.info.functions["base_regressor"].outputs["pi_b"])


def test_the_consistent_estimate_is_physical_and_fits_the_run(arm):
    """From a wrong prior (every link's mass properties 30 % off), the consistent estimate keeps every link a rigid
    body (pseudo-inertia positive semidefinite to rounding) and the drives non-negative, fits the run to the
    noise, and its identifiable combinations K pi are the true base parameters within a few standard deviations
    of the least-squares estimate."""
    from symkin.derivation import Derivation

    t, q, qd, qdd, tau = simulated_run(arm)
    Y, pi = arm.regressor(q, qd, qdd)
    Y_b, pi_b = arm.base_regressor(q, qd, qdd)
    base_names = arm.info.functions["base_regressor"].outputs["pi_b"]
    wls = estimation.least_squares(Y_b, tau, base_names, "wls")
    triangle, target = estimation.weighted_triangle(Y, tau, 1.0 / wls.joint_std)
    prior = pi[0].copy()
    prior[:20] *= 1.3
    found = consistent.estimate(triangle, target, arm.info.functions["regressor"].outputs["pi"], prior)
    for J in found.pseudo_inertias():
        assert np.linalg.eigvalsh(J)[0] >= -1e3 * EPS * np.max(np.abs(J))
    assert np.all(found.values[20:23] >= 0)                       # theta1's rotor inertia, viscous, Coulomb
    assert np.allclose(np.sqrt(np.mean((Y @ found.values - tau) ** 2, axis=0)), NOISE, rtol=0.1)
    driven = model_from_text(DRIVEN, "driven")
    K = Derivation(driven)["base_parameters"].evaluate({p.name: float(p.value) for p in driven.parameters})
    assert np.all(np.abs(K @ found.values - pi_b[0]) < 5 * wls.std)
    assert found.converged
    assert found.solver_text().startswith("converged in ")
    stopped = consistent.estimate(triangle, target, arm.info.functions["regressor"].outputs["pi"], prior, budget=3)
    assert not stopped.converged
    assert stopped.evaluations <= 3
    assert stopped.optimality > found.optimality
    assert stopped.solver_text().startswith("not converged: stopped at its budget of ")     # said, never silent
    for J in stopped.pseudo_inertias():                                                    # consistent all the same
        assert np.linalg.eigvalsh(J)[0] >= -1e3 * EPS * np.max(np.abs(J))


def test_an_offset_beyond_the_coulomb_friction_keeps_both_levels_of_the_consistent_estimate():
    """One drive, tau = 0.2 sign(qd) + 0.5 (a constant push of 0.5 N m against Coulomb friction of 0.2 N m): least
    squares puts the push into the offset, f_o > f_c, a level f_c - f_o < 0 that would push the joint along its
    motion; the consistent estimate keeps both Coulomb levels f_c + f_o and f_c - f_o non-negative (to the rounding
    of their sum and difference), as the model file needs them (friction: {coulomb: {positive, negative}})."""
    rng = np.random.default_rng(4)
    qd, qdd = np.sin(np.linspace(0, 20, 400)), np.cos(np.linspace(0, 20, 400))
    Y = np.column_stack([qdd, qd, np.sign(qd), np.ones_like(qd)])     # I_a, f_v, f_c, f_o
    tau = Y @ [0.01, 0.05, 0.2, 0.5] + rng.normal(0, 1e-3, len(qd))
    Q, R = np.linalg.qr(Y)
    unconstrained = np.linalg.lstsq(R, Q.T @ tau, rcond=None)[0]
    assert unconstrained[3] - unconstrained[2] > 0.25                  # the data alone want a negative level
    found = consistent.estimate(R, Q.T @ tau, ["j.Ia", "j.fv", "j.fc", "j.fo"], np.zeros(4)).values
    rounding = 4 * EPS * (abs(found[2]) + abs(found[3]))
    assert found[2] + found[3] >= -rounding
    assert found[2] - found[3] >= -rounding


def test_the_command_estimates_consistent_standard_parameters(arm, tmp_path):
    t, q, qd, qdd, tau = simulated_run(arm)
    data = write_run(tmp_path / "run.csv", ["theta1", "theta2"], t, q, tau, qd, qdd)
    result = subprocess.run(SYMKIN_CLI + ["identify", str(arm.directory), str(data), "--method", "consistent",
                                          "--no-figure", "-o", str(tmp_path / "out")], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    record = json.loads((tmp_path / "out" / "estimate.json").read_text())
    assert set(record["standard"]["parameters"]) >= {"link1.m", "link2.Izz", "theta2.fc"}
    assert record["standard"]["parameters"]["link2.m"] > 0
    solver = record["standard"]["solver"]                         # how the solver ended, in the record and summary
    assert 0 < solver["evaluations"] <= consistent.EVALUATIONS
    said = (f"solver converged in {solver['evaluations']} evaluations" if solver["converged"] else
            f"solver not converged: stopped at its budget of {solver['evaluations']} evaluations")
    assert said in (tmp_path / "out" / "summary.txt").read_text()


def _energy_estimate(arm, t, q, qd, qdd, tau, window=0.05):
    from symkin.identification.implied_parameters import combinations

    run = estimation.Measurements("run", t, q, qd, qdd, tau, "measured")
    Y, Y_b = arm.regressor(q, qd, qdd)[0], arm.base_regressor(q, qd, qdd)[0]
    return estimation.energy_least_squares(
        run, Y, arm.energy_regressor(q, qd)[0], Y_b, combinations(Y, Y_b),
        arm.info.functions["regressor"].outputs["pi"], arm.info.functions["base_regressor"].outputs["pi_b"], window)


def test_the_energy_balance_holds_for_the_true_parameters_to_the_quadrature_error(arm):
    """Noise-free runs: the balance of the model's own pi over every window misses only the trapezoidal rule's
    error, O(h^2): sampled twice as fast, the largest miss shrinks fourfold (Richardson), and it is small against
    the work itself. Friction (viscous, Coulomb on both joints) enters as the integral of its power."""
    misses = []
    for rate in (RATE, 2 * RATE):
        t, q, qd, qdd = excitation(2, seed=1, rate=rate)
        Y, pi = arm.regressor(q, qd, qdd)
        dissipative = np.array([n.rsplit(".", 1)[-1] in DISSIPATIVE
                                for n in arm.info.functions["regressor"].outputs["pi"]])
        W, work = estimation.energy_balance(t, qd, arm.inverse_dynamics(q, qd, qdd),
                                                arm.energy_regressor(q, qd)[0], np.where(dissipative, Y, 0.0), 0.05)
        assert len(work) == 199
        assert np.all(np.isfinite(W))
        misses.append(np.max(np.abs(W @ pi[0] - work)))
    assert misses[0] < 1e-3 * np.max(np.abs(work))
    assert 3.0 < misses[0] / misses[1] < 5.0, misses


def test_the_energy_estimate_gives_back_the_models_base_parameters(arm):
    """From the noisy run of the least-squares tests, without its accelerations: each base parameter within a few
    of its standard deviations (larger than OLS's: one equation per window instead of n per sample), and the
    torques the estimate predicts (with the accelerations) fit to the noise."""
    t, q, qd, qdd, tau = simulated_run(arm)
    found = _energy_estimate(arm, t, q, qd, qdd, tau)
    pi_b = arm.base_regressor(q, qd, qdd)[1][0]
    error = np.abs(found.values - pi_b) / found.std
    assert found.method == "energy"
    assert np.all(error < 5), dict(zip(found.names, error))
    assert np.median(error) < 1.5
    assert np.all(found.joint_std < 2 * NOISE)
    ols = estimation.least_squares(arm.base_regressor(q, qd, qdd)[0], tau, found.names, "ols")
    assert np.all(found.std > ols.std)


def test_the_energy_estimate_needs_no_acceleration(arm):
    """The balance reads q, qd and tau only: accelerations that are wrong change the regressor's inertial
    columns but not the estimate (they enter its torque residual alone)."""
    t, q, qd, qdd, tau = simulated_run(arm)
    found = _energy_estimate(arm, t, q, qd, qdd, tau)
    scrambled = _energy_estimate(arm, t, q, qd, qdd[::-1] * 3.0, tau)
    assert np.allclose(scrambled.values, found.values, rtol=0, atol=1e-9 * np.max(np.abs(found.values)))


def test_the_command_estimates_from_the_energy_balance_and_refuses_too_few_windows(arm, tmp_path):
    t, q, qd, qdd, tau = simulated_run(arm)
    data = write_run(tmp_path / "run.csv", ["theta1", "theta2"], t, q, tau, qd, qdd)
    result = subprocess.run(SYMKIN_CLI + ["identify", str(arm.directory), str(data), "--method", "energy",
                                          "--window", "0.1", "-o", str(tmp_path / "out")], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    record = json.loads((tmp_path / "out" / "estimate.json").read_text())
    assert (record["method"], record["window"], len(record["parameters"])) == ("energy", 0.1, 13)
    assert all(r < 3 * NOISE for r in record["validation"]["rms"].values())
    assert "energy balance over windows of 0.1 s" in (tmp_path / "out" / "summary.txt").read_text()
    result = subprocess.run(SYMKIN_CLI + ["identify", str(arm.directory), str(data), "--method", "energy",
                                          "--window", "1", "-o", str(tmp_path / "long")], capture_output=True, text=True)
    assert result.returncode == 2
    assert "7 windows of the run give 7 energy equations for 13 base parameters: shorten --window" in result.stderr
    assert not (tmp_path / "long").exists()


def test_a_generated_parallel_model_without_its_base_regressor_is_refused_before_any_work(tmp_path):
    """generated/delta holds the scene's functions, not the base regressor a parallel model's identification needs:
    exit 2, nothing written, and the message says how to derive it (a model file derives it on the fly:
    tests/parallel/test_parallel_base_parameters.py)."""
    data = tmp_path / "run.csv"
    data.write_text("t,theta1,theta2,theta3\n0,0,0,0\n")
    result = subprocess.run(SYMKIN_CLI + ["identify", str(ROOT / "generated/delta"), str(data),
                                          "-o", str(tmp_path / "out")], capture_output=True, text=True)
    assert result.returncode == 2
    assert "a parallel model's identification needs base_regressor; derive them" in result.stderr
    assert not (tmp_path / "out").exists()


def test_a_generated_open_chain_without_its_base_regressor_is_refused_with_the_derive_that_gives_it(tmp_path):
    """generated/planar_2r holds no regressors: the open chain's refusal names them (before, a bare KeyError)."""
    data = tmp_path / "run.csv"
    data.write_text("t,theta1,theta2\n0,0,0\n")
    result = subprocess.run(SYMKIN_CLI + ["identify", str(ROOT / "generated/planar_2r"), str(data),
                                          "-o", str(tmp_path / "out")], capture_output=True, text=True)
    assert result.returncode == 2
    assert "the identification needs base_regressor; derive it (symkin derive --only base_regressor,regressor)" in \
        result.stderr
    assert not (tmp_path / "out").exists()


def test_the_consistent_estimates_jacobian_is_the_derivative_of_its_parameterization():
    """d pi / d theta of one link's log-Cholesky parameters, analytic (consistent._standard_derivatives), against
    central differences at random theta: truncation h^2 |pi'''| ~ 1e-12 and rounding EPS |pi| / h ~ 1e-10."""
    rng = np.random.default_rng(61)
    h = 1e-6

    def standard(theta):
        U = consistent._factor(theta)
        return consistent._standard_of(U @ U.T)

    for _ in range(5):
        theta = rng.normal(scale=0.5, size=10)
        analytic = consistent._standard_derivatives(theta)
        differences = np.array([(standard(theta + h * e) - standard(theta - h * e)) / (2 * h) for e in np.eye(10)]).T
        np.testing.assert_allclose(analytic, differences, atol=1e-8 * np.abs(analytic).max())
