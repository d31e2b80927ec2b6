"""The base parameters of parallel models (issue 33): exact regrouping by modular elimination.

Independent oracles: the regressor itself in floating point at assembled states (q = ik(p) of the generated
numpy code), which Y_b K must reproduce and whose stacked numerical rank must be the number of base parameters;
the Agile Eye, whose closure adds dependencies the formula alone does not show; and the DELTA's regrouping,
which follows from its mechanics (the rods' platform ends move with the platform, their elbow ends at the arm's length a on the
arm, every rotor turns about its arm's axis).
"""

from __future__ import annotations

import dataclasses
import json
import subprocess

import numpy as np
import pytest
import sympy
import yaml

from conftest import MODELS_DIR, SYMKIN_CLI, shared_derivation
from identification_runs import excitation, write_run
from symkin import load, pipeline
from symkin.derivation.graph import Derivation
from symkin.dynamics.parameter_names import DRIVE, INERTIAL
from symkin.errors import DerivationError
from symkin.ir.evaluate import symengine_entries
from symkin.model import load_model, model_from_text
from tolerances import DYNAMICS, EPS

TINY = np.finfo(float).tiny
#: name: (task-space box half-width about home, wrist joints, further outputs)
CASES = {"delta": (0.03, 0, ",fk,inverse_dynamics"), "delta_wrist": (0.03, 3, ",fk"), "agile_eye": (0.2, 0, ""),
         "pantograph": (0.01, 0, ""), "stewart": (0.01, 0, "")}
#: Noise on the simulated efforts (N m): large against rounding, small against the DELTA's (~0.05 N m).
NOISE = 1e-4


@pytest.fixture(scope="module", params=sorted(CASES))
def derived(request, tmp_path_factory):
    name = request.param
    model = load_model(MODELS_DIR / f"{name}.yaml")
    request_ = pipeline.resolve_request(model, only="regressor,base_regressor,ik" + CASES[name][2], backends="numpy")
    derivation = shared_derivation(model)  # shared with the worker's other tests (its stability run: base parameters)
    generated = load(pipeline.write(pipeline.generate(model, request_, derivation=derivation),
                                    tmp_path_factory.mktemp(name)))
    return name, derivation["base_parameters"], generated


def _inputs(generated, name, count, seed, **parameters):
    """Assembled states (q = ik(p) about home, random wrist angles) with random rates, as the regressor takes them."""
    half_width, wrist, _ = CASES[name]
    rng = np.random.default_rng(seed)
    home = np.array(generated.info.home)
    p = home + rng.uniform(-half_width, half_width, (count, len(home)))
    q = generated.ik(p, **parameters).joints
    assert np.all(np.isfinite(q))
    n = q.shape[1]
    if not wrist:
        return (q, p, rng.normal(size=(count, n)), rng.normal(size=(count, n)))
    qw = rng.uniform(-1.2, 1.2, (count, wrist))
    return (q, p, qw, rng.normal(size=(count, n)), rng.normal(size=(count, wrist)), rng.normal(size=(count, n)),
            rng.normal(size=(count, wrist)))


