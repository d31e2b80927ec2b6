"""Transmission quality of a mechanism from its Jacobian (seed sec. 4.2, Table 8.5).

Every function takes a stack of Jacobians ``J`` of shape ``(..., m, n)`` (one per
configuration, e.g. the output of a generated ``jacobian(q)`` over a batch of ``q``) and
returns one value per configuration, shape ``(...)``.  Nothing here knows the mechanism:
the same functions rate a serial arm's ``J`` and, through :func:`from_inverse`, a parallel
mechanism's inverse Jacobian ``J^-1``.

Singular values are sigma_i(A) = sqrt(lambda_i(A^T A)) (seed sec. 4.2); with k = min(m, n)
there are k of them, sigma_1 >= ... >= sigma_k >= 0.

Numerical rank: a singular value below ``max(m, n) * eps * sigma_max`` (the threshold of
``numpy.linalg.matrix_rank``) is the rounding noise of an exactly singular matrix and is
reported as exactly 0, so that singular configurations give 1/kappa = 0, never NaN and
never a spurious 1e-17.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

_EPS = np.finfo(np.float64).eps


def _as_stack(J: np.ndarray) -> np.ndarray:
    J = np.asarray(J, dtype=np.float64)
    if J.ndim < 2:
        raise ValueError(f"expected Jacobians of shape (..., m, n), got {J.shape}")
    return J


def _rank_threshold(J: np.ndarray) -> float:
    return max(J.shape[-2:]) * _EPS


def extreme_2x2(J: Any, xp: Any = np) -> tuple[Any, Any]:
    """(sigma_max, sigma_min) of 2 x 2 matrices J = [[a, b], [c, d]] in closed form, in the array module ``xp``
    (numpy, or jax.numpy for the device integrand: one formula).

    sigma_max = (hypot(a + d, b - c) + hypot(a - d, b + c)) / 2 and sigma_min = |ad - bc| /
    sigma_max.  Neither step subtracts nearly equal numbers (the textbook sqrt(t^2 - 4 det^2)
    with t = ||J||_F^2 loses half the digits near isotropy, and t - sqrt(...) half the digits
    of sigma_min), so 1/kappa is as accurate as an SVD's (a few eps) at both ends: exactly 0
    where det J = 0, 1 to a few eps at isotropy.
    """
    a, b, c, d = J[..., 0, 0], J[..., 0, 1], J[..., 1, 0], J[..., 1, 1]
    sigma_max = 0.5 * (xp.hypot(a + d, b - c) + xp.hypot(a - d, b + c))
    root_det = xp.abs(a * d - b * c)
    sigma_min = xp.where(sigma_max > 0, root_det / xp.where(sigma_max > 0, sigma_max, 1.0), 0.0)
    return sigma_max, xp.minimum(sigma_min, sigma_max)


#: The 3 x 3 closed form hands a matrix to LAPACK's SVD when two eigenvalues of J^T J nearly
#: coincide (|r| > 1 - this, see :func:`closed_form_3x3`) ...
CLOSED_FORM_3X3_CLUSTER = 1e-4
#: ... or when sigma_2 / sigma_1 is below this (nearly rank 1).
CLOSED_FORM_3X3_RATIO = 1e-4


def closed_form_3x3(J: Any, xp: Any = np) -> tuple[Any, Any, Any]:
    """(sigma_max, sigma_min, hard) of 3 x 3 matrices in closed form, in the array module ``xp``; ``hard`` marks the
    matrices the closed form does not serve (they take an SVD: :func:`_extreme_3x3` on the host,
    :mod:`symkin.analysis.device_integrand` on a JAX device).

    The eigenvalues lambda_1 >= lambda_2 >= lambda_3 of the Gram matrix A = J^T J come from
    Smith's trigonometric solution of its characteristic cubic (O. K. Smith, "Eigenvalues
    of a symmetric 3 x 3 matrix", Commun. ACM 4 (1961) 168) on the deviator
    B = A - q I, q = tr A / 3, p^2 = tr B^2 / 6, r = det B / (2 p^3):
    lambda_k = q + 2 p cos(arccos(r) / 3 + 2 pi k / 3).  sigma_max = sqrt(lambda_1);
    sigma_min is not sqrt(lambda_3) (its relative error grows as kappa^2) but
    |det J| / sqrt(lambda_1 lambda_2): exactly 0 where det J = 0.

    arccos loses half the digits of r near r = +-1, i.e. where two eigenvalues coincide
    (isotropy in a plane or in space); such matrices (|r| > 1 - :data:`CLOSED_FORM_3X3_CLUSTER`)
    and nearly rank-1 ones (sigma_2 / sigma_1 < :data:`CLOSED_FORM_3X3_RATIO`) are ``hard``.
    Elsewhere the closed form's error in 1/kappa is at most ~16 eps (the
    rounding of r) times arccos's amplification 1/sqrt(1 - r^2) <= 1/sqrt(CLUSTER) = 100,
    i.e. <= 3.6e-13 (tested against mpmath at 40 digits).
    """
    a, b, c = J[..., 0, 0], J[..., 0, 1], J[..., 0, 2]
    d, e, f = J[..., 1, 0], J[..., 1, 1], J[..., 1, 2]
    g, h, i = J[..., 2, 0], J[..., 2, 1], J[..., 2, 2]
    g00, g11, g22 = a * a + d * d + g * g, b * b + e * e + h * h, c * c + f * f + i * i
    b01, b02, b12 = a * b + d * e + g * h, a * c + d * f + g * i, b * c + e * f + h * i
    q = (g00 + g11 + g22) / 3.0
    b00, b11, b22 = g00 - q, g11 - q, g22 - q
    p = xp.sqrt((b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * (b01 * b01 + b02 * b02 + b12 * b12)) / 6.0)
    det_b = b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) + b02 * (b01 * b12 - b11 * b02)
    r = xp.where(p > 0, det_b / (2.0 * xp.where(p > 0, p, 1.0) ** 3), 1.0)
    phi = xp.arccos(xp.clip(r, -1.0, 1.0)) / 3.0
    lambda1 = q + 2.0 * p * xp.cos(phi)
    lambda2 = xp.clip(q + 2.0 * p * xp.cos(phi - 2.0 * np.pi / 3.0), 0.0, lambda1)
    sigma_max = xp.sqrt(xp.maximum(lambda1, 0.0))
    determinant = xp.abs(a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g))
    gram_root = xp.sqrt(lambda1 * lambda2)
    sigma_min = xp.where(gram_root > 0, determinant / xp.where(gram_root > 0, gram_root, 1.0), 0.0)
    sigma_min = xp.minimum(sigma_min, xp.sqrt(lambda2))
    hard = (xp.abs(r) > 1.0 - CLOSED_FORM_3X3_CLUSTER) | (lambda2 < CLOSED_FORM_3X3_RATIO**2 * lambda1)
    return sigma_max, sigma_min, hard


def _extreme_3x3(J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(sigma_max, sigma_min) of 3 x 3 matrices, mostly in closed form (several times faster than an SVD):
    :func:`closed_form_3x3`, its hard matrices by LAPACK's SVD."""
    with np.errstate(invalid="ignore", divide="ignore"):
        sigma_max, sigma_min, hard = closed_form_3x3(J)
    if hard.any():
        flat = hard.reshape(-1)
        sigma_max, sigma_min = np.array(sigma_max).reshape(-1), np.array(sigma_min).reshape(-1)
        s = np.linalg.svd(J.reshape(-1, 3, 3)[flat], compute_uv=False)
        sigma_max[flat], sigma_min[flat] = s[:, 0], s[:, -1]
        sigma_max, sigma_min = sigma_max.reshape(hard.shape), sigma_min.reshape(hard.shape)
    return sigma_max, sigma_min


