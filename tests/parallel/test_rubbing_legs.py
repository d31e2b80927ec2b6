"""Legs without the distance form with friction on their actuators (the dual SCARA of docs/model-format.md, its
link bodies, bar and rotors, and friction on three actuators), derived for numpy and C: the friction in the dynamics
(Pinocchio's constraintDynamics as the reference), the C library's terms, the generated assembly's J and dynamics
in the actuated coordinates (``<model>_actuated_dynamics``) that a simulation's step takes, and the plant."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest

from dual_scara_reference import ACTIVE, CLOSURE_ROWS, HOME, assembled_states, constraint_accelerations
from sample_models import dual_scara_dynamics_text
from symkin import load, pipeline
from symkin.derivation import Derivation
from symkin.mechanism import closure as closure_module
from symkin.mechanism.closure import ClosureFunctions
from symkin.model import model_from_text
from symkin.runtime import closure_dynamics as closure_dynamics_module
from symkin.runtime.closure_dynamics import actuated_dynamics, closure_forward_dynamics, closure_inverse_dynamics
from symkin.runtime.parallel import solve_closure
from symkin.simulation import Plant
from tolerances import DYNAMICS, EPS


#: Friction the test declares on the actuators (viscous N m s/rad or N s/m, Coulomb N m or N).
FRICTION = {"theta1": (0.02, 0.05), "lift1": (3.0, 0.8), "knee2": (0.01, 0.0)}


@pytest.fixture(scope="module")
def rubbing_dir(tmp_path_factory):
    """The document's dual SCARA with friction on three actuators, derived for numpy and C; beside it the same
    model derived without ``closure_dynamics`` and ``friction`` (sharing the derivation)."""
    text = dual_scara_dynamics_text() + "friction:\n" + "".join(
        f"  {joint}: {{viscous: {viscous}, coulomb: {coulomb}}}\n" for joint, (viscous, coulomb) in FRICTION.items())
    model = model_from_text(text, file="rubbing.yaml")
    derivation = Derivation(model)
    out = tmp_path_factory.mktemp("rubbing")
    full = pipeline.resolve_request(model, "closure,closure_jacobians,closure_dynamics,friction", "numpy,c",
                                    fixed="all")
    bare = pipeline.resolve_request(model, "closure,closure_jacobians", "numpy", fixed="all")
    return (pipeline.write(pipeline.generate(model, full, derivation=derivation), out / "full"),
            pipeline.write(pipeline.generate(model, bare, derivation=derivation), out / "bare"))


def test_friction_enters_the_dynamics_as_efforts_against_the_motion(rubbing_dir):
    """F_f = viscous qd + coulomb sign(qd) (written here from the declared coefficients) opposes the actuators:
    the forward dynamics equals Pinocchio's constraintDynamics under the efforts tau - F_f, and the inverse
    dynamics gives tau back (1e-9 relative, as without friction)."""
    accelerations = constraint_accelerations(pytest.importorskip("pinocchio"))
    rubbing = load(rubbing_dir[0])
    rng = np.random.default_rng(3108)
    for q, s, p in assembled_states(rubbing, 3, rng):
        qd, tau = rng.uniform(-1, 1, 4), rng.uniform(-0.5, 0.5, 4) + [0, 4.4, 0, 0]
        friction = np.array([FRICTION[name][0] * v + FRICTION[name][1] * np.sign(v) if name in FRICTION else 0.0
                             for name, v in zip(ACTIVE, qd)])
        reference = accelerations(q, s, actuated_dynamics(rubbing, q, s, p, qd).zd, tau - friction)
        qdd = closure_forward_dynamics(rubbing, q, s, p, qd, tau)
        assert np.max(np.abs(qdd - reference)) <= 1e-9 * np.max(np.abs(reference)), (qdd, reference)
        back = closure_inverse_dynamics(rubbing, q, s, p, qd, reference)
        assert np.max(np.abs(back - tau)) <= 1e-9 * np.max(np.abs(tau)), (back, tau)


def test_the_c_library_gives_the_numpy_terms(rubbing_dir):
    """closure_dynamics and friction compiled in C: each output within DYNAMICS of its largest entry."""
    numpy_model, c_model = load(rubbing_dir[0]), load(rubbing_dir[0], "c")
    (q, s, p), = assembled_states(numpy_model, 1, np.random.default_rng(13))
    rates = np.random.default_rng(14).uniform(-1, 1, 12)
    numpy_terms = numpy_model.closure_dynamics(q, s, p, rates[:4], rates[4:8], rates[8:])
    c_terms = c_model.closure_dynamics(q, s, p, rates[:4], rates[4:8], rates[8:])
    for name in ("M_z", "h_z", "gamma", "u"):
        expected, got = np.asarray(getattr(numpy_terms, name)), np.asarray(getattr(c_terms, name))
        assert np.max(np.abs(got.reshape(expected.shape) - expected)) <= DYNAMICS * np.max(np.abs(expected)), name
    expected = numpy_model.friction(rates[:4])
    assert np.max(np.abs(c_model.friction(rates[:4]) - expected)) <= DYNAMICS * np.max(np.abs(expected))


def test_the_jacobian_of_a_loop_step_comes_from_the_generated_assembly(rubbing_dir, monkeypatch):
    """The run-time mechanism's J = dp/dq of legs loaded with the C backend (a simulation step asks for it before the
    dynamics at the same q): the generated assembly's, not W of the dynamics evaluated at rest for it, equal to the
    p rows of W at the same assembly to rounding amplified by the condition number of [Phi_s Phi_p]."""
    functions = ClosureFunctions(load(rubbing_dir[0], "c"))
    assert functions.assembly.generated is not None
    q = functions.home + [0.05, 0.01, -0.04, 0.02]
    s, p = functions.assembled(q)                                  # continued from the home assembly
    with monkeypatch.context() as patch:
        patch.setattr(closure_module, "actuated_dynamics", lambda *args: pytest.fail("dynamics evaluated for J"))
        J = functions.function("jacobian")(q)
    W = actuated_dynamics(load(rubbing_dir[0]), q, s, p, np.zeros(4)).W
    expected = W[len(W) - len(J):]
    A = np.hstack([np.asarray(functions.model.closure_jacobians(q, s, p)[k]) for k in (2, 0)])   # [Phi_s Phi_p]
    assert np.max(np.abs(J - expected)) <= 100 * EPS * np.linalg.cond(A) * np.max(np.abs(expected))


def test_a_plant_of_rubbing_legs_needs_their_friction(rubbing_dir):
    """Without the generated friction its joints declare, the plant would simulate a frictionless device: refused,
    naming what to derive."""
    from symkin.errors import GeneratedCodeError

    with pytest.raises(GeneratedCodeError, match="closure_dynamics, friction .*--only closure,closure_jacobians,"
                                                 "closure_dynamics,friction"):
        Plant(load(rubbing_dir[1]))
    rubbing = load(rubbing_dir[0])
    plant = Plant(rubbing)
    # near its home assembly, the plant's acceleration is the reduced dynamics with friction (checked against
    # Pinocchio above) at the assembly solved here: its own assembly and friction are wired in
    from symkin.mechanism.closure import assemble_at_home

    home_q, home_s = assemble_at_home(rubbing)
    q = home_q + np.array([0.05, 0.01, -0.04, 0.03])
    solved = solve_closure(rubbing, q, home_s, HOME, unknowns=("p", "s"))
    s, p = solved.solution["s"], solved.solution["p"]
    qd, tau = np.array([0.3, -0.2, 0.05, 0.1]), np.array([0.1, 4.4, -0.1, 0.05])
    expected = closure_forward_dynamics(rubbing, q, s, p, qd, tau)
    frictionless = expected - closure_forward_dynamics(rubbing, q, s, p, qd, tau + rubbing.friction(qd))
    assert np.max(np.abs(frictionless)) > 1e-3 * np.max(np.abs(expected))  # the friction matters here
    # two Gauss-Newton solves of one assembly agree to rounding, which the solve with M amplifies by kappa(M)
    kappa = float(np.linalg.cond(actuated_dynamics(rubbing, q, s, p, qd).M))
    assert np.max(np.abs(plant.acceleration(q, qd, tau) - expected)) <= kappa * DYNAMICS * np.max(np.abs(expected))


def test_the_generated_assembly_gives_the_dynamics_of_a_step(rubbing_dir, monkeypatch):
    """<model>_actuated_dynamics (C: the projection W = [1; -A^+ Phi_q], c = [0; -A^+ gamma], M = W^T M_z W,
    b = W^T (M_z c + h_z) by Householder QR) gives the run-time batch path's terms (numpy, A^+ by LAPACK's QR) at
    assembled states, through the compiled entry points and through ctypes, to rounding amplified by cond(A); the
    run-time mechanism's dynamics of one state take it (the generated closure_jacobians are not called from Python)."""
    monkeypatch.delenv("SYMKIN_C_ENTRY", raising=False)    # the compiled entry points, as a user gets them
    c_model, numpy_model = load(rubbing_dir[0], "c"), load(rubbing_dir[0])
    functions = ClosureFunctions(c_model)
    generated = functions.assembly.generated
    assert generated is not None
    assert generated.has_dynamics
    assert generated.compiled
    rng = np.random.default_rng(2611)
    for q, s, p in assembled_states(numpy_model, 3, rng):
        qd = rng.uniform(-1, 1, 4)
        blocks = numpy_model.closure_jacobians(q, s, p)
        kappa = float(np.linalg.cond(np.hstack([blocks.Phi_s, blocks.Phi_p])[CLOSURE_ROWS]))
        batch = actuated_dynamics(numpy_model, q[None], s[None], p[None], qd[None])   # numpy's
        compiled = actuated_dynamics(c_model, q, s, p, qd, generated)
        with monkeypatch.context() as patch:
            patch.setattr(generated, "_entry", None)                                  # ctypes
            through_ctypes = actuated_dynamics(c_model, q, s, p, qd, generated)
        for terms in (compiled, through_ctypes):
            for name in ("M", "bias", "friction", "W", "zd", "drift", "potential"):
                expected, got = np.asarray(getattr(batch, name))[0], np.asarray(getattr(terms, name))
                bound = 100 * EPS * kappa * max(float(np.max(np.abs(expected))), 1.0)
                assert got.shape == expected.shape, name
                assert np.max(np.abs(got - expected)) <= bound, name
    q = functions.home + [0.05, 0.01, -0.04, 0.02]
    s, p = functions.assembled(q)                                  # continued from the home assembly
    with monkeypatch.context() as patch:
        patch.setattr(c_model, "closure_jacobians", lambda *args: pytest.fail("the projection ran in Python"))
        terms = functions.dynamics(q, qd)
    expected = actuated_dynamics(numpy_model, q[None], s[None], p[None], qd[None]).M[0]
    blocks = numpy_model.closure_jacobians(q, s, p)
    kappa = float(np.linalg.cond(np.hstack([blocks.Phi_s, blocks.Phi_p])[CLOSURE_ROWS]))
    assert np.max(np.abs(terms.M - expected)) <= 100 * EPS * kappa * np.max(np.abs(expected))


