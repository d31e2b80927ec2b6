"""Inverse kinematics: closed forms (planar 2R, UR family) and damped least squares on generated code."""

from __future__ import annotations

import json
import subprocess
import sys

import mpmath
import numpy as np
import pytest

from conftest import MODELS_DIR, SYMKIN_CLI
from symkin import load
from symkin.errors import GeneratedCodeError
from symkin.ik import (BranchFlag, ModelKinematics, closed_form_solver, distinct_solutions, numeric_branches,
                       solve_numeric)
from symkin.ik.rotations import log_so3, pose_from_vector, right_jacobian_inverse, rotation_matrix
from symkin.mechanism.limits import wrap_angle
from tolerances import CLOSED_FORM, KINEMATICS, UR10E_SCALE

UR_MODELS = ["ur10e", "ur10e_classic"]


def _angle_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.max(np.abs(wrap_angle(a - b)), axis=-1)


def _fk_error(model, q: np.ndarray, target: np.ndarray) -> tuple[float, float]:
    T = model.fk(q)
    return (float(np.max(np.abs(T[..., :3, 3] - target[..., :3, 3]))),
            float(np.max(np.abs(T[..., :3, :3] - target[..., :3, :3]))))


@pytest.fixture(scope="module")
def ur(generated_dir):
    return {name: load(generated_dir / name) for name in UR_MODELS}


@pytest.fixture(scope="module")
def arm(generated_dir):
    return load(generated_dir / "planar_2r")


# ----------------------------------------------------------------------------- rotations

def test_log_so3_inverts_the_exponential_up_to_a_half_turn():
    rng = np.random.default_rng(0)
    axis = rng.normal(size=(2000, 3))
    axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
    angle = np.concatenate([rng.uniform(0, np.pi, 1000), np.pi - 10.0 ** -rng.uniform(1, 15, 500),
                            10.0 ** -rng.uniform(1, 15, 500)])
    w = log_so3(rotation_matrix(axis, angle))
    # R's entries (<= 1) are closed forms (CLOSED_FORM absolute); the angle read from them is well
    # conditioned, within CLOSED_FORM plus the log's own ~20 roundings relative (KINEMATICS); w = angle
    # times the axis, angles <= pi: KINEMATICS x pi
    np.testing.assert_allclose(np.linalg.norm(w, axis=-1), angle, rtol=KINEMATICS, atol=CLOSED_FORM)
    regular = angle < np.pi - 1e-6
    np.testing.assert_allclose(w[regular], (axis * angle[:, None])[regular], rtol=0, atol=KINEMATICS * np.pi)


def test_right_jacobian_inverse_matches_finite_differences_of_the_log():
    rng = np.random.default_rng(1)
    for phi in rng.normal(size=(20, 3)) * 0.9:
        R = rotation_matrix(phi / np.linalg.norm(phi), np.linalg.norm(phi))
        h = 1e-7
        numeric = np.stack([(log_so3(R @ rotation_matrix(np.eye(3)[k], h)) - log_so3(R @ rotation_matrix(np.eye(3)[k], -h)))
                            / (2 * h) for k in range(3)], -1)
        np.testing.assert_allclose(right_jacobian_inverse(phi), numeric, atol=1e-7)


# ----------------------------------------------------------------------------- UR family, closed form

@pytest.mark.parametrize("name", UR_MODELS)
def test_ur_closed_form_reproduces_every_target_to_1e_12(ur, name):
    model = ur[name]
    solver = closed_form_solver(model)
    assert solver is not None
    assert solver.name.startswith("UR family")
    assert len(solver.solver.branches) == 8
    rng = np.random.default_rng(2)
    q = rng.uniform(-np.pi, np.pi, (2000, 6))
    T = model.fk(q)
    found = solver.solve(T)
    assert found.q.shape == (2000, 8, 6)
    assert np.all(found.reachable)
    valid = found.valid
    position, rotation = _fk_error(model, found.q[valid], np.broadcast_to(T[:, None], (2000, 8, 4, 4))[valid])
    assert position <= 1e-12
    assert rotation <= 1e-12
    # the configuration that made the target is one of the branches
    distance = np.where(valid, _angle_distance(found.q, q[:, None, :]), np.inf).min(-1)
    assert np.quantile(distance, 0.99) < 1e-10
    assert distance.max() < 1e-7
    # branches that do not exist are reported as such (elbow out of reach), never approximated
    assert np.all((found.flags[~valid] & BranchFlag.UNREACHABLE_ELBOW) != 0)
    assert np.all(np.isnan(found.position_error[~valid]))


