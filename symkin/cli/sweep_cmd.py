"""``symkin sweep MODEL --vary NAME=LOW:HIGH:COUNT ...``: the metrics of many designs, on Dask."""

from __future__ import annotations

import argparse
import os
import signal
import sys
import time
from pathlib import Path

from symkin.analysis.needs import NEEDS
from symkin.cli import analysis_args
from symkin.analysis import model_files
from symkin.cli.progress import Progress


def register(sub: argparse._SubParsersAction) -> None:
    from symkin.design.sweep_metrics import DEFAULT_METRICS, METRICS

    p = sub.add_parser(
        "sweep",
        help="GCI, workspace and conditioning of many designs (grid or Sobol set), on all cores or a Dask cluster",
        description="Evaluate every design of a grid (--vary NAME=LOW:HIGH:COUNT per parameter, row-major) or of a "
                    "Sobol set (--sobol N with --vary NAME=LOW:HIGH): the GCI (seed eq. 8.28) and workspace measure "
                    "of one quasi-Monte Carlo integration over the domain symkin gci rates the model on by default "
                    "(the joint limits; a platform that also rotates: its Cartesian workspace at its home "
                    "orientation; a spherical platform: its orientations), each with its 95 % error "
                    "estimate, and the extreme condition numbers over its points. One derivation serves every "
                    "design (parameters are inputs of the generated code). Chunks of designs run on a Dask "
                    "LocalCluster (default, one worker per core), a scheduler you started (--scheduler "
                    "tcp://HOST:8786) or in this process (--scheduler serial); each completed chunk is written at "
                    "once, so an interrupted sweep continues with --resume. The result is a Parquet table, one "
                    "row per design with a status (a design that fails is a row, not a crash), the model hash, "
                    "symkin version and sweep definition in its metadata, identical to the bit however it was "
                    "scheduled. Figures: metric maps over the first two varied parameters and the Pareto front "
                    "of GCI against workspace measure.",
    )
    p.add_argument("model", metavar="MODEL",
                   help="generated model directory (from 'symkin derive') or a model file (YAML or URDF; derived "
                        "once)")
    p.add_argument("--vary", action="append", default=[], metavar="NAME=LOW:HIGH[:COUNT]",
                   help="a varied parameter: its range and, for a grid, the number of values (repeatable)")
    p.add_argument("--sobol", type=int, default=None, metavar="N",
                   help="N designs of an unscrambled Sobol sequence over the --vary ranges instead of a grid")
    p.add_argument("--metric", default=",".join(DEFAULT_METRICS), metavar="A,B",
                   help=f"metrics, comma-separated, from {', '.join(METRICS)} (torque_peak: the largest actuator "
                        "effort per newton of TCP force over the workspace, N m/N; default: %(default)s)")
    p.add_argument("--set", dest="assignments", action="append", default=[], metavar="NAME=VALUE[,...]",
                   help="values every design shares instead of the defaults (repeatable)")
    p.add_argument("--backend", choices=("numpy", "jax"), default="numpy",
                   help="the code the workers evaluate: numpy (default) or jax (the integrand fused on JAX's default "
                        "device where the device decides the model's workspace - a serial arm, closed-form working "
                        "modes, a rotating or spherical platform's closed-form ik - compiled once for every design; "
                        "workers with a GPU use it)")
    p.add_argument("-n", "--samples", type=int, default=4096, metavar="N",
                   help="integrand evaluations per design (quasi-Monte Carlo; default: %(default)s)")
    p.add_argument("--length", metavar="L", default="auto",
                   help="characteristic length [m] homogenizing the Jacobian of a task space that mixes translations "
                        "and rotations (the UR10e's), the same for every design, or 'auto': each design's own, "
                        "minimizing its mean kappa_F^2 (default: auto; ignored for a task space of one kind)")
    p.add_argument("--seed", type=int, default=0, help="seed of the integrator, the same for every design "
                                                       "(default: %(default)s)")
    p.add_argument("--chunk", type=int, default=64, metavar="K", help="designs per task (default: %(default)s)")
    p.add_argument("--scheduler", default="local", metavar="local|serial|tcp://HOST:PORT",
                   help="where the chunks run: a LocalCluster started for the sweep (default), this process, or "
                        "the Dask scheduler at an address")
    p.add_argument("--workers", type=int, default=None, metavar="K",
                   help="LocalCluster: worker processes (default: one per core)")
    p.add_argument("--resume", action="store_true",
                   help="continue an interrupted sweep with the same options: only the missing chunks run")
    p.add_argument("--optimum", metavar="RESULT.json",
                   help="the result.json of 'symkin optimize': its optimum is evaluated like the designs, printed and "
                        "marked on the Pareto figure")
    p.add_argument("-o", "--out", metavar="FILE.parquet", help="result table (default: out/sweeps/MODEL.parquet)")
    p.add_argument("--figures", metavar="DIR", help="figure directory (default: out/figures)")
    p.add_argument("--no-figure", action="store_true", help="write no figures")
    p.set_defaults(run=run, parser=p)


