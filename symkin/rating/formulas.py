"""A haptic device rated as its datasheet rates it: what the hand feels and what the device can render
at the handle, from the joint-space M, the task Jacobian J (v = J qd), G and the actuators' data.

Every function takes stacks (``...``) of J, M and G in the array module ``xp``: numpy, or jax.numpy inside the
datasheet's program on JAX's device (:mod:`symkin.rating.on_device`); the actuators' data stay numpy.  At one pose,
with n joints and J the m x n translational rows
of the task Jacobian (square for a translational device: 3 x 3 for a DELTA, 2 x 2 for a pantograph or a
planar arm; m < n for a redundant device, e.g. a DELTA carrying a wrist pushed at its grip):

* **apparent mass**: Lambda = (J M^-1 J^T)^-1 (Khatib 1987; J^-T M J^-1 for a square J), F = Lambda a
  from rest.  Its eigenvalues are the masses the hand feels along its principal directions, their
  ratio its isotropy (Salcudean and Stocco 2000; the inertia conditioning of Cammarata 2010).
* **force capability**: with |tau_i| <= tau_max,i the renderable forces F = J^-T tau fill a
  parallelepiped.  The isotropic force (in every direction) is min_i tau_max,i / |J_i|
  (:func:`symkin.rating.forces.isotropic_force`), the peak force (in the best direction) its
  farthest vertex, max over s in {-1, 1}^n of |J^-T (s * tau_max)| (with more joints than task
  coordinates, J the translational rows of an arm pushed at its TCP: the farthest vertex of the
  polytope |J^T F| <= tau_max, tried at every choice of m joints at their limits).
* **position resolution**: encoders that step q_i by dq_i (rad or m per count at the joint) move the
  handle between neighbouring readings (each joint by at most one count) by at most the farthest
  vertex of the zonotope J [-dq, dq], max_s |J (s * dq)|, to first order in dq.
* **Coulomb friction at the handle**: moving with the velocity v the joints resist with
  tau_c,i sign(qd_i), qd = J^-1 v, felt along u = v / |v| as u . J^-T (tau_c * sign(qd)).  Its largest
  value over all directions is again a farthest vertex, max_s |J^-T (s * tau_c)|: with w = J^-1 v,
  sum_i tau_c,i |w_i| = max_s (s * tau_c) . w, and max_w c . w / |J w| = |J^-T c| (Cauchy-Schwarz).  A
  redundant device slips in the joint motion that costs least, min over J w = u of sum tau_c,i |w_i|: the
  farthest point of the polytope |J^T F| <= tau_c, as the peak force (:func:`coulomb_friction_felt`).
* **gravity budget**: max_i |G_i| / tau_max,i, the largest share of an actuator's effort that holding
  the device against gravity takes from what it can render.
* **renderable stiffness**: a virtual wall K (with virtual damping B) rendered by a loop of period T
  on a device with physical damping b is passive iff b > K T / 2 + |B| (Colgate and Schenkel 1997,
  after Colgate and Brown 1994), so K_max = 2 (b - |B|) / T and |B| < b.  At the handle b is the
  smallest eigenvalue of the joints' viscous damping seen there, J^-T diag(b_j) J^-1 ((J B^-1 J^T)^-1 for a
  redundant device, :func:`handle_damping`): the direction in which the device is least damped limits the wall.
* **passive wall along an axis** (issue 64): a wall normal to the task axis e, F = -K q(x_e) e with q the encoders'
  quantization, held for one period.  For one joint (a mass with viscous b and Coulomb f_c, encoder step Delta)
  Abbott and Okamura (IEEE T-RO 21(5), 2005) show it passive if and only if K < 2 b / T and K < 2 f_c / Delta: two
  decoupled modes, a growing oscillation (b, T; Colgate and Brown 1994) and a limit cycle one count wide (f_c,
  Delta).  Both follow from the wall's work over a closed cycle of sampled positions x_k,
  -sum K q(x_k) dx_k = K sum dx_k^2 / 2 + K sum (x_k - q(x_k)) dx_k <= K sum dx_k^2 / 2 + K Delta U (U the motion
  towards the wall), against the dissipation b sum dx_k^2 / T + 2 f_c U.  At the handle the hand may move sideways
  as it pushes, so each input is the worst over the motions whose component along e is one: the least damping
  b_e = 1 / (e^T J B^-1 J^T e) (:func:`axis_damping`), the least Coulomb force f_e = min_i tau_c,i / |J_ei|
  (:func:`axis_slip_friction`), and the widest quantization error along e, Delta_e = sum_i |J_ei| dq_i
  (:func:`axis_quantization`); K_e = min(2 b_e / T, 2 f_e / Delta_e) is then sufficient, and for one joint
  (J = 1) it is Abbott and Okamura's bound.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from typing import Any

import numpy as np


def apparent_mass(M: np.ndarray, J: np.ndarray, xp: Any = np) -> np.ndarray:
    """Lambda = (J M^-1 J^T)^-1 (..., m, m): the inertia the hand feels at the handle, F = Lambda a from rest.

    Args:
        M: joint-space mass matrices (..., n, n).
        J: task Jacobians (..., m, n), v = J qd, of full row rank m <= n.
    """
    return xp.linalg.inv(mobility(M, J, xp))


def mobility(M: np.ndarray, J: np.ndarray, xp: Any = np) -> np.ndarray:
    """J M^-1 J^T (..., m, m): the handle's acceleration per unit force from rest, the inverse apparent mass."""
    M, J = xp.asarray(M, dtype=float), xp.asarray(J, dtype=float)
    return J @ xp.linalg.solve(M, xp.swapaxes(J, -1, -2))


