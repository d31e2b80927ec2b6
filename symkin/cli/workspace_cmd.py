"""``symkin workspace MODEL``: TCP point cloud, area/volume, boundary, singularities, figures."""

from __future__ import annotations

import argparse
import contextlib
import time
from typing import TYPE_CHECKING

from symkin.analysis.needs import NEEDS
from symkin.cli import analysis_args
from symkin.analysis import model_files
from symkin.cli.progress import Progress

if TYPE_CHECKING:
    import numpy as np


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "workspace",
        help="sample the workspace; area/volume, boundary, singularities and figures",
        description="Sample the joint space within the limits, map it through the generated fk and report the "
                    "workspace: bounding box, area/volume with an error estimate, boundary cells, 1/kappa range "
                    "and singular configurations (and whether they lie on the boundary). Draws the point "
                    "cloud (-o) and a 1/kappa map (--map). Several --design options overlay designs, e.g. "
                    "seed Fig. 8.19: symkin workspace generated/planar_2r --design l1=0.1,l2=0.1 "
                    "--design l1=0.2,l2=0.2 --unit cm -o fig-8-19.png. A platform that also rotates "
                    "(Stewart-Gough) is analysed at a constant orientation (--orientation) on a Cartesian grid "
                    "(its joint space is not sampled: -n, --method and --seed do not apply). A spherical platform "
                    "(the Agile Eye) is a set of orientations: its measure in rad^3 (the invariant measure of SO(3)), "
                    "the GCI of its angular-velocity Jacobian and a figure of the reachable orientations (-n, --seed). "
                    "Legs without closed forms (any topology, e.g. two SCARA legs) are continued from the home pose "
                    "over a Cartesian grid at a constant orientation: the working mode of the home assembly, its "
                    "volume, 1/kappa and GCI (-n N: about N^(1/3) cells a side).",
    )
    analysis_args.add_model_arguments(p)
    p.add_argument("--design", action="append", default=[], metavar="NAME=VALUE[,...]",
                   help="a design to analyse and overlay (parameter values on top of --set); repeatable")
    p.add_argument("-n", "--samples", type=analysis_args.sample_count, default=40_000, metavar="N",
                   help="joint configurations per design (default: %(default)s)")
    p.add_argument("--method", choices=("grid", "random", "sobol"), default=None,
                   help="joint-space sampling (default: grid up to 3 joints, else sobol)")
    p.add_argument("--seed", type=int, default=0, help="seed of random/sobol sampling (default: %(default)s)")
    p.add_argument("-o", "--out", metavar="FIGURE", type=analysis_args.figure_path,
                   help="workspace figure (default: out/workspace/MODEL_NAME-workspace.png)")
    p.add_argument("--map", metavar="FIGURE", type=analysis_args.figure_path,
                   help="also draw 1/kappa over the workspace into FIGURE (first design); a platform at a constant "
                        "orientation also gets FIGURE-sections (x-y, x-z, y-z through the home position)")
    p.add_argument("--force-map", metavar="FIGURE", type=analysis_args.figure_path,
                   help="also draw the isotropic force (the largest force rendered in every direction, from the "
                        "actuators' effort limits) over the workspace of the first design into FIGURE; "
                        "translational task spaces only")
    p.add_argument("--effort-limit", metavar="T[,T...]",
                   help="actuator effort limits for --force-map (N m or N; one value for all, or one per actuator; "
                        "default: the model's effort limits)")
    p.add_argument("--no-figure", action="store_true", help="print the report only")
    analysis_args.add_length_argument(p)
    analysis_args.add_orientation_argument(p)
    analysis_args.add_device_argument(p)
    p.add_argument("--unit", choices=tuple(analysis_args.LENGTH_UNITS), default="m",
                   help="length unit of the figures (default: m)")
    p.add_argument("--title", help="figure title")
    analysis_args.add_chunk_arguments(p, "serial mechanisms: the joint-space samples (extent, occupancy, 1/kappa, "
                                         "area/volume; figures from an evenly spaced subsample)")
    p.set_defaults(run=run, parser=p)


