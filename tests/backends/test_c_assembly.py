"""The generated assembly in C (issue 63, first step): ``<model>_assemble`` (Gauss-Newton on the generated closure,
warm-started) and ``<model>_assembly_jacobian`` (J = dp/dq from the closure's Jacobians), called through ctypes.

References: the run-time solver of the same closure (``symkin.runtime.parallel.solve_closure`` and
``closure_velocities``, numpy linear algebra) on the Novint Falcon's legs without the distance form, and the DELTA's
generated closed forms (``fk``, ``jacobian``) against its own generated assembly - the DELTA modelled both ways.
The solvers agree to the Newton tolerance times the condition number of [Phi_s Phi_p]; an unreachable pose gives
0 steps and NaN, never a silently wrong branch.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import shutil
from pathlib import Path

import numpy as np
import pytest

from conftest import GENERATED_DIR, ROOT
from node_scripts import script_forward
from symkin import load, pipeline
from symkin.backends.c import assembly
from symkin.backends.c.build import shared_library
from symkin.mechanism import closure, continuation
from symkin.mechanism.closure import ClosureAssembly, solve_home_assembly
from symkin.model import model_from_text
from symkin.errors import GeneratedCodeError
from symkin.backends.c.loader_assembly import assembly_parameter_names, bind_assembly
from symkin.runtime.assembly import GeneratedAssembly, RuntimeAssembly
from symkin.runtime.loader import LoadedModel
from symkin.runtime.parallel import closure_velocities, solve_closure
from tolerances import EPS

DOUBLES = np.ctypeslib.ndpointer(dtype=np.float64, flags="C_CONTIGUOUS")
#: Gauss-Newton's step tolerance (the runtime's default) and its bound on the steps.
TOLERANCE, ITERATIONS = 1e-12, 50


def library(directory, name: str) -> ctypes.CDLL:
    """The model's compiled C library (the C backend's cache)."""
    return ctypes.CDLL(str(shared_library(directory / f"{name}.c", directory / f"{name}.h")))


def assembly_parameters(model) -> list[float]:
    """The default values of the assembly's parameters, in its header's order."""
    return [model.parameters[name] for name in assembly_parameter_names(model.info)]


def bind(lib: ctypes.CDLL, name: str, params: int):
    """(assemble, assembly_jacobian) of the library with ``params`` free parameters (as doubles)."""
    assemble = getattr(lib, f"{name}_assemble")
    assemble.argtypes = [DOUBLES, DOUBLES, DOUBLES] + [ctypes.c_double] * params + [
        ctypes.c_int, ctypes.c_double, ctypes.POINTER(ctypes.c_double)]
    assemble.restype = ctypes.c_int
    jacobian = getattr(lib, f"{name}_assembly_jacobian")
    jacobian.argtypes = [DOUBLES, DOUBLES, DOUBLES] + [ctypes.c_double] * params + [DOUBLES]
    jacobian.restype = ctypes.c_int
    return assemble, jacobian


@pytest.fixture(scope="module")
def falcon(tmp_path_factory):
    """The Falcon with every parameter folded: (numpy model, assemble, assembly_jacobian)."""
    text = (ROOT / "models" / "devices" / "novint_falcon.yaml").read_text()
    model = model_from_text(text, file="novint_falcon.yaml")
    request = pipeline.resolve_request(model, "closure,closure_jacobians", "numpy,c,js", fixed="all")
    directory = pipeline.write(pipeline.generate(model, request), tmp_path_factory.mktemp("falcon"))
    return (load(directory), *bind(library(directory, "novint_falcon"), "novint_falcon", 0))  # numpy: the runtime's


@pytest.fixture(scope="module")
def falcon_home(falcon):
    """The Falcon's home assembly (its model file's declared one, refined by Gauss-Newton) and home pose."""
    model = falcon[0]
    return solve_home_assembly(model), np.asarray(model.info.home, dtype=float)


def test_a_warm_started_path_follows_the_runtime_solver(falcon, falcon_home):
    model, assemble, jacobian = falcon
    home, p_home = falcon_home
    q0, s, p = home.q, home.s.copy(), p_home.copy()
    residual = ctypes.c_double()
    angles = np.linspace(0.0, 2 * np.pi, 60)
    for t in angles:
        q = q0 + np.radians(5.0) * np.sin(t + np.array([0.0, 2.1, 4.2]))
        steps = assemble(q, s, p, ITERATIONS, TOLERANCE, ctypes.byref(residual))
        assert 1 <= steps <= 6                                  # warm: a few steps from the last sample
        reference = solve_closure(model, q, s, p, unknowns=("p", "s"))
        velocities = closure_velocities(model, q, s, p)
        A = np.hstack([model.closure_jacobians(q, s, p)[k] for k in (2, 0)])      # [Phi_s Phi_p]
        singular = np.linalg.svd(A, compute_uv=False)
        condition = singular[0] / singular[singular > singular[0] * A.shape[0] * EPS][-1]
        np.testing.assert_allclose(p, reference.solution["p"], rtol=0, atol=condition * TOLERANCE)
        assert residual.value <= 64 * EPS
        J = np.empty((3, 3))
        assert jacobian(q, s, p, J) == 1
        np.testing.assert_allclose(J, velocities.J, rtol=0, atol=condition * 64 * EPS * np.abs(velocities.J).max())


@pytest.fixture(scope="module")
def cold_starts(falcon, falcon_home):
    """40 arm positions up to 60 deg from the home assembly's, and where the run-time solver reaches them by continuing
    the home assembly in 2-deg steps (the home assembly's mode): (q, s, p, followed - whether the continuation closed
    every step)."""
    model = falcon[0]
    home, p_home = falcon_home
    q = home.q + np.random.default_rng(63).uniform(-1.0, 1.0, (40, 3)) * np.radians(60.0)
    s_ref, p_ref = np.tile(home.s, (len(q), 1)), np.tile(p_home, (len(q), 1))
    followed = np.ones(len(q), dtype=bool)
    for fraction in np.linspace(0.0, 1.0, 31)[1:]:
        report = solve_closure(model, home.q + fraction * (q - home.q), s_ref, p_ref, unknowns=("p", "s"))
        followed &= closure.closes(report, p_ref)
        s_ref, p_ref = report.solution["s"], report.solution["p"]
    return q, s_ref, p_ref, followed


def _cold_assemblies(backend: str, falcon, directory: Path, q: np.ndarray, s: np.ndarray, p: np.ndarray):
    """(steps, s, p) of each backend's forward assembly from the starts (s, p): the C library (ctypes), the numpy
    RuntimeAssembly, the JavaScript script (Node.js)."""
    model, assemble, _ = falcon
    s, p = s.copy(), p.copy()
    if backend == "c":
        residual = ctypes.c_double()
        steps = [assemble(qk, sk, pk, ITERATIONS, TOLERANCE, ctypes.byref(residual)) for qk, sk, pk in zip(q, s, p)]
        return np.array(steps), s, p
    if backend == "numpy":
        steps, _ = RuntimeAssembly(model).assemble_batch(q, s, p, max_iterations=ITERATIONS, tolerance=TOLERANCE)
        return steps, s, p
    found = script_forward(directory / "novint_falcon.js", q, s, p)
    return (np.array([f["steps"] for f in found]), np.array([f["s"] for f in found]),
            np.array([f["p"] for f in found]))


@pytest.mark.parametrize("backend", ["c", "numpy", "js"])
def test_a_jump_of_assembly_mode_is_flagged(backend, falcon, falcon_home, cold_starts):
    """Cold starts from the home assembly to arms up to 60 deg away, in every backend's forward assembly: where it
    returns a positive count, its assembly is the one the run-time solver reaches by continuing the home assembly
    (the same mode); every start that lands elsewhere is flagged (a negative count: a correction failed to halve) or
    refused (0, NaN).  Some starts are flagged (the check is not idle here)."""
    home, p_home = falcon_home
    q, s_ref, p_ref, followed = cold_starts
    directory = Path(falcon[0].directory)
    steps, s, p = _cold_assemblies(backend, falcon, directory, q, np.tile(home.s, (len(q), 1)),
                                   np.tile(p_home, (len(q), 1)))
    kept = steps > 0
    assert followed[kept].all()
    np.testing.assert_allclose(p[kept], p_ref[kept], rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.angle(np.exp(1j * (s[kept] - s_ref[kept]))), 0.0, rtol=0, atol=1e-6)
    assert steps.min() < 0 < steps.max()
    assert np.isnan(p[steps == 0]).all()


def test_the_run_time_mechanism_steps_by_the_generated_assembly(falcon, monkeypatch):
    """symkin.mechanism.closure.ClosureAssembly of the Falcon loaded with the C backend takes every step by the
    generated assembly (the run-time solver is not called); along a slow path and a jump of 30 deg (continued in
    steps of MAX_STEP) it gives the run-time solver's assembly (the numpy-loaded model's ClosureAssembly) to the
    Newton tolerance times the condition number."""
    model = falcon[0]
    runtime = ClosureAssembly(model)
    path = runtime.home + np.radians(np.vstack([np.linspace(0.0, 4.0, 5)[:, None] * [1.0, -0.5, 0.3],
                                                 [[30.0, -10.0, 5.0]]]))
    references = [runtime(q) for q in path]
    generated = ClosureAssembly(load(model.directory, "c"))
    assert generated.generated is not None
    assert runtime.generated is None

    def refused(*args, **kwargs):
        raise AssertionError("the run-time solver was called")

    monkeypatch.setattr(closure, "solve_closure", refused)
    for q, (s_ref, p_ref) in zip(path, references):
        s, p = generated(q)
        A = np.hstack([model.closure_jacobians(q, s, p)[k] for k in (2, 0)])      # [Phi_s Phi_p]
        singular = np.linalg.svd(A, compute_uv=False)
        condition = singular[0] / singular[singular > singular[0] * A.shape[0] * EPS][-1]
        np.testing.assert_allclose(p, p_ref, rtol=0, atol=condition * TOLERANCE)
        np.testing.assert_allclose(s, s_ref, rtol=0, atol=condition * TOLERANCE)


def test_the_loader_binds_the_assembly_so_that_a_scratch_folder_may_go(falcon, tmp_path, monkeypatch):
    """A model file an analysis derives on the fly loads from a scratch folder that is gone when the analysis asks for
    the generated assembly (symkin.analysis.model_files): the C loader binds it with the library, so the run-time
    mechanism, and a bound design's, still step by it (the run-time solver is not called)."""
    scratch = tmp_path / "novint_falcon"
    shutil.copytree(falcon[0].directory, scratch)
    model = load(scratch, "c")
    shutil.rmtree(scratch)
    assert model.assembly_binding is not None
    assert closure.generated_assembly(model.bind()) is not None
    mechanism = ClosureAssembly(model)                          # the home assembly by the run-time solver
    monkeypatch.setattr(closure, "solve_closure", lambda *args, **kwargs: pytest.fail("the run-time solver ran"))
    s, p = mechanism(mechanism.home + np.radians([2.0, -1.0, 0.5]))
    assert np.all(np.isfinite(p))
    assert load(falcon[0].directory).assembly_binding is None   # numpy: none


