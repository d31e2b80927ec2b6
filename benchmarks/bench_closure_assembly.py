"""The numeric assembly of a parallel mechanism's closure (symkin.parallel.assembly): SymEngine's LLVM backend
against its tree-walking ``lambda`` backend, in the same process.

The derivation assembles each parallel model at poses about home by damped Gauss-Newton on the generated closure
rows (the base parameters' numerical rank, the platform-motion check), its Jacobian by central differences: one
Newton iteration evaluates the rows at 1 + 2 (n + k) states in one batch.  For each parallel example model: the
time of one such batch and of one whole assembly at a pose near home with each backend, and their ratio.

Run with `make bench` or `python benchmarks/bench_closure_assembly.py [MODEL ...]`.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import symengine

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from symkin.derivation.graph import Derivation  # noqa: E402
from symkin.ir.evaluate import symengine_entries  # noqa: E402
from symkin.model import coordinates, load_model  # noqa: E402
from symkin.parallel.assembly import assembler  # noqa: E402
from symkin.parallel.inputs import passive_symbols, task_symbols  # noqa: E402
from symkin.text_table import format_table  # noqa: E402

MODELS = ("delta", "delta_wrist", "agile_eye", "pantograph", "stewart")
BACKENDS = ("lambda", "llvm")


def _best(run, repeats: int = 5) -> float:
    """The least time of ``repeats`` calls of ``run`` (s)."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return min(times)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="*", default=MODELS, help=f"example models (default: {' '.join(MODELS)})")
    args = parser.parse_args(argv)
    if not symengine.have_llvm:
        print("this SymEngine has no LLVM backend: nothing to compare")
        return 0
    rows = []
    for name in args.models:
        model = load_model(ROOT / "models" / f"{name}.yaml")
        derivation = Derivation(model)
        symbols = coordinates.symbols(model, "q") + passive_symbols(model) + task_symbols(model)
        unknowns = len(symbols) - len(task_symbols(model))
        batch = np.random.default_rng(0).uniform(-1, 1, (1 + 2 * unknowns, len(symbols)))
        home = np.array([float(v) for v in model.parallel.home]) + 0.01
        batch_times, assembly_times = {}, {}
        for backend in BACKENDS:
            rows_of = symengine_entries(derivation["closure"], symbols, model.parameter_values, backend)
            batch_times[backend] = _best(lambda: rows_of(batch), 20)
            assemble = assembler(derivation, backend)
            assembly_times[backend] = _best(lambda: assemble(home), 3)
        rows.append([name, len(batch), f"{1e3 * batch_times['lambda']:.3f}", f"{1e3 * batch_times['llvm']:.3f}",
                     f"{batch_times['lambda'] / batch_times['llvm']:.0f}x", f"{assembly_times['lambda']:.3f}",
                     f"{assembly_times['llvm']:.3f}", f"{assembly_times['lambda'] / assembly_times['llvm']:.0f}x"])
    print(format_table(["model", "batch states", "batch lambda ms", "batch llvm ms", "ratio", "assembly lambda s",
                        "assembly llvm s", "ratio"], rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
