"""``symkin workspace MODEL``: TCP point cloud, area/volume, boundary, singularities, figures."""

from __future__ import annotations

import argparse
import time

from symkin.cli import analysis_args
from symkin.cli.progress import Progress


#: Cells along the longest side of the Cartesian grid of a parallel mechanism's workspace.
CARTESIAN_CELLS = 64
#: Fraction of the reachable cells, those of lowest 1/kappa, whose place (boundary or not) is reported.
LOWEST_FRACTION = 0.01


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
                    "(its joint space is not sampled: -n, --method and --seed do not apply).",
    )
    analysis_args.add_model_arguments(p)
    p.add_argument("--design", action="append", default=[], metavar="NAME=VALUE[,...]",
                   help="a design to analyse and overlay (parameter values on top of --set); repeatable")
    p.add_argument("-n", "--samples", type=int, default=40_000, metavar="N",
                   help="joint configurations per design (default: %(default)s)")
    p.add_argument("--method", choices=("grid", "random", "sobol"), default=None,
                   help="joint-space sampling (default: grid up to 3 joints, else sobol)")
    p.add_argument("--seed", type=int, default=0, help="seed of random/sobol sampling (default: %(default)s)")
    p.add_argument("-o", "--out", metavar="FIGURE", help="workspace figure (default: MODEL_NAME-workspace.png)")
    p.add_argument("--map", metavar="FIGURE", help="also draw 1/kappa over the workspace into FIGURE "
                                                   "(first design); a platform at a constant orientation also "
                                                   "gets FIGURE-sections (x-y, x-z, y-z through the home position)")
    p.add_argument("--no-figure", action="store_true", help="print the report only")
    analysis_args.add_length_argument(p)
    add_orientation_argument(p)
    p.add_argument("--unit", choices=tuple(analysis_args.LENGTH_UNITS), default="m",
                   help="length unit of the figures (default: m)")
    p.add_argument("--title", help="figure title")
    p.set_defaults(run=run, parser=p)


def add_orientation_argument(p: argparse.ArgumentParser) -> None:
    """--orientation: the constant orientation at which a rotating platform is analysed (shared with ``symkin gci``)."""
    p.add_argument("--orientation", metavar="ROLL,PITCH,YAW",
                   help="platforms that also rotate (Stewart-Gough): the constant orientation of the analysed "
                        "workspace, R = Rz(yaw) Ry(pitch) Rx(roll), in rad, or in degrees with 'deg' "
                        "(e.g. 0,10deg,0); default: the orientation of the model's home pose (parallel.home)")


def at_orientation(model, text: str | None):
    """``model`` held at the --orientation ``text`` if its platform rotates, else ``model`` itself.

    Raises:
        ValueError: --orientation is malformed, or given for a mechanism whose platform does not rotate.
    """
    from symkin.analysis import mechanism, parallel

    rotates = mechanism.is_parallel(model) and mechanism.mixes_translations_and_rotations(model)
    if text is None:
        return parallel.constant_orientation(model) if rotates else model
    if not rotates:
        raise ValueError(f"--orientation: {model.name} is not a parallel platform that rotates "
                         f"(task space {list(mechanism.task_space(model))}); leave the option out")
    parts = text.split(",")
    try:
        if len(parts) != 3:
            raise ValueError
        angles = [analysis_args.parse_value(part) for part in parts]
    except ValueError:
        raise ValueError(f"--orientation: '{text}' is not ROLL,PITCH,YAW (three numbers in rad, or with 'deg', "
                         "e.g. 0,10deg,0)") from None
    return parallel.constant_orientation(model, angles)