def test_classic_and_modified_dh_give_the_same_eight_solutions(ur):
    rng = np.random.default_rng(3)
    q = rng.uniform(-np.pi, np.pi, (200, 6))
    T = ur["ur10e"].fk(q)
    a = closed_form_solver(ur["ur10e"]).solve(T)
    b = closed_form_solver(ur["ur10e_classic"]).solve(T)
    np.testing.assert_array_equal(a.valid, b.valid)
    assert np.max(_angle_distance(a.q[a.valid], b.q[b.valid])) < 1e-9


@pytest.mark.parametrize("name", UR_MODELS)
def test_ur_closed_form_finds_all_branches_that_numeric_ik_finds_from_many_starts(ur, name):
    model = ur[name]
    solver = closed_form_solver(model)
    rng = np.random.default_rng(4)
    kin = ModelKinematics(model)
    for q in rng.uniform(-np.pi, np.pi, (4, 6)):
        T = model.fk(q)
        numeric, result = numeric_branches(kin, T, starts=96, seed=int(rng.integers(1 << 30)))
        closed = solver.solve(T)
        exact = distinct_solutions(kin, closed.q[closed.valid], tolerance=1e-8)
        assert len(numeric) == len(exact) >= 2
        for row in numeric:
            assert np.min(_angle_distance(exact, row)) < 1e-8
        assert result.converged.sum() > 48


def test_ur_wrist_singularity_is_flagged_and_still_exact(ur):
    model = ur["ur10e"]
    solver = closed_form_solver(model)
    for q5 in (0.0, np.pi, 1e-13):
        q = np.array([0.4, -1.1, 1.3, 0.7, q5, -0.5])
        T = model.fk(q)
        found = solver.solve(T)
        wrist = (found.flags & BranchFlag.WRIST) != 0
        same_shoulder = np.abs(wrap_angle(found.q[:, 0] - q[0])) < 1e-9
        assert wrist[same_shoulder].all()
        assert same_shoulder.sum() == 4
        assert not wrist[~same_shoulder].any()  # the other shoulder branch has q5 != 0
        assert found.valid.all()
        position, rotation = _fk_error(model, found.q, np.broadcast_to(T, (8, 4, 4)))
        assert position <= 1e-12
        assert rotation <= 1e-12
        # there the solutions form a one-parameter family (q6 free, q2, q3, q4 follow): the
        # returned member has q5 exactly at the singular value and reproduces the target
        assert np.all(np.abs(wrap_angle(found.q[same_shoulder, 4] - q5)) < 1e-12)


def test_ur_regular_configurations_are_not_flagged(ur):
    found = closed_form_solver(ur["ur10e"]).solve(ur["ur10e"].fk([0.4, -1.1, 1.3, 0.7, 0.9, -0.5]))
    assert np.all(found.flags[found.valid] == 0)


def test_ur_elbow_singularity_stretched_arm(ur):
    model = ur["ur10e"]
    q = np.array([0.3, -0.8, 0.0, 0.5, 1.2, 0.1])
    T = model.fk(q)
    found = closed_form_solver(model).solve(T)
    elbow = (found.flags & BranchFlag.ELBOW) != 0
    assert elbow.sum() >= 2
    assert found.valid[elbow].all()
    position, rotation = _fk_error(model, found.q[found.valid], np.broadcast_to(T, (8, 4, 4))[found.valid])
    assert position <= 1e-12
    assert rotation <= 1e-12
    assert np.min(_angle_distance(found.q[found.valid], q)) < 1e-7


def test_ur_shoulder_singularity_branches_merge(ur):
    """Move q2 until the wrist point is |delta| from axis 1 (bisection), then solve there."""
    model = ur["ur10e"]
    solver = closed_form_solver(model)
    ur_solver = solver.solver
    c1, u = ur_solver.c[0], np.cross(ur_solver.h[0], ur_solver.h2)

    def radial(q2: float) -> float:
        q = np.array([0.0, q2, 1.0, 0.3, 0.8, 0.2])
        w = (model.fk(q) @ ur_solver.M_inv)[:3] @ np.append(ur_solver.w0, 1.0)
        return float(np.dot(u, w - c1))

    lo, hi = 0.5, 1.1
    assert radial(lo) * radial(hi) < 0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if radial(lo) * radial(mid) > 0 else (lo, mid)
    q = np.array([0.0, 0.5 * (lo + hi), 1.0, 0.3, 0.8, 0.2])
    T = model.fk(q)
    found = solver.solve(T)
    assert ((found.flags & BranchFlag.SHOULDER) != 0).all()
    assert found.valid.any()
    np.testing.assert_allclose(found.q[:4, 0], found.q[4:, 0], atol=1e-6)
    position, rotation = _fk_error(model, found.q[found.valid], np.broadcast_to(T, (8, 4, 4))[found.valid])
    assert position <= 1e-12
    assert rotation <= 1e-12


