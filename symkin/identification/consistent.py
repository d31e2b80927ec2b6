"""Physically consistent identification: standard parameters whose every body is a real rigid body.

Least squares on the base parameters (:mod:`symkin.identification.estimation`) fits the torques but can return
combinations no set of bodies has (a negative mass hidden in a regrouped parameter), which a simulation or
an inertia-cancelling controller then meets as a mass matrix that is not positive definite.  Here the
standard parameters pi themselves are estimated, each link's ten as a pseudo-inertia

    J = [[Sigma, h], [h^T, m]] = U U^T,   Sigma = 1/2 tr(I) 1 - I,  h = m c,

positive definite by construction through its log-Cholesky factor (Rucker and Wensing, "Smooth
parameterization of rigid-body inertia", IEEE Robot. Autom. Lett. 7(2), 2022: U upper triangular with
exp(alpha) times [[e^d1, s12, s13, t1], [0, e^d2, s23, t2], [0, 0, e^d3, t3], [0, 0, 0, 1]]); J
positive definite is exactly the density realizability of the link (Wensing, Kim and Slotine 2017), which
implies m > 0 and the triangle inequalities of the principal moments.  A parallel model's rods are masses at
their ends (each non-negative) and an inertia beyond them (free).  Each drive is estimated as its rotor
inertia I_a, viscous friction f_v and its two Coulomb levels c+ = f_c + f_o (against positive motion) and
c- = f_c - f_o (against negative motion), all four bounded below by zero: f_c = (c+ + c-)/2 and
f_o = (c+ - c-)/2, so the offset may have either sign but never turns a level into a push (the friction the
model file writes, ``coulomb: {positive: c+, negative: c-}``).

The data enter through the triangular factor of the weighted regressor ([W y] = Q [R z; 0 r], as the
least-squares estimate), so the objective is |R pi(theta) - z|^2 + lambda |D (pi(theta) - pi_prior)|^2:
the standard regressor is rank-deficient (only the base combinations are identifiable) and the small
prior term (D: the prior's scale per parameter) picks, among the parameter sets that fit the data equally,
the one closest to the model's (CAD) values.  Solved with SciPy's trust-region reflective least squares on
the analytic Jacobian: J = U U^T is bilinear in U and the standard parameters linear in J, so d pi / d theta
is dU U^T + U dU^T mapped to the ten parameters, with dU/dtheta read off U (:func:`_factor_derivatives`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from symkin.dynamics.parameter_names import DRIVE, INERTIAL, ROD_MASSES

#: Weight of the prior against the data (relative, after both are scaled): small, it only picks among fits.
PRIOR_WEIGHT = 1e-4
#: The solver's tolerances (SciPy's ftol, xtol, gtol: relative change of the cost, of the step, and the scaled
#: gradient) and its budget of residual evaluations.  The prior's small weight leaves the directions the data do not
#: see nearly flat, where the trust region creeps: at 1e-12 and 2000 evaluations (the settings before) neither the
#: driven 2R arm nor the PHANToM of tests/identification converged, the arm's data cost 3.5e-4 (relative) above its
#: optimum; at 1e-10 the arm converges in 2723 evaluations and the PHANToM in about 1100, its cost 2e-6 above the
#: optimum 5000 evaluations reach.  Started from the arm's own (true) parameters it still creeps after 10000
#: (optimality 0.7): a body at the edge of consistency (a singular pseudo-inertia: a point mass, a slender rod) is
#: approached without end by its log-Cholesky factor.  The estimate says whether it converged.
TOLERANCE = 1e-10
EVALUATIONS = 3000
#: The standard parameters of a link and of a joint's drive, in the regressor's order.
LINK_PARAMETERS = len(INERTIAL)
DRIVE_PARAMETERS = len(DRIVE)
#: A drive's standard parameters (I_a, f_v, f_c, f_o) from its estimated ones (I_a, f_v, c+, c-), all >= 0.
DRIVE_OF_LEVELS = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.5, 0.5], [0.0, 0.0, 0.5, -0.5]])
#: The standard parameters of a block of levels from its estimated ones: a drive's, or a joint's friction alone
#: (f_v, f_c, f_o from f_v, c+, c-: a drive whose rotor is shared with others, estimated apart as a mass).
LEVELS = {"drive": DRIVE_OF_LEVELS, "friction": DRIVE_OF_LEVELS[1:, 1:]}


#: The kinds of blocks of the standard parameters, and their sizes: a body (a pseudo-inertia), a drive, a joint's
#: friction, a mass (>= 0), a free parameter.
BLOCK_SIZES = {"body": LINK_PARAMETERS, "drive": DRIVE_PARAMETERS, "friction": DRIVE_PARAMETERS - 1, "mass": 1,
               "free": 1}


def layout(names: Sequence[str]) -> tuple[str, ...]:
    """The blocks of the standard parameters ``names`` in order: ``<body>.m`` ... ``<body>.Izz`` a body,
    ``<joint>.Ia`` ... ``<joint>.fo`` a drive, ``<joint>.fv`` ... ``<joint>.fo`` a joint's friction, a rod's mass
    (``rod.mB``) or a rotor inertia alone (``rotor.Ia``: one for several joints) a mass, anything else free."""
    blocks: list[str] = []
    k = 0
    while k < len(names):
        owner, _, parameter = names[k].rpartition(".")
        for kind, parameters in (("body", INERTIAL), ("drive", DRIVE), ("friction", DRIVE[1:])):
            if list(names[k:k + len(parameters)]) == [f"{owner}.{p}" for p in parameters]:
                break
        else:
            kind = "mass" if parameter in ROD_MASSES + DRIVE[:1] else "free"
        blocks.append(kind)
        k += BLOCK_SIZES[kind]
    return tuple(blocks)


@dataclass(frozen=True)
class ConsistentEstimate:
    """Standard parameters of physically consistent bodies and the drives, and how they fit.

    Attributes:
        names: the standard parameters' names (the regressor's columns).
        values: the estimate.
        blocks: the kind of each block of the parameters (:func:`layout`).
        cost: |R pi - z|^2 at the estimate, against the unconstrained least squares' (``best_cost``).
        converged: whether the solver met its tolerances; False where it stopped at its budget of evaluations
            (the bodies are consistent all the same, the fit short of its optimum: the reports say so).
        evaluations: how many times the solver evaluated the residual.
        optimality: the first-order optimality at the estimate (the gradient's max-norm, SciPy's ``optimality``).
    """

    names: tuple[str, ...]
    values: np.ndarray
    blocks: tuple[str, ...]
    cost: float
    best_cost: float
    converged: bool
    evaluations: int
    optimality: float

    def solver_text(self) -> str:
        """The solver's outcome in words, for a summary."""
        if self.converged:
            return f"converged in {self.evaluations} evaluations"
        return (f"not converged: stopped at its budget of {self.evaluations} evaluations, first-order optimality "
                f"{self.optimality:.3g} (the bodies are consistent, the fit short of its optimum)")

    def pseudo_inertias(self) -> list[np.ndarray]:
        """Each body's 4 x 4 pseudo-inertia (positive definite)."""
        return [pseudo_inertia(self.values[start:start + LINK_PARAMETERS])
                for kind, start in zip(self.blocks, _starts(self.blocks)) if kind == "body"]


