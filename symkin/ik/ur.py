"""Closed-form IK of the Universal Robots family (UR3/5/10/16, e-series): eight solutions.

Structure (recognised on the joint screws at q = 0, :mod:`symkin.ik.screws`): six revolute
joints; axes 2, 3, 4 parallel (direction h2); axis 5 normal to h2; axis 6 normal to axis 5
and intersecting it at the point w (the "wrist point": UR's wrist is not spherical, d5 and
d6 are both non-zero, so Pieper's decomposition is applied to w instead of a wrist
centre).  With E_i = exp([S_i] q_i) the forward kinematics is T = E1 ... E6 M, and for a
target T_t = (R_t, p_t) let R_d = R_t M_R^T = R1 ... R6 (R_i the rotation of E_i).

1. **q1 (shoulder)** - w lies on axes 5 and 6, so q5 and q6 do not move it; q2, q3, q4
   turn about axes parallel to h2, so they keep its coordinate along h2.  Hence, with c1 a
   point of axis 1,

       (R1 h2) . (w_t - c1) = h2 . (w_0 - c1) =: delta    (UR: delta = +-d4, the shoulder offset)

   where w_0 is w at q = 0 and w_t = T_t M^-1 w_0 its position at the target (w is fixed
   relative to the flange).  This is a . cos q1 + b . sin q1 = c (subproblem 4,
   :func:`~symkin.ik.subproblems.sinusoid`): two branches ("shoulder +-"), none if w_t is
   closer than |delta| to axis 1, and one double root at distance exactly |delta|
   (**shoulder singularity**).

2. **q5 (wrist)** - axis 6 has direction a6 = R_d h6 at the target, and R2 R3 R4 keep h2,
   so with k = R1 h2:

       h2 . (R5 h6) = k . a6,

   a sinusoid in q5 whose root sqrt(1 - (k . a6)^2) equals |k x a6| (both unit vectors, h2
   and h6 normal to axis 5): taking it from the cross product instead of the difference of
   squares keeps full accuracy at the **wrist singularity** q5 = 0 or pi (axis 6 parallel
   to axes 2-4), where the usual q5 = +-acos(...) has an error of about 1e-8 rad.  Two
   branches ("wrist +-").

3. **q6** - from h2^T R2 R3 R4 = h2^T:  R6^T (R5^T h2) = R_d^T k, so q6 is the angle that
   turns u = R5^T h2 onto v = R_d^T k about h6 (subproblem 1).  At the wrist singularity u
   is parallel to h6 and q6 is undetermined: any value works together with q4 (only
   q4 + q6 matters there); the one returned is valid, and the branch is flagged
   :attr:`~symkin.ik.closed_form.BranchFlag.WRIST`.

4. **q2, q3 (elbow)** - E2 E3 E4 = E1^-1 T_t M^-1 E6^-1 E5^-1 is now known; it moves a point
   c4 of axis 4 to x = (E2 E3 E4) c4, and E4 does not move c4: a planar two-link problem
   for joints 2 and 3 (:class:`~symkin.ik.planar.ParallelPair`, two branches "elbow +-",
   **elbow singularity** with the arm stretched, q3 = 0, or folded).

5. **q4** - E2 E3 E4 rotates by q2 + s3 q3 + s4 q4 about h2 (s_i = h_i . h2 = +-1), read off
   by subproblem 1 on any vector normal to h2.

The model's DH convention, base and tool frames do not enter: ``ur10e`` (modified DH) and
``ur10e_classic`` (classic DH) give the same eight solutions.
"""

from __future__ import annotations

import numpy as np

from symkin.ik.closed_form import SINGULARITY_EPSILON, STRUCTURE_TOLERANCE, BranchFlag, register
from symkin.ik.planar import ParallelPair
from symkin.ik.problem import ModelKinematics
from symkin.ik.rotations import cross, rotate
from symkin.ik.screws import HomeScrews
from symkin.ik.subproblems import dot, perpendicular, signed_angle, sinusoid


def _closest_point_of_lines(c1: np.ndarray, h1: np.ndarray, c2: np.ndarray, h2: np.ndarray) -> tuple[np.ndarray, float]:
    """The midpoint of the common normal of two non-parallel lines, and their distance."""
    n = cross(h1, h2)
    nn = float(np.dot(n, n))
    delta = c2 - c1
    t1 = np.dot(cross(delta, h2), n) / nn
    t2 = np.dot(cross(delta, h1), n) / nn
    p1, p2 = c1 + t1 * h1, c2 + t2 * h2
    return 0.5 * (p1 + p2), float(np.linalg.norm(p1 - p2))


def _inverse(T: np.ndarray) -> np.ndarray:
    Ti = np.zeros_like(T)
    Rt = np.swapaxes(T[..., :3, :3], -1, -2)
    Ti[..., :3, :3] = Rt
    Ti[..., :3, 3] = -np.einsum("...ij,...j->...i", Rt, T[..., :3, 3])
    Ti[..., 3, 3] = 1.0
    return Ti


