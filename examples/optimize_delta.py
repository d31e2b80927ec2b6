"""Dimensioning the haptic DELTA (models/delta.yaml) for the GCI over a required workspace box.

Seed sec. 4, steps 1-3: (1) the free parameters are the base and platform joint radii and
the upper and lower arm lengths, each within a span that fits a desktop haptic device;
(2) the objective is the GCI (eq. 8.28) over the required workspace, an 80 x 80 x 80 mm
box below the base, through the mean of the smooth 1/kappa_F at fixed grid points (the
joints from the generated closed-form inverse kinematics), subject to the box, grown by a
5 mm margin, staying reachable (the ik radicand >= 0 of every leg at its corners, edges,
faces and the grid points); (3) IPOPT on the generated CasADi functions.  Both designs are
then rated independently: the true GCI (1/kappa from singular values) by randomized QMC
over the box with the generated numpy code, and the box checked on an 11^3 grid.

    .venv/bin/python examples/optimize_delta.py [OUT_DIR]      (default out/examples)
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from symkin import design, load, pipeline
from symkin.design import plots
from symkin.model import load_model

ROOT = Path(__file__).resolve().parent.parent
BOX = {"x": (-0.04, 0.04), "y": (-0.04, 0.04), "z": (-0.19, -0.11)}
BOUNDS = {"r_base": (0.04, 0.10), "r_tcp": (0.015, 0.04), "a": (0.06, 0.15), "b": (0.10, 0.25)}


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    model = load_model(ROOT / "models" / "delta.yaml")
    request = pipeline.resolve_request(model, "ik,jacobian", "numpy,casadi")
    directory = pipeline.write(pipeline.generate(model, request), out / "generated")
    numpy_model, casadi_model = load(directory), load(directory, "casadi")

    wall = time.perf_counter()
    problem = design.design_problem(numpy_model, "gci", list(BOUNDS), bounds=BOUNDS, box=BOX, margin=0.005)
    program = design.formulate(problem, casadi_model, numpy_model)
    solution = design.solve(problem, program)
    before, after = (design.evaluate(problem, numpy_model, d) for d in (solution.start, solution.optimum))
    wall = time.perf_counter() - wall

    print(f"delta: {program.description}")
    for p in problem.free:
        print(f"  {p.name:7s} {p.start * 1e3:7.2f} -> {solution.optimum[p.name] * 1e3:7.2f} mm   "
              f"(bounds {p.lower * 1e3:g} .. {p.upper * 1e3:g} mm)")
    print(f"  {solution.status}, {solution.iterations} iterations; surrogate {solution.surrogate_start:.6f} -> "
          f"{solution.surrogate_optimum:.6f}")
    print(f"  GCI over the box {before.gci} -> {after.gci}")
    print(f"  box reachable at {100 * before.box_reachable:.1f} % -> {100 * after.box_reachable:.1f} % "
          f"of the points ({after.box_check})")
    print(f"  IPOPT {solution.solve_seconds * 1e3:.0f} ms, wall {wall:.2f} s (program, IPOPT, evaluation)")
    (out / "delta-history.png").write_bytes(plots.png(plots.history_figure(solution, problem, "delta")))
    (out / "delta-design.png").write_bytes(plots.png(plots.design_figure(problem, numpy_model, solution,
                                                                          (before, after))))
    print(f"figures in {out}/")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/examples"))
