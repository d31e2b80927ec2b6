"""Workspace, conditioning and GCI of a parallel mechanism: the DELTA (issue 6, parallel part).

Oracles: mpmath's SVD at 40 digits (3 x 3 closed form), finite differences of the generated
fk (the Jacobian whose determinant is the volume element), the geometry of a stretched leg
(boundary singularity, det J_q = 0 in closed form), and the two independent formulations
of the workspace (joint domain through fk with |det J| dq; Cartesian domain through ik with
the reachability indicator), which must agree.
"""

from __future__ import annotations

import re

import mpmath
import numpy as np
import pytest

import symkin
from symkin.numerics import conditioning as C
from symkin.mechanism import feasibility
from symkin.analysis import convergence, global_indices, grids, inverse, workspace
from symkin.mechanism.working_mode import working_mode
from symkin import mechanism
from symkin.mechanism import reach
from symkin.cli import main
from symkin.model import load_model

from conftest import GENERATED_DIR, MODELS_DIR
from tolerances import EPS, KINEMATICS, svd

DELTA_DIR = str(GENERATED_DIR / "delta")
DELTA = symkin.load(DELTA_DIR)
FULL_TURN = {f"theta{i}": (-np.pi, np.pi) for i in (1, 2, 3)}
PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def reference():
    """High-accuracy GCI and volume (adaptive, joint domain, C backend), with their error estimates."""
    model = symkin.load(DELTA_DIR, backend="c")
    result = global_indices.gci(model, method="adaptive", samples=2**18, rtol=1e-13)
    assert result.value.relative_error < 1e-5
    assert result.measure.relative_error < 1e-5
    return result


@pytest.fixture(scope="module")
def ik():
    return inverse.inverse_kinematics_for(DELTA)


def _stretched_leg_1(thetas_deg):
    """Poses where leg 1 is stretched (arm and rod aligned: det J_q = 0), legs 2 and 3 not.

    B_1 = A_1 + (a + b)(cos theta, 0, sin theta), p = B_1 - r_tcp e_x; q from ik for legs 2, 3.
    """
    P = DELTA.parameters
    theta = np.radians(thetas_deg)
    direction = np.stack([np.cos(theta), 0 * theta, np.sin(theta)], axis=-1)
    p = np.array([P["r_base"] - P["r_tcp"], 0.0, 0.0]) + (P["a"] + P["b"]) * direction
    with np.errstate(invalid="ignore"):  # leg 1's margin is 0 up to rounding: its ik may be NaN
        q = DELTA.ik(p).joints.copy()
    q[:, 0] = theta
    return q, p, direction


# --- conditioning of 3 x 3 Jacobians ------------------------------------------------------------

#: Error bound of the 3x3 closed form's 1/kappa (in [0, 1]): r = det B / (2 p^3) carries <= 16 EPS
#: (Gram entries 3 roundings, deviator 1, p^2 a sum of 6 squares, det B 5, p^3 and the quotient 3);
#: arccos amplifies it by 1/sqrt(1 - r^2) <= 1/sqrt(CLOSED_FORM_3X3_CLUSTER) = 100 (closer clusters go
#: to LAPACK), and the eigenvalues and their ratio carry it through factors <= 1.
CLOSED_FORM_3X3 = 16 * EPS / np.sqrt(C.CLOSED_FORM_3X3_CLUSTER)


def test_3x3_closed_form_matches_a_40_digit_svd():
    rng = np.random.default_rng(7)
    matrices = []
    for _ in range(400):
        U, _r = np.linalg.qr(rng.normal(size=(3, 3)))
        V, _r = np.linalg.qr(rng.normal(size=(3, 3)))
        s2 = 10 ** rng.uniform(-9, 0)
        s3 = s2 * rng.choice([1.0, 1 - 1e-9, 1 - 1e-4, 0.5, 10 ** rng.uniform(-9, 0), 0.0])
        matrices.append(U @ np.diag(np.array([1.0, s2, s3]) * 10 ** rng.uniform(-3, 3)) @ V.T)
    matrices = np.array(matrices)
    exact = []
    with mpmath.workdps(40):  # local precision: the global mpmath context is left as it was
        for J in matrices:
            s = sorted(float(x) for x in mpmath.svd_r(mpmath.matrix(J.tolist()), compute_uv=False))
            exact.append(s[0] / s[-1])
    assert np.max(np.abs(C.inverse_condition_number(matrices) - np.array(exact))) <= CLOSED_FORM_3X3


