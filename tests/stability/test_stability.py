"""Numerical stability: every generated quantity against mpmath at 50 digits (issue 7 acceptance)."""

from __future__ import annotations

import math
import subprocess

import numpy as np
import pytest
import sympy
from conftest import (EXAMPLE_MODELS, FOREIGN_ARITHMETIC, GENERATED_DIR, MODELS_DIR, SYMKIN_CLI, model_group,
                      shared_derivation, stability_run)
from tolerances import CLOSED_FORM, EPS, FORWARD_AT_SINGULARITIES

from symkin import load, pipeline
from symkin.derivation import Derivation, catalog, emitted_quantities, registry
from symkin.ir.inputs import coordinate_input
from symkin.ir.quantity import QuantityDef
from symkin.ir.spec import FunctionSpec, InputSpec, OutputSpec, make_function
from symkin.model import coordinates
from symkin.stability import BOUND, KAPPA_LIMIT, run_stability
from symkin.stability.harness import SOLVE_ULPS, allowed_error
from symkin.stability.ir_eval import compile_ir, flatten_outputs
from symkin.stability.reference import BallReference, normwise_error
from symkin.stability.states import parameter_values

def on_the_runs_worker(*names: str):
    """The tests of a model's run share one xdist worker (`make test` uses --dist loadgroup): the model's group
    (conftest.model_group), which tests/stability/test_stability_table.py's test of the model and the tests of its
    references join, so that each run and derivation is computed once and the models spread over the workers."""
    return [model_group(name) for name in names]


def each_model():
    """The example models as parameters, each on its run's worker (:func:`on_the_runs_worker`)."""
    return [pytest.param(name, marks=on_the_runs_worker(name)) for name in EXAMPLE_MODELS]

#: The runs on foreign arithmetic (`make test`'s second pass): fewer states, and not every quantity (below).
QUICK = dict(samples=12, scale_samples=3, float32_samples=6, steps=(1e-2, 1e-6, 1e-10))
#: Left out on foreign arithmetic. The Stewart platform's J = J_x^-1 J_q (a symbolic 6x6 inverse) takes a
#: minute to derive and lambdify for mpmath: that pass checks every other quantity (the first, all).
#: Its dynamics (large expressions at 50 digits) are checked at the bench's full defaults by
#: tests/stability/test_stability_table.py, and against Pinocchio by tests/parallel/test_parallel_dynamics.py.
#: delta_wrist's platform is delta's, leg for leg: its kinematics are the same code (the golden files show it),
#: checked on delta; delta_wrist is checked where the wrist enters (the device functions and the dynamics).
#: The regressors of the UR10e (in both DH conventions) and of the PHANToM are checked at the full defaults in the
#: first pass; on foreign arithmetic the planar arm's stand for them, and the DELTA's, the pantograph's and the Agile
#: Eye's for the Stewart platform's (whose base parameters alone take 6 s to find). The derivatives and sensitivities
#: of the dynamics (a program's automatic differentiation, the same for every serial arm) are checked on foreign
#: arithmetic on the planar arm and the UR10e in its modified DH convention.
REGRESSORS = ("regressor", "base_regressor", "energy_regressor")
DERIVATIVES = ("inverse_dynamics_derivatives", "forward_dynamics_derivatives", "gravity_derivatives",
               "static_torque_derivatives", "fk_sensitivities", "jacobian_sensitivities",
               "inverse_dynamics_sensitivities")
LEFT_OUT = {"ur10e": REGRESSORS,
            "ur10e_classic": REGRESSORS + DERIVATIVES,
            "phantom_premium": REGRESSORS + DERIVATIVES,
            "stewart": ("jacobian", "mass_matrix", "coriolis_vector", "gravity_vector", "inverse_dynamics",
                        "forward_dynamics", "operational_space", "kinetic_energy", "potential_energy") + REGRESSORS
                       + ("closure_regressor", "closure_energy_regressor", "closure_base_regressor") + DERIVATIVES,
            "delta_wrist": ("fk", "jacobian", "ik", "inverse_jacobian", "singularities", "leg_points", "closure",
                            "closure_jacobians", "constraints", "constraint_jacobians", "tcp_force_map",
                            "tcp_force_map_inverse")}
CHECKED = {"serial": {"fk", "frames", "jacobian", "jacobian_geometric", "mass_matrix", "forward_dynamics"},
           "parallel": {"ik", "inverse_jacobian", "constraints", "constraint_jacobians", "closure", "singularities"}}


class _Runs(dict):
    """The runs by model name, each made when a test first asks for it (on the worker of its group)."""

    def __init__(self, make):
        super().__init__()
        self._make = make

    def __missing__(self, name):
        self[name] = run = self._make(name)
        return run


