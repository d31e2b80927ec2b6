"""Constant-orientation workspace, conditioning and GCI of the Stewart-Gough platform (models/stewart.yaml).

Oracles, written here from the model's geometry with plain numpy (no symkin code): the leg
lengths |p + R b_i - a_i| and their actuator stroke give an independent Monte Carlo volume and
GCI; the inverse Jacobian of a UPS platform, rows (u_i, (R b_i) x u_i) with u_i the unit leg
vector (Merlet, Parallel Robots, sec. 3.1), gives an independent 1/kappa.  At the home
orientation the assembly mode of the home pose is the half-space z > 0 (the platform above
the base; the plane z = 0 is singular).
"""

from __future__ import annotations

import re

import numpy as np
import pytest

import symkin
from symkin.numerics import conditioning as C
from symkin.mechanism import feasibility
from symkin.analysis import global_indices, grids, inverse, workspace
from symkin.mechanism import reach
from symkin import mechanism
from symkin.cli import main

from conftest import GENERATED_DIR, MODELS_DIR

STEWART_DIR = str(GENERATED_DIR / "stewart")
STEWART = symkin.load(STEWART_DIR)
HELD = reach.constant_orientation(STEWART)
TILTED = np.radians([5.0, -8.0, 20.0])
#: Characteristic length of the tests (m): fixed, so no test depends on the 'auto' search.
LENGTH = 0.1
PNG = b"\x89PNG\r\n\x1a\n"


# --- the independent oracle ------------------------------------------------------------------


def _geometry():
    """Base joints a_i, platform joints b_i (platform frame) and the stroke, from the model file's numbers."""
    import yaml

    text = (MODELS_DIR / "stewart.yaml").read_text()
    data = yaml.safe_load(text)
    assert "limits: [0.20, 0.32]" in text
    assert data["parameters"]["r_b"]["value"] == 0.2
    gamma = np.radians(15.0)
    base = np.radians([0, 0, 120, 120, 240, 240]) + np.array([-gamma, gamma] * 3)
    top = np.radians([-60, 60, 60, 180, 180, 300]) + np.array([gamma, -gamma] * 3)
    a = 0.2 * np.stack([np.cos(base), np.sin(base), np.zeros(6)], -1)
    b = 0.1 * np.stack([np.cos(top), np.sin(top), np.zeros(6)], -1)
    return a, b, (0.20, 0.32)


A, B, STROKE = _geometry()


def _rotation(roll, pitch, yaw):
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _legs(points, orientation=(0.0, 0.0, 0.0)):
    """Leg vectors (N, 6, 3) from a_i to the platform joints."""
    Rb = B @ _rotation(*orientation).T
    return points[:, None, :] + Rb[None] - A[None]


def _inverse_condition(points, orientation=(0.0, 0.0, 0.0), length=LENGTH):
    """1/kappa of the homogenized twist Jacobian from the textbook J^-1 rows (u_i, (R b_i) x u_i).

    dq = J^-1 t with t = (v, omega); homogenizing J's translational rows by 1/L multiplies
    J^-1's translational columns by L.
    """
    legs = _legs(points, orientation)
    u = legs / np.linalg.norm(legs, axis=-1, keepdims=True)
    Rb = np.broadcast_to(B @ _rotation(*orientation).T, u.shape)
    J_inv = np.concatenate([length * u, np.cross(Rb, u)], axis=-1)
    s = np.linalg.svd(J_inv, compute_uv=False)
    return s[:, -1] / s[:, 0]


def _monte_carlo(orientation=(0.0, 0.0, 0.0), count=1_000_000, seed=1):
    """Volume, its standard error, the reachable points and the box, by plain Monte Carlo over a generous box."""
    lower, upper = np.array([-0.22, -0.22, 0.0]), np.array([0.22, 0.22, 0.33])
    points = np.random.default_rng(seed).uniform(lower, upper, (count, 3))
    lengths = np.linalg.norm(_legs(points, orientation), axis=-1)
    inside = np.all((lengths >= STROKE[0]) & (lengths <= STROKE[1]), axis=-1)
    fraction = inside.mean()
    box = np.prod(upper - lower)
    reached = points[inside]
    # the box holds the workspace: no reachable sample near its faces
    assert np.all(reached - lower > 0.02)
    assert np.all(upper - reached > 0.02)
    return box * fraction, box * np.sqrt(fraction * (1 - fraction) / count), reached