def test_c_code_without_the_assembly_binds_none_and_is_refused_with_the_fix(falcon):
    """A library without ``<model>_assemble`` (C code derived before the generated assembly) binds no assembly, and
    GeneratedAssembly of a model without one says to derive it again."""
    model = load(falcon[0].directory, "c")
    libm = ctypes.CDLL(ctypes.util.find_library("m"))
    assert bind_assembly(libm, Path("libm"), Path("none.h"), model.info) is None
    unbound = LoadedModel(model.directory, model.manifest, "c", dict(model._raw))   # the functions alone
    with pytest.raises(GeneratedCodeError, match="predates the generated assembly; derive the model again"):
        GeneratedAssembly(unbound)


def test_no_convergence_within_the_bound_gives_nan_and_no_steps(falcon, falcon_home):
    """Arms 60 deg from the start's: not closed within two steps, so no pose is returned (the residual says how far)."""
    _, assemble, _ = falcon
    home, p_home = falcon_home
    s, p = home.s.copy(), p_home.copy()
    residual = ctypes.c_double()
    assert assemble(home.q + np.radians(60.0), s, p, 2, TOLERANCE, ctypes.byref(residual)) == 0
    assert np.isnan(s).all()
    assert np.isnan(p).all()
    assert residual.value > 1e-6