def _chunked_study(args: argparse.Namespace, models: list, designs: list[dict[str, float]], method: str, limits,
                   length: float | None, progress: Progress) -> list:
    """--scheduler: every design sampled in chunks on one Dask client (symkin.analysis.chunked_workspace)."""
    from symkin.analysis import chunked_workspace, study, workspace
    from symkin import mechanism
    from symkin.runtime.cluster import check_scheduler, dask_client
    from symkin.runtime.payload import ModelPayload

    check_scheduler(args.scheduler, args.workers)
    if args.backend != "numpy":
        raise ValueError(f"--scheduler samples the workspace with the numpy code on the workers (its clouds come back "
                         f"for the figures), not the {args.backend} code: leave out --backend, or --scheduler to "
                         "evaluate in this process")
    if args.orientation:
        raise ValueError("--scheduler samples a serial mechanism's joint space (no --orientation)")
    with model_files.generated_directory(args.model, ("numpy",), NEEDS["kinematics"], display=Progress) as d:
        payload = ModelPayload.from_directory(d)
    where = {"serial": "in this process", "local": "on a LocalCluster"}.get(args.scheduler, f"on {args.scheduler}")
    found = []
    with (dask_client(args.scheduler, args.workers) if args.scheduler != "serial" else contextlib.nullcontext()) \
            as client:
        for values, model in zip(designs, models):
            parameters = {**analysis_args.parse_assignments(args.assignments), **values}
            spec = chunked_workspace.CloudSpec(tuple(sorted(parameters.items())), tuple(sorted(limits.items())),
                                               length, method, args.samples, args.seed)
            result = chunked_workspace.chunked_workspace(payload, spec, chunk=args.chunk, scheduler=args.scheduler,
                                                         client=client, progress=progress)
            found.append(study.WorkspaceStudy(result.cloud, f"{result.configurations} configurations ({method}, "
                                                            f"in chunks of {args.chunk})", result.inv_kappa, None,
                                              chunked_workspace.report(result, args.chunk, where),
                                              workspace.limit_curves(model, limits=limits)
                                              if mechanism.joint_limits(model, limits).shape[0] == 2 else []))
    return found


def _orientations(args: argparse.Namespace, model, limits: dict) -> int:
    """A spherical platform: its orientation workspace (the Haar measure of SO(3)) and a cloud of the reachable
    orientations in the roll-pitch-yaw chart, coloured by 1/kappa of the angular-velocity Jacobian."""
    import numpy as np

    from symkin import mechanism
    from symkin.analysis import orientations, plots, workspace

    start = time.perf_counter()
    try:
        for given, option in ((args.design, "--design"), (args.orientation, "--orientation"),
                              (args.length != "auto", "--length"), (args.scheduler, "--scheduler"),
                              (args.force_map, "--force-map"), (args.map, "--map"), (args.method, "--method"),
                              (args.unit != "m", "--unit")):
            if given:
                raise ValueError(f"{option}: {model.name} is a spherical platform, its workspace a set of orientations "
                                 "(roll, pitch, yaw) drawn with 1/kappa of its angular-velocity Jacobian (leave the "
                                 "option out)")
        with Progress(model.name) as progress:
            progress(f"{args.samples} orientations")
            points, values = orientations.orientation_cloud(model, args.samples, seed=args.seed, limits=limits)
            found = orientations.orientation_gci(model, samples=args.samples, seed=args.seed, limits=limits)
            measure = found.measure
            print(f"{model.name}: orientation workspace {measure.value:.4g} +- {measure.error:.2g} rad^3 (the Haar "
                  f"measure of SO(3): {100 * measure.value / orientations.SO3_MEASURE:.3g} % of all orientations), "
                  f"1/kappa of the angular-velocity Jacobian {values.min():.3g} to {values.max():.3g}, "
                  f"mean over the workspace (GCI) {found.value.value:.4g}; {len(points)} of the sampled orientations "
                  "reachable")
            if not args.no_figure:
                progress("drawing")
                cloud = workspace.WorkspaceCloud(points, points, mechanism.ANGLES)
                path = plots.plot_index_map(cloud, values, args.out or f"out/workspace/{model.name}-workspace.png",
                                            scale=180 / np.pi, unit="deg", title=args.title or
                                            f"Orientation workspace of {model.name}: 1/kappa of J_w")
                print(f"figure: {path}")
    except (ValueError, KeyError) as err:
        analysis_args.fail_on_bad_input(args, err)
    print(f"done in {time.perf_counter() - start:.2f} s")
    return 0