@pytest.fixture(scope="session")  # not "module": xdist may interleave other modules' tests, which would recompute it
def runs(models):
    """On native arithmetic the full runs the results table quotes (tests/stability/test_stability_table.py runs them on
    the same workers anyway: every quantity, the bench's defaults); on foreign arithmetic, where the table is not
    rerun, quick runs without :data:`LEFT_OUT`."""
    if not FOREIGN_ARITHMETIC:
        return _Runs(stability_run)

    def quick(name):
        quantities = [q for q in emitted_quantities(models[name].mechanism) if q not in LEFT_OUT.get(name, ())]
        return run_stability(models[name], quantities=quantities, derivation=shared_derivation(models[name]), **QUICK)

    return _Runs(quick)


@pytest.mark.parametrize("name", each_model())
def test_error_below_1e_13_where_kappa_below_1e3(runs, models, name):
    run = runs[name]
    passed, worst = run.acceptance()
    assert passed, (f"{name}: an error above max({BOUND:g}, {SOLVE_ULPS:g} kappa eps) where kappa < {KAPPA_LIMIT}: "
                    f"{[r for r in run.records if r.family != 'float32' and r.kappa < KAPPA_LIMIT and r.error > allowed_error(r.kappa)]}")
    well = [r for r in run.records if r.family != "float32" and r.kappa < KAPPA_LIMIT]
    assert len(well) >= 20
    families = {r.family for r in run.records}
    assert families == {"random", "singular", "scale", "float32"}
    assert {r.parameter for r in run.select("scale")} == {1e-3, 1e-2, 1e-1, 1.0, 1e1, 1e2, 1e3}
    # every quantity the model can derive is checked, nothing produced a non-finite value where a double
    # can hold an answer (kappa eps < 1: at a Stewart platform's interior singularity, 1e-10 away, its
    # actuator-side mass matrix has kappa ~ 1e19 and its LDL^T pivots round to zero)
    assert set(run.quantities) >= CHECKED[models[name].mechanism] - set(LEFT_OUT.get(name, ()))
    assert all(math.isfinite(r.error) for r in run.records if r.kappa * EPS < 1)


def _kappas_along(run, path):
    return [r.kappa for r in run.select("singular") if r.label == path.label]


@pytest.mark.parametrize("name", [pytest.param("planar_2r", marks=on_the_runs_worker("planar_2r"))])
def test_the_planar_arms_singular_paths_are_found_generically(runs, name):
    assert {p.label for p in runs[name].paths} == {"theta2 -> 0", "theta2 -> -3.14159"}


@pytest.mark.parametrize("name", [pytest.param("ur10e", marks=on_the_runs_worker("ur10e"))])
def test_the_ur10es_singular_paths_are_found_generically(runs, name):
    ur = {p.label for p in runs[name].paths}
    assert {"q5 -> 0", "q3 -> 0"} <= ur
    for path in runs[name].paths:
        kappas = _kappas_along(runs[name], path)
        assert max(kappas) > 1e9
        assert min(kappas) < 1e4


@pytest.mark.parametrize("name", [pytest.param("stewart", marks=on_the_runs_worker("stewart"))])
def test_the_stewart_platforms_singular_paths_are_found_generically(runs, name):
    # Stewart-Gough: interior singular poses (kappa ~ 1/t) in position and in every orientation angle
    stewart = runs[name]
    assert {p.name for p in stewart.paths} >= {"roll", "pitch", "yaw"}
    for path in stewart.paths:
        kappas = [k for k in _kappas_along(stewart, path) if math.isfinite(k)]
        assert max(kappas) > 1e8
        assert min(kappas) < 1e5


@pytest.mark.parametrize("name", [pytest.param("delta", marks=on_the_runs_worker("delta"))])
def test_delta_paths_end_in_its_singularities_and_on_its_workspace_boundary(runs, models, name):
    """DELTA: every path the sweep finds ends where det J_q = 0 (a leg stretched or folded: the
    IK's two knee branches merge, the workspace boundary - the IK margin vanishes there and
    just beyond it the mechanism does not assemble) or where det J_x = 0 (a parallel singularity
    inside the workspace); kappa grows without bound along each path."""
    delta = runs[name]
    loaded = load(GENERATED_DIR / name)
    home = np.array([0.0, 0.0, -0.15])
    typical = loaded.singularities(loaded.ik(home).joints, home)
    boundaries = 0
    for path in delta.paths:
        kappas = _kappas_along(delta, path)
        assert max(kappas) > 1e4
        assert min(kappas) < 1e3
        end, beyond = (path.states(np.array([t])) for t in (0.0, -1e-6))
        dets = loaded.singularities(end["q"][0], end["p"][0])
        on_boundary = abs(dets.det_Jq) < 1e-6 * abs(typical.det_Jq)
        assert on_boundary or abs(dets.det_Jx) < 1e-6 * abs(typical.det_Jx), path.label
        if on_boundary:
            boundaries += 1
            assert np.min(loaded.ik(end["p"][0]).margin) < 1e-12
            assert np.isnan(beyond["q"]).any()
    assert boundaries >= 2