def test_unreachable_pose_is_reported_by_both_solvers(ur):
    model = ur["ur10e"]
    target = pose_from_vector([2.5, 0.3, 0.2, 0.0, 3.0, 0.0])
    found = closed_form_solver(model).solve(target)
    assert not found.reachable
    assert not found.valid.any()
    assert all("no solution" in line for line in found.describe())
    result = solve_numeric(model, target, q0=np.zeros(6))
    assert not result.converged
    assert result.reason in ("stalled", "max_iterations")
    assert result.position_error > 0.5
    # a target inside the cylinder of radius d4 around axis 1 has no shoulder angle
    inside = pose_from_vector([0.02, 0.0, 0.6, 0.0, 3.0, 0.0])
    found = closed_form_solver(model).solve(inside)
    assert not found.valid.any()
    assert np.all((found.flags & BranchFlag.UNREACHABLE_SHOULDER) != 0)


def test_closed_form_batches_any_shape(ur):
    model = ur["ur10e"]
    rng = np.random.default_rng(5)
    T = model.fk(rng.uniform(-np.pi, np.pi, (3, 4, 6)))
    solver = closed_form_solver(model)
    batch = solver.solve(T)
    assert batch.q.shape == (3, 4, 8, 6)
    one = solver.solve(T[2, 1])
    np.testing.assert_array_equal(batch.q[2, 1], one.q)


def test_closed_form_respects_joint_limits(ur):
    model = ur["ur10e"]
    kin = ModelKinematics(model, limits=[(-np.pi, np.pi)] * 5 + [(0.0, 1.0)])
    solver = closed_form_solver(kin)
    q = np.array([0.4, -1.1, 1.3, 0.7, 0.9, 0.5])
    found = solver.solve(model.fk(q))
    assert found.within_limits.any()
    assert not found.within_limits[found.valid].all()
    inside = found.q[found.within_limits]
    assert np.all((inside >= kin.lower) & (inside <= kin.upper))


# ----------------------------------------------------------------------------- planar 2R

def test_planar_2r_both_elbow_branches(arm):
    solver = closed_form_solver(arm)
    assert solver is not None
    assert solver.name == "planar 2R"
    assert solver.kind == "task"
    rng = np.random.default_rng(6)
    q = rng.uniform(-np.pi, np.pi, (2000, 2))
    x = arm.fk(q)[:, :2, 3]
    found = solver.solve(x, reference=np.zeros(2))
    assert found.valid.all()
    T = arm.fk(found.q)
    assert np.max(np.abs(T[..., :2, 3] - x[:, None, :])) <= 1e-12 * 0.2
    # the two elbow branches are +-acos of one computed cosine, wrapped into (-pi, pi]: CLOSED_FORM x pi
    np.testing.assert_allclose(found.q[:, 0, 1], -found.q[:, 1, 1], rtol=0, atol=CLOSED_FORM * np.pi)
    assert np.max(np.min(_angle_distance(found.q, q[:, None, :]), axis=-1)) < 1e-9
    # the seed's limits (0..90 deg) keep only the elbow + branch for targets made within them
    q_in = rng.uniform(0.01, np.pi / 2 - 0.01, (500, 2))
    found = solver.solve(arm.fk(q_in)[:, :2, 3])
    assert found.within_limits[:, 0].all()
    assert not found.within_limits[:, 1].any()


