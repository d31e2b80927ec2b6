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

from conftest import SYMKIN_CLI
from sample_models import dual_scara_text
from symkin import load, pipeline
from symkin.analysis.continued_workspace import continued_workspace
from symkin.mechanism.closure import assemble_at_home, solve_home_assembly
from symkin.model import model_from_text
from symkin.reporting import reporting_to
from symkin.parallel.motion_check import check_platform_motion
from symkin.runtime.parallel import closure_velocities, solve_closure
from symkin.structure.mobility import SCHOENFLIES, SPATIAL, model_mobility
from tolerances import EPS, KINEMATICS

D, L1, L2, E = 0.3, 0.25, 0.25, 0.1
HOME = np.array([0.0, 0.3, 0.1, 0.0])
#: solve_closure's step tolerance: with quadratic convergence the error after the last step is far below it.
SOLVE_TOL = 1e-12
#: Positions and lengths of this device are below its reach l1 + l2 + d = 0.8 m.
SCALE = 0.8


@pytest.fixture(scope="module")
def scara_dir(tmp_path_factory):
    model = model_from_text(dual_scara_text(), file="dual_scara.yaml")
    request = pipeline.resolve_request(model, "closure,closure_jacobians,leg_joints", fixed="all")
    return pipeline.write(pipeline.generate(model, request), tmp_path_factory.mktemp("scara"))


@pytest.fixture(scope="module")
def scara(scara_dir):
    return load(scara_dir)


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
    report = model_mobility(model_from_text(dual_scara_text()))
    assert report.lam == SCHOENFLIES
    assert report.mobility == report.intended == 4
    tilted = dual_scara_text().replace("{name: hand, type: R, axis: [0, 0, 1]}", "{name: hand, type: R, axis: [0, 1, 0]}")
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
    check = check_platform_motion(model_from_text(dual_scara_text()))
    assert (check.problems, check.free, check.locked) == ((), 4, 0)
    # declared roll where the legs turn the bar about z: both directions named
    rolling = check_platform_motion(model_from_text(dual_scara_text().replace("motion: schoenflies",
                                                                         "motion: [x, y, z, roll]")))
    assert len(rolling.problems) == 2
    assert "turn about (0, 0, 1) (its coordinate yaw), which parallel.motion [x, y, z, roll] holds at 0" in \
        rolling.problems[0]
    assert "do not let the platform move in its coordinate roll" in rolling.problems[1]
    # yaw left out and leg 2's knee made passive: the bar turns with every actuator locked
    loose = (dual_scara_text().replace("motion: schoenflies", "motion: [x, y, z]").replace("home: [0, 0.3, 0.1, 0]",
                                                                                       "home: [0, 0.3, 0.1]")
             .replace("{name: knee, type: R, axis: [0, 0, 1], active: true,", "{name: knee, type: R, axis: [0, 0, 1],"))
    check = check_platform_motion(model_from_text(loose))
    assert check.locked == 1
    assert "with the actuators locked the legs still let the platform turn about (0, 0, 1)" in check.problems[0]


def test_the_mobility_command_reports_a_wrong_motion_with_its_place_and_exit_2(tmp_path):
    path = tmp_path / "rolling.yaml"
    path.write_text(dual_scara_text().replace("motion: schoenflies", "motion: [x, y, z, roll]"))
    result = subprocess.run(SYMKIN_CLI + ["mobility", str(path)], capture_output=True, text=True)
    assert result.returncode == 2
    assert f"{path}: parallel.motion: the legs let the platform turn about (0, 0, 1) (its coordinate yaw)" in \
        result.stderr
    good = tmp_path / "dual_scara.yaml"
    good.write_text(dual_scara_text())
    result = subprocess.run(SYMKIN_CLI + ["mobility", str(good)], capture_output=True, text=True)
    assert result.returncode == 0
    assert "at the home pose: the legs let the platform move in [x, y, z, yaw] (4 DoF)" in result.stdout


