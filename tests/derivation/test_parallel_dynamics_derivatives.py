"""Derivatives of the reduced dynamics of parallel mechanisms (issue 65: "parallel models where their reduced dynamics
are generated"): ``inverse_dynamics_derivatives``, ``forward_dynamics_derivatives`` and ``gravity_derivatives`` of
the DELTA (models/delta.yaml, with viscous and Coulomb friction added at its actuators), the DELTA carrying a wrist (a
hybrid device: its wrist's joints are coordinates of their own), the pantograph and the Agile Eye, in the actuated
coordinates with the platform pose moving along the closure (p = fk(q)).

Reference: central differences of the derived inverse dynamics, forward dynamics and gravity efforts (plain lambdify
of the un-optimized derivation) along the closure - each side at q +- h e_j with its own pose fk(q +- h e_j), the
closed-form forward kinematics - with h = EPS^(1/3) max(1, |x|): truncation h^2 |f'''| / 6 and rounding EPS |f| / h,
both ~EPS^(2/3) ~ 4e-11 of the scale, times the condition number the efforts carry (J_x^-1 enters them up to four
times: kappa(J)^4 at most, 1.2 to 1.8 here); 1e-8 of the scale times kappa(J) leaves a factor of more than 10
(the errors are 1e-11 to 1e-10 of it).  The
derivatives by qdd and tau are M and M^-1; d qdd/dq is -M^-1 d tau/dq at the forward dynamics' motion.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import MODELS_DIR, home_joints, reference_function
from symkin.derivation import Derivation
from symkin.model import load_model, model_from_text
from tolerances import DYNAMICS, EPS

#: The DELTA's actuators with friction (the model file declares none): a sign(qd) Coulomb term and a viscous one.
DELTA_FRICTION = "".join(f"  theta{k}: {{viscous: 0.002, coulomb: 0.03}}\n" for k in (1, 2, 3))


def _model(name: str):
    if name != "delta":
        return load_model(MODELS_DIR / f"{name}.yaml")
    return model_from_text((MODELS_DIR / "delta.yaml").read_text() + "friction:\n" + DELTA_FRICTION, file="delta.yaml")


def _central(f, state: list[np.ndarray], which: int, fk, legs: int | None = None) -> np.ndarray:
    """Columns (f(state + h e_j) - f(state - h e_j)) / 2h in the state's vector ``which`` (0: q, the pose p = fk(q)
    following it).  A hybrid device's (``legs``: its legs' coordinates) vectors stack the legs' and the wrist's parts,
    (q, qw), (qd, qwd), ...: f takes them split, f(q, p, qw, qd, qwd, ...)."""
    columns = []
    for j in range(len(state[which])):
        h = EPS ** (1 / 3) * max(1.0, abs(state[which][j]))
        sides = []
        for sign in (1.0, -1.0):
            moved = [v.copy() for v in state]
            moved[which][j] += sign * h
            if legs is None:
                sides.append(f(moved[0], fk(moved[0])[0], *moved[1:])[0])
                continue
            q, qw = moved[0][:legs], moved[0][legs:]
            sides.append(f(q, fk(q)[0], qw, *(part for v in moved[1:] for part in (v[:legs], v[legs:])))[0])
        columns.append((sides[0] - sides[1]) / (2 * h))
    return np.column_stack(columns)


@pytest.mark.parametrize("name", ["delta", "pantograph", "agile_eye"])
def test_the_derivatives_are_central_differences_along_the_closure(name):
    model = _model(name)
    d = Derivation(model)
    fk, jacobian = (reference_function(model, d[k]) for k in ("fk", "jacobian"))
    tau, forward, G = (reference_function(model, d[k]) for k in ("inverse_dynamics", "forward_dynamics",
                                                                  "gravity_vector"))
    inverse_slopes, forward_slopes, gravity_slope = (
        reference_function(model, d[k])
        for k in ("inverse_dynamics_derivatives", "forward_dynamics_derivatives", "gravity_derivatives"))
    rng = np.random.default_rng(65)
    n = model.dof
    for _ in range(3):
        q = home_joints(model) + rng.uniform(-0.15, 0.15, n)       # near the home pose: fk assembles
        p = fk(q)[0]
        kappa = float(np.linalg.cond(jacobian(q, p)[0]))
        qd = rng.uniform(0.2, 2, n) * rng.choice([-1, 1], n)    # |qd| > h: no Coulomb sign flips
        qdd = rng.uniform(-5, 5, n)
        dq, dqd, dqdd = inverse_slopes(q, p, qd, qdd)
        scale = max(float(np.abs(v).max()) for v in (tau(q, p, qd, qdd)[0], dq, dqd))    # the efforts' own scale
        atol = 1e-8 * kappa * scale
        np.testing.assert_allclose(dq, _central(tau, [q, qd, qdd], 0, fk), rtol=0, atol=atol)
        np.testing.assert_allclose(dqd, _central(tau, [q, qd, qdd], 1, fk), rtol=0, atol=atol)
        M = dqdd
        np.testing.assert_allclose(M, M.T, rtol=0, atol=64 * EPS * scale)
        effort = tau(q, p, qd, qdd)[0]
        fq, fqd, ftau = forward_slopes(q, p, qd, effort)
        accel = max(1.0, float(np.abs(qdd).max()))
        kappa_M = float(np.linalg.cond(M))
        np.testing.assert_allclose(ftau @ M, np.eye(n), rtol=0, atol=64 * EPS * kappa_M)
        np.testing.assert_allclose(fq, -ftau @ dq, rtol=0, atol=64 * EPS * kappa_M * np.abs(ftau @ dq).max())
        np.testing.assert_allclose(fqd, -ftau @ dqd, rtol=0, atol=64 * EPS * kappa_M * np.abs(ftau @ dqd).max())
        np.testing.assert_allclose(fq, _central(forward, [q, qd, effort], 0, fk), rtol=0,
                                   atol=1e-8 * kappa * kappa_M * accel)
        gravity = gravity_slope(q, p)[0]
        gravity_scale = max(float(np.abs(G(q, p)[0]).max()), float(np.abs(gravity).max()))
        np.testing.assert_allclose(gravity, _central(G, [q], 0, fk), rtol=0, atol=1e-8 * kappa * gravity_scale)


def test_a_hybrid_devices_derivatives_are_central_differences_along_the_closure():
    """models/delta_wrist.yaml (a DELTA carrying a 3-joint wrist): the efforts (tau, tauw) by the coordinates (q, qw)
    - the legs' q moving the platform with them, the wrist's joints their own coordinates - by (qd, qwd) and (qdd, qwdd)
    = M, and the forward dynamics' and gravity's, (3 + 3) x (3 + 3) each, against central differences of the derived
    functions (the tolerance as the module docstring's)."""
    model = load_model(MODELS_DIR / "delta_wrist.yaml")
    d = Derivation(model)
    fk, jacobian, tau, forward, G = (reference_function(model, d[k]) for k in (
        "fk", "jacobian", "inverse_dynamics", "forward_dynamics", "gravity_vector"))
    inverse_slopes, forward_slopes, gravity_slope = (reference_function(model, d[k]) for k in (
        "inverse_dynamics_derivatives", "forward_dynamics_derivatives", "gravity_derivatives"))
    rng = np.random.default_rng(66)
    legs = model.dof
    for _ in range(2):
        q, qw = home_joints(model) + rng.uniform(-0.15, 0.15, legs), rng.uniform(-0.6, 0.6, 3)
        p = fk(q)[0]
        kappa = float(np.linalg.cond(jacobian(q, p)[0]))
        x, xd, xdd = np.concatenate([q, qw]), rng.uniform(-2, 2, 6), rng.uniform(-5, 5, 6)
        dq, dqd, M = inverse_slopes(q, p, qw, xd[:3], xd[3:], xdd[:3], xdd[3:])
        effort = tau(q, p, qw, xd[:3], xd[3:], xdd[:3], xdd[3:])[0]
        scale = max(float(np.abs(v).max()) for v in (effort, dq, dqd))
        for which, slope in ((0, dq), (1, dqd), (2, M)):
            np.testing.assert_allclose(slope, _central(tau, [x, xd, xdd], which, fk, legs), rtol=0,
                                       atol=1e-8 * kappa * scale)
        assert np.abs(dq[:, legs:]).max() > 1e-3 * scale      # the wrist's own columns are not idle
        fq, fqd, ftau = forward_slopes(q, p, qw, xd[:3], xd[3:], effort[:3], effort[3:])
        kappa_M = float(np.linalg.cond(M))
        np.testing.assert_allclose(ftau @ M, np.eye(6), rtol=0, atol=64 * EPS * kappa_M)
        np.testing.assert_allclose(fq, _central(forward, [x, xd, effort], 0, fk, legs), rtol=0,
                                   atol=1e-8 * kappa * kappa_M * max(1.0, float(np.abs(xdd).max())))
        np.testing.assert_allclose(fqd, -ftau @ dqd, rtol=0, atol=64 * EPS * kappa_M * np.abs(ftau @ dqd).max())
        gravity = gravity_slope(q, p, qw)[0]
        gravity_scale = max(float(np.abs(G(q, p, qw)[0]).max()), float(np.abs(gravity).max()))
        np.testing.assert_allclose(gravity, _central(G, [x], 0, fk, legs), rtol=0,
                                   atol=1e-8 * kappa * gravity_scale)


def test_the_generated_numpy_and_c_functions_give_the_derivation(tmp_path):
    """The DELTA's three derivative functions derived with the numpy and C backends (every parameter folded) equal
    the un-optimized derivation at a state: to DYNAMICS of the scale, kappa_degree 5 of kappa(J) ~ 1."""
    from symkin import load, pipeline

    model = _model("delta")
    names = ["inverse_dynamics_derivatives", "forward_dynamics_derivatives", "gravity_derivatives"]
    request = pipeline.resolve_request(model, ",".join(["fk"] + names), "numpy,c", fixed="all")
    directory = pipeline.write(pipeline.generate(model, request), tmp_path)
    d = Derivation(model)
    q = home_joints(model) + np.array([0.1, -0.05, 0.12])
    p = reference_function(model, d["fk"])(q)[0]
    state = {"inverse_dynamics_derivatives": (np.array([0.5, -1.0, 0.8]), np.array([2.0, -3.0, 1.0])),
             "forward_dynamics_derivatives": (np.array([0.5, -1.0, 0.8]), np.array([0.1, 0.2, -0.1])),
             "gravity_derivatives": ()}
    for backend in ("numpy", "c"):
        delta = load(directory, backend)
        for name in names:
            want = reference_function(model, d[name])(q, p, *state[name])
            got = getattr(delta, name)(q, p, *state[name])
            got = (got,) if isinstance(got, np.ndarray) else got       # one output: the array itself
            for a, b in zip(got, want):
                scale = max(float(np.abs(b).max()), EPS)
                np.testing.assert_allclose(a, b, rtol=0, atol=DYNAMICS * 5 * scale)


def test_the_stewart_platforms_derivative_is_the_slope_along_its_inverse_kinematics():
    """models/stewart.yaml (six U-P-S legs, no closed-form fk): moving the pose p and the struts q = ik(p) together,
    d tau/dp = d tau/dq J^-1 (J^-1 the generated inverse Jacobian), against central differences of the derived tau
    at (ik(p +- h e_k), p +- h e_k); h = EPS^(1/3) max(1, |p_k|), 1e-8 of the scale times kappa(J^-1)."""
    model = load_model(MODELS_DIR / "stewart.yaml")
    d = Derivation(model)
    ik, inverse_jacobian, tau, slopes = (reference_function(model, d[k]) for k in (
        "ik", "inverse_jacobian", "inverse_dynamics", "inverse_dynamics_derivatives"))
    home = np.array([float(e.xreplace(model.parameter_values)) for e in model.parallel.home])
    p = home + np.array([0.01, -0.02, 0.015, 0.05, -0.04, 0.03])
    q = ik(p)[0]
    qd, qdd = np.array([0.05, -0.02, 0.03, 0.01, -0.04, 0.02]), np.array([0.3, -0.1, 0.2, -0.2, 0.1, 0.4])
    dq = slopes(q, p, qd, qdd)[0]
    J_inverse = inverse_jacobian(q, p)[0]
    columns = []
    for k in range(6):
        h = EPS ** (1 / 3) * max(1.0, abs(p[k]))
        sides = [tau(ik(p + sign * h * np.eye(6)[k])[0], p + sign * h * np.eye(6)[k], qd, qdd)[0] for sign in (1, -1)]
        columns.append((sides[0] - sides[1]) / (2 * h))
    slope = np.column_stack(columns)
    scale = max(float(np.abs(tau(q, p, qd, qdd)[0]).max()), float(np.abs(slope).max()))
    np.testing.assert_allclose(dq @ J_inverse, slope, rtol=0, atol=1e-8 * np.linalg.cond(J_inverse) * scale)
