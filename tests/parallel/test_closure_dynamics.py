"""Dynamics of legs without the distance form (issue 31): the dual SCARA of docs/model-format.md with its link
bodies, bar and rotors (``closure_dynamics`` over z = (q, s, p), reduced at run time through the closure).

Reference: Pinocchio's ``constraintDynamics`` of the same two legs as a kinematic tree from the base (leg 1 carries
the bar on its wrist) closed by a 6-D weld of leg 2's hand to the bar: Pinocchio's own CRBA, RNEA and constraint
accelerations, with the loop multipliers (proximal, mu = 1e-6 on the weld's two rows that all-vertical axes make
redundant; it converges to the exact solution).  Every mass property is written again from the document in
tests/dual_scara_reference.py.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from conftest import MODELS_DIR
from sample_models import dual_scara_dynamics_text
from symkin import load, pipeline
from symkin.derivation import Derivation
from symkin.dynamics.parameter_names import DRIVE, INERTIAL
from symkin.errors import DerivationError, ModelError
from symkin.mechanism.closure import ClosureFunctions
from symkin.model import load_model, model_from_text
from symkin.runtime.closure_dynamics import (actuated_dynamics, closure_forward_dynamics, closure_inverse_dynamics,
                                             closure_regressor)
from symkin.runtime.parallel import solve_closure
from symkin.simulation import ArmSystem, Plant, run_adaptive
from symkin.cli import main
from tolerances import DYNAMICS, EPS, NEWTON

from dual_scara_reference import CLOSURE_ROWS, GRAVITY, HOME, ROTOR, assembled_states, constraint_accelerations


@pytest.fixture(scope="module")
def scara_dir(tmp_path_factory):
    model = model_from_text(dual_scara_dynamics_text(), file="dual_scara_dynamics.yaml")
    request = pipeline.resolve_request(model, "closure,closure_jacobians,closure_dynamics", "numpy,casadi",
                                       fixed="all")
    return pipeline.write(pipeline.generate(model, request), tmp_path_factory.mktemp("scara"))


@pytest.fixture(scope="module")
def scara(scara_dir):
    return load(scara_dir)


def test_forward_and_inverse_dynamics_match_pinocchio_constraint_dynamics(scara):
    """At random assembled states, velocities and efforts: the reduced forward dynamics equals Pinocchio's
    accelerations of the actuated joints, and the inverse dynamics at them gives back the efforts.  Both sides
    solve with matrices of kappa <= ~1e3 here (M, [Phi_s Phi_p]): kappa eps ~ 1e-13; the issue's 1e-9 relative
    leaves room for two different algorithms and is still far below any modelling error (a missing body or rotor
    changes the accelerations by > 1e-3)."""
    accelerations = constraint_accelerations(pytest.importorskip("pinocchio"))
    rng = np.random.default_rng(3107)
    for q, s, p in assembled_states(scara, 5, rng):
        qd, tau = rng.uniform(-1, 1, 4), rng.uniform(-0.5, 0.5, 4) + [0, 4.4, 0, 0]
        reference = accelerations(q, s, actuated_dynamics(scara, q, s, p, qd).zd, tau)
        qdd = closure_forward_dynamics(scara, q, s, p, qd, tau)
        assert np.max(np.abs(qdd - reference)) <= 1e-9 * np.max(np.abs(reference)), (qdd, reference)
        back = closure_inverse_dynamics(scara, q, s, p, qd, reference)
        assert np.max(np.abs(back - tau)) <= 1e-9 * np.max(np.abs(tau)), (back, tau)


def test_at_rest_the_lift_holds_what_moves_with_the_bar(scara):
    """Closed forms: all revolute axes are vertical, so at rest gravity loads only the lift, with the weight of the
    bar, its own link and the planar leg's slide and hand (0.45 kg); M is symmetric positive definite and its lift
    entry is that mass plus the rotor's gear_ratio^2 J_rotor (the lift's motion moves nothing else)."""
    (q, s, p), = assembled_states(scara, 1, np.random.default_rng(7))
    terms = actuated_dynamics(scara, q, s, p, np.zeros(4))
    expected = np.array([0.0, (0.1 + 0.2 + 0.1 + 0.05) * GRAVITY, 0.0, 0.0])
    assert np.max(np.abs(terms.bias - expected)) <= 64 * np.finfo(float).eps * expected[1]
    assert np.max(np.abs(terms.M - terms.M.T)) <= 64 * np.finfo(float).eps * np.max(np.abs(terms.M))
    assert np.all(np.linalg.eigvalsh(terms.M) > 0)
    assert abs(terms.M[1, 1] - (0.45 + ROTOR)) <= 64 * np.finfo(float).eps


def test_the_casadi_function_gives_the_numpy_terms(scara, scara_dir):
    """The same expressions through CasADi's SX graph: each output within DYNAMICS of its largest entry."""
    (q, s, p), = assembled_states(scara, 1, np.random.default_rng(11))
    rates = np.random.default_rng(12).uniform(-1, 1, 12)
    numpy_terms = scara.closure_dynamics(q, s, p, rates[:4], rates[4:8], rates[8:])
    casadi_terms = load(scara_dir, "casadi").closure_dynamics(q, s, p, rates[:4], rates[4:8], rates[8:])
    for name in ("M_z", "h_z", "gamma"):
        expected, got = np.asarray(getattr(numpy_terms, name)), np.asarray(getattr(casadi_terms, name))
        assert np.max(np.abs(got.reshape(expected.shape) - expected)) <= DYNAMICS * np.max(np.abs(expected)), name