@pytest.mark.parametrize("name", [pytest.param("ur10e", marks=on_the_runs_worker("ur10e"))])
def test_forward_quantities_stay_accurate_into_the_ur_singularities(runs, name):
    """No division in the UR's kinematics and dynamics: even at kappa = 1e10 the code is accurate to
    rounding (quantities that invert J, the TCP force and operational space, are excluded)."""
    singular = [r for r in runs[name].select("singular") if registry("serial")[r.quantity].solves_with is None]
    assert max(r.kappa for r in singular) > 1e9
    worst = max(singular, key=lambda r: r.error)
    assert worst.error <= FORWARD_AT_SINGULARITIES, f"bound {FORWARD_AT_SINGULARITIES:.3g} exceeded by {worst}"


@pytest.mark.parametrize("name", [pytest.param("planar_2r", marks=on_the_runs_worker("planar_2r"))])
def test_folded_planar_arm_error_grows_with_kappa_as_its_conditioning_allows(runs, name):
    """theta2 -> pi with l1 = l2 puts the TCP at the base: x = l1 c1 + l2 c12 cancels, and the
    task coordinates' relative error grows like kappa * eps - never beyond it."""
    rs = [r for r in runs[name].select("singular", "task_coordinates") if r.label == "theta2 -> -3.14159"]
    assert max(r.error for r in rs) > 1e-10
    assert all(r.error <= 16 * np.finfo(float).eps * r.kappa for r in rs)


@pytest.mark.parametrize("name", each_model())
def test_length_scales_and_float32(runs, name):
    eps = float(np.finfo(float).eps)
    run = runs[name]
    for r in run.select("scale"):
        # Scaling lengths but not the published inertias makes M ill-conditioned: forward
        # dynamics then meets the bound only where its own kappa = cond(M) is moderate,
        # and stays within a small multiple of kappa * eps everywhere (backward stable).
        assert r.error < BOUND or r.kappa >= KAPPA_LIMIT, r
        assert r.error <= 64 * eps * max(r.kappa, 1.0), r
    errors = [r.error for r in run.select("float32")]
    eps32 = float(np.finfo(np.float32).eps)
    assert max(errors) < 50 * eps32
    assert max(errors) > 1e-3 * eps32  # really computed in single precision


def test_ir_evaluator_in_float64_is_bit_identical_to_the_generated_module(models, tmp_path):
    model = models["ur10e"]
    generation = pipeline.generate(model, pipeline.Request(("fk", "frames", "jacobian"), (), ("numpy",)))
    loaded = load(pipeline.write(generation, tmp_path))
    rng = np.random.default_rng(0)
    q = rng.uniform(-np.pi, np.pi, (50, 6))
    params = parameter_values(model)
    for f in generation.functions:
        used = {i.name: params[i.name] for i in f.spec.parameter_inputs}
        ours = compile_ir(f, np.float64)({"q": q}, used)
        theirs = flatten_outputs(getattr(loaded, f.name)(q, **used), [o.shape for o in f.spec.outputs])
        np.testing.assert_array_equal(ours, theirs)
        assert compile_ir(f, np.float32)({"q": q}, used).dtype == np.float32


def test_reference_and_error_measure():
    x = sympy.Symbol("x", real=True)
    spec = FunctionSpec("f", "f", "f", (InputSpec("q", "vector", (x,), ("x",), ("m",), "x"),),
                        (OutputSpec("y", sympy.ImmutableMatrix([[1 - sympy.cos(x), x]]), "y"),))
    reference = BallReference(spec)
    hi, lo = reference({"q": np.array([1e-8])}, {})
    # 1 - cos(x) = x^2/2 - x^4/24 + ...: 5e-17 to 4e-33 relative, the reference's 50 digits keep it
    # to its last bit; one rounding of the hi part: EPS/2.
    assert hi[0] == pytest.approx(5e-17, rel=EPS)
    assert hi[1] == 1e-8
    naive = np.array([1 - np.cos(1e-8), 1e-8])  # 1 - cos cancels to 0: 100 % wrong in that entry
    assert normwise_error(naive, hi, lo) == pytest.approx(5e-9, rel=1e-6)
    assert normwise_error(np.array([5e-17, 1e-8]), hi, lo) < EPS  # exact up to the rounding of 5e-17
    assert normwise_error(np.array([np.nan, 1e-8]), hi, lo) == math.inf