@pytest.fixture(scope="module")
def oracle():
    return _monte_carlo()


@pytest.fixture(scope="module")
def ik():
    return inverse.inverse_kinematics_for(HELD)


# --- workspace -------------------------------------------------------------------------------


def test_the_held_platform_is_a_positional_parallel_mechanism_with_the_leg_limits(ik):
    assert isinstance(ik, reach.ConstantOrientationInverse)
    assert ik.dimension == 3
    assert mechanism.position_axes(HELD) == (0, 1, 2)
    assert mechanism.mixes_translations_and_rotations(HELD)
    np.testing.assert_array_equal(mechanism.joint_limits(HELD), [STROKE] * 6)
    np.testing.assert_allclose(HELD.orientation, 0.0)
    # the sphere centres c_i = a_i - R b_i, read off the generated ik
    tilted = reach.constant_orientation(STEWART, TILTED)
    np.testing.assert_allclose(reach.leg_sphere_centres(tilted), A - B @ _rotation(*TILTED).T, atol=1e-12)


def test_raw_pose_platform_and_translational_models_are_refused_with_a_message():
    with pytest.raises(ValueError, match="constant orientation"):
        reach.generated_inverse(STEWART)
    with pytest.raises(ValueError, match="task space x, y, z, roll, pitch, yaw"):
        reach.constant_orientation(symkin.load(GENERATED_DIR / "delta"), (0, 0, 0))
    with pytest.raises(ValueError, match="singularity of the roll-pitch-yaw angles"):
        reach.constant_orientation(STEWART, (0, np.pi / 2, 0))


def test_reachability_is_the_stroke_in_the_assembly_mode_of_home(ik):
    points = np.random.default_rng(2).uniform([-0.22, -0.22, -0.33], [0.22, 0.22, 0.33], (20_000, 3))
    lengths = np.linalg.norm(_legs(points), axis=-1)
    expected = np.all((lengths >= STROKE[0]) & (lengths <= STROKE[1]), axis=-1) & (points[:, 2] > 0)
    got = feasibility.reachable(ik, points, mechanism.joint_limits(HELD), mechanism.revolute_mask(HELD))
    assert expected.sum() > 300
    np.testing.assert_array_equal(got, expected)


@pytest.mark.parametrize("orientation", [(0.0, 0.0, 0.0), tuple(TILTED)])
def test_volume_agrees_with_an_independent_monte_carlo(oracle, orientation):
    volume, error, _ = oracle if orientation == (0.0, 0.0, 0.0) else _monte_carlo(orientation, 600_000, seed=3)
    held = reach.constant_orientation(STEWART, orientation)
    measured = global_indices.workspace_measure(held, domain="cartesian", inverse=reach.generated_inverse(held),
                                                method="qmc", samples=2**15, seed=0)
    assert abs(measured.value - volume) <= 4.0 * np.hypot(error, measured.error / 2.0)
    assert measured.error < 0.02 * measured.value


def test_reachable_cells_approach_the_volume_and_the_boundary_holds_the_lowest_conditioning(oracle, ik):
    box = reach.bounding_box(HELD)
    occupancy, values = grids.index_grid(HELD, ik, box, 0.008, length=LENGTH)
    # cells whose centre is reachable: a midpoint rule for the volume (thin spikes of the
    # workspace fall between centres, so the interior/occupied bracket is not guaranteed)
    assert abs(occupancy.occupied.sum() * occupancy.cell_volume - oracle[0]) < 0.02 * oracle[0]
    reachable = occupancy.occupied
    assert np.all(np.isfinite(values[reachable]))
    assert np.all(np.isnan(values[~reachable]))
    worst = reachable & (values <= np.quantile(values[reachable], 0.01))
    assert (worst & occupancy.boundary()).sum() >= 0.9 * worst.sum()


# --- conditioning ----------------------------------------------------------------------------


