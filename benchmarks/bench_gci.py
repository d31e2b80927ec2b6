"""GCI of the seed's planar 2R arm: wall time against achieved error of every integrator.

Run with `make bench` or `python benchmarks/bench_gci.py [options of 'symkin bench gci']`.
The same as `symkin bench gci generated/planar_2r`: the grid, Monte Carlo, quasi-Monte
Carlo and adaptive integrators on the joint domain (dW = |det J| dq) and the Cartesian
domain (reachability by closed-form inverse kinematics), each at budgets of 4^4 ... 4^10
evaluations, timed (best of 3) against an adaptive reference at rtol 1e-13.  Prints the
table and the fastest run per accuracy target; the plot goes to
bench-results/planar_2r-gci-time-vs-error.png.  The DELTA joins in phase 2.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from symkin.cli import main  # noqa: E402

if __name__ == "__main__":
    raise SystemExit(main(["bench", "gci", str(ROOT / "generated" / "planar_2r"),
                           "-o", str(ROOT / "bench-results" / "planar_2r-gci-time-vs-error.png"), *sys.argv[1:]]))