def test_3x3_closed_form_matches_lapack_on_the_delta_workspace():
    q = workspace.sample_workspace(DELTA, 4000, method="sobol", seed=0).q
    J = mechanism.jacobian(DELTA, q)
    s = np.linalg.svd(J, compute_uv=False)
    assert np.max(np.abs(C.inverse_condition_number(J) - s[:, -1] / s[:, 0])) <= CLOSED_FORM_3X3 + svd(3)
    assert np.allclose(C.inverse_condition_number(np.eye(3) * 0.3), 1.0, rtol=0, atol=svd(3))


def test_the_jacobian_is_the_derivative_of_the_generated_fk():
    q = workspace.sample_workspace(DELTA, 64, method="sobol", seed=1).q
    h = 1e-6
    numeric = np.stack([(DELTA.fk(q + h * e).position - DELTA.fk(q - h * e).position) / (2 * h) for e in np.eye(3)],
                       axis=-1)
    assert np.allclose(mechanism.jacobian(DELTA, q), numeric, rtol=1e-6, atol=1e-9)


def test_singular_and_unassembled_configurations_give_zero_never_nan():
    q, p, _ = _stretched_leg_1([-120, -115, -110, -105])
    # leg 1 is singular: det J_q vanishes to the rounding of its terms (a^3 b^3 = 3.4e-6 m^6)
    assert np.all(np.abs(DELTA.singularities(q, p).det_Jq) < KINEMATICS * (0.1 * 0.15) ** 3)
    J = DELTA.jacobian(q, p)
    assert np.all(C.inverse_condition_number(J) == 0.0)
    assert np.all(C.condition_number(J) == np.inf)
    # Over a full turn of the actuators the legs often cannot be assembled: J is NaN there.
    cloud_q = np.random.default_rng(0).uniform(-np.pi, np.pi, (5000, 3))
    with np.errstate(invalid="ignore"):  # fk is NaN where the legs cannot be assembled
        J = mechanism.jacobian(DELTA, cloud_q)
    assert not np.isfinite(J).all()
    for values in (C.inverse_condition_number(J), C.inverse_frobenius_condition_number(J),
                   C.transmission_indices(J).speed, C.singular_values(J)):
        assert not np.isnan(values).any()
    assert np.all(C.inverse_condition_number(J)[~np.isfinite(J).all(axis=(1, 2))] == 0.0)


# --- workspace: reachability, boundary, boundary singularities ---------------------------------


def test_ik_reachability_respects_the_actuator_limits(ik):
    limits = mechanism.joint_limits(DELTA)
    assert np.allclose(limits, np.radians([[-90, 60]] * 3))
    points = reach.bounding_box(DELTA)
    grid = np.random.default_rng(3).uniform(points[0], points[1], (20000, 3))
    q, inside = feasibility.feasible_configurations(ik, grid, limits, mechanism.revolute_mask(DELTA))
    assert inside.mean() > 0.1
    assert np.all((q[inside] >= limits[:, 0] - 1e-9) & (q[inside] <= limits[:, 1] + 1e-9))
    assert np.allclose(DELTA.fk(q[inside]).position, grid[inside], atol=1e-12)
    # Points reached only with an actuator outside its range are refused.
    with np.errstate(invalid="ignore"):
        raw = DELTA.ik(grid).joints
    outside = np.isfinite(raw).all(axis=1) & np.any((raw < limits[:, 0] - 1e-6) | (raw > limits[:, 1] + 1e-6), axis=1)
    assert outside.any()
    assert not inside[outside].any()


