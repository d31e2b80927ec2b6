"""Constant-orientation workspace and GCI of the Stewart-Gough platform: values, errors and run time.

Run with `make bench` or `python benchmarks/bench_stewart.py`.  For the example platform
(models/stewart.yaml, legs 0.20 ... 0.32 m) at the home orientation and at a tilted one, it
times (best of 3, numpy and C backends) the Cartesian box, the automatic characteristic
length and the volume and GCI (Cartesian domain, 1/kappa of the twist Jacobian homogenized
by L) with the qmc and grid integrators at a ladder of budgets, and prints the estimates
with their error estimates.  Nothing is asserted: the figures go into docs/analysis.md.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import symkin  # noqa: E402
from symkin.analysis import global_indices  # noqa: E402
from symkin.mechanism import reach  # noqa: E402

ORIENTATIONS = {"home (0, 0, 0 deg)": (0.0, 0.0, 0.0), "tilted (5, -8, 20 deg)": tuple(np.radians([5, -8, 20]))}
BUDGETS = (2**12, 2**14, 2**16, 2**18)


def best_of(repeats, function):
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return min(times), result


def main() -> None:
    for backend in ("numpy", "c"):
        model = symkin.load(ROOT / "generated" / "stewart", backend)
        for label, orientation in ORIENTATIONS.items():
            held = reach.constant_orientation(model, orientation)
            ik = reach.generated_inverse(held)
            seconds, box = best_of(3, lambda: reach.bounding_box(held))
            print(f"stewart ({backend}) at {label}: box {np.round(box[0], 4)} .. {np.round(box[1], 4)} m "
                  f"in {seconds * 1e3:.1f} ms")
            seconds, length = best_of(1, lambda: reach.characteristic_length_of(held))
            print(f"  characteristic length (auto) L = {length:.6g} m in {seconds * 1e3:.0f} ms")
            for method in ("qmc", "grid"):
                for samples in BUDGETS:
                    seconds, result = best_of(3, lambda: global_indices.gci(
                        held, domain="cartesian", inverse=ik, box=box, method=method, samples=samples, seed=0,
                        length=length))
                    print(f"  {method:4s} {samples:7d}: GCI {result.value}, volume {result.measure} m^3, "
                          f"{seconds * 1e3:.1f} ms")


if __name__ == "__main__":
    main()
