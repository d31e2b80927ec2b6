"""The base regressor of legs without the distance form as a CasADi function of the actuators, for the excitation
optimizer (:mod:`symkin.identification.excitation`).

Such legs have no fk: at each sample the passive joints and the pose u = (s, p) solve the closure
Phi_R(q, u) = 0 (R: as many of its rows as u has entries, independent at the home assembly; the others vanish
identically, as the dual SCARA's tilts, or repeat them) by CasADi's Newton rootfinder from a guess - the start
motion's assembly, continued numerically along it - so that IPOPT differentiates through the implicit function
(du/dq = -A^-1 Phi_q, A = Phi_u).  There

    W = [I; -A^-1 Phi_q],   zd = W qd,   zdd = W qdd + [0; -A^-1 gamma(z, zd)],   Y = W^T Y_z,b(z, zd, zdd),

the closure's velocities and accelerations as :mod:`symkin.runtime.closure_dynamics` has them, from the generated
``closure``, ``closure_jacobians``, ``closure_dynamics`` (gamma) and ``closure_base_regressor``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import casadi
import numpy as np

from symkin.design.formulation import casadi_function
from symkin.runtime.info import GeneratedModel
from symkin.mechanism.closure import ClosureAssembly

#: Bisection steps of the factor that keeps the legs assembled along a shrunk motion.
ASSEMBLY_STEPS = 20


def independent_rows(closure: ClosureAssembly) -> list[int]:
    """The closure's rows R whose [Phi_s Phi_p] is square and invertible at the home assembly: the first
    independent ones (rows that vanish identically, or repeat others, left out).

    Raises:
        ValueError: the closure's rows do not fix (s, p) there (a singular assembly).
    """
    model, q = closure.model, closure.home
    s, p = closure(q)
    jacobians = model.closure_jacobians(q, s, p)
    A = np.hstack([np.asarray(jacobians.Phi_s, dtype=float), np.asarray(jacobians.Phi_p, dtype=float)])
    rows: list[int] = []
    for k in range(A.shape[0]):
        if np.linalg.matrix_rank(A[rows + [k]], tol=1e-9 * max(float(np.abs(A).max()), 1.0)) > len(rows):
            rows.append(k)
    if len(rows) != A.shape[1]:
        raise ValueError(f"{model.name}: the closure fixes {len(rows)} of the {A.shape[1]} passive joints and pose "
                         "coordinates at the home assembly (a singular assembly); move the home pose")
    return rows


def guesses(closure: ClosureAssembly, q: np.ndarray) -> np.ndarray:
    """u = (s, p) (size, samples) along the motion q (samples, n), continued from the home assembly.

    Raises:
        ValueError: the legs stop closing along it.
    """
    s, p = closure(q)
    u = np.concatenate([s, p], axis=1)
    if not np.all(np.isfinite(u)):
        raise ValueError(f"{closure.model.name}: the legs stop closing along the excitation's motion (from its "
                         "home assembly); narrow the limits about home or lower --max-velocity")
    return u.T


def assembled_factor(closure: ClosureAssembly, motion: Callable[[float], np.ndarray], shrink: float) -> float:
    """The largest f <= ``shrink`` (to 2^-ASSEMBLY_STEPS of it) at which the legs close along ``motion(f)`` (the
    check grid's actuator positions of the motion shrunk by f), continued from the home assembly."""

    def closes(f: float) -> bool:
        s, p = closure(motion(f))
        return bool(np.all(np.isfinite(s)) and np.all(np.isfinite(p)))

    if closes(shrink):
        return shrink
    low, high = 0.0, shrink
    for _ in range(ASSEMBLY_STEPS):
        low, high = ((low + high) / 2, high) if closes((low + high) / 2) else (low, (low + high) / 2)
    return low


def regressor_function(model: GeneratedModel, rows: list[int]) -> casadi.Function:
    """(Y_b, pi_b)(q, qd, qdd, guess): W^T Y_z,b (n x columns) at the assembly u = (s, p) that the rootfinder finds
    from ``guess`` (the module docstring), and pi_b, the model's parameters at their (bound) values (the outputs of
    a generated base_regressor)."""
    closure, jacobians = casadi_function(model, "closure"), casadi_function(model, "closure_jacobians")
    dynamics, base = casadi_function(model, "closure_dynamics"), casadi_function(model, "closure_base_regressor")
    n, ns, m = closure.size1_in(0), closure.size1_in(1), closure.size1_in(2)
    q, qd, qdd = (casadi.MX.sym(name, n) for name in ("q", "qd", "qdd"))
    u, guess = casadi.MX.sym("u", ns + m), casadi.MX.sym("guess", ns + m)

    def call(function: casadi.Function, **states: Any) -> dict[str, Any]:
        return function.call({name: states[name] if name in states else casadi.DM(model.parameters[name])
                              for name in function.name_in()})

    residual = casadi.Function("closure_rows", [u, q], [call(closure, q=q, s=u[:ns], p=u[ns:])["phi"][rows]])
    assembly = casadi.rootfinder("assembly", "newton", residual, {"error_on_fail": False})(guess, q)
    s, p = assembly[:ns], assembly[ns:]
    J = call(jacobians, q=q, s=s, p=p)
    A = casadi.horzcat(J["Phi_s"], J["Phi_p"])[rows, :]
    W = casadi.vertcat(casadi.DM.eye(n), -casadi.solve(A, J["Phi_q"][rows, :]))
    zd = W @ qd
    rates = {"qd": qd, "sd": zd[n:n + ns], "pd": zd[n + ns:]}
    gamma = call(dynamics, q=q, s=s, p=p, **rates)["gamma"][rows]
    zdd = W @ qdd + casadi.vertcat(casadi.DM.zeros(n), -casadi.solve(A, gamma))
    accelerations = {"qdd": qdd, "sdd": zdd[n:n + ns], "pdd": zdd[n + ns:]}
    terms = call(base, q=q, s=s, p=p, **rates, **accelerations)
    return casadi.Function("closure_base_regressor_q", [q, qd, qdd, guess], [W.T @ terms["Y_b"], terms["pi_b"]],
                           ["q", "qd", "qdd", "guess"], ["Y_b", "pi_b"])