def test_joint_and_cartesian_workspaces_have_the_same_volume(reference, ik):
    cartesian = global_indices.workspace_measure(DELTA, method="qmc", samples=2**17, seed=0, domain="cartesian",
                                                 inverse=ik)
    assert abs(cartesian.value - reference.measure.value) <= max(cartesian.error, 1e-4 * reference.measure.value)
    assert 4e-3 < reference.measure.value < 6e-3  # m^3: a desktop haptic device's workspace


def test_boundary_singularities_lie_on_the_workspace_boundary(ik):
    """A stretched leg (det J_q = 0, 1/kappa = 0): one step outwards is out of reach, one inwards is reachable."""
    q, p, direction = _stretched_leg_1(np.linspace(-120, -105, 7))
    limits, revolute = mechanism.joint_limits(DELTA, FULL_TURN), mechanism.revolute_mask(DELTA)
    assert np.all(C.inverse_condition_number(DELTA.jacobian(q, p)) == 0.0)
    step = 1e-5
    assert not feasibility.reachable(ik, p + step * direction, limits, revolute).any()
    assert feasibility.reachable(ik, p - step * direction, limits, revolute).all()
    box = reach.bounding_box(DELTA, limits=FULL_TURN, samples=2**15)
    occupancy = grids.reachability_grid(DELTA, ik, box, 0.006, limits=FULL_TURN)
    boundary_centres = occupancy.centers()[occupancy.boundary()]
    distance = np.linalg.norm(p[:, None, :] - boundary_centres[None], axis=-1).min(axis=1)
    assert np.all(distance <= np.sqrt(3) * 0.006)
    assert not occupancy.lookup(p, occupancy.interior()).any()


def test_lowest_conditioning_lies_on_the_boundary_within_the_actuator_limits(ik):
    """In the model's limits the working mode ends at leg singularities: the worst cells are boundary cells."""
    box = reach.bounding_box(DELTA)
    occupancy, values = grids.index_grid(DELTA, ik, box, 0.006)
    assert np.array_equal(np.isfinite(values), occupancy.occupied)
    reachable = values[occupancy.occupied]
    worst = occupancy.occupied & (values <= np.quantile(reachable, 0.01))
    assert (worst & occupancy.boundary()).sum() >= 0.95 * worst.sum()
    assert np.nanmin(values[occupancy.interior()]) > 2 * np.nanmin(values[occupancy.boundary()])


def test_working_mode_excludes_other_branches():
    q = workspace.sample_workspace(DELTA, 8000, method="sobol", seed=2).q
    p, inside = working_mode(DELTA, q)
    assert inside.all()
    assert np.allclose(DELTA.ik(p).joints, q, atol=1e-9)
    box_q = np.random.default_rng(4).uniform(*np.radians([-90, 60]), (8000, 3))
    _, inside = working_mode(DELTA, box_q)
    assert 0.5 < inside.mean() < 0.99  # some actuator angles put a knee inwards


# --- GCI -------------------------------------------------------------------------------------


@pytest.mark.parametrize("domain", ["joint", "cartesian"])
@pytest.mark.parametrize("method", ["grid", "mc", "qmc", "adaptive"])
def test_every_integrator_converges_to_the_reference(reference, ik, method, domain):
    exact = reference.value.value
    errors, estimates = [], []
    for samples in (4**5, 4**8):
        result = global_indices.gci(DELTA, method=method, samples=samples, seed=11, domain=domain, inverse=ik)
        errors.append(abs(result.value.value - exact))
        estimates.append(result.value.error)
        assert errors[-1] <= result.value.error + reference.value.error
    assert errors[-1] < 0.012 * exact
    assert estimates[-1] < estimates[0] / 2
    if method in ("grid", "adaptive"):  # a single random run may be lucky at the small budget
        assert errors[-1] < errors[0]


