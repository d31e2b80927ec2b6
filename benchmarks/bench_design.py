"""Run times of dimensioning optimization (symkin.design): program build, IPOPT, independent evaluation; and
IPOPT on the CasADi program against L-BFGS-B on JAX gradients of the same surrogate (``--gradients jax``).

Run with `make bench` or `python benchmarks/bench_design.py [--repeat N]`.  Each problem is
built and solved from scratch (median over the repeats), on the committed generated code
(generated/planar_2r, generated/delta): building the CasADi program (mapping the generated
functions over the nodes), IPOPT (including CasADi's function and derivative evaluations),
and the independent rating of the start and the optimum (true GCI by randomized QMC,
2^14 evaluations each, and the box check).  The second table solves the problems both solvers take (a serial
model's GCI within bounds; a parallel model's GCI or worst force over a required box, the force also under a bound on
the apparent mass) both ways in the same process:
the CasADi program's build and IPOPT against the JAX path's first call (XLA's compile of the surrogate's value and
gradient) and a warm solve (what every later design or restart costs: the program is compiled once per generated
Jacobian), on generated/'s JAX modules.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import symkin  # noqa: E402
from symkin import design  # noqa: E402
from symkin.text_table import format_table  # noqa: E402

PROBLEMS = {
    "planar_2r, free l1/l2": ("planar_2r", dict(free=["l1"], bounds={"l1": (0.05, 0.3)})),
    "planar_2r, free l1, box": ("planar_2r", dict(free=["l1"], bounds={"l1": (0.05, 0.3)},
                                                  box={"x": (0.11, 0.14), "y": (0.11, 0.14)})),
    "delta, 4 free, box": ("delta", dict(free=["r_base", "r_tcp", "a", "b"],
                                         bounds={"r_base": (0.04, 0.10), "r_tcp": (0.015, 0.04), "a": (0.06, 0.15),
                                                 "b": (0.10, 0.25)},
                                         box={"x": (-0.04, 0.04), "y": (-0.04, 0.04), "z": (-0.19, -0.11)},
                                         margin=0.005)),
}


def _run(numpy_model, casadi_model, options: dict) -> dict[str, float]:
    options = dict(options)
    free = options.pop("free")
    wall = time.perf_counter()
    problem = design.design_problem(numpy_model, "gci", free, **options)
    program = design.formulate(problem, casadi_model, numpy_model)
    solution = design.solve(problem, program, build_seconds=time.perf_counter() - wall)
    start = time.perf_counter()
    before, after = (design.evaluate(problem, numpy_model, d) for d in (solution.start, solution.optimum))
    return {"build": solution.build_seconds, "ipopt": solution.solve_seconds, "iterations": solution.iterations,
            "evaluation": time.perf_counter() - start, "wall": time.perf_counter() - wall,
            "before": before.gci, "after": after.gci}


DELTA_BOX = {"x": (-0.04, 0.04), "y": (-0.04, 0.04), "z": (-0.19, -0.11)}
#: The problems of the solver comparison: model, objective, free parameters, design_problem's other options.
GRADIENT_PROBLEMS = {
    "planar_2r gci, free l1": ("planar_2r", "gci", dict(free=["l1"])),
    "ur10e gci, free a2, a3 (L = 0.3 m)": ("ur10e", "gci", dict(free=["a2", "a3"], length=0.3)),
    "delta gci, free a, b, box (SLSQP)": ("delta", "gci", dict(free=["a", "b"], box=DELTA_BOX)),
    "delta force, free a, b, box (SLSQP, epigraph)": ("delta", "force", dict(
        free=["a", "b"], bounds={"a": (0.06, 0.15), "b": (0.10, 0.25)}, box=DELTA_BOX, effort_limits=[1.0, 1.0, 1.0])),
    "delta force, apparent mass <= 0.2 kg (SLSQP)": ("delta", "force", dict(
        free=["a", "b"], bounds={"a": (0.06, 0.15), "b": (0.10, 0.25)}, box=DELTA_BOX, effort_limits=[1.0, 1.0, 1.0],
        max_apparent_mass=0.2)),
}


def _timed(solve, *args) -> tuple[float, object]:
    """(wall seconds, solution) of one solve (build included)."""
    start = time.perf_counter()
    solution = solve(*args)
    return time.perf_counter() - start, solution


def _solve_with_casadi(problem, casadi_model, numpy_model):
    return design.solve(problem, design.formulate(problem, casadi_model, numpy_model))


def _solve_with_jax(problem, jax_model, numpy_model):
    from symkin.design.gradient_solving import solve_with_jax

    return solve_with_jax(problem, jax_model, numpy_model)[0]


def _compare_solvers(repeat: int) -> list[list[str]]:
    """Per problem: IPOPT's median ms (build and solve) and iterations; JAX's first call (compile included), its
    median warm ms and iterations; their ratio and how far the optima differ."""
    rows = []
    for label, (name, objective, options) in GRADIENT_PROBLEMS.items():
        options = dict(options)
        free = options.pop("free")
        numpy_model, casadi_model, jax_model = (symkin.load(ROOT / "generated" / name, backend)
                                                for backend in ("numpy", "casadi", "jax"))  # every scene emits JAX
        problem = design.design_problem(numpy_model, objective, free, **options)
        first, _ = _timed(_solve_with_jax, problem, jax_model, numpy_model)
        _solve_with_casadi(problem, casadi_model, numpy_model)  # warm-up: CasADi's plugin loading
        ipopt = [_timed(_solve_with_casadi, problem, casadi_model, numpy_model) for _ in range(repeat)]
        warm = [_timed(_solve_with_jax, problem, jax_model, numpy_model) for _ in range(repeat)]
        ipopt_ms, jax_ms = (statistics.median(t for t, _ in runs) * 1e3 for runs in (ipopt, warm))
        rows.append([label, f"{ipopt_ms:.1f}", str(ipopt[0][1].iterations), f"{first * 1e3:.0f}", f"{jax_ms:.1f}",
                     str(warm[0][1].iterations), f"{ipopt_ms / jax_ms:.1f}x",
                     f"{max(abs(warm[0][1].optimum[k] / ipopt[0][1].optimum[k] - 1) for k in free):.1e}"])
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args(argv)
    rows = []
    for label, (name, options) in PROBLEMS.items():
        models = symkin.load(ROOT / "generated" / name), symkin.load(ROOT / "generated" / name, "casadi")
        _run(*models, options)  # warm-up: imports (scipy.stats, matplotlib-free), CasADi plugin loading
        runs = [_run(*models, options) for _ in range(args.repeat)]
        median = {k: statistics.median(r[k] for r in runs) for k in ("build", "ipopt", "evaluation", "wall")}
        rows.append([label, f"{runs[0]['iterations']}", f"{median['build'] * 1e3:.0f}", f"{median['ipopt'] * 1e3:.0f}",
                     f"{median['evaluation'] * 1e3:.0f}", f"{median['wall'] * 1e3:.0f}",
                     str(runs[0]["before"]), str(runs[0]["after"])])
    print(format_table(["problem", "iter", "build ms", "IPOPT ms", "eval ms", "wall ms", "GCI before", "GCI after"],
                       rows))
    print()
    print(format_table(["problem", "CasADi+IPOPT ms", "iter", "JAX first call ms", "JAX warm ms", "iter",
                        "IPOPT/JAX", "optima differ (rel)"], _compare_solvers(args.repeat)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