def principal_masses(M: np.ndarray, J: np.ndarray, xp: Any = np, *, handle_mobility: Any = None) -> np.ndarray:
    """The eigenvalues of the apparent mass (..., m), ascending: the masses felt along its principal axes, the
    reciprocals of the eigenvalues of the mobility J M^-1 J^T (inf along a direction a singular J cannot move).
    ``handle_mobility``: J M^-1 J^T where the caller has it (:func:`mobility`), else formed here."""
    eigenvalues = xp.linalg.eigvalsh(mobility(M, J, xp) if handle_mobility is None else handle_mobility)[..., ::-1]
    return xp.where(eigenvalues > 0.0, 1.0 / xp.where(eigenvalues > 0.0, eigenvalues, 1.0), np.inf)


def farthest_vertex(A: np.ndarray, half_widths: Sequence[float] | np.ndarray, xp: Any = np) -> np.ndarray:
    """max over s in {-1, 1}^n of |A (s * h)| (...,): the largest image under A (..., m, n) of the box
    |x_i| <= h_i, reached at a vertex as |A x| is convex.  s and -s give the same length, so 2^(n-1)
    sign vectors are tried."""
    A = xp.asarray(A, dtype=float)
    h = np.broadcast_to(np.asarray(half_widths, dtype=float), A.shape[-1:])
    n = A.shape[-1]
    signs = np.array([(1.0,) + rest for rest in itertools.product((1.0, -1.0), repeat=n - 1)])  # (2^(n-1), n)
    images = xp.einsum("...mn,kn->...km", A, signs * h)
    return xp.max(xp.linalg.norm(images, axis=-1), axis=-1)


#: Above this condition number J is taken as singular: the forces at the handle are NaN there.
SINGULAR_CONDITION = 1e12


def inverse_transpose(J: np.ndarray, xp: Any = np) -> np.ndarray:
    """J^-T (..., m, m), NaN where J is singular (kappa > :data:`SINGULAR_CONDITION`): what the forces at the handle
    (F = J^-T tau), its friction and its damping take; a caller rating several of them forms it once and passes it
    (``inverse_transpose=``)."""
    J = xp.asarray(J, dtype=float)
    if J.shape[-1] != J.shape[-2]:
        raise ValueError(f"the handle's forces need a square task Jacobian (F = J^-T tau), got "
                         f"{J.shape[-2]} x {J.shape[-1]}")
    with np.errstate(invalid="ignore"):
        regular = xp.linalg.cond(J) < SINGULAR_CONDITION
    safe = xp.where(regular[..., None, None], J, np.eye(J.shape[-1]))
    return xp.where(regular[..., None, None], xp.swapaxes(xp.linalg.inv(safe), -1, -2), np.nan)


