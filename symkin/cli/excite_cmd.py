"""``symkin excite MODEL``: an excitation trajectory for identification (symkin.identification.excitation)."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from symkin.cli import analysis_args
from symkin.analysis import model_files
from symkin.cli.progress import Progress


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "excite", help="design an excitation trajectory that makes the base parameters identifiable",
        description="Optimize a periodic motion for identifying the device (symkin identify): a finite Fourier "
                    "series per joint (Swevers et al. 1997), starting and ending at rest, within the joint limits "
                    "and the --max-velocity and --max-acceleration bounds, that minimizes a smooth bound of the "
                    "condition number of the stacked base regressor over one period (CasADi and IPOPT). Writes "
                    "excitation.csv (t, q_, qd_, qdd_ of --periods periods at --rate), excitation.json (the "
                    "coefficients and the condition numbers of the start and of the result), summary.txt and "
                    "excitation.png into the output directory (replaced as a whole). A parallel platform without a "
                    "closed-form fk (the Stewart-Gough) moves its pose in such series instead, its actuators "
                    "following q = ik(p); legs without the distance form move their actuators about the home "
                    "assembly (give --limit for each), each sample assembled by a rootfinder.",
        epilog="e.g. symkin excite models/planar_2r.yaml --max-velocity 2 --max-acceleration 10 --period 4")
    analysis_args.add_model_arguments(p, backend=False)
    p.add_argument("--period", type=float, default=10.0, metavar="T", help="period in s (default: %(default)s)")
    p.add_argument("--harmonics", type=int, default=5, metavar="L", help="harmonics per joint (default: %(default)s)")
    p.add_argument("--max-velocity", type=float, metavar="V",
                   help="bound on every |qd| (rad/s or m/s; default: the model's velocity limits)")
    p.add_argument("--max-acceleration", type=float, required=True, metavar="A",
                   help="bound on every |qdd| (rad/s^2 or m/s^2)")
    p.add_argument("--samples", type=int, metavar="K",
                   help="samples of one period in the criterion (default: 4 per base parameter and joint, >= 50)")
    p.add_argument("--rate", type=float, default=200.0, metavar="HZ", help="rate of the CSV (default: %(default)s)")
    p.add_argument("--periods", type=int, default=1, metavar="N", help="periods in the CSV (default: %(default)s)")
    p.add_argument("--seed", type=int, default=0, help="seed of the start (default: %(default)s)")
    p.add_argument("--max-iterations", type=int, default=200, metavar="N",
                   help="IPOPT iterations (default: %(default)s)")
    p.add_argument("-o", "--out", metavar="DIR", help="output directory (default: out/excite/MODEL)")
    p.add_argument("--no-figure", action="store_true", help="write the numbers only")
    p.set_defaults(run=run, parser=p)


def run(args: argparse.Namespace) -> int:
    from symkin.analysis.needs import DERIVED
    from symkin.identification import excitation

    start = time.perf_counter()
    try:
        for name in ("period", "max_acceleration", "rate"):
            if not getattr(args, name) > 0:
                raise ValueError(f"--{name.replace('_', '-')} must be positive")
        if args.harmonics < 1 or args.periods < 1:
            raise ValueError("--harmonics and --periods must be at least 1")
        model = model_files.generated_model(args.model, "casadi", *DERIVED["excite"], display=Progress)
        values = analysis_args.parse_assignments(args.assignments)
        model = model.bind(**values) if values else model
        joints = model.info.device_coordinates   # a hybrid device's wrist joints after the legs' actuators
        with Progress(model.name) as progress:
            progress(f"optimizing {len(joints) * (2 * args.harmonics + 1)} coefficients with IPOPT")
            found = excitation.optimize_excitation(model, period=args.period, harmonics=args.harmonics, samples=args.samples,
                                        max_velocity=args.max_velocity, max_acceleration=args.max_acceleration,
                                        seed=args.seed, limits=analysis_args.parse_limits(args.limits),
                                        max_iterations=args.max_iterations)
            files = _files(args, model, found)
            if not args.no_figure:
                progress("drawing the trajectory")
                files["excitation.png"] = excitation.figure_png(
                    found, [c.name for c in joints], [c.revolute for c in joints],
                    f"{model.name}: excitation, cond {found.condition_start:.3g} -> {found.condition:.3g}")
    except (ValueError, KeyError) as err:
        analysis_args.fail_on_bad_input(args, err)
    analysis_args.write_outputs(Path(args.out or f"out/excite/{model.name}"), files, start)
    return 0


def _files(args: argparse.Namespace, model, found) -> dict[str, str | bytes]:
    names = [c.name for c in model.info.device_coordinates]
    series = list(found.coordinates)      # the joints', or a platform's task coordinates' without a closed-form fk
    t = np.arange(int(round(args.periods * found.period * args.rate))) / args.rate
    q, qd, qdd = found.states(t)
    header = ",".join(["t", *(f"{g}_{n}" for g in ("q", "qd", "qdd") for n in names)])
    rows = [",".join(repr(float(v)) for v in row) for row in np.column_stack([t, q, qd, qdd])]
    record = {"model": model.name, "period": found.period, "harmonics": found.harmonics,
              "series_of": "joints" if found.joints is None else "task coordinates (the joints: q = ik(p))",
              "offsets": dict(zip(series, map(float, found.offsets))),
              "a": {n: list(map(float, row)) for n, row in zip(series, found.a)},
              "b": {n: list(map(float, row)) for n, row in zip(series, found.b)},
              "condition_start": _finite(found.condition_start), "condition": _finite(found.condition),
              "samples": found.samples,
              "ipopt_status": found.status}
    per = "joint" if found.joints is None else "task coordinate"
    summary = (f"{model.name}: excitation of period {found.period:g} s, {found.harmonics} harmonics per {per}: "
               f"cond(W) {found.condition_start:.4g} at the start -> {found.condition:.4g} (columns scaled, "
               f"{found.samples} samples; IPOPT: {found.status})\n"
               f"  run it on the device at {args.rate:g} Hz ({len(t)} samples in excitation.csv), record tau_<joint>, "
               "and give the file to symkin identify\n")
    return {"excitation.csv": header + "\n" + "\n".join(rows) + "\n",
            "excitation.json": json.dumps(record, indent=2, allow_nan=False) + "\n", "summary.txt": summary}


def _finite(value: float) -> float | None:
    """A JSON number, or null for an infinite condition number (a start that excites nothing)."""
    return value if np.isfinite(value) else None
