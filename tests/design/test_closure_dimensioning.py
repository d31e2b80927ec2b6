"""Dimensioning of legs without closed forms (issue 31): the dual SCARA of docs/model-format.md, whose Schoenflies
platform has only its generated loop closure.

Oracles independent of the CasADi program: the numpy runtime's ``closure_velocities`` (J from the orthogonal
complement of range(Phi_s) and an SVD, where the program solves [Phi_s Phi_p] on the closure's independent rows) with
``symkin.numerics.conditioning`` at the program's points; central differences of that numpy surrogate at the
optimum (stationary: its free lengths end inside their bounds); Gauss-Newton continuation of the optimum's home
assembly to every point (the optimizer's assemblies stay in the working mode it started in); the independent
evaluation over a denser grid of the box.
"""

from __future__ import annotations

import json

import casadi
import numpy as np
import pytest

from sample_models import dual_scara_text
from symkin import design, load, pipeline
from symkin.numerics import conditioning
from symkin import mechanism
from symkin.mechanism.continuation import angular_rates, continue_from
from symkin.cli import main
from symkin.mechanism.casadi_assembly import CasadiAssembly
from symkin.design.evaluation import continued_home
from symkin.model import model_from_text
from symkin.runtime.parallel import closure_velocities, solve_closure
from tolerances import KINEMATICS, NEWTON, svd

BOX = {"x": (-0.1, 0.1), "y": (0.25, 0.35), "z": (0.05, 0.15)}
STROKE = {"lift1": (0.0, 0.2)}
LENGTH = 0.2
#: The closure's rows that are not identically zero (each leg's x, y, z and yaw; all axes are vertical).
CLOSURE_ROWS = [0, 1, 2, 5, 6, 7, 8, 11]
#: The largest position and length of the device (m): the legs' reach l1 + l2 <= 2 x 0.5 at the bounds.
SCALE = 1.0


@pytest.fixture(scope="module")
def models(tmp_path_factory):
    model = model_from_text(dual_scara_text(), file="dual_scara.yaml")
    request = pipeline.resolve_request(model, "closure,closure_jacobians", "numpy,casadi")
    directory = pipeline.write(pipeline.generate(model, request), tmp_path_factory.mktemp("scara"))
    return load(directory), load(directory, "casadi")


@pytest.fixture(scope="module")
def problem(models):
    return design.design_problem(models[0], "gci", ["l1", "l2"], box=BOX, limits=STROKE, length=LENGTH)


@pytest.fixture(scope="module")
def program(models, problem):
    return design.formulate(problem, models[1], models[0])


@pytest.fixture(scope="module")
def solution(problem, program):
    return design.solve(problem, program)


def _assemblies(program, x):
    """(P, 8) the program's (q, s) at its points, from a solution vector."""
    return np.asarray(x, dtype=float)[program.free_count:].reshape(len(program.box_points), -1)


def _poses(model, points):
    poses = np.zeros((len(points), 4))
    poses[:, :3] = points
    poses[:, 3] = mechanism.home_pose(model)[3]
    return poses


def _numpy_surrogate(model, program, assemblies):
    """The mean 1/kappa_F over the objective's points, J from the numpy runtime, and the largest kappa([Phi_p
    Phi_s]) and kappa(J_h) there (for the tolerance)."""
    objective = assemblies[-len(program.nodes):]
    poses = _poses(model, program.nodes)
    J = angular_rates(model, closure_velocities(model, objective[:, :4], objective[:, 4:], poses).J, poses)
    J_h = conditioning.homogenize(J, LENGTH, mechanism.position_rows(model))
    blocks = model.closure_jacobians(objective[:, :4], objective[:, 4:], poses)
    rows = np.any(np.abs(np.concatenate([blocks.Phi_p, blocks.Phi_s], axis=-1)) > 0, axis=(0, 2))
    A = np.concatenate([blocks.Phi_p, blocks.Phi_s], axis=-1)[:, rows]
    return (float(np.mean(conditioning.inverse_frobenius_condition_number(J_h))), float(np.max(np.linalg.cond(A))),
            float(np.max(np.linalg.cond(J_h))))