def test_base_columns_span_the_regressor_on_assembled_states(derived):
    """Y = Y_b K within the rounding of the products, Y_b pi_b = Y pi, and Y stacked over assembled states has the
    numerical rank len(pi_b): the b-th singular value of the column-equilibrated stack stands far above the
    rounding, the next ones at it."""
    name, found, generated = derived
    inputs = _inputs(generated, name, 48, 61)
    full, base = generated.regressor(*inputs), generated.base_regressor(*inputs)
    defaults = {i.name: i.default for i in generated.info.functions["regressor"].inputs if i.kind == "parameter"}
    K = found.evaluate(defaults)
    assert base.Y_b.shape[-1] == len(found.base) == K.shape[0]
    row_scale = np.abs(full.Y).max(axis=-1, keepdims=True)  # each row's largest entry: what its rounding scales with
    np.testing.assert_array_less(np.abs(base.Y_b - full.Y[..., list(found.base)]), np.broadcast_to(DYNAMICS * row_scale + TINY, base.Y_b.shape))
    scale = np.abs(base.Y_b) @ np.abs(K) + row_scale  # the rebuilt entry's terms, and the row's (Y's own rounding)
    np.testing.assert_array_less(np.abs(base.Y_b @ K - full.Y), DYNAMICS * scale + TINY)
    tau, tau_b = np.einsum("sik,sk->si", full.Y, full.pi), np.einsum("sik,sk->si", base.Y_b, base.pi_b)
    np.testing.assert_array_less(np.abs(tau_b - tau), DYNAMICS * (np.abs(full.Y) @ np.abs(full.pi[0])) + TINY)
    stacked = full.Y.reshape(-1, full.Y.shape[-1])
    norms = np.linalg.norm(stacked, axis=0)
    singular = np.linalg.svd(stacked[:, norms > 0] / norms[norms > 0], compute_uv=False)
    rank = len(found.base)
    rounding = np.sqrt(stacked.shape[0]) * DYNAMICS * singular[0]
    assert singular[rank - 1] > 1e6 * rounding, (name, singular[rank - 1], rounding)
    if rank < len(singular):
        assert singular[rank] < rounding, (name, singular[rank], rounding)


@pytest.mark.parametrize("derived", ["delta"], indirect=True)
def test_the_deltas_regrouping_is_its_mechanics(derived):
    """The rods' platform ends (rod.mB) move with the platform, three of them; their elbow ends (rod.mC) sit at a
    on the arm (first moment a m_C, inertia a^2 m_C about the axis); the rotors share the arms' axis, so the three
    arms' common Iyy and the three rotor inertias leave one combination out.  K keeps a symbolic: at another arm
    length the base regressor still spans the regressor."""
    name, found, generated = derived
    assert found.equations()[:6] == (
        "platform.mR = platform.m + 3 rod.mB", "actuated_link.mxR = actuated_link.mx + a rod.mC",
        "actuated_link.mz = actuated_link.mz", "actuated_link.IyyR = actuated_link.Iyy + a**2 rod.mC + theta3.Ia",
        "rod.dI = rod.dI", "theta1.IaR = theta1.Ia - theta3.Ia")
    assert found.geometry == ("a",)
    moved = {"a": 0.12}
    inputs = _inputs(generated, name, 16, 62, **moved)
    full, base = generated.regressor(*inputs, **moved), generated.base_regressor(*inputs, **moved)
    K = found.evaluate(moved)
    assert K[1, found.names.index("rod.mC")] == 0.12
    np.testing.assert_array_less(np.abs(base.Y_b @ K - full.Y), DYNAMICS * (np.abs(base.Y_b) @ np.abs(K)) + TINY)
    assert np.abs(base.Y_b @ found.evaluate({"a": 0.1}) - full.Y).max() > 1e3 * EPS * np.abs(full.Y).max()


