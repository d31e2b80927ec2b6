"""``symkin check`` and ``symkin quantities``: validate models, list what can be derived."""

from __future__ import annotations

import argparse

from symkin.cli.urdf_args import add_urdf_arguments, print_notes, urdf_options
from symkin.text_table import format_table


def register_check(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("check", help="validate model files without deriving",
                       description="Validate model files (syntax, names, expressions, physical plausibility of "
                                   "masses and inertias, scene; of a parallel mechanism, that its legs let the "
                                   "platform move in the coordinates parallel.motion declares at the home pose, and "
                                   "hold it with the actuators locked) and print a summary. Writes nothing; exit "
                                   "2 with the place of the first problem.")
    p.add_argument("models", nargs="+", metavar="MODEL",
                   help="model file(s): YAML, or URDF (told by its content: a .urdf or .xml whose root is <robot>)")
    add_urdf_arguments(p)
    p.set_defaults(run=run_check)


def run_check(args: argparse.Namespace) -> int:
    from symkin import pipeline
    from symkin.model import load_model
    from symkin.model.summary import structure_summary

    for path in args.models:
        model = load_model(path, **urdf_options(args, path))
        request = pipeline.resolve_request(model)
        pipeline.require_derivable(model, request)  # what derive would refuse
        print(f"{path}: ok - model '{model.name}', {structure_summary(model)}; "
              f"scene: {', '.join(request.outputs)} via {', '.join(request.backends)}")
        print_notes(model.source, model.notes)
    return 0


def register_quantities(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("quantities", help="list the quantities symkin can derive",
                       description="List the outputs that a scene or --only may request.")
    p.set_defaults(run=run_quantities)


def run_quantities(_args: argparse.Namespace) -> int:
    from symkin import pipeline

    rows = [list(row) for row in pipeline.derivable_quantities()]
    print(format_table(["output", "models", "meaning"], rows, indent=""))
    return 0
