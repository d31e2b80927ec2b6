"""The closure in CasADi: the assembly of legs of any topology as a differentiable function of the actuators
(issue 62: the CasADi counterpart of :class:`symkin.mechanism.closure.ClosureAssembly`, which the excitation design
asks; issue 63: the generated forward kinematics and J = dp/dq in CasADi).

A model loaded with the CasADi backend whose legs have no closed forms has the generated ``closure``
phi(q, s, p) and ``closure_jacobians`` (Phi_q, Phi_s, Phi_p).  The passive joints and the pose u = (s, p) at the
actuators q solve R of the closure's rows, Phi_R(q, u) = 0, where R (:func:`independent_rows`) are as many rows as u
has entries, independent at the home assembly (the others vanish identically, as the dual SCARA's tilts, or repeat
them, as a translational platform's legs do).  CasADi's Newton rootfinder solves them from a guess (a control loop's
previous sample, or :class:`~symkin.mechanism.closure.ClosureAssembly`'s continuation along a motion), and
differentiates the solution by the implicit function theorem:

    du/dq = -A^-1 Phi_q,   A = Phi_u = [Phi_s Phi_p] on the rows R,

so that J = dp/dq is the p-part of it, W = [I; -A^-1 Phi_q] maps qd to the closure's rates zd = (qd, sd, pd), and
zdd = W qdd - [0; A^-1 gamma(z, zd)] (gamma from the generated ``closure_dynamics``: the closure's second
derivative at qdd = 0).  :meth:`CasadiAssembly.function` checks the result: s, p and J are NaN where the rootfinder
stopped short of closing every row of the closure (max |phi| above :data:`symkin.mechanism.closure.CLOSED` times
the pose's scale), and an assembly that may belong to another mode than the guess's is flagged - never a plausible
but wrong assembly unsaid.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Any

import casadi
import numpy as np

from symkin.backends.casadi.loader import casadi_function
from symkin.mechanism.closure import CLOSED, ClosureAssembly
from symkin.runtime.info import GeneratedModel


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


class CasadiAssembly:
    """The assembly u = (s, p) of a CasADi-loaded model of legs without closed forms, its rates and accelerations,
    as CasADi expressions of the actuators (the module docstring).

    Args:
        model: the model loaded with ``backend="casadi"`` (its ``closure`` and ``closure_jacobians``; its
            ``closure_dynamics`` for :meth:`accelerations`).
        rows: the closure's rows R (:func:`independent_rows`).
        parameters: the model's parameters by name, numbers or CasADi symbols (a design program's free lengths);
            default its (bound) values.  The rootfinder (:meth:`assembly`, :meth:`function`) needs numbers.
    """

    def __init__(self, model: GeneratedModel, rows: list[int], parameters: Mapping[str, Any] | None = None):
        self.model, self.rows = model, list(rows)
        self.parameters = dict(model.parameters if parameters is None else parameters)
        self._closure = casadi_function(model, "closure")
        self._jacobians = casadi_function(model, "closure_jacobians")
        self.n, self.ns, self.m = (self._closure.size1_in(k) for k in range(3))

    @classmethod
    def at_home(cls, model: GeneratedModel, runtime: GeneratedModel,
                parameters: Mapping[str, Any] | None = None) -> CasadiAssembly:
        """The assembly of the CasADi-loaded ``model`` on the closure's rows independent at the home assembly of
        ``runtime`` (the same model loaded for the run-time mechanism, at the parameters' values to find it at).

        Raises:
            GeneratedCodeError: the legs do not close at the home pose.
            ValueError: the closure's rows do not fix (s, p) there.
        """
        return cls(model, independent_rows(ClosureAssembly(runtime)), parameters)

    @functools.cached_property
    def _rootfinder(self) -> casadi.Function:
        q, u = casadi.MX.sym("q", self.n), casadi.MX.sym("u", self.ns + self.m)
        residual = casadi.Function("closure_rows", [u, q], [self.residual(q, u[:self.ns], u[self.ns:])])
        return casadi.rootfinder("assembly", "newton", residual, {"error_on_fail": False})

    def call(self, function: casadi.Function, **states: Any) -> dict[str, Any]:
        """A generated function's outputs by name, its states given and its parameters at :attr:`parameters`."""
        def parameter(name: str) -> Any:
            value = self.parameters[name]
            return value if isinstance(value, (casadi.SX, casadi.MX)) else casadi.DM(value)

        return function.call({name: states[name] if name in states else parameter(name)
                              for name in function.name_in()})

    def residual(self, q: Any, s: Any, p: Any) -> Any:
        """phi(q, s, p) on the rows R: what the rootfinder zeroes, a design program's equality constraints."""
        return self.call(self._closure, q=q, s=s, p=p)["phi"][self.rows]

    def assembly(self, q: Any, guess: Any) -> tuple[Any, Any]:
        """(s, p) closing the rows R at the actuators q, by Newton from ``guess`` = (s, p) stacked (unchecked: the
        rootfinder's last iterate where it did not converge; :meth:`function` checks)."""
        u = self._rootfinder(guess, q)
        return u[:self.ns], u[self.ns:]

    def _blocks(self, q: Any, s: Any, p: Any) -> tuple[Any, Any]:
        """(A, Phi_q) on the rows R: A = [Phi_s Phi_p], the closure's Jacobian in the unknowns u = (s, p)."""
        blocks = self.call(self._jacobians, q=q, s=s, p=p)
        return casadi.horzcat(blocks["Phi_s"], blocks["Phi_p"])[self.rows, :], blocks["Phi_q"][self.rows, :]

    def velocity_map(self, q: Any, s: Any, p: Any) -> tuple[Any, Any]:
        """(W, A) at an assembly: W = [I; -A^-1 Phi_q] ((n + ns + m) x n, zd = W qd) and A = [Phi_s Phi_p] on the
        rows R."""
        A, Phi_q = self._blocks(q, s, p)
        return casadi.vertcat(casadi.DM.eye(self.n), -casadi.solve(A, Phi_q)), A

    def jacobian(self, q: Any, s: Any, p: Any) -> Any:
        """J = dp/dq (m x n) at an assembly: the p-rows of W."""
        return self.velocity_map(q, s, p)[0][self.n + self.ns:, :]

    def accelerations(self, q: Any, s: Any, p: Any, qd: Any, qdd: Any) -> tuple[dict[str, Any], dict[str, Any], Any]:
        """(rates, accelerations, W) of the closure's variables at an assembly: {"qd", "sd", "pd"},
        {"qdd", "sdd", "pdd"} (the generated ``closure_dynamics``' gamma for the velocity product)."""
        W, A = self.velocity_map(q, s, p)
        n, ns = self.n, self.ns
        zd = W @ qd
        rates = {"qd": qd, "sd": zd[n:n + ns], "pd": zd[n + ns:]}
        gamma = self.call(casadi_function(self.model, "closure_dynamics"), q=q, s=s, p=p, **rates)["gamma"][self.rows]
        zdd = W @ qdd + casadi.vertcat(casadi.DM.zeros(n), -casadi.solve(A, gamma))
        return rates, {"qdd": qdd, "sdd": zdd[n:n + ns], "pdd": zdd[n + ns:]}, W

    def function(self) -> casadi.Function:
        """``assembly(q, guess) -> (s, p, J, residual, jump)``: the checked forward kinematics - (s, p) from the
        guess, J = dp/dq (m x n), max |phi| over every closure row, and 1 where the assembly may belong to another
        mode than the guess's (else 0).  s, p and J are NaN where the residual is above
        :data:`~symkin.mechanism.closure.CLOSED` max(1, max |p|) (the rootfinder did not close the legs).

        The jump flag is the Newton-Kantorovich bound read backwards (Ortega and Rheinboldt, Iterative Solution of
        Nonlinear Equations in Several Variables, 12.6.2): inside the guess's Kantorovich region the solution is
        the one its mode continues to and lies within 2 |d_0| of the guess, d_0 = -A^-1 Phi_R the first Newton
        correction there (max-norms); a solution farther away says the guess was outside it (as the C assembly's
        negative count, :mod:`symkin.backends.c.assembly`).  A full turn of a passive joint counts as a jump too.
        Differentiable where the legs close (the rootfinder's implicit-function sensitivities)."""
        q, guess = casadi.MX.sym("q", self.n), casadi.MX.sym("guess", self.ns + self.m)
        s, p = self.assembly(q, guess)
        J = self.jacobian(q, s, p)
        residual = casadi.mmax(casadi.fabs(self.call(self._closure, q=q, s=s, p=p)["phi"]))
        closed = residual <= CLOSED * casadi.fmax(1, casadi.mmax(casadi.fabs(p)))
        s0, p0 = guess[:self.ns], guess[self.ns:]
        A0, _ = self._blocks(q, s0, p0)
        first = casadi.solve(A0, self.residual(q, s0, p0))
        jump = casadi.mmax(casadi.fabs(casadi.vertcat(s, p) - guess)) > 2 * casadi.mmax(casadi.fabs(first))

        def checked(value: Any) -> Any:
            return casadi.if_else(closed, value, casadi.DM.nan(*value.shape))

        return casadi.Function("assembly", [q, guess], [checked(s), checked(p), checked(J),
                                                         residual, jump],
                               ["q", "guess"], ["s", "p", "J", "residual", "jump"])