def test_a_delta_pose_the_legs_cannot_reach_gives_nan(generated_dir):
    """generated/delta's arms where its closed-form fk's spheres do not meet (margin < 0): no assembly exists."""
    delta = load(generated_dir / "delta")
    values = assembly_parameters(delta)
    assemble, _ = bind(library(generated_dir / "delta", "delta"), "delta", len(values))
    q = np.radians([0.0, 0.0, 180.0])
    with np.errstate(invalid="ignore"):
        assert float(delta.fk(q).margin) < 0
    ns = delta.info.functions["closure"].inputs[1].shape[0]
    s, p = np.zeros(ns), np.array([0.0, 0.0, -0.15])
    residual = ctypes.c_double()
    assert assemble(q, s, p, *values, ITERATIONS, TOLERANCE, ctypes.byref(residual)) == 0
    assert np.isnan(p).all()
    assert residual.value > 1e-3                    # a least-squares minimum: the steps vanished there


def test_the_legs_are_the_blocks_of_the_passive_joints_structural_non_zeros():
    """Legs are the connected blocks (rows joined through a shared passive joint), the rows no passive joint enters
    are free; a leg with more joints than rows, or a joint in no row, leaves the system to the dense QR (None)."""
    pattern = ["x.x", "xx.", ".x.", "..x", ".x.", "..."]           # rows 0 and 1 join joints 0, 1 and 2: one leg
    zero = [c == "." for row in pattern for c in row]
    assert assembly.leg_blocks(zero, 6, 3) == ([{"rows": [0, 1, 2, 3, 4], "columns": [0, 1, 2]}], [5])
    pattern = ["x..", "x..", ".x.", "..x", ".x.", "..."]
    zero = [c == "." for row in pattern for c in row]
    assert assembly.leg_blocks(zero, 6, 3) == ([{"rows": [0, 1], "columns": [0]}, {"rows": [2, 4], "columns": [1]},
                                                {"rows": [3], "columns": [2]}], [5])
    assert assembly.leg_blocks([c == "." for c in "xx" ".." ".."], 3, 2) is None          # 1 row, 2 joints
    assert assembly.leg_blocks([c == "." for c in "x." "x." ".."], 3, 2) is None          # joint 1 in no row