def test_a_free_motion_keeps_its_energy(scara):
    """Released from the home assembly with joint velocities and no efforts, under gravity: k + u stays constant
    along DOP853's solution to rtol 1e-10 (the plant solves each state's assembly from the last).  A V_z that did
    not follow from M_z, a missing closure acceleration c or a wrong W would change it by > 1e-4 J within 0.2 s."""
    plant = Plant(scara)
    system = ArmSystem(plant)
    x0 = system.initial(plant.mechanism.home_configuration, np.array([0.8, 0.05, -0.6, 0.7]))
    run = run_adaptive(system.derivative, lambda t, x: np.zeros(4), x0, np.linspace(0.0, 0.2, 21))
    state = system.split(run.x)
    energy = plant.energy(state.q, state.qd)
    scale = float(np.max(np.abs(energy)))
    assert np.ptp(energy) <= 1e-8 * scale, (np.ptp(energy), scale)
    assert np.ptp(state.q[:, 0]) > 0.1  # it moved


def test_the_plant_continues_the_home_assembly_to_a_far_configuration(scara):
    """The plant's assembly at actuator positions 0.4 rad away is the home assembly continued (in steps of at most
    0.2 rad: two here) and equals a continuation written here in 40 steps; a batch read after the plant moved
    there gives the home pose back at the home configuration (solved from the home assembly, the nearer one)."""
    from symkin.mechanism.closure import ClosureFunctions

    functions = ClosureFunctions(scara)
    home_q, home_s = functions.home, functions.assembly(functions.home)[0]
    far = home_q + np.array([0.4, 0.05, -0.3, 0.3])
    s, p = home_s, HOME
    for fraction in np.linspace(0.0, 1.0, 41)[1:]:
        report = solve_closure(scara, home_q + fraction * (far - home_q), s, p, unknowns=("p", "s"))
        s, p = report.solution["s"], report.solution["p"]
    s_far, p_far = functions.assembly(far)
    blocks = scara.closure_jacobians(far, s, p)
    kappa = float(np.linalg.cond(np.concatenate([blocks.Phi_s, blocks.Phi_p], axis=-1)[CLOSURE_ROWS]))
    assert np.max(np.abs(np.concatenate([s_far - s, p_far - p]))) <= kappa * NEWTON
    s_batch, p_batch = functions.assembly(np.stack([home_q, far]))
    assert np.max(np.abs(p_batch[0] - HOME)) <= kappa * NEWTON
    assert np.max(np.abs(p_batch[1] - p_far)) <= kappa * NEWTON