def _starts(blocks: Sequence[str]) -> list[int]:
    """The index of each block's first parameter."""
    return list(np.cumsum([0] + [BLOCK_SIZES[kind] for kind in blocks[:-1]]).astype(int)) if blocks else []


def pseudo_inertia(link: np.ndarray) -> np.ndarray:
    """J of ten standard parameters (m, m c, I about the frame origin: xx, xy, yy, xz, yz, zz)."""
    m, hx, hy, hz, xx, xy, yy, xz, yz, zz = link
    inertia = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    sigma = 0.5 * np.trace(inertia) * np.eye(3) - inertia
    h = np.array([hx, hy, hz])
    return np.block([[sigma, h[:, None]], [h[None, :], np.array([[m]])]])


def _standard_of(J: np.ndarray) -> np.ndarray:
    """The ten standard parameters of a pseudo-inertia (inverse of :func:`pseudo_inertia`)."""
    sigma, h, m = J[:3, :3], J[:3, 3], J[3, 3]
    inertia = np.trace(sigma) * np.eye(3) - sigma
    return np.array([m, *h, inertia[0, 0], inertia[0, 1], inertia[1, 1], inertia[0, 2], inertia[1, 2], inertia[2, 2]])


#: The log-Cholesky exponents are clipped here while the solver explores (e^50: far beyond any body).
EXPONENT_LIMIT = 50.0