def test_the_generated_solver_closes_the_legs_by_the_runtimes_rule():
    assert assembly.CLOSED == closure.CLOSED


def test_the_delta_s_generated_assembly_is_its_closed_form(generated_dir):
    """generated/delta: fk and jacobian in closed form; its closure (distance-form legs, every parameter free) solved
    by the generated assembly from a start 10 mm and a few degrees away."""
    delta = load(generated_dir / "delta")
    values = assembly_parameters(delta)
    assemble, jacobian = bind(library(generated_dir / "delta", "delta"), "delta", len(values))
    rng = np.random.default_rng(63)
    residual = ctypes.c_double()
    for q in rng.uniform(np.radians(-20.0), np.radians(40.0), (20, 3)):
        exact = np.asarray(delta.fk(q).position)
        s_exact = solve_closure(delta, q, np.zeros(delta.info.functions["closure"].inputs[1].shape[0]), exact,
                                unknowns=("s",)).solution["s"]
        s, p = s_exact + rng.uniform(-0.05, 0.05, s_exact.shape), exact + rng.uniform(-0.01, 0.01, 3)
        assert assemble(q, s, p, *values, ITERATIONS, TOLERANCE, ctypes.byref(residual)) >= 1
        np.testing.assert_allclose(p, exact, rtol=0, atol=1e-12)
        J = np.empty((3, 3))
        assert jacobian(q, s, p, *values, J) == 1
        np.testing.assert_allclose(J, delta.jacobian(q, exact), rtol=0, atol=1e-10 * np.abs(J).max())