def run(args: argparse.Namespace) -> int:
    from symkin.analysis import global_indices, mechanism, parallel, plots, workspace

    try:
        base, limits = analysis_args.model_from_args(args)
        base = at_orientation(base, args.orientation)
        designs = [analysis_args.parse_assignments([text]) for text in args.design] or [{}]
        models = [base.bind(**values) if values else base for values in designs]
        joints = mechanism.joint_limits(base, limits).shape[0]
        length = analysis_args.resolve_length(base, args.length, limits)  # of the base design, for all designs
    except (ValueError, KeyError) as err:
        analysis_args.fail_on_bad_input(args, err)
    method = args.method or workspace.default_method(base)
    layers, grids = [], []
    start = time.perf_counter()
    with Progress(base.name) as progress:
        for values, model in zip(designs, models):
            label = analysis_args.design_label(base, values, args.unit)
            progress(f"sampling {label}")
            try:
                inv_kappa, box, grid = None, None, None
                if mechanism.is_parallel(model):  # 1/kappa and the volume come from a Cartesian grid
                    box = workspace.bounding_box(model, limits=limits)
                    progress(f"Cartesian grid {label}")
                    grid = cartesian_index_grid(model, box, limits, length)
                    grids.append(grid)
                if isinstance(model, parallel.ConstantOrientation):  # no fk: the grid's surface is the cloud
                    cloud = _boundary_cloud(model, grid[0], limits)
                    sampled = (f"{int(grid[0].occupied.sum())} reachable cells of a Cartesian grid at roll, pitch, "
                               f"yaw = {parallel.orientation_text(model)}")
                else:
                    cloud = workspace.sample_workspace(model, args.samples, method=method, limits=limits,
                                                       seed=args.seed)
                    if grid is None:
                        progress(f"conditioning {label}")
                        inv_kappa = global_indices.local_index(model, cloud.q, length=length, limits=limits)
                    sampled = f"{len(cloud.q)} configurations ({method})"
                report = _report(model, cloud, inv_kappa, limits, progress, box)
                report += _cartesian_report(*grid) if grid is not None else []
            except ValueError as err:
                analysis_args.fail_on_bad_input(args, err)
            print(f"{model.name} ({label}): {sampled}, workspace in {', '.join(cloud.axes)}")
            for line in report:
                print(f"  {line}")
            outline = workspace.limit_curves(model, limits=limits) if joints == 2 else ()
            layers.append((plots.WorkspaceLayer(label, cloud, outline), inv_kappa))
        scale = analysis_args.LENGTH_UNITS[args.unit]
        if not args.no_figure:
            progress("drawing")
            title = args.title or f"Workspace of {base.name}"
            path = plots.plot_workspaces([layer for layer, _ in layers], args.out or f"{base.name}-workspace.png",
                                         title=title, scale=scale, unit=args.unit)
            print(f"figure: {path}")
        if args.map:
            layer, values = layers[0]
            title = f"1/kappa over the workspace of {base.name} ({layer.label})"
            if grids:
                path = plots.plot_index_slices(*grids[0], args.map, scale=scale, unit=args.unit,
                                               title=f"{title}: Cartesian grid, reachability by ik")
                if isinstance(models[0], parallel.ConstantOrientation):
                    sections = plots.plot_index_sections(
                        *grids[0], sections_path(args.map), parallel.home_position(models[0]), scale=scale,
                        unit=args.unit, title=f"{title}: sections through the home position at roll, pitch, yaw "
                                              f"= {parallel.orientation_text(models[0])}")
                    print(f"1/kappa sections: {sections}")
            else:
                path = plots.plot_index_map(layer.cloud, values, args.map, outline=layer.outline, scale=scale,
                                            unit=args.unit, title=title)
            print(f"1/kappa map: {path}")
    print(f"done in {time.perf_counter() - start:.2f} s")
    return 0


def sections_path(path: str) -> str:
    """The file of the sections through the home position, next to the --map FIGURE: map.png -> map-sections.png."""
    from pathlib import Path

    figure = Path(path)
    return str(figure.with_name(f"{figure.stem}-sections{figure.suffix}"))


def cartesian_index_grid(model, box, limits, length, index=None):
    """Reachability grid of a parallel mechanism over ``box`` (CARTESIAN_CELLS along its longest
    side) with a local index (1/kappa by default) at its cell centres (see symkin.analysis.grids.index_grid)."""
    from symkin.analysis import parallel
    from symkin.analysis.grids import index_grid

    cell = float(max(box[1] - box[0])) / CARTESIAN_CELLS
    return index_grid(model, parallel.parallel_inverse(model), box, cell, index=index, limits=limits,
                                length=length)


