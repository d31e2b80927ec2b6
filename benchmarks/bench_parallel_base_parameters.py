"""Parallel base parameters (issue 33): the exact modular elimination against the numerical route.

For each parallel example model: the time to derive its regressor's formula, then its base parameters exactly
(symkin.parallel.base_parameters: the formula over a prime field at states on the closure, compiled once into a
straight-line program; K's entries as polynomials in the geometry, verified with a second prime), against the
route SymPyBotics takes for serial arms, run in the same process on the same formula: the regressor in floating
point at random assembled states, stacked, and its numerical rank by SVD with a threshold (the count only: no
regrouping, no geometry kept symbolic).  The derivation includes that numerical check too (the counts must agree),
so the exact column's time covers both.  The dual SCARA of docs/model-format.md (legs without the distance form,
taken from the document) runs the elimination of symkin.parallel.closure_base: points of the closure over the
prime field by resultants, Y = W^T Y_z there; its numerical rank is that of W^T Y_z at assembled states.

Run with `make bench` or `python benchmarks/bench_parallel_base_parameters.py [MODEL ...]`.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from documented_models import DOCUMENTED, model_text  # noqa: E402

from symkin.derivation.graph import Derivation  # noqa: E402
from symkin.model import load_model, model_from_text  # noqa: E402
from symkin.parallel.base_regressor import closure_rank  # noqa: E402
from symkin.parallel.closure_base import assembled_rank  # noqa: E402
from symkin.parallel.regressor import reduced_regressor  # noqa: E402
from symkin.text_table import format_table  # noqa: E402

MODELS = ("delta", "delta_wrist", "agile_eye", "pantograph", "stewart", "dual_scara")


def _model(name: str):
    if name not in DOCUMENTED:
        return load_model(ROOT / "models" / f"{name}.yaml")
    return model_from_text(model_text(name), file=f"docs/model-format.md ({name})")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="*", default=MODELS, help=f"example models (default: {' '.join(MODELS)})")
    args = parser.parse_args(argv)
    rows = []
    for name in args.models:
        model = _model(name)
        derivation = Derivation(model)
        closure = name in DOCUMENTED
        start = time.perf_counter()
        columns = derivation["closure_regressor" if closure else reduced_regressor].outputs[0].shape[1]
        formula = time.perf_counter() - start
        start = time.perf_counter()
        found = derivation["closure_base_parameters" if closure else "base_parameters"]
        exact = time.perf_counter() - start
        start = time.perf_counter()
        rank = assembled_rank(derivation) if closure else closure_rank(derivation, columns)
        numeric = time.perf_counter() - start
        rows.append([name, str(columns), str(len(found.base)), str(rank), f"{formula:.2f} s", f"{exact:.2f} s",
                     f"{numeric:.2f} s", f"{exact / numeric:.1f}x"])
    print(format_table(["model", "columns", "base (exact)", "numerical rank", "formula", "exact base parameters",
                        "numerical rank only", "exact / numerical"], rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