def _definition(args: argparse.Namespace):
    from symkin.design.sweeps import SweepDefinition, parse_axis

    axes = tuple(parse_axis(text, args.sobol is None) for text in args.vary)
    fixed = tuple(sorted(analysis_args.parse_assignments(args.assignments).items()))
    metrics = tuple(m.strip() for m in args.metric.split(",") if m.strip())
    return SweepDefinition(axes, metrics, args.sobol, args.samples, args.seed, args.chunk, fixed,
                           analysis_args.parse_length(args.length))


def _check_names(definition, payload) -> None:
    """Every varied and --set name is a free parameter of the model (checked before any worker starts)."""
    model = payload.load()
    unknown = [n for n in (*definition.names, *(name for name, _ in definition.fixed)) if n not in model.parameters]
    if unknown:
        raise ValueError(f"{model.name}: not free parameters: {', '.join(unknown)}; free: "
                         f"{', '.join(sorted(model.parameters))}")


def _optimum(path: str | None, definition, payload) -> dict | None:
    """The optimum of a 'symkin optimize' result.json, evaluated like a design (None without --optimum).

    Raises:
        ValueError: the file is not such a result.
    """
    if path is None:
        return None
    import json

    from symkin.design.sweeps import evaluate_design

    try:
        values = {name: float(p["optimum"]) for name, p in json.loads(Path(path).read_text())["parameters"].items()}
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as err:
        raise ValueError(f"--optimum {path}: not a result.json of 'symkin optimize' ({err})") from None
    design = ", ".join(f"{n} = {v:.4g}" for n, v in values.items())
    return {**evaluate_design(payload.load(), values, definition), "label": f"symkin optimize: {design}",
            "design": design}


def _terminate(signum, _frame) -> None:
    raise KeyboardInterrupt(f"signal {signum}")


def run(args: argparse.Namespace) -> int:
    from symkin.design import sweep_plots
    from symkin.design.sweeps import evaluate_missing, summary_rows
    from symkin.design.sweep_store import SweepStore
    from symkin.runtime.cluster import check_scheduler
    from symkin.runtime.payload import ModelPayload
    from symkin.text_table import format_table

    try:
        definition = _definition(args)
        check_scheduler(args.scheduler, args.workers)
        with model_files.generated_directory(args.model, (args.backend,), NEEDS["kinematics"], display=Progress) as d:
            payload = ModelPayload.from_directory(d, args.backend)
        _check_names(definition, payload)
        out = Path(args.out or Path("out") / "sweeps" / f"{payload.name}.parquet")
        optimum = _optimum(args.optimum, definition, payload)
        store = SweepStore(out, definition, payload, resume=args.resume)
    except (ValueError, KeyError) as err:
        analysis_args.fail_on_bad_input(args, err)
    already = len(store.completed())
    where = {"serial": "in this process", "local": f"on a LocalCluster of {args.workers or os.cpu_count()} "
             "workers"}.get(args.scheduler, f"on the Dask scheduler at {args.scheduler}")
    print(f"sweep of {payload.name}: {definition.size} designs in {definition.chunks} chunks of {definition.chunk}, "
          f"{where}" + (f"; resuming with {already} chunks done" if already else ""))
    start = time.perf_counter()
    previous = signal.signal(signal.SIGTERM, _terminate)
    try:
        with Progress(f"{payload.name} sweep") as progress:
            def report(done: int, total: int) -> None:
                progress("evaluating designs", done=done, total=total)

            progress("starting" if args.scheduler == "serial" else "starting the Dask cluster")

            evaluate_missing(payload, definition, store, scheduler=args.scheduler, workers=args.workers,
                          progress=report)
    except KeyboardInterrupt:
        kept = len(store.completed())
        print(f"symkin sweep: interrupted; {kept} of {definition.chunks} chunks are stored in {store.parts}; "
              "rerun the same command with --resume to continue", file=sys.stderr)
        return 130
    finally:
        signal.signal(signal.SIGTERM, previous)
    table = store.finish()
    seconds = time.perf_counter() - start
    rows = summary_rows(table, definition)
    if optimum is not None:
        rows += [[f"optimum {m}", f"{optimum[m]:.6g}", optimum["design"]] for m in definition.metrics
                 if m in ("gci", "volume")]
    print(format_table(["", "value", "design"], rows))
    failures = [(design, status) for design, status in zip(table.column("design").to_pylist(),
                                                           table.column("status").to_pylist())
                if status.startswith("failed")]
    if failures:
        print(f"design {failures[0][0]} {failures[0][1]}" + (f" (and {len(failures) - 1} more: the status column)"
                                                             if len(failures) > 1 else ""))
    print(f"wrote {out} ({table.num_rows} rows) in {seconds:.1f} s")
    if not args.no_figure:
        from symkin.atomic import replace_file

        folder = Path(args.figures or Path("out") / "figures")
        figures = {"maps": sweep_plots.metric_maps(table, definition, payload.name),
                   "pareto": sweep_plots.pareto_figure(table, definition, payload.name, optimum)}
        for kind, content in figures.items():
            if content is not None:
                replace_file(folder / f"{payload.name}-sweep-{kind}.png", content)
                print(f"figure written to {folder / f'{payload.name}-sweep-{kind}.png'}")
    return 0
