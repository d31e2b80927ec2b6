"""The JAX backend (issue 66): pure, jit-compiled, float64 jax.numpy functions from the same intermediate
representation as numpy's, composing with jax.vmap, jax.jacfwd and jax.jit.

References: the numpy module of the same model and request at random states, to the backends' agreement bound
(tests/checks.py: 1e-12 relative, plus the rounding a solve amplifies); the generated Jacobian against jax.jacfwd
of the generated forward kinematics (the derivative of the chain's transform against the geometric Jacobian
derived symbolically: two programs); vmap against the batch.  The models: every example model's scene, every
function - the planar 2R's compiled by XLA (jit), the others' run op by op (jax.disable_jit: the same traced code
without XLA's compile, which takes about half a minute for the UR10e's scene alone on a CPU) - as generated/ holds
them (every scene emits the JAX module; tests/backends/test_golden.py checks its bytes).
"""

from __future__ import annotations

import contextlib
import faulthandler
import inspect
import re

import jax
import jax.numpy as jnp
import numpy as np
import pyarrow.parquet as pq
import pytest

from checks import agreement_bound
from conftest import EXAMPLE_MODELS, MODELS_DIR, ROOT, function_spec, random_inputs, relative_errors, worst_state
from symkin import derive, load, pipeline
from symkin.cli import main
from tolerances import DYNAMICS, EPS, KINEMATICS, svd

pytestmark = pytest.mark.xdist_group("jax")  # one worker imports JAX, after its other tests (conftest.LAST)
POINTS = 64
#: The models whose functions the equality test runs compiled (jax.jit, as a user calls them); the other example
#: models' run op by op (jax.disable_jit): XLA compiles the UR10e's scene in about half a minute on a CPU
#: (forward_dynamics_derivatives 13 s, operational_space 8 s: benchmarks/bench_jax.py --compile), the Stewart
#: platform's longer, more than the suite has for them; the code traced is the same.
COMPILED = ("planar_2r",)
#: The UR10e's functions that the jit, vmap and jacfwd test compiles.
UR10E_FUNCTIONS = ("fk", "jacobian", "mass_matrix", "coriolis_vector", "gravity_vector", "inverse_dynamics",
                   "combined")


@pytest.fixture(scope="module")
def jax_directory(generated_dir):
    """jax_directory(name): the example model's generated directory, whose scene emits the JAX module too."""
    return lambda name: generated_dir / name


@pytest.fixture(scope="module")
def jax_model(jax_directory):
    """jax_model(name): the example model's JAX code, loaded."""
    return lambda name: load(jax_directory(name), backend="jax")


def _tuple(result):
    return result if isinstance(result, tuple) else (result,)


@pytest.mark.parametrize("name", EXAMPLE_MODELS)
def test_every_function_equals_numpys(name, models, derivations, loaded, jax_model):
    model, reference, generated = models[name], loaded(name, "numpy"), jax_model(name)
    assert generated.functions == reference.functions
    rng = np.random.default_rng(66)
    for record in reference.manifest["functions"]:
        spec = function_spec(model, derivations[name], record)
        inputs = random_inputs(model, spec, rng, POINTS)
        want = _tuple(getattr(reference, record["name"])(*inputs))
        with contextlib.nullcontext() if name in COMPILED else jax.disable_jit():
            got = _tuple(getattr(generated, record["name"])(*inputs))
        assert type(got).__name__ == type(want).__name__
        bound = agreement_bound(model, spec, inputs, reference)
        for g, w, out in zip(got, want, record["outputs"]):
            assert g.dtype == jnp.float64
            g = np.asarray(g)
            assert g.shape == w.shape
            error = relative_errors(g, w)
            worst = int(np.argmax(error / bound))
            assert error[worst] < bound[worst], (record["name"], out["name"], f"error {error[worst]:.3g} > bound "
                                                 f"{bound[worst]:.3g}", worst_state(g, w, inputs))


def test_vmap_jit_and_jacfwd_compose_with_the_generated_functions(jax_model, loaded, models):
    """jax.vmap of a single configuration's call is the batched call (to DYNAMICS of M's largest entry: another
    compiled order); jax.jacfwd of fk's position column is the
    generated Jacobian's linear rows (to KINEMATICS times the arm's reach, 2 m); jax.jit of a composition runs."""
    arm, reference = jax_model("ur10e"), loaded("ur10e", "numpy")
    q = np.random.default_rng(3).uniform(-np.pi, np.pi, (16, 6))
    qd = np.random.default_rng(4).uniform(-1, 1, (16, 6))
    M = np.asarray(arm.mass_matrix(q))
    np.testing.assert_allclose(np.asarray(jax.vmap(arm.mass_matrix)(q)), M, rtol=0, atol=DYNAMICS * np.abs(M).max())
    position = jax.vmap(jax.jacfwd(lambda x: arm.fk(x)[:3, 3]))(q)
    np.testing.assert_allclose(np.asarray(position), reference.jacobian_geometric(q)[:, :3], rtol=0,
                               atol=KINEMATICS * 2.0)
    energy = jax.jit(lambda x, v: 0.5 * v @ arm.mass_matrix(x) @ v)
    np.testing.assert_allclose(np.asarray(jax.vmap(energy)(q, qd)), reference.kinetic_energy(q, qd), rtol=1e-12)


def test_the_module_is_float64_and_says_what_it_takes(jax_model):
    arm = jax_model("planar_2r")
    assert jax.config.jax_enable_x64
    assert arm.fk(np.zeros(2)).dtype == jnp.float64
    # x = l1 cos 0 + l2 cos 0 = 0.25 + 0.5: exact in binary
    assert float(arm.fk([0.0, 0.0], l1=0.25, l2=0.5)[0, 3]) == 0.75
    with pytest.raises(ValueError, match=r"^fk\(\): 'q' must have shape \(\.\.\., 2\), got \(3,\)"):
        arm.fk(np.zeros(3))


def _fused(values):
    raise AssertionError("fused")


def test_a_functions_outputs_are_computed_in_one_loop_on_a_cpu(jax_model):
    """XLA's CPU compiler gives each output entry a loop of its own, each recomputing the subexpressions the entries
    share: the UR10e's Jacobian compiled 177 sine and cosine evaluations for the 10 of its source so.  The module
    computes a function's entries in one loop (_in_one_loop: one variadic reduce): a few loops XLA splits off remain,
    so at most three times the source's; the values are exact (-0.0 + e = e), signed zeros, infinities and NaN
    included.  Op by op (jax.disable_jit) the entries are left as they are."""
    arm = jax_model("ur10e")
    source = inspect.getsource(arm.jacobian)
    written = len(re.findall(r"jax\.numpy\.(?:sin|cos)\(", source))
    compiled = jax.jit(arm.jacobian).lower(np.zeros((16, 6))).compile().as_text()
    assert 0 < len(re.findall(r"\b(?:sine|cosine)\(", compiled)) <= 3 * written
    module = arm.jacobian.__wrapped__.__globals__
    one_loop = module["_one_loop"]
    values = np.array([-0.0, 0.0, np.inf, -np.inf, np.nan, 1e-300, -1.5, np.finfo(float).max])
    assert np.asarray(jax.jit(one_loop)((values, -values))[1]).tobytes() == (-values).tobytes()
    # op by op (jit disabled) there is no loop to fuse: the reduce is neither compiled nor run
    module["_one_loop"] = _fused
    try:
        with jax.disable_jit():
            assert np.asarray(arm.jacobian(np.zeros(6))).shape == (6, 6)
        with pytest.raises(AssertionError, match="fused"):
            jax.jit(arm.jacobian)(np.ones(6))
    finally:
        module["_one_loop"] = one_loop