def test_the_python_binding_gives_the_c_functions_results_with_the_models_design(falcon, falcon_home, generated_dir):
    """symkin.runtime.assembly.GeneratedAssembly: the same steps, pose and J as the raw C functions on the Falcon;
    a bound design of the DELTA (a = 0.12 m) assembles at that design's closed-form fk; bad arrays and a model
    without the C assembly are refused with the fix."""
    model, assemble, jacobian = falcon
    home, p_home = falcon_home
    q, s0, p0 = home.q, home.s + 0.02, p_home - [0.0, 0.0, 0.005]       # a start 5 mm and 1 deg off
    s, p, residual = s0.copy(), p0.copy(), ctypes.c_double()
    steps = assemble(q, s, p, ITERATIONS, TOLERANCE, ctypes.byref(residual))
    raw_J = np.empty((3, 3))
    jacobian(q, s, p, raw_J)
    directory = model.directory
    bound = GeneratedAssembly(load(directory, "c"))
    s1, p1 = s0.copy(), p0.copy()
    assert bound.assemble(q, s1, p1) == (steps, residual.value)
    np.testing.assert_array_equal(p1, p)
    np.testing.assert_array_equal(bound.jacobian(q, s1, p1), raw_J)
    delta = load(generated_dir / "delta", "c").bind(a=0.12)
    assembly = GeneratedAssembly(delta)
    q = np.radians([30.0, 35.0, 40.0])
    exact = np.asarray(delta.fk(q).position)
    s = solve_closure(delta, q, np.zeros(assembly.sizes["s"]), exact, unknowns=("s",)).solution["s"]
    p = exact + 0.005
    assert assembly.assemble(q, s, p)[0] >= 1
    np.testing.assert_allclose(p, exact, rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match="'s' must be a writable float64 C-contiguous array of shape"):
        assembly.assemble(q, s.astype(np.float32), p)
    with pytest.raises(GeneratedCodeError, match="load the model with backend=\"c\""):
        GeneratedAssembly(load(generated_dir / "delta"))


def test_the_compiled_entry_points_give_the_ctypes_results(falcon, falcon_home, monkeypatch):
    """GeneratedAssembly's compiled CPython entry points (exact float64 arrays) and its ctypes binding
    (SYMKIN_C_ENTRY=ctypes) call the same C functions: the same steps, residual, pose and J, bit for bit; arguments
    the entry points do not take (a list, a float32 array) go to the ctypes side, which converts or refuses them."""
    model = falcon[0]
    monkeypatch.delenv("SYMKIN_C_ENTRY", raising=False)      # the suite's default is ctypes (tests/conftest.py)
    compiled = GeneratedAssembly(load(model.directory, "c"))
    monkeypatch.setenv("SYMKIN_C_ENTRY", "ctypes")
    plain = GeneratedAssembly(load(model.directory, "c"))
    assert compiled.compiled
    assert not plain.compiled
    home, p_home = falcon_home
    q = home.q + 0.01
    results = []
    for assembly in (compiled, plain):
        s, p = home.s + 0.02, p_home - [0.0, 0.0, 0.005]
        steps, residual = assembly.assemble(q, s, p)
        results.append((steps, residual, p, assembly.jacobian(q, s, p)))
    assert results[0][:2] == results[1][:2]
    np.testing.assert_array_equal(results[0][2], results[1][2])
    np.testing.assert_array_equal(results[0][3], results[1][3])
    s, p = home.s.copy(), p_home.copy()
    with pytest.raises(ValueError, match="'q' must be a float64 C-contiguous array of shape"):
        compiled.assemble(list(q), s, p)
    with pytest.raises(ValueError, match="'p' must be a float64 C-contiguous array of shape"):
        compiled.jacobian(q, s, p.astype(np.float32))