@pytest.mark.parametrize("derived", ["delta"], indirect=True)
def test_symkin_identify_gives_back_the_deltas_base_parameters(derived, tmp_path):
    """A run simulated with the DELTA's own inverse dynamics along a periodic excitation about home (a finite
    Fourier series of the actuators, the poses from fk), noise on the efforts: `symkin identify models/delta.yaml
    --method consistent` (poses from fk per sample) recovers the model's pi_b within 5 standard deviations (its
    weighted least squares), and standard parameters whose platform and arm are rigid bodies (pseudo-inertias
    positive semidefinite to rounding) and whose rods' end masses are not negative, fitting the run as well as
    the true parameters do; and identified.yaml (:func:`_check_identified_model`)."""
    name, found, generated = derived
    t, q, qd, qdd = excitation(3, seed=3)
    home = generated.ik(np.array(generated.info.home)).joints
    q, qd, qdd = home + 0.25 * (q - 0.7), 0.25 * qd, 0.25 * qdd   # excitation() swings about 0.7 rad
    p = generated.fk(q).position
    tau = generated.inverse_dynamics(q, p, qd, qdd) + np.random.default_rng(3).normal(0, NOISE, q.shape)
    run = write_run(tmp_path / "run.csv", generated.info.coordinate_names, t, q, tau, qd, qdd)
    out, record = _identify("delta", run, found, tmp_path)
    standard = record["standard"]
    assert len(standard["smallest_pseudo_inertia_eigenvalue"]) == 2               # the platform and the arm
    largest = max(abs(v) for v in standard["parameters"].values())
    assert min(standard["smallest_pseudo_inertia_eigenvalue"]) >= -1e3 * EPS * largest
    assert min(standard["parameters"]["rod.mB"], standard["parameters"]["rod.mC"]) >= 0
    # the data weighted by the noise, the true parameters cost chi^2 with len(pi_b) = 16 degrees of freedom more than
    # least squares (mean 16, beyond 64 with a probability below 1e-7): the consistent estimate may cost no more
    assert standard["data_cost"] - standard["least_squares_cost"] < 4 * len(found.base)
    _check_identified_model(out, found, record)