def test_the_analyses_take_the_jax_backend(jax_directory, generated_dir, capsys):
    """symkin gci and workspace evaluate the JAX code (the planar 2R's integrand reduced on the device) to the numbers
    of the numpy code: the same Sobol points, the same figures as printed; the GCI says where it ran."""
    site = f"; fused on JAX's {jax.default_backend()} device"
    for command in (["gci", "-n", "512", "--seed", "0"], ["workspace", "-n", "512", "--no-figure"]):
        printed = {}
        for backend, directory in (("jax", jax_directory("planar_2r")), ("numpy", generated_dir / "planar_2r")):
            assert main([command[0], str(directory), "--backend", backend, *command[1:]]) == 0
            printed[backend] = re.sub(r"[0-9.]+ (ms|s)\b", "(time)", capsys.readouterr().out)  # run times differ
        assert (site in printed["jax"]) == (command[0] == "gci")
        assert printed["jax"].replace(site, "") == printed["numpy"]


def _values_on_the_host(self, points):
    raise AssertionError("the device integrand's values came back to the host")


@pytest.mark.parametrize("name, options, methods", [
    ("planar_2r", {}, ("qmc", "mc", "grid")),
    ("ur10e", {"measure": "joint", "length": 0.5}, ("qmc", "mc", "grid")),
    ("delta", {}, ("qmc",)),
])
def test_the_global_index_is_reduced_on_the_device(name, options, methods, jax_model, loaded, monkeypatch):
    """gci of a model loaded with JAX takes the device's reductions (the integrand's values never come back: calling
    them fails here) and gives numpy's figures: the same points, the same arithmetic up to rounding (the SVD and the
    order of the sums): 1e-12 of the index, the error estimates to 1e-6.  The DELTA's working mode (fk assembles,
    ik(fk(q)) = q) is decided on the device: a third of its joint box lies outside it."""
    from symkin import analysis
    from symkin.analysis import device_integrand
    from symkin.integration.integrand import Integrand

    assert device_integrand.on_device(jax_model(name))
    for method in methods:
        want = analysis.gci(loaded(name, "numpy"), method=method, samples=2**10, seed=5, **options)
        with monkeypatch.context() as patch:
            patch.setattr(Integrand, "__call__", _values_on_the_host)
            got = analysis.gci(jax_model(name), method=method, samples=2**10, seed=5, **options)
        assert got.value.value == pytest.approx(want.value.value, rel=1e-12)
        assert got.value.error == pytest.approx(want.value.error, rel=1e-6)
        assert got.measure.value == pytest.approx(want.measure.value, rel=1e-12)
        assert got.description == f"{want.description}; fused on JAX's {jax.default_backend()} device"


def test_a_jax_model_on_the_host_says_so_and_why(jax_model):
    """--backend jax never falls back to the host silently: the planar 2R's manipulability (an index the device
    program does not compute) and the adaptive integrator (which refines on the values) run the JAX code point by
    point, and the result's description says so and why."""
    from symkin import analysis
    from symkin.numerics import conditioning

    model = jax_model("planar_2r")
    other_index = analysis.global_index(model, samples=2**8, seed=1, index=conditioning.manipulability)
    assert other_index.description.endswith("; the JAX code evaluated point by point, its values reduced on the host "
                                            "(the device program computes 1/kappa, not another index)")
    adaptive = analysis.gci(model, method="adaptive", samples=2**8, rtol=1e-2)
    assert adaptive.description.endswith("(the adaptive integrator refines on the values)")


@pytest.mark.parametrize("name", ["ur10e", "delta"])
def test_the_torque_peak_is_reduced_on_the_device(name, jax_model, loaded, monkeypatch):
    """symkin sweep's torque_peak (max over Sobol configurations of J_p's largest column norm) of a model loaded with
    JAX: reduced on the device - the host's Jacobians are never formed (calling them fails here) - and numpy's value to
    rounding (the same configurations, the DELTA's working mode decided there): a few eps times kappa(J) at the
    peak's configuration (the DELTA's J solves with J_x; at a = 0.12 m its peak lies near a singularity)."""
    from symkin import mechanism
    from symkin.design import sweep_metrics
    from symkin.mechanism import working_mode
    from symkin.numerics import sampling

    numpy_model = loaded(name, "numpy")
    box = mechanism.joint_limits(numpy_model)
    want = sweep_metrics.torque_peak(numpy_model, box[:, 0], box[:, 1], 4096, 3)
    q = sampling.sobol(box[:, 0], box[:, 1], 12, np.random.default_rng(3))  # torque_peak's configurations
    J, inside = working_mode.jacobian_in_working_mode(numpy_model, q)
    levers = np.linalg.norm(J[:, list(mechanism.position_rows(numpy_model)), :], axis=1).max(axis=1)
    peak = np.argmax(np.where(True if inside is None else inside, levers, -np.inf))
    assert levers[peak] == want
    with monkeypatch.context() as patch:
        patch.setattr(working_mode, "jacobian_in_working_mode", _values_on_the_host)
        got = sweep_metrics.torque_peak(jax_model(name), box[:, 0], box[:, 1], 4096, 3)
    assert got == pytest.approx(want, rel=16 * EPS * np.linalg.cond(J[peak]))


def _check_the_cartesian_values(models, inverse, box, points, **options):
    """The inverse runs on the device for the JAX model only, and there the Cartesian integrand's values at
    ``points`` are numpy's point by point: the same reachable set (the box holds points out of the workspace too),
    1/kappa to 1e-12.  Returns numpy's values."""
    from symkin.analysis import device_cartesian
    from symkin.analysis.global_indices import cartesian_integrand

    assert device_cartesian.cartesian_on_device(models["jax"], inverse["jax"])
    assert not device_cartesian.cartesian_on_device(models["numpy"], inverse["numpy"])
    want = cartesian_integrand(models["numpy"], inverse["numpy"], box, **options)(points)
    got = device_cartesian.device_cartesian_integrand(models["jax"], inverse["jax"], box, **options)(points)
    assert np.array_equal(got[:, 1], want[:, 1])
    assert 0 < want[:, 1].sum() < len(points)
    assert np.max(np.abs(got[:, 0] - want[:, 0])) <= 1e-12
    return want


