"""``symkin gci MODEL``: global conditioning index (seed eq. 8.28) with an error estimate."""

from __future__ import annotations

import argparse
import importlib
import time

from symkin.mechanism import POSITION_COMPONENTS
from symkin.analysis.needs import NEEDS
from symkin.cli import analysis_args
from symkin.analysis import model_files
from symkin.cli.progress import Progress
from symkin.runtime.info import GeneratedModel

#: Configurations drawn for --map (serial mechanisms).
MAP_SAMPLES = 40_000
#: Local indices that ``--index`` can average (names of symkin.numerics.conditioning functions).
INDICES = {
    "inverse-condition": "inverse_condition_number",
    "inverse-frobenius": "inverse_frobenius_condition_number",
    "manipulability": "manipulability",
}


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "gci",
        help="global conditioning index with an error estimate",
        description="Global conditioning index v = int_W 1/kappa dW / int_W dW (seed eq. 8.28) and the workspace "
                    "measure int_W dW, each with an error estimate (95 % confidence half-width for mc/qmc, "
                    "a deterministic estimate for grid/adaptive). The default integrates over the joint limits "
                    "with dW = |det J| dq, the Cartesian measure (exact where q -> TCP is one-to-one); "
                    "--domain cartesian integrates the reachability indicator over a Cartesian box (needs a "
                    "closed-form inverse kinematics: the planar 2R, parallel mechanisms with a generated ik such "
                    "as the DELTA). A parallel mechanism's workspace is the set reached in its declared working "
                    "mode (ik and fk branches) within the actuator limits, on both domains. A platform that also "
                    "rotates (Stewart-Gough) is analysed at a constant orientation (--orientation) over the "
                    "Cartesian domain, 1/kappa of its twist Jacobian homogenized by --length. A spherical platform "
                    "(the Agile Eye) is rated over its orientations with the invariant measure of SO(3) (rad^3), "
                    "1/kappa of its angular-velocity Jacobian. Legs without closed forms (any topology) are rated over the "
                    "working mode of their home assembly at a constant orientation, on a grid the loop closure is "
                    "continued over (-n N: about N^(1/3) cells a side; the error estimate is the change from half as "
                    "many).",
    )
    analysis_args.add_model_arguments(p)
    p.add_argument("--method", choices=("grid", "mc", "qmc", "adaptive"), default="qmc",
                   help="integrator (default: %(default)s)")
    p.add_argument("-n", "--samples", type=analysis_args.sample_count, default=2**16, metavar="N",
                   help="budget of integrand evaluations (default: %(default)s)")
    p.add_argument("--rtol", type=float, default=0.0,
                   help="adaptive: stop at this relative error estimate (default: spend the budget)")
    p.add_argument("--domain", choices=("joint", "cartesian"), default=None,
                   help="integrate over the joint limits or a Cartesian box (default: joint; cartesian for a "
                        "platform that also rotates, the only domain it has)")
    p.add_argument("--measure", choices=("cartesian", "joint"), default="cartesian",
                   help="joint domain: dW = |det J| dq (cartesian, default) or dq (joint)")
    p.add_argument("--index", choices=tuple(INDICES), default="inverse-condition",
                   help="local index to average (default: %(default)s = 1/kappa, the GCI)")
    analysis_args.add_length_argument(p)
    analysis_args.add_orientation_argument(p)
    analysis_args.add_device_argument(p)
    p.add_argument("--seed", type=int, default=None, help="seed of mc/qmc (default: fresh randomness)")
    analysis_args.add_chunk_arguments(p, "mc/qmc on the joint or Cartesian domain (the numpy or JAX code of --backend on each worker; with jax each chunk is reduced on the worker's device)")
    p.add_argument("--map", metavar="FIGURE", help="also draw the local index over the workspace into FIGURE")
    p.set_defaults(run=run, parser=p)


