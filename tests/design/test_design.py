"""Dimensioning optimization (``symkin.design``, ``symkin optimize``): seed sec. 4 steps 1-3, GCI eq. 8.28.

Oracles independent of the CasADi surrogate: the numpy backend with
``symkin.numerics.conditioning`` at the same nodes (value and gradient by central
differences), the true GCI by ``symkin.analysis.gci`` (1/kappa from singular values,
randomized QMC), the closed forms of the 2R arm (isotropy at l1 = sqrt(2) l2,
theta2 = 135 deg; the pointwise optimum of 1/kappa_F(theta2; l1/l2) is l1/l2 = sqrt(2) for
every theta2; the smallest reach sqrt(l1^2 + l2^2) at theta2 = 90 deg) and the DELTA's
closed-form ik on a grid denser than the optimizer's constraint points; for a spherical platform
(the spherical 3-RRR of docs/design-optimization.md) the numpy code with E(p) of
``mechanism.reach`` and central differences of its surrogate.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

import symkin
from conftest import GENERATED_DIR, MODELS_DIR, ROOT
from symkin import design
from symkin.numerics import conditioning
from symkin.rating import forces, formulas
from symkin.mechanism import MechanismKind
from symkin.analysis.needs import NEEDS
from symkin.mechanism.reach import angular_velocity_matrix
from symkin.cli import main
from symkin.design import formulation
from tolerances import CLOSED_FORM, KINEMATICS, svd

ARM_DIR = str(GENERATED_DIR / "planar_2r")
DELTA_DIR = str(GENERATED_DIR / "delta")
DELTA_BOX = {"x": (-0.04, 0.04), "y": (-0.04, 0.04), "z": (-0.19, -0.11)}


@pytest.fixture(scope="module")
def arm():
    return symkin.load(ARM_DIR), symkin.load(ARM_DIR, "casadi")


@pytest.fixture(scope="module")
def delta():
    return symkin.load(DELTA_DIR), symkin.load(DELTA_DIR, "casadi")


def _optimize(models, objective, free, **kwargs):
    numpy_model, casadi_model = models
    nodes = kwargs.pop("nodes", None)
    problem = design.design_problem(numpy_model, objective, free, **kwargs)
    program = design.formulate(problem, casadi_model, numpy_model, nodes=nodes)
    return problem, program, design.solve(problem, program)


def _serial_surrogate(model, q, smoothing=formulation.DETERMINANT_SMOOTHING):
    """sum |det J| / kappa_F / sum sqrt(det J^2 + eps^2), eps^2 = smoothing^2 mean(det J^2)."""
    J = model.jacobian(q)
    det = np.linalg.det(J)
    weight = np.sqrt(det**2 + smoothing**2 * np.mean(det**2))
    index = conditioning.inverse_frobenius_condition_number(J)
    return np.sum(conditioning.absolute_determinant(J) * index) / np.sum(weight)


def test_serial_surrogate_and_gradient_match_the_numpy_code(arm):
    numpy_model, casadi_model = arm
    problem = design.design_problem(numpy_model, "gci", ["l1", "l2"], limits={"theta2": (0.0, np.pi)})
    program = design.formulate(problem, casadi_model, numpy_model, nodes=7)
    free = np.array([0.13, 0.08])
    value = float(program.objective(free, program.x0[program.free_count:]))
    bound = numpy_model.bind(l1=0.13, l2=0.08)
    # a mean of kinematic quantities (CasADi's graph against numpy's): KINEMATICS
    assert value == pytest.approx(_serial_surrogate(bound, program.nodes), rel=KINEMATICS)
    # the smoothing of |det J| changes the Frobenius GCI estimate by about smoothing^2
    assert value == pytest.approx(_serial_surrogate(bound, program.nodes, smoothing=0.0), rel=1e-5)
    import casadi

    p = casadi.SX.sym("p", 2)
    surrogate = program.objective(p, program.x0[program.free_count:])
    gradient = np.asarray(casadi.Function("g", [p], [casadi.gradient(surrogate, p)])(free)).ravel()
    h = 1e-6
    numeric = [(_serial_surrogate(numpy_model.bind(**dict(zip(("l1", "l2"), free + h * e))), program.nodes)
                - _serial_surrogate(numpy_model.bind(**dict(zip(("l1", "l2"), free - h * e))), program.nodes)) / (2 * h)
               for e in np.eye(2)]
    assert gradient == pytest.approx(numeric, rel=1e-6, abs=1e-9)
    # the GCI depends on the length ratio only: the gradient is orthogonal to the design
    assert gradient @ free == pytest.approx(0.0, abs=1e-12)


def test_parallel_surrogate_matches_the_numpy_code(delta):
    numpy_model, casadi_model = delta
    problem = design.design_problem(numpy_model, "gci", ["a", "b"], box=DELTA_BOX)
    program = design.formulate(problem, casadi_model, numpy_model, nodes=3)
    q = numpy_model.bind(a=0.11, b=0.16).ik(program.nodes).joints
    J = numpy_model.bind(a=0.11, b=0.16).jacobian(q, program.nodes)
    expected = np.mean(conditioning.inverse_frobenius_condition_number(J))
    # the same mean through the DELTA's IK and a 3x3 SVD: KINEMATICS + svd(3)
    value = float(program.objective([0.11, 0.16], program.x0[program.free_count:]))
    assert value == pytest.approx(expected, rel=KINEMATICS + svd(3))


#: The spherical 3-RRR with free link angles that docs/design-optimization.md declares (its heredoc).
SPHERICAL_MODEL = re.search(r"^cat > out/spherical_3rrr\.yaml <<'EOF'\n(.*?)^EOF$",
                            (ROOT / "docs" / "design-optimization.md").read_text(), re.S | re.M)
#: A box of orientations symmetric about the home orientation.
SPHERICAL_BOX = {axis: (-np.radians(30), np.radians(30)) for axis in ("roll", "pitch", "yaw")}
ORTHOGONAL = np.pi / 2


@pytest.fixture(scope="module")
def spherical(tmp_path_factory):
    assert SPHERICAL_MODEL, "docs/design-optimization.md no longer declares spherical_3rrr.yaml"
    path = tmp_path_factory.mktemp("spherical") / "spherical_3rrr.yaml"
    path.write_text(SPHERICAL_MODEL.group(1))
    directory = symkin.derive(path, path.parent, outputs=NEEDS["design"][MechanismKind.PARALLEL_ORIENTATION],
                              backends=["numpy", "casadi"])
    return symkin.load(directory), symkin.load(directory, "casadi")


def _spherical_surrogate(model, points, alpha1, alpha2):
    """sum cos(pitch) / kappa_F(E J) / sum cos(pitch) by the numpy code (E from mechanism.reach)."""
    bound = model.bind(alpha1=alpha1, alpha2=alpha2)
    J_w = angular_velocity_matrix(points) @ bound.jacobian(bound.ik(points).joints, points)
    weights = np.cos(points[:, 1])
    return np.sum(weights * conditioning.inverse_frobenius_condition_number(J_w)) / np.sum(weights)


def test_spherical_surrogate_weighs_the_angular_velocity_jacobian_by_the_invariant_measure(spherical):
    numpy_model, casadi_model = spherical
    problem = design.design_problem(numpy_model, "gci", ["alpha1", "alpha2"], box=SPHERICAL_BOX)
    program = design.formulate(problem, casadi_model, numpy_model, nodes=3)
    alphas = np.radians([75.0, 100.0])
    # a weighted mean through the spherical legs' IK and a 3x3 SVD: KINEMATICS + svd(3)
    value = float(program.objective(alphas, program.x0[program.free_count:]))
    assert value == pytest.approx(_spherical_surrogate(numpy_model, program.nodes, *alphas), rel=KINEMATICS + svd(3))


def test_spherical_3rrr_optimum_over_a_symmetric_box_is_the_agile_eyes_orthogonal_design(spherical):
    numpy_model, _ = spherical
    bounds = {"alpha1": (np.radians(60), np.radians(120)), "alpha2": (np.radians(60), np.radians(120))}
    problem, program, solution = _optimize(spherical, "gci", ["alpha1", "alpha2"], bounds=bounds, box=SPHERICAL_BOX)
    assert solution.success
    # IPOPT's tolerance (1e-8 on the scaled KKT conditions) at a curvature of order 1
    assert [solution.optimum["alpha1"], solution.optimum["alpha2"]] == pytest.approx([ORTHOGONAL] * 2, abs=1e-7)
    # the numpy code alone: the surrogate's gradient vanishes at 90 deg (central differences, step h: truncation
    # ~ h^2, rounding ~ KINEMATICS / h) and every neighbouring design 2 deg away does worse
    h = 1e-4
    for e in np.eye(2):
        slope = (_spherical_surrogate(numpy_model, program.nodes, *(ORTHOGONAL + h * e))
                 - _spherical_surrogate(numpy_model, program.nodes, *(ORTHOGONAL - h * e))) / (2 * h)
        assert abs(slope) < 10 * h**2 + KINEMATICS / h
    best = _spherical_surrogate(numpy_model, program.nodes, ORTHOGONAL, ORTHOGONAL)
    for step in np.radians([[2, 0], [-2, 0], [0, 2], [0, -2], [2, 2], [2, -2], [-2, 2], [-2, -2]]):
        assert _spherical_surrogate(numpy_model, program.nodes, *(ORTHOGONAL + step)) < best
    before, after = (design.evaluate(problem, numpy_model, d, samples=2**10) for d in (solution.start, solution.optimum))
    assert after.gci.value - after.gci.error > before.gci.value + before.gci.error
    assert after.box_reachable == 1.0


@pytest.mark.parametrize("box, message", [
    ({"x": (0, 1), "y": (0, 1), "z": (0, 1)}, "needs exactly the axes roll, pitch, yaw"),
    ({**SPHERICAL_BOX, "pitch": (0.0, np.radians(100))}, "the pitch of the required box must lie within (-90 deg"),
])
def test_a_spherical_box_is_one_of_orientations_within_the_chart(spherical, box, message):
    with pytest.raises(ValueError, match=re.escape(message)):
        design.design_problem(spherical[0], "gci", ["alpha1"], box=box)


@pytest.mark.parametrize("theta2_limits", [(0.0, np.pi / 2), (0.0, np.pi)])
def test_2r_with_free_length_ratio_finds_the_isotropic_design(arm, theta2_limits):
    numpy_model, _ = arm
    _, _, solution = _optimize(arm, "gci", ["l1"], bounds={"l1": (0.05, 0.3)}, limits={"theta2": theta2_limits})
    assert solution.success
    l1, l2 = solution.optimum["l1"], solution.optimum["l2"]
    assert l1 / l2 == pytest.approx(np.sqrt(2), rel=1e-9)
    # kappa = 1 at the isotropic configuration theta2 = 135 deg, by the generated numpy code and an SVD
    J = numpy_model.bind(l1=l1, l2=l2).jacobian(np.array([0.3, 3 * np.pi / 4]))
    assert conditioning.condition_number(J) == pytest.approx(1.0, abs=1e-8)
    assert conditioning.condition_number(numpy_model.bind(l1=np.sqrt(2) * 0.1).jacobian([0.3, 3 * np.pi / 4])) \
        == pytest.approx(1.0, abs=svd(2) + CLOSED_FORM)  # l1 = sqrt(2) l2 is rounded once


def test_maximizing_the_gci_of_the_2r_improves_its_independent_gci_and_keeps_the_box(arm, monkeypatch):
    numpy_model, _ = arm
    box = {"x": (0.11, 0.14), "y": (0.11, 0.14)}
    problem, _, solution = _optimize(arm, "gci", ["l1"], bounds={"l1": (0.05, 0.3)}, box=box)
    assert solution.success
    assert solution.constraint_violation < 1e-9
    # the box corner nearest the base needs the smallest reach sqrt(l1^2 + l2^2) (theta2 = 90 deg) <= |corner|
    assert solution.optimum["l1"] == pytest.approx(np.sqrt(2 * 0.11**2 - 0.1**2), rel=1e-7)
    before, after = (design.evaluate(problem, numpy_model, d, samples=2**12)
                     for d in (solution.start, solution.optimum))
    assert after.gci.value - after.gci.error > before.gci.value + before.gci.error
    assert before.box_reachable == after.box_reachable == 1.0
    # the optimizer's box configurations reach the box points within the joint limits
    q = solution.box_configurations
    assert np.all((q >= -1e-9) & (q <= np.pi / 2 + 1e-9))
    tcp = numpy_model.bind(**solution.optimum).fk(q)[:, :2, 3]
    assert np.abs(tcp[[0, -1]] - [[0.11, 0.11], [0.14, 0.14]]).max() < 1e-9
    # without a closed-form inverse, the box is checked at those configurations by the generated fk
    monkeypatch.setattr("symkin.analysis.inverse.inverse_kinematics_for", lambda model: None)
    checked = design.evaluate(problem, numpy_model, solution.optimum, samples=2**10,
                              box_points=solution.box_points, box_configurations=q)
    assert checked.box_reachable == 1.0
    assert "generated fk" in checked.box_check
    moved = design.evaluate(problem, numpy_model, solution.optimum, samples=2**10,
                            box_points=solution.box_points + 1e-6, box_configurations=q)
    assert moved.box_reachable == 0.0


def test_workspace_maximization_of_the_2r_reaches_the_length_bound(arm):
    numpy_model, _ = arm
    problem, _, solution = _optimize(arm, "workspace", ["l1"], bounds={"l1": (0.05, 0.2)})
    assert solution.optimum["l1"] == pytest.approx(0.2, rel=1e-7)
    rating = design.evaluate(problem, numpy_model, solution.optimum, samples=2**12)
    area = np.pi / 2 * 0.2 * 0.1  # int_0^pi/2 int_0^pi/2 l1 l2 sin(theta2) dq
    assert abs(rating.measure.value - area) <= rating.measure.error
    assert solution.surrogate_optimum == pytest.approx(area, rel=1e-3)


#: The 2R arm whose forearm's direction theta1 + theta2 stays within [0, 90 deg] (a coupled joint stop).
STOPPED_ARM = ((MODELS_DIR / "planar_2r.yaml").read_text()
               + '\njoint_stops:\n  - {expression: "theta1 + theta2", limits: [0, deg(90)], doc: forearm}\n')


@pytest.fixture(scope="module")
def stopped_arm(tmp_path_factory):
    path = tmp_path_factory.mktemp("stopped_arm") / "planar_2r.yaml"
    path.write_text(STOPPED_ARM)
    out = symkin.derive(path, path.parent, outputs=["fk", "jacobian"], backends=["numpy", "casadi"], fixed=[])
    return symkin.load(out), symkin.load(out, "casadi")


def test_the_workspace_measure_counts_only_the_nodes_within_the_joint_stops(stopped_arm):
    """int |det J| dq over the joint box cut by theta1 + theta2 <= 90 deg: l1 l2 int_0^pi/2 sin(t) (pi/2 - t) dt =
    l1 l2 (pi/2 - 1).  The surrogate is the smoothed sum over the Sobol nodes within the stop, times the box's
    area over all the nodes (the others lie outside the workspace); the independent rating's estimate covers the
    closed form."""
    numpy_model, _ = stopped_arm
    problem, program, solution = _optimize(stopped_arm, "workspace", ["l1"], bounds={"l1": (0.05, 0.2)})
    assert solution.optimum["l1"] == pytest.approx(0.2, rel=1e-7)
    nodes = program.nodes
    assert len(nodes) < 2 ** formulation.JOINT_NODES_LOG2
    assert bool(np.all(nodes.sum(axis=1) <= np.pi / 2))
    det = np.linalg.det(numpy_model.bind(**solution.optimum).jacobian(nodes))
    smoothed = np.sqrt(det ** 2 + formulation.DETERMINANT_SMOOTHING ** 2 * np.mean(det ** 2))
    surrogate = smoothed.sum() * (np.pi / 2) ** 2 / 2 ** formulation.JOINT_NODES_LOG2
    assert solution.surrogate_optimum == pytest.approx(surrogate, rel=KINEMATICS)
    area = 0.2 * 0.1 * (np.pi / 2 - 1)
    rating = design.evaluate(problem, numpy_model, solution.optimum, samples=2 ** 12)
    assert abs(rating.measure.value - area) <= rating.measure.error
    assert "within the joint stops" in program.description


def test_the_box_configurations_keep_the_joint_stops(stopped_arm):
    """The GCI of the 2R arm over the box (0.11..0.14)^2: without the stop its optimum (l1 = 0.1192 m) reaches the
    corner (0.11, 0.11) with theta2 = 90 deg and theta1 = 5 deg, the forearm at 95 deg; with it every box
    configuration keeps theta1 + theta2 <= 90 deg, the stop binds, and the optimum moves."""
    numpy_model, _ = stopped_arm
    box = {"x": (0.11, 0.14), "y": (0.11, 0.14)}
    _, program, solution = _optimize(stopped_arm, "gci", ["l1"], bounds={"l1": (0.05, 0.3)}, box=box)
    assert solution.success
    assert solution.constraint_violation < 1e-9
    q = solution.box_configurations
    forearm = q.sum(axis=1)
    assert bool(np.all(forearm <= np.pi / 2 + 1e-9))
    assert forearm.max() == pytest.approx(np.pi / 2, abs=1e-8)
    assert abs(solution.optimum["l1"] - np.sqrt(2 * 0.11 ** 2 - 0.1 ** 2)) > 1e-3
    tcp = numpy_model.bind(**solution.optimum).fk(q)[:, :2, 3]
    np.testing.assert_allclose(tcp, program.box_points, rtol=0, atol=1e-9)


def test_a_delta_s_design_keeps_its_joint_stops_at_every_box_point(delta, tmp_path):
    """The DELTA with its first two arms kept within 45 deg of each other: the GCI's optimum over the box without
    the stop (a = 0.101 m) breaks it at the box's corners (60 deg apart); with it, every required point's arms (the
    closed-form ik at the optimum) keep it."""
    path = tmp_path / "delta.yaml"
    path.write_text((MODELS_DIR / "delta.yaml").read_text()
                    + '\njoint_stops:\n  - {expression: "theta1 - theta2", limits: [deg(-45), deg(45)]}\n')
    out = symkin.derive(path, tmp_path, outputs=["ik", "jacobian"], backends=["numpy", "casadi"], fixed=[])
    stopped = symkin.load(out), symkin.load(out, "casadi")
    apart = {}
    for name, models in (("free", delta), ("stopped", stopped)):
        _, program, solution = _optimize(models, "gci", ["a"], bounds={"a": (0.05, 0.3)}, box=DELTA_BOX)
        assert solution.success
        assert solution.constraint_violation < 1e-9
        q = np.asarray(models[0].bind(**solution.optimum).ik(program.box_points).joints)
        apart[name] = np.abs(q[:, 0] - q[:, 1]).max()
    assert apart["free"] > np.radians(50)
    assert apart["stopped"] <= np.radians(45) + 1e-9


def test_delta_optimization_improves_the_gci_and_keeps_the_box_reachable(delta):
    numpy_model, _ = delta
    problem, program, solution = _optimize(delta, "gci", ["r_base", "r_tcp", "a", "b"], box=DELTA_BOX,
                                           margin=0.005, nodes=4)
    assert solution.success
    assert solution.constraint_violation < 1e-9
    assert solution.surrogate_optimum > solution.surrogate_start
    before, after = (design.evaluate(problem, numpy_model, d, samples=2**12)
                     for d in (solution.start, solution.optimum))
    assert after.gci.value - after.gci.error > before.gci.value + before.gci.error
    assert after.box_reachable == 1.0
    # the box with its margin: the closed-form ik margin at a grid denser than the constraint points
    lower, upper = problem.inflated_box
    points = np.stack(np.meshgrid(*[np.linspace(lo, hi, 9) for lo, hi in zip(lower, upper)]), -1).reshape(-1, 3)
    assert np.all(numpy_model.bind(**solution.optimum).ik(points).margin >= -1e-12)
    for p in problem.free:
        assert p.lower - 1e-12 <= solution.optimum[p.name] <= p.upper + 1e-12


def _worst_force(model, design_values, points, limits, joint_limits):
    """min over the points of the isotropic force min_i tau_i / |J_i| by the numpy code, and whether every leg
    reaches every point with its actuated joint within ``joint_limits`` (n, 2), up to IPOPT's constraint
    tolerance (1e-10; 1e-9 rad here)."""
    bound = model.bind(**design_values)
    solution = bound.ik(points)
    q = np.asarray(solution.joints)
    within = (q >= joint_limits[:, 0] - 1e-9) & (q <= joint_limits[:, 1] + 1e-9)
    feasible = np.all(np.asarray(solution.margin) >= -1e-12) and np.all(within)
    return float(np.min(forces.isotropic_force(bound.jacobian(q, points), limits))), bool(feasible)


def test_the_delta_with_the_largest_worst_case_isotropic_force_keeps_the_box(delta):
    """--maximize force: the epigraph optimum is the numpy code's worst force over the program's points, no
    feasible design nearby does better (random designs 1 % around it, numpy only: every point reached with the
    arms within their declared -90..60 deg, which are active), and the independent rating on the 11^3 grid
    improves on the start design."""
    numpy_model, _ = delta
    bounds = {"a": (0.06, 0.15), "b": (0.10, 0.25)}
    limits = np.ones(3)
    problem, program, solution = _optimize(delta, "force", ["a", "b"], bounds=bounds, box=DELTA_BOX,
                                           effort_limits=limits)
    assert solution.success
    assert solution.constraint_violation < 1e-9
    worst, reached = _worst_force(numpy_model, solution.optimum, program.box_points, limits, problem.limits)
    assert reached
    # the surrogate's minimum over the points and the numpy code's: KINEMATICS (a norm of a 3x3 Jacobian's column)
    assert solution.surrogate_optimum == pytest.approx(worst, rel=KINEMATICS)
    assert solution.surrogate_optimum > 1.3 * solution.surrogate_start
    rng = np.random.default_rng(5)
    optimum = np.array([solution.optimum["a"], solution.optimum["b"]])
    for design_values in optimum * (1 + 0.01 * rng.uniform(-1, 1, (40, 2))):
        nearby = {**solution.optimum, "a": design_values[0], "b": design_values[1]}
        force, reached = _worst_force(numpy_model, nearby, program.box_points, limits, problem.limits)
        if reached and bounds["a"][0] <= design_values[0]:
            assert force <= worst * (1 + 1e-9)
    before, after = (design.evaluate(problem, numpy_model, d, samples=2**10) for d in (solution.start, solution.optimum))
    assert after.force > 1.3 * before.force
    assert after.box_reachable == 1.0


def test_the_serial_arm_with_the_largest_worst_case_force_is_the_closed_form_optimum(arm):
    """--maximize force of a serial arm, at its box configurations: the 2R arm (joints 0..90 deg) with tau_max =
    (1, 0.1) N m.  Its columns are |J_1| = |p| and |J_2| = l2, so f_iso = min(1 / |p|, 0.1 / l2) = 0.1 / l2 here:
    the strongest design has the shortest l2 whose arm still reaches every box point with theta2 in [0, 90 deg]:
    the farthest point stretched, l1 + l2 = r_max, the nearest at theta2 = 90 deg, l1^2 + l2^2 = r_min^2, so
    l2 = (r_max - sqrt(2 r_min^2 - r_max^2)) / 2.  IPOPT stops at a relative 1e-10 (ipopt.tol), the optimum
    agrees to 1e-8; the surrogate is the numpy code's worst force at the optimizer's configurations, which
    reach the box points; the independent rating (closed-form ik on an 11^2 grid) gives the same force."""
    numpy_model, _ = arm
    limits = np.array([1.0, 0.1])
    problem, program, solution = _optimize(arm, "force", ["l1", "l2"], bounds={"l1": (0.05, 0.3), "l2": (0.02, 0.3)},
                                           box={"x": (0.11, 0.14), "y": (0.11, 0.14)}, effort_limits=limits)
    assert solution.success
    assert solution.constraint_violation < 1e-9
    reach = np.linalg.norm(program.box_points, axis=-1)
    l2 = (reach.max() - np.sqrt(2 * reach.min() ** 2 - reach.max() ** 2)) / 2
    assert solution.optimum["l2"] == pytest.approx(l2, rel=1e-8)
    assert solution.optimum["l1"] == pytest.approx(reach.max() - l2, rel=1e-8)
    bound = numpy_model.bind(**solution.optimum)
    q = solution.box_configurations
    np.testing.assert_allclose(bound.fk(q)[:, :2, 3], program.box_points, atol=1e-9)
    worst = float(np.min(forces.isotropic_force(bound.jacobian(q), limits)))
    assert solution.surrogate_optimum == pytest.approx(worst, rel=KINEMATICS)
    assert worst == pytest.approx(0.1 / l2, rel=1e-8)
    assert solution.surrogate_start == pytest.approx(0.1 / 0.1, rel=KINEMATICS)  # the start's l2 = 0.1 m
    rating = design.evaluate(problem, numpy_model, solution.optimum, samples=2**10)
    assert rating.box_reachable == 1.0
    assert rating.force == pytest.approx(0.1 / l2, rel=1e-8)


def _heaviest(model, design_values, points):
    """The largest apparent mass at the handle over the points (kg): the largest eigenvalue of (J M^-1 J^T)^-1 by
    the numpy code (analysis.rating), the joints from the closed-form ik."""
    bound = model.bind(**design_values)
    q = np.asarray(bound.ik(points).joints)
    return float(np.max(formulas.principal_masses(bound.mass_matrix(q, points), bound.jacobian(q, points))))


def test_the_strongest_delta_whose_handle_feels_at_most_200_grams(delta):
    """--max-apparent-mass with --maximize force: the DELTA's start (a = 100 mm) feels 0.11 kg at most in the box, the
    force optimum without the bound 0.37 kg (shorter arms reflect the rotors' inertia more). Under a 0.2 kg bound the
    optimum's largest apparent mass over the program's points (numpy: the eigenvalues of (J M^-1 J^T)^-1) is the
    bound, active; its worst force is the numpy code's and above the start's, and no feasible design nearby (1 %,
    within the bound, the box and the arm limits) has more; the independent rating's largest mass over its 11^3 grid
    is the bound's to the grid's resolution."""
    numpy_model, _ = delta
    bounds = {"a": (0.06, 0.15), "b": (0.10, 0.25)}
    limits = np.ones(3)
    problem, program, solution = _optimize(delta, "force", ["a", "b"], bounds=bounds, box=DELTA_BOX,
                                           effort_limits=limits, max_apparent_mass=0.2)
    assert solution.success
    assert solution.constraint_violation < 1e-9
    assert _heaviest(numpy_model, solution.start, program.box_points) < 0.12
    assert _heaviest(numpy_model, solution.optimum, program.box_points) == pytest.approx(0.2, rel=1e-6)
    worst, reached = _worst_force(numpy_model, solution.optimum, program.box_points, limits, problem.limits)
    assert reached
    assert solution.surrogate_optimum == pytest.approx(worst, rel=KINEMATICS)
    assert 1.3 * solution.surrogate_start < worst
    rng = np.random.default_rng(6)
    optimum = np.array([solution.optimum["a"], solution.optimum["b"]])
    for design_values in optimum * (1 + 0.01 * rng.uniform(-1, 1, (40, 2))):
        nearby = {**solution.optimum, "a": design_values[0], "b": design_values[1]}
        force, reached = _worst_force(numpy_model, nearby, program.box_points, limits, problem.limits)
        if reached and _heaviest(numpy_model, nearby, program.box_points) <= 0.2:
            assert force <= worst * (1 + 1e-9)
    after = design.evaluate(problem, numpy_model, solution.optimum, samples=2**10)
    assert after.apparent_mass == pytest.approx(0.2, rel=0.02)


@pytest.mark.parametrize("model_dir, free, kwargs, message", [
    (ARM_DIR, ["l1"], {"box": {"x": (0.11, 0.14), "y": (0.11, 0.14)}}, "rate a serial arm's apparent mass with "
                                                                        "'symkin rate'"),
    (str(GENERATED_DIR / "agile_eye"), ["m_p"], {"box": {"roll": (-0.1, 0.1), "pitch": (-0.1, 0.1),
                                                         "yaw": (-0.1, 0.1)}},
     "a parallel mechanism whose handle translates"),
    (DELTA_DIR, ["a"], {"box": DELTA_BOX, "max_apparent_mass": -1.0}, "a positive mass in kg, got -1"),
    (str(GENERATED_DIR / "stewart"), ["r_b"], {"box": {"x": (-0.01, 0.01), "y": (-0.01, 0.01), "z": (0.22, 0.24)},
                                               "length": 0.2},
     "this handle turns (task space ['x', 'y', 'z', 'roll', 'pitch', 'yaw']: the masses and inertias it feels mix kg "
     "with kg m^2); leave the bound out"),
])
def test_the_apparent_mass_bound_says_what_it_needs(model_dir, free, kwargs, message):
    with pytest.raises(ValueError, match=re.escape(message)):
        design.design_problem(symkin.load(model_dir), "gci", free, **{"max_apparent_mass": 0.2, **kwargs})


def test_a_serial_arm_without_a_mass_matrix_is_told_the_bound_is_for_parallel_models(tmp_path):
    """The apparent-mass bound is checked before the functions it needs are looked up: a serial model's code without
    mass_matrix is told what the bound is for, not to derive mass_matrix."""
    arm = symkin.load(symkin.derive(str(MODELS_DIR / "planar_2r.yaml"), str(tmp_path), outputs=["fk", "jacobian"]))
    with pytest.raises(ValueError, match="rate a serial arm's apparent mass with 'symkin rate'"):
        design.design_problem(arm, "gci", ["l1"], box={"x": (0.11, 0.14), "y": (0.11, 0.14)}, max_apparent_mass=0.2)


@pytest.mark.parametrize("model_dir, kwargs, message", [
    (ARM_DIR, {"effort_limits": [1, 1]}, "the force objective is the isotropic force at the worst point of the "
                                          "required box: give --require-box x=LOWER:UPPER,y=LOWER:UPPER"),
    (DELTA_DIR, {"box": DELTA_BOX}, "give --effort-limit T"),
    (DELTA_DIR, {"effort_limits": [1, 1, 1]}, "the worst-case force of a parallel mechanism is taken over the "
                                              "required workspace box: give --require-box x=LOWER:UPPER"),
    (DELTA_DIR, {"box": DELTA_BOX, "effort_limits": [1, -1, 1]}, "one positive effort limit per actuator"),
])
def test_the_force_objective_says_what_it_needs(model_dir, kwargs, message):
    with pytest.raises(ValueError, match=re.escape(message)):
        design.design_problem(symkin.load(model_dir), "force", ["a"] if model_dir == DELTA_DIR else ["l1"], **kwargs)


def test_cli_on_a_model_file_writes_figures_and_result(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["optimize", str(MODELS_DIR / "planar_2r.yaml"), "--free", "l1", "--bounds", "l1=0.05:0.3",
                 "--nodes", "6", "-n", "1024", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "l1: 0.1 -> 0.1414213562" in text
    assert "IPOPT" in text
    assert "wall" in text
    assert sorted(p.name for p in out.iterdir()) == ["design.png", "history.png", "result.json"]
    for name in ("design.png", "history.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    result = json.loads((out / "result.json").read_text())
    assert result["evaluation"]["optimum"]["gci"] > result["evaluation"]["start"]["gci"]
    assert result["solver"]["name"] == "IPOPT"
    assert result["solver"]["history"][-1] == pytest.approx(result["surrogate_value"]["optimum"])


def test_cli_dimensions_a_parallel_model_file(tmp_path, capsys):
    """A parallel model file is derived with its closed-form fk too: the rating checks the working mode with it."""
    out = tmp_path / "pantograph"
    assert main(["optimize", str(MODELS_DIR / "pantograph.yaml"), "--free", "l,L", "--bounds", "l=0.05:0.1,L=0.07:0.12",
                 "--require-box", "x=-0.03:0.03,y=0.08:0.12", "-n", "64", "--no-cache", "-o", str(out)]) == 0
    result = json.loads((out / "result.json").read_text())
    assert result["evaluation"]["optimum"]["gci"] > result["evaluation"]["start"]["gci"]
    assert "fk(ik(x)) = x" in capsys.readouterr().out


@pytest.mark.parametrize("arguments, message", [
    ([ARM_DIR, "--free", "l3"], "'l3' is not a free parameter of the model; parameters: g, l1, l2, m1, m2"),
    ([ARM_DIR, "--free", "m1"], "the objective does not depend on 'm1'"),
    ([ARM_DIR, "--free", "l1", "--bounds", "l1=0.3:0.1"], "LOWER must be smaller than UPPER"),
    ([ARM_DIR, "--free", "l1", "--bounds", "l1=short:long"], "LOWER and UPPER must be numbers"),
    ([ARM_DIR, "--free", "l1", "--bounds", "l1"], "'l1' is not NAME=LOWER:UPPER"),
    ([ARM_DIR, "--free", "l1", "--bounds", "l2=0.1:0.2"], "--bounds for l2, which is not among the free"),
    ([ARM_DIR, "--free", "l1", "--require-box", "x=0:1"], "missing: y"),
    ([DELTA_DIR, "--free", "a"], "give --require-box x=LOWER:UPPER,y=LOWER:UPPER,z=LOWER:UPPER"),
    ([DELTA_DIR, "--free", "a", "--maximize", "workspace", "--require-box", "x=0:1,y=0:1,z=0:1"],
     "maximizing the workspace of a parallel mechanism is not supported"),
    ([str(GENERATED_DIR / "ur10e"), "--free", "a2"], "mixes translations and rotations"),
    ([ARM_DIR, "--free", "l1", "--nodes", "0"], "--nodes must be between 1 and 16"),
    ([ARM_DIR, "--free", "l1", "--set", "l1=0"], "'l1' starts at 0, so no default span applies; give --bounds"),
])
def test_bad_input_is_refused_with_exit_code_2(tmp_path, capsys, arguments, message):
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as exit_info:
        main(["optimize", *arguments, "-o", str(out)])
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_an_unreachable_box_fails_with_exit_code_1_and_writes_nothing(tmp_path, capsys):
    """The corner (0.05, 0.05) is nearer the base than any 2R design within the bounds reaches at 0..90 deg."""
    out = tmp_path / "out"
    assert main(["optimize", ARM_DIR, "--free", "l1", "--bounds", "l1=0.05:0.3", "--require-box",
                 "x=0.05:0.1,y=0.05:0.1", "-o", str(out)]) == 1
    assert "IPOPT did not converge (Infeasible_Problem_Detected" in capsys.readouterr().err
    assert not out.exists()


def test_delta_actuated_joint_limits_are_kept_over_the_box(delta):
    """Upper arms at most 20 deg above horizontal: the unconstrained optimum needs about 30 deg."""
    numpy_model, _ = delta
    limits = {f"theta{i}": (-np.pi / 2, np.radians(20)) for i in (1, 2, 3)}
    bounds = {"r_base": (0.04, 0.10), "r_tcp": (0.015, 0.04), "a": (0.06, 0.15), "b": (0.10, 0.25)}
    problem, _, solution = _optimize(delta, "gci", list(bounds), bounds=bounds, box=DELTA_BOX, margin=0.005,
                                     limits=limits, nodes=4)
    assert solution.success
    lower, upper = problem.inflated_box
    points = np.stack(np.meshgrid(*[np.linspace(lo, hi, 9) for lo, hi in zip(lower, upper)]), -1).reshape(-1, 3)
    q = numpy_model.bind(**solution.optimum).ik(points).joints
    assert np.degrees(q.max()) == pytest.approx(20.0, abs=1e-6)  # active at the box's top corners
    assert design.evaluate(problem, numpy_model, solution.optimum, samples=2**10).box_reachable == 1.0


def test_a_limited_angle_is_taken_about_its_limits_centre_in_both_programs(tmp_path):
    """The pantograph's proximal joints are limited to [0, pi]; its ik's atan2 returns pi + d as -pi + d: the joint rules
    take it as pi + d (continuous in the design), in numpy and CasADi alike, and leave lengths alone."""
    model = symkin.load(str(GENERATED_DIR / "pantograph"))
    problem = design.design_problem(model, "gci", ["l"], box={"x": (-0.03, 0.03), "y": (0.08, 0.12)})
    rules = formulation.joint_rules(problem, model)
    assert rules.centres == pytest.approx([np.pi / 2, np.pi / 2])
    d = 1e-3
    joints = np.array([[-np.pi + d, 0.3], [np.pi - d, -0.6 * np.pi], [0.0, np.pi / 2]])
    expected = np.array([[np.pi + d, 0.3], [np.pi - d, 1.4 * np.pi], [0.0, np.pi / 2]])
    assert rules.centred(joints) == pytest.approx(expected, abs=4 * np.pi * np.finfo(float).eps)
    q = formulation.casadi.SX.sym("q", 2)
    centred = formulation.casadi.Function("centred", [q], [rules.centred(q, formulation.casadi)])
    for row, want in zip(joints, expected):
        assert np.asarray(centred(row)).ravel() == pytest.approx(want, abs=4 * np.pi * np.finfo(float).eps)
    stewart = symkin.load(str(GENERATED_DIR / "stewart"))  # prismatic legs: lengths, not angles
    legs = formulation.joint_rules(design.design_problem(stewart, "gci", ["r_b"], box={"x": (-0.01, 0.01), "y": (
        -0.01, 0.01), "z": (0.22, 0.24)}, length=0.2), stewart)
    assert np.all(np.isnan(legs.centres))


@pytest.mark.parametrize("model_dir, free, options, flat", [
    (ARM_DIR, ["l1", "l2"], {}, ("l1", "l2")),
    (ARM_DIR, ["l1"], {}, ()),
    (str(GENERATED_DIR / "phantom_premium"), ["l1", "l2"], {}, ("l1", "l2")),       # its fk takes l1 and l2 only
    (ARM_DIR, ["l1", "l2"], {"box": {"x": (0.11, 0.14), "y": (0.11, 0.14)}}, ()),  # the box sets the scale
    (str(GENERATED_DIR / "ur10e"), ["a2", "a3", "d4", "d5", "d6"], {"length": 0.3}, ()),  # so does L (and d1, fixed)
])
def test_a_gci_that_only_sees_the_ratios_of_the_free_lengths_is_said_so(model_dir, free, options, flat):
    """The GCI of a design and of all its free lengths doubled are one number where scale_invariance says so (the
    CasADi surrogate at its nodes), so that the optimum is a ray and the report says which ratios were optimized."""
    numpy_model = symkin.load(model_dir)
    problem = design.design_problem(numpy_model, "gci", free, **options)
    assert design.scale_invariance(problem, numpy_model) == flat
    if not flat:
        return
    program = design.formulate(problem, symkin.load(model_dir, "casadi"), numpy_model, nodes=6)
    start = np.array([problem.start[name] for name in free])
    rest = program.x0[program.free_count:]
    assert float(program.objective(2 * start, rest)) == pytest.approx(float(program.objective(start, rest)),
                                                                      rel=KINEMATICS)


def test_a_6x6_pose_task_with_a_characteristic_length_converges():
    """UR10e, L = 0.3 m: nodes whose det J changes sign with the design would stall IPOPT without smoothing."""
    directory = GENERATED_DIR / "ur10e"
    models = symkin.load(directory), symkin.load(directory, "casadi")
    _, program, solution = _optimize(models, "gci", ["a2", "a3"], length=0.3, nodes=6)
    assert solution.success, solution.status
    assert solution.surrogate_optimum > solution.surrogate_start