def _factor(theta: np.ndarray) -> np.ndarray:
    """U(theta) of the module docstring."""
    alpha, d1, d2, d3, s12, s23, s13, t1, t2, t3 = theta
    alpha, d1, d2, d3 = np.clip([alpha, d1, d2, d3], -EXPONENT_LIMIT, EXPONENT_LIMIT)
    return np.exp(alpha) * np.array([[np.exp(d1), s12, s13, t1], [0.0, np.exp(d2), s23, t2],
                                     [0.0, 0.0, np.exp(d3), t3], [0.0, 0.0, 0.0, 1.0]])


#: Where each log-Cholesky entry of theta (after alpha and the d's) sits in U: s12, s23, s13, t1, t2, t3.
_OFF_DIAGONAL = ((0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3))


def _factor_derivatives(theta: np.ndarray) -> np.ndarray:
    """dU/dtheta_j (10, 4, 4) of :func:`_factor`: U itself for alpha, e^alpha e^d_i at (i, i) for d_i,
    e^alpha at the entry of each s and t; zero for an exponent held at its clip."""
    U = _factor(theta)
    scale = np.exp(np.clip(theta[0], -EXPONENT_LIMIT, EXPONENT_LIMIT))
    inside = np.abs(theta[:4]) < EXPONENT_LIMIT
    out = np.zeros((10, 4, 4))
    out[0] = U * inside[0]
    for i in range(3):
        out[1 + i, i, i] = U[i, i] * inside[1 + i]
    for k, (row, column) in enumerate(_OFF_DIAGONAL):
        out[4 + k, row, column] = scale
    return out


def _standard_derivatives(theta: np.ndarray) -> np.ndarray:
    """d standard / d theta (10, 10) of one link: J = U U^T, dJ = dU U^T + U dU^T, and the standard parameters are
    linear in J (:func:`_standard_of`)."""
    U = _factor(theta)
    return np.array([_standard_of(dU @ U.T + U @ dU.T) for dU in _factor_derivatives(theta)]).T


def _log_cholesky(J: np.ndarray) -> np.ndarray:
    """theta with U(theta) U(theta)^T = J (J positive definite): U = P L^T P of the Cholesky factor of P J P."""
    flip = np.eye(4)[::-1]
    lower = np.linalg.cholesky(flip @ J @ flip)
    U = flip @ lower @ flip                                # upper triangular, U U^T = J
    alpha = np.log(U[3, 3])
    U = U / U[3, 3]
    return np.array([alpha, np.log(U[0, 0]), np.log(U[1, 1]), np.log(U[2, 2]), U[0, 1], U[1, 2], U[0, 2],
                     U[0, 3], U[1, 3], U[2, 3]])


def _regularized(J: np.ndarray, scale: float) -> np.ndarray:
    """J made positive definite for a start: a point mass or a massless link (J singular) gets a small body."""
    eigenvalues, vectors = np.linalg.eigh(J)
    floor = 1e-6 * max(scale, 1e-12)
    return (vectors * np.maximum(eigenvalues, floor)) @ vectors.T


def prior_scale(prior: np.ndarray) -> np.ndarray:
    """The scale of each standard parameter in the prior term: its own size, at least 1e-3 of the largest
    (a zero prior is no scale; all zero: 1)."""
    return np.maximum(np.abs(prior), 1e-3 * float(np.max(np.abs(prior))) if np.any(prior) else 1.0)