def test_the_stewart_platform_gets_its_forward_kinematics_from_the_generated_assembly(generated_dir):
    """generated/stewart (six U-P-S legs: 36 closure rows in 30 passive joints and the 6 pose coordinates): from the
    home pose to poses 10 mm and 3 deg away, the generated assembly lands on the pose whose closed-form ik gave the
    lengths, and its J inverts the generated inverse Jacobian."""
    stewart = load(generated_dir / "stewart", "c")
    assembly = GeneratedAssembly(stewart)
    home = np.asarray(stewart.info.home, dtype=float)
    q_home = np.asarray(stewart.ik(home).joints)
    s_home = solve_closure(stewart, q_home, np.zeros(assembly.sizes["s"]), home, unknowns=("s",)).solution["s"]
    rng = np.random.default_rng(63)
    for offset in rng.uniform(-1.0, 1.0, (10, 6)) * np.array([0.01, 0.01, 0.01, 0.05, 0.05, 0.05]):
        target = home + offset
        q = np.asarray(stewart.ik(target).joints)
        s, p = s_home.copy(), home.copy()
        steps, residual = assembly.assemble(q, s, p)
        assert steps >= 1
        np.testing.assert_allclose(p, target, rtol=0, atol=1e-12)
        J = assembly.jacobian(q, s, p)
        np.testing.assert_allclose(np.asarray(stewart.inverse_jacobian(q, p)) @ J, np.eye(6), rtol=0, atol=1e-10)


def test_idle_passive_motions_take_the_pivoted_steps_and_agree_with_the_runtime(tmp_path):
    """An S-P-S Stewart-Gough platform (models/stewart.yaml with its base U joints made spherical: each rod free to
    spin about itself, 42 passive and pose unknowns in 36 closure rows, rank 36): Cholesky refuses the normal
    equations, the pivoted QR gives the basic steps (the spins 0), and the generated assembly lands where the
    run-time solver does from the same start - on the pose whose closed-form ik gave the lengths - its J as
    closure_velocities' (the minimum-norm passive rates).  The home assembly has the struts within their limits
    (q = s = 0 closes the legs with the rods turned around, lengths -0.26 m: refused)."""
    text = (ROOT / "models" / "stewart.yaml").read_text().replace(
        "- {name: ub, type: U, axes: [[0, 0, 1], [0, 1, 0]]}", "- {name: ub, type: S}")
    model = model_from_text(text, file="sps.yaml")
    request = pipeline.resolve_request(model, "ik,closure,closure_jacobians", "numpy,c", fixed="all")
    loaded = load(pipeline.write(pipeline.generate(model, request), tmp_path), "c")
    assembly = GeneratedAssembly(loaded)
    home = np.asarray(loaded.info.home, dtype=float)
    start = solve_home_assembly(loaded)
    np.testing.assert_allclose(start.q, loaded.ik(home).joints, rtol=0, atol=1e-12)
    Phi_p, _, Phi_s = loaded.closure_jacobians(start.q, start.s, home)
    assert np.linalg.matrix_rank(np.hstack([Phi_s, Phi_p])) < Phi_s.shape[1] + Phi_p.shape[1]
    target = home + np.array([0.005, -0.004, 0.003, 0.02, -0.01, 0.03])
    q = np.asarray(loaded.ik(target).joints)
    s, p = start.s.copy(), home.copy()
    steps, residual = assembly.assemble(q, s, p)
    assert steps >= 1
    reference = solve_closure(loaded, q, start.s.copy(), home.copy(), unknowns=("p", "s"))
    np.testing.assert_allclose(p, target, rtol=0, atol=1e-12)
    np.testing.assert_allclose(reference.solution["p"], target, rtol=0, atol=1e-12)
    J = assembly.jacobian(q, s, p)
    velocities = closure_velocities(loaded, q, s, p)
    np.testing.assert_allclose(J, velocities.J, rtol=0, atol=1e-12 * np.abs(J).max())