def _extreme_singular_values(J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(sigma_max, sigma_min) with the numerical-rank rule applied to sigma_min.

    Closed forms for 2 x 2 and 3 x 3 matrices (:func:`_extreme_2x2`, :func:`_extreme_3x3`),
    an SVD otherwise.  A matrix with a non-finite entry (e.g. a parallel mechanism's
    J = J_x^-1 J_q where det J_x = 0, or at a pose it cannot assemble) is singular:
    sigma_max = inf, sigma_min = 0, so every index rates it as such and none is NaN.
    """
    m, n = J.shape[-2:]
    finite = np.isfinite(J).all(axis=(-2, -1))
    if not finite.all():
        J = np.where(finite[..., None, None], J, 0.0)
    if m == n == 2:
        with np.errstate(invalid="ignore", divide="ignore"):
            sigma_max, sigma_min = extreme_2x2(J)
    elif m == n == 3:
        sigma_max, sigma_min = _extreme_3x3(J)
    else:
        s = np.linalg.svd(J, compute_uv=False)
        sigma_max, sigma_min = s[..., 0], s[..., -1]
    sigma_min = np.where(sigma_min <= _rank_threshold(J) * sigma_max, 0.0, sigma_min)
    if not finite.all():
        sigma_max, sigma_min = np.where(finite, sigma_max, np.inf), np.where(finite, sigma_min, 0.0)
    return sigma_max, sigma_min


def singular_values(J: np.ndarray) -> np.ndarray:
    """All singular values sigma_1 >= ... >= sigma_k of each J, shape (..., k), k = min(m, n).

    Values below the numerical-rank threshold (see module docstring) are set to 0; a J
    with a non-finite entry gives (inf, 0, ..., 0).
    """
    J = _as_stack(J)
    finite = np.isfinite(J).all(axis=(-2, -1))
    s = np.linalg.svd(np.where(finite[..., None, None], J, 0.0), compute_uv=False)
    s = np.where(s <= _rank_threshold(J) * s[..., :1], 0.0, s)
    if not finite.all():  # non-finite J: singular (see _extreme_singular_values)
        s = np.where(finite[..., None], s, 0.0)
        s[..., 0] = np.where(finite, s[..., 0], np.inf)
    return s


def inverse_condition_number(J: np.ndarray) -> np.ndarray:
    """1/kappa = sigma_min / sigma_max in [0, 1] (seed eq. 8.25).

    1 at isotropic configurations (J^T J proportional to I), exactly 0 at singular ones
    (and for J = 0); never NaN.
    """
    sigma_max, sigma_min = _extreme_singular_values(_as_stack(J))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(sigma_max > 0, sigma_min / np.where(sigma_max > 0, sigma_max, 1.0), 0.0)


def condition_number(J: np.ndarray) -> np.ndarray:
    """kappa = sigma_max / sigma_min >= 1 (seed eq. 8.25); +inf at singular configurations."""
    sigma_max, sigma_min = _extreme_singular_values(_as_stack(J))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(sigma_min > 0, sigma_max / np.where(sigma_min > 0, sigma_min, 1.0), np.inf)


def inverse_frobenius_condition_number(J: np.ndarray) -> np.ndarray:
    """1/kappa_F in [0, 1], the Frobenius-norm conditioning, smooth away from singularities.

    kappa_F = (1/k) ||J||_F ||J^+||_F = (1/k) sqrt(sum sigma_i^2 * sum sigma_i^-2)
    (Angeles, Fundamentals of Robotic Mechanical Systems, sec. 4.9; Gosselin and Angeles
    1991).  kappa / k <= kappa_F <= kappa, with kappa_F = 1 exactly at isotropy; unlike
    sigma_min / sigma_max it has no kink where singular values cross, so gradient-based
    dimensioning prefers it.  1/kappa_F = 0 at singular configurations, never NaN.  For
    k = 2, kappa_F = (kappa + 1/kappa) / 2.
    """
    J = _as_stack(J)
    if min(J.shape[-2:]) == 2:
        r = inverse_condition_number(J)
        return 2.0 * r / (1.0 + r * r)
    s = singular_values(J)
    squares = s * s
    regular = s[..., -1] > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse_sum = (1.0 / np.where(regular[..., None], squares, 1.0)).sum(axis=-1)
        value = s.shape[-1] / np.sqrt(squares.sum(axis=-1) * inverse_sum)
    return np.where(regular, value, 0.0)


def frobenius_condition_number(J: np.ndarray) -> np.ndarray:
    """kappa_F >= 1 (see :func:`inverse_frobenius_condition_number`); +inf at singular configurations."""
    inverse = inverse_frobenius_condition_number(J)
    with np.errstate(divide="ignore"):
        return np.where(inverse > 0, 1.0 / np.where(inverse > 0, inverse, 1.0), np.inf)


def absolute_determinant(J: np.ndarray) -> np.ndarray:
    """|det J| of square Jacobians (..., n, n); closed forms for n = 2 and 3 (no LAPACK call).

    |det J| dq is the Cartesian volume element of the workspace in joint coordinates.
    """
    J = _as_stack(J)
    n = J.shape[-1]
    if J.shape[-2] != n:
        raise ValueError(f"a determinant needs square matrices, got {J.shape[-2:]}")
    if n == 2:
        return np.abs(J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0])
    if n == 3:
        return np.abs(np.einsum("...i,...i->...", J[..., 0, :], np.cross(J[..., 1, :], J[..., 2, :])))
    return np.abs(np.linalg.det(J))


def manipulability(J: np.ndarray) -> np.ndarray:
    """Yoshikawa's manipulability w = sqrt(det(J J^T)) = prod(sigma_i) (Table 8.5); |det J| if square."""
    J = _as_stack(J)
    m, n = J.shape[-2:]
    if m == n:
        return absolute_determinant(J)
    return np.prod(singular_values(J), axis=-1)


class TransmissionIndices(NamedTuple):
    """The optimization criteria of seed Table 8.5 at each configuration (arrays of shape (...)).

    With tau = J^T F (seed eq. 8.35) and dq = J^-1 dp (eq. 8.30), the singular values of
    J^-1 are 1/sigma_i(J):

    Attributes:
        force: sigma_min(J^-1) = 1 / sigma_max(J); force transmission, to be maximized.
        speed: sigma_max(J^-1) = 1 / sigma_min(J); speed transmission, to be minimized
            (+inf at singular configurations).
        manipulability: prod sigma_i(J) (Yoshikawa), to be maximized; 0 at singularities.
        inverse_condition: 1/kappa in [0, 1] (eq. 8.25), to be maximized.
        inverse_frobenius_condition: 1/kappa_F in [0, 1], its smooth counterpart.
    """

    force: np.ndarray
    speed: np.ndarray
    manipulability: np.ndarray
    inverse_condition: np.ndarray
    inverse_frobenius_condition: np.ndarray


def transmission_indices(J: np.ndarray) -> TransmissionIndices:
    """The Table 8.5 criteria from the forward Jacobian J (dp = J dq)."""
    J = _as_stack(J)
    sigma_max, sigma_min = _extreme_singular_values(J)
    with np.errstate(divide="ignore"):
        force = np.where(sigma_max > 0, 1.0 / np.where(sigma_max > 0, sigma_max, 1.0), np.inf)
        speed = np.where(sigma_min > 0, 1.0 / np.where(sigma_min > 0, sigma_min, 1.0), np.inf)
    return TransmissionIndices(force, speed, manipulability(J), inverse_condition_number(J),
                               inverse_frobenius_condition_number(J))


def from_inverse(J_inverse: np.ndarray) -> np.ndarray:
    """The forward Jacobian J = (J^-1)^-1 of each non-singular inverse Jacobian, NaN-free.

    Parallel mechanisms give the inverse Jacobian (dq = J^-1 dp) in closed form; the
    indices above need J.  Singular J^-1 (seed: workspace-interior singularity,
    det(J^-1) = 0) map to J = 0, which every index above rates as singular (1/kappa = 0).
    Since kappa(J) = kappa(J^-1), ``inverse_condition_number(J_inverse)`` gives 1/kappa
    directly and needs no inversion.
    """
    J_inverse = _as_stack(J_inverse)
    if J_inverse.shape[-1] != J_inverse.shape[-2]:
        raise ValueError(f"an inverse Jacobian must be square, got {J_inverse.shape[-2:]}")
    regular = inverse_condition_number(J_inverse) > 0
    safe = np.where(regular[..., None, None], J_inverse, np.eye(J_inverse.shape[-1]))
    return np.where(regular[..., None, None], np.linalg.inv(safe), 0.0)


def homogenize(J: np.ndarray, length: float, position_rows: tuple[int, ...]) -> np.ndarray:
    """Dimensionless Jacobian for mixed translation/rotation task spaces.

    The rows of translational velocities (m per rad) are divided by a characteristic
    length L, so that all entries share one unit and singular values can be compared
    (Angeles and Lopez-Cajun 1992; Khan and Angeles 2006).  Rotational rows are unchanged.

    Args:
        J: Jacobians (..., m, n).
        length: characteristic length L > 0 (same unit as the translational rows' lengths).
        position_rows: indices of the translational rows (x, y, z in the task space).
    """
    return np.asarray(J, dtype=np.float64) * homogenizing_scale(np.shape(J)[-2], length, position_rows)[:, None]


def homogenizing_scale(rows: int, length: float, position_rows: tuple[int, ...]) -> np.ndarray:
    """The factor of each of the ``rows`` rows that :func:`homogenize` applies: 1/L on ``position_rows``, else 1."""
    if not length > 0:
        raise ValueError(f"the characteristic length must be positive, got {length}")
    scale = np.ones(rows)
    scale[list(position_rows)] = 1.0 / length
    return scale


def characteristic_length(J: np.ndarray, position_rows: tuple[int, ...],
                          bounds: tuple[float, float] | None = None) -> float:
    """The characteristic length L that makes the homogenized Jacobians best conditioned.

    L minimizes the mean of kappa_F^2 of ``homogenize(J, L)`` over the given
    configurations (Angeles' definition of the characteristic length as the length
    minimizing the condition number, here averaged over a sample of the workspace and
    with the smooth Frobenius conditioning).  Configurations that are singular for every
    L are ignored.  Scaling the mechanism by s scales L by s.

    Args:
        J: Jacobians (..., m, n), e.g. ``model.jacobian(q)`` over workspace samples.
        position_rows: indices of the translational rows.
        bounds: search interval for L; default: 1e-3 to 1e3 times the median ratio of the
            translational to the rotational row norms.

    Returns:
        L, in the length unit of J's translational rows.
    """
    from scipy.optimize import minimize_scalar

    J = _as_stack(J).reshape((-1,) + np.shape(J)[-2:])
    rows = list(position_rows)
    others = [i for i in range(J.shape[-2]) if i not in rows]
    if not rows or not others:
        raise ValueError("a characteristic length needs both translational and rotational rows")
    ok = inverse_condition_number(J) > 0
    if not ok.any():
        raise ValueError("every configuration is singular: no characteristic length can be found")
    J = J[ok]
    if bounds is None:
        ratio = np.median(np.linalg.norm(J[:, rows], axis=(-2, -1)) / np.linalg.norm(J[:, others], axis=(-2, -1)))
        bounds = (ratio * 1e-3, ratio * 1e3)

    def cost(log_length: float) -> float:
        inverse = inverse_frobenius_condition_number(homogenize(J, float(np.exp(log_length)), position_rows))
        with np.errstate(divide="ignore"):
            return float(np.mean(1.0 / inverse**2))

    result = minimize_scalar(cost, bounds=(np.log(bounds[0]), np.log(bounds[1])), method="bounded",
                             options={"xatol": 1e-10})
    return float(np.exp(result.x))
