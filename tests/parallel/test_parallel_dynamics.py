"""Dynamics of parallel mechanisms (issue 14): the DELTA and the Stewart platform of models/.

The references share no code with the derivation:

* Pinocchio: the DELTA as a tree closed by three point constraints (constraintDynamics, with the
  loop multipliers), the Stewart platform as a free-flying rigid body (rnea) pushed by its struts;
  both agree with symkin to a few eps (benchmarks/bench_parallel_dynamics.py prints the DELTA's
  difference; the tests assert the issue's 1e-9);
* the kinetic and potential energy of the bodies written out here from the model files' geometry
  (arm, elbow and platform positions of the DELTA by hand; the Stewart platform's attachment
  points from its leg angles), with velocities by central differences of the closed-form fk / ik
  and angular velocities from differences of the rotation matrix;
* the static balance of the DELTA at its home pose by rod tensions (a hand calculation);
* Lagrange's equations by differences of the generated mass matrix along the constraint manifold;
* the power balance d(k + u)/dt = tau . qd along motions planned in the task space and
  converted by ik, and the task-space form tau = J^T (Mx pdd + Vx + Gx);
* energy conservation of a free, frictionless simulation, to the integrator's tolerance.

Finite differences: a central difference with step h has truncation error ~ h^2 |f'''| / 6 and
rounding error ~ eps |f| / h; with h = 1e-5 on quantities of order one both are ~ 1e-10, so the
bounds below are 1e-7 relative (a thousand times that, for the constants of the derivatives).
Second differences (h = 1e-4) carry ~ eps |f| / h^2 ~ 2e-8: bounds 1e-5 relative.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import symkin
from conftest import MODELS_DIR, reference_function
from symkin.derivation import Derivation
from symkin.errors import DerivationError
from symkin.model import load_model
from tolerances import CLOSED_FORM, EPS

STEP = 1e-5
G = np.array([0.0, 0.0, -9.81])
NAMES = ("ik", "mass_matrix", "coriolis_vector", "gravity_vector", "inverse_dynamics",
         "forward_dynamics", "kinetic_energy", "potential_energy", "operational_space", "tcp_force_map")


def _values(model) -> dict[str, float]:
    return {s.name: float(v) for s, v in model.parameter_values.items()}


@pytest.fixture(scope="module", params=["delta", "stewart"])
def case(request, models, derivations):
    model, d = models[request.param], derivations[request.param]
    names = NAMES + (("fk",) if request.param == "delta" else ())
    functions = {name: reference_function(model, d[name]) for name in names}
    home = np.array([float(e.xreplace(model.parameter_values)) for e in model.parallel.home])
    return model, functions, home


def _poses(home: np.ndarray, rng: np.random.Generator, count: int) -> np.ndarray:
    spread = np.where(np.arange(len(home)) < 3, 0.02, 0.1)  # 2 cm and 0.1 rad around the home pose
    return home + rng.uniform(-1, 1, (count, len(home))) * spread


# --------------------------------------------------------------------------- independent body models

def _delta_points(v: dict[str, float], theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(arm centres of mass, elbows C_i, arm directions) of the DELTA (models/delta.yaml, by hand)."""
    phi = np.radians([0.0, 120.0, 240.0])
    radial = np.stack([np.cos(phi), np.sin(phi), np.zeros(3)], axis=1)
    arm = np.stack([np.cos(theta) * np.cos(phi), np.cos(theta) * np.sin(phi), np.sin(theta)], axis=1)
    A = v["r_base"] * radial
    return A + v["a"] / 2 * arm, A + v["a"] * arm, arm


def _delta_platform_joints(v: dict[str, float], P: np.ndarray) -> np.ndarray:
    phi = np.radians([0.0, 120.0, 240.0])
    return P + v["r_tcp"] * np.stack([np.cos(phi), np.sin(phi), np.zeros(3)], axis=1)