def _given_or_formed(given: Any, J: np.ndarray, xp: Any) -> Any:
    """J^-T as the caller gave it, or formed here (:func:`inverse_transpose`)."""
    return inverse_transpose(J, xp) if given is None else given


def peak_force(J: np.ndarray, effort_limits: Sequence[float] | np.ndarray, xp: Any = np, *,
               inverse_transpose: Any = None) -> np.ndarray:
    """The largest force the actuators render in the best direction (...,): max |F| over the polytope
    |J_i . F| <= tau_max,i (tau = J^T F).

    Its farthest point is a vertex, where m of the n slabs' faces meet: for a square J the 2^n points
    J^-T (s * tau_max); with more joints than task coordinates (an arm pushed at its TCP, J its
    translational rows) every choice of m joints at their limits whose point the others can hold
    (within a relative 1e-9 of their limits) is tried.  ``inverse_transpose``: J^-T of a square J where the caller
    has it (:func:`inverse_transpose`).
    """
    J = xp.asarray(J, dtype=float)
    m, n = J.shape[-2:]
    if m > n:
        raise ValueError(f"the handle's forces need at least as many joints as task coordinates, got a {m} x {n} "
                         "task Jacobian")
    limits = np.broadcast_to(np.asarray(effort_limits, dtype=float), (n,))
    if m == n:
        return farthest_vertex(_given_or_formed(inverse_transpose, J, xp), limits, xp)
    chosen = np.array(list(itertools.combinations(range(n), m)))                 # (C, m): the joints at their limits
    signs = np.array([(1.0,) + rest for rest in itertools.product((1.0, -1.0), repeat=m - 1)])  # (S, m)
    columns = xp.moveaxis(J[..., :, chosen], -3, -2)                            # (..., C, m, m)
    regular = xp.abs(xp.linalg.det(columns)) > 1e-12 * xp.prod(xp.linalg.norm(columns, axis=-2), axis=-1)
    square = xp.where(regular[..., None, None], columns, np.eye(m))
    limited = limits[chosen][:, :, None] * signs.T[None]                       # (C, m, S): tau at every vertex
    F = xp.linalg.solve(xp.swapaxes(square, -1, -2), xp.broadcast_to(limited, square.shape[:-1] + signs.shape[:1]))
    efforts = xp.abs(xp.einsum("...mn,...cmk->...cnk", J, F))                   # (..., C, n, S)
    feasible = regular[..., None] & xp.all(efforts <= limits[:, None] * (1 + 1e-9), axis=-2)
    return xp.max(xp.where(feasible, xp.linalg.norm(F, axis=-2), 0.0), axis=(-2, -1))


def position_resolution(J: np.ndarray, joint_steps: Sequence[float] | np.ndarray, xp: Any = np) -> np.ndarray:
    """The largest handle step between neighbouring encoder readings (...,): max_s |J (s * dq)|, dq the joints'
    steps per count (rad or m)."""
    return farthest_vertex(J, joint_steps, xp)


def axis_mass(M: np.ndarray, J: np.ndarray, xp: Any = np, *, handle_mobility: Any = None) -> np.ndarray:
    """The mass felt pushing along each task axis e_a from rest, the handle free in the others (..., m):
    1 / (e_a^T Lambda^-1 e_a), the force along e_a per unit acceleration along it (Khatib 1995's effective mass
    along a direction; a vendor's "apparent mass at the tip" along an axis); inf along an axis the handle cannot
    move along; ``handle_mobility`` as for :func:`principal_masses`."""
    handle_mobility = mobility(M, J, xp) if handle_mobility is None else handle_mobility
    with np.errstate(divide="ignore"):
        return 1.0 / xp.diagonal(handle_mobility, axis1=-2, axis2=-1)


