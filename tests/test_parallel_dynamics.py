"""Dynamics of parallel mechanisms (issue 14): the DELTA and the Stewart platform of models/.

The references share no code with the derivation:

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

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from conftest import reference_function
from tolerances import EPS

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
        assert np.allclose(M, M.T, rtol=0, atol=0) and np.all(np.linalg.eigvalsh(M) > 0)


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
