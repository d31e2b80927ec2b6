"""Base parameters of legs without the distance form (issue 33): the dual SCARA of docs/model-format.md, its points
on the closure over a prime field found by elimination (symkin/parallel/closure_points.py), its regressor's base
parameters exact with the geometry symbolic (symkin/parallel/closure_base.py).

References: a planted point of a planar 2R leg (both elbow branches found); the count against the numerical rank
of Y = W^T Y_z stacked over states assembled in floating point; Y = Y_b K and tau = Y_b pi_b on the generated
code at assembled states (Gauss-Newton of the runtime, not the prime field); K with the geometry symbolic against
a second elimination with the geometry written into the file as numbers.
"""

from __future__ import annotations

import json
import random
import re
import subprocess

import numpy as np
import pytest
import sympy

from conftest import SYMKIN_CLI, shared_derivation
from identification_runs import write_run
from sample_models import dual_scara_dynamics_text
from symkin import load, pipeline
from symkin.model import model_from_text
from symkin.parallel.closure_base import assembled_rank
from symkin.parallel.closure_points import LegSystem, leg_point
from symkin.parallel.prime_field import NoPoint, PrimeField
from symkin.runtime.closure_dynamics import (actuated_dynamics, closure_energy_regressor, closure_inverse_dynamics,
                                             closure_regressor)
from symkin.runtime.parallel import solve_closure
from symkin.mechanism.closure import ClosureAssembly
from tolerances import DYNAMICS, EPS, NEWTON

#: One worker for the module: its tests share the derivation of the model (shared_derivation) and its generation.
pytestmark = pytest.mark.xdist_group("dual_scara_base_parameters")

HOME = np.array([0.0, 0.3, 0.1, 0.0])
#: The geometry of the document's dual SCARA (d, l1, l2, e) written as numbers: the second elimination's model.
NUMBERS = {"d": sympy.Rational(3, 10), "l1": sympy.Rational(1, 4), "l2": sympy.Rational(1, 4),
           "e": sympy.Rational(1, 10)}


@pytest.fixture(scope="module")
def model():
    return model_from_text(dual_scara_dynamics_text(), file="dual_scara_dynamics.yaml")


@pytest.fixture(scope="module")
def found(model):
    return shared_derivation(model)["closure_base_parameters"]


@pytest.fixture(scope="module")
def generated_dir(model, tmp_path_factory):
    """The model derived with what symkin identify --method energy and symkin excite derive legs without the
    distance form with (numpy and CasADi)."""
    request = pipeline.resolve_request(model, "closure,closure_jacobians,closure_dynamics,closure_regressor,"
                                              "closure_base_regressor,closure_energy_regressor", "numpy,casadi",
                                       fixed="all", combine="none")
    generation = pipeline.generate(model, request, derivation=shared_derivation(model))
    return pipeline.write(generation, tmp_path_factory.mktemp("dual-scara"))


@pytest.fixture(scope="module")
def generated(generated_dir):
    return load(generated_dir)