def test_symkin_simulate_runs_the_haptic_wall_on_the_model_file(tmp_path):
    """The model file derived on the fly with closure_dynamics (an optional output of the simulation), a 1 kHz
    wall rendered against the hand for 0.1 s: the loop's power balance holds to the integrator's error."""
    (tmp_path / "dual_scara.yaml").write_text(dual_scara_dynamics_text())
    out = tmp_path / "wall"
    assert main(["simulate", str(tmp_path / "dual_scara.yaml"), "--scenario", "haptic-wall", "--duration", "0.1",
                 "--no-figure", "-o", str(out)]) == 0
    summary = (out / "summary.txt").read_text()
    drift = float(summary.split("energy balance drift ")[1].split()[0])
    assert drift <= 1e-8, summary


def test_the_datasheet_rates_the_apparent_mass_from_the_closure_dynamics(scara):
    """With bodies, symkin rate's apparent mass (J_v M^-1 J_v^T)^-1 (the yaw free) over the working mode: along z the
    handle moves with the lift alone and nothing else moves with z, so the smallest principal mass at every cell is
    what rides on the lift, 0.45 kg, plus its rotor (closed form; the solves' rounding, kappa(M) <= 1e3, times
    64 eps); the horizontal ones are heavier (the arms and their geared rotors)."""
    from symkin.rating import datasheet
    from symkin.rating.handle_measures import Actuation

    sheet = datasheet.rate(scara, Actuation.of_model(scara, effort_limits=[1.0] * 4), samples=216,
                           limits={"lift1": (0.0, 0.2)})
    measures = {measure.name: measure.values for measure in sheet.measures}
    assert "apparent_mass" not in sheet.skipped
    assert np.max(np.abs(measures["apparent_mass_min"] - (0.45 + ROTOR))) <= 1e3 * 64 * np.finfo(float).eps
    assert np.all(measures["apparent_mass_max"] > 1.5 * measures["apparent_mass_min"])
    # the gravity share from the efforts at rest (issue 60: it was dropped unlisted): only the lift holds the 0.45 kg
    assert np.max(np.abs(measures["gravity_share"] - 0.45 * GRAVITY / 1.0)) <= 1e3 * 64 * np.finfo(float).eps
    assert "apparent_inertia_min" in measures
    assert "continuous_torque" in sheet.skipped


@pytest.mark.parametrize("bodies, message", [
    ("  links:\n    theta3: {mass: 0.1}\n", "no leg joint named 'theta3'"),
    ("  links:\n    theta1: {mass: 0.1}\n  rod: {mass: 0.1}\n", "cannot be combined with rod"),
    ("  links: [theta1]\n", "expected a mapping"),
])
def test_link_bodies_that_name_no_joint_or_mix_forms_are_refused_where_they_are(bodies, message):
    text = dual_scara_dynamics_text().split("bodies:\n")[0] + "bodies:\n" + bodies
    with pytest.raises(ModelError) as error:
        model_from_text(text, file="bad.yaml")
    assert message in str(error.value)
    assert "bad.yaml:" in str(error.value)


def test_closure_dynamics_is_for_legs_without_the_distance_form():
    with pytest.raises(DerivationError, match="distance form, whose dynamics are mass_matrix"):
        Derivation(load_model(MODELS_DIR / "delta.yaml"))["closure_dynamics"]
    bare = model_from_text(dual_scara_dynamics_text().split("gravity:")[0], file="bare.yaml")
    with pytest.raises(DerivationError, match="needs the mass properties"):
        Derivation(bare)["closure_dynamics"]


