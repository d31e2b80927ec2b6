"""``symkin rate``: a haptic device's datasheet over its usable workspace (symkin.rating.datasheet)."""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

from symkin.analysis.needs import NEEDS
from symkin.cli import analysis_args
from symkin.analysis import model_files
from symkin.cli.progress import Progress


def _measure_names() -> str:
    """The datasheet's measures, as --help lists them (from the groups the rating checks it covers)."""
    from symkin.rating.handle_measures import PUSHED_GROUPS, SPHERICAL_GROUPS

    names = [name for groups in (PUSHED_GROUPS, SPHERICAL_GROUPS) for names in groups.values() for name in names]
    return ", ".join(dict.fromkeys(names))


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "rate", help="rate a haptic device as its datasheet does: apparent mass, forces, resolution, stiffness",
        description="Rate a device whose handle translates (a serial arm's TCP, a DELTA's or a pantograph's "
                    "handle) over its usable workspace (the sampled poses where 1/kappa of the translational "
                    "Jacobian is at least --conditioning, within --box) and at its home pose: the apparent mass "
                    "(principal masses of (J M^-1 J^T)^-1 and their ratio), the isotropic and peak force from the "
                    "actuators' effort limits (and the continuous force where the drives declare it), the share "
                    "of the efforts spent holding the device against gravity, the position resolution from "
                    "--encoder, and from the joints' declared friction the Coulomb friction felt at the handle, "
                    "the least viscous damping there and the stiffest wall a --rate loop renders passively "
                    "(Colgate-Brown, K < 2 b / T); along each task axis also the stiffest passive wall with the "
                    "encoders' quantization (Abbott-Okamura, K < min(2 b_e / T, 2 f_e / Delta_e)). A platform that also rotates (Stewart-Gough) is rated at a "
                    "constant --orientation, its handle pushed (orientation free) and twisted (position free): "
                    "the apparent rotational inertia, the isotropic and peak torque and the angular resolution "
                    "join the table; a spherical platform (the Agile Eye) is rated over its orientations, its "
                    "handle twisted about the centre (--box in rad of roll, pitch, yaw). Legs without closed forms "
                    "(any topology) are rated over the working mode continued from the home pose at a constant "
                    "--orientation (-n N: about N^(1/3) cells a side); their apparent mass, inertia and gravity "
                    "share come from the generated closure_dynamics where the model declares bodies (else they "
                    "are not rated). Every measure (" + _measure_names() + ") appears with its value or as not "
                    "rated with the reason and what to give, and the largest box and upright cylinder inside the "
                    "usable workspace (--shape-samples); --datasheet sets a maker's figures (and workspace box) "
                    "beside them. Writes datasheet.json (every number with its unit and "
                    "the pose of each extreme), datasheet.csv (every rated pose), datasheet.png (a map per measure) "
                    "and summary.txt into the output directory (replaced as a whole).",
        epilog="e.g. symkin rate generated/delta --effort-limit 0.3 --encoder 4096 --gear 10 -o out/rate/delta")
    analysis_args.add_model_arguments(p)
    p.add_argument("-n", "--samples", type=analysis_args.sample_count, default=4096, metavar="N",
                   help="poses sampled: joint configurations within the limits, or a rotating platform's centres "
                        "(default: %(default)s)")
    p.add_argument("--seed", type=int, default=0, help="seed of the sampling (default: %(default)s)")
    p.add_argument("--box", action="append", default=[], metavar="AXIS=LO:HI[,...]",
                   help="rate only the poses whose TCP lies in this box, in m, e.g. --box x=-0.03:0.03,z=-0.17:-0.11 "
                        "(the required workspace; the home pose is quoted anyway)")
    p.add_argument("--conditioning", type=float, default=None, metavar="C",
                   help="the usable workspace: poses with 1/kappa >= C (default: 0.05; 0 rates every pose)")
    p.add_argument("--effort-limit", metavar="T[,T...]",
                   help="peak actuator efforts (N m or N at the joints; one value for all or one per actuator; "
                        "default: the model's effort limits)")
    p.add_argument("--encoder", metavar="COUNTS[,...]",
                   help="encoder counts per turn of each actuator's motor (revolute joints) or per metre of "
                        "travel (prismatic): the position resolution")
    p.add_argument("--gear", metavar="N[,...]",
                   help="motor turns per joint turn between encoder and revolute joint (default: the gear ratios of "
                        "the model's actuators, or of a parallel model's rotor: 'rotor: {gear_ratio: ...}', else 1)")
    p.add_argument("--shape-samples", type=int, default=None, metavar="N",
                   help="samples of the grid the largest box and upright cylinder inside the usable workspace are "
                        "found on (default: 2^18 joint configurations of an arm, 2^15 Cartesian cells of a platform; "
                        "0: not rated)")
    p.add_argument("--rate", type=float, default=1000.0, metavar="HZ",
                   help="servo rate of the haptic loop, for the renderable stiffness (default: 1000)")
    analysis_args.add_device_argument(p)
    analysis_args.add_orientation_argument(p)
    p.add_argument("-o", "--out", metavar="DIR", help="output directory (default: out/rate/MODEL)")
    p.add_argument("--no-figure", action="store_true", help="write the numbers only")
    p.add_argument("--datasheet", metavar="SPEC.yaml",
                   help="a maker's published figures (device, source, figures: {MEASURE: {value, unit, at: "
                        "home|worst, quote}}), printed beside symkin's values with their ratio "
                        "(models/datasheets/ holds the shipped devices' figures)")
    p.set_defaults(run=run, parser=p)


