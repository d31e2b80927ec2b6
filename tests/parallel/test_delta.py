"""The haptic DELTA (models/delta.yaml): closed-form IK and FK, Jacobians and both singularity types.

Independent oracles: the seed's geometry (sec. 3.2.1) written out here with numpy, the
seed's own equations (symbolically), finite differences of the generated FK.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy

from symkin import load
from symkin.model import coordinates
from tolerances import CLOSED_FORM, DELTA_SCALE, KINEMATICS

PHI = np.deg2rad([0.0, 120.0, 240.0])
E = np.stack([np.cos(PHI), np.sin(PHI), np.zeros(3)], axis=-1)  # radial unit vectors e_i
Z = np.array([0.0, 0.0, 1.0])


@pytest.fixture(scope="module")
def delta(generated_dir):
    return load(generated_dir / "delta")


@pytest.fixture(scope="module")
def dims(models):
    return {p.name: float(p.value) for p in models["delta"].parameters}


def elbows(theta, d):
    """C_i = A_i + a (cos theta_i e_i + sin theta_i z) (seed: base_T_A_i A_i_T_C_i)."""
    th = np.asarray(theta)[..., None]
    return (d["r_base"] + d["a"] * np.cos(th)) * E + d["a"] * np.sin(th) * Z


def platform_joints(p, d):
    """B_i = P + r_tcp e_i."""
    return np.asarray(p)[..., None, :] + d["r_tcp"] * E


def knee_out(theta, p, d):
    """True where every leg has its knee outwards: B_i at a negative rotation about -y_Ai from C_i."""
    A = d["r_base"] * E
    C, B = elbows(theta, d), platform_joints(p, d)
    axis = -np.cross(Z, E)  # -y_Ai
    return np.all(np.einsum("...ij,ij->...i", np.cross(C - A, B - A), axis) < 0, axis=-1)


def below_elbows(p, theta, d):
    """True where the TCP is on the side of the sphere-centre plane opposite to n = (S2 - S1) x (S3 - S1)."""
    S = elbows(theta, d) - d["r_tcp"] * E
    n = np.cross(S[..., 1, :] - S[..., 0, :], S[..., 2, :] - S[..., 0, :])
    return np.einsum("...i,...i->...", np.asarray(p) - S[..., 0, :], n) < 0


def reachable_points(delta, d, rng, count, min_margin=1e-6):
    """Random TCP positions in a box around the workspace where IK and FK modes agree.

    Points whose relative IK margin is below ``min_margin`` (within about 1e-7 m of the reach
    of a leg) are left out: there a leg is almost stretched or folded (boundary singularity),
    the angle's condition number grows like 1/sqrt(margin), and rounding alone exceeds 1e-12.
    """
    p = rng.uniform([-0.08, -0.08, -0.22], [0.08, 0.08, -0.03], (count, 3))
    with np.errstate(invalid="ignore"):
        ik = delta.ik(p)
    ok = np.all(ik.margin >= min_margin * (d["a"] * d["b"]) ** 2, axis=-1)
    p, theta = p[ok], ik.joints[ok]
    keep = below_elbows(p, theta, d)
    return p[keep], theta[keep]


def test_fk_of_ik_is_the_identity_on_thousands_of_points(delta, dims):
    p, theta = reachable_points(delta, dims, np.random.default_rng(11), 6000)
    assert len(p) > 3000
    fk = delta.fk(theta)
    assert np.all(fk.margin >= 0)
    np.testing.assert_allclose(fk.position, p, rtol=0, atol=1e-12)
    # The solutions are geometric: every rod has length b, every knee points outwards.
    rods = np.linalg.norm(platform_joints(p, dims) - elbows(theta, dims), axis=-1)
    # the rod length is the residual of the IK's equation |B - C(theta)| = b: backward stable (an error
    # in theta of EPS x its condition number moves the rod by EPS x the scale), KINEMATICS of the reach
    np.testing.assert_allclose(rods, dims["b"], rtol=0, atol=KINEMATICS * DELTA_SCALE)
    assert np.all(knee_out(theta, p, dims))


def test_ik_of_fk_is_the_identity_on_thousands_of_configurations(delta, dims):
    rng = np.random.default_rng(12)
    theta = rng.uniform(np.deg2rad(-80), np.deg2rad(80), (6000, 3))
    fk = delta.fk(theta)
    valid = fk.margin >= 0
    p = fk.position[valid]
    theta = theta[valid]
    margin = delta.ik(p).margin / (dims["a"] * dims["b"]) ** 2
    mode = knee_out(theta, p, dims) & np.all(margin > 1e-6, axis=-1)  # IK gives knee-out (see reachable_points)
    assert mode.sum() > 3000
    back = delta.ik(p[mode]).joints
    np.testing.assert_allclose(np.angle(np.exp(1j * (back - theta[mode]))), 0, atol=1e-12)
    # Where the configuration has a knee inwards, IK gives the other (knee-out) solution of the same p.
    other = delta.ik(p[~mode])
    np.testing.assert_allclose(delta.fk(other.joints).position, p[~mode], atol=1e-12)


def test_no_real_solution_gives_nan_and_a_negative_margin(delta, dims):
    far = np.array([[0.0, 0.0, -0.5], [0.3, 0.0, -0.1]])  # beyond a + b from the base
    with np.errstate(invalid="ignore"):
        ik = delta.ik(far)
    assert np.all(np.any(ik.margin < 0, axis=-1))
    assert np.array_equal(np.isnan(ik.joints), ik.margin < 0)
    theta = np.random.default_rng(18).uniform(-np.pi, np.pi, (400, 3))
    with np.errstate(invalid="ignore"):
        fk = delta.fk(theta)
    none = fk.margin < 0
    assert 20 < none.sum() < 380
    assert np.all(np.isnan(fk.position[none]))
    assert np.all(np.isfinite(fk.position[~none]))
    rods = np.linalg.norm(platform_joints(fk.position[~none], dims) - elbows(theta[~none], dims), axis=-1)
    np.testing.assert_allclose(rods, dims["b"], atol=1e-12)
    # Independently: the circle where spheres 1 and 2 meet never reaches sphere 3 (or they do not meet).
    S = elbows(theta[none], dims) - dims["r_tcp"] * E
    t = np.linspace(0, 2 * np.pi, 20001)
    for s1, s2, s3 in S[:40]:
        axis = s2 - s1
        d12 = np.linalg.norm(axis)
        along = d12 / 2  # equal radii b: the circle lies halfway
        if d12 > 2 * dims["b"]:
            continue
        radius = np.sqrt(dims["b"] ** 2 - along**2)
        e1 = np.cross(axis, [1.0, 0.3, 0.1])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(axis / d12, e1)
        circle = s1 + along * axis / d12 + radius * (np.cos(t)[:, None] * e1 + np.sin(t)[:, None] * e2)
        assert np.min(np.abs(np.linalg.norm(circle - s3, axis=-1) - dims["b"])) > 1e-9


def test_knee_out_is_the_elbow_farther_from_the_axis(delta, dims):
    p = np.array([0.02, -0.01, -0.15])
    theta = delta.ik(p).joints
    radial = np.linalg.norm(elbows(theta, dims)[:, :2], axis=-1)
    # The other root of each leg: reflect C_i about the line A_i B_i' in the leg plane.
    A = dims["r_base"] * E
    B = platform_joints(p, dims)
    for i in range(3):
        rel = B[i] - A[i]
        x, z = rel @ E[i], rel[2]
        K = (rel @ rel + dims["a"] ** 2 - dims["b"] ** 2) / (2 * dims["a"])
        psi, delta_angle = np.arctan2(z, x), np.arccos(K / np.hypot(x, z))
        roots = [psi + delta_angle, psi - delta_angle]
        chosen = min(roots, key=lambda r: abs(np.angle(np.exp(1j * (r - theta[i])))))
        other = roots[1] if chosen is roots[0] else roots[0]
        other_radial = dims["r_base"] + dims["a"] * np.cos(other)
        assert radial[i] > other_radial


def test_jacobian_matches_finite_differences_of_fk(delta, dims):
    p, theta = reachable_points(delta, dims, np.random.default_rng(13), 400)
    J = delta.jacobian(theta, p)
    h = 1e-6
    for j in range(3):
        step = np.zeros(3)
        step[j] = h
        fd = (delta.fk(theta + step).position - delta.fk(theta - step).position) / (2 * h)
        np.testing.assert_allclose(J[:, :, j], fd, rtol=0, atol=1e-7 * np.max(np.abs(J)))
    # Velocity relation J_x pdot = J_q thetadot and J^-1 = J_q^-1 J_x.
    jac = delta.constraint_jacobians(theta, p)
    # J = J_x^-1 J_q solved by LU: backward stable, the product's residual within KINEMATICS of |J_q| <= 1 m
    np.testing.assert_allclose(jac.J_x @ J, jac.J_q, rtol=0, atol=KINEMATICS * DELTA_SCALE)
    np.testing.assert_allclose(delta.inverse_jacobian(theta, p) @ J, np.broadcast_to(np.eye(3), J.shape), atol=1e-9)


def _normalized_dets(delta, dims, theta, p):
    s = delta.singularities(theta, p)
    return s.det_Jq / (dims["a"] * dims["b"]) ** 3, s.det_Jx / dims["b"] ** 3


def test_boundary_singularities_zero_det_Jq_only(delta, dims):
    """A stretched leg (rod continuing its arm) or a folded one (rod back over it): B_1 = A_1 + (a +- b) u
    with the arm along u; the other legs from IK.  Workspace-boundary singularity (seed sec. 4.2)."""
    rng = np.random.default_rng(14)
    found = {"stretched": 0, "folded": 0}
    for kind, reach, angles in (("stretched", dims["a"] + dims["b"], (-2.8, -1.6)),
                                ("folded", dims["a"] - dims["b"], (0.3, 2.8))):
        for t1 in rng.uniform(*angles, 100):
            u = np.cos(t1) * E[0] + np.sin(t1) * Z
            p = dims["r_base"] * E[0] + reach * u - dims["r_tcp"] * E[0]
            with np.errstate(invalid="ignore"):
                ik = delta.ik(p)
            if np.any(ik.margin[1:] <= 0):
                continue
            theta = ik.joints.copy()
            theta[0] = t1
            assert np.linalg.norm(platform_joints(p, dims)[0] - elbows(theta, dims)[0]) == pytest.approx(dims["b"])
            det_q, det_x = _normalized_dets(delta, dims, theta, p)
            # det J_q = prod of three leg terms, one of them a vanishing cross product of lengths <= a + b:
            # its rounding is KINEMATICS of the normalized terms (<= 1)
            assert abs(det_q) < KINEMATICS
            assert abs(det_x) > 1e-3
            found[kind] += 1
    assert min(found.values()) > 30, found


def test_interior_singularities_zero_det_Jx_only(delta, dims):
    """Equal arm angles with cos(theta) = (r_tcp - r_base)/a put the three sphere centres on one point:
    all rods are parallel (to any unit w) and the platform can move on a sphere (interior singularity)."""
    h = np.sqrt(dims["a"] ** 2 - (dims["r_base"] - dims["r_tcp"]) ** 2)
    theta = np.full(3, np.arctan2(h, dims["r_tcp"] - dims["r_base"]))
    rng = np.random.default_rng(15)
    w = rng.normal(size=(100, 3))
    w /= np.linalg.norm(w, axis=-1, keepdims=True)
    p = np.array([0, 0, h]) - dims["b"] * w
    # points and rods built by closed forms of the scale b (CLOSED_FORM); det J_x of three rods that are
    # parallel up to that rounding, normalized by b^3: KINEMATICS
    np.testing.assert_allclose(np.linalg.norm(platform_joints(p, dims) - elbows(theta, dims), axis=-1),
                               dims["b"], rtol=0, atol=CLOSED_FORM * DELTA_SCALE)
    det_q, det_x = _normalized_dets(delta, dims, np.broadcast_to(theta, p.shape), p)
    assert np.max(np.abs(det_x)) < KINEMATICS
    assert np.min(np.abs(det_q)[np.abs(w[:, 2]) > 0.3]) > 1e-4


def test_coplanar_rods_are_interior_singular(delta, dims):
    """With longer arms (a = 0.12) the rods can lie horizontal, in one plane, with the TCP at elbow height."""
    a = 0.12
    wide = delta.bind(a=a)
    theta = np.full(3, np.arccos((dims["b"] + dims["r_tcp"] - dims["r_base"]) / a))
    p = np.array([0.0, 0.0, a * np.sin(theta[0])])
    # the constraints are squared lengths (m^2, terms <= 0.1 m^2) that vanish here; det J_x is a triple
    # product of rods (terms <= b^3 = 3.4e-3 m^3) that vanishes: both at the rounding of their terms
    assert wide.constraints(theta, p) == pytest.approx(np.zeros(3), abs=KINEMATICS * 0.1)
    s = wide.singularities(theta, p)
    assert abs(s.det_Jx) < KINEMATICS * dims["b"] ** 3
    assert abs(s.det_Jq) > 1e-9


def test_regular_points_are_not_singular(delta, dims):
    p, theta = reachable_points(delta, dims, np.random.default_rng(16), 3000)
    margins = delta.ik(p).margin / (dims["a"] * dims["b"]) ** 2
    interior = np.all(margins > 0.05, axis=-1)  # away from the reach of every leg
    det_q, det_x = _normalized_dets(delta, dims, theta[interior], p[interior])
    assert interior.sum() > 1000
    assert np.min(np.abs(det_q)) > 1e-4
    assert np.min(np.abs(det_x)) > 1e-3


def test_leg_equation_is_the_seed_sphere_about_the_virtual_frame(models, derivations):
    """f_i = ((x - x_C'i)^2 + (y - y_C'i)^2 + (z - z_C'i)^2 - b^2)/2 with C'_i from the seed's matrices (sec. 3.2.1)."""
    model = models["delta"]
    f = derivations["delta"]["constraint_vector"]
    sym = {p.name: p.symbol for p in model.parameters}
    x, y, z = sympy.symbols("x y z", real=True)
    thetas = coordinates.symbols(model, "q")
    for i, theta in enumerate(thetas):
        phi = sympy.Rational(2, 3) * sympy.pi * i
        c, s = sympy.cos(-phi), sympy.sin(-phi)
        base_T_A = sympy.Matrix([[c, s, 0, sym["r_base"] * c], [-s, c, 0, -sym["r_base"] * s], [0, 0, 1, 0],
                                 [0, 0, 0, 1]])  # the seed's matrix, as printed
        A_T_C = sympy.Matrix([[1, 0, 0, sym["a"] * sympy.cos(theta)], [0, 1, 0, 0],
                              [0, 0, 1, sym["a"] * sympy.sin(theta)], [0, 0, 0, 1]])
        C_T_Cp = sympy.Matrix([[1, 0, 0, -sym["r_tcp"]], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
        Cp = (base_T_A * A_T_C * C_T_Cp)[:3, 3]
        sphere = ((x - Cp[0]) ** 2 + (y - Cp[1]) ** 2 + (z - Cp[2]) ** 2 - sym["b"] ** 2) / 2
        assert sympy.simplify(sympy.expand(f[i] - sphere)) == 0


def test_ik_agrees_with_seed_eqs_8_18_and_8_19(delta, dims):
    """With theta_1 from symkin's IK, the seed's theta_3 = acos(y_B/b) (8.18) and theta_2 of (8.19) (one of
    its two signs) reproduce B in the A_i frame through the seed's A_i_T_B_i; eq. 8.20 is not needed."""
    p, theta = reachable_points(delta, dims, np.random.default_rng(17), 300)
    a, b = dims["a"], dims["b"]
    for i in range(3):
        rel = platform_joints(p, dims)[:, i] - dims["r_base"] * E[i]
        xB, yB, zB = rel @ E[i], rel @ np.cross(Z, E[i]), rel[:, 2]
        t3 = np.arccos(yB / b)
        t2 = np.arccos((xB**2 + yB**2 + zB**2 - a**2 - b**2) / (2 * a * b * np.sin(t3)))
        t1 = theta[:, i]
        errors = []
        for sign in (1, -1):
            x = a * np.cos(t1) + b * np.sin(t3) * np.cos(t1 + sign * t2)
            z = a * np.sin(t1) + b * np.sin(t3) * np.sin(t1 + sign * t2)
            errors.append(np.hypot(x - xB, z - zB))
        assert np.max(np.min(errors, axis=0)) < 1e-12