class URFamily:
    """The eight branches of a UR-type arm (see the module docstring)."""

    name = "UR family 6R (axes 2-4 parallel, axes 5-6 intersecting)"
    kind = "pose"
    branches = tuple(f"shoulder {s1}, wrist {s5}, elbow {s3}"
                     for s1 in "+-" for s5 in "+-" for s3 in "+-")

    def __init__(self, screws: HomeScrews, wrist_point: np.ndarray):
        self.screws = screws
        self.h = screws.directions
        self.c = screws.points
        self.w0 = wrist_point
        self.h2 = self.h[1]
        self.delta = float(np.dot(self.h2, wrist_point - self.c[0]))
        self.s3 = float(np.sign(np.dot(self.h[2], self.h2)))
        self.s4 = float(np.sign(np.dot(self.h[3], self.h2)))
        self.elbow = ParallelPair(self.h2, self.c[1], self.c[2], 1.0, self.s3, self.c[3])
        self.M_inv = _inverse(screws.home)
        # any unit vector normal to h2, to read the rotation angle of E2 E3 E4 about h2
        normal = perpendicular(self.h2, np.eye(3)[int(np.argmin(np.abs(self.h2)))])
        self.normal = normal / np.linalg.norm(normal)
        # the target-independent coefficients of the two sinusoids (steps 1 and 2)
        h1, h2, h5, h6 = self.h[0], self.h2, self.h[4], self.h[5]
        self.shoulder_coefficients = (perpendicular(h1, h2), cross(h1, h2), np.dot(h1, h2))
        self.wrist_coefficients = (np.dot(perpendicular(h5, h6), h2), np.dot(cross(h5, h6), h2),
                                   np.dot(h5, h6) * np.dot(h5, h2))

    def candidates(self, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """All eight branches at once: axes (..., shoulder, wrist, elbow) flattened to (..., 8)."""
        h, c, h2, s = self.h, self.c, self.h2, self.screws
        h1, h5, h6 = h[0], h[4], h[5]
        TM = target @ self.M_inv                       # E1 ... E6
        R_d = TM[..., :3, :3]
        w = np.einsum("...ij,j->...i", R_d, self.w0) + TM[..., :3, 3]
        a6 = R_d @ h6

        # 1. shoulder: (R1 h2) . (w - c1) = delta                              -> q1 (..., 2)
        r = w - c[0]
        along_a, along_b, h1_h2 = self.shoulder_coefficients
        shoulder = sinusoid(dot(along_a, r), dot(along_b, r), self.delta - h1_h2 * dot(h1, r))
        q1 = np.stack([shoulder.plus, shoulder.minus], -1)
        shoulder_flags = (np.where(shoulder.unreachable, int(BranchFlag.UNREACHABLE_SHOULDER), 0)
                          | np.where(shoulder.clamped, int(BranchFlag.CLAMPED), 0)
                          | np.where(shoulder.root <= SINGULARITY_EPSILON * s.scale, int(BranchFlag.SHOULDER), 0))

        # 2. wrist: h2 . (R5 h6) = k . a6 with the root |k x a6|              -> q5 (..., 2, 2)
        k = rotate(h1, q1, h2)
        a6_b = a6[..., None, :]
        wrist_a, wrist_b, wrist_c = self.wrist_coefficients
        wrist = sinusoid(wrist_a, wrist_b, dot(k, a6_b) - wrist_c, root=np.linalg.norm(cross(k, a6_b), axis=-1))
        q5 = np.stack([wrist.plus, wrist.minus], -1)
        wrist_flags = np.where(wrist.root <= SINGULARITY_EPSILON, int(BranchFlag.WRIST), 0)

        # 3. q6 turns u = R5^T h2 onto v = R_d^T k about h6 by -q6             -> q6 (..., 2, 2)
        u = rotate(h5, -q5, h2)
        v = np.einsum("...ji,...kj->...ki", R_d, k)[..., :, None, :]
        q6 = -signed_angle(h6, u, v)

        # 4. E2 E3 E4 = E1^-1 T M^-1 E6^-1 E5^-1 moves c4 (on axis 4) to x     -> q2, q3 (..., 2, 2, 2)
        E234 = (s.transform(0, -q1)[..., :, None, :, :] @ TM[..., None, None, :, :]
                @ s.transform(5, -q6) @ s.transform(4, -q5))
        x = np.einsum("...ij,j->...i", E234[..., :3, :3], c[3]) + E234[..., :3, 3]
        q2, q3, elbow_flags = self.elbow.solve(x)

        # 5. q4 from the total turn about h2
        turned = np.einsum("...ij,j->...i", E234[..., :3, :3], self.normal)
        total = signed_angle(h2, self.normal, turned)[..., None]
        q4 = self.s4 * (total - q2 - self.s3 * q3)

        shape = q2.shape
        q = np.empty(shape + (6,))
        q[..., 0], q[..., 1], q[..., 2], q[..., 3] = q1[..., :, None, None], q2, q3, q4
        q[..., 4], q[..., 5] = q5[..., None], q6[..., None]
        flags = shoulder_flags[..., None, None, None] | wrist_flags[..., :, None, None] | elbow_flags
        batch = shape[:-3]
        return q.reshape(batch + (8, 6)), np.broadcast_to(flags, shape).reshape(batch + (8,))


@register
def recognise_ur_family(kin: ModelKinematics, screws: HomeScrews) -> URFamily | None:
    """Six revolute joints; h2 || h3 || h4; h5 normal to h2; h6 normal to h5; axes 5 and 6
    intersect; axis 1 not parallel to h2; a regular elbow triangle."""
    if kin.dof != 6 or not np.all(kin.revolute) or kin.default_kind != "pose":
        return None
    h = screws.directions
    tol = STRUCTURE_TOLERANCE
    parallel = all(np.linalg.norm(cross(h[1], h[i])) <= tol for i in (2, 3))
    if not parallel or abs(np.dot(h[4], h[1])) > tol or abs(np.dot(h[4], h[5])) > tol:
        return None
    if np.linalg.norm(cross(h[0], h[1])) <= tol:
        return None
    wrist_point, distance = _closest_point_of_lines(screws.points[4], h[4], screws.points[5], h[5])
    if distance > tol * screws.scale:
        return None
    solver = URFamily(screws, wrist_point)
    return solver if solver.elbow.is_regular(screws.scale) else None
