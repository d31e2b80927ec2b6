"""A planar 3-RRR (p = x, y, yaw): three RRR legs whose last joints sit at the corners of a triangular platform.

The geometry and masses are those of Nopour, Aghdam and Taghvaeipour's 3-RRR (R. Nopour, M. M. Aghdam,
A. Taghvaeipour, "Nonlinear analysis of flexible parallel mechanisms through Bezier-based integration", Springer
2024, and ICRoM 2022/2023; the rigid model of github.com/nopour/3RRR-mechanism, RIGID/Run.m): an equilateral base
of side b = 0.9 m and platform of side a = 0.08 m, both centred on their origins, proximal and distal links of
0.4 m, the proximal links aluminium bars of 23 x 6 mm (2740 kg/m^3), the distal links steel bars of 23 x 2 mm
(7801 kg/m^3), the platform 0.1898 kg.

Independent oracles: each leg's ik by the law of cosines written here (the elbow on the circle about the motor
axis, at the distal length from the platform corner), the platform pose recovered from Newton's fk, finite
differences of that closed form for the Jacobian, the mobility of a planar mechanism (eq. 8.2 with lambda = 3),
and M and the inverse dynamics against MuJoCo's tree of the three chains closed by two point constraints.
"""

from __future__ import annotations

import numpy as np
import pytest

from mujoco_reference import MUJOCO_AGREEMENT, TINY_INERTIA, TINY_MASS, reduced_dynamics
from symkin import load, load_model, pipeline
from symkin.model.schema import PlatformMotion
from symkin.runtime.parallel import solve_fk
from symkin.structure.mobility import model_mobility
from tolerances import KINEMATICS, NEWTON

B_SIDE, A_SIDE, L_PROX, L_DIST = 0.9, 0.08, 0.4, 0.4
M_PROX, M_DIST, M_PLATFORM = 2740 * 0.023 * 0.006 * L_PROX, 7801 * 0.023 * 0.002 * L_DIST, 0.1898
#: the corners of an equilateral triangle of unit side about its centre, counter-clockwise from the lower left
CORNERS = np.array([[-0.5, -np.sqrt(3) / 6], [0.5, -np.sqrt(3) / 6], [0.0, np.sqrt(3) / 3]])

MODEL = f"""
name: planar_3rrr
description: Planar 3-RRR of Nopour, Aghdam and Taghvaeipour (2022-2024).
parameters:
  b: {{value: {B_SIDE}, unit: m, doc: side of the base triangle}}
  a: {{value: {A_SIDE}, unit: m, doc: side of the platform triangle}}
  l1: {{value: {L_PROX}, unit: m, doc: proximal link}}
  l2: {{value: {L_DIST}, unit: m, doc: distal link}}
  m1: {{value: {M_PROX!r}, unit: kg, doc: proximal link (aluminium 23 x 6 mm)}}
  m2: {{value: {M_DIST!r}, unit: kg, doc: distal link (steel 23 x 2 mm)}}
  me: {{value: {M_PLATFORM}, unit: kg, doc: platform}}
gravity: [0, 0, -9.81]
bodies:
  platform: {{mass: me, inertia: {{xx: me*a^2/24, yy: me*a^2/24, zz: me*a^2/12}}}}
  actuated_link: {{mass: m1, com: [l1/2, 0, 0], inertia: {{yy: m1*l1^2/12, zz: m1*l1^2/12}}}}
  rod: {{mass: m2, platform_fraction: 1/2}}
parallel:
  motion: [x, y, yaw]
  chains:
    rrr:
      - {{name: theta, type: R, axis: [0, 0, 1], active: true}}
      - {{name: elbow, type: R, axis: [0, 0, 1], origin: {{xyz: [l1, 0, 0]}}}}
      - {{name: corner, type: R, axis: [0, 0, 1], origin: {{xyz: [l2, 0, 0]}}}}
  legs:
    - {{name: leg1, chain: rrr, base: {{xyz: [-b/2, -sqrt(3)*b/6, 0]}}, platform: {{xyz: [-a/2, -sqrt(3)*a/6, 0]}},
        ik_branch: positive}}
    - {{name: leg2, chain: rrr, base: {{xyz: [b/2, -sqrt(3)*b/6, 0]}}, platform: {{xyz: [a/2, -sqrt(3)*a/6, 0]}},
        ik_branch: positive}}
    - {{name: leg3, chain: rrr, base: {{xyz: [0, sqrt(3)*b/3, 0]}}, platform: {{xyz: [0, sqrt(3)*a/3, 0]}},
        ik_branch: positive}}
  home: [0, 0, 0]
scene:
  outputs: [ik, jacobian, inverse_jacobian, singularities, constraints, constraint_jacobians, mass_matrix,
            inverse_dynamics]
  backends: [numpy]
"""


