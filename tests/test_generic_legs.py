"""Legs of any topology (issue 31): a Schoenflies platform on two SCARA legs R-R-P-R, whose legs have no
distance form, solved from its loop closure alone (symkin.runtime.parallel).

The model is the one docs/model-format.md declares ("Legs of any topology"), read from there.  Independent
oracles: the device's geometry written out here (leg 2's planar 2R places the bar's right end B2, the bar's
left end B1 lies where the circle of leg 1's distal link about its elbow meets the circle of the bar's length
about B2), finite differences of that closed form, the distance form of the DELTA (its generated jacobian
and singularity measures), and the mobility of a mechanism of the Schoenflies group (eq. 8.2, lambda = 4).
The check of the declared motion (symkin.parallel.motion_check) against the example models, which move as
declared, and against declarations the legs contradict.
"""

from __future__ import annotations

import re
import subprocess

import numpy as np
import pytest

from conftest import ROOT, SYMKIN_CLI
from symkin import load, pipeline
from symkin.model import model_from_text
from symkin.parallel.motion_check import check_platform_motion
from symkin.runtime.parallel import closure_velocities, solve_closure
from symkin.structure.mobility import SCHOENFLIES, SPATIAL, model_mobility
from tolerances import EPS, KINEMATICS

DOC = ROOT / "docs" / "model-format.md"
D, L1, L2, E = 0.3, 0.25, 0.25, 0.1
HOME = np.array([0.0, 0.3, 0.1, 0.0])
#: solve_closure's step tolerance: with quadratic convergence the error after the last step is far below it.
SOLVE_TOL = 1e-12
#: Positions and lengths of this device are below its reach l1 + l2 + d = 0.8 m.
SCALE = 0.8


def model_text() -> str:
    match = re.search(r"cat > dual_scara.yaml <<'EOF_MODEL'\n(.*?)^EOF_MODEL$", DOC.read_text(), re.S | re.M)
    assert match, "docs/model-format.md lost the dual SCARA"
    return match.group(1)


@pytest.fixture(scope="module")
def scara(tmp_path_factory):
    model = model_from_text(model_text(), file="dual_scara.yaml")
    request = pipeline.resolve_request(model, fixed="all")
    return load(pipeline.write(pipeline.generate(model, request), tmp_path_factory.mktemp("scara")))


@pytest.fixture(scope="module")
def home_joints(scara):
    """(q, s) at the home pose: the assembly mode the docs' rough start leads to (elbows turned clockwise)."""
    report = solve_closure(scara, [1.0, 0.1, 1.6, 0.0], np.zeros(4), HOME, unknowns=("q", "s"), max_step=0.2)
    assert report.all_converged
    return report.solution["q"], report.solution["s"]


def _planar_2r(base_x, first, second):
    return np.stack([base_x + L1 * np.cos(first) + L2 * np.cos(first + second),
                     L1 * np.sin(first) + L2 * np.sin(first + second)], axis=-1)


def closed_form(q, side=1.0):
    """(p, s) from q by the geometry: B2 from leg 2's 2R, B1 on the circles |B1 - E1| = l2 and
    |B1 - B2| = 2e (on the ``side`` of E1 -> B2), the bar's middle and direction; NaN where they do not meet."""
    theta, lift, phi, knee = np.moveaxis(np.asarray(q, dtype=float), -1, 0)
    E1 = np.stack([-D / 2 + L1 * np.cos(theta), L1 * np.sin(theta)], axis=-1)
    B2 = _planar_2r(D / 2, phi, knee)
    c = B2 - E1
    distance = np.linalg.norm(c, axis=-1)
    along = (L2**2 - (2 * E) ** 2 + distance**2) / (2 * distance)
    with np.errstate(invalid="ignore"):
        across = side * np.sqrt(L2**2 - along**2)
    u = c / distance[..., None]
    B1 = E1 + along[..., None] * u + across[..., None] * np.stack([-u[..., 1], u[..., 0]], axis=-1)
    yaw = np.arctan2(B2[..., 1] - B1[..., 1], B2[..., 0] - B1[..., 0])
    distal = np.arctan2(B1[..., 1] - E1[..., 1], B1[..., 0] - E1[..., 0])
    wrap = lambda angle: np.angle(np.exp(1j * angle))  # noqa: E731 - into (-pi, pi]
    s = np.stack([wrap(distal - theta), wrap(yaw - distal), lift, wrap(yaw - phi - knee)], axis=-1)
    return np.concatenate([(B1 + B2) / 2, lift[..., None], yaw[..., None]], axis=-1), s


def _near_home(home_joints, count, seed):
    q_home, _ = home_joints
    q = q_home + np.random.default_rng(seed).uniform(-1, 1, (count, 4)) * [0.2, 0.05, 0.2, 0.2]
    p, s = closed_form(q)
    assembled = np.all(np.isfinite(p), axis=-1)
    return q, p, s, assembled


