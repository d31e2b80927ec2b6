"""Parallel mechanisms: evaluation time of the generated functions and of the Newton solvers.

Run with `make bench` or `python benchmarks/bench_parallel.py [--batch N] [--repeat N]`.

* generated numpy code (one CSE across the outputs) against sympy.lambdify of the same,
  un-optimized expressions, side by side in this process, for a batch and for one point;
* the DELTA's closed-form FK (trilateration) against Newton's method on the generated leg
  equations (symkin.runtime.parallel.solve_fk): time and largest error against IK(p);
* the Stewart-Gough FK by Newton from a start 1 cm / 0.03 rad away: time per pose,
  iterations and largest error.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
import sympy

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from symkin import load, pipeline  # noqa: E402
from symkin.text_table import format_table  # noqa: E402
from symkin.derivation import Derivation  # noqa: E402
from symkin.model import load_model  # noqa: E402
from symkin.runtime.parallel import solve_fk  # noqa: E402


REFERENCE_BATCH = 2_000


def timed(fn, repeat: int) -> float:
    """Median seconds of ``repeat`` calls."""
    runs = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        runs.append(time.perf_counter() - start)
    return statistics.median(runs)


def lambdified(model, derivation: Derivation, name: str):
    spec = derivation[name]
    vectors = [list(i.symbols) for i in spec.vector_inputs]
    exprs = [sympy.Matrix(o.expr).xreplace(model.parameter_values) for o in spec.outputs]
    fn = sympy.lambdify(vectors, exprs, modules="numpy")
    return lambda *args: fn(*(np.moveaxis(a, -1, 0) for a in args))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--batch", type=int, default=100_000)
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    out = Path(tempfile.mkdtemp(prefix="symkin-bench-"))
    loaded, derivations, models = {}, {}, {}
    for name in ("delta", "stewart"):
        model = load_model(ROOT / "models" / f"{name}.yaml")
        pipeline.write(pipeline.generate(model, pipeline.resolve_request(model)), out)
        loaded[name], derivations[name], models[name] = load(out / name), Derivation(model), model
    rng = np.random.default_rng(1)
    n = args.batch
    p_delta = np.column_stack([rng.uniform(-0.04, 0.04, (n, 2)), rng.uniform(-0.18, -0.12, n)])
    q_delta = loaded["delta"].ik(p_delta).joints
    p_stewart = np.column_stack([rng.uniform(-0.03, 0.03, (n, 2)), rng.uniform(0.2, 0.26, n),
                                 rng.uniform(-0.15, 0.15, (n, 3))])
    q_stewart = loaded["stewart"].ik(p_stewart).joints
    cases = [
        ("delta", "ik", (p_delta,)), ("delta", "fk", (q_delta,)), ("delta", "jacobian", (q_delta, p_delta)),
        ("delta", "singularities", (q_delta, p_delta)),
        ("stewart", "ik", (p_stewart,)), ("stewart", "inverse_jacobian", (q_stewart, p_stewart)),
        ("stewart", "singularities", (q_stewart, p_stewart)),
    ]
    rows = []
    for model_name, function, inputs in cases:
        generated = getattr(loaded[model_name], function)
        reference = lambdified(models[model_name], derivations[model_name], function)
        one = tuple(x[0] for x in inputs)
        few = tuple(x[:REFERENCE_BATCH] for x in inputs)  # lambdify is slow: time it on fewer points
        t_gen = timed(lambda: generated(*inputs), args.repeat) / n
        t_ref = timed(lambda: reference(*few), 3) / len(few[0])
        t_gen1, t_ref1 = timed(lambda: generated(*one), 200), timed(lambda: reference(*one), 20)
        rows.append([model_name, function, f"{1e9 * t_gen:.1f}", f"{1e9 * t_ref:.1f}", f"{t_ref / t_gen:.1f}",
                     f"{1e6 * t_gen1:.1f}", f"{1e6 * t_ref1:.1f}", f"{t_ref1 / t_gen1:.1f}"])
    print(f"generated numpy (batch {n}, median of {args.repeat}) vs sympy.lambdify of the un-optimized expressions "
          f"(batch {REFERENCE_BATCH}, median of 3)")
    print(format_table(["model", "function", "ns/point", "lambdify ns/point", "ratio", "us/call (1 point)",
                        "lambdify us/call", "ratio"], rows))

    m = min(n, 10_000)
    delta = loaded["delta"]
    t_closed = timed(lambda: delta.fk(q_delta[:m]), args.repeat)
    err_closed = np.max(np.abs(delta.fk(q_delta[:m]).position - p_delta[:m]))
    start = p_delta[:m] + rng.normal(0, 0.005, (m, 3))
    t_newton = timed(lambda: solve_fk(delta, q_delta[:m], start), args.repeat)
    report = solve_fk(delta, q_delta[:m], start)
    stewart = loaded["stewart"]
    start_s = p_stewart[:m] + rng.normal(0, [0.01] * 3 + [0.03] * 3, (m, 6))
    t_stewart = timed(lambda: solve_fk(stewart, q_stewart[:m], start_s), args.repeat)
    report_s = solve_fk(stewart, q_stewart[:m], start_s)
    rows = [
        ["delta", "fk (trilateration, closed form)", f"{1e6 * t_closed / m:.2f}", "-", f"{err_closed:.1e}", "all"],
        ["delta", "solve_fk (Newton, 5 mm start)", f"{1e6 * t_newton / m:.2f}", str(report.iterations.max()),
         f"{np.nanmax(np.abs(report.solution - p_delta[:m])):.1e}", f"{report.converged.mean():.1%}"],
        ["stewart", "solve_fk (Newton, 1 cm / 0.03 rad start)", f"{1e6 * t_stewart / m:.2f}",
         str(report_s.iterations.max()), f"{np.nanmax(np.abs(report_s.solution - p_stewart[:m])):.1e}",
         f"{report_s.converged.mean():.1%}"],
    ]
    print(f"\nforward kinematics, batch {m}")
    print(format_table(["model", "method", "us/pose", "max iterations", "max error", "converged"], rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
