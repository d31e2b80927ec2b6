"""The emitted dynamics (composite-rigid-body M, Newton-Euler V, G and tau) equal the Lagrangian reference.

``lagrangian_dynamics`` computes M = sum J^T I J, C and V = C qd from the Christoffel symbols
of that M, G = du/dq and tau = M qdd + V + G + F_f from the closed forms of
symkin.dynamics.lagrange; the emitted functions share none of that code.  Checked
symbolically for the seed's planar arm and numerically at random states for every example
serial model, the friction arm (prismatic joint, tilted frames, friction) and an arm made to
hit every branch of the Newton-Euler code (base transform, oblique and offset axes, several
bodies on one link, a body with inertia and no mass, a link without bodies, an oblique prismatic joint).
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy

from conftest import EXAMPLE_MODELS, MODELS_DIR, random_q, reference_function
from lagrangian_reference import lagrangian_dynamics
from symkin.derivation import Derivation
from symkin.model import load_model, model_from_text, tree
from sample_models import FRICTION_ARM, ODD_ARM
from tolerances import DYNAMICS


STATES = 6


@pytest.fixture(scope="module")
def cases(models, derivations):
    # the Lagrangian reference walks a chain (a body moves with every joint before it): trees, such as the
    # PHANToM's parallelogram branch, are checked against Pinocchio (tests/references/test_crosscheck.py)
    out = {name: (models[name], derivations[name]) for name in EXAMPLE_MODELS
           if models[name].parallel is None and models[name].bodies and tree.is_chain(models[name])}
    for key, model in (("ur10e_urdf", load_model(MODELS_DIR / "ur10e.urdf")), ("friction_arm", model_from_text(FRICTION_ARM)),
                       ("odd_arm", model_from_text(ODD_ARM))):
        out[key] = (model, Derivation(model))
    return out


CASES = ["planar_2r", "ur10e", "ur10e_classic", "ur10e_urdf", "friction_arm", "odd_arm"]


def test_every_serial_example_model_with_bodies_is_checked(cases):
    assert {name for name in cases} == set(CASES)


def _relative(got, want) -> float:
    """max |got - want| relative to max |want| (the models' torques range from mN m to kN m)."""
    scale = float(np.max(np.abs(want)))
    assert scale > 0
    return float(np.max(np.abs(got - want))) / scale


@pytest.mark.parametrize("name", CASES)
def test_emitted_dynamics_equal_the_lagrangian_reference(name, cases):
    model, d = cases[name]
    reference = reference_function(model, lagrangian_dynamics(d))
    names = [o.name for o in lagrangian_dynamics(d).outputs]
    emitted = {"M": ("mass_matrix", 1), "C": ("coriolis_matrix", 2), "V": ("coriolis_vector", 2),
               "G": ("gravity_vector", 1), "tau": ("inverse_dynamics", 3)}
    assert set(names) == set(emitted)
    functions = {out: (reference_function(model, d[quantity]), arity) for out, (quantity, arity) in emitted.items()
                 if out in names}
    rng = np.random.default_rng(40)
    for _ in range(STATES):
        state = (random_q(model, rng), rng.uniform(-2, 2, model.dof), rng.uniform(-3, 3, model.dof))
        want = dict(zip(names, reference(*state)))
        for out, (f, arity) in functions.items():
            got = f(*state[:arity])[0]
            # two exact derivations (Newton-Euler, Lagrange) differ in rounding only: DYNAMICS
            assert _relative(got, want[out]) <= DYNAMICS, (out, DYNAMICS, got, want[out], state)


def test_forward_dynamics_inverts_the_lagrangian_torques(cases):
    """forward_dynamics (M by the composite-rigid-body algorithm, V + G by Newton-Euler) against the reference."""
    model, d = cases["odd_arm"]
    reference = reference_function(model, lagrangian_dynamics(d))
    qdd_of = reference_function(model, d["forward_dynamics"])
    rng = np.random.default_rng(41)
    for _ in range(STATES):
        q, qd, qdd = random_q(model, rng), rng.uniform(-2, 2, model.dof), rng.uniform(-3, 3, model.dof)
        tau = reference(q, qd, qdd)[-1]
        # a solve with M: backward stable, the error of qdd grows with kappa(M)
        bound = DYNAMICS * np.linalg.cond(reference_function(model, d["mass_matrix"])(q)[0])
        assert _relative(qdd_of(q, qd, tau)[0], qdd) <= bound, (bound, q, qd, tau)


def _symbolic(spec) -> list[sympy.Matrix]:
    return [sympy.Matrix(e) for e in spec.expanded_outputs()]


def test_planar_arm_equals_the_lagrangian_reference_symbolically(cases):
    """Exact equality (the difference simplifies to zero) for the seed's 2-DoF arm, parameters symbolic."""
    _, d = cases["planar_2r"]
    reference = dict(zip([o.name for o in lagrangian_dynamics(d).outputs], _symbolic(lagrangian_dynamics(d))))
    for out, quantity in (("M", "mass_matrix"), ("C", "coriolis_matrix"), ("V", "coriolis_vector"),
                          ("G", "gravity_vector"), ("tau", "inverse_dynamics")):
        (got,) = _symbolic(d[quantity])
        difference = (got - reference[out].reshape(*got.shape)).applyfunc(
            lambda e: sympy.simplify(sympy.expand_trig(sympy.expand(e))))
        assert difference.is_zero_matrix, (out, difference)