def axis_step(J: np.ndarray, joint_steps: Sequence[float] | np.ndarray, xp: Any = np) -> np.ndarray:
    """The handle's step along each task axis for one encoder count of the joint that moves it most there (..., m):
    max_i |J_ai| dq_i, a vendor's "nominal position resolution" per axis (one count at a time, against
    :func:`position_resolution`'s every joint stepping at once)."""
    J = xp.asarray(J, dtype=float)
    return xp.max(xp.abs(J) * np.abs(np.asarray(joint_steps, dtype=float)), axis=-1)


def axis_friction(J: np.ndarray, coulomb: Sequence[float] | np.ndarray, xp: Any = np, *,
                  inverse_transpose: Any = None) -> np.ndarray:
    """The Coulomb friction felt moving the handle along each task axis e_a (..., m), J square: the joints turn at
    w = J^-1 e_a per unit speed and resist with power sum_i tau_c,i |w_i| (a vendor's "backdrive friction" along
    an axis; :func:`coulomb_friction_felt` is its largest over all directions); NaN where J is singular."""
    rates = xp.swapaxes(_given_or_formed(inverse_transpose, J, xp), -1, -2)   # column a: J^-1 e_a
    return xp.einsum("i,...ia->...a", np.abs(np.asarray(coulomb, dtype=float)), xp.abs(rates))


def coulomb_friction_felt(J: np.ndarray, coulomb: Sequence[float] | np.ndarray, xp: Any = np, *,
                          inverse_transpose: Any = None) -> np.ndarray:
    """The largest Coulomb friction force the hand feels, over all directions of motion (...,): the farthest
    point of the polytope |J_i . F| <= tau_c,i, max_s |J^-T (s * tau_c)| for a square J.

    Moving the handle along u, the joints slip with some w, J w = u, and dissipate sum_i tau_c,i |w_i|; the
    hand pushes the device into the motion that costs least (a redundant device - more joints than task
    coordinates - chooses among many w), so the friction felt along u is min over J w = u of sum tau_c,i |w_i|,
    which by linear-programming duality is max over |J^T F| <= tau_c of F . u, the support function of that
    polytope.  Its largest value over all directions u is the polytope's farthest point (:func:`peak_force`
    with the Coulomb levels as limits)."""
    return peak_force(J, coulomb, xp, inverse_transpose=inverse_transpose)


def gravity_share(G: np.ndarray, effort_limits: Sequence[float] | np.ndarray, xp: Any = np) -> np.ndarray:
    """max_i |G_i| / tau_max,i (...,): the largest share of an actuator's effort limit spent holding the device."""
    G = xp.asarray(G, dtype=float)
    return xp.max(xp.abs(G) / np.broadcast_to(np.asarray(effort_limits, dtype=float), G.shape[-1:]), axis=-1)


def handle_damping(J: np.ndarray, viscous: Sequence[float] | np.ndarray, xp: Any = np, *,
                   inverse_transpose: Any = None) -> np.ndarray:
    """The smallest viscous damping at the handle (...,), N s/m: the least eigenvalue of J^-T diag(b) J^-1 for
    a square J.

    With more joints than task coordinates the joints the hand moves at the velocity v are those that dissipate
    least, min over J w = v of w^T B w = v^T (J B^-1 J^T)^-1 v (B = diag(b); the damping's counterpart of the
    apparent mass (J M^-1 J^T)^-1), so the least damping is 1 / the largest eigenvalue of J B^-1 J^T; 0 where an
    undamped joint (b_j = 0) moves the handle.
    """
    J = xp.asarray(J, dtype=float)
    m, n = J.shape[-2:]
    b = np.broadcast_to(np.asarray(viscous, dtype=float), (n,))
    if m == n:
        inverse_transpose = _given_or_formed(inverse_transpose, J, xp)
        damping = (inverse_transpose * b) @ xp.swapaxes(inverse_transpose, -1, -2)
        return xp.linalg.eigvalsh(damping)[..., 0]
    damped = b > 0
    free_motion = xp.any(xp.linalg.norm(J[..., :, ~damped], axis=-2) > 0, axis=-1)
    mobility = (J[..., :, damped] / b[damped]) @ xp.swapaxes(J[..., :, damped], -1, -2)
    largest = xp.linalg.eigvalsh(mobility)[..., -1]
    with np.errstate(divide="ignore"):
        return xp.where(free_motion, 0.0, 1.0 / largest)


