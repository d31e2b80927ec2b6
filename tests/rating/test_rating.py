"""The datasheet measures of symkin.rating.formulas (issue 32) on the seed's planar 2R arm with point masses.

Oracles written here from the seed's J (eq. 8.56) and the point masses m1 at the elbow, m2 at the tip:
the apparent mass in closed form, Lambda = m2 I + m1 / sin^2(theta2) u u^T with u the forearm's direction
(J^-T M J^-1 with M = J_e^T m1 J_e + J^T m2 J, J_e the elbow's Jacobian: J_e J^-1 = a r^T, |a| = l1,
r = u / (l1 sin theta2)); the force capability and the friction felt against a dense scan of directions;
the position resolution against encoders simulated by rounding q to counts and mapping the neighbouring
readings through fk.
"""

from __future__ import annotations

import numpy as np
import pytest

import json

from conftest import MODELS_DIR
from symkin import load
from symkin.rating import forces, formulas, handle_measures
from symkin.cli import main
from tolerances import CLOSED_FORM, DYNAMICS, EPS

L1 = L2 = 0.1
M1 = M2 = 0.1
POSES = np.radians([[10.0, 30.0], [45.0, 90.0], [80.0, 150.0], [0.0, 12.0]])


@pytest.fixture(scope="module")
def arm(generated_dir):
    return load(generated_dir / "planar_2r")


def seed_jacobian(q: np.ndarray) -> np.ndarray:
    s1, c1, s12, c12 = np.sin(q[0]), np.cos(q[0]), np.sin(q.sum()), np.cos(q.sum())
    return np.array([[-L1 * s1 - L2 * s12, -L2 * s12], [L1 * c1 + L2 * c12, L2 * c12]])


def directions(count: int) -> np.ndarray:
    angle = np.linspace(0.0, 2.0 * np.pi, count, endpoint=False)
    return np.stack([np.cos(angle), np.sin(angle)], axis=-1)


@pytest.mark.parametrize("q", POSES)
def test_the_apparent_mass_is_m2_across_the_forearm_and_grows_as_1_over_sin2_along_it(arm, q):
    M, J = arm.mass_matrix(q), seed_jacobian(q)
    forearm = np.array([np.cos(q.sum()), np.sin(q.sum())])
    expected = M2 * np.eye(2) + M1 / np.sin(q[1]) ** 2 * np.outer(forearm, forearm)
    Lambda = formulas.apparent_mass(M, J)
    # two solves with J's conditioning, each backward stable: relative error ~ kappa(J)^2 kappa(M) eps
    bound = 16 * np.linalg.cond(J) ** 2 * np.linalg.cond(M) * EPS
    np.testing.assert_allclose(Lambda, expected, rtol=0, atol=bound * np.abs(expected).max())
    np.testing.assert_allclose(arm.operational_space(q, np.zeros(2)).Mx, Lambda, rtol=0,  # the derived Mx
                               atol=bound * np.abs(expected).max())
    masses = formulas.principal_masses(M, J)
    np.testing.assert_allclose(masses, [M2, M2 + M1 / np.sin(q[1]) ** 2], rtol=bound)


@pytest.mark.parametrize("q", POSES)
def test_the_figures_along_each_axis_are_the_closed_forms_of_the_2r_arm(arm, q):
    """Issue 64, a maker's figures along x and y: the mass felt pushing along e, 1 / (e^T Lambda^-1 e) with the
    closed-form Lambda above ((m2 I + a u u^T)^-1 = (I - a / (m2 + a) u u^T) / m2, a = m1 / sin^2 theta2); the force
    along e from the seed's J, min_i tau_i / |J_i . e|; the step along e of one encoder count of one joint, through
    the closed-form fk (first order in the count); the friction felt moving along e, the farthest vertex
    J^-T (s tau_c) of the friction polytope in the direction e (every sign vector s)."""
    import itertools

    M, J = arm.mass_matrix(q), seed_jacobian(q)
    forearm = np.array([np.cos(q.sum()), np.sin(q.sum())])
    a = M1 / np.sin(q[1]) ** 2
    bound = 16 * np.linalg.cond(J) ** 2 * np.linalg.cond(M) * EPS
    expected_mass = M2 / (1.0 - a / (M2 + a) * forearm ** 2)
    np.testing.assert_allclose(formulas.axis_mass(M, J), expected_mass, rtol=bound)
    efforts = np.array([0.7, 0.4])
    along = forces.axis_force(J, efforts)
    np.testing.assert_allclose(along, [min(efforts / np.abs(J[k])) for k in range(2)], rtol=CLOSED_FORM)

    def tip(angles):
        return np.array([L1 * np.cos(angles[0]) + L2 * np.cos(angles.sum()),
                         L1 * np.sin(angles[0]) + L2 * np.sin(angles.sum())])

    steps = 2 * np.pi / np.array([4096 * 10.0, 4096 * 8.0])
    moved = np.array([np.abs(tip(q + steps[i] * np.eye(2)[i]) - tip(q)) for i in range(2)])  # (joint, axis)
    np.testing.assert_allclose(formulas.axis_step(J, steps), moved.max(axis=0), rtol=4 * steps.max())
    coulomb = np.array([0.02, 0.05])
    vertices = np.array([np.linalg.solve(J.T, np.array(s) * coulomb) for s in itertools.product((-1, 1), repeat=2)])
    np.testing.assert_allclose(formulas.axis_friction(J, coulomb), vertices.max(axis=0),
                               rtol=16 * np.linalg.cond(J) * EPS)


