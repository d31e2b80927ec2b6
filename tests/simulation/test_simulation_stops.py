"""Joint stops in the simulation: the linear spring-damper beyond the joint limits.

Oracles: the closed forms of the linear oscillator d'' + 2 zeta omega d' + omega^2 d = 0
(contact time pi / omega_d, restitution exp(-zeta pi / sqrt(1 - zeta^2)), peak penetration)
with the effective inertia 1 / (M^-1)_ii at the contact, the static rest k d = G(q) on the
stops, the energy balance k + u + U + D - w, stops off as the reference inside the limits,
and the growth or decay of a perturbation as RK4's stability region predicts.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from symkin import load
from symkin.cli import main
from symkin.simulation import ArmSystem, ComputedTorque, JointSine, Plant, run_adaptive, run_sampled, scenarios
from symkin.simulation.contacts import intervals
from symkin.simulation.stops import ContactModes, JointStops, effective_inertia, rk4_stability, stop_configurations
from tests.conftest import GENERATED_DIR, MODELS_DIR
from tolerances import CLOSED_FORM

START = np.radians([45.0, 45.0])
ZERO = np.zeros(2)


@pytest.fixture(scope="module")
def plant():
    return Plant(load(GENERATED_DIR / "planar_2r"))


@pytest.fixture(scope="module")
def impact():
    """planar_2r without gravity, theta2 thrown at -3 rad/s onto its lower stop, theta1 free (DOP853)."""
    plant = Plant(load(GENERATED_DIR / "planar_2r").bind(g=0.0))
    q0, qd0 = np.radians([45.0, 10.0]), np.array([0.0, -3.0])
    stops = JointStops.from_plant(plant, q0)
    system = ArmSystem(plant, stops=stops)
    run = run_adaptive(system.derivative, lambda t, x: ZERO, system.initial(q0, qd0), np.linspace(0.0, 0.1, 2001),
                       modes=ContactModes(stops))
    return plant, stops, system, run


def test_defaults_follow_from_the_effective_inertia(plant):
    stops = JointStops.from_plant(plant, START, time_constant=0.004, damping_ratio=0.3)
    M = plant.model.mass_matrix(START)
    m = 1.0 / np.diag(np.linalg.inv(M))
    np.testing.assert_allclose(stops.stiffness, m / 0.004 ** 2, rtol=1e-12)
    np.testing.assert_allclose(stops.damping, 2 * 0.3 * m / 0.004, rtol=1e-12)
    np.testing.assert_allclose(stops.lower, [0.0, 0.0])
    np.testing.assert_allclose(stops.upper, [np.pi / 2, np.pi / 2])
    custom = JointStops.from_plant(plant, START, stiffness={"theta2": 50.0}, damping={"theta1": 0.0})
    assert custom.stiffness[1] == 50.0
    assert custom.damping[0] == 0.0


def test_inside_the_limits_the_stops_change_nothing(plant):
    stops = JointStops.from_plant(plant, START)
    rng = np.random.default_rng(3)
    q = rng.uniform(0.0, np.pi / 2, (50, 2))
    tau, _ = stops.torque_and_dissipation(q, rng.normal(size=(50, 2)))
    assert np.all(tau == 0.0)
    assert np.all(stops.stored_energy(q) == 0.0)
    reference = JointSine(START, 1, np.radians(30), 1.0)
    q0, qd0, _ = reference(0.0)
    runs = []
    for s in (None, stops):
        system = ArmSystem(plant, stops=s)
        runs.append(run_sampled(system.derivative, ComputedTorque(system, reference), system.initial(q0, qd0),
                                1e-3, 300))
    np.testing.assert_array_equal(runs[1].x[:, :4], runs[0].x[:, :4])      # bit for bit
    np.testing.assert_array_equal(runs[1].u, runs[0].u)
    assert np.all(runs[1].x[:, -1] == 0.0)                                   # nothing dissipated
    # DOP853 with contact modes: no switch, the same motion to the tolerance
    timing = scenarios.Timing(0.5, 200, "dop853")
    results = [scenarios.sine([("", plant)], START, 1, np.radians(30), 1.0, timing, stops=s)
               for s in (None, scenarios.StopSettings())]
    on, off = results[1].series[0], results[0].series[0]
    assert on.contacts == ()
    np.testing.assert_allclose(on.columns["simulated theta2 [rad]"], off.columns["simulated theta2 [rad]"], atol=1e-9)
    assert np.all(on.columns["tau_stop_theta2 [N m]"] == 0.0)
    assert "  theta1, theta2: no contact with their stops" in results[1].summary


def _oscillator(v: float, omega: float, zeta: float, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Penetration and its rate of d'' + 2 zeta omega d' + omega^2 d = 0, d(0) = 0, d'(0) = v (underdamped):
    d = v / omega_d e^(-zeta omega t) sin(omega_d t), written out here independently of symkin.simulation.stops."""
    omega_d = omega * math.sqrt(1 - zeta ** 2)
    decay = np.exp(-zeta * omega * t)
    return (v / omega_d * decay * np.sin(omega_d * t),
            v * decay * (np.cos(omega_d * t) - zeta * omega / omega_d * np.sin(omega_d * t)))