@pytest.fixture(scope="module")
def rrr(tmp_path_factory):
    directory = tmp_path_factory.mktemp("planar_3rrr")
    (directory / "planar_3rrr.yaml").write_text(MODEL)
    model = load_model(directory / "planar_3rrr.yaml")
    pipeline.write(pipeline.generate(model, pipeline.resolve_request(model)), directory / "out")
    return model, load(directory / "out" / "planar_3rrr", backend="numpy")


def corners(p):
    """B_i = (x, y) + R(yaw) a c_i: the platform corners (..., 3, 2)."""
    x, y, yaw = np.moveaxis(np.asarray(p, dtype=float), -1, 0)
    c, s = np.cos(yaw)[..., None], np.sin(yaw)[..., None]
    local = A_SIDE * CORNERS
    return np.stack([x[..., None] + c * local[:, 0] - s * local[:, 1],
                     y[..., None] + s * local[:, 0] + c * local[:, 1]], axis=-1)


def ik_by_the_law_of_cosines(p, side=1):
    """theta_i = atan2(d) + side * acos((l1^2 + |d|^2 - l2^2) / (2 l1 |d|)), d = B_i - A_i: the elbow on the
    circle of radius l1 about the motor axis A_i at l2 from the corner B_i, on the side ``side`` of A_i -> B_i."""
    d = corners(p) - B_SIDE * CORNERS
    distance = np.linalg.norm(d, axis=-1)
    return np.arctan2(d[..., 1], d[..., 0]) + side * np.arccos(
        (L_PROX**2 + distance**2 - L_DIST**2) / (2 * L_PROX * distance))


def poses(seed, count):
    rng = np.random.default_rng(seed)
    return np.stack([rng.uniform(-0.1, 0.1, count), rng.uniform(-0.1, 0.1, count),
                     rng.uniform(-0.5, 0.5, count)], axis=-1)


def wrapped(angles):
    return np.angle(np.exp(1j * angles))


def test_the_model_is_planar_with_three_coordinates_and_mobility_three(rrr):
    model, _ = rrr
    assert model.parallel.motion is PlatformMotion.PLANAR
    assert model.parallel.coordinates == ("x", "y", "yaw")
    report = model_mobility(model)
    # 3 legs x 2 links + the platform = 7 moving bodies and the base, 9 revolute joints: 3 (8 - 1 - 9) + 9 = 3
    assert (report.lam, report.bodies, report.joints) == (3, 8, 9)
    assert report.mobility == report.intended == 3


def test_every_legs_inverse_kinematics_is_in_closed_form(rrr):
    _, generated = rrr
    p = poses(1, 200)
    expected = ik_by_the_law_of_cosines(p)
    branch_of = {1: expected, -1: ik_by_the_law_of_cosines(p, side=-1)}
    q = generated.ik(p).joints
    # the model's positive branch is one of the two elbows per leg; which one is fixed by the sign convention of
    # symkin's distance form, the same for every leg
    side = 1 if np.max(np.abs(wrapped(q - branch_of[1]))) < np.max(np.abs(wrapped(q - branch_of[-1]))) else -1
    assert np.max(np.abs(wrapped(q - branch_of[side]))) <= KINEMATICS * 10


def test_newtons_forward_kinematics_returns_the_pose(rrr):
    _, generated = rrr
    p = poses(2, 50)
    q = generated.ik(p).joints
    report = solve_fk(generated, q, np.zeros(3))
    assert report.all_converged
    kappa = np.linalg.cond(generated.inverse_jacobian(q, p))
    assert np.all(np.max(np.abs(report.solution - p), axis=-1) <= NEWTON * kappa)


def test_the_jacobian_is_the_derivative_of_the_pose_along_the_actuators(rrr):
    """J (pd = J qd) against central differences of Newton's fk (h = 1e-6, truncation ~h^2, its own rounding
    ~eps kappa / h)."""
    _, generated = rrr
    p = np.array([0.03, -0.02, 0.2])
    q = generated.ik(p).joints
    h = 1e-6
    columns = [(solve_fk(generated, q + h * e, p).solution - solve_fk(generated, q - h * e, p).solution) / (2 * h)
               for e in np.eye(3)]
    J = generated.jacobian(q, p)
    np.testing.assert_allclose(J, np.array(columns).T, atol=1e-7 * np.abs(J).max())