def _encoders(args: argparse.Namespace, model) -> tuple[list[float], list[float], str] | None:
    """(counts per turn or metre, gear ratios, where the gears come from) of ``--encoder`` (None without it)."""
    if args.encoder is None:
        if args.gear is not None:
            raise ValueError("--gear: give --encoder too (the gear scales the encoder's counts)")
        return None
    count = len(model.info.coordinates)
    counts = analysis_args.per_joint("--encoder", args.encoder, count)
    declared = [c.gear_ratio or 1.0 for c in model.info.coordinates]  # the model's drives (serial or legs' rotor)
    gears = analysis_args.per_joint("--gear", args.gear, count) if args.gear else declared
    if not all(c > 0 and math.isfinite(c) for c in counts + gears):
        raise ValueError("--encoder and --gear must be positive numbers")
    source = "--gear" if args.gear else "the model's drives" if any(
        c.gear_ratio is not None for c in model.info.coordinates) else "direct drive (the model declares no gear)"
    return counts, gears, source


def _joint_steps(model, encoders: tuple[list[float], list[float], str] | None) -> list[float] | None:
    """Encoder steps at the joints: 2 pi / (counts N) rad (revolute), 1 / counts m (prismatic)."""
    if encoders is None:
        return None
    counts, gears, _ = encoders
    return [2 * math.pi / (c * n) if coordinate.revolute else 1.0 / c
            for c, n, coordinate in zip(counts, gears, model.info.coordinates)]


def _inputs(args: argparse.Namespace, model, actuation, encoders) -> dict[str, object]:
    """Every input the rating used, per actuated coordinate, and where it came from (datasheet.json, summary)."""
    def listed(values) -> list[float | None]:
        return [None] * len(model.info.coordinates) if values is None else [float(v) for v in values]

    counts, gears, source = encoders if encoders is not None else (listed(None), listed(None), "no --encoder")
    efforts = listed(actuation.effort_limits)
    return {"servo_period_s": actuation.period, "effort_limits_from": "--effort-limit" if args.effort_limit else
            "the model", "gears_from": source,
            "coordinates": [{"name": c.name, "encoder_counts": n, "gear_ratio": g, "effort_limit": e,
                             "continuous_effort_limit": ce, "coulomb": cf, "viscous": v}
                            for c, n, g, e, ce, cf, v in zip(model.info.coordinates, counts, gears, efforts,
                                                             listed(actuation.continuous_limits),
                                                             listed(actuation.coulomb), listed(actuation.viscous))]}


def _input_lines(inputs: dict[str, object]) -> list[str]:
    lines = [f"inputs: servo period {inputs['servo_period_s']:g} s; effort limits from {inputs['effort_limits_from']};"
             f" gears from {inputs['gears_from']}"]
    for c in inputs["coordinates"]:  # type: ignore[attr-defined]
        shown = ", ".join(f"{key.replace('_', ' ')} {value:g}" for key, value in c.items()
                          if key != "name" and value is not None)
        lines.append(f"  {c['name']}: {shown or 'no drive data'}")
    return lines


