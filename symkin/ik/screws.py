"""The joint axes of a serial model at q = 0, read from its generated functions.

Every serial chain symkin derives is a product of exponentials (Brockett 1984; Lynch &
Park, "Modern Robotics", sec. 4.1):

    base_T_tcp(q) = exp([S_1] q_1) ... exp([S_n] q_n) M,       M = base_T_tcp(0),

where S_i is joint i's screw at q = 0: for a revolute joint the unit direction h_i and a
point c_i of its axis, for a prismatic joint its direction.  Both come from one evaluation
of the generated functions at q = 0: column i of the geometric Jacobian is
[h_i x (p_tcp - c_i); h_i] (revolute) or [h_i; 0] (prismatic), so with the moment
m_i = c_i x h_i = v_i + p_tcp x h_i the point of the axis nearest the origin is
c_i = h_i x m_i.  A model derived without a pose Jacobian (e.g. a model file derived on
the fly for the analyses, fk and the task Jacobian only) gives them through n more
evaluations of ``fk`` (:func:`_axes_from_fk`).

The closed-form solvers (:mod:`symkin.ik.closed_form`) recognise structures (parallel or
perpendicular axes, intersecting axes) on these screws, so a model's DH convention, base
and tool frames do not matter: ``ur10e`` (modified DH) and ``ur10e_classic`` (classic DH)
give the same axes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from symkin.errors import GeneratedCodeError
from symkin.ik.problem import ModelKinematics
from symkin.ik.rotations import cross, rotate, rotation_matrix, vee

#: Agreement required between the product of exponentials and the generated fk (relative).
CHECK_TOLERANCE = 1e-9


@dataclass(frozen=True)
class HomeScrews:
    """Joint axes at q = 0 in the base frame.

    Attributes:
        directions: (n, 3) unit axis directions h_i.
        points: (n, 3) point c_i of each revolute axis nearest the base origin (zero for
            prismatic joints).
        revolute: (n,) joint types.
        home: (4, 4) base_T_tcp at q = 0 (M).
        scale: a length scale of the mechanism (largest distance between axis points and
            the TCP), for relative tolerances.
    """

    directions: np.ndarray
    points: np.ndarray
    revolute: np.ndarray
    home: np.ndarray
    scale: float

    def transform_point(self, i: int, q: np.ndarray, x: np.ndarray) -> np.ndarray:
        """exp([S_i] q) applied to points x (..., 3)."""
        h = self.directions[i]
        if self.revolute[i]:
            return rotate(h, q, x - self.points[i]) + self.points[i]
        return x + np.asarray(q)[..., None] * h

    def transform(self, i: int, q: np.ndarray) -> np.ndarray:
        """exp([S_i] q) as 4x4 transforms (..., 4, 4)."""
        q = np.asarray(q, dtype=float)
        T = np.zeros(q.shape + (4, 4))
        T[..., 3, 3] = 1.0
        h = self.directions[i]
        if self.revolute[i]:
            R = rotation_matrix(h, q)
            T[..., :3, :3] = R
            T[..., :3, 3] = self.points[i] - R @ self.points[i]
        else:
            T[..., :3, :3] = np.eye(3)
            T[..., :3, 3] = q[..., None] * h
        return T

    def fk(self, q: np.ndarray) -> np.ndarray:
        """base_T_tcp by the product of exponentials (..., 4, 4)."""
        q = np.asarray(q, dtype=float)
        T = np.broadcast_to(np.eye(4), q.shape[:-1] + (4, 4))
        for i in range(len(self.revolute)):
            T = T @ self.transform(i, q[..., i])
        return T @ self.home


def home_screws(kinematics: ModelKinematics, rng: np.random.Generator | None = None) -> HomeScrews:
    """Read the joint screws at q = 0 from the generated ``fk`` and geometric Jacobian (or,
    where no pose Jacobian was generated, from ``fk`` alone: :func:`_axes_from_fk`).

    The product of exponentials is checked against the generated ``fk`` at a few random
    configurations.

    Raises:
        GeneratedCodeError: the generated functions do not describe a serial chain of
            revolute/prismatic joints (they disagree with the product of exponentials).
    """
    M = np.asarray(kinematics.fk(np.zeros(kinematics.dof)), dtype=float)
    axes = _axes_from_jacobian if kinematics.has_pose_jacobian else _axes_from_fk
    with np.errstate(invalid="ignore", divide="ignore"):  # a joint that moves about no axis of its own: NaN, refused below
        directions, points = axes(kinematics, M)
    scale = float(max(1e-300, np.max(np.linalg.norm(points - M[:3, 3], axis=-1))))
    screws = HomeScrews(directions, points, kinematics.revolute.copy(), M, scale)
    rng = rng or np.random.default_rng(0)
    q = rng.uniform(-np.pi, np.pi, size=(8, kinematics.dof))
    deviation = np.max(np.abs(screws.fk(q) - kinematics.fk(q)))
    if not deviation <= CHECK_TOLERANCE * max(1.0, scale):  # NaN too: a coupled joint (the PHANToM's parallelogram)
        raise GeneratedCodeError(f"{kinematics.name}: the generated fk is not a product of exponentials of its "
                                 f"joint axes (deviation {deviation:.3g}); derive the model again")
    return screws


def _axes_from_jacobian(kinematics: ModelKinematics, M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(h_i, c_i) from the columns [h_i x (p_tcp - c_i); h_i] (revolute) or [h_i; 0] of J(0)."""
    J = np.asarray(kinematics.pose_jacobian(np.zeros(kinematics.dof)), dtype=float)
    p_tcp = M[:3, 3]
    directions, points = [], []
    for i in range(kinematics.dof):
        v, w = J[:3, i], J[3:, i]
        if kinematics.revolute[i]:
            h = w / np.linalg.norm(w)
            moment = v + cross(p_tcp, h)
            directions.append(h)
            points.append(cross(h, moment))
        else:
            directions.append(v / np.linalg.norm(v))
            points.append(np.zeros(3))
    return np.array(directions), np.array(points)


def _axes_from_fk(kinematics: ModelKinematics, M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(h_i, c_i) from fk alone: E_i = fk(t e_i) M^-1 = exp([S_i] t) is joint i's motion on its own.

    Revolute, t = pi/2: E_i = (R, (I - R) c_i) with R = exp([h_i] pi/2), so the vector of the
    antisymmetric part of R is sin(pi/2) h_i = h_i, and for c_i normal to h_i the translation
    d = (I - R) c_i = c_i - h_i x c_i gives c_i = (d + h_i x d) / 2.  Prismatic, t = 1:
    E_i = (I, h_i).
    """
    steps = np.where(kinematics.revolute, np.pi / 2, 1.0)
    E = np.asarray(kinematics.fk(np.diag(steps)), dtype=float) @ np.linalg.inv(M)
    d = E[:, :3, 3]
    h = np.where(kinematics.revolute[:, None], vee(E[:, :3, :3]), d)
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    points = np.where(kinematics.revolute[:, None], 0.5 * (d + cross(h, d)), 0.0)
    return h, points