@pytest.mark.parametrize("orientation", [(0.0, 0.0, 0.0), tuple(TILTED)])
def test_inverse_condition_matches_the_textbook_inverse_jacobian(oracle, orientation):
    held = reach.constant_orientation(STEWART, orientation)
    points = oracle[2][:400]
    q = held.ik(points).joints
    scored = global_indices.scaled_index(held, C.inverse_condition_number, LENGTH, mechanism.joint_limits(held))
    got = scored(mechanism.jacobian(held, q, points))
    np.testing.assert_allclose(got, _inverse_condition(points, orientation), rtol=1e-10)
    # a longer L changes the value (homogenization acts)
    assert not np.allclose(got, _inverse_condition(points, orientation, length=2 * LENGTH))


def test_singular_and_unassembled_poses_give_zero_never_nan():
    # the platform in the plane of the base joints: every leg horizontal, det J^-1 = 0
    points = np.array([[0.0, 0.0, 0.0], [0.03, -0.02, 0.0]])
    q = HELD.ik(points).joints
    assert np.all(np.isfinite(q))
    J = C.homogenize(HELD.jacobian(q, points), LENGTH, (0, 1, 2))
    np.testing.assert_array_equal(C.inverse_condition_number(J), 0.0)
    np.testing.assert_array_equal(C.condition_number(J), np.inf)
    np.testing.assert_array_equal(C.inverse_frobenius_condition_number(J), 0.0)
    J_nan = HELD.jacobian(np.full((1, 6), np.nan), np.array([[0.0, 0.0, 0.23]]))
    np.testing.assert_array_equal(C.inverse_condition_number(J_nan), 0.0)


# --- GCI -------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def oracle_gci(oracle):
    """Mean 1/kappa over the Monte Carlo sample of the workspace (uniform in W): the GCI, and its standard error."""
    values = _inverse_condition(oracle[2])
    return values.mean(), values.std() / np.sqrt(len(values))


@pytest.mark.parametrize("method, samples", [("qmc", 2**14), ("mc", 2**15), ("grid", 2**15), ("adaptive", 2**15)])
def test_gci_estimators_converge_to_the_independent_value(oracle_gci, ik, method, samples):
    result = global_indices.gci(HELD, domain="cartesian", inverse=ik, method=method, samples=samples, seed=4,
                                length=LENGTH)
    reference, error = oracle_gci
    assert abs(result.value.value - reference) <= 4.0 * error + 0.005 * reference
    if method != "adaptive":  # the adaptive cubature's estimate on the 3-D indicator is far too pessimistic (~1)
        assert abs(result.value.value - reference) <= 4.0 * error + result.value.error
        assert result.value.error < 0.01 * result.value.value
    assert "assembly mode of the home pose" in result.description


def test_automatic_length_minimizes_the_mean_kappa_f_squared(ik):
    length = reach.characteristic_length_of(HELD)
    points = grids.reachability_grid(HELD, ik, reach.bounding_box(HELD), 0.01)
    points = points.centers()[points.occupied]
    J = HELD.jacobian(HELD.ik(points).joints, points)

    def cost(L):
        return np.mean(C.inverse_frobenius_condition_number(C.homogenize(J, L, (0, 1, 2))) ** -2.0)

    assert 0.05 < length < 0.2
    assert cost(length) < min(cost(0.8 * length), cost(1.25 * length))


# --- commands --------------------------------------------------------------------------------


def test_workspace_command_reports_the_volume_and_draws_the_figures(tmp_path, capsys, oracle):
    cloud, kappa_map = tmp_path / "cloud.png", tmp_path / "map.png"
    assert main(["workspace", STEWART_DIR, "--length", str(LENGTH), "-o", str(cloud), "--map", str(kappa_map)]) == 0
    out = capsys.readouterr().out
    assert "reachable cells of a Cartesian grid at roll, pitch, yaw = 0, 0, 0 deg" in out
    volume = float(re.search(r"volume: ([0-9.e-]+) \+- ([0-9.e-]+) m\^3 \(qmc", out).group(1))
    assert abs(volume - oracle[0]) < 0.03 * oracle[0]
    sections = tmp_path / "map-sections.png"
    assert f"1/kappa sections: {sections}" in out
    assert all(path.read_bytes()[:8] == PNG for path in (cloud, kappa_map, sections))


