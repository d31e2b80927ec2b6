"""Derive time of every example model: load, derive, optimize, emit (median of several runs).

Run with `make bench` or `python benchmarks/bench_derive.py [--repeat N] [MODEL ...]`.
Each run starts from a fresh derivation graph (nothing memoized between runs).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from symkin import pipeline  # noqa: E402
from symkin.text_table import format_table  # noqa: E402
from symkin.model import load_model  # noqa: E402


def measure(path: Path) -> dict[str, float | str]:
    start = time.perf_counter()
    model = load_model(path)
    loaded = time.perf_counter()
    result = pipeline.generate(model, pipeline.resolve_request(model))
    done = time.perf_counter()
    return {
        "load": loaded - start,
        "derive": sum(r.derive_seconds for r in result.reports),
        "optimize": sum(r.optimize_seconds for r in result.reports),
        "emit": result.emit_seconds,
        "total": done - start,
        "outputs": ",".join(result.request.outputs),
        "ops": sum(r.op_counts["cse"] for r in result.reports),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("models", nargs="*", type=Path, default=sorted((ROOT / "models").glob("*.yaml")))
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args(argv)
    rows = []
    for path in args.models:
        runs = [measure(path) for _ in range(args.repeat)]
        med = {k: statistics.median(r[k] for r in runs) for k in ("load", "derive", "optimize", "emit", "total")}
        rows.append([path.stem, runs[0]["outputs"], runs[0]["ops"]] +
                    [f"{1e3 * med[k]:.1f}" for k in ("load", "derive", "optimize", "emit", "total")])
    print(f"derive time per model, median of {args.repeat} runs (ms)")
    print(format_table(["model", "outputs", "ops", "load", "derive", "optimize", "emit", "total"], rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