def _shapes(args: argparse.Namespace, model, conditioning: float):
    """The largest box and cylinder inside the usable workspace (:mod:`symkin.rating.workspace_shapes`), or why not."""
    from symkin.rating import workspace_shapes

    if args.shape_samples is not None and args.shape_samples < 0:
        raise ValueError(f"--shape-samples must not be negative, got {args.shape_samples}")
    if args.shape_samples == 0:
        return workspace_shapes.WorkspaceShapes(None, None, 0.0, 0, "--shape-samples 0")
    return workspace_shapes.usable_shapes(model, conditioning, analysis_args.parse_limits(args.limits),
                                          args.shape_samples, analysis_args.parse_orientation(args.orientation))


def run(args: argparse.Namespace) -> int:
    from symkin.rating import datasheet, datasheet_files

    start = time.perf_counter()
    maker = None
    if args.datasheet is not None:  # read before any work; the model layer's YAML reader imports sympy, so only here
        from symkin.rating import maker_figures

        maker = maker_figures.read_maker_sheet(args.datasheet)
    try:
        if not args.rate > 0:
            raise ValueError(f"--rate must be positive, got {args.rate:g}")
        conditioning = datasheet.USABLE_CONDITIONING if args.conditioning is None else args.conditioning
        if not 0.0 <= conditioning <= 1.0:
            raise ValueError(f"--conditioning must lie in [0, 1], got {conditioning:g}")
        box = analysis_args.parse_ranges(args.box, "--box", "AXIS")
        device = analysis_args.DEVICE_OUTPUTS if args.device else ()
        optional = ("gravity_vector", "closure_dynamics", *device)
        loaded = model_files.load_for_analysis(args.model, args.backend, NEEDS["rate"], optional, display=Progress)
        analysis_args.say_where_continued(args.backend, loaded)
        model = analysis_args.device_view(args, analysis_args.with_assignments(args, [loaded])[0])
        encoders = _encoders(args, model)
        actuation = datasheet.Actuation.of_model(model, effort_limits=analysis_args.effort_limits(args.effort_limit,
                                                                                                  model),
                                                 joint_steps=_joint_steps(model, encoders), period=1.0 / args.rate)
        inputs = _inputs(args, model, actuation, encoders)
        with Progress(model.name) as progress:
            progress(f"rating {args.samples} poses")
            sheet = datasheet.rate(model, actuation, samples=args.samples, seed=args.seed, box=box,
                                   limits=analysis_args.parse_limits(args.limits), conditioning=conditioning,
                                   orientation=analysis_args.parse_orientation(args.orientation))
            record = sheet.to_json()
            beside = () if maker is None else maker_figures.compare(maker, sheet)
            shapes = _shapes(args, model, conditioning)
            record["workspace_shapes"] = shapes.to_json()
            summary = [f"{model.name}: {len(sheet.q) - 1} poses of the usable workspace (1/kappa >= {conditioning:g}"
                       + (f", TCP in {args.box[0] if len(args.box) == 1 else args.box}" if box else "")
                       + ") and the home pose", *("  " + line for line in sheet.summary()),
                       *("  " + line for line in shapes.lines()),
                       *("  " + line for line in _input_lines(inputs))]
            if maker is not None:
                summary += [f"  beside the maker's figures ({maker.device}; {maker.source}):",
                            *("    " + comparison.line() for comparison in beside)]
                record["maker"] = {"file": maker.file, "device": maker.device, "source": maker.source,
                                   "figures": [comparison.to_json() for comparison in beside]}
                if maker.box is not None:
                    box_lines, record["maker"]["workspace_box"] = maker_figures.box_lines_and_record(maker.box, shapes)
                    summary += ["    " + line for line in box_lines]
            draw = not args.no_figure and bool(datasheet_files.drawn_measures(sheet))
            if not args.no_figure and not draw:
                summary.append("  no datasheet.png: no measure over every direction was rated (why: above)")
            files: dict[str, str | bytes] = {
                "datasheet.json": json.dumps(record | {"servo_rate_hz": args.rate,
                                                       "usable_conditioning": conditioning,
                                                       "inputs": inputs},
                                             indent=2, allow_nan=False) + "\n",
                "datasheet.csv": datasheet_files.csv_text(sheet, model.info.coordinate_names),
                "summary.txt": "\n".join(summary) + "\n"}
            if draw:
                progress("drawing the datasheet")
                files["datasheet.png"] = datasheet_files.figure_png(sheet, f"{model.name}: datasheet over the usable "
                                                                     "workspace")
    except (ValueError, KeyError) as err:
        analysis_args.fail_on_bad_input(args, err)
    analysis_args.write_outputs(Path(args.out or f"out/rate/{model.name}"), files, start)
    return 0