def test_a_state_the_generated_dynamics_cannot_project_takes_the_batch_path(rubbing_dir, monkeypatch):
    """NaN in the state (legs that do not close): <model>_actuated_dynamics returns 0 and None reaches Python, which
    then takes the batch path: NaN in, NaN out, never a number."""
    c_model = load(rubbing_dir[0], "c")
    generated = ClosureFunctions(c_model).assembly.generated
    q, s, p = assembled_states(load(rubbing_dir[0]), 1, np.random.default_rng(5))[0]
    nan_s = np.full_like(s, np.nan)
    assert generated.actuated_dynamics(q, nan_s, p, np.zeros(4)) is None
    taken = []
    batch = closure_dynamics_module._one_state
    monkeypatch.setattr(closure_dynamics_module, "_one_state", lambda *args: taken.append(1) or batch(*args))
    terms = actuated_dynamics(c_model, q, nan_s, p, np.zeros(4), generated)
    assert taken
    assert np.all(np.isnan(terms.M))
    assert np.all(np.isnan(terms.bias))


def test_the_generated_dynamics_is_strict_c99(rubbing_dir, tmp_path):
    """The C source with <model>_actuated_dynamics compiles warning-free with the strict flags (the example models'
    scenes derive no closure_dynamics: tests/backends/test_c_backend.py compiles them), at -O1, where GCC's
    flow-sensitive warnings run."""
    from checks import CC, STRICT_FLAGS

    if CC is None:
        pytest.skip("no C compiler")
    source = next(rubbing_dir[0].glob("*.c"))
    assert "_actuated_dynamics(" in source.read_text()
    flags = ["-O1" if flag == "-O3" else flag for flag in STRICT_FLAGS]
    result = subprocess.run([CC, *flags, "-c", str(source), "-o", str(tmp_path / "rubbing.o")], capture_output=True,
                            text=True)
    assert result.returncode == 0, result.stderr
    assert not result.stderr, result.stderr
