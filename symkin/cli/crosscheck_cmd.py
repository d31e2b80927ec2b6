"""``symkin crosscheck`` (symkin against Pinocchio on the same robot) and ``symkin export`` (a model as URDF)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from symkin.cli.urdf_args import add_urdf_arguments, urdf_options
from symkin.text_table import format_table


def register_crosscheck(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("crosscheck", help="compare a model's derived quantities with Pinocchio",
                       description="Derive fk, every link frame, the geometric Jacobian, M, V, G, C (through C qd "
                                   "= V and the skew symmetry of Mdot - 2C), the joint friction and the inverse "
                                   "dynamics tau (with the friction the file declares) of a serial model, in the "
                                   "numpy and C code, and compare them with Pinocchio's, built from the same robot "
                                   "(a URDF as it is; a YAML model through the URDF that 'symkin export' writes), "
                                   "at random states within the joint limits. Prints the largest normwise relative "
                                   "error of each quantity (relative to its natural size where it vanishes, e.g. V "
                                   "at rest); exit 1 if one exceeds the tolerance.")
    p.add_argument("models", nargs="+", metavar="MODEL",
                   help="model file(s): YAML, or URDF (told by its content: a .urdf or .xml whose root is <robot>)")
    p.add_argument("--reference", choices=("pinocchio",), default="pinocchio",
                   help="the reference library (default: %(default)s; pip install 'symkin[crosscheck]')")
    p.add_argument("--reference-urdf", metavar="FILE", type=Path,
                   help="the URDF the reference reads instead of the model's own (e.g. the vendor's file)")
    p.add_argument("--samples", type=int, default=20, metavar="N", help="random states (default: %(default)s)")
    p.add_argument("--seed", type=int, default=0, help="seed of the random states (default: %(default)s)")
    p.add_argument("--backend", default="numpy,c", metavar="NAMES",
                   help="comma-separated generated code to check: numpy, c (default: %(default)s)")
    p.add_argument("--coriolis-matrix", action=argparse.BooleanOptionalAction, default=None,
                   help="check the Coriolis matrix C (default: for chains of up to 7 joints; its derivation grows "
                        "as n^3)")
    p.add_argument("--tolerance", type=float, default=None, metavar="TOL",
                   help="largest normwise relative error accepted (default: 1e-12)")
    add_urdf_arguments(p)
    p.set_defaults(run=run_crosscheck)


def run_crosscheck(args: argparse.Namespace) -> int:
    from symkin.references.crosscheck import DEFAULT_TOLERANCE, crosscheck
    from symkin.errors import ModelError, Problem

    if args.samples < 1:
        raise ModelError([Problem("<command line>", None, None, "--samples", f"--samples {args.samples} is not a "
                                  "positive number of states", "give --samples 1 or more (default 20)")])
    backends = tuple(b.strip() for b in args.backend.split(",") if b.strip())
    if not backends or not set(backends) <= {"numpy", "c"}:
        raise ModelError([Problem("<command line>", None, None, "--backend", f"--backend '{args.backend}' names "
                                  "no generated code crosscheck runs", "write --backend numpy, c or numpy,c")])
    failed = []
    for path in args.models:
        report = crosscheck(path, reference_urdf=args.reference_urdf, samples=args.samples, seed=args.seed,
                            tolerance=DEFAULT_TOLERANCE if args.tolerance is None else args.tolerance,
                            urdf=urdf_options(args, path), backends=backends, coriolis_matrix=args.coriolis_matrix,
                            progress=lambda line: print(f"  {line} ...", file=sys.stderr, flush=True))
        print(f"{path}: model '{report.model}' against {report.reference}, {report.samples} states, "
              f"tolerance {report.tolerance:g} (normwise relative)")
        rows = [[c.quantity, "-" if c.note else f"{c.error:.2e}",
                 c.note or ("pass" if c.error <= report.tolerance else "FAIL")] for c in report.comparisons]
        print(format_table(["quantity", "max error", "result"], rows))
        failed += [f"{path}: {c.quantity} ({c.error:.2e} > {report.tolerance:g})" for c in report.failures]
    if failed:
        print("error: crosscheck failed: " + "; ".join(failed), file=sys.stderr)
        return 1
    return 0


def register_export(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("export", help="write a serial model as a URDF",
                       description="Write a serial model as a URDF whose link frames are the model's link frames "
                                   "(numbers at the parameters' default values), for ROS, Pinocchio, MuJoCo and "
                                   "simulators.")
    p.add_argument("model", metavar="MODEL", help="model file: YAML, or URDF (.urdf)")
    p.add_argument("--urdf", action="store_true", default=True, help="write URDF (the only format; the default)")
    p.add_argument("-o", "--out", metavar="FILE", help="output file (default: print to stdout)")
    p.set_defaults(run=run_export)


def run_export(args: argparse.Namespace) -> int:
    from symkin.atomic import replace_file
    from symkin.model import load_model
    from symkin.model.urdf_export import export_urdf

    text = export_urdf(load_model(args.model))
    if args.out is None:
        sys.stdout.write(text)
    else:
        replace_file(Path(args.out), text)
    return 0
