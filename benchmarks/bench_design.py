"""Run times of dimensioning optimization (symkin.design): program build, IPOPT, independent evaluation.

Run with `make bench` or `python benchmarks/bench_design.py [--repeat N]`.  Each problem is
built and solved from scratch (median over the repeats), on the committed generated code
(generated/planar_2r, generated/delta): building the CasADi program (mapping the generated
functions over the nodes), IPOPT (including CasADi's function and derivative evaluations),
and the independent rating of the start and the optimum (true GCI by randomized QMC,
2^14 evaluations each, and the box check).
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
    return {"build": solution.build_seconds, "ipopt": solution.ipopt_seconds, "iterations": solution.iterations,
            "evaluation": time.perf_counter() - start, "wall": time.perf_counter() - wall,
            "before": before.gci, "after": after.gci}


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
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