def _randomized_bodies(text, rng):
    """Every body of the document's dual SCARA with a random mass, an off-axis centre of mass and a full inertia
    (principal-like moments 1-1.5e-3 kg m^2, products below 2e-5: positive definite), so that every standard
    parameter of the regressor is nonzero."""
    def body(_):
        m, c = rng.uniform(0.05, 0.4), rng.uniform(-0.05, 0.05, 3)
        d, off = rng.uniform(1e-3, 1.5e-3, 3), rng.uniform(-2e-5, 2e-5, 3)
        return (f"{{mass: {m:.4f}, com: [{c[0]:.4f}, {c[1]:.4f}, {c[2]:.4f}], inertia: {{xx: {d[0]:.6f}, "
                f"yy: {d[1]:.6f}, zz: {d[2]:.6f}, xy: {off[0]:.7f}, xz: {off[1]:.7f}, yz: {off[2]:.7f}}}}}")

    changed, count = re.subn(r"\{mass: [^{}]*\{[^{}]*\}\}", body, text)
    assert count == 8  # the platform and the seven link bodies
    return changed


def test_the_regressor_of_legs_without_the_distance_form_is_their_inverse_dynamics(tmp_path):
    """The dual SCARA with random full bodies and friction on two actuators: at assembled states, random rates and
    accelerations, Y pi (Y = W^T Y_z at the motion the closure allows) equals closure_inverse_dynamics (friction
    included) to DYNAMICS of sum |Y_ik pi_k|; pi lists each link body's ten parameters about its joint's frame, the
    platform's, then each actuator's drive."""
    rng = np.random.default_rng(57)
    text = _randomized_bodies(dual_scara_dynamics_text(), rng) + (
        "\nfriction:\n  theta1: {viscous: 0.01, coulomb: 0.02}\n"
        "  knee2: {viscous: 0.02, coulomb: {positive: 0.03, negative: 0.01}}\n")
    model = model_from_text(text, file="dual_scara_random.yaml")
    request = pipeline.resolve_request(model, "closure,closure_jacobians,closure_dynamics,closure_regressor,friction",
                                       "numpy", fixed="all")
    generated = load(pipeline.write(pipeline.generate(model, request), tmp_path))
    names = generated.info.functions["closure_regressor"].results[1].elements
    links = [body.link for body in model.parallel.bodies.links]
    assert names == tuple([f"{link}.{p}" for link in links + ["platform"] for p in INERTIAL]
                          + [f"{c.name}.{p}" for c in model.coordinates for p in DRIVE])
    ik = solve_closure(generated, [1.0, 0.1, 1.6, 0.0], np.zeros(4), HOME, unknowns=("q", "s"), max_step=0.2)
    states = []
    for _ in range(4):
        q = ik.solution["q"] + rng.uniform(-0.03, 0.03, 4)
        fk = solve_closure(generated, q, ik.solution["s"], HOME, unknowns=("p", "s"))
        assert fk.all_converged
        states.append((q, fk.solution["s"], fk.solution["p"], rng.normal(size=4), rng.normal(size=4)))
        Y, pi = closure_regressor(generated, *states[-1])
        assert np.all(pi[:len(INERTIAL) * (len(links) + 1)] != 0)  # every body's parameters are exercised
        tau = closure_inverse_dynamics(generated, *states[-1])
        np.testing.assert_array_less(np.abs(Y @ pi - tau), DYNAMICS * np.abs(Y * pi).sum(axis=-1))
    batch = closure_regressor(generated, *(np.stack(values) for values in zip(*states)))  # one call, four states
    np.testing.assert_allclose(batch[0][-1], Y, rtol=0, atol=DYNAMICS * np.abs(Y).max())
    np.testing.assert_array_equal(batch[1][-1], pi)
    first = model.parallel.bodies.links[0]
    assert pi[names.index(f"{first.link}.m")] == float(first.mass)
    assert pi[names.index(f"{first.link}.my")] == pytest.approx(float(first.mass * first.com[1]), rel=2 * EPS)
