"""Dynamics of parallel mechanisms: derive time, and the generated C against Pinocchio's constrained dynamics.

Run with `make bench` or `python benchmarks/bench_parallel_dynamics.py [--batch N] [--calls N] [--repeat N]`.

* derive: models/delta.yaml and models/stewart.yaml (parameters folded), mass_matrix, coriolis_vector, gravity_vector,
  inverse_dynamics, forward_dynamics and operational_space derived, optimized and emitted to numpy,
  C and CasADi, everything `symkin derive` does from loading the model (median of --repeat runs).
* evaluation: the DELTA's generated C inverse_dynamics, gravity_vector and forward_dynamics, timed
  in C (bench_eval's harness: one call per state of a ring of 1024, and the batch entry point; the
  harness's inputs are uniform in [-pi, pi], not assembled states, which straight-line code does not
  notice), and from Python through the loaded library at assembled states (one call; a batch).
  Pinocchio's constraintDynamics of the same DELTA (benchmarks/competitors.pinocchio_delta: a tree
  of 12 joints closed by three point constraints, the exact KKT solve with the loop multipliers) is
  timed from Python per call, beside the cost of a trivial Pinocchio call from Python (its binding
  overhead), which the ratio against symkin's Python call shares.  Pinocchio has no closed-loop
  inverse dynamics or gravity compensation: its forward dynamics is the like-for-like row, and
  the two forward dynamics' largest difference at the assembled states is printed.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT.parent))
sys.path.insert(0, str(ROOT))

from bench_eval import HARNESS_HEAD, HARNESS_TAIL, RING, run_harness, symkin_case_c  # noqa: E402
from competitors import constraint_dynamics_of, delta_tree_state, pinocchio_delta  # noqa: E402
from symkin import load, pipeline  # noqa: E402
from symkin.model import load_model  # noqa: E402
from symkin.text_table import format_table  # noqa: E402

DYNAMICS = ("mass_matrix", "coriolis_vector", "gravity_vector", "inverse_dynamics", "forward_dynamics",
            "operational_space")
TIMED = ("inverse_dynamics", "gravity_vector", "forward_dynamics")


def derive_seconds(name: str, out: Path) -> float:
    start = time.perf_counter()
    model = load_model(ROOT / "models" / f"{name}.yaml")
    outputs = ["ik"] + (["fk", "jacobian"] if name == "delta" else []) + list(DYNAMICS)
    request = pipeline.resolve_request(model, outputs, ["numpy", "c", "casadi"], "all", combine="none")
    pipeline.write(pipeline.generate(model, request), out)
    return time.perf_counter() - start


def per_call_us(fn, states, repeat: int = 5) -> float:
    """Median over ``repeat`` passes of the mean time of one call, cycling through ``states``."""
    runs = []
    for _ in range(repeat):
        start = time.perf_counter()
        for s in states:
            fn(*s)
        runs.append((time.perf_counter() - start) / len(states))
    return 1e6 * statistics.median(runs)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--batch", type=int, default=100_000, help="states per batched call (default 1e5)")
    parser.add_argument("--calls", type=int, default=1_000_000, help="single calls per C timing run (default 1e6)")
    parser.add_argument("--repeat", type=int, default=3, help="derive runs (median; default 3)")
    parser.add_argument("--cflags", default="-O3 -march=native", help="flags of the C harness (default: %(default)s)")
    args = parser.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="symkin-bench-"))
    os.environ.setdefault("SYMKIN_CACHE_DIR", str(work / "cache"))
    try:
        rows = [[name, f"{statistics.median(derive_seconds(name, work / f'd{k}') for k in range(args.repeat)):.2f}"]
                for name in ("delta", "stewart")]
        print(f"derive + optimize + emit (numpy, C, CasADi) of {', '.join(DYNAMICS)}, median of {args.repeat}")
        print(format_table(["model", "seconds"], rows))

        target = work / "d0" / "delta"
        c_model = load(target, "c")
        source = HARNESS_HEAD % {"includes": '#include "delta.h"'} + "".join(
            symkin_case_c(name, "delta", next(f for f in c_model.manifest["functions"] if f["name"] == name))
            for name in TIMED) + HARNESS_TAIL
        in_c = run_harness(source, [target / "delta.c"], [target], [os.environ.get("CC", "cc")],
                           ["-std=c99", *args.cflags.split()], work, args.calls, args.batch, "harness_delta")

        rng = np.random.default_rng(2)
        p = np.column_stack([rng.uniform(-0.03, 0.03, (args.batch, 2)), rng.uniform(-0.17, -0.13, args.batch)])
        q = c_model.ik(p).joints
        qd, qdd, tau = (rng.uniform(-1, 1, (args.batch, 3)) for _ in range(3))
        inputs = {"inverse_dynamics": (q, p, qd, qdd), "gravity_vector": (q, p), "forward_dynamics": (q, p, qd, tau)}
        table = []
        for name in TIMED:
            fn = getattr(c_model, name)
            ring = [tuple(a[k] for a in inputs[name]) for k in range(RING)]
            start = time.perf_counter()
            fn(*inputs[name])
            batch_ns = 1e9 * (time.perf_counter() - start) / args.batch
            table.append([name, "symkin C", f"{in_c[name, 'single']:.0f}", f"{in_c[name, 'batch']:.0f}",
                          f"{per_call_us(fn, ring):.2f}", f"{batch_ns:.0f}"])
        agreement = None
        try:
            import pinocchio as pin
        except ImportError:
            print("Pinocchio: not installed (pip install pin); its rows are left out")
        else:
            values = {s.name: float(v) for s, v in load_model(ROOT / "models" / "delta.yaml").parameter_values.items()}
            pin, tree, constraints, legs = pinocchio_delta(values)
            data, datas, settings = constraint_dynamics_of(pin, tree, constraints)
            states = []
            for k in range(RING):
                x, v, arms = delta_tree_state(pin, tree, data, legs, values, p[k], q[k], qd[k])
                efforts = np.zeros(tree.nv)
                efforts[arms] = tau[k]
                states.append((x, v, efforts))
            call = lambda x, v, e: pin.constraintDynamics(tree, data, x, v, e, constraints, datas, settings)  # noqa: E731
            symkin_qdd = c_model.forward_dynamics(q[:RING], p[:RING], qd[:RING], tau[:RING])
            agreement = max(np.abs(call(*state)[arms] - ours).max() / np.abs(ours).max()
                            for state, ours in zip(states, symkin_qdd))
            table.append(["forward_dynamics", "Pinocchio constraintDynamics", "", "", f"{per_call_us(call, states):.2f}",
                          ""])
            floor = lambda x, v, e: pin.computeGeneralizedGravity(tree, data, x)  # noqa: E731
            table.append(["(binding overhead)", "Pinocchio computeGeneralizedGravity", "", "",
                          f"{per_call_us(floor, states):.2f}", ""])
        print(f"\nDELTA evaluation, C flags '{args.cflags}', batch {args.batch}")
        print(format_table(["function", "implementation", "C call [ns]", "C batch [ns/state]", "py call [us]",
                            "py batch [ns/state]"], table))
        if agreement is not None:
            print(f"symkin C forward_dynamics against Pinocchio's constraintDynamics at the {RING} assembled states: "
                  f"largest difference {agreement:.1e} of the largest acceleration")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
