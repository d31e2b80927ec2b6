"""Vectorized rotation helpers for inverse kinematics (numpy, any leading batch shape; :func:`cross` and :func:`rotate`
also in jax.numpy, for the closed forms a JAX device traces: :mod:`symkin.analysis.device_cartesian`).

Angles follow the right-hand rule; vectors are arrays of shape (..., 3), rotation matrices
(..., 3, 3) and homogeneous transforms (..., 4, 4).
"""

from __future__ import annotations

from typing import Any

import numpy as np


def cross(u: np.ndarray, v: np.ndarray, xp: Any = np) -> np.ndarray:
    """u x v over the last axis (numpy.cross without its per-call overhead, which dominates
    for the single targets of a control loop), in the array module ``xp`` (numpy, or jax.numpy)."""
    u, v = xp.asarray(u), xp.asarray(v)
    return xp.stack([u[..., 1] * v[..., 2] - u[..., 2] * v[..., 1],
                     u[..., 2] * v[..., 0] - u[..., 0] * v[..., 2],
                     u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]], axis=-1)


def vee(skew: np.ndarray) -> np.ndarray:
    """The vector w of a skew-symmetric matrix [w]x (its antisymmetric part, to be exact)."""
    return 0.5 * np.stack([skew[..., 2, 1] - skew[..., 1, 2],
                           skew[..., 0, 2] - skew[..., 2, 0],
                           skew[..., 1, 0] - skew[..., 0, 1]], axis=-1)


def rotate(axis: np.ndarray, angle: np.ndarray, v: np.ndarray, xp: Any = np) -> np.ndarray:
    """Rotate ``v`` about the unit ``axis`` (through the origin) by ``angle`` (Rodrigues), in the array module ``xp``:
    R v = v cos(t) + (h x v) sin(t) + h (h . v)(1 - cos(t))."""
    angle = xp.asarray(angle)[..., None]
    c, s = xp.cos(angle), xp.sin(angle)
    dot = (axis * v).sum(-1, keepdims=True)
    return v * c + cross(axis, v, xp) * s + axis * dot * (1.0 - c)


def rotation_matrix(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """R = I + sin(t) K + (1 - cos(t)) K^2 with K = [axis]x, shape (..., 3, 3)."""
    axis = np.asarray(axis, dtype=float)
    angle = np.asarray(angle, dtype=float)
    if axis.ndim == 1:  # one axis for every angle (a joint's): one K, built without stacking batches
        kx, ky, kz = axis
        K = np.array([[0.0, -kz, ky], [kz, 0.0, -kx], [-ky, kx, 0.0]])
    else:
        shape = np.broadcast_shapes(axis.shape[:-1], angle.shape)
        kx, ky, kz = (np.broadcast_to(axis[..., i], shape) for i in range(3))
        zero = np.zeros(shape)
        K = np.stack([np.stack([zero, -kz, ky], -1), np.stack([kz, zero, -kx], -1), np.stack([-ky, kx, zero], -1)], -2)
    s = np.sin(angle)[..., None, None]
    c = np.cos(angle)[..., None, None]
    return np.eye(3) + s * K + (1.0 - c) * (K @ K)


def log_so3(R: np.ndarray) -> np.ndarray:
    """Rotation vector w = theta * axis of R (theta in [0, pi]), accurate over the whole range.

    With s = vee(R - R^T)/2 = sin(theta) axis and c = (trace R - 1)/2 = cos(theta),
    theta = atan2(|s|, c).  For theta <= pi/2, w = s theta/|s| (the factor tends to 1);
    for theta > pi/2 the axis comes from the symmetric part (R + R^T)/2 - c I = (1 - c) a a^T,
    whose largest column is well conditioned, signed by s (at theta = pi both signs are right).
    """
    R = np.asarray(R, dtype=float)
    s_vec = vee(R)
    s = np.linalg.norm(s_vec, axis=-1)
    c = 0.5 * (np.trace(R, axis1=-2, axis2=-1) - 1.0)
    theta = np.arctan2(s, c)
    with np.errstate(invalid="ignore", divide="ignore"):
        factor = np.where(s > 0.0, theta / np.where(s > 0.0, s, 1.0), 1.0)
    small = s_vec * factor[..., None]
    B = 0.5 * (R + np.swapaxes(R, -1, -2)) - c[..., None, None] * np.eye(3)
    k = np.argmax(np.diagonal(B, axis1=-2, axis2=-1), axis=-1)
    column = np.take_along_axis(B, k[..., None, None], axis=-1)[..., 0]
    norm = np.linalg.norm(column, axis=-1, keepdims=True)
    axis = column / np.where(norm > 0.0, norm, 1.0)
    sign = np.where(np.sum(axis * s_vec, axis=-1, keepdims=True) < 0.0, -1.0, 1.0)
    large = axis * sign * theta[..., None]
    return np.where((c < 0.0)[..., None], large, small)


def right_jacobian_inverse(phi: np.ndarray) -> np.ndarray:
    """J_r^-1(phi), with log(exp([phi]) exp([d])) = phi + J_r^-1(phi) d + O(d^2), shape (..., 3, 3):

    J_r^-1 = I + [phi]/2 + (1/theta^2 - (1 + cos theta) / (2 theta sin theta)) [phi]^2
    (Chirikjian, "Stochastic Models, Information Theory, and Lie Groups", vol. 2, 10.86);
    the coefficient tends to 1/12 + theta^2/720 as theta -> 0 and grows without bound as
    theta -> pi, where the rotation vector jumps.
    """
    phi = np.asarray(phi, dtype=float)
    theta = np.linalg.norm(phi, axis=-1)
    x, y, z = phi[..., 0], phi[..., 1], phi[..., 2]
    zero = np.zeros_like(x)
    K = np.stack([np.stack([zero, -z, y], -1), np.stack([z, zero, -x], -1), np.stack([-y, x, zero], -1)], -2)
    small = theta < 1e-4
    t = np.where(small, 1.0, theta)
    with np.errstate(divide="ignore", invalid="ignore"):
        coefficient = np.where(small, 1.0 / 12.0 + theta**2 / 720.0,
                               1.0 / t**2 - (1.0 + np.cos(t)) / (2.0 * t * np.sin(t)))
    return np.eye(3) + 0.5 * K + coefficient[..., None, None] * (K @ K)


def pose_error(target: np.ndarray, T: np.ndarray) -> np.ndarray:
    """[p_target - p; log(R_target R^T)], shape (..., 6): the twist, in the base frame, that
    moves the pose T onto the target (first order); its derivative with respect to q at a
    solution is minus the geometric Jacobian [v; w]."""
    dp = target[..., :3, 3] - T[..., :3, 3]
    dR = target[..., :3, :3] @ np.swapaxes(T[..., :3, :3], -1, -2)
    return np.concatenate([dp, log_so3(dR)], axis=-1)


def pose_from_vector(vector: np.ndarray) -> np.ndarray:
    """The 4x4 pose of [x, y, z, rx, ry, rz] (position and rotation vector, as UR controllers
    write poses), shape (..., 4, 4)."""
    vector = np.asarray(vector, dtype=float)
    w = vector[..., 3:6]
    theta = np.linalg.norm(w, axis=-1)
    axis = w / np.where(theta > 0.0, theta, 1.0)[..., None]
    T = np.zeros(vector.shape[:-1] + (4, 4))
    T[..., :3, :3] = rotation_matrix(axis, theta)
    T[..., :3, 3] = vector[..., :3]
    T[..., 3, 3] = 1.0
    return T