def test_a_planted_point_of_a_planar_2r_leg_is_found_on_either_branch():
    """l1 (C1, S1) + l2 (C1 C2 - S1 S2, S1 C2 + C1 S2) = (X, Y) with (X, Y) from joint angles drawn on the unit
    circle mod P: every draw is solved (the point exists), each solution satisfies the equations and the circles,
    and both elbow branches come out (S2 and -S2)."""
    rng = random.Random(3)
    field = PrimeField.embeddings(rng, [])[0]
    P = field.P
    # generators (C1, S1, C2, S2); x-row: l1 C1 + l2 C1 C2 - l2 S1 S2 - X, y-row: l1 S1 + l2 S1 C2 + l2 C1 S2 - Y
    monomials = (((1, 0, 0, 0), (1, 0, 1, 0), (0, 1, 0, 1), (0, 0, 0, 0)),
                 ((0, 1, 0, 0), (0, 1, 1, 0), (1, 0, 0, 1), (0, 0, 0, 0)))
    leg = LegSystem((sympy.Symbol("a1"), sympy.Symbol("a2")), (True, True), monomials, (0, 4, 8), 2)
    branches = set()
    for _ in range(40):
        (C1, S1), (C2, S2) = field.circle_point(rng), field.circle_point(rng)
        l1, l2 = field.residue(rng), field.residue(rng)
        X = (l1 * C1 + l2 * (C1 * C2 - S1 * S2)) % P
        Y = (l1 * S1 + l2 * (S1 * C2 + C1 * S2)) % P
        c1, s1, c2, s2 = leg_point(leg, [l1, l2, -l2 % P, -X % P, l1, l2, l2, -Y % P], P, rng, "planted")
        assert (l1 * c1 + l2 * (c1 * c2 - s1 * s2) - X) % P == 0
        assert (l1 * s1 + l2 * (s1 * c2 + c1 * s2) - Y) % P == 0
        assert (c1 * c1 + s1 * s1 - 1) % P == 0
        assert (c2 * c2 + s2 * s2 - 1) % P == 0
        assert c2 == C2  # the elbow's cosine is fixed by |(X, Y)|, its sine by the branch
        assert s2 in (S2, P - S2)
        branches.add(s2 == S2)
    assert branches == {True, False}
    with pytest.raises(NoPoint):  # beyond reach: |(X, Y)| = l1 + l2 + 1 has no point over the reals' image either
        leg_point(leg, [1, 1, P - 1, P - 3, 1, 1, 1, 0], P, rng, "planted")


def test_the_dual_scara_has_24_base_parameters_with_the_geometry_symbolic(model, found):
    """96 columns (8 bodies x 10, 4 drives x 4) give 24 on the closure: the count equals the numerical rank of
    Y = W^T Y_z stacked over states assembled in floating point, and K depends on the link lengths and the bar's
    half length e (rationally: the bar and the hand form one rigid body, its inertia regroups with 1/e), not on
    the legs' spacing d."""
    assert len(found.base) == 24
    assert assembled_rank(shared_derivation(model)) == 24
    assert set(found.geometry) == {"e", "l1", "l2"}
    equations = found.equations()
    assert "elbow1.myR = elbow1.my + lift1.my" in equations
    assert "hand2.mxR = hand2.mx + 1/(2*e) hand2.Izz - e/2 platform.m + 1/(2*e) platform.Izz" in equations
    assert any(re.match(r"lift1\.mR = lift1\.m \+ slide2\.m \+ hand2\.m \+ platform\.m", e) for e in equations)


def test_the_regrouping_with_the_geometry_symbolic_is_the_one_at_the_geometrys_numbers(found):
    """The elimination on the model with d, l1, l2, e written as numbers gives K at those numbers, entry for entry
    (an independent run: other primes' residues, no interpolation in the geometry)."""
    numeric = model_from_text(_numbers_written_in(dual_scara_dynamics_text()), file="dual_scara_numbers.yaml")
    folded = shared_derivation(numeric)["closure_base_parameters"]
    assert folded.base == found.base
    assert folded.geometry == ()
    values = {sympy.Symbol(k): v for k, v in NUMBERS.items()}
    for row_symbolic, row_numbers in zip(found.combinations, folded.combinations):
        assert [k.xreplace(values) for k in row_symbolic] == list(row_numbers)


def _numbers_written_in(text: str) -> str:
    """The model with its geometry parameters' values in place of their names in the leg origins and attachments."""
    head, legs = text.split("\nparallel:\n")
    for name, value in NUMBERS.items():
        legs = re.sub(rf"(?<![\w.]){name}(?=[/,\]])", str(value), legs)
    assert not re.search(r"xyz: \[[^\]]*[a-z]", legs.split("\ngravity:")[0]), legs
    return head + "\nparallel:\n" + legs