@pytest.mark.parametrize("q", POSES)
def test_a_walls_inputs_along_each_axis_are_the_worst_motions_the_hand_can_make(q):
    """Issue 64, the passive wall normal to an axis e: the hand moves v = e + t n (n normal to e) as it pushes, and a
    scan of t finds the least damping v^T J^-T B J^-1 v and the least Coulomb force sum_i tau_c,i |(J^-1 v)_i| the
    formulas give; the quantization error along e, encoders read one count below the joints, reaches
    sum_i |J_ei| dq_i (to first order in the counts) at the reading of the worst corner."""
    J = seed_jacobian(q)
    viscous, coulomb = np.array([0.002, 0.001]), np.array([0.02, 0.05])
    sideways = np.linspace(-50.0, 50.0, 400_001)                   # t, in steps of 2.5e-4
    for axis in range(2):
        e, n = np.eye(2)[axis], np.eye(2)[1 - axis]
        ahead, aside = np.linalg.solve(J, e), np.linalg.solve(J, n)  # the joints' rates for e and for n
        w = ahead[None, :] + sideways[:, None] * aside[None, :]
        damping = np.sum(viscous * w ** 2, axis=-1)
        friction = np.sum(coulomb * np.abs(w), axis=-1)
        least_damping = float(formulas.axis_damping(J, viscous)[axis])
        least_friction = float(formulas.axis_slip_friction(J, coulomb)[axis])
        # the exact minima are no larger than any scanned motion, and the scan comes within its step of them: a
        # quadratic in t within (step / 2)^2 times its curvature, a piecewise-linear function within step / 2 times
        # its largest slope
        curvature, slope = 2 * np.sum(viscous * aside ** 2), np.sum(coulomb * np.abs(aside))
        assert least_damping <= damping.min() * (1 + 1e-12)
        assert damping.min() - least_damping <= (2.5e-4 / 2) ** 2 * curvature / 2 + 1e-12 * least_damping
        assert least_friction <= friction.min() * (1 + 1e-12)
        assert friction.min() - least_friction <= 2.5e-4 / 2 * slope + 1e-12 * least_friction
    steps = 2 * np.pi / np.array([4096 * 10.0, 4096 * 8.0])
    corners = np.array([[0, 0], [0, 1], [1, 0], [1, 1]]) * steps                    # the joints above their readings
    tip = np.stack([L1 * np.cos(q[0] + corners[:, 0]) + L2 * np.cos(q.sum() + corners.sum(axis=1)),
                    L1 * np.sin(q[0] + corners[:, 0]) + L2 * np.sin(q.sum() + corners.sum(axis=1))], axis=-1)
    widest = np.ptp(tip, axis=0)                                                       # per task axis
    # fk's second-order terms at a corner are at most the reach times (dq_1 + dq_2)^2 / 2, twice that in a width
    np.testing.assert_allclose(formulas.axis_quantization(J, steps), widest, rtol=0, atol=(L1 + L2) * steps.sum() ** 2)


@pytest.mark.parametrize("q", POSES)
def test_the_peak_force_is_the_best_direction_of_a_dense_scan(arm, q):
    J, limits = seed_jacobian(q), np.array([0.3, 0.2])
    peak = float(formulas.peak_force(J, limits))
    scanned = forces.directional_force(J, limits, directions(200_000))
    assert np.max(scanned) <= peak * (1 + 1e-12)
    assert np.max(scanned) >= peak * (1 - 1e-3)          # the scan's angular step, 3e-5 rad, near a kink
    assert float(forces.isotropic_force(J, limits)) == pytest.approx(np.min(scanned), rel=1e-3)


@pytest.mark.parametrize("q", POSES)
def test_the_coulomb_friction_felt_is_the_worst_direction_of_motion(arm, q):
    J, coulomb = seed_jacobian(q), np.array([0.004, 0.0025])
    u = directions(200_000)
    qd = np.linalg.solve(J, u.T).T                          # moving the handle with unit speed along u
    felt = np.abs(qd) @ coulomb                             # u . J^-T (tau_c sign(qd)) = sum tau_c |qd_i|
    worst = float(formulas.coulomb_friction_felt(J, coulomb))
    assert np.max(felt) <= worst * (1 + 1e-12)
    assert np.max(felt) >= worst * (1 - 1e-3)


@pytest.mark.parametrize("q", POSES)
def test_the_damping_at_the_handle_is_its_least_damped_direction(arm, q):
    J, viscous = seed_jacobian(q), np.array([0.002, 0.001])
    count = 200_000
    qd = np.linalg.solve(J, directions(count).T).T
    along = np.sum(viscous * qd ** 2, axis=-1)              # u . J^-T diag(b) J^-1 u
    least = float(formulas.handle_damping(J, viscous))
    # the scan misses the least direction by at most half its angular step h: u . B u exceeds the least
    # eigenvalue by at most (h / 2)^2 (largest - least)
    spread = np.max(along) - least
    assert least <= np.min(along) * (1 + 1e-12)
    assert np.min(along) - least <= (np.pi / count) ** 2 * spread
    assert float(formulas.renderable_stiffness(least, 1e-3)) == pytest.approx(2 * least / 1e-3, rel=CLOSED_FORM)


@pytest.mark.parametrize("q", POSES)
def test_the_position_resolution_is_the_largest_step_between_neighbouring_encoder_readings(arm, q):
    counts = np.array([4096.0, 2000.0])                     # per joint turn
    step = 2 * np.pi / counts
    read = np.round(q / step) * step
    neighbours = read + np.array([[a, b] for a in (-1, 0, 1) for b in (-1, 0, 1)]) * step
    tcp = arm.fk(neighbours)[:, :2, 3]
    simulated = np.max(np.linalg.norm(tcp - arm.fk(read)[:2, 3], axis=-1))
    first_order = float(formulas.position_resolution(arm.jacobian(read), step))
    # fk - its linearization is at most 1/2 |dq|^2 max|fk''| <= (l1 + l2) |dq|^2 (two joints)
    assert abs(simulated - first_order) <= (L1 + L2) * float(np.sum(step ** 2))