def continuation_options(args: argparse.Namespace, model) -> dict:
    """The held angles (--orientation), the characteristic length (--length) and the cells a side (-n N: about
    N^(1/3)) of a workspace continued over a grid (:func:`symkin.analysis.study.continued_study`)."""
    from symkin.mechanism import reach

    length = analysis_args.parse_length(args.length)
    orientation = reach.held_orientation(model, analysis_args.parse_orientation(args.orientation))
    return {"orientation": orientation, "length": None if length == "auto" else float(length),
            "cells": max(8, int(round(args.samples ** (1 / 3))))}


def _continued(args: argparse.Namespace, model, limits: dict) -> int:
    """A mechanism sampled by continuation (no closed forms): the working mode of the home assembly at a constant
    orientation, continued over a Cartesian grid from the home pose (:func:`symkin.analysis.study.continued_study`)."""
    from symkin.analysis import study

    start = time.perf_counter()
    try:
        for given, option in ((args.design, "--design"), (args.scheduler, "--scheduler"),
                              (args.force_map, "--force-map")):
            if given:
                raise ValueError(f"{option}: {model.name}'s legs have no closed forms; its workspace is continued from "
                                 "the home pose over one Cartesian grid (no designs, chunks or force map)")
        options = continuation_options(args, model)
        with Progress(model.name) as progress:
            found = study.continued_study(model, limits=limits, progress=progress, **options)
    except (ValueError, KeyError) as err:
        analysis_args.fail_on_bad_input(args, err)
    _print_study(args, model.name, found)
    print(f"done in {time.perf_counter() - start:.2f} s")
    return 0


def _print_study(args: argparse.Namespace, name: str, found) -> None:
    """A workspace study's findings; with --map, 1/kappa over its Cartesian grid (the figures of one design)."""
    from symkin.analysis import plots

    print(f"{name}: {found.sampled}, workspace in {', '.join(found.cloud.axes)}")
    for line in found.report:
        print(f"  {line}")
    scale = analysis_args.LENGTH_UNITS[args.unit]
    if not args.no_figure:
        path = plots.plot_workspaces([plots.WorkspaceLayer(name, found.cloud, found.outline)],
                                     args.out or f"out/workspace/{name}-workspace.png",
                                     title=args.title or f"Workspace of {name}", scale=scale, unit=args.unit)
        print(f"figure: {path}")
    if args.map and found.grid is not None:
        occupancy, values = found.grid
        path = plots.plot_index_slices(occupancy, values, args.map, axes=found.grid_axes, scale=scale, unit=args.unit,
                                       title=f"1/kappa over the workspace of {name}: Cartesian grid, "
                                             f"{found.reached_by}")
        print(f"1/kappa map: {path}")