def test_the_surrogate_is_the_mean_inverse_frobenius_of_the_closure_jacobian(models, problem, program):
    """At the start design: the program's start assemblies close the legs, and its surrogate is numpy's mean
    1/kappa_F.  Tolerance: J by a square solve on the closure's independent rows (those of A below) carries
    KINEMATICS kappa(A) relative; 1/kappa_F moves by at most 2 kappa(J_h) times J's relative error (||J||_F and
    ||J^-1||_F each), plus two SVD-free evaluations."""
    numpy_model = models[0].bind(**problem.start)
    assemblies = _assemblies(program, program.x0)
    poses = _poses(numpy_model, program.box_points)
    residual = numpy_model.closure(assemblies[:, :4], assemblies[:, 4:], poses)
    assert np.max(np.abs(residual)) <= NEWTON * SCALE
    expected, kappa_A, kappa_J = _numpy_surrogate(numpy_model, program, assemblies)
    assert abs(program.surrogate(program.x0) - expected) <= 2 * kappa_J * kappa_A * NEWTON + svd(4)


def _surrogate_at(model, program, assemblies, design_values):
    """numpy's surrogate at a design, the assemblies solved by Gauss-Newton from ``assemblies``."""
    bound = model.bind(**design_values)
    poses = _poses(bound, program.box_points)
    report = solve_closure(bound, assemblies[:, :4], assemblies[:, 4:], poses, unknowns=("q", "s"))
    assert report.all_converged
    return _numpy_surrogate(bound, program, np.hstack([report.solution["q"], report.solution["s"]]))[0]


def test_the_optimum_is_stationary_and_improves_the_independent_gci(models, problem, program, solution):
    """IPOPT's optimum (both lengths inside their bounds) is a stationary point of numpy's surrogate by central
    differences, whose gradient at the start is not; the assemblies it found are the optimum's home assembly
    continued to every point (the working mode); the independent GCI over a 16^3 grid improves beyond both error
    estimates, with the whole box reached."""
    numpy_model = models[0]
    assert solution.success
    assert solution.surrogate_optimum > solution.surrogate_start
    lengths = np.array([solution.optimum["l1"], solution.optimum["l2"]])
    assert np.all((lengths > 0.125 + 1e-3) & (lengths < 0.5 - 1e-3))
    h = 1e-5

    def gradient(values, assemblies):
        return np.array([(_surrogate_at(numpy_model, program, assemblies, {**values, name: values[name] + h})
                          - _surrogate_at(numpy_model, program, assemblies, {**values, name: values[name] - h}))
                         / (2 * h) for name in ("l1", "l2")])

    at_optimum = gradient(solution.optimum, solution.box_configurations)
    at_start = gradient(solution.start, _assemblies(program, program.x0))
    # IPOPT stops at a scaled dual infeasibility of 1e-10; central differences err by h^2 |f'''| ~ 1e-10 plus the
    # closure solves' rounding at the two designs over h, kappa NEWTON / h ~ 1e-13 / 1e-5 = 1e-8: the optimum's
    # gradient is below 1e-6 of the start's (~0.7 per metre).
    assert np.max(np.abs(at_optimum)) <= 1e-6 * np.max(np.abs(at_start))
    bound = numpy_model.bind(**solution.optimum)
    home = continued_home(problem, numpy_model, solution.optimum)
    poses = _poses(bound, program.box_points)
    q, s, taken = continue_from(bound, (*home, mechanism.home_pose(bound)), poses, step=0.005, limits=problem.limits)
    assert taken.all()
    revolute = np.array([True, False, True, True, True, True, False, True])
    difference = np.hstack([q, s]) - solution.box_configurations
    difference[:, revolute] = np.angle(np.exp(1j * difference[:, revolute]))
    blocks = bound.closure_jacobians(q, s, poses)
    closing = np.concatenate([blocks.Phi_q, blocks.Phi_s], axis=-1)[:, CLOSURE_ROWS]  # d phi / d(q, s) at fixed p
    kappa = float(np.max(np.linalg.cond(closing)))
    assert np.max(np.abs(difference)) <= kappa * NEWTON * SCALE
    before = design.evaluate(problem, numpy_model, solution.start)
    after = design.evaluate(problem, numpy_model, solution.optimum)
    assert after.gci.value - after.gci.error > before.gci.value + before.gci.error
    assert (before.box_reachable, after.box_reachable) == (1.0, 1.0)


