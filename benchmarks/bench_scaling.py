"""Derive time and operation counts against the number of joints (issue 12).

For the generated n-joint chains of ``chain_models.py`` (n = 3, 6, 12, 24 by default):
``symkin derive --only fk,jacobian,mass_matrix,coriolis_vector,gravity_vector --backend
numpy,c`` in process (load, derive, optimize, emit; no compilation), with the operations
of every function as derived (a tree count) and after CSE, and the exponent of a power-law
fit of the derive time against n over the sizes from 6 on.

The generated dynamics are set against the algorithmic operation counts of the recursive
algorithms Pinocchio runs on the same chain (``recursive_reference.py``: CRBA for M, RNEA
with qdd = 0 for V + G, counted on CasADi symbols); issue 12's target is a ratio <= 1.5.

Run with `make bench` or `python benchmarks/bench_scaling.py [--sizes 3,6,12,24]`.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from chain_models import chain_yaml, dh_chain  # noqa: E402
from recursive_reference import arithmetic_operations, crba_function, rnea_function  # noqa: E402
from symkin import pipeline  # noqa: E402
from symkin.model import load_model  # noqa: E402
from symkin.text_table import format_table  # noqa: E402

OUTPUTS = "fk,jacobian,mass_matrix,coriolis_vector,gravity_vector"
GRAVITY = (0.0, 0.0, -9.81)


def measure(n: int, directory: Path) -> dict[str, float]:
    path = directory / f"chain{n}.yaml"
    path.write_text(chain_yaml(n))
    start = time.perf_counter()
    model = load_model(path)
    result = pipeline.generate(model, pipeline.resolve_request(model, OUTPUTS, "numpy,c", None, None, None))
    generated = time.perf_counter()
    pipeline.write(result, directory / "out")
    seconds = time.perf_counter() - start
    parts = {r.name: r.op_counts for r in result.reports if r.name != "combined"}
    derive = sum(r.derive_seconds for r in result.reports)
    optimize = sum(r.optimize_seconds for r in result.reports)
    return {"n": n, "seconds": seconds, "derive": derive, "optimize": optimize, "emit": result.emit_seconds,
            "other": generated - start - derive - optimize - result.emit_seconds, "write": seconds - (generated - start),
            "derived": sum(c["derived"] for c in parts.values()), "cse": sum(c["cse"] for c in parts.values()),
            "combined": next((r.op_counts["cse"] for r in result.reports if r.name == "combined"), 0),
            "mass_matrix": parts["mass_matrix"]["cse"],
            "bias": parts["coriolis_vector"]["cse"] + parts["gravity_vector"]["cse"],
            "crba": arithmetic_operations(crba_function(dh_chain(n))),
            "rnea": arithmetic_operations(rnea_function(dh_chain(n), GRAVITY, with_acceleration=False))}


def fitted_exponent(rows: list[dict[str, float]]) -> float:
    """Least-squares slope of log(time) against log(n), over n >= 6 (small n is fixed overhead)."""
    points = [(math.log(r["n"]), math.log(r["seconds"])) for r in rows if r["n"] >= 6]
    if len(points) < 2:
        return float("nan")
    mx = sum(x for x, _ in points) / len(points)
    my = sum(y for _, y in points) / len(points)
    return sum((x - mx) * (y - my) for x, y in points) / sum((x - mx) ** 2 for x, _ in points)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", default="3,6,12,24", help="numbers of joints, comma-separated (default: %(default)s)")
    args = parser.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in (int(s) for s in args.sizes.split(",")):
            rows.append(measure(n, Path(tmp)))
            r = rows[-1]
            print(f"  n = {n}: {r['seconds']:.2f} s", file=sys.stderr, flush=True)
    print(f"derive {OUTPUTS} (numpy, c) for generated n-joint chains")
    print(format_table(["n", "wall (s)", "ops derived (tree)", "ops after CSE", "combined ops"],
                       [[r["n"], f"{r['seconds']:.2f}", f"{r['derived']:,}", f"{r['cse']:,}", f"{r['combined']:,}"]
                        for r in rows]))
    print(f"fitted exponent of the derive time in n (n >= 6): {fitted_exponent(rows):.2f}")
    print()
    print("where the wall time goes (s): sympy derivation, expression optimization (value numbering, CSE), "
          "emission (printers, templates), the rest of generate (model load, request), writing the files")
    print(format_table(["n", "derive", "optimize", "emit", "other", "write"],
                       [[r["n"]] + [f"{r[k]:.2f}" for k in ("derive", "optimize", "emit", "other", "write")]
                        for r in rows]))
    print()
    print("generated dynamics against the recursive algorithms (operations; target ratio <= 1.5)")
    print(format_table(["n", "M (symkin)", "CRBA", "ratio", "V + G (symkin)", "RNEA qdd=0", "ratio"],
                       [[r["n"], f"{r['mass_matrix']:,}", f"{r['crba']:,}", f"{r['mass_matrix'] / r['crba']:.2f}",
                         f"{r['bias']:,}", f"{r['rnea']:,}", f"{r['bias'] / r['rnea']:.2f}"] for r in rows]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
