"""The base regressor of legs without the distance form as a CasADi function of the actuators, for the excitation
optimizer (:mod:`symkin.identification.excitation`).

Such legs have no fk: at each sample the passive joints and the pose u = (s, p) solve the closure
Phi_R(q, u) = 0 (R: as many of its rows as u has entries, independent at the home assembly:
:func:`symkin.mechanism.casadi_assembly.independent_rows`) by CasADi's Newton rootfinder from a guess - the start
motion's assembly, continued numerically along it - so that IPOPT differentiates through the implicit function
(du/dq = -A^-1 Phi_q, A = Phi_u; :class:`symkin.mechanism.casadi_assembly.CasadiAssembly`).  There

    W = [I; -A^-1 Phi_q],   zd = W qd,   zdd = W qdd + [0; -A^-1 gamma(z, zd)],   Y = W^T Y_z,b(z, zd, zdd),

the closure's velocities and accelerations as :mod:`symkin.runtime.closure_dynamics` has them, from the generated
``closure``, ``closure_jacobians``, ``closure_dynamics`` (gamma) and ``closure_base_regressor``.
"""

from __future__ import annotations

from collections.abc import Callable

import casadi
import numpy as np

from symkin.backends.casadi.loader import casadi_function
from symkin.mechanism.casadi_assembly import CasadiAssembly
from symkin.mechanism.closure import ClosureAssembly
from symkin.runtime.info import GeneratedModel

#: Bisection steps of the factor that keeps the legs assembled along a shrunk motion.
ASSEMBLY_STEPS = 20


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
    from ``guess`` (the module docstring; :class:`symkin.mechanism.casadi_assembly.CasadiAssembly`), and pi_b, the
    model's parameters at their (bound) values (the outputs of a generated base_regressor)."""
    closure = CasadiAssembly(model, rows)
    q, qd, qdd = (casadi.MX.sym(name, closure.n) for name in ("q", "qd", "qdd"))
    guess = casadi.MX.sym("guess", closure.ns + closure.m)
    s, p = closure.assembly(q, guess)
    rates, accelerations, W = closure.accelerations(q, s, p, qd, qdd)
    terms = closure.call(casadi_function(model, "closure_base_regressor"), q=q, s=s, p=p, **rates, **accelerations)
    return casadi.Function("closure_base_regressor_q", [q, qd, qdd, guess], [W.T @ terms["Y_b"], terms["pi_b"]],
                           ["q", "qd", "qdd", "guess"], ["Y_b", "pi_b"])