def test_the_gravity_budget_is_the_largest_share_of_an_effort_limit(arm):
    q = POSES[0]
    G = arm.gravity_vector(q)
    assert float(formulas.gravity_share(G, [0.5, 0.1])) == pytest.approx(max(abs(G[0]) / 0.5, abs(G[1]) / 0.1),
                                                                      rel=CLOSED_FORM)


def test_forces_at_the_handle_need_as_many_joints_as_task_coordinates():
    with pytest.raises(ValueError, match="at least as many joints as task coordinates"):
        formulas.coulomb_friction_felt(np.ones((3, 2)), [1.0, 1.0])


#: A redundant device: three joints move a handle in the plane (v = J qd).
REDUNDANT = np.array([[-0.12, -0.07, -0.02], [0.15, 0.09, 0.05]])


def test_a_redundant_device_slips_in_its_cheapest_joint_motion():
    """The Coulomb friction felt moving along u is the least friction work over the joint motions J w = u (a
    linear program, scipy's HiGHS); the largest over a dense scan of directions is the rated value."""
    from scipy.optimize import linprog

    coulomb = np.array([0.01, 0.004, 0.002])
    felt = float(formulas.coulomb_friction_felt(REDUNDANT, coulomb))
    values = []
    for u in directions(720):
        # w = w+ - w-, both >= 0: min c . (w+ + w-) s.t. J (w+ - w-) = u
        result = linprog(np.concatenate([coulomb, coulomb]), A_eq=np.hstack([REDUNDANT, -REDUNDANT]), b_eq=u,
                         bounds=(0, None), method="highs")
        assert result.status == 0
        values.append(result.fun)
    assert max(values) <= felt * (1 + 1e-9)
    assert max(values) >= felt * (1 - 1e-4)
    square = REDUNDANT[:, :2]
    assert float(formulas.coulomb_friction_felt(square, coulomb[:2])) == pytest.approx(
        float(formulas.farthest_vertex(np.linalg.inv(square).T, coulomb[:2])), rel=CLOSED_FORM)


def test_a_redundant_devices_damping_is_its_least_dissipating_joint_motion():
    """min over J w = u of w^T B w, solved in the null space of J (w = J^+ u + N z, least squares in z), is a
    quadratic form u^T D u; its least eigenvalue is the rated damping.  An undamped joint that moves the handle
    leaves it undamped."""
    viscous = np.array([0.002, 0.001, 0.0005])
    _, _, Vt = np.linalg.svd(REDUNDANT)
    N = Vt[2:].T                                                        # null space of J (3 x 1)
    root = np.sqrt(viscous)[:, None]

    def least_dissipation(u):
        particular = np.linalg.pinv(REDUNDANT) @ u
        z = np.linalg.lstsq(root * N, -root[:, 0] * particular, rcond=None)[0]
        w = particular + N @ z
        return w @ (viscous * w)

    e = np.eye(2)
    D = np.array([[least_dissipation(e[i]) if i == j else
                   (least_dissipation(e[i] + e[j]) - least_dissipation(e[i]) - least_dissipation(e[j])) / 2
                   for j in range(2)] for i in range(2)])
    expected = np.linalg.eigvalsh(D)[0]
    # two solves, each within a few ulps times kappa(J B^-1 J^T) = 92: 1e3 EPS
    assert float(formulas.handle_damping(REDUNDANT, viscous)) == pytest.approx(expected, rel=1e3 * EPS)
    assert float(formulas.handle_damping(REDUNDANT, [0.002, 0.0, 0.0005])) == 0.0


def test_the_peak_force_of_a_redundant_arm_is_the_farthest_point_its_efforts_allow():
    """Three joints, two task coordinates: the polytope |J^T F| <= tau_max against a dense scan of f(u)."""
    J = np.array([[-0.12, -0.07, -0.02], [0.15, 0.09, 0.05]])
    limits = np.array([0.4, 0.25, 0.1])
    peak = float(formulas.peak_force(J, limits))
    scanned = forces.directional_force(J, limits, directions(200_000))
    assert np.max(scanned) <= peak * (1 + 1e-9)
    assert np.max(scanned) >= peak * (1 - 1e-3)


def test_the_delta_feels_the_mass_pinocchio_accelerates_with_a_push_at_the_handle(generated_dir):
    """The DELTA of models/delta.yaml as Pinocchio's tree closed by three point constraints
    (benchmarks/competitors.pinocchio_delta): pushed from rest at the platform by a unit force along each
    axis, without gravity and with the motors off, its acceleration is the mobility J M^-1 J^T, the
    inverse of the apparent mass.  Both are solves with kappa <= 1e4 (tests/parallel/test_parallel_dynamics.py):
    1e-9 relative leaves room for two algorithms."""
    pin = pytest.importorskip("pinocchio")
    from benchmarks.competitors import constraint_dynamics_of, delta_tree_state, pinocchio_delta

    delta = load(generated_dir / "delta")
    values = {p.name: p.default for p in delta.info.parameters}
    _, tree, constraints, legs = pinocchio_delta(values)
    tree.gravity = pin.Motion.Zero()
    data, datas, settings = constraint_dynamics_of(pin, tree, constraints)
    platform = tree.joints[tree.getJointId("platform")].idx_v
    for P in (np.array(delta.info.home), np.array([0.03, -0.02, -0.13]), np.array([-0.05, 0.04, -0.18])):
        theta = delta.ik(P).joints
        q, velocity, _ = delta_tree_state(pin, tree, data, legs, values, P, theta, np.zeros(3))
        pushed = []
        for axis in np.eye(3):
            efforts = np.zeros(tree.nv)
            efforts[platform:platform + 3] = axis                     # 1 N on the platform, motors off
            acceleration = pin.constraintDynamics(tree, data, q, velocity, efforts, constraints, datas, settings)
            pushed.append(acceleration[platform:platform + 3])
        mobility = np.array(pushed).T
        Lambda = formulas.apparent_mass(delta.mass_matrix(theta, P), delta.jacobian(theta, P))
        np.testing.assert_allclose(Lambda @ mobility, np.eye(3), rtol=0, atol=1e-9)