def test_symkin_check_locates_a_motion_the_legs_contradict(tmp_path, capsys):
    """`symkin check` runs the motion check: the wrong parallel.motion is refused with its line and exit 2, the
    declared one passes."""
    from symkin.cli import main

    path = tmp_path / "rolling.yaml"
    text = dual_scara_text().replace("motion: schoenflies", "motion: [x, y, z, roll]")
    path.write_text(text)
    line = text[:text.index("motion: [x, y, z, roll]")].count("\n") + 1
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"{path}:{line}" in err
    assert "the legs let the platform turn about (0, 0, 1) (its coordinate yaw)" in err
    assert "symkin mobility MODEL prints them" in err
    good = tmp_path / "dual_scara.yaml"
    good.write_text(dual_scara_text())
    assert main(["check", str(good)]) == 0
    assert "ok - model 'dual_scara'" in capsys.readouterr().out


#: The lift's stroke (m) for the workspace: a prismatic actuator needs limits, the model file declares none.
STROKE = (0.0, 0.2)


def _inverse_in_mode(poses, elbow_sign, knee_sign):
    """The device's inverse kinematics at poses (x, y, z, yaw) in the branch (elbow_sign, knee_sign) of the legs,
    written from the geometry: the bar's ends B1, B2 = (x, y) -+ e (cos yaw, sin yaw); leg 2 a planar 2R to B2,
    leg 1 a planar 2R (theta, elbow) to B1.  Returns (q, wrist) with q NaN where a leg does not reach; wrist =
    yaw - the distal link's angle."""
    def two_r(base_x, target, sign):
        dx, dy = target[..., 0] - base_x, target[..., 1]
        cosine = (dx**2 + dy**2 - L1**2 - L2**2) / (2 * L1 * L2)
        with np.errstate(invalid="ignore"):
            second = sign * np.arccos(cosine)
        first = np.arctan2(dy, dx) - np.arctan2(L2 * np.sin(second), L1 + L2 * np.cos(second))
        return first, second
    half_bar = E * np.stack([np.cos(poses[..., 3]), np.sin(poses[..., 3])], axis=-1)
    theta, elbow = two_r(-D / 2, poses[..., :2] - half_bar, elbow_sign)
    phi, knee = two_r(D / 2, poses[..., :2] + half_bar, knee_sign)
    return np.stack([theta, poses[..., 2], phi, knee], axis=-1), poses[..., 3] - (theta + elbow)


@pytest.fixture(scope="module")
def scara_flood(scara):
    """The continued workspace, and what it reported while it ran (symkin.reporting)."""
    reports: list[tuple[str, int | None, int | None]] = []
    with reporting_to(lambda stage, done=None, total=None: reports.append((stage, done, total))):
        found = continued_workspace(scara, limits={"lift1": STROKE}, cells=20)
    return found, reports


@pytest.fixture(scope="module")
def scara_workspace(scara_flood):
    return scara_flood[0]


def test_the_flood_reports_the_cells_it_has_reached(scara_flood):
    """Issue 60 (10): the flood's count grows layer by layer up to the cells it reaches (no total: the workspace is
    what it finds); the grid's size is in the stage."""
    found, reports = scara_flood
    floods = [(stage, done) for stage, done, total in reports if stage.startswith("flooding a grid")]
    assert floods
    assert all(total is None for stage, _, total in reports if stage.startswith("flooding a grid"))
    runs: list[list[int]] = []
    for _stage, done in floods:
        if done == 1:                                        # a flood starts from its seed cell
            runs.append([])
        runs[-1].append(done)
    assert all(run == sorted(run) for run in runs)
    assert 1 < runs[-1][-1] <= np.count_nonzero(found.occupancy.occupied)   # the last layer is reported before


def test_the_home_assembly_closes_the_legs(scara):
    q, s = assemble_at_home(scara)
    p = np.array([closed_form(q, side)[0] for side in (1.0, -1.0)])
    assert np.min(np.max(np.abs(p - HOME), axis=-1)) <= SOLVE_TOL


