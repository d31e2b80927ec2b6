"""GCI run time against achieved error of every integrator: the seed's planar 2R arm and the DELTA.

Run with `make bench` or `python benchmarks/bench_gci.py [options of 'symkin bench gci']`.
The same as `symkin bench gci generated/planar_2r --backends numpy,c` and
`symkin bench gci generated/delta --backends numpy,c`: the grid, Monte Carlo, quasi-Monte
Carlo and adaptive integrators on the joint domain (dW = |det J| dq; for the DELTA the
configurations in its working mode) and the Cartesian domain (reachability by closed-form
inverse kinematics), each at budgets of 4^4 ... 4^10 evaluations, timed (best of 3) with
the generated numpy and C code against an adaptive reference at rtol 1e-13.  Prints the
tables and the fastest run per accuracy target (the DELTA's target: 1e-3 relative error
in <= 50 ms on one core); the plots go to bench-results/<model>-gci-time-vs-error.png.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from symkin.cli import main  # noqa: E402

MODELS = ("planar_2r", "delta")

if __name__ == "__main__":
    for name in MODELS:
        status = main(["bench", "gci", str(ROOT / "generated" / name), "--backends", "numpy,c",
                       "-o", str(ROOT / "bench-results" / f"{name}-gci-time-vs-error.png"), *sys.argv[1:]])
        if status:
            raise SystemExit(status)