def test_planar_2r_matches_the_textbook_solution_and_its_singular_cases(arm):
    solver = closed_form_solver(arm)
    x, y = 0.12, 0.07
    found = solver.solve([x, y])
    c2 = (x * x + y * y - 0.02) / 0.02
    theta2 = np.arccos(c2)
    theta1 = np.arctan2(y, x) - np.arctan2(0.1 * np.sin(theta2), 0.1 + 0.1 * np.cos(theta2))
    # two closed forms of the same angles (acos, two atan2, sin, cos: ~10 roundings of angles <= pi)
    np.testing.assert_allclose(found.q[0], [theta1, theta2], rtol=0, atol=KINEMATICS * np.pi)
    stretched = solver.solve([0.2, 0.0])
    assert stretched.valid.all()
    assert ((stretched.flags & BranchFlag.ELBOW) != 0).all()
    np.testing.assert_allclose(stretched.q, 0.0, rtol=0, atol=CLOSED_FORM)
    beyond = solver.solve([0.2 + 1e-9, 0.0])
    assert not beyond.valid.any()
    assert ((beyond.flags & BranchFlag.UNREACHABLE_ELBOW) != 0).all()
    rounding = solver.solve([np.nextafter(0.2, 1.0), 0.0])  # on the boundary up to rounding: clamped, flagged
    assert rounding.valid.all()
    assert ((rounding.flags & BranchFlag.CLAMPED) != 0).all()
    folded = solver.solve([0.0, 0.0])
    assert folded.valid.all()
    assert ((folded.flags & BranchFlag.SHOULDER) != 0).all()


def test_planar_2r_elbow_angle_error_is_bounded_by_its_conditioning(arm):
    """theta2 -> 0 is a true singularity of the problem: d = |x| = (l1 + l2)(1 - theta2^2/8 + ...),
    so theta2's relative condition number is |d theta2/dd| d / theta2 ~ 4/theta2^2.  Against
    mpmath at 50 digits (same float target) the error stays within a few eps times that, and
    FK(IK(x)) = x holds to rounding (backward stability)."""
    solver = closed_form_solver(arm)
    eps = np.finfo(float).eps
    for theta2 in 10.0 ** -np.arange(1.0, 8.0):
        x = arm.fk([0.3, theta2])[:2, 3]
        found = solver.solve(x)
        with mpmath.workdps(50):
            l = mpmath.mpf("0.1")
            d = mpmath.sqrt(mpmath.mpf(x[0]) ** 2 + mpmath.mpf(x[1]) ** 2)
            exact = mpmath.acos((d * d - 2 * l * l) / (2 * l * l))
            condition = float(abs(d * d / (l * l * mpmath.sin(exact) * exact)))
        assert abs(found.q[0, 1] - float(exact)) <= 4 * eps * condition * float(exact)
        assert np.max(np.abs(arm.fk(found.q[0])[:2, 3] - x)) <= 2 * eps * 0.2


def test_ur_wrist_angle_is_accurate_near_the_wrist_singularity(ur):
    """q5 -> 0: q5 is the angle between two unit vectors, well conditioned; atan2(|k x a6|, k . a6)
    keeps it to about 1e-16 rad where the textbook acos(k . a6) is off by about 1e-8 rad."""
    model = ur["ur10e"]
    solver = closed_form_solver(model)
    for q5 in 10.0 ** -np.arange(2.0, 14.0):
        q = np.array([0.4, -1.1, 1.3, 0.7, q5, -0.5])
        found = solver.solve(model.fk(q))
        branch = int(np.argmin(_angle_distance(found.q[:, :4], q[:4])))
        assert abs(found.q[branch, 4] - q5) <= CLOSED_FORM, (q5, found.q[branch, 4])  # an atan2 of two components
    textbook_error = abs(np.arccos(np.clip(np.cos(1e-8) + 1e-16, -1, 1)) - 1e-8)
    assert textbook_error > 1e-9  # one rounding of the cosine: the acos form's error at q5 = 1e-8


# ----------------------------------------------------------------------------- numeric

@pytest.mark.parametrize("name", UR_MODELS)
def test_numeric_ik_converges_to_1e_12_on_batches(ur, name):
    model = ur[name]
    rng = np.random.default_rng(7)
    q = rng.uniform(-np.pi, np.pi, (300, 6))
    T = model.fk(q)
    start = q + rng.normal(scale=0.1, size=q.shape)
    result = solve_numeric(model, T, start)
    assert result.converged.all(), result.reason[~result.converged]
    assert np.all(result.reason == "converged")
    position, rotation = _fk_error(model, result.q, T)
    assert position <= 1e-12
    assert rotation <= 1e-12
    assert result.iterations.max() < 50
    assert result.q.shape == (300, 6)
    assert result.position_error.shape == (300,)