def test_cli_rates_the_delta_and_writes_its_datasheet(generated_dir, tmp_path):
    out = tmp_path / "rate"
    # no --gear: the DELTA's rotor (models/delta.yaml: rotor: {gear_ratio: gear}, gear = 10) is the default
    # (issue 60: a parallel model's gear was ignored, its resolution 10 times too coarse)
    assert main(["rate", str(generated_dir / "delta"), "-n", "1000", "--effort-limit", "0.3", "--encoder", "4096",
                 "-o", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["datasheet.csv", "datasheet.json", "datasheet.png", "summary.txt"]
    sheet = json.loads((out / "datasheet.json").read_text())
    no_friction = "no joint friction declared (friction: in the model file)"
    assert sheet["not_rated"] == {"friction": no_friction, "backdrive_friction": no_friction,
                                  "passive_stiffness": no_friction, "continuous_force": handle_measures.NO_CONTINUOUS_LIMITS}
    rows = np.loadtxt(out / "datasheet.csv", delimiter=",", skiprows=2)
    header = (out / "datasheet.csv").read_text().splitlines()[1].split(",")
    for name, measure in sheet["measures"].items():
        column = rows[:, next(k for k, h in enumerate(header) if h.split(" [")[0] == name)]
        assert measure["max"]["value"] == pytest.approx(np.max(column), rel=1e-8)
        assert measure["home"] == pytest.approx(column[-1], rel=1e-8)       # the home pose is the last row
    # at home the DELTA is symmetric about its axis: the same mass in every direction, to its 1e-3 isotropy
    assert sheet["measures"]["inertia_isotropy"]["home"] == pytest.approx(1.0, abs=2e-3)
    home = np.array(sheet["home"]["q"])
    delta = load(generated_dir / "delta")
    J = delta.jacobian(home, delta.fk(home).position)
    step = 2 * np.pi / (4096 * 10)
    assert sheet["measures"]["resolution"]["home"] == pytest.approx(float(formulas.position_resolution(J, step)),
                                                                     rel=1e-8)
    assert (out / "datasheet.png").read_bytes()[:4] == b"\x89PNG"
    # every input the rating used is recorded, with where it came from
    inputs = sheet["inputs"]
    assert (inputs["gears_from"], inputs["effort_limits_from"], inputs["servo_period_s"]) == \
        ("the model's drives", "--effort-limit", 0.001)
    assert [(c["encoder_counts"], c["gear_ratio"], c["effort_limit"]) for c in inputs["coordinates"]] == \
        [(4096, 10, 0.3)] * 3
    assert "theta1: encoder counts 4096, gear ratio 10, effort limit 0.3" in (out / "summary.txt").read_text()


def test_cli_lists_what_it_cannot_rate_and_refuses_what_it_does_not_rate(generated_dir, tmp_path, capsys):
    assert main(["rate", str(generated_dir / "planar_2r"), "-n", "400", "--no-figure", "-o", str(tmp_path / "a")]) == 0
    text = capsys.readouterr().out
    assert "force: not rated (no effort limits" in text
    assert "resolution: not rated (no encoder data" in text
    for arguments in (["agile_eye", "--box", "x=0:1"], ["delta", "--encoder", "0"], ["delta", "--gear", "10"],
                      ["delta", "--box", "w=0:1"]):
        with pytest.raises(SystemExit) as exit:
            main(["rate", str(generated_dir / arguments[0]), *arguments[1:], "-o", str(tmp_path / "b")])
        assert exit.value.code == 2
        assert not (tmp_path / "b").exists()
        err = capsys.readouterr().err   # the one line that says what is wrong, not the usage text before it
        assert "usage:" not in err
        assert err.endswith("(see 'symkin rate --help')\n")


def test_every_measure_is_rated_or_listed_as_not_rated(arm):
    """Issue 60: a datasheet whose measures and not-rated groups do not cover its groups once each is refused,
    so no measure can drop out silently (the rating of every kind of device builds one)."""
    from symkin.rating.datasheet import Datasheet
    from symkin.rating.handle_measures import PUSHED_GROUPS, Measure

    q, points = np.zeros((2, 2)), np.zeros((2, 2))
    force = [Measure(name, "N", np.ones(2), True, "") for name in PUSHED_GROUPS["force"]]
    rest = {group: "why" for group in PUSHED_GROUPS if group != "force"}
    Datasheet("arm", q, points, ("x", "y"), tuple(force), 1, rest, PUSHED_GROUPS)       # complete: accepted
    for measures, skipped in ((force, {g: w for g, w in rest.items() if g != "gravity_share"}),  # one dropped
                              (force[:1], rest),                                                 # half a group
                              (force, rest | {"force": "why"}),                                  # rated and not
                              (force + force[:1], rest)):                                        # twice
        with pytest.raises(ValueError, match="do not cover"):
            Datasheet("arm", q, points, ("x", "y"), tuple(measures), 1, skipped, PUSHED_GROUPS)


def test_help_and_docs_name_every_measure_the_rating_lists(capsys):
    """Issue 60: --help and docs/analysis.md name every measure of the groups the datasheet is checked against,
    and --help no longer says that legs without closed forms get no apparent mass (they do, from
    closure_dynamics: tests/parallel/test_closure_dynamics.py)."""
    from pathlib import Path

    from symkin.rating.handle_measures import PUSHED_GROUPS, SPHERICAL_GROUPS

    with pytest.raises(SystemExit):
        main(["rate", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    docs = (Path(__file__).parents[2] / "docs" / "analysis.md").read_text()
    section = docs.split("## Rating a haptic device")[1].split("\n## ")[0]
    for groups in (PUSHED_GROUPS, SPHERICAL_GROUPS):
        for name in (name for names in groups.values() for name in names):
            assert name in text, name
            stem = name.rsplit("_", 1)[0] + "_" if name.endswith(("_min", "_max")) else name
            assert f"`{stem}" in section, name
    assert "no apparent mass" not in text
    assert "from the generated closure_dynamics" in text


def test_friction_declared_in_the_model_is_felt_at_the_handle(tmp_path):
    """planar_2r with joint friction and effort limits: the Coulomb friction, the damping at the handle and
    the Colgate-Brown stiffness at 1 kHz come from the manifest's friction record."""
    text = (MODELS_DIR / "planar_2r.yaml").read_text()
    text = text.replace("gravity: [0, -g, 0]", "gravity: [0, -g, 0]\nfriction:\n"
                        "  theta1: {viscous: 0.002, coulomb: 0.004}\n"
                        "  theta2: {viscous: 0.001, coulomb: 0.0025}")
    path = tmp_path / "planar_2r.yaml"
    path.write_text(text)
    out = tmp_path / "rate"
    assert main(["rate", str(path), "-n", "400", "--effort-limit", "0.5,0.3", "--encoder", "4096", "--no-figure",
                 "-o", str(out)]) == 0
    sheet = json.loads((out / "datasheet.json").read_text())
    assert "friction" not in sheet["not_rated"]
    assert "passive_stiffness" not in sheet["not_rated"]
    home = np.array(sheet["home"]["q"])
    J = seed_jacobian(home)
    measures = sheet["measures"]
    assert measures["coulomb_friction"]["home"] == pytest.approx(
        float(formulas.coulomb_friction_felt(J, [0.004, 0.0025])), rel=1e-9)
    damping = float(formulas.handle_damping(J, [0.002, 0.001]))
    assert measures["handle_damping"]["home"] == pytest.approx(damping, rel=1e-9)
    assert measures["renderable_stiffness"]["home"] == pytest.approx(2 * damping / 1e-3, rel=1e-9)
    # along each axis e (a row of J): the least damping 1 / sum_i J_ei^2 / b_i, the least Coulomb force
    # min_i tau_c,i / |J_ei| and the quantization width sum_i |J_ei| dq_i, one count of 4096 at each joint
    step = 2 * np.pi / 4096
    for axis, row in zip("xy", J):
        sampled = 2 / (1e-3 * np.sum(row ** 2 / [0.002, 0.001]))
        quantized = 2 * min(0.004 / abs(row[0]), 0.0025 / abs(row[1])) / (step * np.sum(np.abs(row)))
        assert measures[f"renderable_stiffness_{axis}"]["home"] == pytest.approx(sampled, rel=1e-9)
        assert measures[f"quantization_stiffness_{axis}"]["home"] == pytest.approx(quantized, rel=1e-9)
        assert measures[f"passive_stiffness_{axis}"]["home"] == pytest.approx(min(sampled, quantized), rel=1e-9)


@pytest.fixture(scope="module")
def damped_delta(tmp_path_factory):
    """The DELTA of models/delta.yaml with viscous friction 0.01 N m s/rad at its motors, as a plant."""
    from symkin.analysis.needs import NEEDS
    from symkin.cli import simulate_cmd
    from symkin.analysis import model_files
    from symkin.simulation import Plant

    path = tmp_path_factory.mktemp("damped") / "delta.yaml"
    path.write_text((MODELS_DIR / "delta.yaml").read_text() + "\nfriction:\n"
                    + "".join(f"  theta{i}: {{viscous: 0.01}}\n" for i in (1, 2, 3)))
    return Plant(model_files.generated_model(str(path), "numpy", NEEDS["simulate"],
                                          simulate_cmd.OPTIONAL_OUTPUTS))


@pytest.mark.parametrize("factor, grows", [(0.97, False), (1.03, True)])
def test_a_virtual_spring_beyond_the_colgate_brown_stiffness_makes_the_loop_unstable(damped_delta, factor, grows):
    """A virtual spring K (no virtual damping) about the DELTA's home pose, rendered by a 1 kHz loop that holds
    tau = G + J^T F for a period, the handle let go 0.1 mm away: below K_max = 2 b / T (b the least damping at
    the handle, symkin rate's renderable_stiffness) the oscillation decays, above it grows: 3 % on either side
    of the bound decides.  For one mass m with damping b under a sampled spring the exact boundary (the
    discrete system's spectral radius 1) lies at K_max (1 + O(b T / m)), here within 0.1 %; over 1 s the
    amplitude changes by rho^1000, about 0.79 at 0.97 K_max and 1.19 at 1.03 K_max for the DELTA's apparent
    mass (isotropic at home to 1e-3)."""
    from symkin.simulation import ArmSystem, run_sampled

    plant = damped_delta
    home = np.array(plant.model.info.home)
    q0 = plant.model.ik(home).joints
    J = plant.point_jacobian(q0)
    K = factor * float(formulas.renderable_stiffness(formulas.handle_damping(J, [0.01, 0.01, 0.01]), 1e-3))

    def spring(t, x):
        q = x[:3]
        return plant.gravity(q) + plant.point_jacobian(q).T @ (-K * (plant.point(q) - home))

    start = plant.model.ik(home + 1e-4 * np.array([1.0, 1.0, 1.0]) / np.sqrt(3)).joints
    system = ArmSystem(plant)
    run = run_sampled(system.derivative, spring, system.initial(start), 1e-3, 1000)
    distance = np.linalg.norm(plant.point(run.x[:, :3]) - home, axis=-1)
    first, last = np.max(distance[:100]), np.max(distance[-100:])
    assert (last > 1.1 * first) if grows else (last < 0.9 * first), (first, last)


@pytest.fixture(scope="module")
def stewart_sheet(generated_dir):
    from symkin.rating import datasheet

    stewart = load(generated_dir / "stewart")
    limits = np.full(6, 300.0)  # N per leg: an assumed actuator, the model declares none
    sheet = datasheet.rate(stewart, datasheet.Actuation(effort_limits=limits, joint_steps=np.full(6, 1e-5)),
                           samples=512)
    return stewart, sheet, limits


def test_a_rotating_platform_is_rated_pushed_with_its_orientation_free_and_twisted_with_its_position_free(
        stewart_sheet):
    """The Stewart platform at its home orientation: the principal masses and inertias of the datasheet are those
    of the generated operational-space mass matrix Mx (task coordinates p, roll-pitch-yaw rates): the mobility
    J_t M^-1 J_t^T of the twist t = (v, omega) = diag(I, E) pd is diag(I, E) Mx^-1 diag(I, E)^T, so the apparent
    mass is the inverse of its translational block and the apparent inertia of its rotational one."""
    from symkin.mechanism.reach import angular_velocity_matrix

    stewart, sheet, _ = stewart_sheet
    measures = {m.name: m.values for m in sheet.measures}
    assert len(sheet.q) > 40
    for k in range(0, len(sheet.q), 5):
        pose = np.concatenate([sheet.points[k], np.zeros(3)])  # the home orientation of models/stewart.yaml
        Mx = stewart.operational_space(sheet.q[k], pose, np.zeros(6)).Mx
        mobility = np.linalg.inv(Mx)
        E = angular_velocity_matrix(pose[3:])
        masses = 1.0 / np.linalg.eigvalsh(mobility[:3, :3])[::-1]
        inertias = 1.0 / np.linalg.eigvalsh(E @ mobility[3:, 3:] @ E.T)[::-1]
        # M^-1 and Mx^-1 both go through kappa(M) (and J's two inverses): the dynamics budget times them
        bound = DYNAMICS * np.linalg.cond(Mx) ** 2
        np.testing.assert_allclose([measures["apparent_mass_min"][k], measures["apparent_mass_max"][k]],
                                   masses[[0, -1]], rtol=bound)
        np.testing.assert_allclose([measures["apparent_inertia_min"][k], measures["apparent_inertia_max"][k]],
                                   inertias[[0, -1]], rtol=bound)


def test_a_rotating_platforms_isotropic_torque_is_its_weakest_axis_and_loads_a_leg_to_its_limit(stewart_sheet):
    """About the weakest of a dense scan of axes the legs render the isotropic torque (no force), and the torque
    tau = J_w^T m of that size about the axis that sets it loads one leg exactly to its limit."""
    from symkin.mechanism import reach

    stewart, sheet, limits = stewart_sheet
    torque = {m.name: m.values for m in sheet.measures}["isotropic_torque"]
    view = reach.constant_orientation(stewart)
    rng = np.random.default_rng(3)
    axes = rng.normal(size=(20000, 3))
    axes /= np.linalg.norm(axes, axis=-1, keepdims=True)
    for k in (0, len(sheet.q) // 2, sheet.home):
        J_w = view.jacobian(sheet.q[k], sheet.points[k])[3:]
        scanned = forces.directional_force(J_w, limits, axes)
        assert torque[k] <= scanned.min() * (1 + CLOSED_FORM)
        assert torque[k] >= 0.98 * scanned.min()  # 20000 random axes come within 2 % of the weakest
        weakest = np.argmin(limits / np.linalg.norm(J_w, axis=0))  # the leg whose column sets it
        m = torque[k] * J_w[:, weakest] / np.linalg.norm(J_w[:, weakest])
        assert np.max(np.abs(J_w.T @ m) / limits) == pytest.approx(1.0, rel=CLOSED_FORM)


def test_cli_rates_a_rotating_platform_at_a_constant_orientation(generated_dir, tmp_path, capsys):
    out = tmp_path / "stewart"
    assert main(["rate", str(generated_dir / "stewart"), "--effort-limit", "300", "--orientation", "0,5deg,0",
                 "-n", "256", "--no-figure", "-o", str(out)]) == 0
    sheet = json.loads((out / "datasheet.json").read_text())
    assert {"apparent_mass_min", "isotropic_force", "apparent_inertia_max", "isotropic_torque"} <= set(sheet["measures"])
    assert sheet["measures"]["isotropic_torque"]["unit"] == "N m"
    with pytest.raises(SystemExit) as exit_info:  # --orientation on a mechanism that does not rotate
        main(["rate", str(generated_dir / "delta"), "--orientation", "0,0,0", "-o", str(tmp_path / "d")])
    assert exit_info.value.code == 2
    assert "--orientation applies to platforms that also rotate" in capsys.readouterr().err


# --------------------------------------------------------------------------- a spherical platform (the Agile Eye)

@pytest.fixture(scope="module")
def eye_sheet(generated_dir):
    from symkin.rating import datasheet

    eye = load(generated_dir / "agile_eye")
    limits = np.full(3, 1.0)  # N m per actuator: an assumed drive, the model declares none
    sheet = datasheet.rate(eye, datasheet.Actuation(effort_limits=limits, joint_steps=np.full(3, 2 * np.pi / 4096)),
                           samples=2048)
    return eye, sheet, limits


def _angular_jacobian_by_differences(eye, q):
    """omega = J_w qd from central differences of R(fk(q)) (h = 1e-6: truncation ~h^2, rounding ~eps / h)."""
    from scipy.spatial.transform import Rotation

    def rotation_matrix(p):  # R = Rz(yaw) Ry(pitch) Rx(roll): intrinsic Z-Y-X
        return Rotation.from_euler("ZYX", p[::-1]).as_matrix()

    h = 1e-6
    R = rotation_matrix(eye.fk(q).orientation)
    columns = []
    for e in np.eye(3):
        rate = (rotation_matrix(eye.fk(q + h * e).orientation) - rotation_matrix(eye.fk(q - h * e).orientation)) / (2 * h)
        W = rate @ R.T
        columns.append([W[2, 1], W[0, 2], W[1, 0]])
    return np.array(columns).T


def test_a_spherical_platform_is_rated_by_the_inertia_and_torques_felt_turning_its_handle(eye_sheet):
    """The Agile Eye over its orientations: the principal inertias are those of the generated operational-space
    Mx (roll-pitch-yaw coordinates: the mobility of omega = E pd is E Mx^-1 E^T); the isotropic torque is the
    weakest of 20000 axes through a J_w taken from differences of the closed-form fk; at the home pose, where the
    Agile Eye is isotropic (J_w orthogonal), the inertia is the same about every axis and the isotropic torque is
    the effort limit."""
    from symkin.mechanism.reach import angular_velocity_matrix

    eye, sheet, limits = eye_sheet
    measures = {m.name: m.values for m in sheet.measures}
    assert sheet.axes == ("roll", "pitch", "yaw")
    assert len(sheet.q) > 60
    rng = np.random.default_rng(5)
    axes = rng.normal(size=(20000, 3))
    axes /= np.linalg.norm(axes, axis=-1, keepdims=True)
    for k in list(range(0, len(sheet.q), 15)) + [sheet.home]:
        q, p = sheet.q[k], sheet.points[k]
        Mx = eye.operational_space(q, p, np.zeros(3)).Mx
        E = angular_velocity_matrix(p)
        inertias = 1.0 / np.linalg.eigvalsh(E @ np.linalg.inv(Mx) @ E.T)[::-1]
        bound = DYNAMICS * np.linalg.cond(Mx) ** 2
        np.testing.assert_allclose([measures["apparent_inertia_min"][k], measures["apparent_inertia_max"][k]],
                                   inertias[[0, -1]], rtol=bound)
        scanned = forces.directional_force(_angular_jacobian_by_differences(eye, q), limits, axes)
        assert measures["isotropic_torque"][k] <= scanned.min() * (1 + 1e-6)  # the differences' error, ~1e-10
        assert measures["isotropic_torque"][k] >= 0.98 * scanned.min()  # 20000 random axes come within 2 %
    home = sheet.home
    assert measures["apparent_inertia_max"][home] == pytest.approx(measures["apparent_inertia_min"][home],
                                                                   rel=DYNAMICS)
    assert measures["isotropic_torque"][home] == pytest.approx(1.0, rel=CLOSED_FORM)


def test_the_agile_eyes_inertia_at_home_is_the_sum_of_what_turns_about_an_axis(eye_sheet):
    """By hand, at home (J = 1): turning the handle about x turns leg 1's actuator alone, so leg 1's proximal arc
    (x-y plane: m_p r_p^2 / 2 about x) and rotor, the camera, leg 1's distal arc (y-z plane: m_d r_d^2) and leg 3's
    (x-y plane, about its middle axis x: m_d r_d^2 / 2) turn about x; leg 2's distal arc, between the fixed axes z
    and x, stays.  By the symmetry of the legs the same holds about y and z."""
    from symkin import load_model

    _, sheet, _ = eye_sheet
    v = {p.name: float(p.value) for p in load_model(MODELS_DIR / "agile_eye.yaml").parameters}
    by_hand = (v["m_p"] * v["r_p"] ** 2 / 2 + v["J_rotor"] + v["I_camera"] + v["m_d"] * v["r_d"] ** 2
               + v["m_d"] * v["r_d"] ** 2 / 2)
    measures = {m.name: m.values for m in sheet.measures}
    assert measures["apparent_inertia_min"][sheet.home] == pytest.approx(by_hand, rel=DYNAMICS)
    assert measures["apparent_inertia_max"][sheet.home] == pytest.approx(by_hand, rel=DYNAMICS)


def test_cli_rates_a_spherical_platform_over_its_orientations(generated_dir, tmp_path):
    out = tmp_path / "eye"
    assert main(["rate", str(generated_dir / "agile_eye"), "--effort-limit", "1", "--encoder", "4096",
                 "--box", "yaw=-0.5:0.5", "-n", "1024", "--no-figure", "-o", str(out)]) == 0
    sheet = json.loads((out / "datasheet.json").read_text())
    assert sheet["axes"] == ["roll", "pitch", "yaw"]
    assert sheet["measures"]["apparent_inertia_min"]["unit"] == "kg m^2"
    assert sheet["measures"]["angular_resolution"]["unit"] == "rad"
    assert all(abs(m["min"]["tcp"][2]) <= 0.5 for m in sheet["measures"].values())
    assert "roll [rad],pitch [rad],yaw [rad]" in (out / "datasheet.csv").read_text()
    assert "at orientation (" in (out / "summary.txt").read_text()


def test_a_device_carrying_a_wrist_feels_the_friction_of_its_cheapest_joint_motion(tmp_path):
    """The DELTA with its wrist (models/delta_wrist.yaml) rated whole at its grip point (--device): six joints move
    three grip coordinates, so the friction and damping felt are those of the least dissipating joint motion.  The
    datasheet's home values against rating's functions on J from central differences of the generated fk and
    device_fk (the grip's position as the legs and the wrist turn)."""
    text = (MODELS_DIR / "delta_wrist.yaml").read_text()
    text = text.replace("  tcp: {xyz: [0, h, 0]}\n", "  tcp: {xyz: [0, h, 0]}\n  friction:\n"
                        + "".join(f"    psi{i}: {{viscous: 0.0002, coulomb: 0.001}}\n" for i in (1, 2, 3)))
    text += "friction:\n" + "".join(f"  theta{i}: {{viscous: 0.01, coulomb: 0.02}}\n" for i in (1, 2, 3))
    path = tmp_path / "delta_wrist.yaml"
    path.write_text(text)
    out = tmp_path / "rate"
    assert main(["rate", str(path), "--device", "-n", "200", "--effort-limit", "1", "--no-figure", "-o", str(out)]) == 0
    sheet = json.loads((out / "datasheet.json").read_text())
    assert "friction" not in sheet["not_rated"]
    from symkin import derive
    device = load(derive(str(path), str(tmp_path / "code"), outputs=["fk", "device_fk"]))
    home = np.array(sheet["home"]["q"])

    def grip(coordinates):
        q, qw = coordinates[:3], coordinates[3:]
        return device.device_fk(device.fk(q).position, qw)[:3, 3]

    h = 1e-6
    J = np.stack([(grip(home + h * e) - grip(home - h * e)) / (2 * h) for e in np.eye(6)], axis=-1)
    coulomb, viscous = [0.02] * 3 + [0.001] * 3, [0.01] * 3 + [0.0002] * 3
    measures = sheet["measures"]
    # central differences: truncation h^2 |grip'''| ~ 1e-12 and rounding EPS / h ~ 1e-10, relative to entries ~ 0.1
    assert measures["coulomb_friction"]["home"] == pytest.approx(float(formulas.coulomb_friction_felt(J, coulomb)),
                                                                 rel=1e-7)
    assert measures["handle_damping"]["home"] == pytest.approx(float(formulas.handle_damping(J, viscous)), rel=1e-7)


def test_a_clipped_colour_scale_says_so_and_the_map_shows_the_worst_over_height():
    """Issue 60: a map whose bar ended at 11 kg while the summary said 69 kg - a scale that clips has extend arrows
    and the true range in its label; a spatial device's map shows, per x-y cell, the worst value over z."""
    from symkin.rating.datasheet_files import colour_range, worst_map

    values = np.concatenate([np.linspace(1.0, 2.0, 200), [69.0]])
    low, high, extend, note = colour_range(values, values)
    assert (extend, note) == ("both", "colours clipped; values 1 .. 69")
    assert high < 69.0
    assert colour_range(np.ones(5), np.ones(5))[2:] == ("neither", "")
    points = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 0.0], [1.0, 1.0, 1.0]])
    masses, forces_ = np.array([1.0, 5.0, 2.0, 3.0]), np.array([4.0, 0.5, 2.0, 3.0])
    _, _, heaviest = worst_map(points, masses, worst_is_min=False, cells=2)
    _, _, weakest = worst_map(points, forces_, worst_is_min=True, cells=2)
    assert (heaviest[0, 0], heaviest[1, 1]) == (5.0, 3.0)      # the worst of the two heights in each corner cell
    assert (weakest[0, 0], weakest[1, 1]) == (0.5, 2.0)
    assert np.isnan(heaviest[0, 1])


def test_the_datasheet_figure_keeps_titles_clear_and_prints_no_negative_zero(generated_dir):
    from checks import check_figure_layout

    from symkin.rating import datasheet, datasheet_files
    from symkin.rating.handle_measures import Actuation

    delta = load(generated_dir / "delta")
    sheet = datasheet.rate(delta, Actuation.of_model(delta, effort_limits=[0.3] * 3), samples=500)
    check_figure_layout(datasheet_files.datasheet_figure(sheet, "delta"))   # titles clear of the colour bars
    assert datasheet._point([-1e-17, 0.0, -0.15], ("x", "y", "z")) == "(0.0, 0.0, -150.0) mm"


def test_a_datasheet_factorizes_each_jacobian_once(generated_dir, monkeypatch):
    """The measures that take J^-T (peak force, Coulomb friction felt, damping, backdrive friction along each axis) and
    J M^-1 J^T (principal and per-axis masses) share one of each per handle (handle_measures.SharedFactors): a DELTA
    with friction and encoders, every group rated, forms J^-T once and J M^-1 J^T once; the Agile Eye's turned handle
    (torques, friction) likewise.  (The figures themselves: the oracles above, the formulas called on their own.)"""
    from symkin.rating import datasheet

    formed = {"inverse_transpose": 0, "mobility": 0}
    for name in formed:
        def counted(*args, original=getattr(formulas, name), name=name, **kwargs):
            formed[name] += 1
            return original(*args, **kwargs)
        monkeypatch.setattr(formulas, name, counted)
    delta = load(generated_dir / "delta")
    actuation = handle_measures.Actuation(np.full(3, 0.3), np.full(3, 0.15), np.full(3, 1e-4), np.full(3, 0.01),
                                          np.full(3, 0.02))
    sheet = datasheet.rate(delta, actuation, samples=400)
    assert not sheet.skipped
    assert formed == {"inverse_transpose": 1, "mobility": 1}
    eye = load(generated_dir / "agile_eye")
    formed.update(inverse_transpose=0, mobility=0)
    datasheet.rate(eye, handle_measures.Actuation(np.full(3, 1.0), None, np.full(3, 1e-3), np.full(3, 0.01),
                                                  np.full(3, 0.02)), samples=64)
    assert formed == {"inverse_transpose": 1, "mobility": 1}