class _StrokeOf:
    """A loaded model seen with other actuator limits (everything else its own)."""

    def __init__(self, model, limits):
        self._model, self.joint_limits = model, limits

    def __getattr__(self, name):
        return getattr(self._model, name)


def test_the_home_assembly_keeps_the_struts_within_their_stroke(generated_dir):
    """generated/stewart: q = s = 0 closes the legs with four struts turned around (lengths -0.26 m, outside the
    stroke [0.20, 0.32] m): refused; the middle of the stroke gives the assembly of the closed-form ik's lengths.
    A stroke the home pose cannot take is refused with the reason."""
    stewart = load(generated_dir / "stewart")
    found = solve_home_assembly(stewart)
    home = np.asarray(stewart.info.home, dtype=float)
    np.testing.assert_allclose(found.q, stewart.ik(home).joints, rtol=0, atol=KINEMATICS)
    assert found.start == "the middle of the actuators' limits, s = 0"
    with pytest.raises(ValueError, match=r"close only outside the declared joint limits"):
        solve_home_assembly(_StrokeOf(stewart, ((0.40, 0.50),) * 6))


def test_the_continued_workspace_is_the_working_mode_written_from_the_geometry(scara, scara_workspace):
    """The reached cells are those where both legs reach the bar's ends in the home assembly's branches, the
    distal link of leg 1 stays on the home side of the bar (sin(wrist1) keeps its sign: the interior
    singularity is the distal link along the bar) and the lift is within its stroke, connected to the home cell
    (scipy.ndimage's face connectivity, as the flood's)."""
    from scipy import ndimage

    q0, s0 = assemble_at_home(scara)
    found = scara_workspace
    centres = found.occupancy.centers()
    poses = np.concatenate([centres, np.zeros(centres.shape[:-1] + (1,))], axis=-1)
    q, wrist = _inverse_in_mode(poses, np.sign(np.sin(s0[0])), np.sign(np.sin(q0[3])))
    mode = (np.all(np.isfinite(q), axis=-1) & (np.sign(np.sin(wrist)) == np.sign(np.sin(s0[1])))
            & (centres[..., 2] >= STROKE[0]) & (centres[..., 2] <= STROKE[1]))
    labels, _ = ndimage.label(mode)
    home_cell = tuple(((HOME[:3] - found.occupancy.lower) // found.occupancy.cell).astype(int))
    assert labels[home_cell] > 0, "the home pose lies in the working mode"
    expected = labels == labels[home_cell]
    assert expected.sum() > 300  # a volume, not a few cells
    np.testing.assert_array_equal(found.occupancy.occupied, expected)
    reached = found.occupancy.occupied
    wrapped = np.angle(np.exp(1j * (found.q[reached] - q[reached])))  # the continuation does not wrap angles
    np.testing.assert_allclose(wrapped[:, [0, 2, 3]], 0.0, atol=KINEMATICS)
    np.testing.assert_allclose(found.q[reached][:, 1], centres[reached][:, 2], atol=KINEMATICS)


def test_the_workspace_conditioning_is_that_of_the_closure_jacobian(scara, scara_workspace):
    """1/kappa at a cell: the singular values of J = dp/dq written from the geometry (central differences of
    the inverse kinematics, inverted) with the position rows divided by the characteristic length."""
    from symkin.numerics.conditioning import homogenize, inverse_condition_number

    q0, s0 = assemble_at_home(scara)
    found = scara_workspace
    reached = found.occupancy.occupied
    points = found.occupancy.centers()[reached][::37]
    poses = np.concatenate([points, np.zeros((len(points), 1))], axis=-1)
    h = 1e-6
    columns = []
    for k in range(4):
        step = np.zeros(4)
        step[k] = h
        plus = _inverse_in_mode(poses + step, np.sign(np.sin(s0[0])), np.sign(np.sin(q0[3])))[0]
        minus = _inverse_in_mode(poses - step, np.sign(np.sin(s0[0])), np.sign(np.sin(q0[3])))[0]
        columns.append((plus - minus) / (2 * h))
    inverse_jacobian = np.stack(columns, axis=-1)  # dq/dp, the yaw column included
    J = homogenize(np.linalg.inv(inverse_jacobian), found.length, (0, 1, 2))
    # central differences: truncation h^2 ~ 1e-12, rounding eps / h ~ 1e-10 in dq/dp; 1/kappa moves by as much
    np.testing.assert_allclose(found.inv_kappa[reached][::37], inverse_condition_number(J), atol=1e-6)
    assert found.gci == pytest.approx(np.mean(found.inv_kappa[reached]))


def test_legs_without_closed_forms_are_sampled_by_continuation(scara):
    from symkin import mechanism

    assert mechanism.sampling(scara) is mechanism.Sampling.CONTINUATION
    assert mechanism.sampled_in_task_space(scara)


def test_the_workspace_command_continues_the_closure_and_refuses_an_unbounded_stroke(scara_dir, tmp_path):
    result = subprocess.run(SYMKIN_CLI + ["workspace", str(scara_dir), "--limit", "lift1=0:0.2", "-n", "8000",
                                          "--map", str(tmp_path / "map.png"), "-o", str(tmp_path / "ws.png")],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert "working mode of the home assembly at yaw = 0 deg" in result.stdout
    assert re.search(r"\d+ reached cells; volume: ", result.stdout)
    assert "mean over the workspace (GCI)" in result.stdout
    assert (tmp_path / "map.png").stat().st_size > 0
    assert (tmp_path / "ws.png").stat().st_size > 0
    result = subprocess.run(SYMKIN_CLI + ["workspace", str(scara_dir), "--limit", "lift1=0:1e6", "--no-figure"],
                            capture_output=True, text=True)
    assert result.returncode == 2
    assert "it is unbounded within the joint limits; declare limits on the prismatic joints" in result.stderr
    result = subprocess.run(SYMKIN_CLI + ["workspace", str(scara_dir), "--limit", "lift1=0:0.2",
                                          "--orientation", "0,5deg,0", "--no-figure"], capture_output=True, text=True)
    assert result.returncode == 2
    assert "holds pitch = 0.0872665 at 0 (parallel.motion); give 0 there" in result.stderr


def test_the_gci_command_averages_over_the_continued_workspace(scara_dir, scara_workspace):
    """`symkin gci` of legs without closed forms: the mean 1/kappa of the same grid as continued_workspace (-n 8000:
    20 cells a side), printed to the digits its error estimate supports, and the options that do not apply refused."""
    result = subprocess.run(SYMKIN_CLI + ["gci", str(scara_dir), "--limit", "lift1=0:0.2", "-n", "8000"],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    match = re.search(r"GCI = (\d+\.(\d+)) \+- ", result.stdout)
    assert match, result.stdout
    assert abs(float(match.group(1)) - scara_workspace.gci) <= 0.5 * 10.0 ** -len(match.group(2))
    assert "the working mode of the home assembly at yaw = 0 deg" in result.stdout
    result = subprocess.run(SYMKIN_CLI + ["gci", str(scara_dir), "--limit", "lift1=0:0.2", "--domain", "joint"],
                            capture_output=True, text=True)
    assert result.returncode == 2
    assert "--domain: dual_scara's legs have no closed forms" in result.stderr


def _geometry_jacobian(poses, elbow_sign, knee_sign):
    """J = dp/dq (..., 4, 4) of the device from central differences of the geometry's inverse kinematics."""
    h = 1e-6
    columns = []
    for k in range(4):
        step = np.zeros(4)
        step[k] = h
        plus = _inverse_in_mode(poses + step, elbow_sign, knee_sign)[0]
        minus = _inverse_in_mode(poses - step, elbow_sign, knee_sign)[0]
        columns.append((plus - minus) / (2 * h))
    return np.linalg.inv(np.stack(columns, axis=-1))


def test_the_rating_of_legs_without_closed_forms_is_that_of_the_geometrys_jacobian(scara):
    """datasheet.rate of the dual SCARA over its continued workspace: the isotropic force and the resolution are
    those of J = dp/dq written from the geometry (its x, y, z rows: the handle pushed with its yaw free), the torque
    about z that of its yaw row; without bodies the apparent mass is not rated, and the
    datasheet says why; the home pose is the last sample."""
    from symkin.rating import datasheet, forces, formulas

    efforts, steps = np.array([1.0, 2.0, 1.0, 0.5]), np.array([1e-3, 1e-5, 1e-3, 2e-3])
    actuation = datasheet.Actuation.of_model(scara, effort_limits=efforts, joint_steps=steps)
    sheet = datasheet.rate(scara, actuation, samples=4000, limits={"lift1": STROKE})
    for group in ("apparent_mass", "gravity_share", "apparent_inertia"):   # listed, with the reason (issue 60)
        assert "no mass properties" in sheet.skipped[group], group
    np.testing.assert_allclose(sheet.points[sheet.home], HOME[:3], atol=KINEMATICS)
    q0, s0 = assemble_at_home(scara)
    poses = np.concatenate([sheet.points, np.zeros((len(sheet.points), 1))], axis=-1)
    J = _geometry_jacobian(poses, np.sign(np.sin(s0[0])), np.sign(np.sin(q0[3])))
    measures = {m.name: m.values for m in sheet.measures}
    # central differences: truncation h^2 ~ 1e-12, rounding eps / h ~ 1e-10 in dq/dp, amplified by J's conditioning
    np.testing.assert_allclose(measures["isotropic_force"], forces.isotropic_force(J[:, :3], efforts), rtol=1e-6)
    np.testing.assert_allclose(measures["resolution"], formulas.position_resolution(J[:, :3], steps), rtol=1e-6)
    np.testing.assert_allclose(measures["isotropic_torque"], forces.isotropic_force(J[:, 3:], efforts), rtol=1e-6)


def test_the_simulation_says_what_analyses_legs_without_closed_forms(scara_dir):
    """`symkin simulate` of the dual SCARA without bodies: no simulation, and the message says what it needs (the
    legs' closure_dynamics, from bodies) instead of asking for outputs such legs cannot have."""
    result = subprocess.run(SYMKIN_CLI + ["simulate", str(scara_dir), "-o", str(scara_dir.parent / "simulation")],
                            capture_output=True, text=True)
    assert result.returncode == 2
    assert "simulating them needs the generated closure_dynamics (declare bodies" in result.stderr
    assert not (scara_dir.parent / "simulation").exists()


def test_symkin_view_of_the_model_file_needs_the_lifts_stroke(tmp_path, capsys):
    """`symkin view` derives the dual SCARA's model file with what its page evaluates (the closure, its Jacobians,
    leg_joints; the browser's side: tests/viewer/test_viewer_browser.py); its unlimited lift is refused with the option
    that bounds it, and nothing is written."""
    from symkin.cli import main

    (tmp_path / "dual_scara.yaml").write_text(dual_scara_text())
    out = tmp_path / "scara.html"
    command = ["view", str(tmp_path / "dual_scara.yaml"), "-o", str(out), "--workspace", "64"]
    with pytest.raises(SystemExit) as refused:
        main(command)
    assert refused.value.code == 2
    assert "prismatic joint 'lift1' declares no limits" in capsys.readouterr().err
    assert not out.exists()
    assert main(command + ["--limit", "lift1=0:0.2"]) == 0
    assert "reached by continuing the loop closure from the home pose" in capsys.readouterr().out
    assert "function leg_joints(q, s, params)" in out.read_text()


def test_leg_joints_walk_each_leg_to_its_platform_attachment(scara, home_joints):
    """leg_joints at an assembled (q, s): each leg from its first joint at its base point to its end, which is the
    bar's end the leg carries (p -+ e along the bar's direction); the joint centres as the geometry places them."""
    q, s = home_joints
    theta, lift, phi, knee = q
    legs = scara.leg_joints(q, s)
    assert legs._fields == ("leg1", "leg2")
    yaw = HOME[3]
    bar = np.array([np.cos(yaw), np.sin(yaw), 0.0]) * E
    elbow1 = [-D / 2 + L1 * np.cos(theta), L1 * np.sin(theta), 0.0]
    np.testing.assert_allclose(legs.leg1[:2], [[-D / 2, 0, 0], elbow1], atol=KINEMATICS)
    np.testing.assert_allclose(legs.leg1[-1], HOME[:3] - bar, atol=KINEMATICS)
    assert legs.leg1[-1][2] == pytest.approx(lift, abs=KINEMATICS)  # the lift raises the wrist to the bar
    np.testing.assert_allclose(legs.leg2[1], [D / 2 + L1 * np.cos(phi), L1 * np.sin(phi), 0.0], atol=KINEMATICS)
    np.testing.assert_allclose(legs.leg2[2][:2], _planar_2r(D / 2, phi, knee), atol=KINEMATICS)
    np.testing.assert_allclose(legs.leg2[-1], HOME[:3] + bar, atol=KINEMATICS)


def test_legs_with_the_distance_form_are_drawn_by_leg_points(derivations):
    kept, skipped = derivations["delta"].available(["leg_joints"])
    assert kept == []
    assert "drawn by leg_points" in skipped["leg_joints"]


def test_angle_rows_become_angular_velocity_at_each_pose():
    """A task space with roll, pitch and yaw: each sample's angle rows are turned into angular velocity by E of its
    own pose (omega = E d(roll, pitch, yaw)/dt, mechanism.reach.angular_velocity_matrix), not of the home pose;
    a task space with yaw alone keeps its rows."""
    from types import SimpleNamespace

    from symkin.mechanism.continuation import angular_rates
    from symkin.mechanism.reach import angular_velocity_matrix

    rng = np.random.default_rng(8)
    J, poses = rng.normal(size=(5, 6, 6)), rng.uniform(-1, 1, (5, 6))
    pose_model = SimpleNamespace(info=SimpleNamespace(task_space=("x", "y", "z", "roll", "pitch", "yaw")))
    turned = angular_rates(pose_model, J, poses)
    for k in range(5):
        E = np.eye(6)
        E[3:, 3:] = angular_velocity_matrix(poses[k, 3:])
        np.testing.assert_allclose(turned[k], E @ J[k], rtol=0, atol=16 * EPS * np.max(np.abs(J[k])))
    schoenflies = SimpleNamespace(info=SimpleNamespace(task_space=("x", "y", "z", "yaw")))
    np.testing.assert_array_equal(angular_rates(schoenflies, J[:, :4, :4], poses[:, :4]), J[:, :4, :4])


def test_symkin_derive_refuses_a_motion_the_legs_contradict_and_writes_nothing(tmp_path, capsys):
    """`symkin derive` runs the check of `symkin check` before deriving: the same located refusal, exit 2, no output
    directory; the declared motion derives."""
    from symkin.cli import main

    path = tmp_path / "rolling.yaml"
    text = dual_scara_text().replace("motion: schoenflies", "motion: [x, y, z, roll]")
    path.write_text(text)
    line = text[:text.index("motion: [x, y, z, roll]")].count("\n") + 1
    out = tmp_path / "out"
    assert main(["derive", str(path), "-o", str(out), "--only", "closure", "--no-cache"]) == 2
    err = capsys.readouterr().err
    assert f"{path}:{line}" in err
    assert "do not let the platform move in its coordinate roll" in err
    assert not out.exists()
    good = tmp_path / "dual_scara.yaml"
    good.write_text(dual_scara_text())
    assert main(["derive", str(good), "-o", str(out), "--only", "closure", "--no-cache", "-q"]) == 0
    assert (out / "dual_scara" / "manifest.json").exists()
