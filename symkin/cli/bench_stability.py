"""``symkin bench stability MODEL``: generated code against a 50-digit reference (error vs kappa, scale, float32)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from symkin.cli.progress import Progress


def register(kinds: argparse._SubParsersAction) -> None:
    p = kinds.add_parser(
        "stability", help="accuracy of the generated code against a 50-digit reference",
        description="Evaluate every quantity the model can derive - generated and optimized as 'symkin derive' "
                    "does, all parameters as inputs - at random states, along paths into the singular "
                    "configurations found by sweeping each joint, with every length parameter scaled by 1e-3 to "
                    "1e3, and in float32 (the optimized code printed by the numpy printer, run on float32 "
                    "arrays); compare with the un-optimized expressions evaluated at 50 digits (arb ball arithmetic). "
                    "Prints tables of the normwise relative error against kappa (condition number of the task "
                    "Jacobian) and against the length scale, the closed-form IK angles near singularities "
                    "(textbook acos against symkin's atan2 forms), and the acceptance line "
                    "(error <= 1e-13 where kappa < 1e3); writes a figure.")
    p.add_argument("model", metavar="MODEL", help="model file (YAML)")
    p.add_argument("--samples", type=int, default=32, help="random states at the default parameters (default: 32)")
    p.add_argument("--scale-samples", type=int, default=6, help="random states per length scale (default: 6)")
    p.add_argument("--float32-samples", type=int, default=16, help="random states in float32 (default: 16)")
    p.add_argument("--only", metavar="NAMES", help="comma-separated quantities (default: all the model can derive)")
    p.add_argument("--skip", metavar="NAMES", help="comma-separated quantities to leave out (of --only's, or of all)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    p.add_argument("--figure", type=Path, metavar="PATH",
                   help="figure file (default: out/figures/MODEL_NAME-stability.png)")
    p.add_argument("--no-figure", action="store_true", help="write no figure")
    p.add_argument("--csv", type=Path, metavar="PATH", help="also write every record as CSV")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from symkin.model import load_model
    from symkin.stability import report
    from symkin.stability.harness import run_stability

    model = load_model(args.model)
    only = _names(args.only) if args.only else None
    try:
        with Progress(f"{model.name} stability") as progress:
            result = run_stability(model, samples=args.samples, scale_samples=args.scale_samples,
                                   float32_samples=args.float32_samples, quantities=only,
                                   skip=_names(args.skip or ""), seed=args.seed, progress=progress)
    except ValueError as err:
        if not str(err).startswith("skip: "):
            raise
        print(f"error: --{err}", file=sys.stderr)
        return 2
    print(report.report_text(result))
    if args.csv:
        report.write_csv(result, args.csv)
        print(f"records written to {args.csv}")
    if not args.no_figure:
        figure = args.figure or Path("out") / "figures" / f"{model.name}-stability.png"
        report.write_figure(result, figure)
        print(f"figure written to {figure}")
    return 0


def _names(text: str) -> list[str]:
    return [n.strip() for n in text.split(",") if n.strip()]