def test_the_schoenflies_group_has_lambda_4():
    report = model_mobility(model_from_text(model_text()))
    assert report.lam == SCHOENFLIES
    assert report.mobility == report.intended == 4
    tilted = model_text().replace("{name: hand, type: R, axis: [0, 0, 1]}", "{name: hand, type: R, axis: [0, 1, 0]}")
    assert model_mobility(model_from_text(tilted)).lam == SPATIAL


def test_closed_form_branch_is_the_home_assembly(home_joints):
    q, s = home_joints
    p, s_closed = closed_form(q)
    np.testing.assert_allclose(p, HOME, atol=SOLVE_TOL)
    np.testing.assert_allclose(s, s_closed, atol=SOLVE_TOL)


def test_forward_and_inverse_kinematics_from_the_closure(scara, home_joints):
    q, p, s, assembled = _near_home(home_joints, 400, 41)
    assert 0.3 < assembled.mean() < 0.95  # the sample reaches past the workspace's edge on purpose
    fk = solve_closure(scara, q, home_joints[1], HOME, unknowns=("p", "s"), max_step=0.1)
    np.testing.assert_array_equal(fk.converged, assembled)  # converges exactly where the circles meet
    np.testing.assert_allclose(fk.solution["p"][assembled], p[assembled], atol=SOLVE_TOL)
    np.testing.assert_allclose(fk.solution["s"][assembled], s[assembled], atol=SOLVE_TOL)
    assert fk.residual[assembled].max() <= KINEMATICS * SCALE
    ik = solve_closure(scara, home_joints[0], home_joints[1], p[assembled], unknowns=("q", "s"), max_step=0.1)
    assert ik.all_converged
    np.testing.assert_allclose(ik.solution["q"], q[assembled], atol=SOLVE_TOL)


def test_jacobian_and_passive_rates_are_the_derivatives_of_the_geometry(scara, home_joints):
    q, p, s, assembled = _near_home(home_joints, 400, 42)
    q, p, s = q[assembled], p[assembled], s[assembled]
    velocities = closure_velocities(scara, q, s, p)
    h = 1e-6
    steps = h * np.eye(4)
    fd = [(np.array(closed_form(q + step)) - np.array(closed_form(q - step))) / (2 * h) for step in steps]
    fd_p = np.stack([d[0] for d in fd], axis=-1)
    fd_s = np.stack([d[1] for d in fd], axis=-1)
    # Away from the singularities (entries <= 5): truncation h^2 |f'''| / 6 and rounding EPS / h, ~1e-10 each.
    regular = np.abs(velocities.J).max(axis=(1, 2)) < 5
    assert regular.mean() > 0.5
    np.testing.assert_allclose(velocities.J[regular], fd_p[regular], atol=1e-8)
    np.testing.assert_allclose(velocities.passive[regular], fd_s[regular], atol=1e-8)
    assert np.all(velocities.interior > 0)
    assert np.all(velocities.boundary > 0)


def _assembled(scara, q, p):
    """s at a consistent (q, p), from the closed form, refined on the closure."""
    _, s = closed_form(q)
    report = solve_closure(scara, q, s, p, unknowns=("s",))
    assert report.all_converged
    return report.solution["s"]


def test_singularity_measures_vanish_at_both_kinds(scara, home_joints):
    q_home, s_home = home_joints
    reference = closure_velocities(scara, q_home, s_home, HOME)
    # Boundary: leg 2 stretched (knee 0): its actuators can move together with B2 held.
    stretched = np.array([np.pi / 3, 0.1, np.pi / 2, 0.0])
    p, _ = closed_form(stretched)
    at_boundary = closure_velocities(scara, stretched, _assembled(scara, stretched, p), p)
    # Interior: leg 1's distal link along the bar (|B2 - E1| = l2 + 2e): the bar turns about B2 with the
    # actuators locked.  Leg 2 reaches B2 = E1 + (l2 + 2e) x by its 2R inverse kinematics.
    theta = np.pi / 3
    E1 = np.array([-D / 2 + L1 * np.cos(theta), L1 * np.sin(theta)])
    B2 = E1 + [L2 + 2 * E, 0.0]
    r = B2 - [D / 2, 0.0]
    knee = -np.arccos((r @ r - L1**2 - L2**2) / (2 * L1 * L2))
    phi = np.arctan2(r[1], r[0]) - np.arctan2(L2 * np.sin(knee), L1 + L2 * np.cos(knee))
    folded = np.array([theta, 0.1, phi, knee])
    p = np.array([B2[0] - E, B2[1], 0.1, 0.0])
    np.testing.assert_allclose(_planar_2r(D / 2, phi, knee), B2, atol=KINEMATICS)
    at_interior = closure_velocities(scara, folded, _assembled(scara, folded, p), p)
    # A product of singular values whose smallest is zero comes out at the rounding of the SVD of an
    # 8 x 4 matrix (4 n EPS sigma_max, LAPACK) times the others: relative to the home pose's, far below 1e-12.
    assert at_boundary.boundary / reference.boundary < 1e3 * EPS
    assert at_boundary.interior / reference.interior > 0.05
    assert at_interior.interior / reference.interior < 1e3 * EPS
    assert at_interior.boundary / reference.boundary > 0.05
    assert np.all(np.isnan(at_interior.J))