def axis_damping(J: np.ndarray, viscous: Sequence[float] | np.ndarray, xp: Any = np) -> np.ndarray:
    """The least viscous damping of a handle motion whose component along each task axis e_a is one (..., m):
    b_e = 1 / (e^T J B^-1 J^T e), B = diag(b_j) (min over J w = v, e . v = 1 of w^T B w, the hand free to move
    sideways); 0 where an undamped joint moves the handle along e, inf where no joint does."""
    J = xp.asarray(J, dtype=float)
    b = np.broadcast_to(np.asarray(viscous, dtype=float), J.shape[-1:])
    moves = xp.abs(J) > 0.0
    undamped = xp.any(moves & (b == 0.0), axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        compliance = xp.sum(xp.where(moves, J ** 2 / np.where(b > 0.0, b, 1.0), 0.0), axis=-1)
        return xp.where(undamped, 0.0, 1.0 / compliance)


def axis_slip_friction(J: np.ndarray, coulomb: Sequence[float] | np.ndarray, xp: Any = np) -> np.ndarray:
    """The least Coulomb friction force of a handle motion whose component along each task axis e_a is one
    (..., m): f_e = min over J w = v, e . v = 1 of sum_i tau_c,i |w_i| = min_i tau_c,i / |J_ei| (a weighted l1
    minimum sits on one joint: the hand slips in the joint that resists least per unit motion along e); inf where no
    joint moves the handle along e."""
    J = xp.abs(xp.asarray(J, dtype=float))
    tau = np.broadcast_to(np.abs(np.asarray(coulomb, dtype=float)), J.shape[-1:])
    with np.errstate(divide="ignore"):
        return xp.min(xp.where(J > 0.0, tau / xp.where(J > 0.0, J, 1.0), np.inf), axis=-1)


def axis_quantization(J: np.ndarray, joint_steps: Sequence[float] | np.ndarray, xp: Any = np) -> np.ndarray:
    """The width of the quantization error along each task axis (..., m): every encoder reads its joint up to one
    count dq_i below its position, so the handle's reading along e is off by up to Delta_e = sum_i |J_ei| dq_i."""
    J = xp.abs(xp.asarray(J, dtype=float))
    return xp.sum(J * np.abs(np.asarray(joint_steps, dtype=float)), axis=-1)


def quantization_stiffness(friction: np.ndarray | float, quantization: np.ndarray | float, xp: Any = np
                           ) -> np.ndarray:
    """K < 2 f_c / Delta (N/m): the stiffest wall whose one-count limit cycle the device's Coulomb friction f_c
    dissipates, with encoder quantization Delta (Abbott and Okamura 2005; :func:`renderable_stiffness` is the other
    half of their condition)."""
    with np.errstate(divide="ignore"):
        return 2.0 * xp.asarray(friction, dtype=float) / xp.asarray(quantization, dtype=float)


def renderable_stiffness(damping: np.ndarray | float, period: float, virtual_damping: float = 0.0, xp: Any = np
                         ) -> np.ndarray:
    """K_max = 2 (b - |B|) / T (N/m): the stiffest virtual wall a loop of period T renders passively on a device
    with physical damping b at the handle and virtual damping B (Colgate and Schenkel 1997); 0 where |B| >= b."""
    if not period > 0.0:
        raise ValueError(f"the servo period must be positive, got {period:g} s")
    return xp.maximum(2.0 * (xp.asarray(damping, dtype=float) - abs(virtual_damping)) / period, 0.0)
