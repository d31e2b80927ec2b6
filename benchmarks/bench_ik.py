"""Inverse-kinematics throughput on the generated numpy code (median of several runs).

Run with `make bench` or `python benchmarks/bench_ik.py [--repeat N] [--closed-form-only]`.
Closed forms solve a batch of targets (every branch, verified through fk) and the same
targets one call each (a control loop's case: the per-call overhead of numpy on tiny
arrays); damped least squares solves the batch from starts 0.1 rad away, and from q = 0.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import symkin  # noqa: E402
from symkin.text_table import format_table  # noqa: E402
from symkin.ik import closed_form_solver, solve_numeric  # noqa: E402


def _median(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--batch", type=int, default=1000)
    parser.add_argument("--singles", type=int, default=200, help="targets solved one call each (default: %(default)s)")
    parser.add_argument("--closed-form-only", action="store_true", help="skip damped least squares")
    args = parser.parse_args(argv)
    rng = np.random.default_rng(0)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, outputs in (("planar_2r", ["fk", "jacobian", "jacobian_geometric"]),
                              ("ur10e", ["fk", "jacobian_geometric"])):
            model = symkin.load(symkin.derive(ROOT / "models" / f"{name}.yaml", tmp, outputs=outputs))
            q = rng.uniform(0.05, 1.5, (args.batch, model.manifest["model"]["dof"]))
            T = model.fk(q)
            target = T if name == "ur10e" else T[:, :2, 3]
            solver = closed_form_solver(model)
            found = solver.solve(target)
            seconds = _median(lambda: solver.solve(target), args.repeat)
            rows.append([name, "closed form", args.batch, f"{len(solver.solver.branches)} branches",
                         f"{1e6 * seconds / args.batch:.1f}", f"{found.valid.mean():.2f} valid"])
            singles = target[:args.singles]
            one = _median(lambda: [solver.solve(t) for t in singles], args.repeat)
            rows.append([name, "closed form, one call per target", 1, f"{len(solver.solver.branches)} branches",
                         f"{1e6 * one / len(singles):.1f}", ""])
            if args.closed_form_only:
                continue
            near = q + rng.normal(scale=0.1, size=q.shape)
            for label, start in (("DLS, start 0.1 rad away", near), ("DLS, start q = 0", np.zeros(q.shape[-1]))):
                result = solve_numeric(model, target, start)
                seconds = _median(lambda s=start: solve_numeric(model, target, s), args.repeat)
                rows.append([name, label, args.batch, f"{np.median(result.iterations):.0f} iterations (median)",
                             f"{1e6 * seconds / args.batch:.1f}", f"{result.converged.mean():.2f} converged"])
    print(f"inverse kinematics on generated numpy code, median of {args.repeat} runs")
    print(format_table(["model", "method", "batch", "work", "us per target", "outcome"], rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