def restitution(v: float, omega: float, zeta: float) -> float:
    """Rebound speed over impact speed: -d'(t_c) / v at the end of contact t_c = pi / omega_d."""
    return float(-_oscillator(v, omega, zeta, np.array([math.pi / (omega * math.sqrt(1 - zeta ** 2))]))[1][0] / v)


def peak_penetration(v: float, omega: float, zeta: float) -> float:
    """max d(t) over the contact, by dense sampling of the analytic response (relative resolution ~1e-9)."""
    t = np.linspace(0.0, math.pi / (omega * math.sqrt(1 - zeta ** 2)), 200_001)
    return float(np.max(_oscillator(v, omega, zeta, t)[0]))


def test_an_impact_follows_the_linear_spring_damper_closed_forms(impact):
    plant, stops, system, run = impact
    assert [(s.guard.joint, s.guard.side, s.guard.entering) for s in run.switches] == [(1, -1, True), (1, -1, False)]
    enter, leave = run.switches
    assert abs(enter.x[1]) < 1e-12
    assert abs(leave.x[1]) < 1e-12              # located on the limit
    # the contact oscillator: effective inertia of theta2 with theta1 free, at the contact
    m = effective_inertia(plant.mass_matrix(enter.x[:2]))[1]
    k, c = stops.stiffness[1], stops.damping[1]
    omega, zeta = math.sqrt(k / m), c / (2 * math.sqrt(k * m))
    assert 0.3 < zeta < 0.8                                                   # underdamped: it bounces
    v = -enter.x[3]
    np.testing.assert_allclose(leave.t - enter.t, math.pi / (omega * math.sqrt(1 - zeta ** 2)), rtol=1e-3)
    np.testing.assert_allclose(leave.x[3] / v, restitution(v, omega, zeta), rtol=1e-3)
    peak = np.max(stops.depth(run.x[:, :2])[:, 1])                           # samples every 50 us
    np.testing.assert_allclose(peak, peak_penetration(v, omega, zeta), rtol=2e-3)
    assert peak < v * math.sqrt(m / k)                                        # below the undamped bound v / omega


def test_energy_balance_holds_with_contacts(impact, plant):
    _, stops, system, run = impact
    s = system.split(run.x)
    energy = system.plant.energy(s.q, s.qd)
    balance = system.balance(run.x)
    assert np.ptp(balance) < 1e-9 * energy[0]
    lost = energy[0] - energy[-1]
    np.testing.assert_allclose(s.dissipated[-1], lost, rtol=1e-9)             # the damper has what was lost
    # theta1's momentum p_1 is untouched by the stop: the loss is 1/2 m v^2 (1 - e^2) of the contact oscillator
    enter = run.switches[0]
    m = effective_inertia(system.plant.mass_matrix(enter.x[:2]))[1]
    e = run.switches[1].x[3] / -enter.x[3]
    np.testing.assert_allclose(lost, 0.5 * m * enter.x[3] ** 2 * (1 - e ** 2), rtol=1e-3)
    # during the contact the spring holds 1/2 k d_peak^2 at the peak of the oscillator
    k, c = stops.stiffness[1], stops.damping[1]
    peak = peak_penetration(-enter.x[3], math.sqrt(k / m), c / (2 * math.sqrt(k * m)))
    np.testing.assert_allclose(np.max(stops.stored_energy(s.q)), 0.5 * k * peak ** 2, rtol=4e-3)


@pytest.fixture(scope="module")
def fall(plant):
    """planar_2r released at rest under gravity from 45, 45 deg (DOP853 with contact events)."""
    return scenarios.free_swing("", plant, START, scenarios.Timing(1.2, 200, "dop853"), stops=scenarios.StopSettings())