def run(args: argparse.Namespace) -> int:
    from symkin import mechanism
    from symkin.analysis import orientations, plots, study, workspace
    from symkin.mechanism import reach

    try:
        base, limits = analysis_args.model_from_args(args)
        base = analysis_args.device_view(args, base)
        sampled = mechanism.sampling(base)
        if sampled is mechanism.Sampling.ORIENTATIONS:
            return _orientations(args, base, limits)
        if sampled is mechanism.Sampling.CONTINUATION:
            return _continued(args, base, limits)
        base = reach.held_at(base, analysis_args.parse_orientation(args.orientation))
        designs = [analysis_args.parse_assignments([text]) for text in args.design] or [{}]
        models = [base.bind(**values) if values else base for values in designs]
        length = analysis_args.resolve_length(base, args.length, limits)  # of the base design, for all designs
    except (ValueError, KeyError) as err:
        analysis_args.fail_on_bad_input(args, err)
    method = args.method or workspace.default_method(base)
    layers: list[tuple[plots.WorkspaceLayer, np.ndarray | None]] = []  # 1/kappa of the cloud, unless a grid has it
    grids: list[tuple[workspace.Occupancy, np.ndarray]] = []
    start = time.perf_counter()
    with Progress(base.name) as progress:
        studies: list = []
        if args.scheduler is not None:
            try:
                studies = _chunked_study(args, models, designs, method, limits, length, progress)
            except ValueError as err:
                analysis_args.fail_on_bad_input(args, err)
        for k, (values, model) in enumerate(zip(designs, models)):
            label = analysis_args.design_label(base, values, args.unit)
            progress(f"sampling {label}")
            try:
                found = studies[k] if studies else study.study_workspace(
                    model, samples=args.samples, method=method, seed=args.seed, limits=limits, length=length,
                    progress=progress)
            except ValueError as err:
                analysis_args.fail_on_bad_input(args, err)
            if found.grid is not None:
                grids.append(found.grid)
            print(f"{model.name} ({label}): {found.sampled}, workspace in {', '.join(found.cloud.axes)}")
            for line in found.report:
                print(f"  {line}")
            layers.append((plots.WorkspaceLayer(label, found.cloud, found.outline), found.inv_kappa))
        scale = analysis_args.LENGTH_UNITS[args.unit]
        if not args.no_figure:
            progress("drawing")
            title = args.title or f"Workspace of {base.name}"
            path = plots.plot_workspaces([layer for layer, _ in layers],
                                         args.out or f"out/workspace/{base.name}-workspace.png", title=title,
                                         scale=scale, unit=args.unit)
            print(f"figure: {path}")
        if args.map:
            layer, inv_kappa = layers[0]
            title = f"1/kappa over the workspace of {base.name} ({layer.label})"
            if grids:
                occupancy, cell_values = grids[0]
                path = plots.plot_index_slices(occupancy, cell_values, args.map, scale=scale, unit=args.unit,
                                               title=f"{title}: Cartesian grid, reachability by ik")
                if isinstance(models[0], reach.ConstantOrientation):
                    sections = plots.plot_index_sections(
                        occupancy, cell_values, sections_path(args.map), reach.home_position(models[0]), scale=scale,
                        unit=args.unit, title=f"{title}: sections through the home position at roll, pitch, yaw "
                                              f"= {reach.orientation_text(models[0])}")
                    print(f"1/kappa sections: {sections}")
            else:
                assert inv_kappa is not None, "a joint-space cloud carries its 1/kappa"
                path = plots.plot_index_map(layer.cloud, inv_kappa, args.map, outline=layer.outline, scale=scale,
                                            unit=args.unit, title=title)
            print(f"1/kappa map: {path}")
        if args.force_map:
            progress("isotropic force")
            try:
                path, summary = _force_map(args, models[0], layers[0][0], limits, scale)
            except ValueError as err:
                analysis_args.fail_on_bad_input(args, err)
            print(f"isotropic force: {summary}")
            print(f"force map: {path}")
    print(f"done in {time.perf_counter() - start:.2f} s")
    return 0


def _force_map(args: argparse.Namespace, model, layer, limits, scale: float):
    """(figure path, summary) of the isotropic force over the workspace (symkin.rating.forces)."""
    import numpy as np

    from symkin.analysis import plots, study, workspace
    from symkin.rating import forces
    from symkin import mechanism
    from symkin.mechanism import reach

    if not mechanism.is_positional(model):
        raise ValueError(f"--force-map: the task space of {model.name} ({', '.join(mechanism.task_space(model))}) "
                         "is not translations only")
    efforts = analysis_args.effort_limits(args.effort_limit, model)
    if efforts is None:
        raise ValueError(f"{model.name} declares no effort limit for every actuator: give --effort-limit T[,T...]")
    title = f"isotropic force over the workspace of {model.name} (effort limits {', '.join(f'{e:g}' for e in efforts)})"
    if mechanism.sampled_in_task_space(model):
        grid, values = study.cartesian_index_grid(model, reach.bounding_box(model, limits=limits), limits, None,
                                                  lambda J: forces.isotropic_force(J, efforts))
        path = plots.plot_index_slices(grid, values, args.force_map, label="isotropic force [N]", title=title,
                                       scale=scale, unit=args.unit)
        reachable = values[grid.occupied]
    else:
        values = forces.isotropic_force(mechanism.jacobian(model, layer.cloud.q), efforts)
        path = plots.plot_index_map(layer.cloud, values, args.force_map, outline=layer.outline, label="isotropic "
                                    "force [N]", title=title, scale=scale, unit=args.unit)
        reachable = values
    finite = reachable[np.isfinite(reachable)]
    summary = (f"min {finite.min():.4g} N, median {np.median(finite):.4g} N, max {finite.max():.4g} N over the "
               "workspace")
    return path, summary


def sections_path(path: str) -> str:
    """The file of the sections through the home position, next to the --map FIGURE: map.png -> map-sections.png."""
    from pathlib import Path

    figure = Path(path)
    return str(figure.with_name(f"{figure.stem}-sections{figure.suffix}"))