@pytest.mark.parametrize("domain", ["joint", "cartesian"])
@pytest.mark.parametrize("method", ["mc", "qmc"])
def test_statistical_error_estimates_cover_the_true_error_in_repeated_runs(reference, ik, method, domain):
    exact = reference.value.value
    runs = [global_indices.gci(DELTA, method=method, samples=2048, seed=seed, domain=domain, inverse=ik).value
            for seed in range(40)]
    covered = np.mean([abs(r.value - exact) <= r.error for r in runs])
    halved = np.mean([abs(r.value - exact) <= r.error / 2 for r in runs])
    assert covered >= 0.8  # nominal 95 %
    assert halved < covered  # and not merely conservative


@pytest.mark.parametrize("domain", ["joint", "cartesian"])
@pytest.mark.parametrize("method", ["grid", "adaptive"])
def test_deterministic_error_estimates_bracket_the_true_error(reference, ik, method, domain):
    exact = reference.value.value
    for samples in (600, 3000, 15000, 60000):
        result = global_indices.gci(DELTA, method=method, samples=samples, domain=domain, inverse=ik).value
        assert abs(result.value - exact) <= result.error, (samples, result)


def test_c_and_numpy_backends_give_the_same_gci():
    c_model = symkin.load(DELTA_DIR, backend="c")
    for domain in ("joint", "cartesian"):
        kwargs = {"domain": domain, "inverse": inverse.inverse_kinematics_for(c_model)} if domain == "cartesian" else {}
        a = global_indices.gci(c_model, method="grid", samples=4096, **kwargs).value.value
        kwargs["inverse"] = inverse.inverse_kinematics_for(DELTA) if domain == "cartesian" else None
        b = global_indices.gci(DELTA, method="grid", samples=4096, domain=domain,
                               **({"inverse": kwargs["inverse"]} if domain == "cartesian" else {})).value.value
        assert a == pytest.approx(b, rel=1e-12)


def test_convergence_table_reaches_the_target_accuracy(reference):
    trials = convergence.time_against_error(DELTA, reference.value, methods=["grid", "qmc"], budgets=[4096, 32768],
                                            repeats=1)
    best = convergence.fastest_within(trials, 1e-3)
    assert best[("numpy", "joint", "grid")] is not None
    assert best[("numpy", "joint", "qmc")] is not None


# --- commands --------------------------------------------------------------------------------


def test_workspace_command_reports_the_cartesian_grid_and_draws_slices(tmp_path, capsys):
    cloud, kappa_map = tmp_path / "cloud.png", tmp_path / "map.png"
    assert main(["workspace", DELTA_DIR, "-n", "8000", "--unit", "mm", "-o", str(cloud), "--map", str(kappa_map)]) == 0
    out = capsys.readouterr().out
    assert "reachability by ik in the working mode" in out
    match = re.search(r"the (\d+) cells of lowest 1/kappa \(1%\): (\d+) on the workspace boundary", out)
    assert match
    assert int(match.group(2)) >= 0.9 * int(match.group(1))
    assert cloud.read_bytes()[:8] == PNG
    assert kappa_map.read_bytes()[:8] == PNG


def test_gci_command_states_the_domain(capsys):
    assert main(["gci", DELTA_DIR, "--domain", "cartesian", "--method", "qmc", "-n", "4096", "--seed", "0"]) == 0
    out = capsys.readouterr().out
    assert "Cartesian box with reachability from inverse kinematics" in out
    assert "working mode" in out
    assert 0.5 < float(re.search(r"GCI = ([0-9.]+)", out).group(1)) < 0.54