def test_an_arm_released_under_gravity_comes_to_rest_on_its_stops(plant, fall):
    series = fall.series[0]
    c = series.columns
    stops = JointStops.from_plant(plant, START)
    q = np.stack([c["theta1 [rad]"], c["theta2 [rad]"]], -1)
    # at rest on both lower stops: k d = G(q) (m_eff g / k), q = -d
    depth = np.stack([c["penetration theta1 [rad]"], c["penetration theta2 [rad]"]], -1)
    np.testing.assert_allclose(depth[-1], plant.gravity(q[-1]) / stops.stiffness, rtol=1e-6)
    assert np.all(depth[-1] > 1e-4)
    # no stop takes more than the energy released above the lowest point, (0, 0) (u = 0):
    # 1/2 k d^2 <= E0 + G_max d  ->  d <= (G_max + sqrt(G_max^2 + 2 k E0)) / k
    e0 = c["energy k + u [J]"][0]
    g_max = plant.gravity(np.zeros(2))
    bound = (g_max + np.sqrt(g_max ** 2 + 2 * stops.stiffness * e0)) / stops.stiffness
    assert np.all(np.max(depth, axis=0) < bound)
    assert np.all(np.max(depth, axis=0) > 10 * depth[-1])                     # real impacts, not just sagging
    # both joints met their lower stops, and still rest on them
    joints = {(contact.joint, contact.side) for contact in series.contacts}
    assert {("theta1", "lower"), ("theta2", "lower")} <= joints
    assert {contact.end for contact in series.contacts if contact.side == "lower"} >= {1.2}
    np.testing.assert_allclose(c["balance drift [J]"], 0.0, atol=1e-9 * e0)
    assert any(line.strip().startswith("theta1: in contact") for line in fall.summary)


def test_sampled_contacts_agree_with_the_located_events(plant, fall):
    """RK4 contact intervals (interpolated between samples) against DOP853's events: the first contact."""
    stops = JointStops.from_plant(plant, START)
    system = ArmSystem(plant, stops=stops)
    run = run_sampled(system.derivative, lambda t, x: ZERO, system.initial(START), 1e-3, 200, substeps=4)
    first = intervals(stops, run)[0]
    exact = fall.series[0].contacts[0]
    assert (first.joint, first.side) == (exact.joint, exact.side)
    assert abs(first.start - exact.start) < 1e-4
    assert abs(first.end - exact.end) < 1e-3


def test_rk4_is_stable_in_contact_exactly_where_the_condition_says(plant):
    stops = JointStops.from_plant(plant, START, time_constant=3e-4)
    system = ArmSystem(plant, stops=stops)
    depth = np.zeros(2)
    for _ in range(50):                                                       # rest on the stops: k d = G(-d)
        depth = plant.gravity(-depth) / stops.stiffness
    rest = -depth
    stability = rk4_stability(stops, plant.mass_matrix(rest), 1e-3)
    assert not stability.stable
    assert stability.substeps_needed > 1
    deviation = {}
    for substeps in (stability.substeps_needed - 1, stability.substeps_needed):
        run = run_sampled(system.derivative, lambda t, x: ZERO, system.initial(rest + 1e-3 * depth), 1e-3, 100,
                          substeps)
        deviation[substeps] = np.max(np.abs(run.x[:, :2] - rest), axis=1)
    unstable, stable = deviation.values()
    assert unstable[-1] > 100 * unstable[0]
    assert stable[-1] < stable[0]
    assert rk4_stability(stops, plant.mass_matrix(rest), 1e-3, stability.substeps_needed).stable
    # the check before a run, from the start configuration, covers the rest on the stops through the corners
    corners = plant.mass_matrix(stop_configurations(stops, START))
    assert rk4_stability(stops, corners, 1e-3).substeps_needed >= stability.substeps_needed
    assert rk4_stability(stops, plant.mass_matrix(START), 1e-3).substeps_needed < stability.substeps_needed