def _check_the_cartesian_gci_and_grid(models, inverse, box, cell, monkeypatch, **options):
    """The Cartesian GCI and workspace measure on the device with the values never coming back (calling them fails
    here): numpy's to 1e-12; and symkin workspace's grid of 1/kappa at the reachable cell centres (side ``cell``),
    which takes the same program: numpy's."""
    from symkin import analysis
    from symkin.analysis import grids
    from symkin.integration.integrand import Integrand

    want = analysis.gci(models["numpy"], domain="cartesian", inverse=inverse["numpy"], samples=2**12, seed=4, **options)
    with monkeypatch.context() as patch:
        patch.setattr(Integrand, "__call__", _values_on_the_host)
        got = analysis.gci(models["jax"], domain="cartesian", inverse=inverse["jax"], samples=2**12, seed=4, **options)
    assert got.value.value == pytest.approx(want.value.value, rel=1e-12)
    assert got.measure.value == pytest.approx(want.measure.value, rel=1e-12)
    (occupied, on_host), (occupied_too, on_device) = (
        grids.index_grid(models[backend], inverse[backend], box, cell) for backend in ("numpy", "jax"))
    assert np.array_equal(occupied_too.occupied, occupied.occupied)
    np.testing.assert_allclose(on_device, on_host, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name, options", [("delta", {}), ("stewart", {"length": "auto"})])
def test_the_cartesian_integrand_runs_on_the_device(name, options, jax_model, loaded, monkeypatch):
    """The Cartesian domain on the device: the DELTA's working mode (fk(ik(p)) = p) and the Stewart platform's at its
    home orientation (det J^-1 keeps its sign; 1/kappa of the homogenized twist Jacobian diag(I, E) (J^-1)^-1)
    decided there, at the same points as numpy's: the same reachable set point by point, 1/kappa to 1e-12.  The
    DELTA's GCI and workspace volume with the values never coming back (calling them fails here): numpy's to 1e-12,
    and symkin workspace's grid of 1/kappa at the reachable cell centres numpy's.  An inverse with passive-joint
    limits stays on the host."""
    from dataclasses import replace

    from symkin.analysis import device_cartesian
    from symkin.analysis.inverse import inverse_kinematics_for
    from symkin.mechanism import reach

    models = {"numpy": reach.held_at(loaded(name, "numpy"), None), "jax": reach.held_at(jax_model(name), None)}
    inverse = {backend: inverse_kinematics_for(model) for backend, model in models.items()}
    assert not device_cartesian.cartesian_on_device(models["jax"], replace(inverse["jax"], passive_limits=object()))
    box = reach.bounding_box(models["numpy"])
    _check_the_cartesian_values(models, inverse, box, np.random.default_rng(2).uniform(*box, (2048, 3)), **options)
    if name != "delta":
        return  # a second program (the reduction) compiled for one model is enough
    _check_the_cartesian_gci_and_grid(models, inverse, box, 0.04, monkeypatch, **options)


def test_the_orientation_integrand_runs_on_the_device(jax_model, loaded, monkeypatch):
    """The Agile Eye's orientation workspace on the device (the roll-pitch-yaw chart of SO(3), the invariant measure
    |cos pitch|): at random orientations of the whole chart the same reachable set as numpy's point by point, the
    weights and 1/kappa of J^-1 E^-1 to rounding (E^-1 by cofactors, numpy's by LAPACK: a few eps times kappa(E) =
    O(1 / |cos pitch|)); the GCI and the measure with the values never coming back (calling them fails here): numpy's
    to 1e-12, and a sweep's design (symkin sweep --backend jax) the same, its kappa extremes numpy's."""
    from symkin.analysis import device_cartesian, orientations
    from symkin.design.sweep_metrics import evaluate_design
    from symkin.design.sweeps import SweepAxis, SweepDefinition
    from symkin.integration.integrand import Integrand

    numpy_model, model = loaded("agile_eye", "numpy"), jax_model("agile_eye")
    assert device_cartesian.orientations_on_device(model)
    assert not device_cartesian.orientations_on_device(numpy_model)
    points = np.random.default_rng(7).uniform(*orientations.FULL_CHART, (4096, 3))
    want = orientations.orientation_integrand(numpy_model)(points)
    got = orientations.orientation_integrand(model)(points)
    assert np.array_equal(got[:, 1] > 0, want[:, 1] > 0)
    assert 0 < np.count_nonzero(want[:, 1]) < len(points)
    bound = 64 * EPS / np.abs(np.cos(points[:, 1]))
    assert np.all(np.abs(got - want) <= bound[:, None])
    expected = orientations.orientation_gci(numpy_model, samples=2**12, seed=4)
    with monkeypatch.context() as patch:
        patch.setattr(Integrand, "__call__", _values_on_the_host)
        found = orientations.orientation_gci(model, samples=2**12, seed=4)
        # a sweep's design on the device (the same compiled reduction: 16 replicates of 256 orientations)
        definition = SweepDefinition((SweepAxis("r_p", 0.08, 0.08, 1),), samples=2**12, seed=4)
        row = evaluate_design(model, {"r_p": 0.08}, definition)
    assert found.value.value == pytest.approx(expected.value.value, rel=1e-12)
    assert found.measure.value == pytest.approx(expected.measure.value, rel=1e-12)
    assert (row["status"], row["gci"], row["volume"]) == ("ok", found.value.value, found.measure.value)
    host_row = evaluate_design(numpy_model, {"r_p": 0.08}, definition)
    for extreme in ("kappa_min", "kappa_max"):  # 1/kappa to 64 eps / |cos pitch| at the same orientations
        assert row[extreme] == pytest.approx(host_row[extreme], rel=1e-9)


def test_a_serial_arms_closed_form_runs_on_the_device(jax_model, loaded, monkeypatch):
    """The planar 2R's Cartesian domain (seed Fig. 8.19) on the device: both elbow branches by the half-angle law of
    cosines in jax.numpy, valid where fk reproduces the point, the first one within the 0..90 deg limits, 1/kappa of
    J there - point by point numpy's: the same reachable set (random points, and the edge cases: the stretched arm's
    circle, where the law of cosines clamps, the folded arm at the shoulder's axis, the points the limits' edges
    reach), 1/kappa to 1e-12; the GCI, its workspace area and symkin workspace's grid of 1/kappa with the values never
    coming back."""
    from symkin.analysis.inverse import inverse_kinematics_for
    from symkin.mechanism import reach

    models = {"numpy": loaded("planar_2r", "numpy"), "jax": jax_model("planar_2r")}
    inverse = {backend: inverse_kinematics_for(model) for backend, model in models.items()}
    box = reach.bounding_box(models["numpy"])
    angles = np.linspace(0.0, np.pi / 2, 33)
    reach_of = 0.2                                               # l1 + l2 = 0.2 m: the stretched arm
    edges = np.concatenate([
        reach_of * np.stack([np.cos(angles), np.sin(angles)], axis=-1),              # stretched: the clamped root
        np.zeros((1, 2)),                                                            # folded onto the shoulder
        0.1 * np.stack([1 + np.cos(angles), np.sin(angles)], axis=-1),               # theta1 = 0, theta2 in limits
        0.1 * np.stack([np.cos(angles) - np.sin(angles), np.sin(angles) + np.cos(angles)], axis=-1)])  # theta2 = 90
    want = _check_the_cartesian_values(models, inverse, box,
                                       np.concatenate([np.random.default_rng(2).uniform(*box, (2048, 2)), edges]))
    assert want[-len(edges):, 1].sum() > len(edges) / 2             # most edge points are reached
    _check_the_cartesian_gci_and_grid(models, inverse, box, 0.005, monkeypatch)


@pytest.mark.parametrize("fraction", [0.0, 0.1, 0.4, 0.9, 1.0])
def test_gathered_rows_give_every_rows_values(fraction):
    """on_gathered_rows: the function at the masked rows, 0 elsewhere, whichever share of the batch holds them
    (1/8, 1/2, or the whole batch where more than half are masked), row 0 masked or not."""
    from symkin.analysis.device_cartesian import REACHABLE_SHARES
    from symkin.analysis.device_integrand import on_gathered_rows

    jax.config.update("jax_enable_x64", True)  # as importing a generated module does (the device programs' case)
    rng = np.random.default_rng(1)
    x = rng.normal(size=(1000, 3))
    mask = rng.uniform(size=1000) < fraction
    got = jax.jit(lambda m, a: on_gathered_rows(m, REACHABLE_SHARES, lambda b: b[:, 0] * b[:, 1], a))(mask, x)
    assert np.array_equal(np.asarray(got), np.where(mask, x[:, 0] * x[:, 1], 0.0))  # one rounding


@contextlib.contextmanager
def _fails_if_it_hangs(seconds: float = 120.0):
    """End the test process with every thread's traceback if the block runs longer than ``seconds`` (a deadlock)."""
    faulthandler.dump_traceback_later(seconds, exit=True)
    try:
        yield
    finally:
        faulthandler.cancel_dump_traceback_later()


def test_the_devices_factorizations_run_in_order(jax_model, loaded):
    """The UR10e's GCI with the Cartesian measure on the device at 2^14 configurations: |det J| and the SVD of J,
    which jaxlib's CPU LAPACK kernels ran concurrently and deadlocked on (2 cores) before they were ordered
    (symkin.numerics.ordered_linalg), now |det J| beside Jacobi's sweeps (no LAPACK); numpy's figures to the same
    bounds as the other models'."""
    from symkin import analysis

    want = analysis.gci(loaded("ur10e", "numpy"), samples=2**14, seed=3, length=0.5)
    with _fails_if_it_hangs():
        got = analysis.gci(jax_model("ur10e"), samples=2**14, seed=3, length=0.5)
    assert got.value.value == pytest.approx(want.value.value, rel=1e-12)
    assert got.measure.value == pytest.approx(want.measure.value, rel=1e-12)


@pytest.mark.parametrize("name, samples, chunk", [("delta", 2**15, None), ("ur10e", 256, 100), ("agile_eye", 256, None)])
def test_the_datasheet_is_rated_on_the_device(name, samples, chunk, jax_model, loaded, monkeypatch):
    """symkin rate's measures of a model loaded with JAX are one program compiled for JAX's device (the datasheet's
    formulas traced with jax.numpy, never called with numpy): a DELTA pushed (a square J), the UR10e pushed at its
    TCP (a redundant J: the farthest vertices of its efforts' polytope over every choice of 3 of its 6 joints) and
    the Agile Eye turned, every group rated.  They equal numpy's sample by sample to the rounding the solves
    amplify: the apparent mass (J M^-1 J^T)^-1 to svd(n) kappa(J)^2 kappa(M) (kappa(J) <= 1 / USABLE_CONDITIONING
    on the usable samples; the home pose, quoted whatever its conditioning, left out), every other measure less.
    The DELTA's 2^15 samples are more than the batch at which its factorizations deadlocked unordered; the UR10e's
    go through in chunks of 100 (the last one padded)."""
    from symkin import mechanism
    from symkin.numerics.ordered_linalg import InOrder
    from symkin.rating import datasheet
    from symkin.rating.handle_measures import Actuation
    from tolerances import svd

    modules = []
    measures = datasheet._measures

    def recorded(*arguments):
        modules.append(arguments[-1])  # the array module
        return measures(*arguments)

    reference = loaded(name, "numpy")
    n = len(reference.info.coordinates)
    actuation = Actuation(np.full(n, 10.0), np.full(n, 5.0), np.full(n, 1e-4), np.full(n, 0.01), np.full(n, 0.02))
    want = datasheet.rate(reference, actuation, samples=samples)
    monkeypatch.setattr(datasheet, "_measures", recorded)
    if chunk is not None:
        from symkin.rating import on_device

        monkeypatch.setattr(on_device, "CHUNK", chunk)
    with _fails_if_it_hangs():
        got = datasheet.rate(jax_model(name), actuation, samples=samples)
    assert {type(module) for module in modules} == {InOrder}  # jax.numpy, its factorizations in order
    np.testing.assert_allclose(got.q, want.q, rtol=0, atol=KINEMATICS * np.pi)  # the same samples (by JAX's ik)
    assert got.skipped == want.skipped
    assert [m.name for m in got.measures] == [m.name for m in want.measures]
    M = mechanism.call(reference, "mass_matrix", q=want.q, p=want.points)
    bound = DYNAMICS + svd(n) * (1 / datasheet.USABLE_CONDITIONING) ** 2 * np.linalg.cond(M[:-1])
    for g, w in zip(got.measures, want.measures):
        np.testing.assert_array_less(np.abs(g.values - w.values)[:-1], bound * np.abs(w.values[:-1]), g.name)


def test_a_later_rating_of_the_model_runs_the_program_compiled_before(jax_model, monkeypatch):
    """The rating's program is kept per model and rating options (on_device.PROGRAMS): a DELTA rated again over other
    samples (as many usable ones, padded to the same power of two) makes no new program, XLA compiles nothing new, and
    it gives what a fresh program gives; other actuators' data make another program."""
    from symkin.rating import datasheet, on_device
    from symkin.rating.handle_measures import Actuation

    made = []
    program = on_device._program
    monkeypatch.setattr(on_device, "_program", lambda *arguments: made.append(1) or program(*arguments))
    monkeypatch.setattr(on_device, "PROGRAMS", type(on_device.PROGRAMS)())  # none of the other tests' programs
    delta = jax_model("delta")
    actuation = Actuation(np.full(3, 10.0), np.full(3, 5.0), np.full(3, 1e-4), np.full(3, 0.01), np.full(3, 0.02))
    datasheet.rate(delta, actuation, samples=200, seed=1)
    again = datasheet.rate(delta, actuation, samples=250, seed=3)
    assert len(made) == 1
    assert [program._cache_size() for program in on_device.PROGRAMS.values()] == [1]  # one XLA executable
    monkeypatch.setattr(on_device, "PROGRAMS", type(on_device.PROGRAMS)())
    fresh = datasheet.rate(delta, actuation, samples=250, seed=3)
    assert len(made) == 2
    for a, b in zip(again.measures, fresh.measures):
        np.testing.assert_array_equal(a.values, b.values, a.name)
    datasheet.rate(delta, Actuation(np.full(3, 20.0)), samples=200, seed=1)
    assert len(made) == 3


@pytest.mark.parametrize("hard_share", [0.0, 0.05, 0.5])
def test_the_devices_extreme_singular_values_are_the_hosts(hard_share):
    """device_integrand.extreme_singular_values (jitted) against conditioning's host rules on 2 x 2, 3 x 3 and 4 x 4
    batches: random matrices, and a share of 3 x 3 ones the closed form does not serve (two equal singular values:
    isotropic in a plane; nearly rank 1) - fewer than the gathered share (their own SVD) and more (an SVD of the
    whole batch) - and exactly singular ones (sigma_min 0).  Both sides evaluate the same formulas or an SVD: a few
    eps of sigma_max (DYNAMICS leaves a wide margin)."""
    from symkin.analysis.device_integrand import extreme_singular_values
    from symkin.numerics import conditioning

    rng = np.random.default_rng(int(100 * hard_share))
    for size in (2, 3, 4):
        J = rng.normal(size=(64, size, size))
        J[:4, -1] = J[:4, 0]                                      # exactly singular
        if size == 3:
            hard = int(hard_share * len(J))
            U, _, V = np.linalg.svd(rng.normal(size=(hard, 3, 3)))
            s = np.where(np.arange(hard)[:, None] % 2 == 0, [2.0, 2.0, 0.5], [1.0, 1e-6, 1e-7])
            J[4:4 + hard] = U @ (s[:, :, None] * V)
        threshold = size * EPS
        largest, smallest = jax.jit(extreme_singular_values, static_argnums=1)(jnp.asarray(J), threshold)
        want = conditioning.singular_values(J)
        scale = want[:, 0]
        np.testing.assert_allclose(np.asarray(largest), want[:, 0], rtol=DYNAMICS)
        np.testing.assert_allclose(np.asarray(smallest), want[:, -1], rtol=0, atol=DYNAMICS * scale.max())
        assert not np.any(np.asarray(smallest)[:4])               # the numerical rank's 0


@pytest.mark.parametrize("shape", [(6, 6), (3, 3), (4, 4), (2, 2), (6, 7), (7, 6)])
def test_jacobis_singular_values_are_lapacks(shape):
    """symkin.numerics.jacobi_svd.jacobi_singular_values (jitted) against numpy's LAPACK SVD: random matrices,
    graded ones (singular values 1 ... 1e-14), ones with all but one singular value equal, exactly singular ones
    (two equal columns, or rows of a wide one: sigma_min within the numerical-rank threshold), the zero matrix,
    matrices scaled by 1e-200 and 1e200 (no underflow or overflow in |a|^2), tall and wide; NaN for a matrix with a
    NaN.  Two backward-stable SVDs: svd(n) of sigma_max."""
    from symkin.numerics.jacobi_svd import jacobi_singular_values

    rng = np.random.default_rng(sum(shape))
    m, n = shape
    k = min(shape)
    A = rng.normal(size=(64, m, n))
    if m >= n:
        A[:4, :, -1] = A[:4, :, 0]
    else:
        A[:4, -1] = A[:4, 0]
    U = np.linalg.qr(rng.normal(size=(20, m, m)))[0]
    V = np.linalg.qr(rng.normal(size=(20, n, n)))[0]
    S = np.zeros((20, m, n))
    S[:, range(k), range(k)] = np.where(np.arange(20)[:, None] % 2 == 0, np.geomspace(1.0, 1e-14, k),
                                        np.r_[np.full(k - 1, 2.0), 0.5])
    A[4:24] = U @ S @ np.swapaxes(V, -1, -2)
    A[24] = 0.0
    A[25] *= 1e-200
    A[26] *= 1e200
    A[27, 0, 0] = np.nan
    got = np.sort(np.asarray(jax.jit(jacobi_singular_values)(jnp.asarray(A))), axis=-1)[:, ::-1]
    assert got.shape == (64, k)
    assert np.all(np.isnan(got[27]))
    A[27, 0, 0] = 0.0
    want = np.linalg.svd(A, compute_uv=False)
    kept = np.arange(64) != 27
    error = np.abs(got - want)[kept].max(axis=-1)
    assert np.all(error <= svd(max(shape)) * want[kept, 0])
    assert np.all(got[:4, -1] <= max(shape) * EPS * got[:4, 0])   # the numerical rank's 0 in extreme_singular_values
    assert not np.any(got[24])


def test_the_device_counts_only_the_configurations_within_the_joint_stops(models, tmp_path, monkeypatch):
    """The planar 2R with the coupled stop 0 <= theta1 + theta2 <= 90 deg (tests/design/test_design.py's arm): the
    device integrand drops the configurations outside it as the host does - the same GCI and workspace measure
    (1e-12) - where the stop's rows were once left out (a measure of the whole box, 2.8 times too large)."""
    from symkin import analysis
    from symkin.integration.integrand import Integrand
    from symkin.model import load_model

    path = tmp_path / "planar_2r.yaml"
    path.write_text((MODELS_DIR / "planar_2r.yaml").read_text()
                    + '\njoint_stops:\n  - {expression: "theta1 + theta2", limits: [0, deg(90)]}\n')
    model = load_model(path)
    directory = pipeline.write(pipeline.generate(model, pipeline.resolve_request(model, "fk,jacobian", "numpy,jax")),
                               tmp_path / "generated")
    want = analysis.gci(load(directory), samples=2**10, seed=5)
    with monkeypatch.context() as patch:
        patch.setattr(Integrand, "__call__", _values_on_the_host)
        got = analysis.gci(load(directory, backend="jax"), samples=2**10, seed=5)
    assert got.value.value == pytest.approx(want.value.value, rel=1e-12)
    assert got.measure.value == pytest.approx(want.measure.value, rel=1e-12)
    l1, l2 = (load(directory).parameters[name] for name in ("l1", "l2"))
    assert abs(got.measure.value - l1 * l2 * (np.pi / 2 - 1)) <= 4 * got.measure.error  # the closed form


def test_a_sweep_on_the_jax_backend_compiles_once_and_gives_numpys_rows(jax_directory, generated_dir, tmp_path):
    """symkin sweep's designs of the planar 2R with the JAX payload (the workers load the JAX module): the GCI, its
    error, the workspace measure and the kappa extremes of every design equal the numpy payload's (the same points;
    1e-12 relative, the errors 1e-6), and the four designs ran one compiled program (the parameters are traced)."""
    from symkin.analysis import device_integrand
    from symkin.design.sweep_store import SweepStore
    from symkin.design.sweeps import SweepAxis, SweepDefinition, evaluate_missing
    from symkin.runtime.payload import ModelPayload

    definition = SweepDefinition((SweepAxis("l1", 0.1, 0.3, 2), SweepAxis("l2", 0.1, 0.3, 2)), chunk=4, samples=1024)
    rows = {}
    for backend, directory in (("jax", jax_directory("planar_2r")), ("numpy", generated_dir / "planar_2r")):
        payload = ModelPayload.from_directory(directory, backend)
        store = SweepStore(tmp_path / f"{backend}.parquet", definition, payload)
        evaluate_missing(payload, definition, store, scheduler="serial")
        rows[backend] = store.finish().to_pydict()
    assert rows["jax"]["status"] == rows["numpy"]["status"] == ["ok"] * 4
    for column, rel in (("gci", 1e-12), ("volume", 1e-12), ("kappa_min", 1e-12), ("kappa_max", 1e-12),
                        ("gci_error", 1e-6), ("volume_error", 1e-6)):
        assert rows["jax"][column] == pytest.approx(rows["numpy"][column], rel=rel), column
    jacobian, _ = ModelPayload.from_directory(jax_directory("planar_2r"), "jax").load().unbound("jacobian")
    reduce = device_integrand._compiled(device_integrand._Functions(jacobian), "cartesian", True,
                                        2 * np.finfo(float).eps)[1]
    assert reduce._cache_size() == 1         # one batch shape (each replicate's 64 points), one compile
    out = tmp_path / "cli.parquet"
    assert main(["sweep", str(jax_directory("planar_2r")), "--backend", "jax", "--vary", "l1=0.1:0.3:2", "--vary",
                 "l2=0.1:0.3:2", "-n", "1024", "--scheduler", "serial", "-o", str(out), "--no-figure"]) == 0
    assert pq.read_table(out).to_pydict()["gci"] == rows["jax"]["gci"]


@pytest.mark.parametrize("name, domain", [("planar_2r", "joint"), ("delta", "cartesian")])
def test_chunks_of_the_jax_payload_are_reduced_on_the_workers_device(name, domain, jax_directory, generated_dir,
                                                                    monkeypatch):
    """The GCI in chunks (symkin.integration.chunked) with the JAX payload: each chunk's integrand is the device's
    (its values never come back: calling them fails here) and the qmc and mc estimates equal the numpy payload's at
    the same points - the integrals to 1e-12 relative, their covariances (spreads of a few hundred values) to 1e-9."""
    from symkin.integration.chunked import IntegrandSpec, integrate_chunked
    from symkin.integration.integrand import Integrand
    from symkin.mechanism import reach
    from symkin.runtime.payload import ModelPayload

    payloads = {backend: ModelPayload.from_directory(directory, backend)
                for backend, directory in (("numpy", generated_dir / name), ("jax", jax_directory(name)))}
    box = None
    if domain == "cartesian":
        box = tuple(tuple(float(v) for v in b) for b in reach.bounding_box(payloads["numpy"].load()))
    spec = IntegrandSpec(domain=domain, box=box)
    assert spec.build(payloads["jax"].load()).moments is not None
    assert spec.build(payloads["numpy"].load()).moments is None
    for method, samples in (("qmc", 2**12), ("mc", 2**11)):   # chunks of one shape: one compile
        want = integrate_chunked(payloads["numpy"], spec, method, samples, seed=3, chunk=256, scheduler="serial")
        with monkeypatch.context() as patch:
            patch.setattr(Integrand, "__call__", _values_on_the_host)
            got = integrate_chunked(payloads["jax"], spec, method, samples, seed=3, chunk=256, scheduler="serial")
        assert got.evaluations == want.evaluations
        np.testing.assert_allclose(got.values, want.values, rtol=1e-12, atol=0)
        np.testing.assert_allclose(got.covariance, want.covariance, rtol=1e-9, atol=0)


def test_the_chunked_gci_takes_the_backend_it_is_given(jax_directory, capsys):
    """symkin gci --scheduler runs the --backend it is given on the workers (JAX: each chunk reduced on the device,
    as the report says) and refuses a backend it cannot ship (C) with exit code 2, as symkin workspace --scheduler
    refuses any but numpy's (its clouds come back for the figures), instead of running numpy's code silently."""
    directory = str(jax_directory("planar_2r"))
    common = ["-n", "4096", "--seed", "1", "--scheduler", "serial", "--chunk", "1000"]
    assert main(["gci", directory, "--backend", "jax", *common]) == 0
    assert "in chunks of at most 1000 points in this process, each reduced on the worker's JAX device" in \
        capsys.readouterr().out
    for command in (["gci", directory, "--backend", "c", *common],
                    ["workspace", directory, "--backend", "jax", "--scheduler", "serial", "--no-figure"]):
        with pytest.raises(SystemExit) as exit_info:
            main(command)
        assert exit_info.value.code == 2
        assert "--scheduler" in capsys.readouterr().err


def test_the_smooth_gcis_gradient_is_its_central_difference(jax_model, loaded):
    """smooth_gci_gradient of the planar 2R (jax.value_and_grad through the generated Jacobian) against the same
    surrogate in numpy (conditioning's 1/kappa_F and |det J| of the numpy backend's J) and its central differences in
    l1 and l2: h = EPS^(1/3) max(1, |p|), truncation and rounding ~EPS^(2/3) of the scale; 1e-8 leaves a wide margin.
    The points keep q2 off the folded and stretched arm (J^T J regular)."""
    from symkin.analysis.device_integrand import compiled_surrogate_gradient, smooth_gci_gradient
    from symkin.numerics import conditioning
    from tolerances import EPS

    rng = np.random.default_rng(66)
    points = np.column_stack([rng.uniform(-np.pi, np.pi, 256), rng.uniform(0.3, 2.8, 256)])
    host = loaded("planar_2r", "numpy")

    def surrogate(**parameters):
        J = host.bind(**parameters).jacobian(points)
        weight = conditioning.absolute_determinant(J)
        return float(np.sum(weight * conditioning.inverse_frobenius_condition_number(J)) / np.sum(weight))

    arm = jax_model("planar_2r")
    value, gradient = smooth_gci_gradient(arm, points)
    base = dict(host.parameters)
    assert value == pytest.approx(surrogate(**base), rel=1e-12)
    assert sorted(gradient) == ["l1", "l2"]
    for name, slope in gradient.items():
        h = EPS ** (1 / 3) * max(1.0, abs(base[name]))
        difference = (surrogate(**{**base, name: base[name] + h}) - surrogate(**{**base, name: base[name] - h})) / (2 * h)
        assert slope == pytest.approx(difference, rel=1e-8, abs=1e-8 * max(abs(v) for v in gradient.values()))
    designed = smooth_gci_gradient(arm.bind(l1=0.3, l2=0.2), points)
    assert designed[0] == pytest.approx(surrogate(l1=0.3, l2=0.2), rel=1e-12)
    # kappa_F of the 2R is (1/rho + 2 rho + 2 cos q2) / |sin q2| with rho = l2 / l1 (||J^-1||_F = ||J||_F / |det J|
    # for 2 x 2): least at rho = 1/sqrt(2) in every configuration, so there the gradient vanishes to rounding
    optimal = smooth_gci_gradient(arm.bind(l1=0.3, l2=0.3 / np.sqrt(2)), points)[1]
    assert max(abs(v) for v in optimal.values()) <= 64 * EPS * max(abs(v) for v in gradient.values())
    compiled = compiled_surrogate_gradient(arm.unbound("jacobian")[0], "cartesian")
    assert compiled._cache_size() == 1        # three designs, one compiled program


@pytest.mark.parametrize("name, free, options", [
    ("planar_2r", ["l1"], {}),
    ("ur10e", ["a2", "a3"], {"length": 0.3}),
])
def test_jax_gradients_optimize_the_casadi_programs_surrogate(name, free, options, jax_model, loaded):
    """symkin.design.gradient_solving: L-BFGS-B on jax.grad of the surrogate optimizes the function the CasADi program
    does (the same nodes, the same smoothed |det J|): equal surrogates at the start (two formulas of 1/kappa_F, both
    rounding to ~1e-15), the same optimum as IPOPT's (both stop on a scaled gradient of ~1e-10; the 2R's is the closed
    form l1 = sqrt(2) l2 of the Frobenius condition number, tests/numerics/test_conditioning.py), and the
    workspace objective too (maximal at the upper bound of l1)."""
    from symkin import design
    from symkin.design.gradient_solving import solve_with_jax

    numpy_model = loaded(name, "numpy")
    problem = design.design_problem(numpy_model, "gci", free, **options)
    ipopt = design.solve(problem, design.formulate(problem, loaded(name, "casadi"), numpy_model, nodes=6))
    solution, description = solve_with_jax(problem, jax_model(name), numpy_model, nodes=6)
    assert solution.success
    assert solution.solver == "L-BFGS-B"
    assert "64 fixed Sobol nodes" in description
    assert solution.surrogate_start == pytest.approx(ipopt.surrogate_start, rel=1e-12)
    assert solution.history[0] == solution.surrogate_start
    assert solution.history[-1] == solution.surrogate_optimum
    assert solution.surrogate_optimum >= ipopt.surrogate_optimum * (1 - 1e-12)
    for parameter in free:
        assert solution.optimum[parameter] == pytest.approx(ipopt.optimum[parameter], rel=1e-7)
    if name != "planar_2r":
        return
    assert solution.optimum["l1"] == pytest.approx(np.sqrt(2) * numpy_model.parameters["l2"], rel=1e-9)
    workspace = design.design_problem(numpy_model, "workspace", free)
    largest, _ = solve_with_jax(workspace, jax_model(name), numpy_model, nodes=6)
    reference = design.formulate(workspace, loaded(name, "casadi"), numpy_model, nodes=6)
    assert largest.surrogate_start == pytest.approx(reference.surrogate(reference.x0), rel=1e-12)
    assert largest.optimum["l1"] == pytest.approx(workspace.free[0].upper, rel=4 * EPS)  # the scaled bound's rounding


#: The spherical 3-RRR with free link angles that docs/design-optimization.md declares (its heredoc).
SPHERICAL_MODEL = re.search(r"^cat > out/spherical_3rrr\.yaml <<'EOF'\n(.*?)^EOF$",
                            (ROOT / "docs" / "design-optimization.md").read_text(), re.S | re.M)


@pytest.mark.parametrize("name", ["delta", "delta_stopped", "spherical_3rrr", "stewart", "pantograph"])
def test_jax_gradients_optimize_a_parallel_models_gci_over_its_box(name, jax_model, loaded, tmp_path):
    """A parallel model with a closed-form ik (the DELTA's box of positions, free a and b; the spherical 3-RRR's box
    of +-30 deg orientations, free link angles): SLSQP on JAX gradients optimizes the CasADi program's surrogate
    under its reach constraints - the same surrogate at the start (two formulas of 1/kappa_F, ~1e-15), IPOPT's
    optimum (both stop on a scaled objective change of ~1e-10 or less; the spherical one's is orthogonal arcs,
    pi/2, tests/design/test_design.py), every leg reaching the box (the closed-form ik margin >= 0 on a grid denser
    than the constraint points).  The DELTA with its first two arms kept within 45 deg of each other (a joint stop
    the free optimum and the start break at the box's corners, tests/design/test_design.py): SLSQP's optimum is
    IPOPT's and keeps it at every constraint point.  The Stewart-Gough platform (free joint radii) over a box of
    positions at its home orientation, its twist Jacobian's position rows divided by L = 0.2 m: the same.  The
    pantograph (default bounds), whose optimum holds a proximal joint at its limit pi, where the ik's atan2 wraps: its
    angles are taken about their limits' centre, so SLSQP's line search sees no 2 pi jump (it stopped there)."""
    from symkin import design
    from symkin.analysis.needs import NEEDS
    from symkin.design.gradient_solving import solve_with_jax
    from symkin.design.problem import held
    from symkin.mechanism import MechanismKind

    box = {"x": (-0.04, 0.04), "y": (-0.04, 0.04), "z": (-0.19, -0.11)}
    options = {}
    if name == "pantograph":
        numpy_model, casadi_model, model = (loaded("pantograph", "numpy"), loaded("pantograph", "casadi"),
                                            jax_model("pantograph"))
        free, box = ["l", "L"], {"x": (-0.03, 0.03), "y": (0.08, 0.12)}
    elif name == "stewart":
        numpy_model, casadi_model, model = loaded("stewart", "numpy"), loaded("stewart", "casadi"), jax_model("stewart")
        free, box = ["r_b", "r_p"], {"x": (-0.03, 0.03), "y": (-0.03, 0.03), "z": (0.21, 0.25)}
        options = {"length": 0.2, "bounds": {"r_b": (0.1, 0.4), "r_p": (0.05, 0.2)}}
    elif name == "delta":
        numpy_model, casadi_model, model = loaded("delta", "numpy"), loaded("delta", "casadi"), jax_model("delta")
        free = ["a", "b"]
    elif name == "delta_stopped":
        path = tmp_path / "delta.yaml"
        path.write_text((MODELS_DIR / "delta.yaml").read_text()
                        + '\njoint_stops:\n  - {expression: "theta1 - theta2", limits: [deg(-45), deg(45)]}\n')
        directory = derive(path, tmp_path, outputs=["ik", "jacobian"], backends=["numpy", "casadi", "jax"], fixed=[])
        numpy_model, casadi_model, model = (load(directory, backend) for backend in ("numpy", "casadi", "jax"))
        free = ["a"]
    else:
        assert SPHERICAL_MODEL, "docs/design-optimization.md no longer declares spherical_3rrr.yaml"
        path = tmp_path / "spherical_3rrr.yaml"
        path.write_text(SPHERICAL_MODEL.group(1))
        directory = derive(path, tmp_path, outputs=NEEDS["design"][MechanismKind.PARALLEL_ORIENTATION],
                           backends=["numpy", "casadi", "jax"])
        numpy_model, casadi_model, model = (load(directory, backend) for backend in ("numpy", "casadi", "jax"))
        free, box = ["alpha1", "alpha2"], {axis: (-np.radians(30), np.radians(30)) for axis in ("roll", "pitch", "yaw")}
    problem = design.design_problem(numpy_model, "gci", free, box=box, **options)
    ipopt = design.solve(problem, design.formulate(problem, casadi_model, numpy_model, nodes=3))
    solution, description = solve_with_jax(problem, model, numpy_model, nodes=3)
    assert solution.success
    assert solution.solver == "SLSQP"
    assert description.endswith("SLSQP on JAX gradients")
    assert f"3^{len(box)} midpoint grid" in description
    assert solution.surrogate_start == pytest.approx(ipopt.surrogate_start, rel=1e-12)
    # the Stewart's r_p ends on its upper bound, which IPOPT may pass by its bound_relax_factor (1e-8 relative; here
    # 1e-11) where the surrogate rises with r_p (relative slope ~ 10): 1e-9 covers ten times that
    optimum_tolerance = 1e-9 if name == "stewart" else 1e-10
    assert solution.surrogate_optimum == pytest.approx(ipopt.surrogate_optimum, rel=optimum_tolerance)
    improved = solution.surrogate_optimum > solution.surrogate_start
    assert improved != (name == "delta_stopped")                       # the stopped DELTA's start breaks its stop
    for parameter in free:
        assert solution.optimum[parameter] == pytest.approx(ipopt.optimum[parameter], rel=1e-6)
    # an active constraint (the Stewart's leg stroke: lengths of ~0.3 m) holds to the rounding of its kinematics
    assert solution.constraint_violation <= KINEMATICS
    axes = [np.linspace(lo, hi, 7) for lo, hi in zip(*problem.inflated_box)]
    points = np.stack(np.meshgrid(*axes), -1).reshape(-1, len(axes))
    assert np.all(np.asarray(held(problem, numpy_model.bind(**solution.optimum)).ik(points).margin) >= -1e-12)
    if name == "delta_stopped":
        points = design.formulate(problem, casadi_model, numpy_model, nodes=3).box_points
        unstopped = design.design_problem(loaded("delta", "numpy"), "gci", free, box=box)
        apart = {}
        for key, (at, optimum) in {"stopped": (numpy_model, solution.optimum), "free": (
                loaded("delta", "numpy"), solve_with_jax(unstopped, jax_model("delta"), loaded("delta", "numpy"),
                                                         nodes=3)[0].optimum)}.items():
            q = np.asarray(at.bind(**optimum).ik(points).joints)
            apart[key] = np.abs(q[:, 0] - q[:, 1]).max()
        assert apart["free"] > np.radians(45), apart
        assert apart["stopped"] <= np.radians(45) + 1e-9, apart


def test_jax_gradients_maximize_a_parallel_models_worst_force_over_its_box(jax_model, loaded):
    """--maximize force --gradients jax: the DELTA's worst isotropic force over its required box (free a and b, unit
    efforts, the arms within their declared limits), SLSQP on the CasADi program's epigraph form with JAX gradients:
    the same worst force at the start (1e-12), IPOPT's optimum (both converge to ~1e-11 here: the parameters to 1e-8,
    the force to 1e-10), 40 % more force than at the start, every leg reaching the box on a grid denser than the
    constraint points."""
    from symkin import design
    from symkin.design.gradient_solving import solve_with_jax

    numpy_model, casadi_model = loaded("delta", "numpy"), loaded("delta", "casadi")
    box = {"x": (-0.04, 0.04), "y": (-0.04, 0.04), "z": (-0.19, -0.11)}
    problem = design.design_problem(numpy_model, "force", ["a", "b"], bounds={"a": (0.06, 0.15), "b": (0.10, 0.25)},
                                    box=box, effort_limits=np.ones(3))
    ipopt = design.solve(problem, design.formulate(problem, casadi_model, numpy_model, nodes=3))
    solution, description = solve_with_jax(problem, jax_model("delta"), numpy_model, nodes=3)
    assert solution.success
    assert solution.solver == "SLSQP"
    assert "epigraph form" in description
    assert description.endswith("SLSQP on JAX gradients")
    assert solution.surrogate_start == pytest.approx(ipopt.surrogate_start, rel=1e-12)
    assert solution.surrogate_optimum == pytest.approx(ipopt.surrogate_optimum, rel=1e-10)
    assert solution.surrogate_optimum > 1.4 * solution.surrogate_start
    for parameter in ("a", "b"):
        assert solution.optimum[parameter] == pytest.approx(ipopt.optimum[parameter], rel=1e-8)
    assert solution.constraint_violation <= 1e-12
    axes = [np.linspace(lo, hi, 7) for lo, hi in zip(*problem.inflated_box)]
    points = np.stack(np.meshgrid(*axes), -1).reshape(-1, 3)
    assert np.all(np.asarray(numpy_model.bind(**solution.optimum).ik(points).margin) >= -1e-12)


def test_jax_gradients_hold_the_apparent_mass_bound_of_the_casadi_program(jax_model, loaded):
    """--maximize force --max-apparent-mass 0.2 --gradients jax: the DELTA of the force test under the CasADi program's
    bound on the apparent mass at the handle (every principal minor of 0.2 J M^-1 J^T - 1 >= 0 at every point): IPOPT's
    optimum (the force to 1e-10, the parameters to 1e-8), the bound active there - the largest apparent mass over the
    points, the eigenvalues of (J M^-1 J^T)^-1 by the numpy code, is 0.2 kg."""
    from symkin import design
    from symkin.design.gradient_solving import solve_with_jax
    from symkin.rating import formulas

    numpy_model, casadi_model = loaded("delta", "numpy"), loaded("delta", "casadi")
    box = {"x": (-0.04, 0.04), "y": (-0.04, 0.04), "z": (-0.19, -0.11)}
    problem = design.design_problem(numpy_model, "force", ["a", "b"], bounds={"a": (0.06, 0.15), "b": (0.10, 0.25)},
                                    box=box, effort_limits=np.ones(3), max_apparent_mass=0.2)
    program = design.formulate(problem, casadi_model, numpy_model, nodes=3)
    ipopt = design.solve(problem, program)
    solution, description = solve_with_jax(problem, jax_model("delta"), numpy_model, nodes=3)
    assert solution.success
    assert "the apparent mass at the handle is at most 0.2 kg" in description
    assert solution.surrogate_start == pytest.approx(ipopt.surrogate_start, rel=1e-12)
    assert solution.surrogate_optimum == pytest.approx(ipopt.surrogate_optimum, rel=1e-10)
    for parameter in ("a", "b"):
        assert solution.optimum[parameter] == pytest.approx(ipopt.optimum[parameter], rel=1e-8)
    assert solution.constraint_violation <= 1e-12
    bound = numpy_model.bind(**solution.optimum)
    q = np.asarray(bound.ik(program.box_points).joints)
    masses = formulas.principal_masses(bound.mass_matrix(q, program.box_points), bound.jacobian(q, program.box_points))
    assert float(np.max(masses)) == pytest.approx(0.2, rel=1e-6)


def test_jax_gradients_refuse_what_they_do_not_solve(jax_model, loaded):
    """A serial model's required box (constraints) or its force objective: a ValueError naming the CasADi path."""

    from symkin import design
    from symkin.design.gradient_solving import solve_with_jax

    arm = loaded("planar_2r", "numpy")
    for problem, model in ((design.design_problem(arm, "gci", ["l1"], box={"x": (0.11, 0.14), "y": (0.11, 0.14)}),
                            "planar_2r"),
                           (design.design_problem(arm, "force", ["l1"], box={"x": (0.11, 0.14), "y": (0.11, 0.14)},
                                                  effort_limits=np.ones(2)), "planar_2r")):
        with pytest.raises(ValueError, match="--gradients casadi"):
            solve_with_jax(problem, jax_model(model), loaded(model, "numpy"))


def test_a_simulation_with_the_jax_code_says_it_is_not_the_fast_way(jax_directory, capsys, tmp_path):
    """symkin simulate evaluates one state per call: with --backend jax it says that numpy's or C's code is faster."""
    out = tmp_path / "swing"
    assert main(["simulate", str(jax_directory("planar_2r")), "--backend", "jax", "--scenario", "free-swing",
                 "--duration", "0.01", "--no-figure", "-o", str(out)]) == 0
    assert "planar_2r: --backend jax: a simulation evaluates one state per call" in capsys.readouterr().out


def test_legs_continued_with_jax_code_alone_say_how_to_get_the_faster_code(tmp_path, capsys):
    """A generated directory of the Novint Falcon (legs without closed forms) that holds JAX's code alone is analysed
    with it, point by point: the first line says so and how to get numpy's code (load_for_analysis takes numpy's
    where it is there: tests/rating/test_novint_falcon.py)."""
    from symkin.analysis.model_files import load_for_analysis
    from symkin.cli.analysis_args import say_where_continued
    from symkin.model import load_model

    model = load_model(MODELS_DIR / "devices" / "novint_falcon.yaml")
    request = pipeline.resolve_request(model, "closure,closure_jacobians", "jax", fixed="all")
    directory = pipeline.write(pipeline.generate(model, request), tmp_path)
    taken = load_for_analysis(str(directory), "jax")
    assert taken.backend == "jax"
    say_where_continued("jax", taken)
    printed = capsys.readouterr().out
    assert printed.startswith(f"novint_falcon: --backend jax: its legs have no closed forms and {directory} holds no "
                              "numpy code")
    assert printed.rstrip().endswith("derive it with --backend numpy too")