def estimate(triangle: np.ndarray, target: np.ndarray, names: Sequence[str], prior: np.ndarray,
             start: np.ndarray | None = None, budget: int = EVALUATIONS) -> ConsistentEstimate:
    """The consistent estimate of the module docstring from the triangular factor ``triangle`` (P x P) and
    ``target`` (z) of the weighted standard regressor and the prior (the model's pi); the blocks from ``names``.
    Parameters a model file holds instead, pi = fixed + T x (:class:`symkin.identification.identified_model.Held`),
    are estimated from ``triangle`` R T and ``target`` z - R fixed, named as x (a rotor shared by several joints:
    ``rotor.Ia``, their friction apart).  ``start``: where the solver starts (default: the prior; a nearby
    estimate saves iterations); ``budget``: the most residual evaluations (the estimate says whether it converged)."""
    from scipy.optimize import least_squares

    count = len(names)
    blocks = layout(names)
    spans = [slice(start, start + BLOCK_SIZES[kind]) for kind, start in zip(blocks, _starts(blocks))]
    first = prior if start is None else start
    starts = []
    for kind, span in zip(blocks, spans):  # theta of the start: each block's own parameterization
        if kind == "body":
            size = max(float(np.max(np.abs(first[span]))), 1e-9)
            starts.append(_log_cholesky(_regularized(pseudo_inertia(first[span]), size)))
        elif kind in LEVELS:
            starts.append(np.maximum(np.linalg.solve(LEVELS[kind], first[span]), 0.0))
        else:
            starts.append(np.maximum(first[span], 0.0) if kind == "mass" else first[span])
    theta0 = np.concatenate(starts) if starts else np.zeros(0)
    lower = np.concatenate([np.full(BLOCK_SIZES[kind], -np.inf if kind in ("body", "free") else 0.0)
                            for kind in blocks]) if blocks else np.zeros(0)
    scale = prior_scale(prior)
    data_scale = max(float(np.linalg.norm(target)), 1e-300)
    weight = np.sqrt(PRIOR_WEIGHT) * data_scale / np.sqrt(count)

    def standard(theta: np.ndarray) -> np.ndarray:
        out = np.empty(count)
        for kind, span in zip(blocks, spans):
            if kind == "body":
                U = _factor(theta[span])
                out[span] = _standard_of(U @ U.T)
            else:
                out[span] = LEVELS[kind] @ theta[span] if kind in LEVELS else theta[span]
        return out

    def residual(theta: np.ndarray) -> np.ndarray:
        pi = standard(theta)
        return np.concatenate([triangle @ pi - target, weight * (pi - prior) / scale])

    rows = np.vstack([triangle, np.diag(weight / scale)])

    def jacobian(theta: np.ndarray) -> np.ndarray:
        """[R; w D^-1] d pi / d theta: block diagonal over the bodies (:func:`_standard_derivatives`), the drives
        and joints' friction (:data:`LEVELS`) and the masses and free parameters (1)."""
        d_pi = np.zeros((len(theta), len(theta)))
        for kind, span in zip(blocks, spans):
            if kind == "body":
                d_pi[span, span] = _standard_derivatives(theta[span])
            else:
                d_pi[span, span] = LEVELS[kind] if kind in LEVELS else 1.0
        return rows @ d_pi

    result = least_squares(residual, theta0, jac=jacobian, bounds=(lower, np.full(len(theta0), np.inf)),
                           method="trf", x_scale="jac", xtol=TOLERANCE, ftol=TOLERANCE, gtol=TOLERANCE, max_nfev=budget)
    pi = standard(result.x)
    best = np.linalg.lstsq(triangle, target, rcond=None)[0]
    return ConsistentEstimate(tuple(names), pi, blocks, float(np.sum((triangle @ pi - target) ** 2)),
                              float(np.sum((triangle @ best - target) ** 2)), bool(result.status > 0),
                              int(result.nfev), float(result.optimality))
