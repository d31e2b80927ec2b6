"""Dynamics of legs without the distance form in the actuated coordinates, from the generated ``closure_dynamics``.

The generated function gives the Lagrangian terms over all the mechanism's variables z = (q, s, p) (M_z, h_z) and
the closure's acceleration term gamma (:mod:`symkin.parallel.closure_dynamics`).  At an assembled state the
closure allows the velocities zd = W qd,

    W = [1; -A^+ Phi_q],   A = [Phi_s Phi_p]   (Phi_z zd = 0; A^+ the pseudo-inverse, exact where A has full
                                                column rank: the passive joints and the platform are determined),

and the accelerations zdd = W qdd + c with c = [0; -A^+ gamma] (Phi_z zdd + gamma = 0).  The constraint forces do no
work on the allowed motions (d'Alembert), so projecting the Lagrange equations M_z zdd + h_z = Q onto them gives the
actuator efforts

    tau = M qdd + b,   M = W^T M_z W,   b = W^T (M_z c + h_z)

(M includes the rotors' gear_ratio^2 J_rotor; b the Coriolis, centrifugal and gravity efforts), plus the actuators'
friction F_f(qd) where the model generates ``friction`` (tau = M qdd + b + F_f, seed eq. 8.34).  Evaluate at an
assembled (q, s, p) (:func:`symkin.runtime.parallel.solve_closure`); NaN in a state gives NaN.  A^+ applies as
R^-1 Q^T from A = Q R where A has full column rank, the SVD's pseudo-inverse elsewhere
(:func:`symkin.newton.left_inverses`); one state of a model whose C code holds ``<model>_actuated_dynamics`` is
projected by that (the same projection, Householder QR).  No sympy: the generated functions only.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from symkin.newton import left_inverses
from symkin.runtime.info import GeneratedModel

if TYPE_CHECKING:
    from symkin.runtime.assembly import GeneratedAssembly


@dataclass(frozen=True)
class ActuatedDynamics:
    """The dynamics of an assembled state in the actuated coordinates (:func:`actuated_dynamics`).

    Attributes:
        M: (..., n, n) the mass matrix W^T M_z W (symmetric positive definite away from singularities).
        bias: (..., n) the efforts at qdd = 0: Coriolis, centrifugal and gravity, W^T (M_z c + h_z).
        friction: (..., n) the actuators' friction efforts F_f(qd) (zero where the model generates no ``friction``).
        W: (..., N, n) the velocities the closure allows, zd = W qd over z = (q, s, p).
        zd: (..., N) the mechanism's velocities W qd.
        potential: (...,) the potential energy u(z).
        drift: (..., N) c, the mechanism's accelerations at qdd = 0: zdd = W qdd + c.
    """

    M: np.ndarray
    bias: np.ndarray
    friction: np.ndarray
    W: np.ndarray
    zd: np.ndarray
    potential: np.ndarray
    drift: np.ndarray

    def accelerations(self, tau) -> np.ndarray:
        """qdd = M^-1 (tau - b - F_f) (..., n): the actuated accelerations under the actuator efforts tau."""
        return np.linalg.solve(self.M, (np.asarray(tau, dtype=float) - self.bias - self.friction)[..., None])[..., 0]

    def efforts(self, qdd) -> np.ndarray:
        """tau = M qdd + b + F_f (..., n): the actuator efforts that move the mechanism with qdd."""
        return np.einsum("...ij,...j->...i", self.M, np.asarray(qdd, dtype=float)) + self.bias + self.friction

    @property
    def kinetic(self) -> np.ndarray:
        """(...,) k = 1/2 qd^T M qd = 1/2 zd^T M_z zd."""
        qd = self.zd[..., :self.M.shape[-1]]
        return 0.5 * np.einsum("...i,...ij,...j->...", qd, self.M, qd)


def actuated_dynamics(model: GeneratedModel, q, s, p, qd, assembly: GeneratedAssembly | None = None
                      ) -> ActuatedDynamics:
    """M, the bias and the friction efforts in the actuated coordinates at an assembled (q, s, p) moving at qd (see
    the module docstring); inputs broadcast against each other.  The model needs ``closure_jacobians`` and
    ``closure_dynamics`` (and ``friction`` for the friction efforts).  ``assembly``: the model's generated assembly,
    whose ``<model>_actuated_dynamics`` (C) then gives one state's terms.
    """
    for name in ("closure_jacobians", "closure_dynamics"):
        if name not in model.functions:
            raise ValueError(f"{model.name}: the dynamics of legs without the distance form need the generated "
                             f"'{name}' (derive with --only closure,closure_jacobians,closure_dynamics and declare "
                             "bodies: links: and platform:)")
    q, s, p, qd = (np.asarray(v, dtype=float) for v in (q, s, p, qd))
    if q.ndim == s.ndim == p.ndim == qd.ndim == 1:
        one = _one_state(model, q, s, p, qd, assembly)
        if one is not None:
            return one
    batch = np.broadcast_shapes(q.shape[:-1], s.shape[:-1], p.shape[:-1], qd.shape[:-1])
    # the generated functions take the batch as it is: one state's 1-D vectors go to their single-state entry points
    q, s, p, qd = (np.broadcast_to(v, batch + v.shape[-1:]) for v in (q, s, p, qd))
    n, ns = q.shape[-1], s.shape[-1]
    blocks = model.closure_jacobians(q, s, p)
    Phi_q, Phi_s, Phi_p = (np.asarray(b, dtype=float).reshape(batch + np.shape(b)[-2:])
                           for b in (blocks.Phi_q, blocks.Phi_s, blocks.Phi_p))
    A = np.concatenate([Phi_s, Phi_p], axis=-1)
    flat = A.reshape((-1,) + A.shape[-2:])
    assembled = np.all(np.isfinite(flat), axis=(-2, -1))  # NaN in, NaN out (an unassembled state)
    inverses = np.full(np.swapaxes(flat, -1, -2).shape, np.nan)
    inverses[assembled] = left_inverses(flat[assembled])
    inverse = inverses.reshape(batch + inverses.shape[-2:])
    W = np.concatenate([np.broadcast_to(np.eye(n), batch + (n, n)), -inverse @ Phi_q], axis=-2)
    zd = np.einsum("...ij,...j->...i", W, qd)
    terms = model.closure_dynamics(q, s, p, qd, zd[..., n:n + ns], zd[..., n + ns:])
    N = W.shape[-2]
    M_z = np.asarray(terms.M_z, dtype=float).reshape(batch + (N, N))
    h_z = np.asarray(terms.h_z, dtype=float).reshape(batch + (N,))
    gamma = np.asarray(terms.gamma, dtype=float).reshape(batch + (-1,))
    c = np.concatenate([np.zeros(batch + (n,)), -np.einsum("...ij,...j->...i", inverse, gamma)], axis=-1)
    WT = np.swapaxes(W, -1, -2)
    friction = (np.asarray(model.friction(qd), dtype=float).reshape(batch + (n,)) if "friction" in model.functions
                else np.zeros(batch + (n,)))
    return ActuatedDynamics(WT @ M_z @ W, np.einsum("...ij,...j->...i", WT, np.einsum("...ij,...j->...i", M_z, c) + h_z),
                            friction, W, zd, np.asarray(terms.u, dtype=float).reshape(batch), c)


def _one_state(model: GeneratedModel, q: np.ndarray, s: np.ndarray, p: np.ndarray, qd: np.ndarray,
               assembly: GeneratedAssembly | None) -> ActuatedDynamics | None:
    """:func:`actuated_dynamics` of one state (a simulation's step) by the generated assembly's
    ``<model>_actuated_dynamics`` (C: the same projection, a few microseconds), or None where the model has none or
    it refuses the state (a dependent column of [Phi_s Phi_p], NaN in the state): the batch path decides there."""
    if assembly is None or not assembly.has_dynamics:
        return None
    terms = assembly.actuated_dynamics(*(np.ascontiguousarray(v) for v in (q, s, p, qd)))
    if terms is None:
        return None
    M, bias, W, drift, u = terms
    n = len(q)
    friction = np.reshape(model.friction(qd), n) if "friction" in model.functions else np.zeros(n)
    return ActuatedDynamics(M, bias, friction, W, W @ qd, np.array(u), drift)


def closure_inverse_dynamics(model: GeneratedModel, q, s, p, qd, qdd) -> np.ndarray:
    """tau = M qdd + b + F_f: the actuator efforts (..., n) that move the assembled mechanism with qdd."""
    return actuated_dynamics(model, q, s, p, qd).efforts(qdd)


def closure_forward_dynamics(model: GeneratedModel, q, s, p, qd, tau) -> np.ndarray:
    """qdd = M^-1 (tau - b - F_f): the actuated accelerations (..., n) under the actuator efforts tau."""
    return actuated_dynamics(model, q, s, p, qd).accelerations(tau)


def closure_regressor(model: GeneratedModel, q, s, p, qd, qdd, base: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(Y, pi) with tau = Y pi (..., n) the actuator efforts that move the assembled mechanism with qdd, friction
    included: Y = W^T Y_z(z, zd, zdd) (..., n, P) at zd = W qd and zdd = W qdd + c, and the model's standard
    parameters pi (..., P), named by the generated ``closure_regressor``'s output elements; with ``base``, the
    base regressor W^T Y_z,b and pi_b of the generated ``closure_base_regressor`` (full column rank).  The model
    needs ``closure_jacobians``, ``closure_dynamics`` (for c) and the regressor.
    """
    name = "closure_base_regressor" if base else "closure_regressor"
    if name not in model.functions:
        raise ValueError(f"{model.name}: the regressor of legs without the distance form needs the generated "
                         f"'{name}' (derive with --only closure_jacobians,closure_dynamics,{name})")
    motion = actuated_dynamics(model, q, s, p, qd)
    batch = motion.zd.shape[:-1]
    q, s, p, qdd = (np.broadcast_to(np.asarray(v, dtype=float), batch + np.shape(v)[-1:]) for v in (q, s, p, qdd))
    n, ns = motion.W.shape[-1], s.shape[-1]
    zdd = np.einsum("...ij,...j->...i", motion.W, qdd) + motion.drift
    zd = motion.zd
    Y_z, pi = getattr(model, name)(q, s, p, zd[..., :n], zd[..., n:n + ns], zd[..., n + ns:],
                                   zdd[..., :n], zdd[..., n:n + ns], zdd[..., n + ns:])
    Y_z = np.broadcast_to(np.asarray(Y_z, dtype=float), batch + np.shape(Y_z)[-2:])
    return np.einsum("...ki,...kj->...ij", motion.W, Y_z), np.broadcast_to(pi, batch + np.shape(pi)[-1:])


def closure_energy_regressor(model: GeneratedModel, q, s, p, qd) -> tuple[np.ndarray, np.ndarray]:
    """(Y_e, pi) with k + u = Y_e pi (...,) the energy of the assembled mechanism moving with qd: the generated
    ``closure_energy_regressor`` at zd = W qd (..., P), and the model's standard parameters pi (..., P).  The model
    needs ``closure_jacobians``, ``closure_dynamics`` (for W) and ``closure_energy_regressor``."""
    if "closure_energy_regressor" not in model.functions:
        raise ValueError(f"{model.name}: the energy regressor of legs without the distance form needs the generated "
                         "'closure_energy_regressor' (derive with --only closure_jacobians,closure_dynamics,"
                         "closure_energy_regressor)")
    zd = actuated_dynamics(model, q, s, p, qd).zd
    batch = zd.shape[:-1]
    q, s, p = (np.broadcast_to(np.asarray(v, dtype=float), batch + np.shape(v)[-1:]) for v in (q, s, p))
    n, ns = q.shape[-1], s.shape[-1]
    Y_e, pi = model.closure_energy_regressor(q, s, p, zd[..., :n], zd[..., n:n + ns], zd[..., n + ns:])
    return (np.broadcast_to(np.asarray(Y_e, dtype=float), batch + np.shape(Y_e)[-1:]),
            np.broadcast_to(pi, batch + np.shape(pi)[-1:]))