def test_gci_command_derives_a_model_file_on_the_fly(capsys):
    """A platform that rotates has no closed-form fk: the analyses derive ik and J^-1 only."""
    args = ["--length", str(LENGTH), "-n", "4096", "--seed", "0"]
    assert main(["gci", STEWART_DIR, *args]) == 0
    from_directory = re.search(r"GCI = ([0-9.]+)", capsys.readouterr().out).group(1)
    assert main(["gci", str(MODELS_DIR / "stewart.yaml"), *args]) == 0
    assert re.search(r"GCI = ([0-9.]+)", capsys.readouterr().out).group(1) == from_directory


def test_gci_command_integrates_over_the_cartesian_domain_at_the_given_orientation(capsys):
    assert main(["gci", STEWART_DIR, "--length", str(LENGTH), "-n", "8192", "--seed", "0"]) == 0
    home = capsys.readouterr().out
    assert "roll, pitch, yaw = 0, 0, 0 deg" in home
    assert main(["gci", STEWART_DIR, "--length", str(LENGTH), "-n", "8192", "--seed", "0",
                 "--orientation", "5deg,-8deg,20deg"]) == 0
    tilted = capsys.readouterr().out
    assert "roll, pitch, yaw = 5, -8, 20 deg" in tilted
    gci = [float(re.search(r"GCI = ([0-9.]+)", out).group(1)) for out in (home, tilted)]
    assert 0.2 < gci[1] < gci[0] < 0.35


@pytest.mark.parametrize("arguments, message", [
    (["gci", STEWART_DIR, "--orientation", "0,1"], "is not ROLL,PITCH,YAW"),
    (["gci", STEWART_DIR, "--orientation", "0,a,1"], "is not ROLL,PITCH,YAW"),
    (["workspace", STEWART_DIR, "--orientation", "0,90deg,0", "--no-figure"], "singularity of the roll-pitch-yaw"),
    (["gci", STEWART_DIR, "--domain", "joint"], "(--domain cartesian)"),
    (["gci", str(GENERATED_DIR / "delta"), "--orientation", "0,0,0"], "leave the option out"),
    (["gci", STEWART_DIR, "--length", "-1"], "--length must be positive"),
    (["workspace", STEWART_DIR, "--limit", "l1=1.0:1.2", "--no-figure"], "no platform position is reachable"),
])
def test_bad_options_exit_with_code_2_and_a_message(arguments, message, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(arguments)
    assert exit_info.value.code == 2
    assert message in capsys.readouterr().err


# --- passive-joint limits --------------------------------------------------------------------


def test_passive_limits_of_the_base_joints_bound_the_legs_elevation(tmp_path):
    """U joints limited to ub_2 in [-75, -50] deg: each leg's elevation above the base plane in [50, 75] deg.

    The base U joint turns the leg frame Rz(angle_i) about z (ub_1), then about the new y
    (ub_2), so the leg's unit vector has the z component -sin(ub_2): elevation = -ub_2.
    """
    text = (MODELS_DIR / "stewart.yaml").read_text()
    plain = "{name: ub, type: U, axes: [[0, 0, 1], [0, 1, 0]]}"
    assert plain in text
    path = tmp_path / "stewart.yaml"
    path.write_text(text.replace(plain, plain[:-1] + ", limits: [null, [deg(-75), deg(-50)]]}"))
    assert main(["derive", str(path), "-o", str(tmp_path), "--only", "ik,inverse_jacobian,closure,closure_jacobians",
                 "--backend", "numpy"]) == 0
    held = reach.constant_orientation(symkin.load(tmp_path / "stewart"))
    points = np.random.default_rng(5).uniform([-0.16, -0.16, 0.15], [0.16, 0.16, 0.3], (3000, 3))
    legs = _legs(points)
    lengths = np.linalg.norm(legs, axis=-1)
    elevation = np.degrees(np.arcsin(legs[..., 2] / lengths))
    stroke = np.all((lengths >= STROKE[0]) & (lengths <= STROKE[1]), axis=-1)
    expected = stroke & np.all((elevation >= 50) & (elevation <= 75), axis=-1)
    got = feasibility.reachable(reach.generated_inverse(held), points, mechanism.joint_limits(held),
                            mechanism.revolute_mask(held))
    assert 100 < expected.sum() < 0.8 * stroke.sum()  # the limits cut the workspace
    np.testing.assert_array_equal(got, expected)
