"""``symkin view``: write (and open) the interactive 3D page of a mechanism (symkin.viewer)."""

from __future__ import annotations

import argparse
import webbrowser
from pathlib import Path

from symkin.cli import analysis_args
from symkin.analysis import model_files
from symkin.analysis.needs import NEEDS
from symkin.cli.analysis_args import sample_count

#: Workspace points of the cloud by default: enough to see its shape and where 1/kappa falls off.
DEFAULT_SAMPLES = 4096


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "view",
        help="write an interactive 3D page of a mechanism (HTML, opens without network)",
        description="Write one self-contained HTML page that shows the mechanism at a pose: its links and joint "
                    "frames, a slider per joint (a serial arm) or per platform coordinate (a parallel mechanism, "
                    "through its closed-form inverse kinematics, or for legs without closed forms by Newton's "
                    "method on the loop closure from the last assembly) and per design parameter, the TCP frame and its "
                    "trace, 1/kappa and det J with a warning near singular configurations, and the workspace as a "
                    "cloud coloured by 1/kappa. The pose is computed in the page by the model's generated "
                    "JavaScript; three.js is embedded. Example: symkin view models/delta.yaml -o delta.html --open",
    )
    p.add_argument("model", metavar="MODEL", help="generated directory (with its JavaScript: --backend js), "
                                                  "or a model file (YAML or URDF), derived on the fly")
    p.add_argument("-o", "--out", metavar="HTML", help="the page to write (default: out/view/<model>-view.html)")
    p.add_argument("--design", action="append", default=[], metavar="NAME=VALUE[,...]",
                   help="parameter values of the design shown (and of its workspace cloud); repeatable")
    p.add_argument("--workspace", type=lambda text: 0 if text == "0" else sample_count(text),
                   default=DEFAULT_SAMPLES, metavar="N",
                   help="about N sampled points in the workspace cloud, 0 for none (default: %(default)s)")
    p.add_argument("--seed", type=int, default=0, help="seed of the cloud's sampling (default: %(default)s)")
    p.add_argument("--limit", dest="limits", action="append", default=[], metavar="JOINT=LOWER:UPPER",
                   help="override an actuated joint's limits (of the cloud and the page's warnings), e.g. --limit "
                        "lift1=0:0.2 for a prismatic joint the model file leaves unlimited (repeatable)")
    p.add_argument("--open", action="store_true", help="open the page in the web browser")
    p.set_defaults(run=run, parser=p)


def run(args: argparse.Namespace) -> int:
    from symkin.runtime import load
    from symkin.atomic import replace_file
    from symkin.cli.progress import Progress
    from symkin.viewer import page

    try:
        design = analysis_args.parse_assignments(args.design)
        limits = analysis_args.parse_limits(args.limits)
    except ValueError as err:
        analysis_args.fail_on_bad_input(args, err)
    with model_files.generated_directory(args.model, ("numpy", "js"), NEEDS["view"],
                                           page.OPTIONAL_VIEW_OUTPUTS, display=Progress) as directory:
        model = load(directory)
        try:
            model = model.bind(**design) if design else model
            with Progress(model.name) as progress:
                html, cloud = page.page_of(model, args.workspace, args.seed, progress, limits)
        except (ValueError, KeyError) as err:  # a ViewUnavailable too
            analysis_args.fail_on_bad_input(args, err)
    out = Path(args.out or f"out/view/{model.name}-view.html")
    replace_file(out, html)
    print(f"{model.name}: {out} ({len(html) / 1e6:.1f} MB; {cloud.note})")
    if args.open:
        webbrowser.open(out.resolve().as_uri())
    return 0
