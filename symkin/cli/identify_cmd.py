"""``symkin identify MODEL DATA.csv``: a device's base parameters from a run (symkin.identification.workflow)."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from symkin.cli import analysis_args
from symkin.analysis import model_files
from symkin.cli.progress import Progress
from symkin.cli.urdf_args import add_urdf_arguments, urdf_options

def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "identify", help="identify a device's base parameters from a measured run (CSV of q, tau)",
        description="Estimate the base parameters pi_b (the identifiable combinations of the links' masses, first "
                    "moments and inertias, the rotor inertias and the joints' friction; symkin quantities: "
                    "base_regressor) from a run recorded on the device: least squares on tau = Y_b(q, qd, qdd) pi_b "
                    "over the samples, with each estimate's standard deviation, validated on the last --holdout "
                    "part of the run (torque RMS per joint). DATA.csv has a column t (s) and, per coordinate, "
                    "q_<name>, tau_<name> and optionally qd_<name>, qdd_<name> (without them, --cutoff derives the "
                    "rates from q by a zero-phase low-pass filter). Writes estimate.json, estimate.csv, "
                    "summary.txt and validation.png (measured and predicted efforts) into the output directory "
                    "(replaced as a whole), and given a model file identified.yaml, the model with the identified "
                    "values (given a URDF or xacro file also identified.urdf; of a parallel model, the values its "
                    "file holds: one rotor for all actuators). A parallel model's run records its actuators (and a "
                    "hybrid device's wrist joints): each sample's platform pose is fk(q) (without a closed form, as "
                    "the Stewart-Gough platform's, by Newton's method from the home pose). Bad data are refused "
                    "with the file, row and column, and nothing is written.",
        epilog="e.g. symkin identify models/planar_2r.yaml run.csv --method wls -o out/identify/planar_2r")
    analysis_args.add_model_arguments(p)
    p.add_argument("data", metavar="DATA.csv", help="the measured run")
    p.add_argument("--method", choices=("ols", "wls", "consistent", "energy"), default="wls",
                   help="ordinary least squares, or weighted by each joint's residual, on the base parameters; or "
                        "'consistent': also the standard parameters, every body (a link; a parallel model's platform "
                        "and arms) a physical rigid body (positive definite pseudo-inertia), a rod's end masses and "
                        "the drives' inertia and friction non-negative, nearest the model's values among the fits; "
                        "or 'energy': least squares on the energy balance over windows of the run (the work of tau "
                        "against the change of the energy and the friction's loss; no accelerations enter the "
                        "estimate) (default: %(default)s)")
    p.add_argument("--window", type=float, default=0.05, metavar="S",
                   help="--method energy: the length of the windows of the energy balance, one equation each "
                        "(default: %(default)s s)")
    p.add_argument("--holdout", type=float, default=0.25, metavar="F",
                   help="the last fraction of the run kept for validation (default: %(default)s; 0: none)")
    p.add_argument("--cutoff", type=float, metavar="HZ",
                   help="low-pass cutoff that derives qd and qdd from q when the file has no rate columns")
    p.add_argument("-o", "--out", metavar="DIR", help="output directory (default: out/identify/MODEL)")
    p.add_argument("--no-figure", action="store_true", help="write the numbers only")
    add_urdf_arguments(p)
    p.set_defaults(run=run, parser=p)


def run(args: argparse.Namespace) -> int:
    from symkin.identification.workflow import IdentifyRequest, identify

    start = time.perf_counter()
    try:
        if not 0.0 <= args.holdout < 1.0:
            raise ValueError(f"--holdout must lie in [0, 1), got {args.holdout:g}")
        if not args.window > 0:
            raise ValueError(f"--window must be a positive number of seconds, got {args.window:g}")
        reading = urdf_options(args, args.model) if model_files.is_model_file(args.model) else {}
        request = IdentifyRequest(args.model, args.data, method=args.method, window=args.window, holdout=args.holdout,
                                  cutoff=args.cutoff, backend=args.backend,
                                  values=analysis_args.parse_assignments(args.assignments), reading=reading,
                                  figure=not args.no_figure)
        found = identify(request, Progress)
    except (ValueError, KeyError) as err:
        analysis_args.fail_on_bad_input(args, err)
    analysis_args.write_outputs(Path(args.out or f"out/identify/{found.name}"), found.files, start)
    return 0