def test_numeric_ik_from_one_start_reports_local_minima_honestly(ur):
    model = ur["ur10e"]
    rng = np.random.default_rng(8)
    T = model.fk(rng.uniform(-np.pi, np.pi, (200, 6)))
    result = solve_numeric(model, T, np.zeros(6))
    assert result.converged.mean() > 0.7
    failed = ~result.converged
    assert np.all(np.isin(result.reason[failed], ["stalled", "max_iterations"]))
    assert np.all(np.maximum(result.position_error[failed], result.orientation_error[failed]) > 1e-6)
    position, rotation = _fk_error(model, result.q[~failed], T[~failed])
    assert position <= 1e-12
    assert rotation <= 1e-12


def test_numeric_ik_respects_joint_limits(arm):
    rng = np.random.default_rng(9)
    q = rng.uniform(0.05, np.pi / 2 - 0.05, (200, 2))
    x = arm.fk(q)[:, :2, 3]
    result = solve_numeric(arm, x, q0=[np.pi / 4, np.pi / 4])
    assert result.kind == "task"
    assert result.converged.all()
    np.testing.assert_allclose(result.q, q, atol=1e-9)
    assert np.all((result.q >= 0) & (result.q <= np.pi / 2))
    # reachable only with theta1 < 0: the solver stops at the limit and says so
    blocked = solve_numeric(arm, [0.15, -0.05], q0=[0.5, 0.5])
    assert not blocked.converged
    assert blocked.at_limit[0]
    assert blocked.q[0] == 0.0
    assert blocked.position_error > 1e-3
    assert "joints at a limit: 1" in blocked.summary()


def test_numeric_ik_beyond_reach_is_not_reported_as_converged(arm):
    result = solve_numeric(arm, [0.25, 0.0], q0=[0.3, 0.3])
    assert not result.converged
    assert result.position_error == pytest.approx(0.05, abs=1e-9)


def test_numeric_ik_pose_targets_of_a_planar_model(arm):
    q = np.array([0.3, 0.9])
    result = solve_numeric(arm, arm.fk(q), q0=[0.5, 0.5], kind="pose")
    assert result.converged
    assert result.kind == "pose"
    np.testing.assert_allclose(result.q, q, atol=1e-12)


def test_numeric_ik_needs_the_generated_functions(tmp_path):
    import symkin

    path = symkin.derive(MODELS_DIR / "planar_2r.yaml", tmp_path, outputs=["frames"])
    with pytest.raises(GeneratedCodeError, match="needs the generated 'fk'"):
        ModelKinematics(load(path))
    path = symkin.derive(MODELS_DIR / "ur10e.yaml", tmp_path, outputs=["fk"])
    with pytest.raises(GeneratedCodeError, match="jacobian_geometric"):
        solve_numeric(load(path), np.eye(4))
    assert closed_form_solver(load(path)) is None


def test_no_closed_form_for_other_structures(tmp_path):
    import symkin

    model = tmp_path / "arm3.yaml"
    model.write_text((MODELS_DIR / "planar_2r.yaml").read_text().replace(
        "      - [theta2, R, 0, 0, l2, 0, [0, deg(90)]]",
        "      - [theta2, R, 0, 0, l2, 0, [0, deg(90)]]\n      - [theta3, R, 0, 0, l2, pi/2]"))
    loaded = load(symkin.derive(model, tmp_path, outputs=["fk", "jacobian_geometric", "jacobian"]))
    assert closed_form_solver(loaded) is None
    q = np.array([0.3, 0.4, 0.5])
    result = solve_numeric(loaded, loaded.fk(q)[:2, 3], q0=[0.5, 0.5, 0.0])
    assert result.converged


def test_ik_does_not_import_sympy(generated_dir):
    code = ("import sys, numpy as np; from symkin import load; from symkin.ik import closed_form_solver, "
            f"solve_numeric; m = load({str(generated_dir / 'ur10e')!r}); T = m.fk(np.full(6, 0.3)); "
            "closed_form_solver(m).solve(T); solve_numeric(m, T); print('sympy' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False"]


# ----------------------------------------------------------------------------- CLI

def test_cli_lists_the_eight_ur_solutions(tmp_path):
    result = subprocess.run(SYMKIN_CLI + ["ik", str(MODELS_DIR / "ur10e.yaml"), "--target", "0.5", "0.2", "0.4",
                                          "0", "3.14159", "0", "--json"], capture_output=True, text=True,
                            cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout)
    solutions = report["targets"][0]["solutions"]
    assert len(solutions) == 8
    assert all(s["valid"] for s in solutions)
    assert list(tmp_path.iterdir()) == []


