"""Force transmission of parallel mechanisms (issue 14): tau = J^T F and F = J^-T tau.

The references share no code with the derivation: virtual work against finite differences of the
closed-form inverse kinematics (a motion pdot of the platform moves the actuators by
qdot = (ik(p + h pdot) - ik(p - h pdot)) / 2h, and tau . qdot must equal F . pdot), and the two
maps inverting each other (one through the adjugate of J_x, the other through J_x^T and the
diagonal J_q).  States: platform poses near the home pose of the DELTA and the Stewart platform.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import MODELS_DIR, reference_function
from tolerances import KINEMATICS

EPS = np.finfo(float).eps
STEP = 1e-5


@pytest.fixture(scope="module", params=["delta", "stewart"])
def case(request, models, derivations):
    model, d = models[request.param], derivations[request.param]
    functions = {name: reference_function(model, d[name]) for name in ("ik", "tcp_force_map", "tcp_force_map_inverse")}
    home = np.array([float(e.xreplace(model.parameter_values)) for e in model.parallel.home])
    return model, functions, home


def _poses(home: np.ndarray, rng: np.random.Generator, count: int) -> np.ndarray:
    spread = np.where(np.arange(len(home)) < 3, 0.02, 0.1)  # 2 cm and 0.1 rad around the home pose
    return home + rng.uniform(-1, 1, (count, len(home))) * spread


def test_the_force_map_does_the_virtual_work_of_the_motion(case):
    model, f, home = case
    rng = np.random.default_rng(140)
    for p in _poses(home, rng, 6):
        q = f["ik"](p)[0]
        F, pdot = rng.uniform(-10, 10, len(p)), rng.uniform(-1, 1, len(p))
        qdot = (f["ik"](p + STEP * pdot)[0] - f["ik"](p - STEP * pdot)[0]) / (2 * STEP)
        tau = f["tcp_force_map"](q, p, F)[0]
        power = F @ pdot
        # central differences: truncation ~ STEP^2 |ik'''| and rounding ~ eps |q| / STEP per component,
        # both below 1e-8 of the terms at these poses; the bound is that times |tau| |qdot|
        bound = 1e-8 * np.abs(tau) @ np.abs(qdot) + 10 * (STEP**2 + EPS / STEP) * np.abs(F) @ np.abs(pdot)
        assert abs(tau @ qdot - power) <= bound, (model.name, tau @ qdot, power, bound)


def test_the_inverse_map_inverts_it(case):
    model, f, home = case
    rng = np.random.default_rng(141)
    for p in _poses(home, rng, 6):
        q = f["ik"](p)[0]
        F = rng.uniform(-10, 10, len(p))
        tau = f["tcp_force_map"](q, p, F)[0]
        back = f["tcp_force_map_inverse"](q, p, tau)[0]
        # a solve's rounding grows with the condition number of J (= that of J^-1, here by differences of ik)
        J_inv = np.array([(f["ik"](p + STEP * e)[0] - f["ik"](p - STEP * e)[0]) / (2 * STEP)
                          for e in np.eye(len(p))]).T
        bound = KINEMATICS * np.linalg.cond(J_inv) * np.abs(F).max()
        np.testing.assert_allclose(back, F, rtol=0, atol=bound)


def test_numpy_c_and_casadi_emit_the_force_maps(tmp_path, models, derivations):
    """symkin derive emits both maps for the three backends, which agree with the reference."""
    from symkin import derive, load

    model = models["delta"]
    directory = derive(MODELS_DIR / "delta.yaml", tmp_path, outputs=["ik", "inverse_jacobian", "tcp_force_map",
                                                              "tcp_force_map_inverse"],
                       backends=["numpy", "c", "casadi"])
    reference = reference_function(model, derivations["delta"]["tcp_force_map"])
    p = np.array([[0.01, -0.02, -0.16], [-0.03, 0.0, -0.14]])
    F = np.array([[1.0, 2.0, 3.0], [-4.0, 0.5, 2.0]])
    for backend in ("numpy", "c", "casadi"):
        delta = load(directory, backend=backend)
        q = delta.ik(p).joints
        tau = delta.tcp_force_map(q, p, F)
        want = np.array([reference(qi, pi, Fi)[0] for qi, pi, Fi in zip(q, p, F)])
        # optimized and reference forms of one expression: rounding of a few dozen operations
        np.testing.assert_allclose(tau, want, rtol=0, atol=KINEMATICS * np.abs(want).max())
        condition = np.linalg.cond(delta.inverse_jacobian(q, p)).max()  # the round trip's amplification
        np.testing.assert_allclose(delta.tcp_force_map_inverse(q, p, tau), F, rtol=0,
                                   atol=KINEMATICS * condition * np.abs(F).max())