def test_closure_velocities_agree_with_the_distance_form_of_the_delta(generated_dir):
    delta = load(generated_dir / "delta")
    rng = np.random.default_rng(43)
    p = np.column_stack([rng.uniform(-0.04, 0.04, (300, 2)), rng.uniform(-0.18, -0.12, 300)])
    theta = delta.ik(p).joints
    s = solve_closure(delta, theta, np.zeros(12), p, unknowns=("s",)).solution["s"]
    velocities = closure_velocities(delta, theta, s, p)
    J = delta.jacobian(theta, p)
    np.testing.assert_allclose(velocities.J, J, atol=KINEMATICS * np.abs(J).max() * 100)
    # Both kinds of measure are zero together with the distance form's determinants: over the sample the
    # generic one is proportional to |det| for the DELTA (each leg's constraint is one rod direction).
    singular = delta.singularities(theta, p)
    for generic, distance in ((velocities.interior, singular.det_Jx), (velocities.boundary, singular.det_Jq)):
        ratio = generic / np.abs(distance)
        np.testing.assert_allclose(ratio, ratio[0], rtol=1e-9)


def test_unassembled_samples_give_nan(scara, home_joints):
    q, s = home_joints
    velocities = closure_velocities(scara, np.stack([q, q + np.nan]), s, HOME)
    assert np.all(np.isfinite(velocities.J[0]))
    assert np.all(np.isnan(velocities.J[1]))
    assert np.isnan(velocities.interior[1])


# --------------------------------------------------------------------------- the declared motion, checked

@pytest.mark.parametrize("name", ["delta", "pantograph", "agile_eye", "delta_wrist", "stewart"])
def test_the_example_models_legs_constrain_the_platform_to_its_declared_motion(name, models):
    """At the home pose the legs' joint twists intersect in exactly the declared coordinates' twists (actuators
    free) and in none (locked); the pantograph's handle is a point, its spin in the joint idle."""
    check = check_platform_motion(models[name])
    assert check.problems == ()
    assert check.note == ""
    assert (check.free, check.locked) == (len(models[name].task_space), 0)


def test_the_schoenflies_platform_moves_as_declared_and_a_wrong_declaration_is_located():
    check = check_platform_motion(model_from_text(model_text()))
    assert (check.problems, check.free, check.locked) == ((), 4, 0)
    # declared roll where the legs turn the bar about z: both directions named
    rolling = check_platform_motion(model_from_text(model_text().replace("motion: schoenflies",
                                                                         "motion: [x, y, z, roll]")))
    assert len(rolling.problems) == 2
    assert "turn about (0, 0, 1) (its coordinate yaw), which parallel.motion [x, y, z, roll] holds at 0" in \
        rolling.problems[0]
    assert "do not let the platform move in its coordinate roll" in rolling.problems[1]
    # yaw left out and leg 2's knee made passive: the bar turns with every actuator locked
    loose = (model_text().replace("motion: schoenflies", "motion: [x, y, z]").replace("home: [0, 0.3, 0.1, 0]",
                                                                                       "home: [0, 0.3, 0.1]")
             .replace("{name: knee, type: R, axis: [0, 0, 1], active: true,", "{name: knee, type: R, axis: [0, 0, 1],"))
    check = check_platform_motion(model_from_text(loose))
    assert check.locked == 1
    assert "with the actuators locked the legs still let the platform turn about (0, 0, -1)" in check.problems[0]


def test_the_mobility_command_reports_a_wrong_motion_with_its_place_and_exit_2(tmp_path):
    path = tmp_path / "rolling.yaml"
    path.write_text(model_text().replace("motion: schoenflies", "motion: [x, y, z, roll]"))
    result = subprocess.run(SYMKIN_CLI + ["mobility", str(path)], capture_output=True, text=True)
    assert result.returncode == 2
    assert f"{path}: parallel.motion: the legs let the platform turn about (0, 0, 1) (its coordinate yaw)" in \
        result.stderr
    good = tmp_path / "dual_scara.yaml"
    good.write_text(model_text())
    result = subprocess.run(SYMKIN_CLI + ["mobility", str(good)], capture_output=True, text=True)
    assert result.returncode == 0
    assert "at the home pose: the legs let the platform move in [x, y, z, yaw] (4 DoF)" in result.stdout