def test_cli_exit_codes(generated_dir):
    arm = str(generated_dir / "planar_2r")
    ok = subprocess.run(SYMKIN_CLI + ["ik", arm, "-t", "0.1", "0.1"], capture_output=True, text=True)
    assert ok.returncode == 0
    assert "elbow +" in ok.stdout
    unreachable = subprocess.run(SYMKIN_CLI + ["ik", arm, "-t", "0.3", "0"], capture_output=True, text=True)
    assert unreachable.returncode == 1
    assert "no solution" in unreachable.stdout
    numeric = subprocess.run(SYMKIN_CLI + ["ik", arm, "-t", "0.1", "0.1", "--method", "numeric", "--q0", "0.5",
                                           "0.5"], capture_output=True, text=True)
    assert numeric.returncode == 0
    assert "converged after" in numeric.stdout
    bad = subprocess.run(SYMKIN_CLI + ["ik", arm, "-t", "0.1"], capture_output=True, text=True)
    assert bad.returncode == 2
    assert "has 2 values, got 1" in bad.stderr


def test_joint_limits_come_from_the_manifest(arm, ur):
    assert arm.joint_limits == ((0.0, np.pi / 2), (0.0, np.pi / 2))
    assert ur["ur10e"].joint_limits == ((-2 * np.pi, 2 * np.pi),) * 6
    assert arm.manifest["model"]["coordinates"][0] == {"name": "theta1", "type": "R", "limits": [0.0, np.pi / 2]}


def test_joint_screws_from_fk_alone_match_the_jacobian_ones(ur, arm, tmp_path):
    """Without a generated pose Jacobian (a model file derived on the fly for the analyses:
    fk and the task Jacobian), the screws come from fk(pi/2 e_i) M^-1 and agree with J(0)'s."""
    import symkin
    from symkin.ik.screws import home_screws

    for model in (arm, ur["ur10e"], ur["ur10e_classic"]):
        kin = ModelKinematics(model)
        kin._pose_jacobian = None  # as if jacobian_geometric had not been generated
        from_fk, from_jacobian = home_screws(kin), home_screws(ModelKinematics(model))
        np.testing.assert_allclose(from_fk.directions, from_jacobian.directions, rtol=0, atol=KINEMATICS)
        np.testing.assert_allclose(from_fk.points, from_jacobian.points, rtol=0, atol=KINEMATICS * UR10E_SCALE)
    lean = load(symkin.derive(MODELS_DIR / "planar_2r.yaml", tmp_path, outputs=["fk", "jacobian"]))
    q = np.array([[0.3, 0.9], [1.2, 0.0]])
    found = closed_form_solver(lean).solve(lean.fk(q)[:, :2, 3])
    assert found.valid.all()
    assert found.solver == "planar 2R"
    assert np.max(_angle_distance(found.q[:, 0], q)) < 1e-7


def test_solve_without_shifting_keeps_the_solver_angles(ur):
    """shift=False (the workspace analyses apply limits of their own): the same branches and
    checks, the angles as the solver gives them (equal modulo 2 pi), within_limits as they lie."""
    model = ur["ur10e"]
    solver = closed_form_solver(model, limits=[(0.0, 2.0 * np.pi)] * 6)
    T = model.fk(np.random.default_rng(11).uniform(-np.pi, np.pi, (50, 6)))
    shifted, raw = solver.solve(T), solver.solve(T, shift=False)
    assert np.array_equal(shifted.valid, raw.valid)
    assert np.array_equal(shifted.flags, raw.flags)
    assert np.all(_angle_distance(shifted.q, raw.q)[shifted.valid] < 1e-12)
    assert shifted.within_limits[shifted.valid].all()
    assert not raw.within_limits[raw.valid].all()


def test_a_coupled_chain_is_no_product_of_exponentials_and_says_so_without_warnings():
    """The PHANToM's elbow is driven through a parallelogram from the base (q3 turns the distal link about an axis
    that moves with q2): fk(pi/2 e_3) is no screw motion of its own, the axis read from it is NaN.  That is refused
    as not a plain serial chain (before: NaN passed the fk check, which compared with '>'), with no RuntimeWarning
    for the user, and no closed form is offered."""
    import warnings

    from conftest import GENERATED_DIR
    from symkin.ik.screws import home_screws

    phantom = load(GENERATED_DIR / "phantom_premium")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(GeneratedCodeError, match="not a product of exponentials"):
            home_screws(ModelKinematics(phantom))
        assert closed_form_solver(phantom) is None