def mujoco_three_rrr():
    """The 3-RRR as MuJoCo sees it: three hinge chains in the plane, the proximal links uniform bars, the distal
    links massless with half their mass at the elbow (welded to the proximal link) and half at the corner, the
    platform (with the corners' masses) on leg 1's last joint, legs 2 and 3 ending on the platform's corners by
    point constraints (connect)."""
    import mujoco

    bar = M_PROX * L_PROX**2 / 12
    point = f'diaginertia="{TINY_INERTIA} {TINY_INERTIA} {TINY_INERTIA}"'
    local = A_SIDE * CORNERS
    platform_mass = M_PLATFORM + 3 * M_DIST / 2
    first = local[0]
    # the platform body sits at corner 1 (leg 1's last joint); its centre and the other corners relative to it
    centre = -first
    inertia = M_PLATFORM * A_SIDE**2 / 12 + M_PLATFORM * centre @ centre + \
        sum(M_DIST / 2 * (c - first) @ (c - first) for c in local)
    com = (M_PLATFORM * centre + sum(M_DIST / 2 * (c - first) for c in local)) / platform_mass
    inertia -= platform_mass * com @ com  # about the centre of mass, as MuJoCo takes it
    sites = "".join(f'<site name="corner{k + 1}" pos="{c[0] - first[0]:.17g} {c[1] - first[1]:.17g} 0"/>'
                    for k, c in enumerate(local))
    legs = []
    for k in range(3):
        A = B_SIDE * CORNERS[k]
        end = (f'<body name="platform" pos="{L_DIST} 0 0"><joint name="corner1" type="hinge" axis="0 0 1"/>'
               f'<inertial pos="{com[0]:.17g} {com[1]:.17g} 0" mass="{platform_mass:.17g}" '
               f'diaginertia="{inertia / 2:.17g} {inertia / 2:.17g} {inertia:.17g}"/>{sites}</body>' if k == 0
               else f'<site name="end{k + 1}" pos="{L_DIST} 0 0"/>')
        legs.append(
            f'<body name="proximal{k + 1}" pos="{A[0]:.17g} {A[1]:.17g} 0">'
            f'<joint name="theta{k + 1}" type="hinge" axis="0 0 1"/>'
            f'<inertial pos="{L_PROX / 2} 0 0" mass="{M_PROX:.17g}" diaginertia="{TINY_INERTIA} {bar!r} {bar!r}"/>'
            f'<body name="elbow{k + 1}" pos="{L_PROX} 0 0"><inertial pos="0 0 0" mass="{M_DIST / 2:.17g}" {point}/>'
            f'</body><body name="distal{k + 1}" pos="{L_PROX} 0 0"><joint name="elbow{k + 1}" type="hinge" '
            f'axis="0 0 1"/><inertial pos="{L_DIST / 2} 0 0" mass="{TINY_MASS}" {point}/>{end}</body></body>')
    xml = (f'<mujoco><option gravity="0 0 -9.81"/><worldbody>{"".join(legs)}</worldbody><equality>'
           '<connect site1="end2" site2="corner2"/><connect site1="end3" site2="corner3"/></equality></mujoco>')
    model = mujoco.MjModel.from_xml_string(xml)
    return model, mujoco.MjData(model)


def tree_angles(q, p):
    """The chains' joint angles at the assembly (q, p): each elbow from its corner, leg 1's last joint from yaw."""
    B = corners(p)
    A = B_SIDE * CORNERS
    elbow = A + L_PROX * np.stack([np.cos(q), np.sin(q)], axis=-1)
    distal = np.arctan2(*(B - elbow).T[::-1])
    corner_1 = p[2] - distal[0]  # the platform body turns with yaw = distal_1 + corner_1
    return np.array([q[0], distal[0] - q[0], corner_1, q[1], distal[1] - q[1], q[2], distal[2] - q[2]])


def test_dynamics_match_mujoco_with_the_loops_closed_at_the_corners(rrr):
    pytest.importorskip("mujoco")
    _, generated = rrr
    reference, data = mujoco_three_rrr()
    rng = np.random.default_rng(9)
    for p in poses(3, 8):
        q = generated.ik(p).joints
        qd, qdd = rng.uniform(-1, 1, 3), rng.uniform(-10, 10, 3)
        M_ref, tau_ref = reduced_dynamics(reference, data, tree_angles(q, p), [0, 3, 5], [1, 2, 4, 6], qd, qdd)
        M = generated.mass_matrix(q, p)
        assert np.max(np.abs(M - M_ref)) <= MUJOCO_AGREEMENT * np.max(np.abs(M_ref))
        tau = generated.inverse_dynamics(q, p, qd, qdd)
        assert np.max(np.abs(tau - tau_ref)) <= MUJOCO_AGREEMENT * np.max(np.abs(tau_ref))