def test_the_generated_base_regressor_gives_the_efforts_and_every_column(model, found, generated):
    """At states assembled by the runtime's Gauss-Newton: W^T Y_z,b pi_b equals closure_inverse_dynamics, and every
    column of the full Y equals Y_b K (K at the model's geometry); Y_b stacked has full column rank; the energy
    regressor at zd = W qd gives the mechanism's kinetic plus potential energy."""
    K = found.evaluate({p.name: float(p.value) for p in model.parameters})
    rng = np.random.default_rng(5)
    ik = solve_closure(generated, [1.0, 0.1, 1.6, 0.0], np.zeros(4), HOME, unknowns=("q", "s"), max_step=0.2)
    stacked = []
    while len(stacked) < 8:
        q = ik.solution["q"] + rng.uniform(-0.03, 0.03, 4)
        fk = solve_closure(generated, q, ik.solution["s"], HOME, unknowns=("p", "s"))
        if not fk.all_converged:
            continue
        state = (q, fk.solution["s"], fk.solution["p"], rng.normal(size=4), rng.normal(size=4))
        Y, pi = closure_regressor(generated, *state)
        Y_b, pi_b = closure_regressor(generated, *state, base=True)
        tau = closure_inverse_dynamics(generated, *state)
        np.testing.assert_array_less(np.abs(Y_b @ pi_b - tau), DYNAMICS * np.abs(Y_b * pi_b).sum(axis=-1))
        np.testing.assert_allclose(Y_b @ K, Y, rtol=0, atol=DYNAMICS * np.abs(Y_b).sum(axis=-1).max()
                                   * np.abs(K).max())
        np.testing.assert_allclose(K @ pi, pi_b, rtol=DYNAMICS)
        Y_e, pi_e = closure_energy_regressor(generated, *state[:4])
        terms = actuated_dynamics(generated, *state[:4])
        np.testing.assert_array_equal(pi_e, pi)
        assert abs(Y_e @ pi - (terms.kinetic + terms.potential)) <= DYNAMICS * np.abs(Y_e * pi).sum()
        stacked.append(Y_b)
    singular = np.linalg.svd(np.concatenate(stacked) / np.linalg.norm(np.concatenate(stacked), axis=0),
                             compute_uv=False)
    assert singular.min() > 1e-6 * singular.max()


#: Noise on the efforts (N m, N): large against rounding and the energy balance's quadrature, small against the
#: lift's 4.4 N and the arms' torques (~0.1 N m).
NOISE = 1e-3
#: The excitation's range per actuator about the home assembly (rad, m, rad, rad): limits given to symkin excite.
SWING = np.array([0.3, 0.05, 0.3, 0.3])