def test_cli_reports_stops_and_warns_before_an_unstable_loop(tmp_path, capsys):
    out = tmp_path / "swing"
    assert main(["simulate", str(GENERATED_DIR / "planar_2r"), "--scenario", "free-swing", "--duration", "0.4",
                 "--rate", "200", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "joint stops: linear spring-damper" in printed
    assert re.search(r"theta1: in contact \d+ x lower [0-9.]+ s; max penetration", printed)
    header = (out / "free-swing-1-asdeclared.csv").read_text().splitlines()[1]
    assert "penetration theta1 [rad]" in header
    assert "stop energy dissipated [J]" in header
    assert (out / "free-swing.png").read_bytes()[:4] == b"\x89PNG"
    off = tmp_path / "off"
    assert main(["simulate", str(GENERATED_DIR / "planar_2r"), "--scenario", "free-swing", "--duration", "0.1",
                 "--rate", "200", "--joint-stops", "off", "--no-figure", "-o", str(off)]) == 0
    assert "penetration" not in (off / "free-swing-1-asdeclared.csv").read_text()
    assert main(["simulate", str(GENERATED_DIR / "planar_2r"), "--scenario", "free-swing", "--duration", "0.01",
                 "--integrator", "rk4", "--stop-time-constant", "0.0003", "--no-figure", "-o", str(off)]) == 0
    captured = capsys.readouterr()
    assert "warning: planar_2r: RK4 at h = 1 ms is unstable in contact" in captured.err
    assert "UNSTABLE" in captured.out


def test_stops_on_a_model_without_limits_exit_with_code_2(tmp_path, capsys):
    source = tmp_path / "planar_2r.yaml"
    source.write_text((MODELS_DIR / "planar_2r.yaml").read_text().replace(", [0, deg(90)]]", "]"))
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as exit_info:
        main(["simulate", str(source), "--scenario", "free-swing", "--joint-stops", "on", "-o", str(out)])
    assert exit_info.value.code == 2
    assert "--joint-stops on: planar_2r declares no joint limits" in capsys.readouterr().err
    assert not out.exists()


def test_a_guard_zero_at_the_restart_fires_at_its_next_crossing_only():
    """scipy's event location (sign change over a step, then Brent's method) returns the root at the start
    of a step whose guard is exactly zero there: a mode restarted at its switch would end where it began.
    y' = 1 from 1 and g = (y - 1) (y - 1.01) rising, at the run's tolerances: the next crossing is at
    t = 0.01, inside DOP853's first step."""
    from scipy.integrate import solve_ivp

    from symkin.simulation.integrate import ArmedGuard

    def guard(t, y):
        return (y[0] - 1.0) * (y[0] - 1.01)

    guard.direction, guard.terminal = 1.0, True
    tolerances = {"rtol": 1e-10, "atol": 1e-12}
    plain = solve_ivp(lambda t, y: np.ones(1), (0.0, 1.0), np.ones(1), method="DOP853", events=guard, **tolerances)
    assert plain.t_events[0][0] == 0.0                                        # the defect: the restart itself
    armed = solve_ivp(lambda t, y: np.ones(1), (0.0, 1.0), np.ones(1), method="DOP853",
                      events=ArmedGuard(guard, 0.0), **tolerances)
    np.testing.assert_allclose(armed.t_events[0], [0.01], rtol=1e-12)


def test_a_joint_pushed_back_onto_its_stop_right_after_leaving_it_does_not_chatter():
    """UR10e free swing from the default start: wrist 1 (q4) bounces on its lower stop and, 0.78 s in, is
    thrown back onto it within 8 ms of leaving it.  Before the guards were re-armed at each restart this
    ran 10 000 switches at that instant and failed ("chattering")."""
    from symkin.simulation.start import start_pose

    plant = Plant(load(GENERATED_DIR / "ur10e"))
    q0, _ = start_pose(plant)
    stops = JointStops.from_plant(plant, q0)
    system = ArmSystem(plant, stops=stops)
    run = run_adaptive(system.derivative, lambda t, x: np.zeros(6), system.initial(q0), np.linspace(0.0, 1.0, 201),
                       modes=ContactModes(stops))
    located = [(s.guard.joint, s.guard.side, s.guard.entering) for s in run.switches]
    assert located == [(3, -1, True), (3, -1, False)] * 2 + [(3, -1, True)]
    assert np.all(np.diff([s.t for s in run.switches]) > 1e-3)                # no zero-length mode
    # the flight after the second release is a ballistic one, 2 v / a: v = qd4 leaving the stop, a = -qdd4
    # with no stop acting (the arm's own motion throws q4 back); a varies along the 8 ms, hence 10 %
    release, contact = run.switches[3], run.switches[4]
    v = release.x[6 + 3]
    a = -system.derivative(release.t, release.x, np.zeros(6), np.zeros(6))[6 + 3]
    assert v > 0.0
    assert a > 0.0
    np.testing.assert_allclose(contact.t - release.t, 2.0 * v / a, rtol=0.1)
    # resting on the stop at the end, and the power balance holds through all five switches
    assert stops.contact(run.x[-1, :6])[3] == -1
    s = system.split(run.x)
    assert np.ptp(system.balance(run.x)) < 1e-9 * np.max(np.abs(plant.energy(s.q, s.qd)))


#: A table moving in x and y (two prismatic joints: M = diag(m1 + m2, m2), constant), whose carriage and slider
#: meet where x + y reaches 0.05 m: a stop on a combination of joints (issue 64), not on either joint.
XY_TABLE = """
name: xy_table
parameters:
  m1: {value: 2.0, unit: kg, doc: carriage}
  m2: {value: 1.0, unit: kg, doc: slider}
serial:
  chain:
    - {name: x, type: P, axis: [1, 0, 0], link: carriage, limits: [-1, 1]}
    - {name: y, type: P, axis: [0, 1, 0], link: slider, limits: [-1, 1]}
task_space: [x, y]
bodies:
  - {link: carriage, mass: m1}
  - {link: slider, mass: m2}
joint_stops:
  - {expression: "x + y", limits: [-1, 0.05], doc: the carriage meets the slider}
"""


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    from symkin.analysis.model_files import generated_model

    path = tmp_path_factory.mktemp("table") / "xy_table.yaml"
    path.write_text(XY_TABLE)
    return Plant(generated_model(str(path), outputs=("fk", "jacobian", "mass_matrix", "forward_dynamics",
                                                      "inverse_dynamics", "kinetic_energy")))


def test_a_stop_on_a_combination_of_joints_bounces_as_its_oscillator_along_it(table):
    """Thrown at the stop x + y = 0.05 m, the table meets it with the effective mass m_a = 1 / (a^T M^-1 a),
    a = (1, 1) (3/4 kg with M = diag(3, 1) kg): the contact lasts pi / omega_d and the speed along a comes back
    times the restitution of (omega, zeta) = (sqrt(k / m_a), c / (2 sqrt(k m_a))); the stop pushes the joints by
    a f, so the momentum b . M qd along b = (1, -1), b . a = 0, is untouched; the balance holds and the joints'
    own stops never engage."""
    q0, qd0 = np.array([0.0, 0.0]), np.array([0.3, 0.1])
    stops = JointStops.from_plant(table, q0)
    assert stops.names == ("x", "y", "x + y")
    M = table.mass_matrix(q0)
    a = np.array([1.0, 1.0])
    m = 1.0 / (a @ np.linalg.solve(M, a))
    assert m == pytest.approx(0.75, rel=CLOSED_FORM)
    np.testing.assert_allclose(stops.stiffness[2], m / 3e-3 ** 2, rtol=CLOSED_FORM)
    system = ArmSystem(table, stops=stops)
    run = run_adaptive(system.derivative, lambda t, x: ZERO, system.initial(q0, qd0), np.linspace(0.0, 0.5, 2001),
                       modes=ContactModes(stops))
    assert [(s.guard.joint, s.guard.side, s.guard.entering) for s in run.switches] == [(2, 1, True), (2, 1, False)]
    enter, leave = run.switches
    assert abs(enter.x[0] + enter.x[1] - 0.05) < 1e-12                     # located on the stop
    k, c = stops.stiffness[2], stops.damping[2]
    omega, zeta = math.sqrt(k / m), c / (2 * math.sqrt(k * m))
    v_in, v_out = a @ enter.x[2:4], a @ leave.x[2:4]
    np.testing.assert_allclose(leave.t - enter.t, math.pi / (omega * math.sqrt(1 - zeta ** 2)), rtol=1e-6)
    np.testing.assert_allclose(-v_out / v_in, restitution(v_in, omega, zeta), rtol=1e-6)
    # the stop's force is a f: it changes M qd only along a, so the momentum along any b with b . a = 0 stays
    b = np.array([1.0, -1.0])
    np.testing.assert_allclose(b @ M @ leave.x[2:4], b @ M @ qd0, rtol=1e-9)
    s = system.split(run.x)
    energy = table.energy(s.q, s.qd)
    assert np.ptp(system.balance(run.x)) < 1e-9 * energy[0]
    np.testing.assert_allclose(s.dissipated[-1], energy[0] - energy[-1], rtol=1e-9)
    found = intervals(stops, run)
    assert [(c.joint, c.side) for c in found] == [("x + y", "upper")]