def _chunked(args: argparse.Namespace) -> int:
    """--scheduler: the integral in chunks on Dask (:mod:`symkin.integration.chunked`)."""
    from symkin.analysis import inverse
    from symkin.integration.chunked import IntegrandSpec, integrate_chunked
    from symkin.analysis.global_indices import GlobalIndex
    from symkin.mechanism import reach
    from symkin.mechanism.reach import bounding_box, domain_description
    from symkin.runtime.cluster import check_scheduler
    from symkin.runtime.payload import PAYLOAD_BACKENDS, ModelPayload

    try:
        check_scheduler(args.scheduler, args.workers)
        if args.method not in ("mc", "qmc") or args.map:
            raise ValueError("--scheduler integrates by mc or qmc (no --map)")
        if args.backend not in PAYLOAD_BACKENDS:
            raise ValueError(f"--scheduler ships the model's {' or '.join(PAYLOAD_BACKENDS)} code to the workers, not "
                             f"its {args.backend} code: use --backend {' or --backend '.join(PAYLOAD_BACKENDS)}")
        with model_files.generated_directory(args.model, (args.backend,), NEEDS["kinematics"],
                                             display=Progress) as d:
            payload = ModelPayload.from_directory(d, args.backend)
        values = analysis_args.parse_assignments(args.assignments)
        model = payload.load().bind(**values) if values else payload.load()
        limits = analysis_args.parse_limits(args.limits)
        orientation = analysis_args.parse_orientation(args.orientation)
        held = reach.held_at(model, orientation)
        domain = _domain(args, held)
        box = None
        if domain == "cartesian":
            if inverse.inverse_kinematics_for(held) is None:
                raise ValueError(f"{model.name}: no inverse kinematics is available for the Cartesian domain")
            lower, upper = bounding_box(held, limits=limits)
            box = (tuple(float(v) for v in lower), tuple(float(v) for v in upper))
        spec = IntegrandSpec(tuple(sorted(values.items())), INDICES[args.index], args.measure,
                             tuple(sorted(limits.items())), analysis_args.resolve_length(held, args.length, limits),
                             domain, box, None if orientation is None else (orientation[0], orientation[1], orientation[2]))
        fused = spec.build(payload.load()).moments is not None    # the integrand each worker builds, built here
        start = time.perf_counter()
        with Progress(model.name) as progress:
            result = integrate_chunked(payload, spec, args.method, args.samples, seed=args.seed or 0,
                                       chunk=args.chunk, scheduler=args.scheduler, workers=args.workers,
                                       progress=lambda done, total: progress(f"{args.method} points", done=done,
                                                                             total=total))
    except (ValueError, KeyError) as err:
        analysis_args.fail_on_bad_input(args, err)
    seconds = time.perf_counter() - start
    chunks = -(-result.evaluations // args.chunk) if args.method == "mc" else None
    where = {"serial": "in this process", "local": "on a LocalCluster"}.get(args.scheduler, f"on {args.scheduler}")
    space = domain_description(held, domain, args.measure)
    found = GlobalIndex(result.ratio(0, 1), result.component(1), result,
                        f"{space}, in chunks of at most {args.chunk} points {where}"
                        + (f" ({chunks} chunks)" if chunks else "")
                        + (", each reduced on the worker's JAX device" if fused else ""))
    _print(args, held, found, seconds, None)
    return 0


def _print(args: argparse.Namespace, model: GeneratedModel, result, seconds: float, path) -> None:
    kind = "confidence half-width (95 %)" if result.value.statistical else "error estimate"
    name = "GCI" if args.index == "inverse-condition" else f"mean {args.index}"
    print(f"{model.name}: {name} = {result.value} ({kind})")
    print(f"  workspace measure int dW = {result.measure} {measure_unit(model, args.measure)}")
    print(f"  {result.integral.evaluations} evaluations by {args.method} in {seconds * 1e3:.1f} ms; {result.description}")
    if result.caveat:
        print(f"  note: {result.caveat}")
    if path is not None:
        print(f"  map: {path}")


def _domain(args: argparse.Namespace, model: GeneratedModel) -> str:
    """--domain, by default joint, or cartesian for a platform that also rotates (its only domain)."""
    from symkin.mechanism import reach

    held = isinstance(model, reach.ConstantOrientation)
    if held and args.domain == "joint":
        raise ValueError(f"{model.name}: a platform that also rotates has no closed-form fk: its GCI is "
                         "integrated over the constant-orientation workspace only (--domain cartesian)")
    return args.domain or ("cartesian" if held else "joint")


def run(args: argparse.Namespace) -> int:
    from symkin.numerics import conditioning
    from symkin.analysis import global_indices, inverse, orientations, plots, study, workspace
    from symkin import mechanism
    from symkin.mechanism import reach
    from symkin.integration.integrators import STATISTICAL

    if args.scheduler is not None:
        return _chunked(args)
    index = getattr(conditioning, INDICES[args.index])
    path = None
    try:
        model, limits = analysis_args.model_from_args(args)
        model = analysis_args.device_view(args, model)
        sampled = mechanism.sampling(model)
        if sampled is mechanism.Sampling.ORIENTATIONS:
            return _orientations(args, model, limits)
        if sampled is mechanism.Sampling.CONTINUATION:
            return _continued(args, model, limits)
        model = reach.held_at(model, analysis_args.parse_orientation(args.orientation))
        args.domain = _domain(args, model)
        length = analysis_args.resolve_length(model, args.length, limits)
        ik = inverse.inverse_kinematics_for(model) if args.domain == "cartesian" else None
        if args.domain == "cartesian" and ik is None:
            raise ValueError(f"{model.name}: no inverse kinematics is available for the Cartesian domain "
                             "(closed forms: planar 2R, parallel mechanisms with ik); use --domain joint")
        options = {"rtol": args.rtol} if args.method == "adaptive" else {}
        if args.method in STATISTICAL:  # a one-time import (the confidence quantile), kept out of the timing
            importlib.import_module("scipy.special")
        start = time.perf_counter()
        with Progress(model.name) as progress:
            progress(f"{args.method} over the {args.domain} domain, {args.samples} samples")
            result = global_indices.global_index(
                model, method=args.method, samples=args.samples, seed=args.seed, domain=args.domain,
                measure=args.measure, index=index, limits=limits, length=length, inverse=ik, **options)
            seconds = time.perf_counter() - start
            if args.map and mechanism.sampled_in_task_space(model):
                progress("drawing")
                box = reach.bounding_box(model, limits=limits)
                occupancy, values = study.cartesian_index_grid(model, box, limits, length, index)
                path = plots.plot_index_slices(occupancy, values, args.map, label=args.index,
                                               title=f"{args.index} over the workspace of {model.name}")
            elif args.map:
                progress("drawing")
                cloud = workspace.sample_workspace(model, MAP_SAMPLES, limits=limits, seed=0)
                values = global_indices.local_index(model, cloud.q, index=index, length=length, limits=limits)
                outline = workspace.limit_curves(model, limits=limits) if cloud.q.shape[1] == 2 else ()
                path = plots.plot_index_map(cloud, values, args.map, outline=outline, label=args.index,
                                            title=f"{args.index} over the workspace of {model.name}")
    except (ValueError, KeyError) as err:
        analysis_args.fail_on_bad_input(args, err)
    _print(args, model, result, seconds, path)
    return 0


def _orientations(args: argparse.Namespace, model: GeneratedModel, limits: dict) -> int:
    """A spherical platform: the GCI over its orientation workspace with the invariant measure of SO(3)."""
    from symkin.analysis import orientations

    try:
        for given, option in ((args.index != "inverse-condition", "--index"), (args.map, "--map"),
                              (args.domain not in (None, "cartesian"), "--domain"), (args.orientation, "--orientation"),
                              (args.measure != "cartesian", "--measure")):
            if given:
                raise ValueError(f"{option}: {model.name} is a spherical platform, rated by 1/kappa of its "
                                 "angular-velocity Jacobian over its orientations (leave the option out)")
        options = {"rtol": args.rtol} if args.method == "adaptive" else {}
        start = time.perf_counter()
        with Progress(model.name) as progress:
            progress(f"{args.method} over the orientations, {args.samples} samples")
            result = orientations.orientation_gci(model, method=args.method, samples=args.samples, seed=args.seed,
                                                  limits=limits, **options)
    except (ValueError, KeyError) as err:
        analysis_args.fail_on_bad_input(args, err)
    _print(args, model, result, time.perf_counter() - start, None)
    return 0


def _continued(args: argparse.Namespace, model: GeneratedModel, limits: dict) -> int:
    """A mechanism sampled by continuation (no closed forms): the GCI over the working mode of the home assembly at
    a constant orientation, on the grid it is continued over (:func:`symkin.analysis.study.continued_gci_study`)."""
    from symkin.analysis import plots, study
    from symkin.cli.workspace_cmd import continuation_options

    try:
        for given, option in ((args.index != "inverse-condition", "--index"), (args.domain == "joint", "--domain"),
                              (args.measure != "cartesian", "--measure"), (args.method not in ("qmc", "grid"), "--method")):
            if given:
                raise ValueError(f"{option}: {model.name}'s legs have no closed forms: its GCI is the mean of 1/kappa "
                                 "over a grid the loop closure is continued over (--method grid; leave the option out)")
        options = continuation_options(args, model)
        start = time.perf_counter()
        with Progress(model.name) as progress:
            progress(f"continuing the loop closure over grids of {options['cells']} and {options['cells'] // 2} "
                     "cells a side")
            found = study.continued_gci_study(model, limits=limits, **options)
            path = None
            if args.map:
                progress("drawing")
                path = plots.plot_index_slices(*found.grid, args.map, axes=found.axes,
                                               title=f"1/kappa over the workspace of {model.name}")
    except (ValueError, KeyError) as err:
        analysis_args.fail_on_bad_input(args, err)
    print(f"{model.name}: GCI = {found.value} (error estimate: the change from a grid of half as many cells a side)")
    for line in found.report:
        print(f"  {line}")
    print(f"  {time.perf_counter() - start:.2f} s")
    if path is not None:
        print(f"  map: {path}")
    return 0


def measure_unit(model: GeneratedModel, measure: str) -> str:
    """The unit of the workspace measure int dW: the product of the task coordinates' units for the
    Cartesian measure (dW = |det J| dq), of the joints' for the joint measure (dW = dq); lengths in
    m, angles (joint angles, orientation coordinates and angular-velocity components) in rad."""
    if measure == "joint":
        units = ["rad" if c.revolute else "m" for c in model.info.coordinates]
    else:
        units = ["m" if c in POSITION_COMPONENTS else "rad" for c in model.info.task_space]
    powers = {u: units.count(u) for u in ("m", "rad") if u in units}
    return " ".join(u if n == 1 else f"{u}^{n}" for u, n in powers.items())
