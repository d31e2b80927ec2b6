"""Identification (issue 33): derive time of the UR10e's regressor and base regressor, and `symkin identify`'s
estimate from 10^5 samples of the UR10e, against Pinocchio's joint-torque regressor stacked over the same samples
(the competitor's route to the same least-squares problem; it has no base parameters, so its 60 standard columns
are solved by a minimum-norm lstsq); `symkin identify --method consistent` end to end (`symkin excite`:
benchmarks/bench_excitation.py).

Run with `make bench` or `python benchmarks/bench_identification.py [--samples N]`.  Targets (issue 33): derive
<= 10 s, identify 10^5 samples <= 10 s on 2 cores.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from symkin import pipeline  # noqa: E402
from symkin.identification import estimation, implied_parameters  # noqa: E402
from symkin.model import load_model  # noqa: E402
from symkin.runtime.loader import load  # noqa: E402
from symkin.text_table import format_table  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=100_000)
    args = parser.parse_args(argv)
    rows = []
    model = load_model(ROOT / "models" / "ur10e.yaml")
    start = time.perf_counter()
    generation = pipeline.generate(model, pipeline.resolve_request(model, ("regressor", "base_regressor",
                                                                           "inverse_dynamics"), "numpy,c,casadi"))
    rows.append(["derive regressor + base regressor + inverse dynamics (numpy, C, CasADi)",
                 f"{time.perf_counter() - start:.2f} s", "<= 10 s"])
    with tempfile.TemporaryDirectory() as scratch:
        directory = pipeline.write(generation, scratch)
        for backend in ("numpy", "c"):
            arm = load(directory, backend)
            rng = np.random.default_rng(0)
            q, qd, qdd = rng.uniform(-2, 2, (3, args.samples, 6))
            tau = arm.inverse_dynamics(q, qd, qdd) + rng.normal(0, 0.01, (args.samples, 6))
            names = arm.info.functions["base_regressor"].outputs["pi_b"]
            start = time.perf_counter()
            Y_b = arm.base_regressor(q, qd, qdd)[0]
            found = estimation.least_squares(Y_b, tau, names, "wls")
            rows.append([f"identify {args.samples} samples, WLS ({backend} base regressor)",
                         f"{time.perf_counter() - start:.2f} s", "<= 10 s"])
        Y = arm.regressor(q, qd, qdd)[0]  # K of Y = Y_b K for identified.yaml: spread states against all of them
        start = time.perf_counter()
        implied_parameters.combinations(Y, Y_b)
        spread = time.perf_counter() - start
        start = time.perf_counter()
        np.linalg.lstsq(Y_b.reshape(-1, Y_b.shape[-1]), Y.reshape(-1, Y.shape[-1]), rcond=None)
        rows.append([f"K of Y = Y_b K: {implied_parameters.COMBINATION_STATES} spread states (all {args.samples})",
                     f"{spread:.3f} s ({time.perf_counter() - start:.2f} s)", "-"])
        try:
            import pinocchio as pin
        except ImportError:
            pin = None
        if pin is not None:
            pmodel = pin.buildModelFromUrdf(str(ROOT / "models" / "ur10e.urdf"))
            pdata = pmodel.createData()
            start = time.perf_counter()
            W = np.vstack([pin.computeJointTorqueRegressor(pmodel, pdata, q[k], qd[k], qdd[k])
                           for k in range(args.samples)])
            np.linalg.lstsq(W, tau.reshape(-1), rcond=None)
            rows.append([f"Pinocchio: stacked joint-torque regressors + lstsq, {args.samples} samples",
                         f"{time.perf_counter() - start:.2f} s", "(no base parameters)"])
        arm = load(directory, "numpy")
        sample = slice(0, 6000)                                   # the size of a 30 s run at 200 Hz
        np.savetxt(Path(scratch) / "run.csv", np.column_stack([np.arange(6000) / 200.0, q[sample], qd[sample],
                                                               qdd[sample], tau[sample]]), delimiter=",",
                   comments="", header=",".join(["t"] + [f"{g}_{c.name}" for g in ("q", "qd", "qdd", "tau")
                                                         for c in arm.info.coordinates]))
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "symkin", "identify", str(directory), str(Path(scratch) / "run.csv"),
                        "--method", "consistent", "--no-figure", "-o", str(Path(scratch) / "identify")],
                       check=True, capture_output=True)
        rows.append(["symkin identify --method consistent, 6000 samples (with start-up)",
                     f"{time.perf_counter() - start:.2f} s", "-"])
    print(format_table(["UR10e", "time", "target"], rows))
    print(f"largest relative std of the estimate: {np.max(found.relative_std[np.isfinite(found.relative_std)]):.2g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