def _boundary_cloud(model, occupancy, limits):
    """The centres of the boundary cells of a Cartesian grid and their joint coordinates, as a point cloud."""
    from symkin.analysis import feasibility, mechanism, parallel, workspace

    points = occupancy.centers()[occupancy.boundary()]
    q, _ = feasibility.feasible_configurations(parallel.parallel_inverse(model), points,
                                               mechanism.joint_limits(model, limits), mechanism.revolute_mask(model))
    return workspace.WorkspaceCloud(q, points, ("x", "y", "z"))


def _cartesian_report(occupancy, values) -> list[str]:
    """Volume, boundary and where the (near-)singular cells lie, from the Cartesian grid."""
    import numpy as np

    boundary = occupancy.boundary()
    interior = occupancy.interior()
    lines = [f"volume: {occupancy.measure()} m^3 (Cartesian grid of {occupancy.cell[0]:.3g} m cells, reachability "
             f"by ik in the working mode: between interior and all reachable cells, a bracket unless thin parts of the "
             f"workspace fall between cell centres); {int(boundary.sum())} boundary cells"]
    if interior.any():
        lines.append(f"1/kappa at the cell centres: min {np.nanmin(values[boundary]):.4g} on boundary cells, "
                     f"min {np.nanmin(values[interior]):.4g} on interior cells")
    reachable = values[occupancy.occupied]
    worst = occupancy.occupied & (values <= np.quantile(reachable, LOWEST_FRACTION))
    lines.append(f"the {int(worst.sum())} cells of lowest 1/kappa ({LOWEST_FRACTION:.0%}): {int((worst & boundary).sum())} "
                 "on the workspace boundary (seed sec. 4.2: boundary singularities)")
    return lines


def _report(model, cloud, inv_kappa, limits, progress, box=None) -> list[str]:
    from symkin.analysis import global_indices, inverse, mechanism, workspace

    lines = []
    lower, upper = cloud.points.min(axis=0), cloud.points.max(axis=0)
    lines.append("extent of the samples: " + ", ".join(f"{a} [{lo:.6g}, {hi:.6g}] m"
                                                       for a, lo, hi in zip(cloud.axes, lower, upper)))
    d = len(cloud.axes)
    unit = f"m^{d}"
    kind = "area" if d == 2 else "volume"
    if mechanism.is_positional(model):
        progress(f"{kind} (joint domain)")
        measure = global_indices.workspace_measure(model, method="qmc", samples=2**16, seed=0, limits=limits)
        lines.append(f"{kind}: {measure} {unit} (qmc, |det J| dq over the joint limits: exact where q -> TCP "
                     "is one-to-one, else with multiplicity)")
    ik = inverse.inverse_kinematics_for(model)
    if ik is not None:
        progress(f"{kind} (Cartesian domain)")
        measure = global_indices.workspace_measure(model, method="qmc", samples=2**16, seed=0, limits=limits,
                                                   domain="cartesian", inverse=ik, box=box)
        lines.append(f"{kind}: {measure} {unit} (qmc over a Cartesian box, reachability by inverse kinematics)")
    if mechanism.is_parallel(model):
        return lines  # the Cartesian grid (_cartesian_report) gives the volume, boundary and singularities
    occupancy = workspace.occupancy_from_cloud(cloud)
    boundary = occupancy.boundary()
    lines.append(f"{kind}: {occupancy.measure()} {unit} (occupancy of {occupancy.cell[0]:.3g} m cells: "
                 f"between interior and all occupied cells); {int(boundary.sum())} boundary cells")
    singular = inv_kappa <= 0.0
    on_boundary = int(occupancy.lookup(cloud.points[singular], boundary).sum())
    lines.append(f"1/kappa: min {inv_kappa.min():.4g}, mean {inv_kappa.mean():.4g}, max {inv_kappa.max():.4g}; "
                 f"singular configurations: {int(singular.sum())}, of which {on_boundary} on the workspace "
                 "boundary (seed sec. 4.2: boundary singularities)")
    return lines
