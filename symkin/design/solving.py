"""Solve a dimensioning program with IPOPT (seed sec. 4.1 step 3: "mathematical optimization, e.g. via a
gradient approach"), recording the objective history and the run times."""

from __future__ import annotations

import time
from typing import Any
from dataclasses import dataclass, field

import casadi
import numpy as np

from symkin import reporting
from symkin.design.formulation import DesignProgram
from symkin.design.problem import DesignProblem

#: IPOPT options: quiet, tight tolerances (the problems are small and smooth).
IPOPT_OPTIONS: dict[str, Any] = {
    "ipopt.print_level": 0,
    "ipopt.sb": "yes",
    "ipopt.tol": 1e-10,
    "ipopt.constr_viol_tol": 1e-10,
    "ipopt.max_iter": 300,
    "print_time": False,
}


class IterationReport(casadi.Callback):
    """IPOPT's iteration callback: reports each iteration to :mod:`symkin.reporting` (``stage``, k of at most
    ``max_iter``).  Keep a reference to it until the solve returns (CasADi holds none on the Python side)."""

    def __init__(self, stage: str, problem: dict[str, Any], max_iter: int):
        casadi.Callback.__init__(self)
        self.stage, self.max_iter, self.iterations = stage, max_iter, 0
        sizes = {"x": problem["x"].numel(), "g": problem["g"].numel(), "p": problem["p"].numel() if "p" in problem
                 else 0}
        self.sizes = {"f": 1, **sizes, **{f"lam_{k}": v for k, v in sizes.items()}}
        self.construct("iteration_report", {})

    def get_n_in(self) -> int:
        return casadi.nlpsol_n_out()

    def get_n_out(self) -> int:
        return 1

    def get_name_in(self, i: int) -> str:
        return casadi.nlpsol_out(i)

    def get_name_out(self, i: int) -> str:
        return "ret"

    def get_sparsity_in(self, i: int) -> casadi.Sparsity:
        return casadi.Sparsity.dense(self.sizes[casadi.nlpsol_out(i)], 1)

    def eval(self, arg: Any) -> list:
        reporting.report_progress(self.stage, done=self.iterations, total=self.max_iter)
        self.iterations += 1
        return [0]

    def options(self) -> dict[str, Any]:
        """The solver options that install it."""
        return {"iteration_callback": self}


@dataclass(frozen=True)
class Solution:
    """The optimizer's result.

    Attributes:
        start, optimum: all parameter values of the start and the optimized design.
        surrogate_start, surrogate_optimum: the objective's surrogate at both.
        history: the surrogate at every iterate of the solver (iteration 0 is the start).
        infeasibility: IPOPT's primal infeasibility (largest scaled constraint violation) at every iterate, SLSQP's
            largest violation of its constraints g >= 0 (zeros for a program with bounds only).
        status: the solver's return status; ``success`` whether it converged.
        iterations: the solver's iterations.
        solve_seconds: wall time of the solve (IPOPT's including CasADi's evaluations of f, g and derivatives).
        build_seconds: wall time to build the program and the solver.
        box_points, box_configurations: serial models: the required box's constraint points and
            the optimizer's joint configurations at them (empty without a box).
        constraint_violation: largest violation of g at the optimum (0 where met).
        solver: ``IPOPT`` (:func:`solve`), ``L-BFGS-B`` or ``SLSQP``
            (:func:`symkin.design.gradient_solving.solve_with_jax`).
    """

    start: dict[str, float]
    optimum: dict[str, float]
    surrogate_start: float
    surrogate_optimum: float
    history: np.ndarray
    infeasibility: np.ndarray
    status: str
    success: bool
    iterations: int
    solve_seconds: float
    build_seconds: float
    box_points: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))
    box_configurations: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))
    constraint_violation: float = 0.0
    solver: str = "IPOPT"


def solve(problem: DesignProblem, program: DesignProgram, *, build_seconds: float = 0.0,
          options: dict | None = None) -> Solution:
    """Run IPOPT on the program and read the design off its solution."""
    start = time.perf_counter()
    nlp: dict[str, Any] = {"x": program.x, "f": program.f, "g": program.g}  # MX expressions
    chosen = {**IPOPT_OPTIONS, **(options or {})}
    iterations = IterationReport("optimizing the design (IPOPT iterations)", nlp, int(chosen["ipopt.max_iter"]))
    solver = casadi.nlpsol("design", "ipopt", nlp, chosen | iterations.options())
    build_seconds += time.perf_counter() - start
    start = time.perf_counter()
    result = solver(x0=program.x0, lbx=program.lbx, ubx=program.ubx, lbg=program.lbg, ubg=program.ubg)
    solve_seconds = time.perf_counter() - start
    stats = solver.stats()
    x = np.asarray(result["x"]).ravel()
    g = np.asarray(result["g"]).ravel()
    violation = float(np.max(np.concatenate([[0.0], program.lbg - g, g - program.ubg]))) if g.size else 0.0
    free = program.free_values(x)
    # CasADi records the scaled objective f = -surrogate / reference at every iterate.
    history = -np.asarray(stats["iterations"]["obj"], dtype=np.float64) * program.reference
    box_q = x[program.free_count:program.free_count + program.configuration_count]
    if program.box_points.size and box_q.size:
        box_q = box_q.reshape(len(program.box_points), -1)
    return Solution(
        start=problem.start, optimum=problem.design(list(free)),
        surrogate_start=program.surrogate(program.x0), surrogate_optimum=program.surrogate(x), history=history,
        infeasibility=np.asarray(stats["iterations"]["inf_pr"], dtype=np.float64),
        status=str(stats["return_status"]), success=bool(stats["success"]), iterations=int(stats["iter_count"]),
        solve_seconds=solve_seconds, build_seconds=build_seconds,
        box_points=program.box_points if box_q.size else np.empty((0, 0)),
        box_configurations=box_q if box_q.size else np.empty((0, 0)), constraint_violation=violation)