def test_an_excitation_of_the_actuators_identifies_the_dual_scara(model, generated, generated_dir, tmp_path):
    """symkin excite moves the four actuators in Fourier series within limits about the home assembly, each sample
    assembled by CasADi's rootfinder (the start's assembly its guess): cond(W S) falls by far, excitation.csv stays
    within the limits and the legs close along it.  A run along it, the efforts from the model's inverse dynamics
    (checked against Pinocchio in test_closure_dynamics.py) with noise, recorded on the actuators alone: symkin
    identify --method consistent, given the model file, continues each sample's assembly along the run, gives every
    one of the 24 base parameters within 5 of its standard deviations (weighted least squares) and writes an
    identified.yaml that the model reader takes back, every leg link's body replaced, its base parameters within
    one standard deviation of the estimate; --method energy on the generated directory (the energy balance over
    windows, without the accelerations) too."""
    names = generated.info.coordinate_names
    home = ClosureAssembly(generated).home
    limits = [f"--limit={name}={float(h - w)!r}:{float(h + w)!r}" for name, h, w in zip(names, home, SWING)]
    excited = tmp_path / "excite"
    result = subprocess.run(SYMKIN_CLI + ["excite", str(generated_dir), *limits, "--max-velocity", "1",
                                          "--max-acceleration", "10", "--period", "4", "--harmonics", "3",
                                          "--periods", "2", "--rate", "125", "--max-iterations", "30", "--no-figure",
                                          "-o", str(excited)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    record = json.loads((excited / "excitation.json").read_text())
    assert record["condition"] < record["condition_start"] / 10, record
    table = np.loadtxt(excited / "excitation.csv", delimiter=",", skiprows=1)
    t, q, qd, qdd = table[:, 0], table[:, 1:5], table[:, 5:9], table[:, 9:13]
    assert len(t) == 1000
    assert np.all(np.abs(q - home) <= SWING + 4 * EPS * np.abs(home))  # the limits, home -+ SWING, as rounded
    s, p = ClosureAssembly(generated)(q)
    assert np.all(np.isfinite(s))
    assert np.all(np.isfinite(p))
    tau = closure_inverse_dynamics(generated, q, s, p, qd, qdd) + np.random.default_rng(4).normal(0, NOISE, q.shape)
    run = write_run(tmp_path / "run.csv", names, t, q, tau, qd, qdd)
    model_file = tmp_path / "dual_scara.yaml"
    model_file.write_text(dual_scara_dynamics_text())
    out = tmp_path / "consistent"
    result = subprocess.run(SYMKIN_CLI + ["identify", str(model_file), str(run), "--method", "consistent",
                                          "--no-figure", "-o", str(out)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    record = json.loads((out / "estimate.json").read_text())
    assert len(record["parameters"]) == 24
    error = {row["name"]: abs(row["value"] - row["model"]) / row["std"] for row in record["parameters"]}
    assert max(error.values()) < 5, error
    identified = model_from_text((tmp_path / "consistent" / "identified.yaml").read_text(), file="identified.yaml")
    written = {body.link: body for body in identified.parallel.bodies.links}
    assert set(written) == {body.link for body in model.parallel.bodies.links}
    summary = (tmp_path / "consistent" / "summary.txt").read_text()
    within = re.search(r"its base parameters within ([0-9.e+-]+) standard deviations of the estimate's", summary)
    assert within, summary
    assert float(within.group(1)) < 1  # what the file holds is the estimate (one rotor for all actuators aside)
    energy = tmp_path / "energy"
    result = subprocess.run(SYMKIN_CLI + ["identify", str(generated_dir), str(run), "--method", "energy", "--no-figure",
                                          "-o", str(energy)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    record = json.loads((energy / "estimate.json").read_text())
    assert (record["method"], len(record["parameters"])) == ("energy", 24)
    error = {row["name"]: abs(row["value"] - row["model"]) / row["std"] for row in record["parameters"]}
    assert max(error.values()) < 5, error


def test_a_sample_where_the_legs_do_not_close_is_refused_with_its_row(generated):
    """symkin identify's view of legs without the distance form (analysis.device_regressors): each sample's assembly
    continued along the run; a sample the legs cannot reach (the planar leg stretched straight along +x puts the
    bar's left end 0.6 m from the lifting leg's axis, beyond its l1 + l2 = 0.5 m) is refused with its CSV row, the
    samples before it assembled."""
    from symkin.identification.device_regressors import DeviceRegressors
    from symkin.identification.estimation import DataError

    device = DeviceRegressors(generated, "run.csv")
    home = ClosureAssembly(generated).home
    q = home + np.outer(np.linspace(0.0, 0.02, 3), [1.0, 0.1, 1.0, 1.0])
    s, p = device.mechanism.assembly(q)
    assert device.info.functions["base_regressor"] is generated.info.functions["closure_base_regressor"]
    assert np.abs(generated.closure(q, s, p)).max() <= NEWTON  # scale: links of 0.25 m, angles < 1 rad
    wild = np.vstack([q, [q[-1, 0], q[-1, 1], 0.0, 0.0]])                  # phi2 = knee2 = 0
    with pytest.raises(DataError, match=r"run.csv: sample 4 \(row 5\): the legs do not assemble"):
        device.base_regressor(wild, np.zeros_like(wild), np.zeros_like(wild))