def _rotation(roll: float, pitch: float, yaw: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return Rz @ Ry @ Rx


def _stewart_platform_joints(v: dict[str, float], p: np.ndarray) -> np.ndarray:
    """B_i = P + R b_i with the platform angles of models/stewart.yaml's legs."""
    g = v["gamma_p"]
    angles = np.array([-np.pi / 3 + g, np.pi / 3 - g, np.pi / 3 + g, np.pi - g, np.pi + g, 5 * np.pi / 3 - g])
    b = v["r_p"] * np.stack([np.cos(angles), np.sin(angles), np.zeros(6)], axis=1)
    return p[:3] + b @ _rotation(*p[3:]).T


def reference_energies(model, f, q: np.ndarray, p: np.ndarray, qd: np.ndarray, pd: np.ndarray) -> tuple[float, float]:
    """(k, u) of the bodies declared in the model file, from positions written out here; velocities
    by central differences along the motion (p + t pd) or (q + t qd)."""
    v = _values(model)
    if model.name == "delta":
        def points(t):
            theta = q + t * qd
            com, elbow, _ = _delta_points(v, theta)
            P = f["fk"](theta)[0]
            return com, elbow, P
        (com, elbow, P), plus, minus = points(0.0), points(STEP), points(-STEP)
        rate = [(a - b) / (2 * STEP) for a, b in zip(plus, minus)]
        arm_inertia = v["m_arm"] * v["a"] ** 2 / 12 + v["gear"] ** 2 * v["J_rotor"]  # about the centre + rotor
        m_elbow = m_tip = v["m_rod"] / 2
        k = 0.5 * (v["m_arm"] * np.sum(rate[0] ** 2) + arm_inertia * qd @ qd + m_elbow * np.sum(rate[1] ** 2)
                   + (v["m_platform"] + 3 * m_tip) * rate[2] @ rate[2])
        u = -G @ (v["m_arm"] * com.sum(0) + m_elbow * elbow.sum(0) + v["m_platform"] * P
                  + m_tip * _delta_platform_joints(v, P).sum(0))
        return k, u
    m = v["m_platform"]
    r, t = v["r_disc"], v["t_disc"]
    inertia = np.diag([m * (r**2 / 4 + t**2 / 12)] * 2 + [m * r**2 / 2])
    R = _rotation(*p[3:])
    Rd = (_rotation(*(p + STEP * pd)[3:]) - _rotation(*(p - STEP * pd)[3:])) / (2 * STEP)
    W = R.T @ Rd  # skew: [w_body]x
    w = np.array([W[2, 1], W[0, 2], W[1, 0]])
    B = _stewart_platform_joints(v, p)
    Bd = (_stewart_platform_joints(v, p + STEP * pd) - _stewart_platform_joints(v, p - STEP * pd)) / (2 * STEP)
    gear = 2 * np.pi / v["lead"]
    m_tip = v["m_strut"] / 2
    k = 0.5 * (m * pd[:3] @ pd[:3] + w @ inertia @ w + m_tip * np.sum(Bd**2) + gear**2 * v["J_rotor"] * qd @ qd)
    u = -G @ (m * p[:3] + m_tip * B.sum(0))
    return k, u


def _motion(f, p: np.ndarray, pd: np.ndarray, pdd: np.ndarray, h: float):
    """q, qd, qdd of the platform path p + t pd + t^2/2 pdd at t = 0, by differences of ik with step h."""
    q = lambda t: f["ik"](p + t * pd + t * t / 2 * pdd)[0]  # noqa: E731
    q0, qp, qm = q(0.0), q(h), q(-h)
    return q0, (qp - qm) / (2 * h), (qp - 2 * q0 + qm) / h**2


# --------------------------------------------------------------------------- tests

def test_the_energies_are_those_of_the_declared_bodies(case):
    model, f, home = case
    rng = np.random.default_rng(1401)
    for p in _poses(home, rng, 5):
        pd = rng.uniform(-0.2, 0.2, len(p))
        q, qd, _ = _motion(f, p, pd, np.zeros_like(p), STEP)
        k_ref, u_ref = reference_energies(model, f, q, p, qd, pd)
        k = f["kinetic_energy"](q, p, qd)[0]
        M = f["mass_matrix"](q, p)[0]
        assert abs(k - k_ref) <= 1e-7 * k_ref, (model.name, k, k_ref)
        assert abs(0.5 * qd @ M @ qd - k) <= 1e-12 * k
        u = f["potential_energy"](q, p)[0]
        assert abs(u - u_ref) <= 64 * EPS * np.abs(u_ref) + 1e-12, (model.name, u, u_ref)
        assert np.allclose(M, M.T, rtol=0, atol=0)
        assert np.all(np.linalg.eigvalsh(M) > 0)


def test_gravity_is_the_gradient_of_the_potential_energy(case):
    """G . qd = du/dt along every motion: G = du/dq on the constraint manifold."""
    model, f, home = case
    rng = np.random.default_rng(1402)
    for p in _poses(home, rng, 4):
        G_vec = None
        for pd in np.eye(len(p)):
            q, qd, _ = _motion(f, p, pd, np.zeros_like(p), STEP)
            G_vec = f["gravity_vector"](q, p)[0]
            shifted = [p + s * STEP * pd for s in (1, -1)]
            u = [reference_energies(model, f, f["ik"](ps)[0], ps, qd, pd)[1] for ps in shifted]
            rate = (u[0] - u[1]) / (2 * STEP)
            assert abs(G_vec @ qd - rate) <= 1e-7 * (np.abs(G_vec) @ np.abs(qd)), (model.name, G_vec @ qd, rate)


def test_the_delta_hangs_at_home_by_its_rod_tensions(models, derivations):
    """Static balance at the home pose (0, 0, z), a hand calculation: by symmetry the three rods carry equal
    tensions t with 3 t e_z = -W (the platform side's weight W, e the rod direction from elbow to platform),
    and each actuator holds the moments of its arm's weight, the elbow mass and the rod tension about its axis."""
    model, d = models["delta"], derivations["delta"]
    v = _values(model)
    ik, gravity = (reference_function(model, d[n]) for n in ("ik", "gravity_vector"))
    P = np.array([0.0, 0.0, -0.15])
    theta = ik(P)[0]
    assert np.ptp(theta) <= 1e-12  # symmetric pose
    com, elbow, _ = _delta_points(v, theta)
    e = (_delta_platform_joints(v, P) - elbow) / v["b"]
    weight = (v["m_platform"] + 1.5 * v["m_rod"]) * 9.81
    tension = -weight / (3 * e[0, 2])
    phi = np.radians([0.0, 120.0, 240.0])
    axis = np.stack([np.sin(phi), -np.cos(phi), np.zeros(3)], axis=1)  # positive theta raises the arm
    A = v["r_base"] * np.stack([np.cos(phi), np.sin(phi), np.zeros(3)], axis=1)
    moment = (np.cross(com - A, v["m_arm"] * G) + np.cross(elbow - A, v["m_rod"] / 2 * G)
              + np.cross(elbow - A, tension * e))
    hold = -np.einsum("ij,ij->i", axis, moment)
    assert np.allclose(gravity(theta, P)[0], hold, rtol=64 * EPS, atol=0), (gravity(theta, P)[0], hold)


def test_the_delta_coriolis_vector_follows_from_its_mass_matrix(case):
    """Lagrange: V = dM/dt qd - 1/2 d(qd^T M qd)/dq with M(q) = mass_matrix(q, fk(q)), by differences."""
    model, f, home = case
    if model.name != "delta":
        pytest.skip("needs the closed-form fk (the Stewart platform's V is checked by the power balance)")
    rng = np.random.default_rng(1403)
    M = lambda q: f["mass_matrix"](q, f["fk"](q)[0])[0]  # noqa: E731
    for p in _poses(home, rng, 4):
        q, qd = f["ik"](p)[0], rng.uniform(-2, 2, 3)
        Mdot = (M(q + STEP * qd) - M(q - STEP * qd)) / (2 * STEP)
        dT = np.array([qd @ (M(q + STEP * e) - M(q - STEP * e)) @ qd / (2 * STEP) for e in np.eye(3)])
        V_ref = Mdot @ qd - dT / 2
        V = f["coriolis_vector"](q, p, qd)[0]
        assert np.allclose(V, V_ref, rtol=0, atol=1e-7 * np.abs(M(q)).max() * qd @ qd), (V, V_ref)


def test_power_balance_and_the_task_space_form(case):
    """Along a motion planned in the task space: tau . qd = d(k + u)/dt, tau = M qdd + V + G, the forward
    dynamics inverts it, and tau = J^T (Mx pdd + Vx + Gx)."""
    model, f, home = case
    rng = np.random.default_rng(1404)
    h = 1e-4
    for p in _poses(home, rng, 5):
        pd, pdd = rng.uniform(-0.3, 0.3, len(p)), rng.uniform(-3, 3, len(p))
        q, qd, qdd = _motion(f, p, pd, pdd, h)
        tau = f["inverse_dynamics"](q, p, qd, qdd)[0]
        M, V, G_vec = f["mass_matrix"](q, p)[0], f["coriolis_vector"](q, p, qd)[0], f["gravity_vector"](q, p)[0]
        scale = np.abs(M) @ np.abs(qdd) + np.abs(V) + np.abs(G_vec)
        assert np.all(np.abs(tau - (M @ qdd + V + G_vec)) <= 1e-12 * scale.max()), model.name
        kappa = np.linalg.cond(M)
        back = f["forward_dynamics"](q, p, qd, tau)[0]
        assert np.allclose(back, qdd, rtol=0, atol=64 * kappa * EPS * np.abs(qdd).max() * len(q))

        def energy(t):
            pt, pdt = p + t * pd + t * t / 2 * pdd, pd + t * pdd
            qt, qdt, _ = _motion(f, pt, pdt, pdd, STEP)
            return f["kinetic_energy"](qt, pt, qdt)[0] + f["potential_energy"](qt, pt)[0]
        power = (energy(h) - energy(-h)) / (2 * h)
        assert abs(tau @ qd - power) <= 1e-5 * (np.abs(tau) @ np.abs(qd)), (model.name, tau @ qd, power)

        Mx, Vx, Gx = f["operational_space"](q, p, qd)
        F = Mx @ pdd + Vx + Gx
        assert np.allclose(f["tcp_force_map"](q, p, F)[0], tau, rtol=0, atol=1e-5 * scale.max()), model.name


def test_a_free_frictionless_motion_keeps_its_energy(case):
    """Integrate the forward dynamics (DELTA: in q, p = fk(q)) or the task-space dynamics (Stewart: in p,
    q = ik(p)) without actuator efforts for 0.2 s; k + u stays constant to the integrator's tolerance."""
    model, f, home = case
    n = len(home)
    rtol = 1e-11

    if model.name == "delta":
        def state(y):
            q, qd = y[:n], y[n:]
            return q, f["fk"](q)[0], qd

        def rate(_t, y):
            q, p, qd = state(y)
            return np.concatenate([qd, f["forward_dynamics"](q, p, qd, np.zeros(n))[0]])
        y0 = np.concatenate([f["ik"](home)[0], [1.0, -0.5, 0.3]])
    else:
        def state(y):
            p, pd = y[:n], y[n:]
            q = f["ik"](p)[0]
            J_inv = np.array([(f["ik"](p + STEP * e)[0] - f["ik"](p - STEP * e)[0]) / (2 * STEP) for e in np.eye(n)]).T
            return q, p, J_inv @ pd

        def rate(_t, y):
            q, p, qd = state(y)
            Mx, Vx, Gx = f["operational_space"](q, p, qd)
            return np.concatenate([y[n:], np.linalg.solve(Mx, -Vx - Gx)])
        y0 = np.concatenate([home, [0.05, -0.02, 0.0, 0.1, 0.0, -0.1]])

    def energy(y):
        q, p, qd = state(y)
        return f["kinetic_energy"](q, p, qd)[0] + f["potential_energy"](q, p)[0]
    solution = solve_ivp(rate, (0.0, 0.2), y0, method="DOP853", rtol=rtol, atol=rtol * 1e-2, dense_output=False)
    assert solution.success
    energies = np.array([energy(y) for y in solution.y.T])
    kinetic = max(f["kinetic_energy"](*state(y))[0] for y in solution.y.T)
    potential = max(abs(f["potential_energy"](*state(y)[:2])[0]) for y in solution.y.T)
    # the local errors of ~len(t) steps, each <= rtol relative to the state, times the energy's scale; the
    # Stewart's state carries the rounding of the ik differences (eps / STEP ~ 2e-11 relative) in qd
    bound = 10 * len(solution.t) * (rtol + EPS / STEP) * (kinetic + potential)
    assert np.ptp(energies) <= bound, (model.name, np.ptp(energies), bound)


# --------------------------------------------------------------------------- Pinocchio as the closed-loop reference

def test_delta_forward_and_inverse_dynamics_match_pinocchio_constraint_dynamics(models, derivations):
    """At random states: symkin's forward dynamics (loop closure eliminated through J) against Pinocchio's
    constraintDynamics of the tree with three loop-closure constraints (multipliers, exact KKT solve, mu = 0;
    the tree is benchmarks/competitors.pinocchio_delta, which the benchmark times), and symkin's inverse
    dynamics at Pinocchio's accelerations gives back the efforts.  Both are solves with matrices of
    kappa <= 1e4 here (kappa eps ~ 2e-12): the issue's 1e-9 relative leaves room for the differences of
    two algorithms and is still seven orders below any modelling error."""
    pytest.importorskip("pinocchio")
    from benchmarks.competitors import constraint_dynamics_of, delta_tree_state, pinocchio_delta

    model, d = models["delta"], derivations["delta"]
    v = _values(model)
    pin, tree, constraints, legs = pinocchio_delta(v)
    data, datas, settings = constraint_dynamics_of(pin, tree, constraints)
    f = {name: reference_function(model, d[name]) for name in ("ik", "forward_dynamics", "inverse_dynamics")}
    rng = np.random.default_rng(1405)
    home = np.array([float(e.xreplace(model.parameter_values)) for e in model.parallel.home])
    for P in _poses(home, rng, 6):
        theta, theta_d, tau = f["ik"](P)[0], rng.uniform(-2, 2, 3), rng.uniform(-0.1, 0.1, 3)
        q, velocity, arms = delta_tree_state(pin, tree, data, legs, v, P, theta, theta_d)
        efforts = np.zeros(tree.nv)
        efforts[arms] = tau
        reference = pin.constraintDynamics(tree, data, q, velocity, efforts, constraints, datas, settings)[arms]
        qdd = f["forward_dynamics"](theta, P, theta_d, tau)[0]
        assert np.allclose(qdd, reference, rtol=0, atol=1e-9 * np.abs(reference).max()), (qdd, reference)
        back = f["inverse_dynamics"](theta, P, theta_d, reference)[0]
        assert np.allclose(back, tau, rtol=0, atol=1e-9 * np.abs(tau).max()), (back, tau)


def _with_rod_inertia(tmp_path, name: str, inertia: str):
    """models/<name>.yaml with ``inertia`` added to its rod (written to tmp_path)."""
    text = (MODELS_DIR / f"{name}.yaml").read_text()
    rod = re.search(r"^  rod: \{(.*)\}$", text, re.M)
    assert rod, f"models/{name}.yaml declares no rod"
    path = tmp_path / f"{name}.yaml"
    path.write_text(text.replace(rod.group(0), f"  rod: {{{rod.group(1)}, inertia: {inertia}}}"))
    return path


def test_a_delta_whose_rods_are_uniform_bars_matches_pinocchio_constraint_dynamics(tmp_path):
    """rod: inertia: m_rod b^2 / 12 (uniform bars instead of the lumped ends' m_rod b^2 / 4) against the same
    Pinocchio tree with that inertia across each rod (its universal joint lets it spin about its own axis, which
    carries no inertia: so the rod of the model); against the lumped ends the accelerations differ by 4e-2 relative."""
    pytest.importorskip("pinocchio")
    from benchmarks.competitors import constraint_dynamics_of, delta_tree_state, pinocchio_delta

    model = load_model(_with_rod_inertia(tmp_path, "delta", "m_rod*b^2/12"))
    delta = symkin.load(symkin.derive(model, tmp_path, outputs=["ik", "forward_dynamics", "inverse_dynamics"],
                                      backends=["numpy"]))
    v = _values(model)
    pin, tree, constraints, legs = pinocchio_delta(v, rod_inertia=v["m_rod"] * v["b"] ** 2 / 12)
    data, datas, settings = constraint_dynamics_of(pin, tree, constraints)
    rng = np.random.default_rng(1412)
    home = np.array([float(e.xreplace(model.parameter_values)) for e in model.parallel.home])
    for P in _poses(home, rng, 4):
        theta, theta_d, tau = delta.ik(P).joints, rng.uniform(-2, 2, 3), rng.uniform(-0.1, 0.1, 3)
        q, velocity, arms = delta_tree_state(pin, tree, data, legs, v, P, theta, theta_d)
        efforts = np.zeros(tree.nv)
        efforts[arms] = tau
        reference = pin.constraintDynamics(tree, data, q, velocity, efforts, constraints, datas, settings)[arms]
        qdd = delta.forward_dynamics(theta, P, theta_d, tau)
        assert np.allclose(qdd, reference, rtol=0, atol=1e-9 * np.abs(reference).max()), (qdd, reference)
        back = delta.inverse_dynamics(theta, P, theta_d, reference)
        assert np.allclose(back, tau, rtol=0, atol=1e-9 * np.abs(tau).max()), (back, tau)


def test_a_strut_of_changing_length_takes_no_inertia_of_its_own(tmp_path):
    model = load_model(_with_rod_inertia(tmp_path, "stewart", "m_strut*0.3^2/12"))
    with pytest.raises(DerivationError, match="rod changes its length"):
        Derivation(model)["mass_matrix"]


def test_stewart_inverse_dynamics_matches_pinocchio_rigid_body_and_strut_statics(models, derivations):
    """The Stewart platform with massless UPS struts: the platform (disc and the struts' halves at B_i) is a
    free-flying rigid body, so Pinocchio's rnea gives the wrench W the struts must exert on it for a motion
    (pose, twist, acceleration, gravity); a strut with a universal and a spherical joint pushes along itself,
    so its force f solves sum_i f_i [n_i; (B_i - P) x n_i] = W, and the actuator effort is
    tau_i = f_i + (2 pi / lead)^2 J_rotor l_i''.  The strut rates come from the motion by hand:
    l' = n . B', l'' = n . B'' + (|B'|^2 - (n . B')^2) / l.  symkin's inverse dynamics (in q, p, qd, qdd:
    no Euler rates enter) and its forward dynamics must agree with it."""
    pin = pytest.importorskip("pinocchio")
    model, d = models["stewart"], derivations["stewart"]
    v = _values(model)
    f = {name: reference_function(model, d[name]) for name in ("inverse_dynamics", "forward_dynamics")}
    m, r, t = v["m_platform"], v["r_disc"], v["t_disc"]
    platform = pin.Inertia(m, np.zeros(3), np.diag([m * (r**2 / 4 + t**2 / 12)] * 2 + [m * r**2 / 2]))
    body_points = _stewart_platform_joints(v, np.zeros(6))               # b_i in platform axes
    for b in body_points:
        platform += pin.Inertia(v["m_strut"] / 2, b, np.zeros((3, 3)))
    tree = pin.Model()
    frame = tree.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "platform")
    tree.appendBodyToJoint(frame, platform, pin.SE3.Identity())
    data = tree.createData()
    g = v["gamma_b"]
    base_angles = np.array([-g, g, 2 * np.pi / 3 - g, 2 * np.pi / 3 + g, 4 * np.pi / 3 - g, 4 * np.pi / 3 + g])
    A = v["r_b"] * np.stack([np.cos(base_angles), np.sin(base_angles), np.zeros(6)], axis=1)
    reflected = (2 * np.pi / v["lead"]) ** 2 * v["J_rotor"]
    rng = np.random.default_rng(1406)
    for p in _poses(np.array([0, 0, 0.23, 0, 0, 0]), rng, 6):
        R = _rotation(*p[3:])
        w, vel = rng.uniform(-1, 1, 3), rng.uniform(-0.3, 0.3, 3)            # angular, origin velocity (world)
        alpha, acc = rng.uniform(-5, 5, 3), rng.uniform(-2, 2, 3)
        arm = body_points @ R.T                                               # B_i - P
        B = p[:3] + arm
        Bd = vel + np.cross(w, arm)
        Bdd = acc + np.cross(alpha, arm) + np.cross(w, np.cross(w, arm))
        length = np.linalg.norm(B - A, axis=1)
        n = (B - A) / length[:, None]
        ld = np.einsum("ij,ij->i", n, Bd)
        ldd = np.einsum("ij,ij->i", n, Bdd) + (np.sum(Bd**2, axis=1) - ld**2) / length
        # Pinocchio's free flyer: local twist, spatial acceleration (classical minus w x v), wrench on the body
        wl, vl = R.T @ w, R.T @ vel
        q_ff = np.concatenate([p[:3], pin.Quaternion(R).coeffs()])
        a_ff = np.concatenate([R.T @ acc - np.cross(wl, vl), R.T @ alpha])
        wrench = pin.rnea(tree, data, q_ff, np.concatenate([vl, wl]), a_ff)
        struts = np.vstack([R.T @ n.T, R.T @ np.cross(arm, n).T])          # unit strut forces, body axes
        tau_ref = np.linalg.solve(struts, wrench) + reflected * ldd
        tau = f["inverse_dynamics"](length, p, ld, ldd)[0]
        assert np.allclose(tau, tau_ref, rtol=0, atol=1e-9 * np.abs(tau_ref).max()), (tau, tau_ref)
        qdd = f["forward_dynamics"](length, p, ld, tau_ref)[0]
        assert np.allclose(qdd, ldd, rtol=0, atol=1e-9 * np.abs(ldd).max()), (qdd, ldd)