def test_the_reference_squares_a_value_that_is_zero_only_in_exact_arithmetic():
    """sin x cos x - sin(2 x)/2 at x = 0.5 is a ball centred on 0 (a cancellation sympy does not see): arb's power
    of it was indeterminate (NaN), a product is not; integer powers of either sign are products (and their
    reciprocals)."""
    x = sympy.Symbol("x", real=True)
    vanishing = sympy.sin(x) * sympy.cos(x) - sympy.sin(2 * x) / 2
    spec = FunctionSpec("f", "f", "f", (InputSpec("q", "vector", (x,), ("x",), ("m",), "x"),),
                        (OutputSpec("y", sympy.ImmutableMatrix([[sympy.sqrt(vanishing ** 2 + 1), vanishing ** 4,
                                                                 (x + 1.5) ** -3]]), "y"),))
    hi, lo = BallReference(spec)({"q": np.array([0.5])}, {})
    assert hi[0] == 1.0
    assert abs(hi[1]) <= EPS ** 8  # the 4th power of a ball of radius ~1e-77 around 0: below 1e-300
    assert hi[2] == 0.125


def test_new_quantities_are_covered_automatically(models, monkeypatch):
    """A quantity registered later (as dynamics will be, with q and qd inputs) joins the harness."""

    def velocity_of_tcp(d: Derivation):
        J = sympy.Matrix(d["jacobian_geometric_matrix"])[:3, :]
        qd = sympy.Matrix(coordinates.symbols(d.model, "qd"))
        return make_function(d.model, "tcp_velocity", "TCP velocity", "v = J_v qd",
                             [coordinate_input(d.model, "q"), coordinate_input(d.model, "qd")],
                             [OutputSpec("v", sympy.ImmutableMatrix(J * qd), "velocity", shape=(3,))])

    monkeypatch.setitem(catalog.QUANTITIES, "tcp_velocity",
                        {"serial": QuantityDef("tcp_velocity", "TCP velocity", velocity_of_tcp, True)})
    run = run_stability(models["planar_2r"], samples=4, scale_samples=1, float32_samples=2, steps=(1e-3,),
                        scales=(1.0,))
    assert "tcp_velocity" in run.quantities
    assert len(run.select(quantity="tcp_velocity")) > 4
    assert run.acceptance()[0]


@pytest.mark.parametrize("name", [pytest.param("ur10e", marks=on_the_runs_worker("ur10e"))])
def test_ik_wrist_formula_error_drop(runs, name):
    (wrist,) = runs[name].formulas
    at = {t: (a, b) for t, a, b in zip(wrist.steps, wrist.textbook, wrist.symkin)}
    textbook, ours = at[1e-6]
    # symkin's wrist angle is an atan2 of two computed components: a closed form (CLOSED_FORM);
    # the textbook acos loses half the digits near its singular value (sqrt(EPS) ~ 1.5e-8).
    assert textbook > 1e-12
    assert ours <= CLOSED_FORM
    assert np.all(wrist.symkin <= CLOSED_FORM), (wrist.steps, wrist.symkin, CLOSED_FORM)


@pytest.mark.parametrize("name", [pytest.param("planar_2r", marks=on_the_runs_worker("planar_2r"))])
def test_ik_elbow_formula_within_its_bound(runs, name):
    (elbow,) = runs[name].formulas
    finite = np.isfinite(elbow.bound)
    assert np.all(elbow.symkin[finite] <= 4 * elbow.bound[finite])


def test_bench_stability_cli(tmp_path):
    result = subprocess.run(SYMKIN_CLI + ["bench", "stability", str(MODELS_DIR / "planar_2r.yaml"), "--samples",
                                          "8", "--scale-samples", "2", "--float32-samples", "4", "--csv",
                                          str(tmp_path / "records.csv")],
                            capture_output=True, text=True, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    for heading in ("error vs kappa", "error vs length scale", "paths into singularities", "float32",
                    "closed-form IK near singularities", "acceptance: "):
        assert heading in result.stdout
    assert "PASS" in result.stdout
    assert (tmp_path / "out" / "figures" / "planar_2r-stability.png").stat().st_size > 10_000
    assert (tmp_path / "records.csv").read_text().startswith("model,quantity,family")