def test_bench_gci_times_both_backends(tmp_path, capsys):
    figure = tmp_path / "bench.png"
    assert main(["bench", "gci", DELTA_DIR, "--backends", "numpy,c", "--methods", "grid,qmc", "--budgets", "4096",
                 "--repeats", "1", "-o", str(figure)]) == 0
    out = capsys.readouterr().out
    rows = [line.split() for line in out.splitlines() if re.match(r"\s+(joint|cartesian)\s.*(yes|NO)$", line)]
    assert {(r[0], r[2]) for r in rows} == {(d, b) for d in ("joint", "cartesian") for b in ("numpy", "c")}
    assert figure.read_bytes()[:8] == PNG


# --- model: limits of leg joints -------------------------------------------------------------


def _legs_model(tmp_path, limits_u: str, limits_p: str):
    path = tmp_path / "legs.yaml"
    path.write_text(f"""name: legs
parameters: {{r_b: 0.2, r_p: 0.1}}
parallel:
  motion: translation
  chains:
    ups:
      - {{name: u, type: U, axes: [[0, 0, 1], [0, 1, 0]], limits: {limits_u}}}
      - {{name: l, type: P, axis: [1, 0, 0], active: true, limits: {limits_p}}}
      - {{name: sp, type: S}}
  legs:
    - {{chain: ups, base: {{radius: r_b, angle: 0}}, platform: {{radius: r_p, angle: 0}}}}
    - {{chain: ups, base: {{radius: r_b, angle: deg(120)}}, platform: {{radius: r_p, angle: deg(120)}}}}
    - {{chain: ups, base: {{radius: r_b, angle: deg(240)}}, platform: {{radius: r_p, angle: deg(240)}}}}
""")
    return path


def test_leg_joint_limits_become_coordinate_and_passive_limits(tmp_path):
    from symkin.manifest import parallel_record

    model = load_model(_legs_model(tmp_path, "[[deg(-45), deg(45)], null]", "[0.1, 0.4]"))
    assert [tuple(float(b) for b in c.limits) for c in model.coordinates] == [(0.1, 0.4)] * 3
    record = parallel_record(model)
    assert record.legs[0].passive_limits == {"u1_1": [pytest.approx(-np.pi / 4), pytest.approx(np.pi / 4)]}


@pytest.mark.parametrize("limits_u, limits_p, message", [
    ("[[1, -1], null]", "[0.1, 0.4]", "the lower limit 1 is not below the upper limit -1"),
    ("[[-1, 1]]", "[0.1, 0.4]", "expected 2 limits"),
    ("[[-1, 1], null]", "[0.4]", "expected 2 bounds [lower, upper]"),
    ("[[-1, foo], null]", "[0.1, 0.4]", "foo"),
])
def test_bad_leg_joint_limits_are_located(tmp_path, limits_u, limits_p, message):
    from symkin.errors import ModelError

    with pytest.raises(ModelError) as info:
        load_model(_legs_model(tmp_path, limits_u, limits_p))
    assert message in str(info.value)
    assert "parallel.chains.ups[" in str(info.value)


def test_delta_actuator_limits_are_validated(tmp_path):
    from symkin.errors import ModelError

    text = (MODELS_DIR / "delta.yaml").read_text().replace("actuator_limits: [deg(-90), deg(60)]",
                                                           "actuator_limits: [deg(60), deg(-90)]")
    path = tmp_path / "delta.yaml"
    path.write_text(text)
    with pytest.raises(ModelError, match=r"parallel\.delta\.actuator_limits"):
        load_model(path)


def test_a_delta_model_file_is_analysed_on_the_fly(capsys):
    assert main(["gci", str(MODELS_DIR / "delta.yaml"), "--method", "grid", "-n", "2000"]) == 0
    assert 0.5 < float(re.search(r"GCI = ([0-9.]+)", capsys.readouterr().out).group(1)) < 0.54


def test_a_platform_without_closed_form_fk_is_refused_on_the_joint_domain_with_a_message(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["gci", str(GENERATED_DIR / "stewart"), "--domain", "joint"])
    assert exit_info.value.code == 2
    assert "constant-orientation workspace only (--domain cartesian)" in capsys.readouterr().err