def test_symkin_quantities_lists_the_dynamics_of_parallel_models(capsys):
    from symkin.cli import main
    assert main(["quantities"]) == 0
    parallel = {line.split()[0] for line in capsys.readouterr().out.splitlines() if " parallel " in line}
    assert {"mass_matrix", "coriolis_vector", "gravity_vector", "friction", "inverse_dynamics", "forward_dynamics",
            "operational_space", "kinetic_energy", "potential_energy", "tcp_force_map"} <= parallel


#: Actuator friction on the DELTA (illustrative coefficients: viscous N m s/rad, Coulomb N m, v_s rad/s).
FRICTION = """
friction:
  theta1: {viscous: 0.002, coulomb: 0.005, smoothing_velocity: 0.05}
  theta2: {viscous: 0.002, coulomb: 0.005}
"""


def test_actuator_friction_enters_the_dynamics_of_a_parallel_model(models, derivations):
    """F_f = viscous qd + coulomb tanh(qd / v_s) (or sign(qd)) per actuator, none on theta3: the inverse dynamics
    gains exactly F_f, the friction output is F_f, and the forward dynamics inverts the inverse dynamics."""
    from symkin.derivation import Derivation
    from symkin.model import model_from_text
    from conftest import MODELS_DIR

    model = model_from_text((MODELS_DIR / "delta.yaml").read_text() + FRICTION, "delta", "delta.yaml")
    d = Derivation(model)
    f = {name: reference_function(model, d[name])
         for name in ("ik", "friction", "mass_matrix", "inverse_dynamics", "forward_dynamics")}
    plain = reference_function(models["delta"], derivations["delta"]["inverse_dynamics"])
    rng = np.random.default_rng(1407)
    home = np.array([0.0, 0.0, -0.15])
    for p in _poses(home, rng, 4):
        q, qd, qdd = f["ik"](p)[0], rng.uniform(-1, 1, 3), rng.uniform(-5, 5, 3)
        expected = np.array([0.002 * qd[0] + 0.005 * np.tanh(qd[0] / 0.05), 0.002 * qd[1] + 0.005 * np.sign(qd[1]),
                             0.0])
        assert np.allclose(f["friction"](qd)[0], expected, rtol=CLOSED_FORM, atol=0)
        tau = f["inverse_dynamics"](q, p, qd, qdd)[0]
        difference = tau - plain(q, p, qd, qdd)[0]
        assert np.allclose(difference, expected, rtol=0, atol=64 * EPS * np.abs(tau).max()), (difference, expected)
        back = f["forward_dynamics"](q, p, qd, tau)[0]
        kappa = np.linalg.cond(f["mass_matrix"](q, p)[0])  # a backward-stable solve: kappa eps, times n and slack
        assert np.allclose(back, qdd, rtol=0, atol=64 * kappa * EPS * np.abs(qdd).max() * len(q))