def _identify(name, run, found, tmp_path):
    """`symkin identify models/<name>.yaml RUN --method consistent` into tmp_path/out: (out, estimate.json's record),
    after checking every base parameter's estimate within 5 of its standard deviations of the model's value (the
    weighted least squares; 1 in 1.7 million to fail by chance)."""
    out = tmp_path / "out"
    result = subprocess.run(SYMKIN_CLI + ["identify", str(MODELS_DIR / f"{name}.yaml"), str(run), "--method",
                                          "consistent", "--no-figure", "-o", str(out)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    record = json.loads((out / "estimate.json").read_text())
    assert [row["name"] for row in record["parameters"]] == list(found.base_names)
    error = {row["name"]: abs(row["value"] - row["model"]) / row["std"] for row in record["parameters"]}
    assert max(error.values()) < 5, error
    return out, record


def _check_identified_model(out, found, record):
    """identified.yaml holds what the DELTA's file can (the consistent estimate among its values: one rotor for
    all actuators): the model reader takes it, and its standard parameters (from its own derivation) have base
    parameters within 5 standard deviations of the least-squares estimate's, the rotors' differences
    (theta1.IaR = theta1.Ia - theta3.Ia, theta2's) 0; the summary and the file say what was replaced."""
    model = load_model(out / "identified.yaml")
    names, pi = _standard_parameters(model)
    assert names == list(record["standard"]["parameters"])
    written = found.evaluate({"a": 0.1}) @ pi
    rotors = [found.base_names.index(f"theta{k}.IaR") for k in (1, 2)]
    np.testing.assert_array_less(np.abs(written[rotors]), DYNAMICS * np.abs(pi).max())
    error = {row["name"]: abs(w - row["value"]) / row["std"] for w, row in zip(written, record["parameters"])}
    assert max(error.values()) < 5, error
    assert model.parallel.bodies.rod_inertia is not None      # rod.dI identified: the rods' inertia declared
    document = yaml.safe_load((out / "identified.yaml").read_text())
    assert document["identified"]["method"] == "consistent"
    K = found.evaluate({"a": 0.1})
    assert document["identified"]["parameters"] == [n for n, k in zip(found.names, K.T) if np.any(k != 0)]
    summary = (out / "summary.txt").read_text()
    assert "with the bodies of platform, actuated_link, rod and the drives of theta1, theta2, theta3 identified " \
        "(19 standard parameters); its base parameters within " in summary, summary


def _standard_parameters(model):
    """The names and values of a model's standard parameters, pi of its regressor (from its own derivation)."""
    regressor = Derivation(model)["regressor"]
    pi = symengine_entries(dataclasses.replace(regressor, outputs=regressor.outputs[1:]), [sympy.Symbol("unused")],
                           model.parameter_values)(np.zeros(1))    # pi depends on the parameters alone
    return list(regressor.outputs[1].elements), pi


#: Per model, what the round trip of its file changes beyond the actuators' drives: (links, joints replaced).
ROUND_TRIPS = {"delta": (("platform", "actuated_link", "rod"), ()),
               "delta_wrist": (("platform", "actuated_link", "rod", "fork1", "fork2", "handle"), ("psi1", "psi2", "psi3")),
               "agile_eye": (("platform", "actuated_link", "distal_link"), ())}


@pytest.mark.parametrize("name", sorted(ROUND_TRIPS))
def test_a_parallel_models_file_takes_the_standard_parameters_it_holds(name, tmp_path):
    """identified_model.updated_model maps a parallel model's standard parameters into its file exactly: bodies
    about their frames' origins back to centres of mass, the rods' end masses and inertia beyond them to mass,
    platform fraction and inertia across (the DELTA's L = b), the actuators' one I_a to the rotor (over gear^2),
    friction levels per actuator, a hybrid device's wrist as a serial chain (links in their joint frames, rotor
    inertias, friction), a spherical model without rods; read back and derived, the file has those parameters to
    rounding."""
    from symkin.identification import identified_model

    path = MODELS_DIR / f"{name}.yaml"
    model = load_model(path)
    names, pi = _standard_parameters(model)
    values = pi.copy()
    column = {name: k for k, name in enumerate(names)}
    for k in (1, 2, 3):
        values[[column[f"theta{k}.{p}"] for p in DRIVE]] = 2e-4, 0.01 * k, 0.02, 0.005
    if name == "delta":
        values[column["platform.m"]] = 0.07
        m, c = 0.012, np.array([0.06, 0.0, 0.004])             # an arm about its centre: diag(2, 10, 11) 1e-6
        I_o = np.diag([2e-6, 1e-5, 1.1e-5]) + m * (c @ c * np.eye(3) - np.outer(c, c))
        values[[column[f"actuated_link.{p}"] for p in INERTIAL]] = \
            m, *(m * c), I_o[0, 0], I_o[0, 1], I_o[1, 1], I_o[0, 2], I_o[1, 2], I_o[2, 2]
        values[column["rod.mB"]], values[column["rod.mC"]], values[column["rod.dI"]] = 0.004, 0.006, 2e-6
    elif name == "delta_wrist":
        values[column["fork1.m"]] *= 1.5
        values[column["psi1.Ia"]], values[column["psi2.fv"]], values[column["psi3.fc"]] = 1e-6, 0.01, 0.002
    else:
        values[[column[f"distal_link.{p}"] for p in INERTIAL]] *= 1.5
    updated = identified_model.updated_model(path, model, names, values, np.ones(len(names), dtype=bool),
                                             {"method": "wls", "data": "run.csv", "samples": 100})
    links, joints = ROUND_TRIPS[name]
    assert (updated.links, updated.joints) == (links, ("theta1", "theta2", "theta3") + joints)
    (tmp_path / "identified.yaml").write_text(updated.text)
    back = load_model(tmp_path / "identified.yaml")
    if name == "delta":
        assert float(back.parallel.bodies.rod_platform_fraction) == 0.4
    written = _standard_parameters(back)[1]
    np.testing.assert_array_less(np.abs(written - values), DYNAMICS * np.abs(values).max())


def test_a_spherical_models_file_holds_no_rods():
    """The Agile Eye's file declares no rods (its legs' last joints turn about axes through the centre): the rods'
    columns are held at the model's values, which symkin identify's summary names."""
    from symkin.identification import identified_model

    model = load_model(MODELS_DIR / "agile_eye.yaml")
    names, pi = _standard_parameters(model)
    held = identified_model.parallel_held(model, names, pi)
    assert [name for name, declared in zip(names, held.columns) if not declared] == ["rod.mB", "rod.mC", "rod.dI"]
    np.testing.assert_array_equal(held.fixed[~held.columns], pi[~held.columns])


@pytest.mark.parametrize("derived", ["delta"], indirect=True)
def test_what_a_parallel_models_file_holds_is_the_nearest_it_can(derived):
    """implied_parameters.nearest_held on the DELTA's file (one rotor for the actuators): base parameters it can
    hold are met to rounding with the three I_a equal; the rotors' differences (theta1.IaR, theta2.IaR), which it
    cannot, are left out (0) and the rest still met."""
    from symkin.identification import identified_model, implied_parameters

    name, found, generated = derived
    model = load_model(MODELS_DIR / "delta.yaml")
    names, pi = _standard_parameters(model)
    K = found.evaluate({"a": 0.1})
    held = identified_model.parallel_held(model, names, pi)
    assert held.names[-1] == "rotor.Ia"
    assert held.T.shape == (len(names), len(names) - 2)
    assert held.columns.all()
    rotors = [names.index(f"theta{k}.Ia") for k in (1, 2, 3)]
    reachable = K @ pi + 0.1 * np.abs(K @ pi)
    base = reachable.copy()
    base[[found.base_names.index("theta1.IaR"), found.base_names.index("theta2.IaR")]] = 1e-5, -2e-5
    for target, missed in ((reachable, []), (base, ["theta1.IaR", "theta2.IaR"])):
        estimate = implied_parameters.nearest_held(K, target, pi, held)
        assert np.ptp(estimate[rotors]) <= DYNAMICS * np.abs(estimate[rotors]).max()
        met = [k for k, n in enumerate(found.base_names) if n not in missed]
        np.testing.assert_array_less(np.abs(K @ estimate - target)[met],
                                     (DYNAMICS * np.abs(K) @ np.abs(estimate) + TINY)[met])
        np.testing.assert_array_less(np.abs(K @ estimate)[[found.base_names.index(n) for n in missed]],
                                     DYNAMICS * np.abs(estimate).max())


def _excite(name, iterations, tmp_path):
    """`symkin excite` on models/<name>.yaml (3 rad/s, 20 rad/s^2, 4 s, 2 harmonics) into tmp_path/out, which it
    returns, after checking that IPOPT lowered cond(W)."""
    out = tmp_path / "out"
    result = subprocess.run(SYMKIN_CLI + ["excite", str(MODELS_DIR / f"{name}.yaml"), "--max-velocity", "3",
                                          "--max-acceleration", "20", "--period", "4", "--harmonics", "2",
                                          "--max-iterations", str(iterations), "--no-figure", "-o", str(out)],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    record = json.loads((out / "excitation.json").read_text())
    assert record["condition"] < record["condition_start"]
    return out


@pytest.mark.parametrize("derived", ["delta"], indirect=True)
def test_symkin_excite_designs_a_run_the_deltas_legs_follow(derived, tmp_path):
    """symkin excite on the DELTA: its base regressor is taken at the poses fk(q) of the trajectory (CasADi), whose
    legs must assemble (fk's margin >= 0) within the actuators' limits; a few IPOPT iterations lower cond(W)."""
    name, found, generated = derived
    out = _excite("delta", 15, tmp_path)
    table = np.loadtxt(out / "excitation.csv", delimiter=",", skiprows=1)
    q = table[:, 1:4]
    lower, upper = np.array(generated.info.coordinates[0].limits)
    assert np.all((q >= lower) & (q <= upper)), (q.min(), q.max(), lower, upper)
    assert np.all(generated.fk(q).margin >= 0)


@pytest.mark.parametrize("derived", ["delta_wrist"], indirect=True)
def test_symkin_excite_moves_a_hybrid_devices_legs_and_wrist(derived, tmp_path):
    """symkin excite on the DELTA carrying a wrist: a series per device joint (the legs' actuators, then the wrist's
    joints, as a run records them), each within its limits, the legs assembled (fk's margin >= 0); the base
    regressor stacked over the run's states has full column rank (every base parameter excited), and IPOPT lowers
    cond(W)."""
    name, found, generated = derived
    out = _excite("delta_wrist", 10, tmp_path)
    joints = [c.name for c in generated.info.device_coordinates]
    with open(out / "excitation.csv") as table_file:
        header = table_file.readline().strip().split(",")
    assert header == ["t"] + [f"{g}_{n}" for g in ("q", "qd", "qdd") for n in joints]
    table = np.loadtxt(out / "excitation.csv", delimiter=",", skiprows=1)
    q, qd, qdd = (table[:, 1 + k * 6:1 + (k + 1) * 6] for k in range(3))
    limits = np.array([c.limits for c in generated.info.device_coordinates])
    assert np.all(q >= limits[:, 0])
    assert np.all(q <= limits[:, 1])
    pose = generated.fk(q[:, :3])
    assert np.all(pose.margin >= 0)
    Y_b = generated.base_regressor(q[:, :3], pose.position, q[:, 3:], qd[:, :3], qd[:, 3:], qdd[:, :3], qdd[:, 3:]).Y_b
    W = Y_b.reshape(-1, Y_b.shape[-1])
    singular = np.linalg.svd(W / np.linalg.norm(W, axis=0), compute_uv=False)
    assert singular[-1] > 1e3 * EPS * singular[0] * np.sqrt(W.shape[0])   # far above rounding: rank len(pi_b)


@pytest.mark.parametrize("derived", ["delta_wrist"], indirect=True)
def test_symkin_identify_gives_back_a_hybrid_devices_base_parameters(derived, tmp_path):
    """A run of the DELTA carrying its wrist simulated with its own regressor (tau = Y pi at p = fk(q), the legs
    swinging about home and the wrist's joints within their limits, noise on the efforts): `symkin identify
    models/delta_wrist.yaml --method consistent` recovers the 43 base parameters within 5 standard deviations
    (weighted least squares), and writes an identified.yaml with the legs' bodies and the wrist's links (the
    consistent estimate among what the file holds) that the model reader takes."""
    name, found, generated = derived
    t, q, qd, qdd = excitation(6, seed=4)
    home = generated.ik(np.array(generated.info.home)).joints
    scale = np.array([0.25, 0.25, 0.25, 1.0, 1.0, 1.0])                  # the wrist's joints swing wider
    centre = np.concatenate([home, np.zeros(3)])
    q, qd, qdd = centre + scale * (q - 0.7), scale * qd, scale * qdd      # excitation() swings about 0.7 rad
    p = generated.fk(q[:, :3]).position
    Y, pi = generated.regressor(q[:, :3], p, q[:, 3:], qd[:, :3], qd[:, 3:], qdd[:, :3], qdd[:, 3:])
    tau = np.einsum("kij,kj->ki", Y, pi) + np.random.default_rng(4).normal(0, NOISE, q.shape)
    run = write_run(tmp_path / "run.csv", [c.name for c in generated.info.device_coordinates], t, q, tau, qd, qdd)
    out, _ = _identify("delta_wrist", run, found, tmp_path)
    model = load_model(out / "identified.yaml")
    assert {b.link for b in model.parallel.wrist.bodies} == {"fork1", "fork2", "handle"}
    assert "with the bodies of platform, actuated_link, rod, fork1, fork2, handle" in (out / "summary.txt").read_text()


@pytest.mark.parametrize("derived", ["stewart"], indirect=True)
def test_the_stewart_platform_is_excited_in_its_pose_and_identified_from_its_struts(derived, tmp_path):
    """The Stewart platform has no closed-form fk.  symkin excite moves its pose in Fourier series (excitation.json)
    with the struts following q = ik(p) (excitation.csv: their q, qd, qdd within the strokes, which ik of the
    series reproduces), and the stacked base regressor along the run has full column rank.  A run along it with
    the efforts of its own regressor (tau = Y pi; Y pi = inverse_dynamics is tests/parallel/test_parallel_regressor.py's)
    and noise: symkin identify, given the struts alone, solves each pose by Newton's method on the leg equations
    and recovers the 34 base parameters within 5 standard deviations; identified.yaml is read back."""
    name, found, generated = derived
    out = _excite("stewart", 5, tmp_path)
    record = json.loads((out / "excitation.json").read_text())
    assert record["series_of"].startswith("task coordinates")
    table = np.loadtxt(out / "excitation.csv", delimiter=",", skiprows=1)
    t, q, qd, qdd = table[:, 0], table[:, 1:7], table[:, 7:13], table[:, 13:19]
    lower, upper = np.array(generated.info.coordinates[0].limits)
    assert np.all((q >= lower) & (q <= upper)), (q.min(), q.max(), lower, upper)
    omega = 2 * np.pi / record["period"] * np.arange(1, record["harmonics"] + 1)
    p = np.column_stack([record["offsets"][c] + np.sin(np.outer(t, omega)) @ (np.array(record["a"][c]) / omega)
                         - np.cos(np.outer(t, omega)) @ (np.array(record["b"][c]) / omega)
                         for c in generated.info.task_space])          # the series of the module docstring
    np.testing.assert_allclose(generated.ik(p).joints, q, rtol=0, atol=1e3 * EPS)
    Y, pi = generated.regressor(q, p, qd, qdd)
    W = generated.base_regressor(q, p, qd, qdd).Y_b.reshape(-1, len(found.base))
    singular = np.linalg.svd(W / np.linalg.norm(W, axis=0), compute_uv=False)
    assert singular[-1] > 1e3 * EPS * singular[0] * np.sqrt(W.shape[0])   # far above rounding: rank len(pi_b)
    tau = np.einsum("kij,kj->ki", Y, pi) + np.random.default_rng(5).normal(0, NOISE, q.shape)
    run = write_run(tmp_path / "run.csv", generated.info.coordinate_names, t, q, tau, qd, qdd)
    identified, _ = _identify("stewart", run, found, tmp_path)
    assert load_model(identified / "identified.yaml").parallel.bodies is not None


@pytest.mark.parametrize("derived", ["delta_wrist"], indirect=True)
def test_a_hybrid_devices_run_is_its_legs_then_its_wrist(derived):
    """symkin identify's view of a hybrid device (analysis.device_regressors): the run's coordinates are the legs'
    actuators then the wrist's joints, each sample's pose fk(q): the same base regressor as given the assembled
    pose; a sample where the legs cannot assemble (rods too short for the arms' spread) is refused with its row."""
    from symkin.identification.device_regressors import DeviceRegressors
    from symkin.identification.estimation import DataError

    name, found, generated = derived
    q, p, qw, qd, qwd, qdd, qwdd = _inputs(generated, name, 16, 63)
    device = DeviceRegressors(generated, "run.csv")
    assert device.info.coordinate_names == ("theta1", "theta2", "theta3", "psi1", "psi2", "psi3")
    Y_b = device.base_regressor(np.hstack([q, qw]), np.hstack([qd, qwd]), np.hstack([qdd, qwdd])).Y_b
    given = generated.base_regressor(q, p, qw, qd, qwd, qdd, qwdd).Y_b   # p from ik, fk's within rounding
    np.testing.assert_array_less(np.abs(Y_b - given), np.broadcast_to(
        DYNAMICS * np.abs(given).max(axis=-1, keepdims=True) + TINY, given.shape))
    short = DeviceRegressors(generated.bind(b=0.03), "run.csv")
    with pytest.raises(DataError, match=r"run.csv: sample 1 \(row 2\): the legs do not assemble at q = "):
        short.pose(np.hstack([q, qw]))


@pytest.mark.parametrize("derived", ["delta"], indirect=True)
def test_a_parts_poses_are_computed_once_for_all_its_regressors(derived):
    """symkin identify passes one part of a run to the base regressor and the regressor: fk runs once for it (also
    for a copy of it), and again for other joint values."""
    from symkin.identification.device_regressors import DeviceRegressors

    name, found, generated = derived
    solved = []

    class CountingFk:
        info = generated.info

        def __getattr__(self, attribute):
            return getattr(generated, attribute)

        def fk(self, q):
            solved.append(len(q))
            return generated.fk(q)

    q, p, qd, qdd = _inputs(generated, name, 8, 5)
    device = DeviceRegressors(CountingFk(), "run.csv")
    first = device.base_regressor(q, qd, qdd).Y_b
    device.regressor(q, qd, qdd)
    assert solved == [8]
    np.testing.assert_array_equal(device.base_regressor(q.copy(), qd, qdd).Y_b, first)
    assert solved == [8]
    device.base_regressor(q + 1e-3, qd, qdd)
    assert solved == [8, 8]


@pytest.mark.parametrize("derived", ["agile_eye"], indirect=True)
def test_the_agile_eyes_closure_regroups_what_its_formula_keeps_apart(derived):
    """The Agile Eye's regressor has 31 columns independent for every (q, p), but on the assembled mechanism only 28:
    the elimination at states on the closure (each leg's actuator solved from the drawn orientation) finds the
    three that the closure adds; the distal links' inertia regroups with the rods' (their ends ride on them)."""
    name, found, generated = derived
    assert len(found.base) == 28
    assert "distal_link.IyzR = distal_link.Iyz + 1/2 rod.dI" in found.equations()


def test_a_parallel_model_without_bodies_has_no_regressor_and_says_what_to_add():
    """The pantograph without its bodies section: the regressor (and so the base parameters) is refused with the
    section to add, not derived as zero columns."""
    text = (MODELS_DIR / "pantograph.yaml").read_text()
    start = text.index("\nbodies:\n")
    bodiless = text[:start + 1] + text[text.index("\n\n", start) + 2:]
    model = model_from_text(bodiless, file="pantograph.yaml")
    assert model.parallel.bodies is None
    for quantity in ("regressor", "base_parameters"):
        with pytest.raises(DerivationError, match="model 'pantograph' declares no bodies, so it has no regressor; "
                                                  "add a 'bodies:' section"):
            Derivation(model)[quantity]


@pytest.mark.parametrize("derived", ["stewart"], indirect=True)
def test_the_stewart_platforms_regrouping_is_its_mechanics(derived):
    """The struts' platform ends (rod.mB) are six point masses fixed on the platform at the radius r_p, 3-fold
    symmetric: they add 6 rod.mB to its mass, nothing to its first moment or products of inertia, and
    6 r_p^2 rod.mB about its axis, 3 r_p^2 rod.mB about each axis in its plane (sum of sin^2 over the six angles: 3);
    their base ends (rod.mC) sit on the fixed U joints and leave no column.  The formula's J_x^-T is rational
    (square-root-free Gram-Schmidt), so only the legs' closures take square roots over the prime field."""
    name, found, generated = derived
    assert len(found.base) == 34
    assert "rod.mC" not in found.base_names
    assert found.equations()[:10] == (
        "platform.mR = platform.m + 6 rod.mB", "platform.mx = platform.mx", "platform.my = platform.my",
        "platform.mz = platform.mz", "platform.IxxR = platform.Ixx + 3*r_p**2 rod.mB", "platform.Ixy = platform.Ixy",
        "platform.IyyR = platform.Iyy + 3*r_p**2 rod.mB", "platform.Ixz = platform.Ixz",
        "platform.Iyz = platform.Iyz", "platform.IzzR = platform.Izz + 6*r_p**2 rod.mB")
    assert found.geometry == ("r_p",)
    moved = {"r_p": 0.08}
    inputs = _inputs(generated, name, 8, 63, **moved)
    full, base = generated.regressor(*inputs, **moved), generated.base_regressor(*inputs, **moved)
    K = found.evaluate(moved)
    scale = np.abs(base.Y_b) @ np.abs(K) + np.abs(full.Y).max(axis=-1, keepdims=True)  # as in the test above
    np.testing.assert_array_less(np.abs(base.Y_b @ K - full.Y), DYNAMICS * scale + TINY)