def test_the_generated_inverse_follows_the_runtime_solver(falcon, falcon_home):
    """``<model>_assemble_inverse_batch``: (q, s) at poses around the home pose from the home assembly, by
    newton_iterate's rules (damped steps, the stall test), equal the run-time solver's to the Newton tolerance times
    the condition number of [Phi_q Phi_s]; a pose beyond the workspace converges in neither."""
    model = falcon[0]
    home, p_home = falcon_home
    inverse = GeneratedAssembly(load(model.directory, "c"))
    assert inverse.has_inverse
    rng = np.random.default_rng(66)
    targets = np.vstack([p_home + rng.uniform(-0.02, 0.02, (24, 3)), p_home + [[0.0, 0.0, 0.5], [0.4, 0.0, 0.0]]])
    q, s = np.tile(home.q, (len(targets), 1)), np.tile(home.s, (len(targets), 1))
    settings = dict(max_step=closure.MAX_STEP, stall=continuation.STALL)
    steps, residual = inverse.assemble_inverse(targets, q, s, max_iterations=ITERATIONS, tolerance=TOLERANCE,
                                               **settings)
    reference = solve_closure(model, home.q, home.s, targets, unknowns=("q", "s"), tol=TOLERANCE,
                              max_iterations=ITERATIONS, **settings)
    np.testing.assert_array_equal(steps > 0, reference.converged)
    assert reference.converged[:24].all()
    assert not reference.converged[24:].any()
    assert np.isnan(q[24:]).all()
    assert np.isnan(s[24:]).all()
    assert np.abs(steps[:24] - reference.iterations[:24]).max() <= 1
    for k in range(24):
        _, Phi_q, Phi_s = (np.asarray(block) for block in model.closure_jacobians(q[k], s[k], targets[k]))
        singular = np.linalg.svd(np.hstack([Phi_q, Phi_s]), compute_uv=False)
        condition = singular[0] / singular[-1]
        np.testing.assert_allclose(q[k], reference.solution["q"][k], rtol=0, atol=condition * TOLERANCE)
        np.testing.assert_allclose(s[k], reference.solution["s"][k], rtol=0, atol=condition * TOLERANCE)
        assert residual[k] <= 64 * EPS


def test_the_continued_workspace_takes_its_solves_from_the_generated_inverse(falcon, monkeypatch):
    """The Falcon's workspace grid continued with the C backend (every solve by the generated inverse: the run-time
    solver is not called) reaches the cells the numpy backend's run-time solver reaches, with the same joints."""
    model = falcon[0]
    runtime = continuation.continued_grid(model, cells=10)
    monkeypatch.setattr(continuation, "solve_closure", lambda *args, **kwargs: pytest.fail("run-time solver called"))
    generated = continuation.continued_grid(load(model.directory, "c"), cells=10)
    np.testing.assert_array_equal(generated.reached, runtime.reached)
    assert runtime.reached.sum() >= 50
    np.testing.assert_allclose(generated.q[generated.reached], runtime.q[runtime.reached], rtol=0, atol=1e-9)