def test_the_command_dimensions_the_model_file_and_refuses_what_does_not_apply(tmp_path, capsys):
    (tmp_path / "dual_scara.yaml").write_text(dual_scara_text())
    model = str(tmp_path / "dual_scara.yaml")
    box = ",".join(f"{axis}={lo}:{hi}" for axis, (lo, hi) in BOX.items())
    common = [model, "--free", "l1,l2", "--require-box", box, "--limit", "lift1=0:0.2", "--no-cache"]
    out = tmp_path / "optimum"
    assert main(["optimize", *common, "--length", str(LENGTH), "-o", str(out)]) == 0
    result = json.loads((out / "result.json").read_text())
    assert result["evaluation"]["optimum"]["gci"] > result["evaluation"]["start"]["gci"]
    assert result["evaluation"]["optimum"]["box_reachable"] == 1.0
    assert "J from the closure at each point's assembly" in capsys.readouterr().out
    for extra, message in ((["--maximize", "force", "--length", "0.2"], "without force objectives"),
                           ([], "give a characteristic length")):
        with pytest.raises(SystemExit) as exit_info:
            main(["optimize", *common, *extra, "-o", str(tmp_path / "refused")])
        assert exit_info.value.code == 2
        assert message in capsys.readouterr().err
        assert not (tmp_path / "refused").exists()


def test_every_points_assembly_keeps_the_joint_stops(solution, tmp_path):
    """A stop on the lifting leg's first joint, 0.05 rad inside the largest theta1 the unstopped optimum's assemblies
    use (their columns: theta1, lift1, phi2, knee2, then the passive joints): the stopped program's assemblies keep it
    at every point, and touch it."""
    bound = float(solution.box_configurations[:, 0].max()) - 0.05
    text = dual_scara_text() + f'\njoint_stops:\n  - {{expression: "theta1", limits: [-1, {bound!r}]}}\n'
    model = model_from_text(text, file="dual_scara.yaml")
    request = pipeline.resolve_request(model, "closure,closure_jacobians", "numpy,casadi")
    directory = pipeline.write(pipeline.generate(model, request), tmp_path)
    stopped = load(directory), load(directory, "casadi")
    problem = design.design_problem(stopped[0], "gci", ["l1", "l2"], box=BOX, limits=STROKE, length=LENGTH)
    stopped_solution = design.solve(problem, design.formulate(problem, stopped[1], stopped[0]))
    assert stopped_solution.success
    theta1 = stopped_solution.box_configurations[:, 0]
    assert theta1.max() <= bound + 1e-9
    assert theta1.max() == pytest.approx(bound, abs=1e-6)


def test_the_programs_assembly_is_the_run_time_mechanisms(models, problem):
    """The program's closure terms come from the run-time mechanism's CasADi counterpart with the free lengths as
    symbols: its rows are the closure's rows that do not vanish identically, and at the start design its J (a
    function of the symbols) is numpy's closure_velocities J at the home assembly, to KINEMATICS kappa(A)."""
    numpy_model, casadi_model = models
    design_values = problem.design([problem.start[p.name] for p in problem.free])
    symbols = {p.name: casadi.SX.sym(p.name) for p in problem.free}
    assembly = CasadiAssembly.at_home(casadi_model, numpy_model.bind(**problem.start), {**design_values, **symbols})
    assert assembly.rows == CLOSURE_ROWS
    bound = numpy_model.bind(**design_values)
    q, s = continued_home(problem, numpy_model, design_values)
    p = mechanism.home_pose(bound)
    J = casadi.Function("J", list(symbols.values()), [assembly.jacobian(q, s, p)])
    J = J(*design_values_of(symbols, design_values)).full()
    expected = closure_velocities(bound, q, s, p).J
    blocks = bound.closure_jacobians(q, s, p)
    kappa = float(np.linalg.cond(np.concatenate([blocks.Phi_s, blocks.Phi_p], axis=-1)[CLOSURE_ROWS]))
    np.testing.assert_allclose(J, expected, rtol=0, atol=kappa * KINEMATICS * np.abs(expected).max())
    residual = casadi.Function("phi", list(symbols.values()), [assembly.residual(q, s, p)])
    assert np.max(np.abs(residual(*design_values_of(symbols, design_values)).full())) <= NEWTON * SCALE


def design_values_of(symbols, design_values):
    """The values of the symbols' parameters, in the symbols' order."""
    return [design_values[name] for name in symbols]
