"""Dimensioning the seed's 2-DoF arm (sec. 4.4.1, Fig. 8.19) for the global conditioning index.

Seed sec. 4, steps 1-3: (1) the free parameter is the length l1 of the first link (l2 = 10 cm
stays, so the length ratio is free), between 5 and 30 cm; (2) the objective is the GCI
(eq. 8.28) through its smooth Frobenius surrogate over the joint limits 0..90 deg, with the
Cartesian measure dW = |det J| dq; (3) IPOPT on the generated CasADi functions.

Run 1 leaves the workspace free: the optimum is the isotropic design l1 = sqrt(2) l2, whose
Jacobian has kappa = 1 exactly at theta2 = 135 deg.  Run 2 requires the square
0.11 m <= x, y <= 0.14 m to stay reachable: its corner nearest the base bounds the smallest
reach sqrt(l1^2 + l2^2), and the optimum sits on that constraint.

    .venv/bin/python examples/optimize_planar_2r.py [OUT_DIR]      (default out/examples)
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from symkin import design, load, pipeline
from symkin.numerics import conditioning
from symkin.design import plots
from symkin.model import load_model

ROOT = Path(__file__).resolve().parent.parent


def derive(out: Path):
    """models/planar_2r.yaml -> generated fk and jacobian (numpy and CasADi), loaded."""
    model = load_model(ROOT / "models" / "planar_2r.yaml")
    request = pipeline.resolve_request(model, "fk,jacobian", "numpy,casadi")
    directory = pipeline.write(pipeline.generate(model, request), out / "generated")
    return load(directory), load(directory, "casadi")


def run(numpy_model, casadi_model, out: Path, label: str, **requirements) -> design.Solution:
    wall = time.perf_counter()
    problem = design.design_problem(numpy_model, "gci", ["l1"], bounds={"l1": (0.05, 0.30)}, **requirements)
    program = design.formulate(problem, casadi_model, numpy_model)
    solution = design.solve(problem, program)
    before, after = (design.evaluate(problem, numpy_model, d) for d in (solution.start, solution.optimum))
    wall = time.perf_counter() - wall
    print(f"{label}: l1 = {solution.start['l1']:.4f} -> {solution.optimum['l1']:.10f} m "
          f"(l1/l2 = {solution.optimum['l1'] / solution.optimum['l2']:.10f}), {solution.status}")
    print(f"  GCI {before.gci} -> {after.gci}   (surrogate {solution.surrogate_start:.6f} -> "
          f"{solution.surrogate_optimum:.6f})")
    if after.box_reachable is not None:
        print(f"  box reachable at {100 * after.box_reachable:.1f} % of the points ({after.box_check})")
    print(f"  IPOPT {solution.solve_seconds * 1e3:.1f} ms ({solution.iterations} iterations), wall {wall:.2f} s")
    history = plots.history_figure(solution, problem, "planar_2r")
    (out / f"planar_2r-{label}-history.png").write_bytes(plots.png(history))
    (out / f"planar_2r-{label}-design.png").write_bytes(
        plots.png(plots.design_figure(problem, numpy_model, solution, (before, after))))
    return solution


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    numpy_model, casadi_model = derive(out)
    free = run(numpy_model, casadi_model, out, "free-ratio")
    J = numpy_model.bind(**free.optimum).jacobian(np.array([0.0, np.radians(135)]))
    print(f"  kappa at theta2 = 135 deg: {float(conditioning.condition_number(J)):.12f} "
          f"(sqrt(2) = {np.sqrt(2):.10f})")
    box = run(numpy_model, casadi_model, out, "with-box", box={"x": (0.11, 0.14), "y": (0.11, 0.14)})
    print(f"  constraint: sqrt(2 * 0.11^2 - l2^2) = {np.sqrt(2 * 0.11**2 - 0.01):.10f} m, "
          f"optimum {box.optimum['l1']:.10f} m")
    print(f"figures in {out}/")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/examples"))
